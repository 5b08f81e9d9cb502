//! What a render is asked for besides the scene: image, K-buffer, volume and shadow-grid settings.

use crate::hair::Hair;
use crate::render::passes::kbuffer::{DEFAULT_FRAGMENTS, Tail};
use crate::shadow::grid::ShadowGrid;
use crate::shadow::voxels::{MAX_DIM, VolumeGrid};

/// What does not change from frame to frame without rebuilding targets.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Multisampling of the occluder in the visibility pass (2 or 4).
    pub samples: u32,
    /// Hair fragments kept per pixel by the K-buffer (1 to [`crate::render::passes::kbuffer::MAX_FRAGMENTS`]).
    pub fragments: u32,
    /// What becomes of the fragments behind the kept ones.
    pub tail: Tail,
    /// Exposure in stops applied by the resolve pass.
    pub exposure: f32,
    pub shadows: bool,
    /// Dual scattering (MS.global, MS.local) on top of single scattering.
    pub multiple_scattering: bool,
    /// Fibers cover at least this many pixels across (0: their true width; 1 draws the old opaque
    /// one-pixel ribbons).
    pub min_width_px: f32,
    /// SRBF lights per shading pass (at most 16).
    pub lights_per_pass: u32,
    /// Voxels along the hair's longest side for the fiber-density volume.
    pub volume_resolution: u32,
    /// Shadow paths skip this many voxels at the grid point (a shaded fiber's own density).
    pub shadow_skip_voxels: f32,
    /// Points of the per-light transmittance grid along the hair's longest side (48: on the blond-clump
    /// test against ray shooting the worst mean-colour error was 16 % at 32 points, 9.5 % at 48).
    pub shadow_grid_resolution: u32,
    /// Shade each visible segment once (each light's single-scattering response at its midpoint,
    /// weighted by the light's transmittance at its ends and midpoint; multiple scattering once per
    /// pair of consecutive segments of a strand with the same absorption, at the point they share:
    /// `shade::ShadingHair::ms_key`) instead of every kept fragment at its own point (false): ~8x
    /// fewer responses at full resolution (S1 on lavapipe: 8.9 s a frame against 101 s per
    /// fragment). On by default; its cost against per-fragment shading is bounded by
    /// `tests/render.rs`, and on the blond clump of `tests/ms_reference.rs` it stays at least as close
    /// to ray shooting (docs/testing.md gives the measured figures). Each light's
    /// response reads the absorption at each of the segment's ends where they differ (the midpoint's
    /// between them), so paint keeps its gradient along the segment; a pair whose points' absorption
    /// differs gets a multiple-scattering sample per segment.
    pub segment_shading: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 720,
            height: 480,
            samples: 4,
            fragments: DEFAULT_FRAGMENTS,
            tail: Tail::Spread,
            exposure: 0.0,
            shadows: true,
            multiple_scattering: true,
            min_width_px: 0.0,
            lights_per_pass: 16,
            volume_resolution: 128,
            shadow_skip_voxels: 0.5,
            shadow_grid_resolution: 48,
            segment_shading: true,
        }
    }
}

impl RenderSettings {
    /// The K-buffer's fragments per pixel and tail.
    pub fn kbuffer(&self) -> (u32, Tail) {
        (self.fragments, self.tail)
    }

    /// The fiber-density grid this renderer builds for `hair` (the CPU twin uses the same).
    pub fn volume_grid(&self, hair: &Hair) -> VolumeGrid {
        VolumeGrid::around(hair, self.voxel_size(hair))
    }

    pub fn voxel_size(&self, hair: &Hair) -> f32 {
        let (lo, hi) = hair.bounds();
        let n = self.volume_resolution.clamp(4, MAX_DIM as u32 - 2) as f32;
        ((hi - lo).max_element() / n).max(1e-3)
    }

    pub fn shadow_skip(&self, hair: &Hair) -> f32 {
        self.shadow_skip_voxels.max(0.0) * self.volume_grid(hair).voxel
    }

    /// The per-light transmittance grid (the CPU twin reads the same).
    pub fn shadow_grid(&self, hair: &Hair) -> ShadowGrid {
        ShadowGrid::around(
            &self.volume_grid(hair),
            self.shadow_grid_resolution.clamp(2, 256),
        )
    }
}
