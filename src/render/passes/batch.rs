//! A light batch (the lights one shading dispatch takes, at a K-buffer slot) and the inputs every
//! shading pass reads: shared by the per-fragment pass, the per-segment pass and the head's.

use crate::render::passes::occluder::GpuOccluder;
use crate::render::passes::segment_shading::SegmentTargets;
use bytemuck::Pod;
use bytemuck::Zeroable;

/// One batch's uniform.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ShadeBatch {
    pub first: u32,
    pub count: u32,
    pub flags: u32,
    /// Fragments per pixel in the K-buffer.
    pub slots: u32,
    /// The K-buffer slot this dispatch shades (per fragment: one dispatch per slot and batch; 0 when
    /// shading segments, which covers every slot).
    pub slot: u32,
    /// Rows [row0, row0 + rows) of the image.
    pub row0: u32,
    pub rows: u32,
    /// Lights in all the batches (the shaded weight counts each batch's share of them).
    pub lights: u32,
}

/// The buffers the shading pass reads that are not frame targets.
pub struct ShadingInputs<'a> {
    pub camera: &'a wgpu::Buffer,
    pub params: &'a wgpu::Buffer,
    pub shadow_grid: &'a wgpu::Buffer,
    pub points: &'a wgpu::Buffer,
    pub segments: &'a wgpu::Buffer,
    pub absorption: &'a wgpu::Buffer,
    pub lights: &'a wgpu::Buffer,
    /// The C_k table.
    pub lut_c: &'a wgpu::Buffer,
    pub shadow_values: &'a wgpu::Buffer,
    pub dual_tables: &'a wgpu::Buffer,
    pub azimuthal_table: &'a wgpu::Buffer,
    /// The occluder, shaded with the first slot's batches (and the preview's).
    pub occluder: Option<&'a GpuOccluder>,
    /// The frame's per-segment buffers (batches flagged [`crate::render::passes::shading::FLAG_SEGMENTS`] use them).
    pub segment_targets: Option<&'a SegmentTargets>,
}

impl<'a> ShadingInputs<'a> {
    /// What every shading kernel reads, at its bindings (0-8, 11, 12 and 19), with the batch's buffer.
    pub fn shading_entries(&self, batch: &'a wgpu::Buffer) -> Vec<(u32, &'a wgpu::Buffer)> {
        vec![
            (0, self.camera),
            (1, self.params),
            (2, batch),
            (3, self.shadow_grid),
            (4, self.points),
            (5, self.segments),
            (6, self.absorption),
            (7, self.lights),
            (8, self.lut_c),
            (11, self.shadow_values),
            (12, self.dual_tables),
            (19, self.azimuthal_table),
        ]
    }
}
