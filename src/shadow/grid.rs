//! Per-light shadows on a coarse grid over the hair: every SRBF light's cone-marched transmittance
//! and, for multiple scattering, its forward-scattering terms (T_f, sigma_f^2, averaged over the same
//! cones) are evaluated once per grid point (when geometry, absorption, lights or the forward table
//! change) and read trilinearly by the shading pass, instead of once per shaded sample and light. A
//! camera move recomputes nothing. Twin of `shaders/shadow_grid.wgsl` and `shadow_grid_build.wgsl`.

use super::cone::{DensityPyramid, srbf_centre_cone, srbf_cones};
use super::fiber_density::{FiberDensity, VolumeGrid};
use super::forward::{ForwardScattering, ForwardTable, forward_scattering};
use glam::Vec3;

/// Floor of the stored transmittances (they are stored as logarithms).
pub const GRID_MIN_TRANSMITTANCE: f32 = 1e-8;

/// What the shading pass reads per light at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GridShadow {
    /// Cone-marched transmittance (the direct fraction of single scattering).
    pub transmittance: f32,
    pub transmittance_f: [f32; 3],
    pub sigma_f2: [f32; 3],
    /// Optical depth of the hair behind the point along the light's travel (the central cone of
    /// [`srbf_cones`] marched away from the light): what the local back-scattering term has to work
    /// with (`backscatter_depth_fraction`). 0 without multiple scattering.
    pub depth_behind: f32,
}

/// forward_scattering over the cones of `srbf_transmittance` (twin of `srbf_forward` in
/// `shaders/shadow_grid_build.wgsl`), each cone marched with its own width, so the direct fraction is
/// `srbf_transmittance` itself; sigma_f^2 is averaged per channel over the forward-scattered light,
/// weights w (T_f - direct).
pub fn srbf_forward(
    pyramid: &DensityPyramid,
    volume: &FiberDensity,
    table: &ForwardTable,
    p: Vec3,
    centre: Vec3,
    lambda: f32,
    skip: f32,
) -> ForwardScattering {
    let (mut direct, mut tf, mut spread, mut scattered) = (0.0, [0.0; 3], [0.0; 3], [0.0; 3]);
    for (d, half_angle, w) in srbf_cones(centre, lambda) {
        let f = forward_scattering(pyramid, volume, table, p, d, half_angle, skip);
        direct += w * f.direct_fraction;
        for c in 0..3 {
            let s = w * (f.transmittance_f[c] - f.direct_fraction).max(0.0);
            tf[c] += w * f.transmittance_f[c];
            scattered[c] += s;
            spread[c] += s * f.sigma_f2[c];
        }
    }
    ForwardScattering {
        direct_fraction: direct,
        transmittance_f: tf,
        sigma_f2: std::array::from_fn(|c| spread[c] / scattered[c].max(1e-12)),
    }
}

/// The sources the grid is built from (CPU twin).
pub struct GridSources<'a> {
    pub pyramid: &'a DensityPyramid,
    /// With the forward table: multiple scattering on.
    pub forward: Option<(&'a FiberDensity, &'a ForwardTable)>,
    pub skip: f32,
}

/// Grid points at the centres of cells of side `spacing` covering the volume's box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowGrid {
    pub origin: Vec3,
    pub spacing: f32,
    pub dims: [u32; 3],
}

impl ShadowGrid {
    /// `resolution` points along the volume's longest side.
    pub fn around(volume: &VolumeGrid, resolution: u32) -> Self {
        let extent = Vec3::from(volume.dims.map(|d| d as f32)) * volume.voxel;
        let spacing = extent.max_element() / resolution.max(2) as f32;
        Self {
            origin: volume.origin,
            spacing,
            dims: [0, 1, 2].map(|a| ((extent[a] / spacing).ceil() as u32).max(1)),
        }
    }

    pub fn point_count(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// Centre of grid point `i` (x fastest).
    pub fn point(&self, i: usize) -> Vec3 {
        let (dx, dy) = (self.dims[0] as usize, self.dims[1] as usize);
        let c = Vec3::new(
            (i % dx) as f32,
            ((i / dx) % dy) as f32,
            (i / (dx * dy)) as f32,
        );
        self.origin + (c + 0.5) * self.spacing
    }

    /// The eight grid points around p (clamped at the border) with their trilinear weights.
    pub fn corners(&self, p: Vec3) -> [(usize, f32); 8] {
        let q = (p - self.origin) / self.spacing - 0.5;
        let hi = Vec3::from(self.dims.map(|d| d as f32 - 1.0));
        let q = q.clamp(Vec3::ZERO, hi);
        let base = q.floor().min((hi - 1.0).max(Vec3::ZERO));
        let f = q - base;
        std::array::from_fn(|corner| {
            let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
            let idx: [u32; 3] =
                std::array::from_fn(|a| (base[a] as u32 + o[a] as u32).min(self.dims[a] - 1));
            let w: f32 = (0..3)
                .map(|a| if o[a] == 1 { f[a] } else { 1.0 - f[a] })
                .product();
            let i = (idx[2] as usize * self.dims[1] as usize + idx[1] as usize)
                * self.dims[0] as usize
                + idx[0] as usize;
            (i, w)
        })
    }

    /// What the build pass stores at grid point i for a light (transmittances as logarithms, floored
    /// at [`GRID_MIN_TRANSMITTANCE`]).
    /// A point with no hair within one spacing (plus a level-0 voxel: the volume deposits a segment at
    /// samples a quarter voxel apart, so a shading point's hair may sit in the next voxel) is read by no
    /// shading point: it is stored lit.
    pub fn value(&self, src: &GridSources, i: usize, centre: Vec3, lambda: f32) -> GridShadow {
        let x = self.point(i);
        let reach = self.spacing + src.pyramid.levels.first().map_or(0.0, |l| l.voxel);
        if !src.pyramid.hair_near(x, reach) {
            return GridShadow::default();
        }
        let ln = |t: f32| t.max(GRID_MIN_TRANSMITTANCE).ln();
        match src.forward {
            None => {
                let t = ln(src.pyramid.srbf_transmittance(x, centre, lambda, src.skip));
                GridShadow {
                    transmittance: t,
                    transmittance_f: [t; 3],
                    sigma_f2: [0.0; 3],
                    depth_behind: 0.0,
                }
            }
            Some((volume, table)) => {
                // The forward march's direct fraction is srbf_transmittance (the same cones, steps
                // and sums, in the same order): d_f = d_b = 0 is single scattering up to rounding.
                let f = srbf_forward(src.pyramid, volume, table, x, centre, lambda, src.skip);
                GridShadow {
                    transmittance: ln(f.direct_fraction),
                    transmittance_f: f.transmittance_f.map(ln),
                    sigma_f2: f.sigma_f2,
                    depth_behind: src.pyramid.cone_optical_depth(
                        x,
                        -centre,
                        srbf_centre_cone(lambda),
                        src.skip,
                    ),
                }
            }
        }
    }

    /// The grid's trilinear reading at p (of the logarithms, for the transmittances), each corner
    /// evaluated on demand (tests).
    pub fn shadow(&self, src: &GridSources, p: Vec3, centre: Vec3, lambda: f32) -> GridShadow {
        let mut out = GridShadow::default();
        for (i, w) in self.corners(p) {
            if w == 0.0 {
                continue;
            }
            let v = self.value(src, i, centre, lambda);
            out.transmittance += w * v.transmittance;
            out.depth_behind += w * v.depth_behind;
            for c in 0..3 {
                out.transmittance_f[c] += w * v.transmittance_f[c];
                out.sigma_f2[c] += w * v.sigma_f2[c];
            }
        }
        out.transmittance = out.transmittance.exp();
        out.transmittance_f = out.transmittance_f.map(f32::exp);
        out
    }
}
