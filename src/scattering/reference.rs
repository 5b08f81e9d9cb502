//! Brute-force integrals of the exact model: the numbers fast forms and tests are checked against.
//! Each works on one colour channel (`channel` in 0..3) so no work is repeated per channel.

use super::marschner::{
    AzimuthalLobe, CausticFix, azimuthal_n_p, lobe_centre, longitudinal_m_p,
    longitudinal_m_p_normalized,
};
use super::numeric::{integrate_piecewise_relative, lobe_breaks};
use super::params::{CausticModel, HairParams, Lobe, LongitudinalModel, ModelVariant};
use std::f64::consts::PI;

/// Relative accuracy of the reference integrals.
pub const REFERENCE_REL_TOL: f64 = 1e-9;

/// Energy fraction one fiber scatters into lobe p: (1/2) integral_{-1}^{1} A_p(h) dh
/// (docs/hair-model.md, "Energy"). By the change of variables phi = phi(p, h) this equals
/// integral N_p dphi for the bare root sum.
pub fn scatter_fraction(
    params: &HairParams,
    variant: ModelVariant,
    lobe: Lobe,
    theta_d: f64,
    phi_h: f64,
    channel: usize,
) -> f64 {
    let az = AzimuthalLobe::new(params, variant, lobe, theta_d, phi_h);
    0.5 * integrate_piecewise_relative(
        &|h| az.attenuation_a_p(h)[channel],
        &[-1.0, 0.0, 1.0],
        REFERENCE_REL_TOL,
    )
}

/// integral_{-pi}^{pi} N_p(phi) dphi at fixed theta_d (and phi_h), by quadrature in phi split at
/// the azimuths where roots appear, vanish or merge (caustics) and around the caustic Gaussians.
pub fn azimuthal_energy(
    params: &HairParams,
    variant: ModelVariant,
    lobe: Lobe,
    theta_d: f64,
    phi_h: f64,
    channel: usize,
) -> f64 {
    let az = AzimuthalLobe::new(params, variant, lobe, theta_d, phi_h);
    let mut breaks = az.breakpoints();
    if variant.caustic == CausticModel::Marschner
        && lobe == Lobe::TRT
        && let Some(fix) = CausticFix::new(params, &az)
    {
        {
            for s in [-1.0, 1.0] {
                for k in [-4.0, -2.0, 0.0, 2.0, 4.0] {
                    let x = s * fix.phi_c + k * fix.w_c;
                    if x > -PI && x < PI {
                        breaks.push(x);
                    }
                }
            }
            breaks.sort_by(f64::total_cmp);
        }
    }
    integrate_piecewise_relative(
        &|phi| azimuthal_n_p(params, variant, &az, phi)[channel],
        &breaks,
        REFERENCE_REL_TOL,
    )
}

/// Directional albedo E_p(theta_o) = integral over the incident sphere of S_p(omega_i, omega_o) cos(theta_i) d omega_i
/// = integral_{-pi/2}^{pi/2} cos(theta_i) [integral_{-pi}^{pi} S_p cos(theta_i) dphi] dtheta_i, for a circular fiber
/// (eccentricity is set to 1): the radiance a fiber in a uniform white environment sends towards omega_o,
/// the white-furnace number.
///
/// Normalised ([`LongitudinalModel::Normalized`]): integral M_p cos(theta_i) d theta_i = 1, so E is the
/// scattered fraction (1/2) integral A_p dh, averaged over the theta_d the lobe covers; the three lobes
/// together reach 1 minus what p >= 3 would carry. Published: M_p is a unit-area Gaussian in
/// theta_h = (theta_i + theta_o)/2, so it integrates to 2 over theta_i and E is close to 2 x the scattered
/// fraction for narrow lobes (docs/hair-model.md, "Energy"). The published S is symmetric, so this
/// equals the integral over theta_o at fixed theta_i.
pub fn directional_albedo(
    params: &HairParams,
    variant: ModelVariant,
    lobe: Lobe,
    theta_o: f64,
    channel: usize,
) -> f64 {
    let mut p = *params;
    p.eccentricity = 1.0;
    let beta = p.beta(lobe);
    // Split theta_i around the lobe centre (std 2 beta in theta_i).
    let breaks = lobe_breaks(
        lobe_centre(&p, variant, lobe, theta_o),
        2.0 * beta,
        &[-8.0, -4.0, -2.0, -1.0, 0.0, 1.0, 2.0, 4.0, 8.0],
    );
    let integrand = |theta_i: f64| -> f64 {
        let theta_d = 0.5 * (theta_o - theta_i);
        // M_p times the factor that turns S cos(theta_i) d omega_i into d theta_i d phi.
        let m_weight = match variant.longitudinal {
            LongitudinalModel::Published => {
                let theta_h = 0.5 * (theta_i + theta_o);
                longitudinal_m_p(&p, lobe, theta_h) * theta_i.cos().powi(2) / theta_d.cos().powi(2)
            }
            LongitudinalModel::Normalized => {
                longitudinal_m_p_normalized(&p, lobe, theta_i, theta_o) * theta_i.cos()
            }
        };
        if m_weight < 1e-200 {
            return 0.0;
        }
        m_weight * azimuthal_energy(&p, variant, lobe, theta_d, 0.0, channel)
    };
    integrate_piecewise_relative(&integrand, &breaks, 1e-7)
}

/// The narrow-lobe limit of [`directional_albedo`] at theta_o, with theta_i* = 2 alpha_p - theta_o the lobe
/// centre and f_p the scattered fraction there: published, 2 f_p(theta_d*) cos^2(theta_i*) / cos^2(theta_d*);
/// normalised, f_p(theta_d*). Exact as beta -> 0 when the lobe stays inside (-pi/2, pi/2).
pub fn directional_albedo_narrow_limit(
    params: &HairParams,
    variant: ModelVariant,
    lobe: Lobe,
    theta_o: f64,
    channel: usize,
) -> f64 {
    let theta_i = 2.0 * params.alpha(lobe) - theta_o;
    let theta_d = 0.5 * (theta_o - theta_i);
    let f = scatter_fraction(params, variant, lobe, theta_d, 0.0, channel);
    match variant.longitudinal {
        LongitudinalModel::Published => 2.0 * f * theta_i.cos().powi(2) / theta_d.cos().powi(2),
        LongitudinalModel::Normalized => f,
    }
}
