//! Which unit next: the plan's stages after a change (preview, volume, shadow grid, visibility,
//! backdrop, shading bands, repaints) and the size of each unit, asked of the cost model.

use super::costs::*;
use super::{ImageReady, Progress, RefineStats, Stage, WorkUnit};
use crate::render::passes::batch::ShadeBatch;
use crate::render::passes::segment_shading::last_light_batch;
use crate::render::passes::shading::FLAG_SEGMENTS;
use crate::render::passes::shadow_grid::SWEEP_SLOTS;
use crate::render::refine::preview::preview_target;
use crate::render::renderer::Renderer;
use std::time::{Duration, Instant};

impl Renderer {
    /// Whether frames read the shadow grid at all.
    pub(super) fn grid_used(&self) -> bool {
        self.settings.shadows && self.scene.light_count > 0
    }

    /// Whether the grid frames read is stale.
    pub(super) fn grid_needed(&self) -> bool {
        self.grid_used() && self.stale.shadow_grid_dirty
    }

    /// The first stage of the frame's plan after the preview.
    pub(super) fn main_stage(&self) -> Stage {
        if self.stale.volume_dirty {
            Stage::Volume { first: 0 }
        } else if self.grid_needed() {
            Stage::ShadowGrid
        } else {
            Stage::Visibility { first: 0 }
        }
    }

    pub(in crate::render) fn replan(&mut self) {
        let stage = if self.refinement.preview_state.owed && self.preview_factor() > 1 {
            Stage::PreviewVisibility { first: 0 }
        } else {
            self.main_stage()
        };
        // Whatever the new plan shades, it shades whole: no repaint waits.
        self.repaint.pending.clear();
        self.repaint.flips_pending.clear();
        self.repaint.flips.clear();
        let r = &mut self.refinement;
        r.preview_state.started = false;
        r.preview_state.new_view = false;
        r.preview_state.shading = Duration::ZERO;
        r.sharp_rows = 0;
        r.shade_done = 0.0;
        r.stats = RefineStats::default();
        r.started = Instant::now();
        r.restarts += 1;
        r.stage = stage;
    }

    /// Whether a batch gathers its rows' segments into pixels (by segment, the last light batch).
    pub(super) fn batch_gathers(&self, b: &ShadeBatch) -> bool {
        self.by_segment && b.flags & FLAG_SEGMENTS != 0 && last_light_batch(b)
    }

    /// Whether the unit gathers (the last light batch's units by segment, and the preview's).
    pub(super) fn unit_gathers(&self, unit: WorkUnit) -> bool {
        match unit {
            WorkUnit::Shade { batch, .. } => self
                .passes
                .shading_pass
                .frame_batches()
                .nth(batch as usize)
                .is_some_and(|b| self.batch_gathers(b)),
            WorkUnit::Preview { .. } => self.by_segment,
            _ => false,
        }
    }

    /// The first pass's light batches as its bands' sizing sees them.
    pub(super) fn first_pass_shapes(&self) -> Vec<BandShape> {
        self.passes
            .shading_pass
            .frame_batches()
            .take_while(|b| b.slot == 0)
            .map(|b| BandShape {
                lights: b.count,
                gathers: self.batch_gathers(b),
            })
            .collect()
    }

    /// Frame batch `batch`'s K-buffer slot and light count.
    pub(super) fn batch_shape(&self, batch: u32) -> Option<(u32, u32)> {
        self.passes
            .shading_pass
            .frame_batches()
            .nth(batch as usize)
            .map(|b| (b.slot, b.count))
    }

    /// Shading batches of the first pass: every light batch at the front K-buffer slot.
    pub(super) fn first_pass_batches(&self) -> u32 {
        self.passes
            .shading_pass
            .frame_batches()
            .take_while(|b| b.slot == 0)
            .count() as u32
    }

    pub(super) fn progress(
        &self,
        submitted: Option<WorkUnit>,
        busy: bool,
        ready: Option<ImageReady>,
    ) -> Progress {
        let r = &self.refinement;
        let grid_cost = r.costs.grid_cost.unwrap_or(GUESS_GRID_ENTRY_S);
        let samples_cost = r.costs.samples_cost.unwrap_or(GUESS_GRID_SAMPLE_S);
        let entries = self.scene.shadow_grid.entry_count() as f64;
        let samples = self.scene.shadow_grid.sample_count() as f64;
        // The grid's sweeps and the samples they read (rebuilt with the pyramid: done when the
        // grid is not stale).
        let grid_total = if self.grid_used() {
            entries * grid_cost + samples * samples_cost
        } else {
            0.0
        };
        let grid_done = if self.grid_needed() {
            r.grid.done as f64 * grid_cost
                + (r.grid.samples_done as f64).min(samples) * samples_cost
        } else {
            grid_total
        };
        let height = self.settings.height as f64;
        let shade_total: f64 = self
            .passes
            .shading_pass
            .frame_batches()
            .map(|b| height * r.costs.light_row_cost(b.slot) * b.count as f64)
            .sum();
        let shade_done = r.shade_done;
        let converged = r.stage == Stage::Converged && r.in_flight.is_none();
        let fraction = if converged {
            1.0
        } else {
            ((grid_done + shade_done) / (grid_total + shade_total).max(1e-12)).min(0.999) as f32
        };
        Progress {
            submitted,
            busy,
            converged,
            ready,
            fraction,
            stats: r.stats,
        }
    }

    /// Shadow-grid entries that shading batch `batch` reads: the lights' up to the batch's last.
    pub(super) fn grid_entries_for(&self, batch: u32) -> u32 {
        let total = self.scene.shadow_grid.entry_count();
        match self.passes.shading_pass.frame_batches().nth(batch as usize) {
            Some(b) => ((b.first + b.count) * SWEEP_SLOTS).min(total),
            None => total,
        }
    }

    /// A shadow-grid unit towards `target` entries (after the sweeps' samples), or None when they
    /// are built.
    pub(super) fn grid_unit(&mut self, target: u32) -> Option<WorkUnit> {
        let samples = self.scene.shadow_grid.sample_count();
        let group = self.shadow_grid_inputs().light_group;
        let r = &mut self.refinement;
        if r.grid.done >= target {
            return None;
        }
        if r.grid.samples_done < samples {
            let count = r.costs.items(
                r.costs.samples_cost,
                GUESS_GRID_SAMPLE_S,
                u32::MAX / 2,
                samples - r.grid.samples_done,
            );
            let first = r.grid.samples_done;
            r.grid.samples_done += count;
            return Some(WorkUnit::GridSamples { first, count });
        }
        let remaining = target - r.grid.done;
        let mut count = r.costs.items(
            r.costs.grid_cost,
            GUESS_GRID_ENTRY_S,
            r.costs.grid_last,
            remaining,
        );
        // Whole rounds of the device's side-by-side workgroups where an entry is one workgroup (a
        // unit within one light group: `ShadowGridPass::encode`): on lavapipe on two cores three
        // entries took as long as four (40-50 ms against the two's 21).
        let p = r.costs.parallel_workgroups.max(1);
        if count > p && count <= group && count < remaining {
            count -= count % p;
        }
        r.costs.grid_last = count;
        let first = r.grid.done;
        r.grid.done += count;
        Some(WorkUnit::ShadowGrid { first, count })
    }

    /// Segments of a visibility unit from `first`: as many as the budget holds at the measured cost
    /// per segment (drawing costs about the same per segment whatever the resolution).
    pub(super) fn visibility_part(&self, first: u32, preview: bool) -> u32 {
        let r = &self.refinement;
        let drawn = match preview {
            true => self.preview_draw_count(),
            false => self.scene.hair.segment_count,
        };
        let remaining = drawn.saturating_sub(first);
        // Before the frame's first part is measured: the preview's cost per segment times its
        // divisor (fragments go with the resolution), or the guess.
        let factor = self.preview.as_ref().map_or(1.0, |p| p.factor as f64);
        let cost = match preview {
            true => r.costs.preview_visibility_cost,
            false => r
                .costs
                .visibility_cost
                .or(r.costs.preview_visibility_cost.map(|c| c * factor)),
        };
        r.costs
            .items(cost, GUESS_VISIBILITY_SEGMENT_S, u32::MAX / 2, remaining)
    }

    /// The next unit of the plan (sized to the budget); advances the plan past it. The shadow grid is
    /// built light batch by light batch, each just before the first shading batch that reads it: the
    /// first light batch's part before the visibility pass clears the image (the last image stays on
    /// screen meanwhile), the others between shading batches.
    pub(super) fn next_unit(&mut self, device: &wgpu::Device) -> Option<WorkUnit> {
        let height = self.settings.height;
        let batches = self.passes.shading_pass.frame_batches().count() as u32;
        let grid_needed = self.grid_needed();
        match self.refinement.stage {
            Stage::PreviewVisibility { first } => {
                let Some(valid) = self.prepare_preview(device).map(|_| self.preview_visible())
                else {
                    self.refinement.stage = self.main_stage();
                    return self.next_unit(device);
                };
                if valid {
                    self.refinement.stage = Stage::Preview { row: 0 };
                    return self.next_unit(device);
                }
                let count = self.visibility_part(first, true);
                self.refinement.stage = if first + count >= self.preview_draw_count() {
                    Stage::Preview { row: 0 }
                } else {
                    Stage::PreviewVisibility {
                        first: first + count,
                    }
                };
                Some(WorkUnit::PreviewVisibility { first, count })
            }
            Stage::PreparePreview { first } => {
                if self.prepare_preview(device).is_none() || self.preview_visible() {
                    self.refinement.stage = Stage::Converged;
                    return self.next_unit(device);
                }
                let count = self.visibility_part(first, true);
                self.refinement.stage = if first + count >= self.preview_draw_count() {
                    Stage::Converged
                } else {
                    Stage::PreparePreview {
                        first: first + count,
                    }
                };
                Some(WorkUnit::PreviewVisibility { first, count })
            }
            Stage::Preview { row } => {
                let Some(p) = self.prepare_preview(device) else {
                    self.refinement.stage = self.main_stage();
                    return self.next_unit(device);
                };
                let rows = self.preview_rows(row, p);
                self.refinement.stage = if row + rows < p {
                    Stage::Preview { row: row + rows }
                } else {
                    self.main_stage()
                };
                Some(WorkUnit::Preview { row0: row, rows })
            }
            Stage::Volume { first } => {
                let segments = self.scene.hair.segment_count;
                let r = &mut self.refinement;
                if first >= segments && first > 0 {
                    r.stage = Stage::Resolve { first: 0 };
                    return self.next_unit(device);
                }
                // Segments cost about the same each: sized by the budget alone (no doubling from
                // a small first unit).
                let count = r.costs.items(
                    r.costs.volume_cost,
                    GUESS_SEGMENT_S,
                    u32::MAX / 2,
                    segments - first,
                );
                r.stage = Stage::Volume {
                    first: first + count,
                };
                Some(WorkUnit::Volume { first, count })
            }
            Stage::Resolve { first } => {
                let voxels = self.scene.volume.grid.voxel_count() as u32;
                let r = &mut self.refinement;
                let count = r
                    .costs
                    .items(
                        r.costs.resolve_cost,
                        GUESS_VOXEL_S,
                        u32::MAX / 2,
                        voxels - first,
                    )
                    .max(MIN_RESOLVE_VOXELS)
                    .min(voxels - first);
                r.stage = if first + count >= voxels {
                    Stage::Pyramid
                } else {
                    Stage::Resolve {
                        first: first + count,
                    }
                };
                Some(WorkUnit::VolumeResolve { first, count })
            }
            Stage::Pyramid => {
                self.refinement.stage = Stage::ShadowGrid;
                Some(WorkUnit::DensityPyramid)
            }
            Stage::ShadowGrid => {
                if grid_needed && let Some(unit) = self.grid_unit(self.grid_entries_for(0)) {
                    return Some(unit);
                }
                self.refinement.stage = Stage::Visibility { first: 0 };
                self.next_unit(device)
            }
            Stage::Visibility { first } => {
                // A parameter change keeps the camera's visibility: one unit clears the components.
                let segments = self.scene.hair.segment_count;
                let (first, count) = if self.stale.visibility_valid {
                    (segments, 0)
                } else {
                    (first, self.visibility_part(first, false))
                };
                self.refinement.stage = if first + count < segments {
                    Stage::Visibility {
                        first: first + count,
                    }
                } else {
                    Stage::Backdrop { row: 0 }
                };
                Some(WorkUnit::Visibility { first, count })
            }
            Stage::Backdrop { row } => {
                let r = &mut self.refinement;
                let guess = GUESS_PIXEL_S * self.settings.width as f64;
                // At most twice the last, from a few workgroups' rows (rows with hair cost more than
                // the background's, and the cost per row measured in one unit can double in the
                // next when a table worker shares the cores).
                if row == 0 {
                    r.costs.backdrop_last = 2 * MIN_BACKDROP_ROWS;
                }
                let rows = r
                    .costs
                    .items(
                        r.costs.backdrop_cost,
                        guess,
                        r.costs.backdrop_last,
                        height - row,
                    )
                    .max(MIN_BACKDROP_ROWS)
                    .min(height - row);
                r.costs.backdrop_last = rows;
                r.stage = if row + rows < height {
                    Stage::Backdrop { row: row + rows }
                } else if batches == 0 {
                    Stage::Converged
                } else {
                    Stage::Shade {
                        batch: 0,
                        row: 0,
                        band: 0,
                    }
                };
                Some(WorkUnit::Backdrop { row0: row, rows })
            }
            Stage::Shade { batch, row, band } => {
                if grid_needed
                    && row == 0
                    && let Some(unit) = self.grid_unit(self.grid_entries_for(batch))
                {
                    return Some(unit);
                }
                let first_pass = self.first_pass_batches();
                let by_segment = self.by_segment;
                let width = self.settings.width;
                // Only a new band of the first batch by segment sizes by them.
                let shapes = match band == 0 && by_segment {
                    true => self.first_pass_shapes(),
                    false => Vec::new(),
                };
                let (slot, lights) = self.batch_shape(batch).unwrap_or((0, 1));
                let lights = lights.max(1) as f64;
                let r = &mut self.refinement;
                let budget = r.costs.unit_seconds() / lights;
                let rows = if band > 0 {
                    band.min(height - row)
                } else {
                    let k = slot_bands(slot);
                    let prior: &[f64] = if k > 0 {
                        &r.costs.bands[0].row_cost
                    } else {
                        &[]
                    };
                    let guess = GUESS_SHADE_ROW_S / GUESS_ROW_LIGHTS;
                    let by_counts = r
                        .costs
                        .row_segments
                        .as_deref()
                        .filter(|_| k == 0 && by_segment)
                        .map(|c| {
                            let total = r.costs.unit_seconds();
                            r.costs
                                .segment_band_rows(c, (row, height, width), &shapes, total)
                        });
                    let rows = by_counts.unwrap_or_else(|| {
                        r.costs.bands[k].rows(row, height, budget, guess, prior)
                    });
                    r.costs.bands[k].last = rows;
                    rows
                };
                r.shade_done += rows as f64 * r.costs.light_row_cost(slot) * lights;
                let next_band = |batch| Stage::Shade {
                    batch,
                    row: 0,
                    band: 0,
                };
                r.stage = if batch < first_pass {
                    // The first pass band by band, each under every light batch: the full image
                    // sharpens from the top over the preview.
                    if batch + 1 < first_pass {
                        Stage::Shade {
                            batch: batch + 1,
                            row,
                            band: rows,
                        }
                    } else if row + rows < height {
                        Stage::Shade {
                            batch: 0,
                            row: row + rows,
                            band: 0,
                        }
                    } else if first_pass < batches {
                        next_band(first_pass)
                    } else {
                        Stage::Converged
                    }
                } else if row + rows < height {
                    Stage::Shade {
                        batch,
                        row: row + rows,
                        band: 0,
                    }
                } else if batch + 1 < batches {
                    next_band(batch + 1)
                } else {
                    Stage::Converged
                };
                Some(WorkUnit::Shade {
                    batch,
                    row0: row,
                    rows,
                })
            }
            Stage::Repaint { batch, first } => {
                let total = self.repaint.segments.len() as u32;
                let lights = self.batch_shape(batch).map_or(1, |b| b.1).max(1) as f64;
                let r = &mut self.refinement;
                // A dab's scattered segments cost more each than a band's (S1: 5.7-6.3 us a
                // segment and light against the bands' 5.3): their own measure, or twice the
                // bands' before one is made (the stroke's first unit, with a quarter over them:
                // 462 segments under 16 lights in 55 ms at 35 ms units, lavapipe on two cores).
                let per = r
                    .costs
                    .repaint_cost
                    .or(r.costs.segment_cost.map(|c| 2.0 * c))
                    .map(|c| c * lights);
                let remaining = total.saturating_sub(first);
                let count = r
                    .costs
                    .items(per, GUESS_SEGMENT_LIGHT_S * lights, u32::MAX / 2, remaining)
                    .max(MIN_MEASURED_SEGMENTS as u32)
                    .min(remaining);
                r.stage = if first + count < total {
                    Stage::Repaint {
                        batch,
                        first: first + count,
                    }
                } else if batch + 1 < batches {
                    Stage::Repaint {
                        batch: batch + 1,
                        first: 0,
                    }
                } else {
                    Stage::RepaintGather {
                        row: self.repaint.rows.start,
                    }
                };
                Some(WorkUnit::Repaint {
                    batch,
                    first,
                    segments: count,
                })
            }
            Stage::RepaintGather { row } => {
                // Bands of the rows at the measured cost per pixel (one unit of no rows when the
                // segments leave none on screen: it still ends the repaint).
                let end = self.repaint.rows.end.max(row);
                let r = &mut self.refinement;
                let width = self.settings.width.max(1) as f64;
                let rows = r
                    .costs
                    .items(
                        r.costs.gather_cost.map(|c| c * width),
                        GUESS_GATHER_PIXEL_S * width,
                        u32::MAX / 2,
                        end - row,
                    )
                    .min(end - row);
                // Whole workgroups (8 rows) unless it is the last band.
                let rows = if rows >= 8 && row + rows < end {
                    rows - rows % 8
                } else {
                    rows
                };
                r.stage = if row + rows < end {
                    Stage::RepaintGather { row: row + rows }
                } else {
                    Stage::Converged
                };
                Some(WorkUnit::RepaintGather { row0: row, rows })
            }
            Stage::Converged => {
                // Dabs that came during a repaint.
                if self.repaint.pending.is_empty() {
                    // The first preview's time changed its divisor: its visibility at the new one
                    // now (S1 on lavapipe: 140 ms of a first edit's 300 ms preview). A divisor
                    // that waited for the next camera move (the redraw would have cost the next
                    // preview more than it saves) applies now, the redraw costing no preview.
                    let r = &mut self.refinement;
                    if let Some(f) = r.preview_state.deferred_factor.take() {
                        r.preview_state.auto_factor = Some(f);
                    }
                    if self.prepare_preview(device).is_some() && !self.preview_visible() {
                        self.refinement.stage = Stage::PreparePreview { first: 0 };
                        return self.next_unit(device);
                    }
                    return None;
                }
                let pending = std::mem::take(&mut self.repaint.pending);
                self.start_repaint(pending);
                self.next_unit(device)
            }
        }
    }

    /// The segments a frame or preview shading unit listed, by the counts (None: not counted, or
    /// not by segment; a kept single scattering's units cost less and are not counted either).
    pub(super) fn listed_segments(&self, unit: WorkUnit) -> Option<(u64, u64)> {
        let (counts, row0, rows, width) = match unit {
            WorkUnit::Shade { batch, row0, rows } if !self.stale.single_kept => {
                let slot = self.batch_shape(batch).map_or(0, |b| b.0);
                let counts = self
                    .refinement
                    .costs
                    .row_segments
                    .as_deref()
                    .filter(|_| slot == 0)?;
                (counts, row0, rows, self.settings.width)
            }
            WorkUnit::Preview { row0, rows } => {
                let p = self.preview.as_ref()?;
                (p.row_segments.as_deref()?, row0, rows, p.targets.width)
            }
            WorkUnit::Repaint { segments, .. } if !self.stale.single_kept => {
                return Some((segments as u64, 0));
            }
            WorkUnit::RepaintGather { rows, .. } => {
                return Some((0, rows as u64 * self.settings.width as u64));
            }
            _ => return None,
        };
        if !self.by_segment {
            return None;
        }
        let end = (row0 + rows).min(counts.len() as u32) as usize;
        let start = (row0 as usize).min(end);
        let segments = counts[start..end].iter().map(|&n| n as u64).sum();
        Some((segments, (end - start) as u64 * width as u64))
    }

    /// Rows of a preview band from `row` (of `height`).
    pub(super) fn preview_rows(&mut self, row: u32, height: u32) -> u32 {
        // Before the preview is measured: the frame's cost of a row under every light batch, scaled
        // to the preview's width (per fragment), or as it is (by segment: `seed_from_preview`).
        let factor = self.preview.as_ref().map_or(1, |p| p.factor) as f64;
        let by_segment = self.by_segment;
        let light_batches = self.first_pass_batches().max(1) as f64;
        let width = self.settings.width as f64 / factor;
        let r = &mut self.refinement;
        let lights = self.scene.light_count as f64;
        let guess = r.costs.bands[0].cost.map_or(
            GUESS_SHADE_ROW_S * light_batches * width / GUESS_ROW_PIXELS,
            |c| {
                if by_segment {
                    c * lights
                } else {
                    c * lights / factor
                }
            },
        );
        // The preview in one unit where its divisor fits it to its target (one UI frame sooner per
        // unit saved), even past a shorter unit budget.
        let budget = preview_target(r.costs.budget).as_secs_f64();
        let counts = self
            .preview
            .as_ref()
            .and_then(|p| p.row_segments.as_deref());
        let rows = match counts.filter(|_| by_segment) {
            // Counted, the bands keep to the unit budget (a UI frame waits behind a unit).
            Some(c) => {
                let size = (row, height, width.ceil() as u32);
                let shape = BandShape {
                    lights: lights as u32,
                    gathers: true,
                };
                r.costs
                    .segment_band_rows(c, size, &[shape], r.costs.budget.as_secs_f64())
            }
            None => r.costs.preview_bands.rows(row, height, budget, guess, &[]),
        };
        r.costs.preview_bands.last = rows;
        rows
    }
}
