//! The shading passes (`shaders/shading.wgsl`): per batch of at most [`MAX_LIGHTS_PER_PASS`] SRBF
//! lights (Xu 2011's multi-pass scheme), its lights' R, TT and TRT radiance (and with multiple
//! scattering MS.global and MS.local): per visible segment ([`crate::render::passes::segment_shading`], the default,
//! gathered into the component buffers after the last batch), or per fragment, one dispatch per
//! K-buffer slot within a batch, added to the component buffers.

use crate::gpu::context::{bind_entries, compute_pipeline};
use crate::gpu::shaders;
use crate::render::passes::batch::{ShadeBatch, ShadingInputs};
use crate::render::passes::occluder::{OccluderPass, shades_occluder};
use crate::render::passes::row_segments::{
    RowSegmentsInputs, RowSegmentsPass, RowSegmentsReadback,
};
use crate::render::passes::segment_shading::{
    SegmentShadingPass, SegmentTargets, last_light_batch,
};
use crate::render::passes::targets::FrameTargets;
use bytemuck::{Pod, Zeroable};

pub const MAX_LIGHTS_PER_PASS: u32 = 16;
pub const FLAG_SHADOWS: u32 = 1;
pub const FLAG_MULTIPLE_SCATTERING: u32 = 2;
/// The batches shade segments ([`crate::render::passes::segment_shading`]), not fragments.
pub const FLAG_SEGMENTS: u32 = 4;
/// A batch by segment shades multiple scattering alone: the segments' single scattering is kept from
/// the last converged pass ([`crate::render::Renderer::keeps_single_scattering`]).
pub const FLAG_SINGLE_KEPT: u32 = 8;

/// One SRBF light as the shaders read it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub direction: [f32; 3],
    pub lambda: f32,
    pub rgb: [f32; 3],
    pub _pad: f32,
}

const _: () = assert!(std::mem::size_of::<GpuLight>() == 32);
const _: () = assert!(std::mem::size_of::<ShadeBatch>() == 32);

pub struct ShadingPass {
    pipeline: wgpu::ComputePipeline,
    segments: SegmentShadingPass,
    rows: RowSegmentsPass,
    occluder: OccluderPass,
    batches: Vec<(ShadeBatch, wgpu::Buffer)>,
}

fn batch_uniform(device: &wgpu::Device, b: &ShadeBatch) -> wgpu::Buffer {
    crate::gpu::context::buffer_init(
        device,
        "shade batch",
        bytemuck::bytes_of(b),
        wgpu::BufferUsages::STORAGE,
    )
}

impl ShadingPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shading"),
            source: wgpu::ShaderSource::Wgsl(shaders::shading_module().into()),
        });
        Self {
            pipeline: compute_pipeline(device, &module, "shade"),
            segments: SegmentShadingPass::new(device, &module),
            rows: RowSegmentsPass::new(device, &module),
            occluder: OccluderPass::new(device),
            batches: Vec::new(),
        }
    }

    pub fn batches(light_count: u32, per_pass: u32) -> Vec<(u32, u32)> {
        let per_pass = per_pass.clamp(1, MAX_LIGHTS_PER_PASS);
        (0..light_count)
            .step_by(per_pass as usize)
            .map(|first| (first, per_pass.min(light_count - first)))
            .collect()
    }

    /// The dispatches of a whole frame, in order (each over all rows).
    pub fn set_batches(&mut self, device: &wgpu::Device, batches: &[ShadeBatch]) {
        self.batches = batches
            .iter()
            .map(|b| (*b, batch_uniform(device, b)))
            .collect();
    }

    /// The visible segments per row of `targets`' K-buffer (the frame's or the preview's, seen by
    /// `camera`) into `readback`, copied for reading ([`crate::render::passes::row_segments`]). Leaves the
    /// segments' claims cleared.
    pub fn encode_row_segments(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        camera: &wgpu::Buffer,
        targets: &FrameTargets,
        segments: &SegmentTargets,
        readback: &mut RowSegmentsReadback,
    ) {
        let layout = ShadeBatch {
            slots: targets.kbuffer.k,
            ..Zeroable::zeroed()
        };
        let batch = batch_uniform(device, &layout);
        let rows = RowSegmentsInputs {
            camera,
            batch: &batch,
            fragments: &targets.kbuffer.fragments,
            segments,
            segment_count: (segments.batches.size() / 4) as u32,
            height: readback.height(),
        };
        self.rows
            .encode(device, encoder, &rows, targets.width, &readback.counts);
        readback.encode_copy(device, encoder);
    }

    /// The batches `encode` dispatches, in order.
    pub fn frame_batches(&self) -> impl Iterator<Item = &ShadeBatch> {
        self.batches.iter().map(|(b, _)| b)
    }

    /// Zeroes the component buffers and the occluder's, and the segments' radiance (the start of a
    /// frame's shading).
    pub fn clear(
        encoder: &mut wgpu::CommandEncoder,
        targets: &FrameTargets,
        segments: Option<&SegmentTargets>,
    ) {
        for b in targets.components.iter().chain([&targets.occluder]) {
            encoder.clear_buffer(b, 0, None);
        }
        if let Some(s) = segments {
            s.clear(encoder);
        }
    }

    fn bind(
        &self,
        device: &wgpu::Device,
        inputs: &ShadingInputs,
        targets: &FrameTargets,
        batch: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        let mut entries = inputs.shading_entries(batch);
        entries.extend((13..).zip(&targets.components));
        entries.push((18, &targets.kbuffer.fragments));
        bind_entries(device, &self.pipeline, "shading", &entries)
    }

    fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind: &wgpu::BindGroup,
        width: u32,
        rows: u32,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shading batch"),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass.dispatch_workgroups(width.div_ceil(8), rows.div_ceil(8), 1);
    }

    /// A whole frame's shading: clears the components, then every batch over every row (and with
    /// segment shading, the gather after the last).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        targets: &FrameTargets,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        Self::clear(encoder, targets, inputs.segment_targets);
        let last = self.batches.len().saturating_sub(1);
        for (k, (b, uniform)) in self.batches.iter().enumerate() {
            let timestamp_writes = timestamps
                .as_ref()
                .filter(|_| k == 0 || k == last)
                .map(|t| wgpu::ComputePassTimestampWrites {
                    query_set: t.query_set,
                    beginning_of_pass_write_index: t
                        .beginning_of_pass_write_index
                        .filter(|_| k == 0),
                    end_of_pass_write_index: t.end_of_pass_write_index.filter(|_| k == last),
                });
            self.encode_with(
                device,
                encoder,
                inputs,
                targets,
                (b, uniform),
                timestamp_writes,
            );
        }
    }

    /// One batch (its rows) with its uniform: a slot's fragments, or the segments under the rows
    /// (gathered after the last light batch), then the occluder.
    fn encode_with(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        targets: &FrameTargets,
        (batch, uniform): (&ShadeBatch, &wgpu::Buffer),
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let size = (targets.width, batch.rows);
        match inputs.segment_targets {
            Some(segments) if batch.flags & FLAG_SEGMENTS != 0 => {
                let gather = last_light_batch(batch);
                let (begin, end) = match &timestamps {
                    Some(t) => (
                        t.beginning_of_pass_write_index
                            .map(|i| wgpu::ComputePassTimestampWrites {
                                query_set: t.query_set,
                                beginning_of_pass_write_index: Some(i),
                                end_of_pass_write_index: None,
                            }),
                        t.end_of_pass_write_index
                            .map(|i| wgpu::ComputePassTimestampWrites {
                                query_set: t.query_set,
                                beginning_of_pass_write_index: None,
                                end_of_pass_write_index: Some(i),
                            }),
                    ),
                    None => (None, None),
                };
                self.segments.encode_batch(
                    device, encoder, inputs, targets, segments, uniform, size, begin,
                );
                self.encode_occluder(device, encoder, inputs, targets, batch);
                if gather {
                    self.segments.encode_gather(
                        device, encoder, inputs, targets, segments, uniform, size, end,
                    );
                }
            }
            _ => {
                let bind = self.bind(device, inputs, targets, uniform);
                self.dispatch(encoder, &bind, size.0, size.1, timestamps);
                self.encode_occluder(device, encoder, inputs, targets, batch);
            }
        }
    }

    /// The occluder's shading under the batch's lights, when there is an occluder and the batch is one
    /// that shades it ([`shades_occluder`]).
    fn encode_occluder(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        targets: &FrameTargets,
        batch: &ShadeBatch,
    ) {
        if let Some(o) = inputs.occluder
            && shades_occluder(batch)
        {
            self.occluder
                .encode(device, encoder, inputs, o, targets, batch);
        }
    }

    /// One batch over its rows `batch.row0 .. batch.row0 + batch.rows` (a unit of progressive
    /// refinement; the components are not cleared).
    pub fn encode_batch(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        targets: &FrameTargets,
        batch: &ShadeBatch,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let uniform = batch_uniform(device, batch);
        self.encode_with(
            device,
            encoder,
            inputs,
            targets,
            (batch, &uniform),
            timestamps,
        );
    }

    /// A repaint's light batch, no claim (written by the caller: the segments in the segment
    /// targets' work list, `candidates` segments and flipped pairs' partners in `ms_candidates`, the
    /// counts): the candidates' keys listed, then the listed segments and keys shaded again (the
    /// rows gather after the last batch: [`Self::encode_repaint_gather`]).
    pub fn encode_repaint(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        batch: &ShadeBatch,
        candidates: u32,
    ) {
        let Some(segments) = inputs.segment_targets else {
            return;
        };
        let uniform = batch_uniform(device, batch);
        if batch.flags & FLAG_MULTIPLE_SCATTERING != 0 {
            self.segments
                .encode_repaint_keys(device, encoder, inputs, segments, &uniform, candidates);
        }
        self.segments
            .encode_listed(device, encoder, inputs, segments, &uniform);
    }

    /// A repaint's gather: rows [batch.row0, + batch.rows) of the components from the segments'
    /// radiance (`batch` the last light batch's, over the rows).
    pub fn encode_repaint_gather(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        targets: &FrameTargets,
        batch: &ShadeBatch,
    ) {
        let Some(segments) = inputs.segment_targets else {
            return;
        };
        let uniform = batch_uniform(device, batch);
        let size = (targets.width, batch.rows);
        self.segments.encode_gather(
            device, encoder, inputs, targets, segments, &uniform, size, None,
        );
    }
}
