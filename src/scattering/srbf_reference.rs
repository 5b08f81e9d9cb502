//! Brute-force SRBF response: integral over the sphere of G_j(omega_i) S_p(omega_i, omega_o) cos(theta_i) d omega_i
//! for the exact model, by nested adaptive quadrature. The yardstick of the fast form
//! ([`super::fast_response`]).
//!
//! The exact model here uses the bare root sum for N_TRT (caustic model `None`): the energy-conserving
//! form that Xu's energy-preserving circular Gaussians approximate (Marschner's caustic Gaussians change
//! the energy with the glint scale, which Xu's fit has no parameter for). The Fresnel model is the
//! caller's (Xu's Schlick for the fast-model tests).
//!
//! d omega = cos(theta_i) d theta_i d phi_i, so the integrand carries cos^2(theta_i) with the published M (cos(theta_i) with
//! the normalised M, whose S cos(theta_i) is M N).
//! Inner integral over phi_i: for a circular fiber, N_p(phi) = sum over roots of A_p(h) / |2 dphi/dh|, so
//! integral N_p(phi) w(phi) dphi = integral_{-1}^{1} A_p(h) / 2 w(phi(p, h)) dh, which needs no root finding
//! and has no singularity (h = sin t removes the square-root ends). With eccentricity the TRT index depends
//! on phi_h, so that lobe is integrated over phi directly, split at its caustics and root-count changes
//! (located by fixed-point iteration, since they move with eta*(phi_h)).

use super::frame::{FiberAngles, wrap_angle};
use super::marschner::{
    AzimuthalLobe, caustic_offset, lobe_centre, longitudinal_m_p, longitudinal_m_p_normalized,
    phi_p,
};
use super::numeric::integrate_piecewise;
use super::params::{CausticModel, HairParams, Lobe, LongitudinalModel, ModelVariant};
use std::f64::consts::{FRAC_PI_2, PI};

/// An SRBF light in the fiber frame (f64).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SrbfLight64 {
    pub theta: f64,
    pub phi: f64,
    pub lambda: f64,
}

impl SrbfLight64 {
    /// G(omega) = exp(2 (omega . omega_j - 1) / lambda^2).
    pub fn eval(&self, theta: f64, phi: f64) -> f64 {
        let d = theta.sin() * self.theta.sin()
            + theta.cos() * self.theta.cos() * (phi - self.phi).cos();
        (2.0 * (d - 1.0) / (self.lambda * self.lambda)).exp()
    }

    /// G along the circle of inclination theta (an inner integral's), its products of sines and
    /// cosines found once.
    pub fn at_theta(&self, theta: f64) -> SrbfOnCircle {
        SrbfOnCircle {
            sin_sin: theta.sin() * self.theta.sin(),
            cos_cos: theta.cos() * self.theta.cos(),
            phi: self.phi,
            two_over_lambda2: 2.0 / (self.lambda * self.lambda),
        }
    }
}

/// [`SrbfLight64::eval`] at a fixed inclination.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SrbfOnCircle {
    sin_sin: f64,
    cos_cos: f64,
    phi: f64,
    two_over_lambda2: f64,
}

impl SrbfOnCircle {
    pub fn eval(&self, phi: f64) -> f64 {
        let d = self.sin_sin + self.cos_cos * (phi - self.phi).cos();
        ((d - 1.0) * self.two_over_lambda2).exp()
    }
}

/// Relative tolerance of the nested integrals (the result is good to ~1e-5 relative, or 1e-10 of the
/// light's power absolute, whichever is larger).
pub const SRBF_REFERENCE_TOL: f64 = 1e-5;
/// Absolute floor of the inner (azimuthal) integrals, whose values are at most ~1.
const INNER_ABS_TOL: f64 = 1e-12;

fn sorted_in(mut v: Vec<f64>, lo: f64, hi: f64) -> Vec<f64> {
    v.retain(|x| x.is_finite() && *x > lo && *x < hi);
    v.push(lo);
    v.push(hi);
    v.sort_by(f64::total_cmp);
    v.dedup_by(|a, b| (*a - *b).abs() < 1e-13);
    v
}

/// inner(theta_i) = integral over phi_i of G(theta_i, phi_i) N_p(phi_o - phi_i) for a circular fiber (h form).
fn inner_h(az: &AzimuthalLobe, light: &SrbfLight64, theta_i: f64, phi_o: f64, ch: usize) -> f64 {
    let p = az.p();
    let g = light.at_theta(theta_i);
    // Over gamma_i = t in [-pi/2, pi/2]: h = sin t, and gamma_i is t itself (phi_p's and A_p's
    // arcsines of h, found once).
    let integrand = |t: f64| {
        let h = t.sin();
        let gamma_t = (h / az.eta_perp).clamp(-1.0, 1.0).asin();
        let phi = 2.0 * p as f64 * gamma_t - 2.0 * t + p as f64 * PI;
        0.5 * az.attenuation_a_p_at(h, t, gamma_t)[ch] * g.eval(phi_o - phi) * t.cos()
    };
    // Split at the offsets whose exit azimuth hits the light's centre and its azimuthal width.
    let lp = light.lambda / (theta_i.cos() * light.theta.cos()).max(1e-12).sqrt();
    let mut breaks = vec![0.0];
    for k in [-1.5, 0.0, 1.5] {
        for &h in az.roots(wrap_angle(phi_o - light.phi + k * lp)).as_slice() {
            breaks.push(h.clamp(-1.0, 1.0).asin());
        }
    }
    integrate_piecewise(
        &integrand,
        &sorted_in(breaks, -FRAC_PI_2, FRAC_PI_2),
        SRBF_REFERENCE_TOL,
        INNER_ABS_TOL,
    )
}

/// Fixed point phi = feature(eta*(phi_h = phi_o - phi/2)) for an azimuthal feature of TRT.
fn moving_feature(
    params: &HairParams,
    variant: ModelVariant,
    theta_d: f64,
    phi_o: f64,
    h_of: impl Fn(&AzimuthalLobe) -> Option<f64>,
) -> Option<f64> {
    for start in [0.0, 1.5, -1.5, 3.0] {
        let mut phi = start;
        for _ in 0..100 {
            let az = AzimuthalLobe::new(params, variant, Lobe::TRT, theta_d, phi_o - 0.5 * phi);
            let h = h_of(&az)?;
            let next = wrap_angle(phi_p(2, h, az.eta_perp));
            if (next - phi).abs() < 1e-13 {
                return Some(next);
            }
            phi = next;
        }
    }
    // Not a contraction from any start: the integral runs without this break.
    None
}

/// inner(theta_i) for TRT with eccentricity: integral over phi of G(theta_i, phi_o - phi) N_TRT(eta*(phi_h), phi).
fn inner_phi_eccentric(
    params: &HairParams,
    variant: ModelVariant,
    light: &SrbfLight64,
    theta_i: f64,
    theta_d: f64,
    phi_o: f64,
    ch: usize,
) -> f64 {
    let g = light.at_theta(theta_i);
    let integrand = |phi: f64| {
        let az = AzimuthalLobe::new(params, variant, Lobe::TRT, theta_d, phi_o - 0.5 * phi);
        az.azimuthal_n_p_roots(phi)[ch] * g.eval(phi_o - phi)
    };
    let lp = light.lambda / (theta_i.cos() * light.theta.cos()).max(1e-12).sqrt();
    let mut breaks = Vec::new();
    for k in [-2.0, -1.0, 0.0, 1.0, 2.0] {
        breaks.push(wrap_angle(phi_o - light.phi + k * lp));
    }
    for sign in [-1.0, 1.0] {
        let end = moving_feature(params, variant, theta_d, phi_o, |_| Some(sign));
        let caustic = moving_feature(params, variant, theta_d, phi_o, |az| {
            caustic_offset(2, az.eta_perp).map(|h| sign * h)
        });
        breaks.extend(end);
        breaks.extend(caustic);
    }
    integrate_piecewise(
        &integrand,
        &sorted_in(breaks, -PI, PI),
        SRBF_REFERENCE_TOL,
        INNER_ABS_TOL,
    )
}

/// The brute-force response of one lobe, one colour channel.
pub fn srbf_response_reference(
    params: &HairParams,
    fresnel_variant: ModelVariant,
    lobe: Lobe,
    light: SrbfLight64,
    wo: FiberAngles,
    ch: usize,
) -> f64 {
    let variant = ModelVariant {
        fresnel: fresnel_variant.fresnel,
        caustic: CausticModel::None,
        ..fresnel_variant
    };
    let (theta_o, phi_o) = (wo.theta, wo.phi);
    let centre = lobe_centre(params, variant, lobe, theta_o);
    let width = 2.0 * params.beta(lobe);
    let mut breaks = Vec::new();
    for k in [-4.0, -1.5, 0.0, 1.5, 4.0] {
        breaks.push(centre + k * width);
        breaks.push(light.theta + 0.5 * k * light.lambda);
    }
    let eccentric = lobe == Lobe::TRT && params.eccentricity != 1.0;
    let integrand = |theta_i: f64| {
        let theta_d = 0.5 * (theta_o - theta_i);
        // M_p times what turns S cos(theta_i) d omega_i into d theta_i d phi_i (with the inner integral's 1).
        let m = match variant.longitudinal {
            LongitudinalModel::Published => {
                longitudinal_m_p(params, lobe, 0.5 * (theta_i + theta_o)) * theta_i.cos().powi(2)
                    / theta_d.cos().powi(2)
            }
            LongitudinalModel::Normalized => {
                longitudinal_m_p_normalized(params, lobe, theta_i, theta_o) * theta_i.cos()
            }
        };
        if m < 1e-300 {
            return 0.0;
        }
        let inner = if eccentric {
            inner_phi_eccentric(params, variant, &light, theta_i, theta_d, phi_o, ch)
        } else {
            let az = AzimuthalLobe::new(params, variant, lobe, theta_d, 0.0);
            inner_h(&az, &light, theta_i, phi_o, ch)
        };
        m * inner
    };
    // Absolute floor: 1e-10 of the light's power (responses below 1e-4 of it are "dark" in the tests).
    let power =
        PI * light.lambda * light.lambda * (1.0 - (-4.0 / (light.lambda * light.lambda)).exp());
    integrate_piecewise(
        &integrand,
        &sorted_in(breaks, -FRAC_PI_2, FRAC_PI_2),
        SRBF_REFERENCE_TOL,
        1e-10 * power,
    )
}
