//! Per-light shadows on a coarse grid over the hair: every SRBF light's transmittance and, for multiple
//! scattering, its forward-scattering terms (T_f, sigma_f^2) are evaluated once per grid point by
//! light-space sweeps ([`super::sweep`]; when geometry, absorption, lights or the forward table change)
//! and read trilinearly by the shading pass, instead of once per shaded sample and light. A camera
//! move recomputes nothing. Twin of `shaders/shadow_grid.wgsl` and `shadow_grid_build.wgsl`.
//! [`srbf_forward`] is the cone march, the sweeps' reference (docs/shadows.md).

use super::cone::{DensityPyramid, srbf_cones};
use super::fiber_density::FiberDensity;
use super::forward::{ForwardScattering, ForwardTable, forward_scattering};
use super::voxels::VolumeGrid;
use glam::Vec3;

/// Floor of the stored transmittances (they are stored as logarithms).
pub const GRID_MIN_TRANSMITTANCE: f32 = 1e-8;
/// depth_behind of a grid point inside the occluder: left out of the interpolation.
pub const GRID_INSIDE_SOLID: f32 = -1.0;

/// What the shading pass reads per light at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GridShadow {
    /// Transmittance (the direct fraction of single scattering).
    pub transmittance: f32,
    pub transmittance_f: [f32; 3],
    pub sigma_f2: [f32; 3],
    /// Optical depth of the hair behind the point along the light's travel (a sweep along the
    /// light's centre reversed): what the local back-scattering term has to work with
    /// (`backscatter_depth_fraction`). 0 without multiple scattering.
    pub depth_behind: f32,
}

/// forward_scattering over the cones of `srbf_transmittance`, each cone marched with its own width, so
/// the direct fraction is `srbf_transmittance` itself; sigma_f^2 is averaged per channel over the
/// forward-scattered light, weights w (T_f - direct). The cone march: the reference the grid's
/// sweeps are tested against.
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
    /// The volume whose solid marks the points inside the occluder ([`FiberDensity::inside_solid`]).
    pub occluder: Option<&'a FiberDensity>,
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

    /// Points of the largest slice across an axis (a sweep's working set).
    pub fn largest_slice(&self) -> usize {
        let [x, y, z] = self.dims.map(|d| d as usize);
        (x * y).max(x * z).max(y * z)
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
}

/// Every light's stored values over the grid, built by light-space sweeps ([`super::sweep`]): the
/// CPU twin of the GPU grid (light-major, logarithms of the transmittances).
pub struct GridValues {
    pub grid: ShadowGrid,
    pub lights: Vec<Vec<GridShadow>>,
}

impl GridValues {
    /// The grid's trilinear reading at p for light `light` (of the logarithms, for the
    /// transmittances): what the shading pass reads (`grid_shadow` in `shaders/shadow_grid.wgsl`).
    /// Points inside the occluder (depth_behind = [`GRID_INSIDE_SOLID`]) are left out and the
    /// others' weights renormalised, unless every corner is inside.
    pub fn shadow(&self, p: Vec3, light: usize) -> GridShadow {
        let values = &self.lights[light];
        let add = |out: &mut GridShadow, v: &GridShadow, w: f32| {
            out.transmittance += w * v.transmittance;
            out.depth_behind += w * v.depth_behind;
            for c in 0..3 {
                out.transmittance_f[c] += w * v.transmittance_f[c];
                out.sigma_f2[c] += w * v.sigma_f2[c];
            }
        };
        let (mut all, mut outside, mut wo, mut any_inside) =
            (GridShadow::default(), GridShadow::default(), 0.0, false);
        for (i, w) in self.grid.corners(p) {
            let v = values[i];
            add(&mut all, &v, w);
            if v.depth_behind >= 0.0 {
                add(&mut outside, &v, w);
                wo += w;
            } else {
                any_inside = true;
            }
        }
        let mut out = all;
        if any_inside && wo > 1e-4 {
            out = outside;
            out.transmittance /= wo;
            out.depth_behind /= wo;
            for c in 0..3 {
                out.transmittance_f[c] /= wo;
                out.sigma_f2[c] /= wo;
            }
        }
        out.depth_behind = out.depth_behind.max(0.0);
        out.transmittance = out.transmittance.exp();
        out.transmittance_f = out.transmittance_f.map(f32::exp);
        out
    }
}
