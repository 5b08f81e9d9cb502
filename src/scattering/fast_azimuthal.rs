//! Xu et al. 2011 Sec. 4.2.1-4.2.5: the azimuthal functions N_R, N_TT, N_TRT in closed or
//! circular-Gaussian form, and their inner integrals against the SRBF's azimuthal circular Gaussian
//! (Eq. 12):  calN_t(lambda', dphi, theta_d) = integral g^c(x; 0, lambda') N_t(theta_d, dphi - x) dx,
//! dphi = phi_o - phi_j.
//!
//! f32 throughout, written as the WGSL twins in `shaders/` are (same function names) where the GPU uses
//! them: N_R's inner integral, eta*-bar and the table's helpers. The circular-Gaussian fits of N_TT and
//! N_TRT are the published form, kept on the CPU with their tests; the renderer reads the exact
//! integrals from [`super::azimuthal_table`] at every lambda'. Xu's Schlick Fresnel is used everywhere
//! (the H tables are built with it).
//!
//! Changes relative to the paper, each measured by the tests:
//! - Circular-Gaussian integrals are the exact 2 pi e^-kappa I0(kappa), and the energy-preserving widths
//!   (Eq. 17 and the eta' > 2 lobe) invert that exact form by Newton's method instead of sqrt(pi) lambda;
//!   amplitudes are then set from the energy, so each fitted lobe carries exactly the Taylor energy.
//! - The caustic width w_c is Marschner's standard deviation; its circular Gaussians use bandwidth
//!   sqrt(2) w_c.
//! - The fast response's calN_TT and calN_TRT are the exact integrals of N_p instead of the fits
//!   ([`super::fast_exact_azimuthal`], read from [`super::azimuthal_table`]), under every light.
//! - T and T^2 in the energies (Eq. 19, 23) are interpolated at Chebyshev nodes of h^2 instead of
//!   Taylor-expanded at h = 0 (same even quartic form, same tables; [`attenuation_polynomial`]).
//! - N_TRT(0) for b_2 (Eq. 21) is the full root sum: for sqrt(2) < eta' < 2 phi(2, h) = 0 has the roots
//!   +-h_2 beside h = 0, found by bisection.

use super::circular_gaussian::{asin_precise, bessel_i0_scaled};
use super::lut::{Luts, lut_sample_c, lut_sample_h, lut_sample_r, wrap_angle_f32};
use std::f32::consts::{PI, SQRT_2, TAU};

/// lambda' is clamped to this (the C_k table's end); the azimuthal Gaussian is nearly flat there.
pub const LAMBDA_PRIME_MAX: f32 = 10.0;

pub type Rgb32 = [f32; 3];

/// eta'(theta_d) = sqrt(eta^2 - sin^2 theta_d) / cos theta_d (Bravais, perpendicular).
pub fn bravais_eta_prime(eta: f32, theta_d: f32) -> f32 {
    let s = theta_d.sin();
    (eta * eta - s * s).sqrt() / theta_d.cos().max(1e-6)
}

/// sigma_a' = sigma_a / cos(theta_t), sin(theta_t) = sin(theta_d) / eta (Xu Table 1).
pub fn sigma_a_prime(sigma_a: f32, eta: f32, theta_d: f32) -> f32 {
    let s = theta_d.sin() / eta;
    sigma_a / (1.0 - s * s).max(1e-12).sqrt()
}

/// Xu's Schlick Fresnel F(eta, theta_d, h) = F0 + (1 - F0)(1 - cos(theta_d) sqrt(1 - h^2))^5.
pub fn fresnel_schlick(eta: f32, cos_theta_d: f32, h: f32) -> f32 {
    let f0 = ((1.0 - eta) / (1.0 + eta)).powi(2);
    let c = 1.0 - cos_theta_d * (1.0 - h * h).max(0.0).sqrt();
    f0 + (1.0 - f0) * c * c * c * c * c
}

/// Fourth-order Taylor coefficients (a_0, a_2, a_4) of T(h) = exp(-2 sigma' sqrt(1 - h^2 / eta'^2)) around
/// h = 0 (Xu Eq. 18). With u = h^2 / eta'^2, sqrt(1 - u) = 1 - u/2 - u^2/8 - ..., so
/// T = e^(-2 sigma') exp(sigma' u + sigma' u^2 / 4) = e^(-2 sigma') (1 + sigma' u + (sigma'^2 / 2 + sigma' / 4) u^2).
/// T^2 (Eq. 22) is the same with 2 sigma'.
pub fn taylor_attenuation(sigma_prime: f32, eta_prime: f32) -> [f32; 3] {
    let t0 = (-2.0 * sigma_prime).exp();
    let e2 = 1.0 / (eta_prime * eta_prime);
    [
        t0,
        t0 * sigma_prime * e2,
        t0 * (0.5 * sigma_prime * sigma_prime + 0.25 * sigma_prime) * e2 * e2,
    ]
}

/// Coefficients (a_0, a_2, a_4) of an even quartic in h approximating T(h) = exp(-2 sigma' sqrt(1 - h^2 / eta'^2))
/// over the whole of [-1, 1]: the quadratic in q = h^2 through T at the Chebyshev nodes of q in [0, 1].
/// Xu's Taylor expansion (Eq. 18, [`taylor_attenuation`]) is exact at h = 0 but its error grows with
/// sigma' towards |h| = 1: for T^2 at sigma_a = 1 the TRT energy (Eq. 23) came out 4.3% low. The
/// interpolant has the same form (so the same H_k tables) and closed-form coefficients.
pub fn attenuation_polynomial(sigma_prime: f32, eta_prime: f32) -> [f32; 3] {
    const Q: [f32; 3] = [0.066_987_3, 0.5, 0.933_012_7];
    let t =
        |q: f32| (-2.0 * sigma_prime * (1.0 - q / (eta_prime * eta_prime)).max(0.0).sqrt()).exp();
    let (y0, y1, y2) = (t(Q[0]), t(Q[1]), t(Q[2]));
    // Newton form: y0 + d1 (q - q0) + d2 (q - q0)(q - q1).
    let d1 = (y1 - y0) / (Q[1] - Q[0]);
    let d2 = ((y2 - y1) / (Q[2] - Q[1]) - d1) / (Q[2] - Q[0]);
    [
        y0 - d1 * Q[0] + d2 * Q[0] * Q[1],
        d1 - d2 * (Q[0] + Q[1]),
        d2,
    ]
}

/// Exact T(h) (for the peak values b_tt, b_2, b_3, which are point values, not energies).
pub fn attenuation_exact(sigma_prime: f32, eta_prime: f32, h: f32) -> f32 {
    (-2.0 * sigma_prime * (1.0 - h * h / (eta_prime * eta_prime)).max(0.0).sqrt()).exp()
}

/// I1(x) e^-x (Abramowitz & Stegun 9.8.3, 9.8.4; relative error < 3e-7), x >= 0.
#[allow(clippy::excessive_precision)] // the published coefficients, verbatim
pub fn bessel_i1_scaled(x: f32) -> f32 {
    let ax = x.abs();
    if ax <= 3.75 {
        let t = (ax / 3.75) * (ax / 3.75);
        let i1 = ax
            * (0.5
                + t * (0.87890594
                    + t * (0.51498869
                        + t * (0.15084934
                            + t * (0.02658733 + t * (0.00301532 + t * 0.00032411))))));
        i1 * (-ax).exp()
    } else {
        let t = 3.75 / ax;
        let p = 0.39894228
            + t * (-0.03988024
                + t * (-0.00362018
                    + t * (0.00163801
                        + t * (-0.01031555
                            + t * (0.02282967
                                + t * (-0.02895312 + t * (0.01787654 + t * -0.00420059)))))));
        p / ax.sqrt()
    }
}

/// integral over a period of g^c with concentration kappa = 2 / lambda^2: 2 pi e^-kappa I0(kappa).
pub fn circular_gaussian_energy(kappa: f32) -> f32 {
    TAU * bessel_i0_scaled(kappa)
}

/// Newton's steps of [`circular_gaussian_kappa_for_ratio`]: from its start, two reach 5e-7 of the
/// energy over kappa in [1e-3, 1e8] (one: 1.3e-3); eight plain steps from 2 pi / ratio^2 did not
/// converge for kappa < 0.05 and cost the fitted lobes 20 % of `bench-fast`'s response.
pub const KAPPA_NEWTON_STEPS: usize = 2;

/// Newton's start for [`circular_gaussian_kappa_for_ratio`]: x = ratio / (2 pi) = I0s(kappa). Wide lobes
/// (x > 0.45, kappa below ~1): I0s(k) ~ e^-k (1 + k^2 / 4), inverted by one fixed-point step from
/// k = -ln x; narrow ones: ratio ~ sqrt(2 pi / kappa) (1 + 1 / (8 kappa)), kappa ~ 2 pi / ratio^2 + 1/4.
pub fn kappa_newton_start(ratio: f32) -> f32 {
    let x = ratio / TAU;
    if x > 0.45 {
        let k = -x.ln();
        return k + (1.0 + 0.25 * k * k).ln();
    }
    TAU / (ratio * ratio) + 0.25
}

/// The concentration kappa of the circular Gaussian whose period integral is `ratio` (= energy / peak),
/// 0 < ratio < 2 pi: [`KAPPA_NEWTON_STEPS`] of Newton's method on ln(2 pi I0s(kappa)) in s = ln kappa,
/// from [`kappa_newton_start`]. Ratios at or above 2 pi give a flat lobe (kappa -> 0).
pub fn circular_gaussian_kappa_for_ratio(ratio: f32) -> f32 {
    const KAPPA_MIN: f32 = 1e-4;
    const KAPPA_MAX: f32 = 1e8;
    if ratio.is_nan() || ratio >= TAU * 0.9999 {
        return KAPPA_MIN;
    }
    if ratio <= 0.0 {
        return KAPPA_MAX;
    }
    let target = ratio.ln();
    let mut s = kappa_newton_start(ratio).clamp(KAPPA_MIN, KAPPA_MAX).ln();
    for _ in 0..KAPPA_NEWTON_STEPS {
        let k = s.exp();
        let (i0, i1) = (bessel_i0_scaled(k), bessel_i1_scaled(k));
        let f = (TAU * i0).ln() - target;
        let df = k * (i1 / i0 - 1.0);
        if df.abs() < 1e-12 {
            break;
        }
        s = (s - (f / df).clamp(-3.0, 3.0)).clamp(KAPPA_MIN.ln(), KAPPA_MAX.ln());
    }
    s.exp()
}

/// A sum of circular Gaussians per channel: b_c g^c(phi; mu, lambda_c).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CircularLobe {
    /// Amplitude per channel.
    pub b: Rgb32,
    /// Centre (shared by the channels).
    pub mu: f32,
    /// Concentration kappa = 2 / lambda^2 per channel.
    pub kappa: Rgb32,
}

impl CircularLobe {
    /// Value at phi.
    pub fn eval(&self, phi: f32) -> Rgb32 {
        let c = (phi - self.mu).cos() - 1.0;
        std::array::from_fn(|i| self.b[i] * (self.kappa[i] * c).exp())
    }

    /// A lobe carrying `energy` with peak `peak` (Xu Eq. 17 with the exact Bessel integral).
    fn from_energy(mu: f32, peak: Rgb32, energy: Rgb32) -> Self {
        let mut lobe = Self {
            mu,
            ..Default::default()
        };
        for c in 0..3 {
            if energy[c] > 1e-30 && peak[c] > 1e-30 {
                let k = circular_gaussian_kappa_for_ratio(energy[c] / peak[c]);
                lobe.kappa[c] = k;
                lobe.b[c] = energy[c] / circular_gaussian_energy(k);
            } else {
                lobe.kappa[c] = 1.0;
            }
        }
        lobe
    }

    /// A lobe of fixed concentration carrying `energy`.
    fn with_kappa(mu: f32, kappa: f32, energy: Rgb32) -> Self {
        let e = circular_gaussian_energy(kappa);
        Self {
            b: energy.map(|x| (x / e).max(0.0)),
            mu,
            kappa: [kappa; 3],
        }
    }
}

/// The circular-Gaussian form of N_TT or N_TRT at one theta_d: up to three lobes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LobeFit {
    pub lobes: [CircularLobe; 3],
    pub count: usize,
}

impl LobeFit {
    pub fn eval(&self, phi: f32) -> Rgb32 {
        let mut out = [0.0; 3];
        for l in &self.lobes[..self.count] {
            let v = l.eval(phi);
            for c in 0..3 {
                out[c] += v[c];
            }
        }
        out
    }
}

/// Coefficients C_k(theta_d, eta), k = 0..6, of N_R = sum_k C_k |cos(phi/2)|^k (Xu Eq. 13):
/// N_R = (1/4) c F(eta, theta_d, sin(phi/2)) with c = |cos(phi/2)| and Schlick's F
/// = F0 + (1 - F0)(1 - cos(theta_d) c)^5, expanded binomially.
pub fn n_r_coefficients(eta: f32, theta_d: f32) -> [f32; 7] {
    let f0 = ((1.0 - eta) / (1.0 + eta)).powi(2);
    let x = -theta_d.cos();
    const BINOM5: [f32; 6] = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
    let mut c = [0.0; 7];
    c[1] = 0.25;
    let mut xn = 1.0;
    for n in 1..6 {
        xn *= x;
        c[n + 1] = 0.25 * (1.0 - f0) * BINOM5[n] * xn;
    }
    c
}

/// calN_R(lambda', dphi, theta_d) = sum_k C_k(theta_d, eta) calC_k(lambda', dphi) (Xu Eq. 14), read by
/// parts from the R table: (1/4) (F0 calC_1 + (1 - F0) calD) ([`crate::scattering::lut::RTable`]).
pub fn inner_integral_r(luts: &Luts, eta: f32, theta_d: f32, lambda_prime: f32, dphi: f32) -> f32 {
    let f0 = ((1.0 - eta) / (1.0 + eta)).powi(2);
    let [c1, d] = lut_sample_r(luts, lambda_prime, dphi, theta_d.cos());
    0.25 * (f0 * c1 + (1.0 - f0) * d)
}

/// [`inner_integral_r`] as Xu Eq. 14 writes it, from the seven C_k (the R table's reference).
pub fn inner_integral_r_ck(
    luts: &Luts,
    eta: f32,
    theta_d: f32,
    lambda_prime: f32,
    dphi: f32,
) -> f32 {
    let ck = n_r_coefficients(eta, theta_d);
    let table = lut_sample_c(luts, lambda_prime, dphi);
    (1..7).map(|k| ck[k] * table[k]).sum()
}

/// N_TT as one circular Gaussian centred at pi (Xu Eq. 15-19): peak b_tt = N_TT(pi) (root h = 0,
/// |dphi/dh| = 2 - 2/eta'), energy (1/2) sum_k a_k H_k^TT.
pub fn tt_lobe(luts: &Luts, eta: f32, sigma_a: Rgb32, theta_d: f32) -> CircularLobe {
    let eta_p = bravais_eta_prime(eta, theta_d);
    let cos_d = theta_d.cos();
    let f = fresnel_schlick(eta, cos_d, 0.0);
    let h = lut_sample_h(luts, false, eta, theta_d);
    let mut peak = [0.0; 3];
    let mut energy = [0.0; 3];
    for c in 0..3 {
        let s = sigma_a_prime(sigma_a[c], eta, theta_d);
        peak[c] = (1.0 - f) * (1.0 - f) * (-2.0 * s).exp() / (4.0 * (1.0 - 1.0 / eta_p));
        let a = attenuation_polynomial(s, eta_p);
        energy[c] = 0.5 * (a[0] * h[0] + a[1] * h[1] + a[2] * h[2]);
    }
    CircularLobe::from_energy(PI, peak, energy)
}

/// A_TRT(h) = (1 - F)^2 F T^2 with exact T, and |d phi(2, h) / dh| = |4 / sqrt(eta'^2 - h^2) - 2 / sqrt(1 - h^2)|.
fn trt_root_term(eta: f32, cos_d: f32, eta_p: f32, sigma_p: Rgb32, h: f32) -> Rgb32 {
    let f = fresnel_schlick(eta, cos_d, h);
    let d = (4.0 / (eta_p * eta_p - h * h).sqrt() - 2.0 / (1.0 - h * h).max(1e-12).sqrt()).abs();
    std::array::from_fn(|c| {
        let t = attenuation_exact(sigma_p[c], eta_p, h);
        (1.0 - f) * (1.0 - f) * f * t * t / (2.0 * d.max(1e-6))
    })
}

/// The root h_2 in (0, 1] of 2 asin(h/eta') = asin(h) for sqrt(2) < eta' < 2 (TRT's outgoing azimuth
/// 0 away from h = 0), in closed form: with gamma_t = asin(h/eta') <= pi/4 (true for eta' >= sqrt(2)),
/// sin(2 gamma_t) = h gives 2 (h/eta') sqrt(1 - h^2/eta'^2) = h, so h_2 = eta' sqrt(1 - eta'^2/4).
pub fn trt_zero_root(eta_p: f32) -> f32 {
    (eta_p * (1.0 - 0.25 * eta_p * eta_p).max(0.0).sqrt()).min(1.0)
}

/// N_TRT(0), the full root sum: h = 0, and +-h_2 ([`trt_zero_root`]) when eta' > sqrt(2).
pub fn trt_value_at_zero(eta: f32, cos_d: f32, eta_p: f32, sigma_p: Rgb32) -> Rgb32 {
    let mut n = trt_root_term(eta, cos_d, eta_p, sigma_p, 0.0);
    if eta_p > SQRT_2 && eta_p < 2.0 {
        let extra = trt_root_term(eta, cos_d, eta_p, sigma_p, trt_zero_root(eta_p));
        for c in 0..3 {
            n[c] += 2.0 * extra[c];
        }
    }
    n
}

pub fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// N_TRT as circular Gaussians (Xu Eq. 20-23) for index `eta` (eta, or the averaged eta* with
/// eccentricity). eta' < 2: b_1 (g^c(phi; phi*, w) + g^c(phi; -phi*, w)) + b_2 g^c(phi; 0, phi*), with
/// w = sqrt(2) w_c, b_2 = N_TRT(0) (1 - g^c(0; phi*, w))^2, and b_1 from the energy. eta' >= 2: one lobe at
/// 0 whose width blends from w to the energy-preserving width over [2, 2 + Delta eta'].
pub fn trt_lobes(
    luts: &Luts,
    eta: f32,
    sigma_a: Rgb32,
    theta_d: f32,
    caustic_width: f32,
    caustic_fade: f32,
) -> LobeFit {
    let eta_p = bravais_eta_prime(eta, theta_d);
    let cos_d = theta_d.cos();
    let h = lut_sample_h(luts, true, eta, theta_d);
    let sigma_p: Rgb32 = std::array::from_fn(|c| sigma_a_prime(sigma_a[c], eta, theta_d));
    let energy: Rgb32 = std::array::from_fn(|c| {
        let k = attenuation_polynomial(2.0 * sigma_p[c], eta_p);
        (0.5 * (k[0] * h[0] + k[1] * h[1] + k[2] * h[2])).max(0.0)
    });
    let w = SQRT_2 * caustic_width;
    let kappa_w = 2.0 / (w * w);
    let n0 = trt_value_at_zero(eta, cos_d, eta_p, sigma_p);
    let mut fit = LobeFit::default();
    if eta_p < 2.0 {
        let hc = ((4.0 - eta_p * eta_p) / 3.0).sqrt();
        let phi_star =
            wrap_angle_f32(4.0 * asin_precise(hc / eta_p) - 2.0 * asin_precise(hc) + TAU).abs();
        let damp = 1.0 - (kappa_w * ((phi_star).cos() - 1.0)).exp();
        let kappa_star = 2.0 / (phi_star * phi_star).max(1e-12);
        let e_star = circular_gaussian_energy(kappa_star);
        let e_w = circular_gaussian_energy(kappa_w);
        let mut b1 = [0.0; 3];
        let mut b2 = [0.0; 3];
        for c in 0..3 {
            b2[c] = n0[c] * damp * damp;
            b1[c] = ((energy[c] - b2[c] * e_star) / (2.0 * e_w)).max(0.0);
        }
        fit.lobes[0] = CircularLobe {
            b: b1,
            mu: phi_star,
            kappa: [kappa_w; 3],
        };
        fit.lobes[1] = CircularLobe {
            b: b1,
            mu: -phi_star,
            kappa: [kappa_w; 3],
        };
        fit.lobes[2] = CircularLobe {
            b: b2,
            mu: 0.0,
            kappa: [kappa_star; 3],
        };
        fit.count = 3;
    } else {
        let s = smoothstep(2.0, 2.0 + caustic_fade, eta_p);
        let wide = CircularLobe::from_energy(0.0, n0, energy);
        let mut lobe = CircularLobe::default();
        for c in 0..3 {
            // Blend the bandwidth lambda = sqrt(2 / kappa), then carry the energy at that width.
            let l3 = (2.0 / wide.kappa[c]).sqrt();
            let l = w + s * (l3 - w);
            let one = CircularLobe::with_kappa(0.0, 2.0 / (l * l), energy);
            lobe.b[c] = one.b[c];
            lobe.kappa[c] = one.kappa[c];
        }
        fit.lobes[0] = lobe;
        fit.count = 1;
    }
    fit
}

/// b integral g^c(x; 0, lambda') g^c(dphi - x; mu, lambda) dx in closed form: the product of two
/// circular Gaussians is kappa_m cos(x - mu_m) with kappa_m e^(i mu_m) = kappa' + kappa e^(i (dphi - mu)),
/// so the integral is 2 pi exp(kappa_m - kappa' - kappa) I0s(kappa_m) (docs/fast-form.md,
/// "Circular Gaussians").
pub fn circular_gaussian_convolution(kappa_prime: f32, dphi: f32, kappa: f32) -> f32 {
    let re = kappa_prime + kappa * dphi.cos();
    let im = kappa * dphi.sin();
    let km = (re * re + im * im).sqrt();
    TAU * (km - kappa_prime - kappa).exp() * bessel_i0_scaled(km)
}

/// calN for a fitted lobe set (Xu Eq. 12 with Eq. 16 or 20).
pub fn inner_integral_lobes(fit: &LobeFit, lambda_prime: f32, dphi: f32) -> Rgb32 {
    let kp = 2.0 / (lambda_prime * lambda_prime);
    let mut out = [0.0; 3];
    for l in &fit.lobes[..fit.count] {
        for c in 0..3 {
            if l.b[c] != 0.0 {
                out[c] += l.b[c] * circular_gaussian_convolution(kp, dphi - l.mu, l.kappa[c]);
            }
        }
    }
    out
}

/// The averaged eccentric index eta*-bar (Xu Eq. 24-26): cos(2 phi_h) averaged over the SRBF's azimuthal
/// circular Gaussian is 2 calC_2 / calC_0 - 1 at (lambda', phi_j + phi_o).
pub fn eta_star_mean(luts: &Luts, eta: f32, a: f32, lambda_prime: f32, phi_sum: f32) -> f32 {
    if a == 1.0 {
        return eta;
    }
    let eta1 = 2.0 * (eta - 1.0) * a * a - eta + 2.0;
    let eta2 = 2.0 * (eta - 1.0) / (a * a) - eta + 2.0;
    let c = lut_sample_c(luts, lambda_prime, phi_sum);
    let mean_cos = 2.0 * c[2] / c[0].max(1e-30) - 1.0;
    0.5 * ((eta1 + eta2) + mean_cos * (eta1 - eta2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scattering::marschner::AzimuthalLobe;
    use crate::scattering::{CausticModel, HairParams, Lobe, ModelVariant};

    /// The closed-form root of 2 asin(h/eta') = asin(h) against bisection of the same equation:
    /// g(h_c) > 0 at the caustic, g(1) < 0.
    #[test]
    fn trt_zero_root_solves_its_equation() {
        use crate::scattering::circular_gaussian::asin_precise;
        let mut worst = 0.0f32;
        for k in 1..400 {
            let eta_p = SQRT_2 + (2.0 - SQRT_2) * k as f32 / 400.0;
            let g = |h: f32| 2.0 * asin_precise(h / eta_p) - asin_precise(h);
            let (mut lo, mut hi) = (((4.0 - eta_p * eta_p) / 3.0).sqrt(), 1.0f32);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if g(mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            worst = worst.max((trt_zero_root(eta_p) - 0.5 * (lo + hi)).abs());
        }
        println!("closed-form TRT root against bisection: worst {worst:.2e}");
        assert!(worst < 1e-5, "{worst}");
    }

    #[test]
    fn kappa_inversion_recovers_the_energy() {
        // kappa over [1e-3, 1e8] (the clamp's end), wide lobes to narrow ones.
        let mut worst: f32 = 0.0;
        for k in 0..=255 {
            let kappa = 1e-3 * 1.1f32.powi(k);
            let ratio = circular_gaussian_energy(kappa);
            if ratio >= TAU * 0.9999 {
                continue;
            }
            let back = circular_gaussian_kappa_for_ratio(ratio);
            let e = circular_gaussian_energy(back) / ratio - 1.0;
            worst = worst.max(e.abs());
        }
        println!(
            "kappa from the energy ratio, {KAPPA_NEWTON_STEPS} Newton steps: worst relative energy {worst:.1e}"
        );
        assert!(worst < 2e-5, "{worst}");
    }

    #[test]
    fn n_r_polynomial_is_the_exact_r_lobe() {
        let v = ModelVariant {
            caustic: CausticModel::None,
            ..ModelVariant::XU
        };
        let p = HairParams::default();
        for theta_d in [0.0f64, 0.4, 1.1] {
            let az = AzimuthalLobe::new(&p, v, Lobe::R, theta_d, 0.0);
            let c = n_r_coefficients(1.55, theta_d as f32);
            for k in 0..20 {
                let phi = -3.0 + 0.3 * k as f64;
                let exact = az.azimuthal_n_p_roots(phi)[0];
                let x = (phi / 2.0).cos().abs() as f32;
                let poly: f32 = (0..7).map(|i| c[i] * x.powi(i as i32)).sum();
                assert!(
                    (poly as f64 - exact).abs() < 1e-6 + 1e-5 * exact,
                    "{theta_d} {phi}: {poly} vs {exact}"
                );
            }
        }
    }
}
