//! Fresnel reflectance for the hair model (Marschner et al. 2003, Appendix B; Xu et al. 2011 Sec. 4.1).

/// Bravais effective index for the perpendicular polarisation, eta'(theta_d)
/// = sqrt(eta^2 - sin^2 theta_d) / cos theta_d (Marschner 2003 Eq. 3; docs/hair-model.md).
pub fn bravais_perpendicular(eta: f64, theta_d: f64) -> f64 {
    let s = theta_d.sin();
    (eta * eta - s * s).max(0.0).sqrt() / theta_d.cos()
}

/// Bravais effective index for the parallel polarisation, eta''(theta_d)
/// = eta^2 cos theta_d / sqrt(eta^2 - sin^2 theta_d).
pub fn bravais_parallel(eta: f64, theta_d: f64) -> f64 {
    let s = theta_d.sin();
    eta * eta * theta_d.cos() / (eta * eta - s * s).max(f64::MIN_POSITIVE).sqrt()
}

/// Reflectance of one polarisation at an interface from index 1 into index `eta`
/// (eta < 1 means leaving the denser medium). Total internal reflection gives 1.
fn fresnel_polarised(eta: f64, cos_i: f64, parallel: bool) -> f64 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin_t2 = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let r = if parallel {
        (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    } else {
        (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    };
    r * r
}

/// Marschner's F(eta', eta'', gamma): the unpolarised average of the perpendicular reflectance with
/// index eta' and the parallel reflectance with index eta'', at azimuthal incidence angle gamma.
pub fn fresnel_bravais(eta_perp: f64, eta_par: f64, gamma: f64) -> f64 {
    let c = gamma.cos();
    0.5 * (fresnel_polarised(eta_perp, c, false) + fresnel_polarised(eta_par, c, true))
}

/// Schlick's approximation as Xu et al. 2011 write it: F0 + (1 - F0)(1 - cos(theta_d) sqrt(1 - h^2))^5,
/// F0 = ((1 - eta)/(1 + eta))^2 (Xu Sec. 4.1, text after Eq. 12).
pub fn fresnel_schlick_xu(eta: f64, theta_d: f64, h: f64) -> f64 {
    let f0 = ((1.0 - eta) / (1.0 + eta)).powi(2);
    let c = theta_d.cos() * (1.0 - h * h).max(0.0).sqrt();
    f0 + (1.0 - f0) * (1.0 - c).powi(5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_matches_f0() {
        let f = fresnel_bravais(1.55, 1.55, 0.0);
        assert!((f - ((0.55f64 / 2.55).powi(2))).abs() < 1e-12);
        assert!((fresnel_schlick_xu(1.55, 0.0, 0.0) - f).abs() < 1e-12);
    }

    #[test]
    fn bravais_reduces_to_eta_in_the_normal_plane() {
        assert!((bravais_perpendicular(1.55, 0.0) - 1.55).abs() < 1e-15);
        assert!((bravais_parallel(1.55, 0.0) - 1.55).abs() < 1e-15);
        assert!(bravais_perpendicular(1.55, 0.8) > 1.55);
    }

    #[test]
    fn grazing_and_total_internal_reflection() {
        assert!((fresnel_bravais(1.55, 1.55, std::f64::consts::FRAC_PI_2) - 1.0).abs() < 1e-9);
        // Inside (eta < 1) beyond the critical angle everything reflects.
        assert_eq!(fresnel_bravais(1.0 / 1.55, 1.0 / 1.55, 1.2), 1.0);
        // Reciprocity of the perpendicular term across the interface.
        let gi: f64 = 0.5;
        let gt = (gi.sin() / 1.55).asin();
        let a = fresnel_polarised(1.55, gi.cos(), false);
        let b = fresnel_polarised(1.0 / 1.55, gt.cos(), false);
        assert!((a - b).abs() < 1e-12);
    }
}
