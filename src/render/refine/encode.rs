//! Encoding one planned unit: the pass it belongs to, over its range, on the frame's or the
//! preview's targets.

use super::WorkUnit;
use crate::gpu::GpuContext;
use crate::render::passes::batch::ShadeBatch;
use crate::render::passes::shading::{FLAG_SEGMENTS, FLAG_SINGLE_KEPT, ShadingPass};
use crate::render::passes::shadow_grid::SWEEP_SLOTS;
use crate::render::renderer::Renderer;

impl Renderer {
    pub(super) fn encode_unit(
        &mut self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        unit: WorkUnit,
    ) {
        let device = &ctx.device;
        match unit {
            WorkUnit::PreviewVisibility { first, count } => {
                self.encode_preview_visibility(ctx, enc, first..first + count)
            }
            WorkUnit::Preview { row0, rows } => self.encode_preview(ctx, enc, row0, rows),
            WorkUnit::Volume { first, count } => {
                self.passes.density_pass.encode_deposit(
                    device,
                    enc,
                    &self.scene.hair,
                    &self.scene.volume,
                    first..first + count,
                );
            }
            WorkUnit::VolumeResolve { first, count } => {
                let voxels = first..first + count;
                self.passes.density_pass.encode_resolve(
                    device,
                    enc,
                    &self.scene.hair,
                    &self.scene.volume,
                    voxels,
                );
            }
            WorkUnit::DensityPyramid => {
                self.passes.pyramid_pass.encode(
                    device,
                    enc,
                    &self.scene.volume,
                    &self.scene.pyramid,
                    None,
                );
                self.stale.volume_dirty = false;
                self.stale.shadow_grid_dirty = true;
                self.refinement.grid.done = 0;
                self.refinement.grid.samples_done = 0;
            }
            WorkUnit::GridSamples { first, count } => {
                let inputs = self.shadow_grid_inputs();
                self.passes.shadow_grid_pass.encode_samples(
                    device,
                    enc,
                    &inputs,
                    &self.scene.shadow_grid,
                    first..first + count,
                    None,
                );
            }
            WorkUnit::ShadowGrid { first, count } => {
                let inputs = self.shadow_grid_inputs();
                self.passes.shadow_grid_pass.encode(
                    device,
                    enc,
                    &inputs,
                    &self.scene.shadow_grid,
                    first,
                    count,
                    None,
                );
                let total = self.scene.shadow_grid.entry_count();
                let group = inputs.light_group * SWEEP_SLOTS;
                self.refinement.grid.built(first, count, group, total);
                if first + count >= total {
                    self.stale.shadow_grid_dirty = false;
                }
            }
            WorkUnit::Visibility { first, count } => {
                if count > 0 {
                    self.passes.visibility_pass.encode(
                        device,
                        enc,
                        &self.view.camera,
                        &self.scene.hair,
                        self.scene.occluder.as_ref().map(|o| &o.gpu),
                        &self.view.targets,
                        first..first + count,
                        None,
                        None,
                    );
                }
                if first + count < self.scene.hair.segment_count {
                    return;
                }
                // The last part: the image's visibility is whole; the components restart.
                self.stale.visibility_valid = true;
                self.encode_row_segments(device, enc);
                ShadingPass::clear(enc, &self.view.targets, self.view.segment_targets.as_ref());
                self.stale.converged_rows = 0;
            }
            WorkUnit::Backdrop { row0, rows } => {
                self.encode_resolve(device, enc, row0..row0 + rows, (true, true));
            }
            WorkUnit::Repaint {
                batch,
                first,
                segments,
            } => {
                let Some(b) = self.passes.shading_pass.frame_batches().nth(batch as usize) else {
                    return;
                };
                let end = (first + segments).min(self.repaint.segments.len() as u32);
                let start = first.min(end) as usize;
                let part = &self.repaint.segments[start..end as usize];
                let mut candidates = Vec::new();
                if let Some(s) = &self.view.segment_targets {
                    ctx.queue
                        .write_buffer(&s.work_list, 0, bytemuck::cast_slice(part));
                    // Multiple scattering's candidates: the part's segments and the partners of the
                    // pairs the dabs joined or split, not listed themselves (each once in the whole
                    // repaint: a segment has one partner), whole pairs for the GPU's keys there
                    // ([`Renderer::repaint_partner`]). A pair that stays joined with one segment
                    // listed keeps its key's sample: its shared point did not change (else both
                    // segments are listed), and the GPU, which lists a candidate only where it is
                    // its own key, leaves it.
                    candidates = part.to_vec();
                    candidates.extend(part.iter().filter_map(|&s| {
                        self.repaint_partner(s)
                            .filter(|p| self.repaint.segments.binary_search(p).is_err())
                    }));
                    if !candidates.is_empty() {
                        ctx.queue.write_buffer(
                            &s.ms_candidates,
                            0,
                            bytemuck::cast_slice(&candidates),
                        );
                    }
                    let count = [part.len() as u32, 0, candidates.len() as u32];
                    ctx.queue
                        .write_buffer(&s.work_count, 0, bytemuck::cast_slice(&count));
                }
                let inputs = self.shading_inputs();
                self.passes.shading_pass.encode_repaint(
                    device,
                    enc,
                    &inputs,
                    b,
                    candidates.len() as u32,
                );
            }
            WorkUnit::RepaintGather { row0, rows } => {
                // The last batch's flags (what the segments hold) over the band.
                let Some(last) = self.passes.shading_pass.frame_batches().last() else {
                    return;
                };
                if rows == 0 {
                    return;
                }
                let b = ShadeBatch {
                    row0,
                    rows,
                    ..*last
                };
                let inputs = self.shading_inputs();
                self.passes.shading_pass.encode_repaint_gather(
                    device,
                    enc,
                    &inputs,
                    &self.view.targets,
                    &b,
                );
                self.encode_resolve(device, enc, row0..row0 + rows, (false, false));
            }
            WorkUnit::Shade { batch, row0, rows } => {
                let Some(b) = self.passes.shading_pass.frame_batches().nth(batch as usize) else {
                    return;
                };
                let kept = if self.stale.single_kept && b.flags & FLAG_SEGMENTS != 0 {
                    FLAG_SINGLE_KEPT
                } else {
                    0
                };
                let b = ShadeBatch {
                    row0,
                    rows,
                    flags: b.flags | kept,
                    ..*b
                };
                let inputs = self.shading_inputs();
                self.passes.shading_pass.encode_batch(
                    device,
                    enc,
                    &inputs,
                    &self.view.targets,
                    &b,
                    None,
                );
                // The last batch leaves its rows converged: resolved as render_frame resolves them.
                // (Shaded by segment, rows have no image before it: their pixels gather then.)
                let last = batch + 1 >= self.passes.shading_pass.frame_batches().count() as u32;
                if last {
                    self.stale.converged_rows = self.stale.converged_rows.max(row0 + rows);
                }
                if last || b.flags & FLAG_SEGMENTS == 0 {
                    self.encode_resolve(device, enc, row0..row0 + rows, (false, !last));
                }
            }
        }
    }

    pub(super) fn encode_resolve(
        &self,
        device: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        rows: std::ops::Range<u32>,
        (background, normalise): (bool, bool),
    ) {
        self.passes.resolve_pass.encode(
            device,
            enc,
            &self.view.camera,
            &self.view.resolve_info,
            &self.scene.background_map,
            &self.view.targets,
            rows,
            (background, normalise),
            None,
        );
    }
}
