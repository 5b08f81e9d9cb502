//! Per-light transmittance on a coarse grid over the hair: every SRBF light's cone-marched
//! transmittance is evaluated once per grid point (when geometry, absorption or lights change) and
//! read trilinearly by the shading pass, instead of once per shaded sample and light. A parameter edit
//! or a camera move recomputes nothing. Twin of `shaders/shadow_grid.wgsl`.

use super::cone::DensityPyramid;
use super::fiber_density::VolumeGrid;
use glam::Vec3;

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

    /// The grid's reading of a light's transmittance at p, each corner evaluated on demand (tests).
    pub fn transmittance(
        &self,
        pyramid: &DensityPyramid,
        p: Vec3,
        centre: Vec3,
        lambda: f32,
        skip: f32,
    ) -> f32 {
        self.corners(p)
            .iter()
            .map(|&(i, w)| {
                if w == 0.0 {
                    0.0
                } else {
                    w * pyramid.srbf_transmittance(self.point(i), centre, lambda, skip)
                }
            })
            .sum()
    }
}
