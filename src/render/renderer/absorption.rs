//! What the fiber-density volume holds and when it is rebuilt: the absorption per point (the dye),
//! immediate or deferred while refinement runs, the fibers' thickness, and the head as a solid.

use super::{RenderError, Renderer, SceneOccluder, all_ms_pairs};
use crate::gpu::GpuContext;
use crate::gpu::fiber_density::GpuHair;
use crate::hair::Hair;
use crate::render::passes::occluder::{GpuOccluder, Occluder, SHADOW_OFFSET_SPACINGS};
use crate::shadow::solid::solid_fraction;

impl Renderer {
    /// Painted absorption (one RGB per point): rewrites the buffer and marks the volume (which carries
    /// the absorption along shadow paths) for rebuilding.
    pub fn set_absorption(
        &mut self,
        ctx: &GpuContext,
        sigma_a: &[[f32; 3]],
    ) -> Result<(), RenderError> {
        self.upload_absorption(ctx, sigma_a)?;
        self.mark_volume_dirty();
        Ok(())
    }

    /// New absorption per point for shading at once, the volume and shadow grid (whose forward terms
    /// carry the crossed fibers' absorption) kept until [`Renderer::rebuild_stale_volume`]: single
    /// scattering, which reads only the grid's transmittance (absorption-free), is exact meanwhile, and
    /// the editor shows a dye or melanin change before spending the grid's rebuild on it.
    pub fn set_absorption_deferred(
        &mut self,
        ctx: &GpuContext,
        sigma_a: &[[f32; 3]],
    ) -> Result<(), RenderError> {
        self.upload_absorption(ctx, sigma_a)?;
        self.absorption_deferred();
        // Shown at once (not left to a parameter change that may not restart).
        self.restart_refinement();
        Ok(())
    }

    /// [`Renderer::set_absorption_deferred`] for a few points (a brush dab): `sigma_a` holds every
    /// point's absorption, and only the points `changed` (sorted) are written, in runs (gaps of a few
    /// unchanged points are written along rather than split). Every point not in `changed` must
    /// hold what the renderer has already (the runs write some of them, and the pairs' sharing,
    /// `repaint.ms_pairs`, reads the changed points' neighbours from `sigma_a`).
    pub fn set_absorption_points_deferred(
        &mut self,
        ctx: &GpuContext,
        sigma_a: &[[f32; 3]],
        changed: &[u32],
    ) -> Result<(), RenderError> {
        if sigma_a.len() != self.scene.point_count {
            return Err(RenderError::AbsorptionCount {
                points: self.scene.point_count,
                absorption: sigma_a.len(),
            });
        }
        const GAP: u32 = 16;
        let mut k = 0;
        while k < changed.len() {
            let start = changed[k];
            let mut end = start + 1;
            k += 1;
            while k < changed.len() && changed[k] < end + GAP {
                end = changed[k] + 1;
                k += 1;
            }
            let end = (end as usize).min(sigma_a.len());
            let v: Vec<[f32; 4]> = sigma_a[start as usize..end]
                .iter()
                .map(|s| [s[0], s[1], s[2], 0.0])
                .collect();
            ctx.queue.write_buffer(
                &self.scene.hair.absorption,
                16 * start as u64,
                bytemuck::cast_slice(&v),
            );
        }
        self.note_pair_flips(sigma_a, changed);
        self.absorption_deferred();
        Ok(())
    }

    /// Updates [`Renderer::ms_pairs`] for the pairs holding the points `changed`, now at absorption
    /// `sigma_a`, and lists those whose sharing changed in [`Renderer::flips_pending`].
    pub(super) fn note_pair_flips(&mut self, sigma_a: &[[f32; 3]], changed: &[u32]) {
        let segments: Vec<u32> = changed
            .iter()
            .flat_map(|&i| self.segments_at_point(i))
            .collect();
        for k in segments {
            let even = k & !1;
            let paired = crate::render::reference::shade::ms_paired(
                &self.scene.segment_first,
                sigma_a,
                even,
            );
            let Some(was) = self.repaint.ms_pairs.get_mut(k as usize / 2) else {
                continue;
            };
            if *was != paired {
                *was = paired;
                self.repaint.flips_pending.push(even);
            }
        }
    }

    /// The segments that join point `i`: the one from it and the one to it (from i - 1, in the
    /// same strand).
    pub(in crate::render) fn segments_at_point(&self, i: u32) -> impl Iterator<Item = u32> + '_ {
        [Some(i), i.checked_sub(1)]
            .into_iter()
            .flatten()
            .filter_map(|p| self.scene.segment_first.binary_search(&p).ok())
            .map(|k| k as u32)
    }

    /// The absorption changed (shown at once): the volume and grid that carry it follow later.
    pub(super) fn absorption_deferred(&mut self) {
        if self.stale.volume_dirty {
            // A deposit under way holds points or absorption of before: it starts again.
            self.restart_refinement();
            return;
        }
        // Only the grid's forward terms read the volume's absorption.
        if self.settings.shadows && self.settings.multiple_scattering && self.scene.light_count > 0
        {
            self.stale.volume_stale = true;
        } else {
            self.stale.volume_absorption_old = true;
        }
    }

    /// Whether a deferred absorption change still waits for its volume and grid.
    pub fn volume_stale(&self) -> bool {
        self.stale.volume_stale
    }

    /// Rebuilds the volume and grid for a deferred absorption change (restarting the refinement);
    /// false when there was none.
    pub fn rebuild_stale_volume(&mut self) -> bool {
        if !self.stale.volume_stale {
            return false;
        }
        // The change itself is on screen (shaded with the old volume): no new preview. After an
        // absorption change the volume's density, and so the grid's transmittance, stays: a converged
        // image keeps its single scattering (shaded at the new absorption already). A thickness
        // change's density shadows single scattering too.
        if self.stale.volume_stale_density {
            self.restart_as_refinement(|r| r.mark_volume_dirty());
        } else {
            self.refine_multiple_only(|r| r.mark_volume_dirty());
        }
        true
    }

    pub(super) fn upload_absorption(
        &mut self,
        ctx: &GpuContext,
        sigma_a: &[[f32; 3]],
    ) -> Result<(), RenderError> {
        if sigma_a.len() != self.scene.point_count {
            return Err(RenderError::AbsorptionCount {
                points: self.scene.point_count,
                absorption: sigma_a.len(),
            });
        }
        let v: Vec<[f32; 4]> = sigma_a.iter().map(|s| [s[0], s[1], s[2], 0.0]).collect();
        ctx.queue
            .write_buffer(&self.scene.hair.absorption, 0, bytemuck::cast_slice(&v));
        // Every point changes: the refinement restarts, shading every segment whole.
        self.repaint.ms_pairs = all_ms_pairs(&self.scene.segment_first, sigma_a);
        self.repaint.flips_pending.clear();
        Ok(())
    }

    /// Rewrites the points buffer with `hair`'s diameters times `thickness_scale`.
    pub(super) fn write_thickness(
        &mut self,
        ctx: &GpuContext,
        hair: &Hair,
        thickness_scale: f32,
    ) -> Result<(), RenderError> {
        if hair.point_count() != self.scene.point_count {
            return Err(RenderError::HairPoints {
                renderer: self.scene.point_count,
                given: hair.point_count(),
            });
        }
        let points = GpuHair::point_data(hair, thickness_scale);
        ctx.queue
            .write_buffer(&self.scene.hair.points, 0, bytemuck::cast_slice(&points));
        self.scene.point_data = points;
        // The ribbons' width changed: the visibility passes draw them again.
        self.invalidate_visibility();
        Ok(())
    }

    /// A new shadow-grid buffer holds zeros, not finished entries: its groups count as unbuilt (its
    /// samples are the old grid's, [`crate::render::passes::shadow_grid::GpuShadowGrid::with_lights`], or unbuilt in a new renderer).
    pub(super) fn grid_buffer_made(&mut self) {
        let group = self
            .settings
            .lights_per_pass
            .clamp(1, crate::render::passes::shading::MAX_LIGHTS_PER_PASS)
            * crate::render::passes::shadow_grid::SWEEP_SLOTS;
        self.refinement
            .grid
            .unbuilt(group, self.scene.shadow_grid.entry_count());
    }

    /// Every fiber's diameter is `hair`'s times `thickness_scale` (the look's fiber thickness, `hair`
    /// the one the renderer was made with): the points are rewritten and the volume, and with it the
    /// shadow grid, rebuilt; the ribbons in the view follow at once.
    pub fn set_thickness_scale(
        &mut self,
        ctx: &GpuContext,
        hair: &Hair,
        thickness_scale: f32,
    ) -> Result<(), RenderError> {
        self.write_thickness(ctx, hair, thickness_scale)?;
        self.mark_volume_dirty();
        Ok(())
    }

    /// [`Renderer::set_thickness_scale`] for the editor: the ribbons' new width shows at once and, with
    /// shadows, the first image is shaded with the old volume and grid, which
    /// [`Renderer::rebuild_stale_volume`] rebuilds after it (a slider drag is not a volume rebuild
    /// per frame). Without shadows nothing reads the volume until they are turned on: it is rebuilt
    /// then.
    pub fn set_thickness_scale_deferred(
        &mut self,
        ctx: &GpuContext,
        hair: &Hair,
        thickness_scale: f32,
    ) -> Result<(), RenderError> {
        self.write_thickness(ctx, hair, thickness_scale)?;
        if self.stale.volume_dirty {
            // A deposit under way holds points or absorption of before: it starts again.
            self.restart_refinement();
            return Ok(());
        }
        if self.settings.shadows && self.scene.light_count > 0 {
            self.stale.volume_stale = true;
            self.stale.volume_stale_density = true;
            self.restart_refinement();
        } else {
            self.mark_volume_dirty();
        }
        Ok(())
    }

    /// The occluder (None: none): drawn opaque in front of the hair behind it, shaded under the lights,
    /// and added to the fiber-density volume as a solid so that it shadows the hair (the volume and the
    /// shadow grid are rebuilt; the voxelisation runs here, on the CPU: ~10 ms for the generated head).
    pub fn set_occluder(&mut self, ctx: &GpuContext, occluder: Option<&Occluder>) {
        self.scene.occluder = occluder.map(|o| {
            let offset = SHADOW_OFFSET_SPACINGS * self.scene.shadow_grid.grid.spacing;
            SceneOccluder {
                gpu: GpuOccluder::new(&ctx.device, o, offset),
                solid: solid_fraction(&self.scene.volume.grid, &o.mesh),
                shadow_offset: offset,
            }
        });
        self.scene.volume.set_solid(
            &ctx.queue,
            self.scene.occluder.as_ref().map(|o| o.solid.as_slice()),
        );
        self.invalidate_visibility();
        self.mark_volume_dirty();
    }

    /// The occluder's albedo alone changed: its shading restarts, nothing else.
    pub fn set_occluder_albedo(&mut self, ctx: &GpuContext, albedo: [f32; 3]) {
        if let Some(o) = &self.scene.occluder {
            o.gpu.set_albedo(&ctx.queue, albedo);
            self.restart_refinement();
        }
    }

    /// The occluder's voxel fractions and the offset its shadow lookups use (tests: the CPU twins).
    pub fn occluder_solid(&self) -> Option<(&[f32], f32)> {
        self.scene
            .occluder
            .as_ref()
            .map(|o| (o.solid.as_slice(), o.shadow_offset))
    }

    /// The next frame rebuilds the fiber-density volume (geometry moved; benchmarks time it).
    pub fn mark_volume_dirty(&mut self) {
        self.stale.volume_dirty = true;
        // The sweeps' samples read the pyramid the volume makes.
        self.refinement.grid.samples_done = 0;
        self.stale.volume_stale = false;
        self.stale.volume_stale_density = false;
        self.stale.volume_absorption_old = false;
        self.mark_shadow_grid_dirty();
    }

    /// The next frame rebuilds the per-light transmittance grid (benchmarks time it).
    pub fn mark_shadow_grid_dirty(&mut self) {
        self.stale.shadow_grid_dirty = true;
        self.refinement.grid.done = 0;
        self.restart_refinement();
    }
}
