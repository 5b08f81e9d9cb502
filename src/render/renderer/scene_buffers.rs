//! The hairstyle, its head and its lights on the GPU, and the volumes built from them.

use crate::gpu::density_pyramid::GpuDensityPyramid;
use crate::gpu::fiber_density::{GpuFiberDensity, GpuHair};
use crate::render::passes::occluder::GpuOccluder;
use crate::render::passes::shadow_grid::GpuShadowGrid;
use glam::Vec3;

/// The hairstyle, its head and its lights on the GPU, and the volumes built from them.
pub(in crate::render) struct SceneBuffers {
    pub(in crate::render) hair: GpuHair,
    pub(in crate::render) point_count: usize,
    pub(in crate::render) skip: f32,
    pub(in crate::render) volume: GpuFiberDensity,
    pub(in crate::render) pyramid: GpuDensityPyramid,
    pub(in crate::render) shadow_grid: GpuShadowGrid,
    pub(in crate::render) lights: wgpu::Buffer,
    pub(in crate::render) light_count: u32,
    /// The background's map texels (one zero texel without one).
    pub(in crate::render) background_map: wgpu::Buffer,
    /// The occluder (the head) drawn, shaded and held in the volume as a solid.
    pub(in crate::render) occluder: Option<SceneOccluder>,
    /// The hair's longest segment and its bounds (whether segments are short enough, as the eye sees
    /// them, to be shaded once each: [`crate::render::renderer::MAX_SEGMENT_ANGLE`]).
    pub(in crate::render) segment_extent: (f32, Vec3, Vec3),
    /// Each segment's first point, in segment order (the brush's repaint finds the segments at the
    /// points a dab changed: [`crate::render::Renderer::repaint_points`]).
    pub(in crate::render) segment_first: Vec<u32>,
    /// Every [`crate::render::refine::preview::PREVIEW_STRAND_STRIDE`]-th strand's segments, which a coarse
    /// preview draws (None for a hair of few strands).
    pub(in crate::render) preview_strands: Option<crate::render::passes::kbuffer::SegmentSubset>,
    /// The points as the GPU holds them (position, diameter), for the rows a repaint covers.
    pub(in crate::render) point_data: Vec<[f32; 4]>,
}

/// The occluder as the renderer holds it.
pub(in crate::render) struct SceneOccluder {
    pub(in crate::render) gpu: GpuOccluder,
    /// Its fraction of each voxel of the volume.
    pub(super) solid: Vec<f32>,
    pub(super) shadow_offset: f32,
}
