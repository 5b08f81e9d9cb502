// Multiple scattering per SRBF light by dual scattering (Xu 2011 Sec. 4.3, Zinke 2008): twin of
// src/scattering/dual_response.rs and of DualTables::backscatter_in_cell / mean_delta_sigma in dual_terms.rs.
// Prepended: circular_gaussian, lut, fast_azimuthal, azimuthal_table, fast_response. The includer
// binds `dual_tables` (dual_tables_texels in src/gpu/dual_eval.rs): one row j per sample of the absorption
// axis (DUAL_ROW vec4 each), holding DUAL_SAMPLES vec4 (ln A_b, ln a_f of row j, the same of row j + 1;
// DualRow::ln_big_a_b and ln_a_f) followed by DUAL_SAMPLES + 1 vec4 (the prefix sums of Delta_b and
// sigma_b of row j, the same of row j + 1). Each channel reads the two rows around its own sigma_a
// (DualTables::backscatter_in_cell, mean_delta_sigma_in_cell) with one load per sample.

const DUAL_SAMPLES: u32 = 128u;
const DUAL_ROW: u32 = 2u * DUAL_SAMPLES + 1u;
const DUAL_GLOBAL: u32 = 0u;
const DUAL_LOCAL: u32 = 1u;
// The absorption axis (dual_terms.rs axis_sigma / axis_pos with DUAL_SIGMA_SAMPLES rows).
const DUAL_SIGMA_SAMPLES: u32 = 65u;
const DUAL_SIGMA_MIN: f32 = 0.005;
const DUAL_SIGMA_MAX: f32 = 50.0;

fn dual_position(theta: f32) -> f32 {
    return clamp((theta + FRAC_PI_2) / PI, 0.0, 1.0) * f32(DUAL_SAMPLES - 1u);
}

// sigma_cell: the axis row below sigma_a and the weight of the one above.
struct DualCell {
    row: u32,
    w: f32,
}

fn dual_sigma_cell(s: f32) -> DualCell {
    var y = max(s / DUAL_SIGMA_MIN, 0.0);
    if (s > DUAL_SIGMA_MIN) {
        y = 1.0 + log(s / DUAL_SIGMA_MIN) / log(DUAL_SIGMA_MAX / DUAL_SIGMA_MIN) * f32(DUAL_SIGMA_SAMPLES - 2u);
    }
    y = clamp(y, 0.0, f32(DUAL_SIGMA_SAMPLES - 1u));
    let j = min(u32(y), DUAL_SIGMA_SAMPLES - 2u);
    return DualCell(j, y - f32(j));
}

// DualRow::ln_backscatter_at of the cell's two rows: (ln A_b, ln a_f) of row c.row, the same of row
// c.row + 1, at theta, linear between the samples.
fn dual_rows_ln(c: DualCell, theta: f32) -> vec4<f32> {
    let x = dual_position(theta);
    let i = min(u32(x), DUAL_SAMPLES - 2u);
    let base = c.row * DUAL_ROW;
    return mix(dual_tables[base + i], dual_tables[base + i + 1u], x - f32(i));
}
// DualTables::backscatter_in_cell: (A_b, a_f) at theta and one channel's absorption cell, log-linear
// in theta and along the axis.
fn dual_backscatter(theta: f32, c: DualCell) -> vec2<f32> {
    let v = dual_rows_ln(c, theta);
    return exp(mix(v.xy, v.zw, c.w));
}
// The axis cells of a point's three channels (found once per point: local_response reads them).
fn dual_cells(sigma_a: vec3<f32>) -> array<DualCell, 3> {
    return array<DualCell, 3>(dual_sigma_cell(sigma_a.x), dual_sigma_cell(sigma_a.y), dual_sigma_cell(sigma_a.z));
}
// The prefix sums of Delta_b and sigma_b of the cell's two rows at entry position x (linear between
// the entries).
fn dual_sat(c: DualCell, x: f32) -> vec4<f32> {
    let i = min(u32(x), DUAL_SAMPLES - 1u);
    let base = c.row * DUAL_ROW + DUAL_SAMPLES;
    return mix(dual_tables[base + i], dual_tables[base + i + 1u], x - f32(i));
}

// DualTables::mean_delta_sigma for one channel, at the axis cell of its absorption: (Delta_b, sigma_b),
// the means over theta in [lo, hi] of each row (DualRow::mean_delta_sigma, Xu Eq. 31) between them.
// The CPU twin reads the sample at the middle of a window under 1e-4 entries; local_response's
// windows are forward_spread >= 1e-3 rad wide (0.04 entries), at least half of that after a clamp at
// a pole (their middle lies within [-pi/2, pi/2]), so that branch (which lavapipe would run beside
// this one) is left out here.
fn mean_delta_sigma(lo: f32, hi: f32, c: DualCell) -> vec2<f32> {
    let a = dual_position(min(lo, hi)) + 0.5;
    let b = dual_position(max(lo, hi)) + 0.5;
    let rows = (dual_sat(c, b) - dual_sat(c, a)) / max(b - a, 1e-4);
    return mix(rows.xy, rows.zw, c.w);
}

// Standard deviation of the forward-scattered light's longitudinal spread.
fn forward_spread(sigma_f2: f32, lambda_j: f32) -> f32 {
    return sqrt(max(sigma_f2 + 0.5 * lambda_j * lambda_j, 1e-6));
}

struct DualIntegrand {
    kind: u32,
    lobe: u32,
    channel: u32,
    theta_o: f32,
    dphi: f32,
    // The lobe's longitudinal function (Zinke's back lobe for the local term).
    longitudinal: LongitudinalLobe,
    // Optical depth of the hair behind the point (local term).
    depth_behind: f32,
    // The absorption axis cell of the channel's sigma_a (local term).
    cell: DualCell,
}

// Optical depth that stands for Zinke's unbounded hair behind the point.
const DEPTH_UNBOUNDED: f32 = 1e30;

// backscatter_depth_fraction (dual_terms.rs): the part of A_b that hair of optical depth `depth` behind
// the point returns, 1 - exp(-depth (1 - a_f^2)).
fn backscatter_depth_fraction(a_f: f32, depth: f32) -> f32 {
    let k = max(1.0 - a_f * a_f, 1e-6);
    return 1.0 - exp(-min(max(depth, 0.0) * k, 80.0));
}

// The smooth factors of Eq. 27 (global: longitudinal factor x calN_t^G) and Eq. 29 (local:
// A_b longitudinal_factor, one channel in all three components).
fn dual_integrand(p: FastHairParams, d: DualIntegrand, ti: f32) -> vec3<f32> {
    let theta_d = 0.5 * (d.theta_o - ti);
    let w = longitudinal_factor(d.longitudinal, ti);
    if (d.kind == DUAL_GLOBAL) {
        // calN_t^G = (1/pi) integral over the front half of the azimuths (Xu Eq. 28).
        return w * azimuthal_table_box(d.lobe, p.sigma_a.xyz, theta_d, d.dphi);
    }
    let b = dual_backscatter(theta_d, d.cell);
    let a = b.x * backscatter_depth_fraction(b.y, d.depth_behind);
    return vec3<f32>(w * a);
}

// The dual terms' quadrature segments (twin: dual_response.rs): half the single-scattering
// quadrature's, at least 2 (the renderer's 4 give 2: one inner node).
fn dual_quadrature_segments(m: u32) -> u32 {
    return max(m / 2u, 2u);
}

// linear_quadrature of fast_response.rs over dual_integrand (parabolas on paired segments).
fn dual_quadrature(p: FastHairParams, d: DualIntegrand, mu: f32, l: f32) -> vec3<f32> {
    let m = dual_quadrature_segments(p.quadrature_segments);
    var q = quadrature_start(mu, l);
    for (var s = 1u; s < m; s++) {
        let x = quadrature_sample(s, m, mu, l);
        quadrature_node(&q, s, m, x, dual_integrand(p, d, x));
    }
    quadrature_end(&q, m);
    return q.out;
}

// M_t^G per unit light power (Xu Eq. 27).
fn global_response_lobe(p: FastHairParams, lobe: u32, light: SrbfInFrame, theta_o: f32, phi_o: f32, sigma_f2: f32) -> vec3<f32> {
    return global_response_lobe_in_view(p, lobe, longitudinal_lobe(p.longitudinal, theta_o, p.alpha[lobe], p.beta[lobe]), light, phi_o, sigma_f2);
}

// global_response_lobe with the lobe's longitudinal function of the view (view_lobes).
fn global_response_lobe_in_view(p: FastHairParams, lobe: u32, longitudinal: LongitudinalLobe, light: SrbfInFrame, phi_o: f32, sigma_f2: f32) -> vec3<f32> {
    let theta_o = longitudinal.theta_o;
    let sigma = forward_spread(sigma_f2, light.lambda);
    let beta = p.beta[lobe];
    let g = gaussian_product(light.theta, SQRT_2 * sigma, longitudinal.mu, 2.0 * SQRT_2 * beta);
    let c = g.x / (2.0 * PI * sigma * 2.0 * beta * max(cos(light.theta), 1e-3));
    if (c < 1e-30) {
        return vec3<f32>(0.0);
    }
    let d = DualIntegrand(DUAL_GLOBAL, lobe, 0u, theta_o, phi_o - light.phi, longitudinal, 0.0, DualCell(0u, 0.0));
    return max(c * dual_quadrature(p, d, g.y, g.z), vec3<f32>(0.0));
}

// M^L per unit light power (Xu Eq. 29-31).
// cells: dual_cells of the point's absorption p.sigma_a; depth_behind: optical depth of the hair behind
// the point along the light's travel (DEPTH_UNBOUNDED: Zinke's).
fn local_response(p: FastHairParams, cells: array<DualCell, 3>, light: SrbfInFrame, theta_o: f32, phi_o: f32, sigma_f2: f32, depth_behind: f32) -> vec3<f32> {
    let sigma = forward_spread(sigma_f2, light.lambda);
    let azimuthal = (PI - abs(wrap_angle(light.phi - phi_o))) / (PI * PI);
    let lo = 0.5 * (theta_o - (light.theta + sigma));
    let hi = 0.5 * (theta_o - (light.theta - sigma));
    var out = vec3<f32>(0.0);
    var cs = cells;
    for (var c = 0u; c < 3u; c++) {
        // Each channel at the point's own absorption (its axis cell found once per point).
        let cell = cs[c];
        let ds = mean_delta_sigma(lo, hi, cell);
        let sb = max(ds.y, 1e-3);
        // Zinke's back lobe as M with tilt Delta_b / 2 and width sigma_b / 2 (dual_response.rs).
        let back = longitudinal_lobe(p.longitudinal, theta_o, 0.5 * ds.x, 0.5 * sb);
        let g = gaussian_product(light.theta, SQRT_2 * sigma, back.mu, SQRT_2 * sb);
        let k = azimuthal * g.x / (2.0 * PI * sigma * sb * max(cos(light.theta), 1e-3));
        if (k < 1e-30) {
            continue;
        }
        let d = DualIntegrand(DUAL_LOCAL, 0u, c, theta_o, 0.0, back, depth_behind, cell);
        out[c] = max(k * dual_quadrature(p, d, g.y, g.z).x, 0.0);
    }
    return out;
}

// Integral of an SRBF of bandwidth lambda over the sphere: pi lambda^2 (1 - e^(-4 / lambda^2)).
fn srbf_integral(lambda: f32) -> f32 {
    let l2 = lambda * lambda;
    return PI * l2 * (1.0 - exp(-4.0 / l2));
}

struct DualComponents {
    ms_global: vec3<f32>,
    ms_local: vec3<f32>,
}

// dual_scattering_components: (MS.global, MS.local) per unit light power.
fn dual_scattering_components(p: FastHairParams, direct_fraction: f32, transmittance_f: vec3<f32>, local_direct: vec3<f32>, global: vec3<f32>, local: vec3<f32>) -> DualComponents {
    let scattered = max(transmittance_f - vec3<f32>(direct_fraction), vec3<f32>(0.0)) * p.d_f;
    return DualComponents(scattered * global, direct_fraction * p.d_b * local_direct + scattered * p.d_b * local);
}
