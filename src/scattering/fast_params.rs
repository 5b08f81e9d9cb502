//! The hair parameters as the fast model (and its WGSL twin, a uniform buffer) reads them: f32,
//! `#[repr(C)]`, Pod, every lobe's shift and width resolved.

use super::params::{HairParams, Lobe, LongitudinalModel};
use bytemuck::{Pod, Zeroable};

/// Default number of segments of Xu's linear quadrature (Sec. 4.2.2).
pub const DEFAULT_QUADRATURE_SEGMENTS: u32 = 4;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct FastHairParams {
    /// sigma_a per unit radius, RGB (w unused).
    pub sigma_a: [f32; 4],
    /// alpha_R, alpha_TT, alpha_TRT (radians; w unused).
    pub alpha: [f32; 4],
    /// beta_R, beta_TT, beta_TRT, standard deviations (radians; w unused).
    pub beta: [f32; 4],
    pub eta: f32,
    /// Eccentricity a (1 = circular).
    pub eccentricity: f32,
    /// Marschner's caustic width w_c, a standard deviation (radians). The circular Gaussians of the
    /// TRT caustics get bandwidth sqrt(2) w_c (bandwidth = sqrt(2) x std-dev: docs/hair-model.md,
    /// "Three Gaussian widths"). Read only by
    /// Xu's fits (`trt_lobes`): the response integrates the exact caustic from the azimuthal table.
    pub caustic_width: f32,
    /// Delta eta' of the smoothstep blend past eta' = 2 (Xu's fits only, as `caustic_width`).
    pub caustic_fade: f32,
    /// m, segments of the linear quadrature (>= 2).
    pub quadrature_segments: u32,
    /// Zinke's d_f and d_b (dual scattering; default 0.7).
    pub d_f: f32,
    pub d_b: f32,
    /// The longitudinal function: [`LONGITUDINAL_NORMALIZED`] (d'Eon et al. 2011, the default) or
    /// [`LONGITUDINAL_PUBLISHED`] (Marschner 2003 / Xu Eq. 7, about twice too bright).
    pub longitudinal: u32,
}

/// `FastHairParams::longitudinal`: d'Eon et al. 2011's normalised M ([`LongitudinalModel::Normalized`]).
pub const LONGITUDINAL_NORMALIZED: u32 = 0;
/// `FastHairParams::longitudinal`: the published M_t(theta_h) / cos^2(theta_d) ([`LongitudinalModel::Published`]).
pub const LONGITUDINAL_PUBLISHED: u32 = 1;

const _: () = assert!(std::mem::size_of::<FastHairParams>() == 80);

impl FastHairParams {
    pub fn new(p: &HairParams, quadrature_segments: u32) -> Self {
        let lobes = |f: &dyn Fn(Lobe) -> f64| {
            [
                f(Lobe::R) as f32,
                f(Lobe::TT) as f32,
                f(Lobe::TRT) as f32,
                0.0,
            ]
        };
        Self {
            sigma_a: [
                p.sigma_a[0] as f32,
                p.sigma_a[1] as f32,
                p.sigma_a[2] as f32,
                0.0,
            ],
            alpha: lobes(&|l| p.alpha(l)),
            beta: lobes(&|l| p.beta(l)),
            eta: p.eta as f32,
            eccentricity: p.eccentricity as f32,
            caustic_width: p.caustic_width as f32,
            caustic_fade: p.caustic_fade as f32,
            quadrature_segments: quadrature_segments.max(2),
            d_f: 0.7,
            d_b: 0.7,
            longitudinal: LONGITUDINAL_NORMALIZED,
        }
    }

    /// The same parameters with another longitudinal function.
    pub fn with_longitudinal(self, model: LongitudinalModel) -> Self {
        Self {
            longitudinal: match model {
                LongitudinalModel::Normalized => LONGITUDINAL_NORMALIZED,
                LongitudinalModel::Published => LONGITUDINAL_PUBLISHED,
            },
            ..self
        }
    }

    /// The exact model's form of [`Self::longitudinal`].
    pub fn longitudinal_model(&self) -> LongitudinalModel {
        if self.longitudinal == LONGITUDINAL_PUBLISHED {
            LongitudinalModel::Published
        } else {
            LongitudinalModel::Normalized
        }
    }

    pub fn sigma_a_rgb(&self) -> [f32; 3] {
        [self.sigma_a[0], self.sigma_a[1], self.sigma_a[2]]
    }
}
