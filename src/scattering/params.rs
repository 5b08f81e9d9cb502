//! Marschner hair parameters (Marschner et al. 2003, Table 1) and named presets.
//!
//! Angles are stored in radians. `sigma_a` is the absorption coefficient per unit fiber RADIUS
//! (the chord through a unit circle has length 2 cos(gamma_t): docs/hair-model.md), per RGB
//! channel.
//! The lobe shifts and widths of TT and TRT default to Marschner's couplings
//! (alpha_TT = -alpha_R/2, alpha_TRT = -3 alpha_R/2, beta_TT = beta_R/2, beta_TRT = 2 beta_R);
//! each can be overridden.

use serde::{Deserialize, Serialize};

/// Which lobe: p = number of internal path segments minus one (R = 0, TT = 1, TRT = 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Lobe {
    R,
    TT,
    TRT,
}

impl Lobe {
    pub const ALL: [Lobe; 3] = [Lobe::R, Lobe::TT, Lobe::TRT];

    /// Marschner's p.
    pub fn p(self) -> u32 {
        match self {
            Lobe::R => 0,
            Lobe::TT => 1,
            Lobe::TRT => 2,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Lobe::R => "R",
            Lobe::TT => "TT",
            Lobe::TRT => "TRT",
        }
    }
}

/// Fresnel term used by the azimuthal attenuation A_p.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum FresnelModel {
    /// Full dielectric Fresnel with Bravais indices eta' (perpendicular) and eta'' (parallel); the
    /// internal reflection of TRT uses F(1/eta', 1/eta'', gamma_t) (Marschner 2003).
    #[default]
    Exact,
    /// Xu et al. 2011: Schlick's approximation F0 + (1-F0)(1 - cos(theta_d) sqrt(1-h^2))^5 with
    /// F0 = ((1-eta)/(1+eta))^2, the same external value reused for the internal reflection.
    XuSchlick,
}

/// Treatment of the TRT caustic singularities.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum CausticModel {
    /// Marschner 2003 Sec. 4.3: the singular peaks at +-phi_c are replaced by Gaussians of width w_c,
    /// limited by the caustic intensity limit, faded out over Delta eta' as eta' approaches 2.
    #[default]
    Marschner,
    /// The bare root sum (integrable 1/sqrt singularities at the caustics). Conserves energy exactly.
    None,
}

/// The longitudinal function M_p and the factor that goes with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum LongitudinalModel {
    /// d'Eon et al. 2011's energy-conserving form, normalised over the incident inclination:
    /// M_p(theta_i, theta_o) = csch(1/v) / (2v) exp(-sin theta_i sin theta_o' / v) I0(cos theta_i cos theta_o' / v)
    /// with integral M_p cos(theta_i) d theta_i = 1, v_p = (2 beta_p)^2 (the published lobe's variance in
    /// theta_i, so the two forms have the same width) and the tilt on the outgoing inclination,
    /// theta_o' = theta_o - 2 alpha_p (as pbrt-v4 and Mitsuba 3 apply it). No 1/cos^2(theta_d):
    /// S cos(theta_i) = sum_p M_p N_p, and a lossless fiber in a white furnace renders at ~1.
    #[default]
    Normalized,
    /// Marschner 2003 / Xu 2011 Eq. 7 as published: M_p(theta_h) a unit-area Gaussian in theta_h and
    /// S = sum_p M_p N_p / cos^2(theta_d). It integrates to ~2 over theta_i: lossless hair in a white
    /// furnace renders at ~1.3-2.3 (docs/hair-model.md, "Energy"). Kept for comparison with the
    /// papers.
    Published,
}

/// Which variant of the exact model is evaluated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub struct ModelVariant {
    pub fresnel: FresnelModel,
    pub caustic: CausticModel,
    pub longitudinal: LongitudinalModel,
}

impl ModelVariant {
    /// Marschner 2003's azimuthal model (exact Fresnel, caustic fix); the longitudinal function is
    /// chosen apart ([`LongitudinalModel`], normalised unless asked).
    pub const MARSCHNER: Self = Self {
        fresnel: FresnelModel::Exact,
        caustic: CausticModel::Marschner,
        longitudinal: LongitudinalModel::Normalized,
    };
    /// The variant Xu 2011's fast model approximates (Schlick Fresnel reused inside, caustic fix).
    pub const XU: Self = Self {
        fresnel: FresnelModel::XuSchlick,
        caustic: CausticModel::Marschner,
        longitudinal: LongitudinalModel::Normalized,
    };
    /// Exact Fresnel, bare root sum: the energy-conserving form.
    pub const UNSMOOTHED: Self = Self {
        fresnel: FresnelModel::Exact,
        caustic: CausticModel::None,
        longitudinal: LongitudinalModel::Normalized,
    };

    /// The same variant with another longitudinal function.
    pub const fn with_longitudinal(self, longitudinal: LongitudinalModel) -> Self {
        Self {
            longitudinal,
            ..self
        }
    }
}

/// All parameters of Marschner's model. Angles in radians.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HairParams {
    /// Index of refraction of the fiber (1.55 for human hair).
    pub eta: f64,
    /// Absorption per unit fiber radius, RGB.
    pub sigma_a: [f64; 3],
    /// Longitudinal shift of R (negative: scales tilt the lobe towards the root), radians.
    pub alpha_r: f64,
    /// Override of alpha_TT (default -alpha_R/2).
    pub alpha_tt: Option<f64>,
    /// Override of alpha_TRT (default -3 alpha_R/2).
    pub alpha_trt: Option<f64>,
    /// Longitudinal width of R, a standard deviation, radians.
    pub beta_r: f64,
    /// Override of beta_TT (default beta_R/2).
    pub beta_tt: Option<f64>,
    /// Override of beta_TRT (default 2 beta_R).
    pub beta_trt: Option<f64>,
    /// Eccentricity a of the elliptical cross-section (1 = circular).
    pub eccentricity: f64,
    /// Azimuthal width w_c of the TRT caustic Gaussians, radians.
    pub caustic_width: f64,
    /// Fade range Delta eta' over which the caustic vanishes as eta' reaches 2.
    pub caustic_fade: f64,
    /// Caustic intensity limit Delta h_M.
    pub caustic_limit: f64,
    /// Glint scale factor g_c multiplying the caustic Gaussians.
    pub glint_scale: f64,
}

impl Default for HairParams {
    fn default() -> Self {
        Preset::Brown.params()
    }
}

impl HairParams {
    /// Marschner's Table 1 mid-range values with a given absorption.
    pub fn with_sigma_a(sigma_a: [f64; 3]) -> Self {
        Self {
            eta: 1.55,
            sigma_a,
            alpha_r: (-7.5f64).to_radians(),
            alpha_tt: None,
            alpha_trt: None,
            beta_r: 7.5f64.to_radians(),
            beta_tt: None,
            beta_trt: None,
            eccentricity: 1.0,
            caustic_width: 15f64.to_radians(),
            caustic_fade: 0.3,
            caustic_limit: 0.5,
            glint_scale: 2.0,
        }
    }

    /// Longitudinal shift alpha_p (Marschner's couplings unless overridden).
    pub fn alpha(&self, lobe: Lobe) -> f64 {
        match lobe {
            Lobe::R => self.alpha_r,
            Lobe::TT => self.alpha_tt.unwrap_or(-0.5 * self.alpha_r),
            Lobe::TRT => self.alpha_trt.unwrap_or(-1.5 * self.alpha_r),
        }
    }

    /// Longitudinal width beta_p, a standard deviation (Marschner's couplings unless overridden).
    pub fn beta(&self, lobe: Lobe) -> f64 {
        match lobe {
            Lobe::R => self.beta_r,
            Lobe::TT => self.beta_tt.unwrap_or(0.5 * self.beta_r),
            Lobe::TRT => self.beta_trt.unwrap_or(2.0 * self.beta_r),
        }
    }

    /// Checks ranges; returns a message naming the offending parameter.
    pub fn validate(&self) -> Result<(), String> {
        let finite = |name: &str, x: f64| {
            if x.is_finite() {
                Ok(())
            } else {
                Err(format!("{name} must be finite, got {x}"))
            }
        };
        finite("eta", self.eta)?;
        if !(1.0..=10.0).contains(&self.eta) || self.eta <= 1.0 {
            return Err(format!("eta must be in (1, 10], got {}", self.eta));
        }
        for (c, s) in self.sigma_a.iter().enumerate() {
            finite("sigma_a", *s)?;
            if *s < 0.0 {
                return Err(format!("sigma_a[{c}] must be >= 0, got {s}"));
            }
        }
        for lobe in Lobe::ALL {
            let a = self.alpha(lobe);
            finite("alpha", a)?;
            // Scales tilt the lobes by a few degrees; past 30 degrees the tilted lobe would wrap at a pole.
            if a.abs() > 30f64.to_radians() {
                return Err(format!(
                    "alpha_{} must be within +-30 degrees, got {} degrees",
                    lobe.name(),
                    degrees(a)
                ));
            }
            let b = self.beta(lobe);
            finite("beta", b)?;
            if b <= 0.0 || b > 1.5 {
                return Err(format!(
                    "beta_{} must be in (0, {:.0}] degrees, got {} degrees",
                    lobe.name(),
                    1.5f64.to_degrees(),
                    degrees(b)
                ));
            }
        }
        if !(self.eccentricity.is_finite() && (0.5..=2.0).contains(&self.eccentricity)) {
            return Err(format!(
                "eccentricity must be in [0.5, 2], got {}",
                self.eccentricity
            ));
        }
        if !(self.caustic_width.is_finite() && self.caustic_width > 0.0) {
            return Err(format!(
                "caustic width must be > 0 degrees, got {} degrees",
                degrees(self.caustic_width)
            ));
        }
        for (name, x) in [
            ("caustic fade", self.caustic_fade),
            ("caustic limit", self.caustic_limit),
            ("glint scale", self.glint_scale),
        ] {
            if !(x.is_finite() && x >= 0.0) {
                return Err(format!("{name} must be >= 0, got {x}"));
            }
        }
        Ok(())
    }
}

/// An angle in radians as the degrees a user typed (rounded to 1e-6, trailing zeros dropped).
fn degrees(x: f64) -> String {
    let d = (x.to_degrees() * 1e6).round() / 1e6;
    format!("{d}")
}

/// Absorption per unit radius of eumelanin and pheomelanin at unit concentration, RGB.
/// From d'Eon et al. 2011, "An Energy-Conserving Hair Reflectance Model", as used by
/// pbrt-v4's `HairBxDF::SigmaAFromConcentration` (Chiang et al. 2016 use the same values):
/// sigma_a = c_eu (0.419, 0.697, 1.37) + c_pheo (0.187, 0.4, 1.05).
pub const EUMELANIN_SIGMA_A: [f64; 3] = [0.419, 0.697, 1.37];
pub const PHEOMELANIN_SIGMA_A: [f64; 3] = [0.187, 0.4, 1.05];

/// sigma_a from melanin concentrations (d'Eon et al. 2011).
pub fn sigma_a_from_melanin(eumelanin: f64, pheomelanin: f64) -> [f64; 3] {
    std::array::from_fn(|c| eumelanin * EUMELANIN_SIGMA_A[c] + pheomelanin * PHEOMELANIN_SIGMA_A[c])
}

/// Named looks. Concentrations are our choices, placed on the scale pbrt-v4's documentation
/// describes (about 0.3 blond, 1.3 brown, 8 black for eumelanin; pheomelanin for red tones).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    DarkBrown,
    Brown,
    Auburn,
    Blond,
    Platinum,
}

impl Preset {
    pub const ALL: [Preset; 5] = [
        Preset::DarkBrown,
        Preset::Brown,
        Preset::Auburn,
        Preset::Blond,
        Preset::Platinum,
    ];

    /// (eumelanin, pheomelanin) concentrations.
    pub fn melanin(self) -> (f64, f64) {
        match self {
            Preset::DarkBrown => (3.0, 0.2),
            Preset::Brown => (1.3, 0.2),
            Preset::Auburn => (0.6, 1.2),
            Preset::Blond => (0.3, 0.1),
            Preset::Platinum => (0.08, 0.02),
        }
    }

    pub fn params(self) -> HairParams {
        let (eu, pheo) = self.melanin();
        HairParams::with_sigma_a(sigma_a_from_melanin(eu, pheo))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn couplings_follow_marschner_and_can_be_overridden() {
        let mut p = HairParams::default();
        assert!((p.alpha(Lobe::TT) + 0.5 * p.alpha_r).abs() < 1e-15);
        assert!((p.alpha(Lobe::TRT) + 1.5 * p.alpha_r).abs() < 1e-15);
        assert!((p.beta(Lobe::TRT) - 2.0 * p.beta_r).abs() < 1e-15);
        p.beta_tt = Some(0.3);
        assert_eq!(p.beta(Lobe::TT), 0.3);
    }

    #[test]
    fn presets_get_darker_with_melanin() {
        let lum = |p: Preset| p.params().sigma_a.iter().sum::<f64>();
        assert!(lum(Preset::DarkBrown) > lum(Preset::Brown));
        assert!(lum(Preset::Brown) > lum(Preset::Blond));
        assert!(lum(Preset::Blond) > lum(Preset::Platinum));
        for p in Preset::ALL {
            p.params().validate().unwrap();
        }
        // Auburn absorbs blue much more than red: it looks red.
        let a = Preset::Auburn.params().sigma_a;
        assert!(a[2] > 2.0 * a[0]);
    }

    #[test]
    fn presets_read_as_the_command_line_spells_them() {
        let p: Preset = serde_json::from_str("\"dark-brown\"").unwrap();
        assert_eq!(p, Preset::DarkBrown);
        let p: Preset = serde_json::from_str("\"blond\"").unwrap();
        assert_eq!(p, Preset::Blond);
    }

    #[test]
    fn limits_are_reported_in_degrees() {
        let p = HairParams {
            beta_r: 1000f64.to_radians(),
            ..Default::default()
        };
        let e = p.validate().unwrap_err();
        assert!(e.contains("1000 degrees"), "{e}");
    }

    #[test]
    fn validation_rejects_nonsense() {
        let p = HairParams {
            eta: f64::NAN,
            ..Default::default()
        };
        assert!(p.validate().is_err());
        let mut p = HairParams::default();
        p.sigma_a[1] = -1.0;
        assert!(p.validate().is_err());
        let p = HairParams {
            beta_r: 0.0,
            ..Default::default()
        };
        assert!(p.validate().is_err());
    }
}
