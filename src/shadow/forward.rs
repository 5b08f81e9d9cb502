//! Forward scattering along a shadow path (Zinke et al. 2008 Sec. 3.1; Xu et al. 2011 Sec. 4.3), from
//! the fiber-density volume, with the absorption of the fibers actually crossed (painted dye tints the
//! light passing through it).
//!
//! Along the path the number of fibers crossed is Poisson with mean tau = integral c ds, c the crossings per
//! cm ([`super::fiber_density`]). With a_f(theta_k, sigma_a_k) the forward attenuation of crossing k:
//! - direct fraction = P(no crossing) = exp(-tau);
//! - T_f = E[prod_k a_f] = exp(-integral c (1 - a_f) ds) (the expectation of a product over a Poisson number of
//!   crossings; it includes the direct part); Zinke's d_f multiplies it in the shader;
//! - sigma_f^2, the spread of the light that arrives forward-scattered, as that light weights it:
//!   sigma_f^2 = E[prod_k a_f sum_j beta_f,j^2] / E[prod_k a_f; at least one crossing],
//!   which is T_f integral c a_f beta_f^2 ds / (T_f - exp(-tau)) ([`forward_spread_weighted`])
//!   (Mecke's formula for a Poisson process: E[prod_k a_k sum_j b_j] = E[prod_k a_k] integral c a b ds).
//!   Per channel. Paths that cross few fibers bring most of the light and have the narrowest spread; the
//!   unweighted E[sum beta_f^2 | a crossing] = integral c beta_f^2 ds / (1 - exp(-tau)) overstates it
//!   (6 beta^2 against 3.7 beta^2 at tau = 6, a_f = 0.6), which made the global term 60% too bright
//!   against ray shooting through the fibers (tests/ms_reference.rs) when the view is off the lobe's peak.
//!
//! Each voxel holds the sign-free orientation tensor only, so a_f and beta_f^2 are averaged over
//! theta = +-asin(sqrt(omega^T <u u^T> omega)) (the fiber's inclination to the light, either way along it),
//! with the tensor read trilinearly as the crossing density is (the table's nodes hold the means over
//! +-theta, [`ForwardTable::lookup_symmetric`]: one lookup a channel). The absorption is the voxel's (an empty
//! voxel holds its neighbours'): reading it as zero where the trilinear density is not made every
//! fourth crossing in a sparse clump a clear fiber, and T_f of blond hair 1.5-2x too high in blue.

use super::cone::DensityPyramid;
use super::fiber_density::FiberDensity;
use super::voxels::crossings;
use crate::scattering::dual_terms::dual_samples_across;
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
pub use crate::scattering::dual_terms::{SIGMA_MAX, SIGMA_MIN, SIGMA_SAMPLES, sigma_at, sigma_pos};

impl ForwardTable {
    pub fn build(params: &HairParams, variant: ModelVariant) -> Self {
        // By theta, every absorption at once (dual_samples_across: the same samples as dual_sample
        // at each, to the bit), then in the table's order (theta fastest).
        let sigmas: Vec<f64> = (0..SIGMA_SAMPLES).map(|j| sigma_at(j) as f64).collect();
        let columns: Vec<Vec<(f32, f32)>> = (0..THETA_SAMPLES)
            .into_par_iter()
            .map(|i| {
                let theta =
                    -FRAC_PI_2 + std::f64::consts::PI * i as f64 / (THETA_SAMPLES - 1) as f64;
                dual_samples_across(params, variant, theta, &sigmas)
                    .iter()
                    .map(|s| (s.a_f[0], s.beta_f2[0]))
                    .collect()
            })
            .collect();
        let cells: Vec<(f32, f32)> = (0..THETA_SAMPLES * SIGMA_SAMPLES)
            .map(|k| columns[k % THETA_SAMPLES][k / THETA_SAMPLES])
            .collect();
        Self {
            a_f: cells.iter().map(|c| c.0).collect(),
            beta_f2: cells.iter().map(|c| c.1).collect(),
        }
    }

    /// The means over +-theta of a_f and of a_f beta_f^2 at node (i, j) (theta index i, sigma_a
    /// index j): the texels of the GPU's table ([`crate::gpu::forward::forward_table_texels`]).
    pub fn symmetric_node(&self, i: usize, j: usize) -> [f32; 2] {
        let (k, m) = (
            j * THETA_SAMPLES + i,
            j * THETA_SAMPLES + THETA_SAMPLES - 1 - i,
        );
        [
            0.5 * (self.a_f[k] + self.a_f[m]),
            0.5 * (self.a_f[k] * self.beta_f2[k] + self.a_f[m] * self.beta_f2[m]),
        ]
    }

    /// The means over +-theta of a_f and of a_f beta_f^2 (a fiber crossed at inclination theta
    /// either way along it) at (theta, sigma_a), bilinear in the nodes' means
    /// ([`Self::symmetric_node`]; the theta samples lie symmetrically about 0, so the mean of a_f is
    /// exactly that of [`Self::lookup`] at +-theta, and the mean of the product differs from the
    /// product of the interpolated factors by the interpolation's error). One lookup where the
    /// integrand took two. Twin of `forward_lookup` in `shaders/forward_scattering.wgsl`.
    pub fn lookup_symmetric(&self, theta: f32, sigma_a: f32) -> (f32, f32) {
        let bil = |c: usize| bilinear(theta, sigma_a, |i, j| self.symmetric_node(i, j)[c]);
        (bil(0), bil(1))
    }

    /// (a_f, beta_f^2) at (theta, sigma_a), bilinear.
    pub fn lookup(&self, theta: f32, sigma_a: f32) -> (f32, f32) {
        let bil = |t: &[f32]| bilinear(theta, sigma_a, |i, j| t[j * THETA_SAMPLES + i]);
        (bil(&self.a_f), bil(&self.beta_f2))
    }
}

/// The bilinear reading at (theta, sigma_a) of a table over the nodes (theta index i, sigma_a
/// index j) given by `at`.
fn bilinear(theta: f32, sigma_a: f32, at: impl Fn(usize, usize) -> f32) -> f32 {
    let x = ((theta + std::f32::consts::FRAC_PI_2) / std::f32::consts::PI).clamp(0.0, 1.0)
        * (THETA_SAMPLES - 1) as f32;
    let y = sigma_pos(sigma_a).clamp(0.0, (SIGMA_SAMPLES - 1) as f32);
    let (i, j) = (
        (x as usize).min(THETA_SAMPLES - 2),
        (y as usize).min(SIGMA_SAMPLES - 2),
    );
    let (wx, wy) = (x - i as f32, y - j as f32);
    let a = at(i, j) + wx * (at(i + 1, j) - at(i, j));
    let b = at(i, j + 1) + wx * (at(i + 1, j + 1) - at(i, j + 1));
    a + wy * (b - a)
}

/// What the shader needs from the shadow path of one light at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForwardScattering {
    pub direct_fraction: f32,
    /// E[prod a_f], per channel (without d_f).
    pub transmittance_f: [f32; 3],
    /// sigma_f^2 of the forward-scattered light, weighted by what each path transmits, per channel
    /// (radians^2).
    pub sigma_f2: [f32; 3],
}

/// The integrals of a shadow path (per cm when read at a point, `forward_integrand`; cm-weighted
/// sums along a path): tau = integral c ds and per channel integral c a_f ds and integral c a_f
/// beta_f^2 ds. Cone marches and light-space sweeps add them up alike. The loss integral c (1 - a_f) ds
/// of T_f is tau - mass ([`PathIntegrals::loss`]), not carried.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PathIntegrals {
    pub tau: f32,
    pub mass: [f32; 3],
    pub spread: [f32; 3],
}

impl PathIntegrals {
    /// self + h o.
    pub fn add_scaled(&self, o: &PathIntegrals, h: f32) -> PathIntegrals {
        PathIntegrals {
            tau: self.tau + h * o.tau,
            mass: std::array::from_fn(|c| self.mass[c] + h * o.mass[c]),
            spread: std::array::from_fn(|c| self.spread[c] + h * o.spread[c]),
        }
    }

    /// Channel c's loss integral c (1 - a_f) ds = tau - mass, the optical depth of T_f (at least 0:
    /// the forward share a_f is at most 1, the difference may round below).
    pub fn loss(&self, c: usize) -> f32 {
        (self.tau - self.mass[c]).max(0.0)
    }

    /// The direct fraction, T_f and sigma_f^2 of a path with these integrals.
    pub fn scattering(&self) -> ForwardScattering {
        ForwardScattering {
            direct_fraction: (-self.tau).exp(),
            transmittance_f: std::array::from_fn(|c| (-self.loss(c)).exp()),
            sigma_f2: std::array::from_fn(|c| {
                forward_spread_weighted(self.mass[c], self.spread[c])
            }),
        }
    }
}

/// The integrands of [`PathIntegrals`] at x along omega (unit), the pyramid read at continuous level
/// `lod`: crossings and inclination from the same (a, M), absorption from the level-0 voxel (an empty
/// one holds its neighbours'). Zero outside the volume. Twin of `forward_integrand` in
/// `shaders/forward_scattering.wgsl`.
pub fn forward_integrand(
    pyramid: &DensityPyramid,
    volume: &FiberDensity,
    table: &ForwardTable,
    x: Vec3,
    omega: Vec3,
    lod: f32,
) -> PathIntegrals {
    let Some(v) = volume.voxel_at(x) else {
        return PathIntegrals::default();
    };
    let (a, m) = pyramid.extinction_at(x, lod);
    forward_integrand_of(a, m, volume.absorption[v], table, omega)
}

/// The integrands of [`PathIntegrals`] along omega (unit) where the volume reads extinction `a`,
/// tensor `m` and absorption `sigma_a` (what [`forward_integrand`] reads at a point; the shadow
/// grid's sweeps read it at their midpoints, from their samples). Twin of `forward_integrand_of` in
/// `shaders/forward_scattering.wgsl`.
pub fn forward_integrand_of(
    a: f32,
    m: [f32; 6],
    sigma_a: [f32; 3],
    table: &ForwardTable,
    omega: Vec3,
) -> PathIntegrals {
    let c = crossings(a, m, omega);
    if c <= 0.0 {
        return PathIntegrals::default();
    }
    let w = omega;
    let q = (m[0] * w.x * w.x
        + m[1] * w.y * w.y
        + m[2] * w.z * w.z
        + 2.0 * (m[3] * w.x * w.y + m[4] * w.x * w.z + m[5] * w.y * w.z))
        / a.max(1e-30);
    let theta = q.clamp(0.0, 1.0).sqrt().asin();
    let mut out = PathIntegrals {
        tau: c,
        ..Default::default()
    };
    for (ch, &sig) in sigma_a.iter().enumerate() {
        let (a_f, spread) = table.lookup_symmetric(theta, sig);
        out.mass[ch] = c * a_f;
        out.spread[ch] = c * spread;
    }
    out
}

/// Forward scattering along the cone of half-angle `half_angle` about omega (unit) from p, marched as
/// [`DensityPyramid::cone_optical_depth`] marches it (so the direct fraction is that cone's exp(-tau)),
/// `skip` cm left out at the start. Twin of `forward_scattering` in `shaders/forward_scattering.wgsl`.
pub fn forward_scattering(
    pyramid: &DensityPyramid,
    volume: &FiberDensity,
    table: &ForwardTable,
    p: Vec3,
    omega: Vec3,
    half_angle: f32,
    skip: f32,
) -> ForwardScattering {
    let exit = pyramid.exit(p, omega);
    let tan = half_angle.min(1.5).tan();
    let mut sums = PathIntegrals::default();
    let mut s = skip;
    while s < exit {
        let (h, lod) = pyramid.cone_step(s, tan, exit);
        let x = p + omega * (s + 0.5 * h);
        s += h;
        sums = sums.add_scaled(&forward_integrand(pyramid, volume, table, x, omega, lod), h);
    }
    sums.scattering()
}

/// sigma_f^2 = T_f W / (T_f - direct) with W = integral c a_f beta_f^2 ds. Since T_f = exp(-(tau - A)) with
/// A = integral c a_f ds, T_f - direct = T_f (1 - exp(-A)) and sigma_f^2 = W / (1 - exp(-A)): the crossed
/// fibers' mean beta_f^2 as A -> 0, 0 when nothing is crossed.
pub fn forward_spread_weighted(forward_mass: f32, weighted_spread: f32) -> f32 {
    if forward_mass <= 0.0 || weighted_spread <= 0.0 {
        return 0.0;
    }
    let scattered = if forward_mass < 1e-3 {
        forward_mass * (1.0 - 0.5 * forward_mass)
    } else {
        1.0 - (-forward_mass).exp()
    };
    weighted_spread / scattered
}
