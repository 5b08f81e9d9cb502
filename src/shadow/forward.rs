//! Forward scattering along a shadow path (Zinke et al. 2008 Sec. 3.1; Xu et al. 2011 Sec. 4.3), from
//! the fiber-density volume, with the absorption of the fibers actually crossed (painted dye tints the
//! light passing through it).
//!
//! Along the path the number of fibers crossed is Poisson with mean tau = integral c ds, c the crossings per
//! cm ([`super::fiber_density`]). With a_f(theta_k, sigma_a_k) the forward attenuation of crossing k:
//! - direct fraction = P(no crossing) = exp(-tau);
//! - T_f = E[prod_k a_f] = exp(-integral c (1 - a_f) ds) (the expectation of a product over a Poisson number of
//!   crossings; it includes the direct part); Zinke's d_f multiplies it in the shader;
//! - sigma_f^2 = E[sum_k beta_f^2 | at least one crossing] = integral c beta_f^2 ds / (1 - exp(-tau)).
//!
//! Each voxel holds the sign-free orientation tensor only, so a_f and beta_f^2 are averaged over
//! theta = +-asin(sqrt(omega^T <u u^T> omega)) (the fiber's inclination to the light, either way along it).

use super::fiber_density::{FiberDensity, box_exit};
use crate::scattering::dual_terms::dual_sample;
use crate::scattering::{HairParams, ModelVariant};
use glam::Vec3;
use rayon::prelude::*;
use std::f64::consts::FRAC_PI_2;

/// a_f and beta_f^2 over (theta, sigma_a) for one set of the other hair parameters (eta, alpha, beta):
/// each colour channel reads it at its own sigma_a, so painted absorption needs no rebuild.
#[derive(Clone, Debug)]
pub struct ForwardTable {
    /// theta samples: THETA_SAMPLES over [-pi/2, pi/2].
    pub a_f: Vec<f32>,
    pub beta_f2: Vec<f32>,
}

pub const THETA_SAMPLES: usize = 64;
/// sigma_a samples: 0, then SIGMA_SAMPLES - 1 log-spaced over [SIGMA_MIN, SIGMA_MAX].
pub const SIGMA_SAMPLES: usize = 33;
pub const SIGMA_MIN: f32 = 0.005;
pub const SIGMA_MAX: f32 = 50.0;

fn sigma_at(j: usize) -> f32 {
    if j == 0 {
        0.0
    } else {
        SIGMA_MIN * (SIGMA_MAX / SIGMA_MIN).powf((j - 1) as f32 / (SIGMA_SAMPLES - 2) as f32)
    }
}

/// Continuous sigma_a index (piecewise: linear between 0 and SIGMA_MIN, logarithmic above).
fn sigma_pos(s: f32) -> f32 {
    if s <= SIGMA_MIN {
        (s / SIGMA_MIN).max(0.0)
    } else {
        1.0 + (s / SIGMA_MIN).ln() / (SIGMA_MAX / SIGMA_MIN).ln() * (SIGMA_SAMPLES - 2) as f32
    }
}

impl ForwardTable {
    pub fn build(params: &HairParams, variant: ModelVariant) -> Self {
        let cells: Vec<(f32, f32)> = (0..THETA_SAMPLES * SIGMA_SAMPLES)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k % THETA_SAMPLES, k / THETA_SAMPLES);
                let theta =
                    -FRAC_PI_2 + std::f64::consts::PI * i as f64 / (THETA_SAMPLES - 1) as f64;
                let mut p = *params;
                p.sigma_a = [sigma_at(j) as f64; 3];
                let s = dual_sample(&p, variant, theta);
                (s.a_f[0], s.beta_f2[0])
            })
            .collect();
        Self {
            a_f: cells.iter().map(|c| c.0).collect(),
            beta_f2: cells.iter().map(|c| c.1).collect(),
        }
    }

    /// (a_f, beta_f^2) at (theta, sigma_a), bilinear.
    pub fn lookup(&self, theta: f32, sigma_a: f32) -> (f32, f32) {
        let x = ((theta + std::f32::consts::FRAC_PI_2) / std::f32::consts::PI).clamp(0.0, 1.0)
            * (THETA_SAMPLES - 1) as f32;
        let y = sigma_pos(sigma_a).clamp(0.0, (SIGMA_SAMPLES - 1) as f32);
        let (i, j) = (
            (x as usize).min(THETA_SAMPLES - 2),
            (y as usize).min(SIGMA_SAMPLES - 2),
        );
        let (wx, wy) = (x - i as f32, y - j as f32);
        let at = |t: &[f32], i: usize, j: usize| t[j * THETA_SAMPLES + i];
        let bil = |t: &[f32]| {
            let a = at(t, i, j) + wx * (at(t, i + 1, j) - at(t, i, j));
            let b = at(t, i, j + 1) + wx * (at(t, i + 1, j + 1) - at(t, i, j + 1));
            a + wy * (b - a)
        };
        (bil(&self.a_f), bil(&self.beta_f2))
    }
}

/// What the shader needs from the shadow path of one light at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForwardScattering {
    pub direct_fraction: f32,
    /// E[prod a_f], per channel (without d_f).
    pub transmittance_f: [f32; 3],
    /// sigma_f^2 given at least one crossing, per channel (radians^2).
    pub sigma_f2: [f32; 3],
}

/// Marches from p towards the light (omega, unit) through the volume (half-voxel midpoint steps).
pub fn forward_scattering(
    volume: &FiberDensity,
    table: &ForwardTable,
    p: Vec3,
    omega: Vec3,
    skip: f32,
) -> ForwardScattering {
    let h0 = 0.5 * volume.voxel;
    let exit = box_exit(volume.origin, volume.voxel, volume.dims, p, omega);
    let (mut tau, mut loss, mut spread) = (0f32, [0f32; 3], [0f32; 3]);
    if exit.is_finite() && exit > skip {
        let steps = ((exit - skip) / h0).ceil() as usize;
        let h = (exit - skip) / steps as f32;
        for k in 0..steps {
            let x = p + omega * (skip + (k as f32 + 0.5) * h);
            let Some(v) = volume.voxel_at(x) else {
                continue;
            };
            let c = volume.crossings_per_length(x, omega);
            if c <= 0.0 {
                continue;
            }
            let a = volume.extinction[v].max(1e-30);
            let m = volume.extinction_tensor[v];
            let w = omega;
            let q = (m[0] * w.x * w.x
                + m[1] * w.y * w.y
                + m[2] * w.z * w.z
                + 2.0 * (m[3] * w.x * w.y + m[4] * w.x * w.z + m[5] * w.y * w.z))
                / a;
            let theta = q.clamp(0.0, 1.0).sqrt().asin();
            tau += c * h;
            for ch in 0..3 {
                let s = volume.absorption[v][ch];
                let (af1, b1) = table.lookup(theta, s);
                let (af2, b2) = table.lookup(-theta, s);
                loss[ch] += c * h * (1.0 - 0.5 * (af1 + af2));
                spread[ch] += c * h * 0.5 * (b1 + b2);
            }
        }
    }
    let direct = (-tau).exp();
    let scattered = (1.0 - direct).max(1e-12);
    ForwardScattering {
        direct_fraction: direct,
        transmittance_f: loss.map(|l| (-l).exp()),
        sigma_f2: spread.map(|s| if tau > 0.0 { s / scattered } else { 0.0 }),
    }
}
