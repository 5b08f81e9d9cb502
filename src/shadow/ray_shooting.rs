//! Forward scattering by ray shooting (Zinke et al. 2008 Sec. 4.1.1): the shadow ray from the shaded
//! point towards the light is traced through the explicit fibers, and every fiber it crosses
//! contributes its own forward attenuation and spread,
//!   T_f = prod_k a_f(theta_k, sigma_a,k)  (Eq. 5, without d_f, which the shading applies),
//!   sigma_f^2 = sum_k beta_f^2(theta_k, sigma_a,k)  (Eq. 8),
//! with theta_k = asin(omega . u_k) the light's inclination to crossed fiber k (its root-to-tip tangent,
//! sign included) and sigma_a,k the absorption where the ray crosses it. No crossing: the direct
//! fraction is 1, T_f = 1, sigma_f^2 = 0; any crossing: the direct fraction is 0.
//!
//! The slow, geometric counterpart of [`super::forward::forward_scattering`] (a density volume's
//! expected crossings) and of the shadow grid's cone filtering: one ray per direction, averaged by the
//! caller over many directions.

use super::fiber_grid::FiberGrid;
use super::forward::{ForwardScattering, ForwardTable};
use glam::Vec3;

/// Traces from p towards the light (omega, unit) through the fibers of `grid`, ignoring the segment
/// `own` and its neighbours on the same strand (the fiber the point lies on; u32::MAX: none).
pub fn shoot_forward(
    grid: &FiberGrid,
    table: &ForwardTable,
    p: Vec3,
    omega: Vec3,
    own: u32,
) -> ForwardScattering {
    let own_strand = grid.segments.get(own as usize).map(|s| s.strand);
    let mut out = ForwardScattering {
        direct_fraction: 1.0,
        transmittance_f: [1.0; 3],
        sigma_f2: [0.0; 3],
    };
    grid.crossings(p, omega, 0.0, |x| {
        let s = &grid.segments[x.segment as usize];
        if Some(s.strand) == own_strand && x.segment.abs_diff(own) <= 1 {
            return;
        }
        let tangent = (s.b - s.a).normalize();
        let theta = omega.dot(tangent).clamp(-1.0, 1.0).asin();
        out.direct_fraction = 0.0;
        for c in 0..3 {
            let sigma = s.sigma_a[0][c] + x.u * (s.sigma_a[1][c] - s.sigma_a[0][c]);
            let (a_f, beta_f2) = table.lookup(theta, sigma);
            out.transmittance_f[c] *= a_f;
            out.sigma_f2[c] += beta_f2;
        }
    });
    out
}

/// Fibers crossed from p away from the light (along -omega), the segment `own` and its neighbours on
/// the same strand left out: the hair behind the point that the local back-scattering term
/// (`backscatter_depth_fraction`) has to work with, counted exactly.
pub fn crossings_behind(grid: &FiberGrid, p: Vec3, omega: Vec3, own: u32) -> u32 {
    let own_strand = grid.segments.get(own as usize).map(|s| s.strand);
    let mut n = 0;
    grid.crossings(p, -omega, 0.0, |x| {
        let s = &grid.segments[x.segment as usize];
        if Some(s.strand) == own_strand && x.segment.abs_diff(own) <= 1 {
            return;
        }
        n += 1;
    });
    n
}
