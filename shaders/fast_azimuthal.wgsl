// Xu 2011 Sec. 4.2.1-4.2.5: N_R in closed form and its inner integral against the SRBF's azimuthal
// circular Gaussian, eta*-bar, and the helpers of the TT and TRT table (azimuthal_table.wgsl, which
// holds their inner integrals at every lambda'). Twin of src/scattering/fast_azimuthal.rs, whose
// circular-Gaussian fits of N_TT and N_TRT (Xu's published form, tested there) the GPU does not use.

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

// calN_R = sum_k C_k calC_k(lambda', dphi) (Xu Eq. 14), with N_R = (1/4) |cos(phi/2)| F (Xu Eq. 13,
// Schlick's F), read by parts from the R table: (1/4) (F0 calC_1 + (1 - F0) calD) (RTable in lut.rs).
fn inner_integral_r(eta: f32, theta_d: f32, lambda_prime: f32, dphi: f32) -> f32 {
    let f0 = ((1.0 - eta) / (1.0 + eta)) * ((1.0 - eta) / (1.0 + eta));
    let v = lut_sample_r(lambda_prime, dphi, cos(theta_d));
    return 0.25 * (f0 * v.x + (1.0 - f0) * v.y);
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
