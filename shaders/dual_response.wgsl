// Multiple scattering per SRBF light by dual scattering (Xu 2011 Sec. 4.3, Zinke 2008): twin of
// src/scattering/dual_response.rs and of DualTables::lookup / mean_delta_sigma in dual_terms.rs.
// Prepended: circular_gaussian, lut, fast_azimuthal, azimuthal_table, fast_response. The includer
// binds `dual_tables`: DUAL_SAMPLES x 4 vec4 (A_b, Delta_b, sigma_b, a_f per sample, RGB) followed by
// (DUAL_SAMPLES + 1) x 2 vec4 (prefix sums of Delta_b and sigma_b).

const DUAL_SAMPLES: u32 = 128u;
const DUAL_GLOBAL: u32 = 0u;
const DUAL_LOCAL: u32 = 1u;

fn dual_position(theta: f32) -> f32 {
    return clamp((theta + FRAC_PI_2) / PI, 0.0, 1.0) * f32(DUAL_SAMPLES - 1u);
}

// DualTables::lookup, term k (0 = A_b, 1 = Delta_b, 2 = sigma_b, 3 = a_f).
fn dual_lookup(k: u32, theta: f32) -> vec3<f32> {
    let x = dual_position(theta);
    let i = min(u32(x), DUAL_SAMPLES - 2u);
    let w = x - f32(i);
    return mix(dual_tables[4u * i + k].xyz, dual_tables[4u * (i + 1u) + k].xyz, w);
}

fn dual_sat(k: u32, x: f32) -> vec3<f32> {
    let i = min(u32(x), DUAL_SAMPLES - 1u);
    let w = x - f32(i);
    let base = 4u * DUAL_SAMPLES;
    return mix(dual_tables[base + 2u * i + k].xyz, dual_tables[base + 2u * (i + 1u) + k].xyz, w);
}

struct DeltaSigma {
    delta: vec3<f32>,
    sigma: vec3<f32>,
}

// DualTables::mean_delta_sigma: means of Delta_b and sigma_b over theta in [lo, hi] (Xu Eq. 31).
fn mean_delta_sigma(lo: f32, hi: f32) -> DeltaSigma {
    let a = dual_position(min(lo, hi)) + 0.5;
    let b = dual_position(max(lo, hi)) + 0.5;
    if (b - a < 1e-4) {
        let t = 0.5 * (lo + hi);
        return DeltaSigma(dual_lookup(1u, t), dual_lookup(2u, t));
    }
    return DeltaSigma((dual_sat(0u, b) - dual_sat(0u, a)) / (b - a), (dual_sat(1u, b) - dual_sat(1u, a)) / (b - a));
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
    let a = dual_lookup(0u, theta_d)[d.channel] * backscatter_depth_fraction(dual_lookup(3u, theta_d)[d.channel], d.depth_behind);
    return vec3<f32>(w * a);
}

// linear_quadrature of fast_response.rs over dual_integrand (parabolas on paired segments).
fn dual_quadrature(p: FastHairParams, d: DualIntegrand, mu: f32, l: f32) -> vec3<f32> {
    let m = p.quadrature_segments;
    var out = vec3<f32>(0.0);
    var x0 = quadrature_sample(0u, m, mu, l);
    var f0 = dual_integrand(p, d, x0);
    var s = 1u;
    loop {
        if (s > m) {
            break;
        }
        let x1 = quadrature_sample(s, m, mu, l);
        let f1 = dual_integrand(p, d, x1);
        if (s < m) {
            let x2 = quadrature_sample(s + 1u, m, mu, l);
            let f2 = dual_integrand(p, d, x2);
            if (x2 > x0 && x1 > x0 && x2 > x1) {
                out = out + quadrature_parabola_pair(x0, x1, x2, f0, f1, f2, mu, l);
            } else if (x2 > x0) {
                out = out + quadrature_linear_piece(x0, x2, f0, f2, mu, l);
            }
            x0 = x2;
            f0 = f2;
            s = s + 2u;
            continue;
        }
        out = out + quadrature_linear_piece(x0, x1, f0, f1, mu, l);
        x0 = x1;
        f0 = f1;
        s = s + 1u;
    }
    return out;
}

// M_t^G per unit light power (Xu Eq. 27).
fn global_response_lobe(p: FastHairParams, lobe: u32, light: SrbfInFrame, theta_o: f32, phi_o: f32, sigma_f2: f32) -> vec3<f32> {
    let sigma = forward_spread(sigma_f2, light.lambda);
    let longitudinal = longitudinal_lobe(p.longitudinal, theta_o, p.alpha[lobe], p.beta[lobe]);
    let g = gaussian_product(light.theta, SQRT_2 * sigma, longitudinal.mu, 2.0 * SQRT_2 * p.beta[lobe]);
    let c = g.x / (2.0 * PI * sigma * 2.0 * p.beta[lobe] * max(cos(light.theta), 1e-3));
    if (c < 1e-30) {
        return vec3<f32>(0.0);
    }
    let d = DualIntegrand(DUAL_GLOBAL, lobe, 0u, theta_o, phi_o - light.phi, longitudinal, 0.0);
    return max(c * dual_quadrature(p, d, g.y, g.z), vec3<f32>(0.0));
}

// M^L per unit light power (Xu Eq. 29-31).
// depth_behind: optical depth of the hair behind the point along the light's travel (DEPTH_UNBOUNDED: Zinke's).
fn local_response(p: FastHairParams, light: SrbfInFrame, theta_o: f32, phi_o: f32, sigma_f2: f32, depth_behind: f32) -> vec3<f32> {
    let sigma = forward_spread(sigma_f2, light.lambda);
    let azimuthal = (PI - abs(wrap_angle(light.phi - phi_o))) / (PI * PI);
    let ds = mean_delta_sigma(0.5 * (theta_o - (light.theta + sigma)), 0.5 * (theta_o - (light.theta - sigma)));
    var out = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        let sb = max(ds.sigma[c], 1e-3);
        // Zinke's back lobe as M with tilt Delta_b / 2 and width sigma_b / 2 (dual_response.rs).
        let back = longitudinal_lobe(p.longitudinal, theta_o, 0.5 * ds.delta[c], 0.5 * sb);
        let g = gaussian_product(light.theta, SQRT_2 * sigma, back.mu, SQRT_2 * sb);
        let k = azimuthal * g.x / (2.0 * PI * sigma * sb * max(cos(light.theta), 1e-3));
        if (k < 1e-30) {
            continue;
        }
        let d = DualIntegrand(DUAL_LOCAL, 0u, c, theta_o, 0.0, back, depth_behind);
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
