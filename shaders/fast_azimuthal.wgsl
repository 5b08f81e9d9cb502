// Xu 2011 Sec. 4.2.1-4.2.5: N_R, N_TT, N_TRT in closed or circular-Gaussian form and their inner
// integrals against the SRBF's azimuthal circular Gaussian. Twin of src/scattering/fast_azimuthal.rs.

// eta'(theta_d) = sqrt(eta^2 - sin^2 theta_d) / cos theta_d.
fn bravais_eta_prime(eta: f32, theta_d: f32) -> f32 {
    let s = sin(theta_d);
    return sqrt(eta * eta - s * s) / max(cos(theta_d), 1e-6);
}

// sigma_a' = sigma_a / cos(theta_t), sin(theta_t) = sin(theta_d) / eta.
fn sigma_a_prime(sigma_a: vec3<f32>, eta: f32, theta_d: f32) -> vec3<f32> {
    let s = sin(theta_d) / eta;
    return sigma_a / sqrt(max(1.0 - s * s, 1e-12));
}

// Xu's Schlick Fresnel F(eta, theta_d, h).
fn fresnel_schlick(eta: f32, cos_theta_d: f32, h: f32) -> f32 {
    let f0 = ((1.0 - eta) / (1.0 + eta)) * ((1.0 - eta) / (1.0 + eta));
    let c = 1.0 - cos_theta_d * sqrt(max(1.0 - h * h, 0.0));
    return f0 + (1.0 - f0) * c * c * c * c * c;
}

// Even quartic in h through T(h) = exp(-2 sigma' sqrt(1 - h^2/eta'^2)) at Chebyshev nodes of h^2 (per channel):
// returns (a_0, a_2, a_4) as three vec3 (one per power).
struct AttenuationPolynomial {
    a0: vec3<f32>,
    a2: vec3<f32>,
    a4: vec3<f32>,
}

fn attenuation_polynomial(sigma_prime: vec3<f32>, eta_prime: f32) -> AttenuationPolynomial {
    let q0 = 0.0669873;
    let q1 = 0.5;
    let q2 = 0.9330127;
    let e2 = eta_prime * eta_prime;
    let y0 = exp(-2.0 * sigma_prime * sqrt(max(1.0 - q0 / e2, 0.0)));
    let y1 = exp(-2.0 * sigma_prime * sqrt(max(1.0 - q1 / e2, 0.0)));
    let y2 = exp(-2.0 * sigma_prime * sqrt(max(1.0 - q2 / e2, 0.0)));
    let d1 = (y1 - y0) / (q1 - q0);
    let d2 = ((y2 - y1) / (q2 - q1) - d1) / (q2 - q0);
    var p: AttenuationPolynomial;
    p.a0 = y0 - d1 * q0 + d2 * q0 * q1;
    p.a2 = d1 - d2 * (q0 + q1);
    p.a4 = d2;
    return p;
}

fn attenuation_exact(sigma_prime: vec3<f32>, eta_prime: f32, h: f32) -> vec3<f32> {
    return exp(-2.0 * sigma_prime * sqrt(max(1.0 - h * h / (eta_prime * eta_prime), 0.0)));
}

// b_c g^c(phi; mu, kappa_c) per channel.
struct CircularLobe {
    b: vec3<f32>,
    mu: f32,
    kappa: vec3<f32>,
}

struct LobeFit {
    lobes: array<CircularLobe, 3>,
    count: u32,
}

// A lobe carrying `energy` with peak `peak` (Xu Eq. 17, exact Bessel integral).
fn circular_lobe_from_energy(mu: f32, peak: vec3<f32>, energy: vec3<f32>) -> CircularLobe {
    var lobe: CircularLobe;
    lobe.mu = mu;
    for (var c = 0u; c < 3u; c++) {
        if (energy[c] > 1e-30 && peak[c] > 1e-30) {
            let k = circular_gaussian_kappa_for_ratio(energy[c] / peak[c]);
            lobe.kappa[c] = k;
            lobe.b[c] = energy[c] / circular_gaussian_energy(k);
        } else {
            lobe.kappa[c] = 1.0;
            lobe.b[c] = 0.0;
        }
    }
    return lobe;
}

// Coefficients of N_R = sum_k C_k |cos(phi/2)|^k (Xu Eq. 13).
fn n_r_coefficients(eta: f32, theta_d: f32) -> array<f32, 7> {
    let f0 = ((1.0 - eta) / (1.0 + eta)) * ((1.0 - eta) / (1.0 + eta));
    let x = -cos(theta_d);
    let binom5 = array<f32, 6>(1.0, 5.0, 10.0, 10.0, 5.0, 1.0);
    var c: array<f32, 7>;
    c[0] = 0.0;
    c[1] = 0.25;
    var xn = 1.0;
    for (var n = 1u; n < 6u; n++) {
        xn = xn * x;
        c[n + 1u] = 0.25 * (1.0 - f0) * binom5[n] * xn;
    }
    return c;
}

// calN_R = sum_k C_k calC_k(lambda', dphi) (Xu Eq. 14).
fn inner_integral_r(eta: f32, theta_d: f32, lambda_prime: f32, dphi: f32) -> f32 {
    let ck = n_r_coefficients(eta, theta_d);
    let table = lut_sample_c(lambda_prime, dphi);
    var sum = 0.0;
    for (var k = 1u; k < 7u; k++) {
        sum = sum + ck[k] * table[k];
    }
    return sum;
}

// N_TT as one circular Gaussian at pi (Xu Eq. 15-19).
fn tt_lobe(eta: f32, sigma_a: vec3<f32>, theta_d: f32) -> CircularLobe {
    let eta_p = bravais_eta_prime(eta, theta_d);
    let f = fresnel_schlick(eta, cos(theta_d), 0.0);
    let h = lut_sample_h(false, eta, theta_d);
    let s = sigma_a_prime(sigma_a, eta, theta_d);
    let peak = (1.0 - f) * (1.0 - f) * exp(-2.0 * s) / (4.0 * (1.0 - 1.0 / eta_p));
    let a = attenuation_polynomial(s, eta_p);
    let energy = 0.5 * (a.a0 * h.x + a.a2 * h.y + a.a4 * h.z);
    return circular_lobe_from_energy(PI, peak, energy);
}

// A_TRT(h) / (2 |d phi(2, h) / dh|) with exact T.
fn trt_root_term(eta: f32, cos_d: f32, eta_p: f32, sigma_p: vec3<f32>, h: f32) -> vec3<f32> {
    let f = fresnel_schlick(eta, cos_d, h);
    let d = abs(4.0 / sqrt(eta_p * eta_p - h * h) - 2.0 / sqrt(max(1.0 - h * h, 1e-12)));
    let t = attenuation_exact(sigma_p, eta_p, h);
    return (1.0 - f) * (1.0 - f) * f * t * t / (2.0 * max(d, 1e-6));
}

// The root h_2 of 2 asin(h/eta') = asin(h) for sqrt(2) < eta' < 2, closed form (trt_zero_root in Rust).
fn trt_zero_root(eta_p: f32) -> f32 {
    return min(eta_p * sqrt(max(1.0 - 0.25 * eta_p * eta_p, 0.0)), 1.0);
}

// N_TRT(0), the full root sum.
fn trt_value_at_zero(eta: f32, cos_d: f32, eta_p: f32, sigma_p: vec3<f32>) -> vec3<f32> {
    var n = trt_root_term(eta, cos_d, eta_p, sigma_p, 0.0);
    if (eta_p > SQRT_2 && eta_p < 2.0) {
        n = n + 2.0 * trt_root_term(eta, cos_d, eta_p, sigma_p, trt_zero_root(eta_p));
    }
    return n;
}

// N_TRT as circular Gaussians (Xu Eq. 20-23).
fn trt_lobes(eta: f32, sigma_a: vec3<f32>, theta_d: f32, caustic_width: f32, caustic_fade: f32) -> LobeFit {
    let eta_p = bravais_eta_prime(eta, theta_d);
    let cos_d = cos(theta_d);
    let h = lut_sample_h(true, eta, theta_d);
    let sigma_p = sigma_a_prime(sigma_a, eta, theta_d);
    let k = attenuation_polynomial(2.0 * sigma_p, eta_p);
    let energy = max(0.5 * (k.a0 * h.x + k.a2 * h.y + k.a4 * h.z), vec3<f32>(0.0));
    let w = SQRT_2 * caustic_width;
    let kappa_w = 2.0 / (w * w);
    let n0 = trt_value_at_zero(eta, cos_d, eta_p, sigma_p);
    var fit: LobeFit;
    if (eta_p < 2.0) {
        let hc = sqrt((4.0 - eta_p * eta_p) / 3.0);
        let phi_star = abs(wrap_angle(4.0 * asin_precise(hc / eta_p) - 2.0 * asin_precise(hc) + TAU));
        let damp = 1.0 - exp(kappa_w * (cos(phi_star) - 1.0));
        let kappa_star = 2.0 / max(phi_star * phi_star, 1e-12);
        let e_star = circular_gaussian_energy(kappa_star);
        let e_w = circular_gaussian_energy(kappa_w);
        let b2 = n0 * damp * damp;
        let b1 = max((energy - b2 * e_star) / (2.0 * e_w), vec3<f32>(0.0));
        fit.lobes[0] = CircularLobe(b1, phi_star, vec3<f32>(kappa_w));
        fit.lobes[1] = CircularLobe(b1, -phi_star, vec3<f32>(kappa_w));
        fit.lobes[2] = CircularLobe(b2, 0.0, vec3<f32>(kappa_star));
        fit.count = 3u;
    } else {
        let s = smoothstep_f(2.0, 2.0 + caustic_fade, eta_p);
        let wide = circular_lobe_from_energy(0.0, n0, energy);
        var lobe: CircularLobe;
        lobe.mu = 0.0;
        for (var c = 0u; c < 3u; c++) {
            let l3 = sqrt(2.0 / wide.kappa[c]);
            let l = w + s * (l3 - w);
            let kappa = 2.0 / (l * l);
            lobe.kappa[c] = kappa;
            lobe.b[c] = max(energy[c] / circular_gaussian_energy(kappa), 0.0);
        }
        fit.lobes[0] = lobe;
        fit.count = 1u;
    }
    return fit;
}

// calN for a fitted lobe set (Xu Eq. 12 with Eq. 16 or 20).
fn inner_integral_lobes(fit: LobeFit, lambda_prime: f32, dphi: f32) -> vec3<f32> {
    let kp = 2.0 / (lambda_prime * lambda_prime);
    var out = vec3<f32>(0.0);
    for (var i = 0u; i < fit.count; i++) {
        let l = fit.lobes[i];
        for (var c = 0u; c < 3u; c++) {
            if (l.b[c] != 0.0) {
                out[c] = out[c] + l.b[c] * circular_gaussian_convolution(kp, dphi - l.mu, l.kappa[c]);
            }
        }
    }
    return out;
}

// The averaged eccentric index eta*-bar (Xu Eq. 24-26).
fn eta_star_mean(eta: f32, a: f32, lambda_prime: f32, phi_sum: f32) -> f32 {
    if (a == 1.0) {
        return eta;
    }
    let eta1 = 2.0 * (eta - 1.0) * a * a - eta + 2.0;
    let eta2 = 2.0 * (eta - 1.0) / (a * a) - eta + 2.0;
    let c = lut_sample_c(lambda_prime, phi_sum);
    let mean_cos = 2.0 * c[2] / max(c[0], 1e-30) - 1.0;
    return 0.5 * ((eta1 + eta2) + mean_cos * (eta1 - eta2));
}
