// The exact azimuthal window integrals as a table (twin of src/scattering/azimuthal_table.rs): calN_TT and
// calN_TRT under every light (Xu Eq. 12) and calN_t^G of the forward-scattered light (Eq. 28). Each cell
// holds a two-node Gauss rule in the chord x = cos gamma_t of the window's measure, (w_1, w_1 x_1, w_2,
// w_2 x_2); the value for absorption s = 2 p sigma_a' is w_1 e^(-s x_1) + w_2 e^(-s x_2).
// The includer binds `azimuthal_table`: array<vec2<u32>> (AzimuthalTable::gpu): entries 0 and 1 the
// header's f32 bits (eta_lo, eta_hi, eta samples, eta), then cell k >= 1 at entry k + 1 as two half
// pairs (w_1, w_1 x_1), (w_2, w_2 x_2), scaled by HALF_SCALE (an exact power of two: the
// lookups interpolate the scaled cells and unscale their value, as exact as scaling each cell).
// Prepended: circular_gaussian (bessel_i0_scaled), fast_azimuthal (sigma_a_prime, bravais_eta_prime).

const TABLE_THETA_D: u32 = 32u;
const THETA_D_MAX: f32 = 1.5;
const TABLE_LAMBDA: u32 = 54u;
const TABLE_LAMBDA_MIN: f32 = 0.005;
// LAMBDA_PRIME_MAX: every lambda' the shading meets.
const TABLE_LAMBDA_MAX: f32 = 10.0;
const TABLE_DPHI: u32 = 256u;
// The cells' scale (src/scattering/half_cells.rs).
const HALF_SCALE: f32 = 1024.0;

fn table_trt_base() -> u32 {
    return 1u + TABLE_THETA_D * TABLE_LAMBDA * TABLE_DPHI;
}

fn table_box_base(eta_samples: u32) -> u32 {
    return table_trt_base() + eta_samples * TABLE_THETA_D * TABLE_LAMBDA * TABLE_DPHI;
}

fn window_energy(lambda_prime: f32) -> f32 {
    return TAU * bessel_i0_scaled(2.0 / (lambda_prime * lambda_prime));
}

struct AxisPosition {
    i: u32,
    w: f32,
}

fn axis_position(x: f32, n: u32) -> AxisPosition {
    let c = clamp(x, 0.0, f32(n - 1u));
    let i = min(u32(c), n - 2u);
    return AxisPosition(i, c - f32(i));
}

fn folded_dphi(dphi: f32) -> f32 {
    let d = dphi + PI;
    let wrapped = d - TAU * floor(d / TAU) - PI;
    return min(abs(wrapped), PI);
}

// The TRT caustic |phi_c| (0 when eta' >= 2) and support edge |Phi(2, 1)|, ordered (trt_knots in Rust).
fn trt_knots(eta_p: f32) -> vec2<f32> {
    var caustic = 0.0;
    if (eta_p < 2.0) {
        let hc = min(sqrt(max((4.0 - eta_p * eta_p) / 3.0, 0.0)), 1.0);
        caustic = abs(4.0 * asin_precise(hc / eta_p) - 2.0 * asin_precise(hc));
    }
    let edge = abs(4.0 * asin_precise(min(1.0 / eta_p, 1.0)) - PI);
    return vec2<f32>(min(caustic, edge), max(caustic, edge));
}

// The TRT cells' aligned azimuth coordinate u in [0, 1] of |dphi| (trt_u in Rust).
fn trt_u(dphi: f32, knots: vec2<f32>) -> f32 {
    let k1 = knots.x;
    let k2 = knots.y;
    if (dphi <= k1) {
        if (k1 > 0.0) {
            return dphi / (3.0 * k1);
        }
        return 1.0 / 3.0;
    }
    if (dphi <= k2) {
        if (k2 > k1) {
            return (1.0 + (dphi - k1) / (k2 - k1)) / 3.0;
        }
        return 2.0 / 3.0;
    }
    return (2.0 + sqrt(max((dphi - k2) / (PI - k2), 0.0))) / 3.0;
}

fn rule_value(c: vec4<f32>, s: vec3<f32>) -> vec3<f32> {
    var x1 = 1.0;
    var x2 = 1.0;
    if (c.x > 0.0) {
        x1 = c.y / c.x;
    }
    if (c.z > 0.0) {
        x2 = c.w / c.z;
    }
    return max(c.x, 0.0) * exp(-s * x1) + max(c.z, 0.0) * exp(-s * x2);
}

fn absorption_exponent(p: u32, eta: f32, sigma_a: vec3<f32>, theta_d: f32) -> vec3<f32> {
    return 2.0 * f32(p) * sigma_a_prime(sigma_a, eta, theta_d);
}

fn table_header() -> vec4<f32> {
    return vec4<f32>(bitcast<vec2<f32>>(azimuthal_table[0]), bitcast<vec2<f32>>(azimuthal_table[1]));
}

// Cell k (k >= 1) times HALF_SCALE.
fn table_cell(k: u32) -> vec4<f32> {
    let e = azimuthal_table[k + 1u];
    return vec4<f32>(unpack2x16float(e.x), unpack2x16float(e.y));
}

// Cells k and k + 1 (along dphi) at weight w of the second.
fn table_pair(k: u32, w: f32) -> vec4<f32> {
    return mix(table_cell(k), table_cell(k + 1u), w);
}

fn table_gaussian_cell(base: u32, it: u32, l: AxisPosition, f: AxisPosition) -> vec4<f32> {
    let row0 = base + (it * TABLE_LAMBDA + l.i) * TABLE_DPHI + f.i;
    return mix(table_pair(row0, f.w), table_pair(row0 + TABLE_DPHI, f.w), l.w);
}

fn table_gaussian_slab(base: u32, t: AxisPosition, l: AxisPosition, f: AxisPosition) -> vec4<f32> {
    return mix(table_gaussian_cell(base, t.i, l, f), table_gaussian_cell(base, t.i + 1u, l, f), t.w);
}

// AzimuthalTable::window_gaussian: calN_TT (p = 1) or calN_TRT (p = 2, eta_star = eta*-bar).
fn azimuthal_table_gaussian(p: u32, eta_star: f32, sigma_a: vec3<f32>, theta_d: f32, lambda_prime: f32, dphi: f32) -> vec3<f32> {
    let header = table_header();
    let eta_samples = u32(header.z);
    let t = axis_position(abs(theta_d) / THETA_D_MAX * f32(TABLE_THETA_D - 1u), TABLE_THETA_D);
    let lp = clamp(lambda_prime, TABLE_LAMBDA_MIN, TABLE_LAMBDA_MAX);
    let a = log(TABLE_LAMBDA_MIN);
    let b = log(TABLE_LAMBDA_MAX);
    let l = axis_position((log(lp) - a) / (b - a) * f32(TABLE_LAMBDA - 1u), TABLE_LAMBDA);
    var u = folded_dphi(dphi) / PI;
    var base = 1u;
    var eta = header.w;
    var e = AxisPosition(0u, 0.0);
    if (p == 2u) {
        base = table_trt_base();
        eta = eta_star;
        // The knots of the cells read: theta_d beyond the axis reads the last cells.
        u = trt_u(folded_dphi(dphi), trt_knots(bravais_eta_prime(eta_star, min(abs(theta_d), THETA_D_MAX))));
        if (eta_samples > 1u) {
            e = axis_position((eta_star - header.x) / (header.y - header.x) * f32(eta_samples - 1u), eta_samples);
        }
    }
    let f = axis_position(u * f32(TABLE_DPHI - 1u), TABLE_DPHI);
    let per_lobe = TABLE_THETA_D * TABLE_LAMBDA * TABLE_DPHI;
    var c = table_gaussian_slab(base + e.i * per_lobe, t, l, f);
    if (e.w > 0.0) {
        c = mix(c, table_gaussian_slab(base + (e.i + 1u) * per_lobe, t, l, f), e.w);
    }
    return window_energy(lambda_prime) / HALF_SCALE * rule_value(c, absorption_exponent(p, eta, sigma_a, theta_d));
}

// AzimuthalTable::window_box: calN_t^G (box window of half-width pi/2, over pi), lobe p = 0, 1, 2.
fn azimuthal_table_box(p: u32, sigma_a: vec3<f32>, theta_d: f32, dphi: f32) -> vec3<f32> {
    let header = table_header();
    let base = table_box_base(u32(header.z)) + p * TABLE_THETA_D * TABLE_DPHI;
    let t = axis_position(abs(theta_d) / THETA_D_MAX * f32(TABLE_THETA_D - 1u), TABLE_THETA_D);
    let f = axis_position(folded_dphi(dphi) / PI * f32(TABLE_DPHI - 1u), TABLE_DPHI);
    let r0 = base + t.i * TABLE_DPHI + f.i;
    let r1 = r0 + TABLE_DPHI;
    let c = mix(table_pair(r0, f.w), table_pair(r1, f.w), t.w);
    return rule_value(c, absorption_exponent(p, header.w, sigma_a, theta_d)) / HALF_SCALE;
}
