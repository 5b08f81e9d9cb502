//! A whole frame at once ([`Renderer::render_frame`]): the passes encoded in order, the batches of
//! lights they shade in, and their timing.

use super::{MAX_SEGMENT_ANGLE, RenderError, Renderer};
use crate::gpu::GpuContext;
use crate::gpu::density_pyramid::DensityPyramidPass;
use crate::gpu::fiber_density::FiberDensityPass;
use crate::render::passes::batch::{ShadeBatch, ShadingInputs};
use crate::render::passes::resolve::ResolvePass;
use crate::render::passes::shading::{
    FLAG_MULTIPLE_SCATTERING, FLAG_SEGMENTS, FLAG_SHADOWS, ShadingPass,
};
use crate::render::passes::shadow_grid::{ShadowGridInputs, ShadowGridPass};
use crate::render::passes::visibility::VisibilityPass;
use glam::Vec3;

/// The passes of a frame, built once.
pub(in crate::render) struct FramePasses {
    pub(in crate::render) density_pass: FiberDensityPass,
    pub(in crate::render) pyramid_pass: DensityPyramidPass,
    pub(in crate::render) shadow_grid_pass: ShadowGridPass,
    pub(in crate::render) visibility_pass: VisibilityPass,
    pub(in crate::render) shading_pass: ShadingPass,
    pub(in crate::render) resolve_pass: ResolvePass,
}

impl Renderer {
    /// Whether the frame can shade each segment once as the eye sees them now: every segment
    /// subtends at most [`MAX_SEGMENT_ANGLE`] (bounded by the longest over the distance from the eye
    /// to the hair's bounds).
    pub(super) fn segments_fit_view(&self) -> bool {
        let (longest, lo, hi) = self.scene.segment_extent;
        let c = self.view_camera();
        let eye = Vec3::from(c.eye);
        let distance = (eye.clamp(lo, hi) - eye).length().max(c.near);
        self.view.segment_targets.is_some() && longest / distance <= MAX_SEGMENT_ANGLE
    }

    /// The camera moved: the frame's batches switch between segments and fragments when the
    /// segments' angular size crossed [`MAX_SEGMENT_ANGLE`].
    pub(super) fn update_shading_mode(&mut self, device: &wgpu::Device) {
        if self.segments_fit_view() != self.by_segment {
            self.update_batches(device);
        }
    }

    pub(super) fn update_batches(&mut self, device: &wgpu::Device) {
        self.by_segment = self.segments_fit_view();
        let mut flags = 0;
        if self.settings.shadows {
            flags |= FLAG_SHADOWS;
        }
        if self.settings.multiple_scattering {
            flags |= FLAG_MULTIPLE_SCATTERING;
        }
        let slots = self.settings.fragments;
        let height = self.settings.height;
        let lights = self.scene.light_count;
        // Per fragment, slot-major: every light batch at the front fragment (most of every pixel),
        // then at the ones behind it, so a refining image has all its lights early. Per segment: the
        // light batches, each over the segments of all the slots.
        let light_batches =
            ShadingPass::batches(self.scene.light_count, self.settings.lights_per_pass);
        let slot_passes = if self.by_segment {
            flags |= FLAG_SEGMENTS;
            1
        } else {
            slots
        };
        let batches: Vec<ShadeBatch> = (0..slot_passes)
            .flat_map(|slot| {
                light_batches.iter().map(move |&(first, count)| ShadeBatch {
                    first,
                    count,
                    flags,
                    slots,
                    slot,
                    row0: 0,
                    rows: height,
                    lights,
                })
            })
            .collect();
        self.passes.shading_pass.set_batches(device, &batches);
        self.restart_refinement();
    }

    /// What the shadow-grid build reads.
    pub(in crate::render) fn shadow_grid_inputs(&self) -> ShadowGridInputs<'_> {
        ShadowGridInputs {
            pyramid: &self.scene.pyramid,
            volume: &self.scene.volume,
            forward_table: &self.look.forward_table,
            lights: &self.scene.lights,
            light_group: self
                .settings
                .lights_per_pass
                .clamp(1, crate::render::passes::shading::MAX_LIGHTS_PER_PASS),
        }
    }

    /// What the shading pass reads.
    pub(in crate::render) fn shading_inputs(&self) -> ShadingInputs<'_> {
        ShadingInputs {
            camera: &self.view.camera,
            params: &self.look.params,
            shadow_grid: &self.scene.shadow_grid.info,
            points: &self.scene.hair.points,
            segments: &self.scene.hair.segments,
            absorption: &self.scene.hair.absorption,
            lights: &self.scene.lights,
            lut_c: &self.look.luts.c,
            shadow_values: &self.scene.shadow_grid.values,
            dual_tables: &self.look.dual_tables,
            azimuthal_table: &self.look.azimuthal_table,
            occluder: self.scene.occluder.as_ref().map(|o| &o.gpu),
            segment_targets: self.view.segment_targets.as_ref(),
        }
    }

    /// Whether the frame (and its preview) shades each visible segment once (else every fragment: per-fragment
    /// shading asked for, segment buffers that would not fit a binding, or segments that the eye sees
    /// under more than [`MAX_SEGMENT_ANGLE`]).
    pub fn shades_segments(&self) -> bool {
        self.by_segment
    }

    /// Encodes and submits one frame.
    pub fn render_frame(&mut self, ctx: &GpuContext) {
        let device = &ctx.device;
        let timer = self.timer.as_ref();
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        });
        self.last_ran.clear();
        if self.stale.volume_dirty {
            self.passes.density_pass.encode(
                device,
                &mut enc,
                &self.scene.hair,
                &self.scene.volume,
                timer.and_then(|t| t.compute_writes("fiber_density")),
            );
            self.passes.pyramid_pass.encode(
                device,
                &mut enc,
                &self.scene.volume,
                &self.scene.pyramid,
                timer.and_then(|t| t.compute_writes("density_pyramid")),
            );
            self.last_ran.extend(["fiber_density", "density_pyramid"]);
            self.stale.volume_dirty = false;
            self.stale.shadow_grid_dirty = true;
            self.refinement.grid.done = 0;
            self.refinement.grid.samples_done = 0;
        }
        if self.stale.shadow_grid_dirty && self.settings.shadows && self.scene.light_count > 0 {
            let count = self.scene.shadow_grid.entry_count();
            let inputs = self.shadow_grid_inputs();
            let samples = self.scene.shadow_grid.sample_count();
            let samples_stale = self.refinement.grid.samples_done < samples;
            if samples_stale {
                self.passes.shadow_grid_pass.encode_samples(
                    device,
                    &mut enc,
                    &inputs,
                    &self.scene.shadow_grid,
                    0..samples,
                    timer.and_then(|t| t.compute_writes("grid_samples")),
                );
            }
            self.passes.shadow_grid_pass.encode(
                device,
                &mut enc,
                &inputs,
                &self.scene.shadow_grid,
                0,
                count,
                timer.and_then(|t| t.compute_writes("shadow_grid")),
            );
            if samples_stale {
                self.last_ran.push("grid_samples");
            }
            self.last_ran.push("shadow_grid");
            self.refinement.grid.samples_done = samples;
            self.stale.shadow_grid_dirty = false;
            self.refinement.grid.complete(count);
        }
        self.passes.visibility_pass.encode(
            device,
            &mut enc,
            &self.view.camera,
            &self.scene.hair,
            self.scene.occluder.as_ref().map(|o| &o.gpu),
            &self.view.targets,
            0..self.scene.hair.segment_count,
            None,
            timer.and_then(|t| t.render_writes("visibility")),
        );
        let mut readback = self.row_readback.take();
        self.encode_row_segments_into(device, &mut enc, &mut readback);
        self.row_readback = readback;
        let inputs = self.shading_inputs();
        self.passes.shading_pass.encode(
            device,
            &mut enc,
            &inputs,
            &self.view.targets,
            timer.and_then(|t| t.compute_writes("shading")),
        );
        self.passes.resolve_pass.encode(
            device,
            &mut enc,
            &self.view.camera,
            &self.view.resolve_info,
            &self.scene.background_map,
            &self.view.targets,
            0..self.settings.height,
            (true, false),
            timer.and_then(|t| t.compute_writes("resolve")),
        );
        self.stale.visibility_valid = true;
        self.stale.converged_rows = u32::MAX;
        self.last_ran.extend(["visibility", "shading", "resolve"]);
        if let Some(t) = timer {
            t.resolve(&mut enc);
        }
        ctx.queue.submit([enc.finish()]);
        self.request_row_segments();
        self.refinement.complete_frame();
        // The whole frame is shaded: no dab waits for a repaint, nothing is kept.
        self.repaint.pending.clear();
        self.repaint.flips_pending.clear();
        self.stale.single_kept = false;
    }

    /// Rebuilds the whole shadow grid alone, its sweeps' samples included, and waits for it:
    /// wall-clock seconds (benchmarks). On lavapipe
    /// a compute pass's timestamps bracket the dispatch's submission to its thread pool, not its work, so
    /// a pass that no later barrier waits for inside its own bracket (the grid) reads ~0 ms there.
    pub fn time_shadow_grid(&mut self, ctx: &GpuContext) -> Result<f64, RenderError> {
        if !self.settings.shadows || self.scene.light_count == 0 {
            return Ok(0.0);
        }
        let t = std::time::Instant::now();
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("shadow grid alone"),
            });
        let inputs = self.shadow_grid_inputs();
        let samples = self.scene.shadow_grid.sample_count();
        self.passes.shadow_grid_pass.encode_samples(
            &ctx.device,
            &mut enc,
            &inputs,
            &self.scene.shadow_grid,
            0..samples,
            None,
        );
        self.passes.shadow_grid_pass.encode(
            &ctx.device,
            &mut enc,
            &inputs,
            &self.scene.shadow_grid,
            0,
            self.scene.shadow_grid.entry_count(),
            None,
        );
        self.refinement.grid.samples_done = samples;
        ctx.queue.submit([enc.finish()]);
        ctx.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        self.refinement
            .grid
            .complete(self.scene.shadow_grid.entry_count());
        Ok(t.elapsed().as_secs_f64())
    }

    /// GPU milliseconds per pass of the last frame (None without timestamp queries).
    pub fn pass_times(
        &self,
        ctx: &GpuContext,
    ) -> Result<Option<Vec<(&'static str, f64)>>, RenderError> {
        match &self.timer {
            None => Ok(None),
            Some(t) => t
                .read_ms(ctx, &self.last_ran)
                .map(Some)
                .map_err(RenderError::Gpu),
        }
    }
}
