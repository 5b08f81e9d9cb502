//! Progressive refinement, the editor's frame loop: a frame's work cut into units, at most one in
//! flight, each submitted on its own by [`Renderer::refine`]; shadow-grid ranges and shading row bands
//! are sized from the measured cost of the units before them (row bands from each row's own cost in
//! earlier batches) to a time budget, so egui, which shares the queue, does not wait behind a long
//! submission (the volume and visibility units are whole passes, not sized; a unit of one row or one
//! sweep can still pass the budget). The units: the fiber-density volume (when geometry or absorption
//! changed), the shadow grid in ranges of sweeps (eight entries per light, one per direction; when the
//! volume, the lights or the forward table changed), visibility, then every shading batch (a light
//! batch at one visibility sample) in bands of rows, each band followed by a resolve of its rows so the
//! image fills in; the grid's entries for a light batch are built just before the first shading batch
//! that reads them, so the image appears after one light batch's grid, not the whole grid. Every pixel
//! takes its batches in `render_frame`'s order, so the converged image is `render_frame`'s bit for bit.
//! A change (parameters, camera, lights, absorption) restarts the plan; a camera move keeps what the
//! shadow grid has built.

use super::renderer::{RenderError, Renderer};
use super::shading::{ShadeBatch, ShadingPass};
use super::shadow_grid::SWEEP_SLOTS;
use crate::gpu::GpuContext;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The default longest submission (the bound on lavapipe is 50 ms; the budget leaves room for
/// the estimate's error).
pub const DEFAULT_UNIT_BUDGET: Duration = Duration::from_millis(30);

/// First guesses, before a unit of the kind has been measured: conservative (lavapipe on two cores
/// sweeps a light of a 48-point grid in about 60 ms, 8 entries, and shades about 15 ms per row of a 16-light batch at
/// 720 pixels).
const GUESS_GRID_ENTRY_S: f64 = 10e-3;
const GUESS_SHADE_ROW_S: f64 = 40e-3;

/// One bounded piece of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorkUnit {
    /// Fiber density and its pyramid.
    Volume,
    /// Shadow-grid entries [first, first + count) (`SWEEP_SLOTS` per light: its sweeps).
    ShadowGrid { first: u32, count: u32 },
    /// The visibility pass; the components are cleared.
    Visibility,
    /// Frame batch `batch` (its lights at its visibility sample) over rows [row0, row0 + rows).
    Shade { batch: u32, row0: u32, rows: u32 },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Volume,
    ShadowGrid,
    Visibility,
    Shade { batch: u32, row: u32 },
    Converged,
}

struct InFlight {
    unit: WorkUnit,
    submitted: Instant,
    done: Arc<Mutex<Option<Instant>>>,
}

/// What refinement has measured since its last restart.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RefineStats {
    /// Units submitted.
    pub units: u32,
    /// The longest unit, submission to completion (as seen by the polling that noticed it), and which.
    pub longest: Duration,
    pub longest_unit: Option<WorkUnit>,
    /// Time spent per pass since the restart, submission to completion of its units (wall clock as
    /// the polling saw it: an upper bound of GPU time), in [`UNIT_PASSES`] order.
    pub pass_time: [Duration; 4],
}

/// The passes the units belong to, in [`RefineStats::pass_time`] order.
pub const UNIT_PASSES: [&str; 4] = ["volume", "shadow grid", "visibility", "shading"];

/// Where progressive refinement stands (owned by the [`Renderer`]).
pub struct Refinement {
    stage: Stage,
    /// Shadow-grid entries built for the current volume, lights and tables.
    pub(super) grid_done: u32,
    /// Rows of shading batches submitted since the restart.
    rows_done: u64,
    budget: Duration,
    /// Seconds per shadow-grid entry and per row of one shading batch (None: not measured yet).
    grid_cost: Option<f64>,
    shade_cost: Option<f64>,
    /// Measured seconds per row of one shading batch, per image row (0: not measured yet). A row
    /// costs about the same in every batch (the same pixels under as many lights), so a band is sized
    /// from its own rows' costs, not from the mean of the (often empty) rows above it.
    row_cost: Vec<f64>,
    /// Items of the last grid and shading units.
    grid_last: u32,
    shade_last: u32,
    in_flight: Option<InFlight>,
    stats: RefineStats,
}

impl Default for Refinement {
    fn default() -> Self {
        Self {
            stage: Stage::Visibility,
            grid_done: 0,
            rows_done: 0,
            budget: DEFAULT_UNIT_BUDGET,
            grid_cost: None,
            shade_cost: None,
            row_cost: Vec::new(),
            grid_last: 1,
            shade_last: 1,
            in_flight: None,
            stats: RefineStats::default(),
        }
    }
}

impl Refinement {
    /// `render_frame` did the whole frame.
    pub(super) fn complete_frame(&mut self) {
        self.stage = Stage::Converged;
    }

    /// Items a unit may hold: the budget over the measured (or guessed) cost per item, at most twice
    /// the previous unit of the kind (`last`: costs are uneven, empty rows and empty sweep slots cost
    /// almost nothing, so one cheap unit must not size a huge next one); at least one, at most what
    /// remains.
    fn items(&self, per_item: Option<f64>, guess: f64, last: u32, remaining: u32) -> u32 {
        let per_item = per_item.unwrap_or(guess).max(1e-12);
        let n = (self.budget.as_secs_f64() / per_item)
            .floor()
            .min(2.0 * last.max(1) as f64);
        (n.min(remaining as f64) as u32)
            .max(1)
            .min(remaining.max(1))
    }

    /// Rows of a shading band from `row` (of `height`): as many as the budget holds by the rows' own
    /// measured costs (the mean row's where not measured yet, then at most twice the last band); at
    /// least one.
    fn shade_rows(&self, row: u32, height: u32) -> u32 {
        let fallback = self.shade_cost.unwrap_or(GUESS_SHADE_ROW_S).max(1e-12);
        let budget = self.budget.as_secs_f64();
        let (mut t, mut n, mut unknown) = (0.0, 0u32, false);
        for r in row..height {
            let c = self.row_cost.get(r as usize).copied().unwrap_or(0.0);
            unknown |= c <= 0.0;
            let c = if c > 0.0 { c } else { fallback };
            if n > 0 && t + c > budget {
                break;
            }
            t += c;
            n += 1;
        }
        if unknown {
            n = n.min(2 * self.shade_last.max(1));
        }
        n.max(1)
    }

    /// The image width changed by `ratio`: a row costs about that much more (or less), and the next
    /// band starts small.
    pub(super) fn resized(&mut self, ratio: f64) {
        if let Some(c) = &mut self.shade_cost {
            *c *= ratio.max(1e-6);
        }
        self.row_cost.clear();
        self.shade_last = 1;
    }

    /// Folds a finished unit's time into the cost per item (mean of the last estimate and the
    /// measurement, so one slow unit does not halve the next ones).
    fn measured(&mut self, unit: WorkUnit, elapsed: Duration) {
        if elapsed > self.stats.longest {
            self.stats.longest = elapsed;
            self.stats.longest_unit = Some(unit);
        }
        let pass = match unit {
            WorkUnit::Volume => 0,
            WorkUnit::ShadowGrid { .. } => 1,
            WorkUnit::Visibility => 2,
            WorkUnit::Shade { .. } => 3,
        };
        self.stats.pass_time[pass] += elapsed;
        let per = |n: u32| elapsed.as_secs_f64() / n.max(1) as f64;
        let blend = |old: Option<f64>, new: f64| Some(old.map_or(new, |o| 0.5 * (o + new)));
        match unit {
            WorkUnit::ShadowGrid { count, .. } => {
                self.grid_cost = blend(self.grid_cost, per(count))
            }
            WorkUnit::Shade { row0, rows, .. } => {
                self.shade_cost = blend(self.shade_cost, per(rows));
                let end = (row0 + rows) as usize;
                if self.row_cost.len() < end {
                    self.row_cost.resize(end, 0.0);
                }
                self.row_cost[row0 as usize..end].fill(per(rows));
            }
            WorkUnit::Volume | WorkUnit::Visibility => {}
        }
    }
}

/// What [`Renderer::refine`] reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// The unit submitted by this call (None: busy or converged).
    pub submitted: Option<WorkUnit>,
    /// A unit is still running: nothing was submitted.
    pub busy: bool,
    /// Every unit of the frame has finished: the image is `render_frame`'s.
    pub converged: bool,
    /// Estimated fraction of the frame's work done (by the measured costs).
    pub fraction: f32,
    pub stats: RefineStats,
}

impl Renderer {
    /// The longest time one unit should take (default [`DEFAULT_UNIT_BUDGET`]).
    pub fn set_unit_budget(&mut self, budget: Duration) {
        self.refinement.budget = budget.max(Duration::from_micros(100));
    }

    /// Whether frames read the shadow grid at all.
    fn grid_used(&self) -> bool {
        self.settings.shadows && self.light_count > 0
    }

    /// Whether the refinement will rebuild (some of) the shadow grid before it shades: the volume or
    /// the grid is stale.
    pub fn shadow_grid_stale(&self) -> bool {
        self.grid_used() && (self.volume_dirty || self.shadow_grid_dirty)
    }

    /// Whether the grid frames read is stale.
    fn grid_needed(&self) -> bool {
        self.grid_used() && self.shadow_grid_dirty
    }

    /// Starts the frame's plan again from the first stage that a change made stale.
    pub(super) fn restart_refinement(&mut self) {
        let grid_needed = self.grid_needed();
        let r = &mut self.refinement;
        r.rows_done = 0;
        r.stats = RefineStats::default();
        r.stage = if self.volume_dirty {
            Stage::Volume
        } else if grid_needed {
            Stage::ShadowGrid
        } else {
            Stage::Visibility
        };
    }

    /// Does the next bounded piece of the frame: returns at once if the previous piece is still
    /// running (the caller draws the last resolved image), otherwise submits one unit sized to the
    /// budget. Call it every UI frame; it never waits for the GPU.
    pub fn refine(&mut self, ctx: &GpuContext) -> Result<Progress, RenderError> {
        ctx.device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| RenderError::Gpu(format!("polling: {e}")))?;
        if let Some(f) = &self.refinement.in_flight {
            let done = *f
                .done
                .lock()
                .map_err(|_| RenderError::Gpu("poisoned".into()))?;
            match done {
                None => return Ok(self.progress(None, true)),
                Some(t) => {
                    let (unit, elapsed) = (f.unit, t.saturating_duration_since(f.submitted));
                    self.refinement.in_flight = None;
                    self.refinement.measured(unit, elapsed);
                }
            }
        }
        self.last_ran.clear(); // pass_times belongs to render_frame
        let Some(unit) = self.next_unit() else {
            return Ok(self.progress(None, false));
        };
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("refinement unit"),
            });
        self.encode_unit(ctx, &mut enc, unit);
        ctx.queue.submit([enc.finish()]);
        let done = Arc::new(Mutex::new(None));
        let flag = done.clone();
        ctx.queue.on_submitted_work_done(move || {
            if let Ok(mut d) = flag.lock() {
                *d = Some(Instant::now());
            }
        });
        self.refinement.in_flight = Some(InFlight {
            unit,
            submitted: Instant::now(),
            done,
        });
        self.refinement.stats.units += 1;
        Ok(self.progress(Some(unit), false))
    }

    /// Refines until converged, waiting for each unit (tests, benchmarks and the CLI).
    pub fn refine_to_convergence(&mut self, ctx: &GpuContext) -> Result<RefineStats, RenderError> {
        loop {
            let p = self.refine(ctx)?;
            if p.converged {
                return Ok(p.stats);
            }
            if p.submitted.is_some() || p.busy {
                ctx.device
                    .poll(wgpu::PollType::wait_indefinitely())
                    .map_err(|e| RenderError::Gpu(format!("waiting for the GPU: {e}")))?;
            }
        }
    }

    fn progress(&self, submitted: Option<WorkUnit>, busy: bool) -> Progress {
        let r = &self.refinement;
        let grid_cost = r.grid_cost.unwrap_or(GUESS_GRID_ENTRY_S);
        let shade_cost = r.shade_cost.unwrap_or(GUESS_SHADE_ROW_S);
        let entries = self.shadow_grid.entry_count() as f64;
        let grid_total = if self.grid_used() {
            entries * grid_cost
        } else {
            0.0
        };
        let grid_done = if self.grid_needed() {
            r.grid_done as f64 * grid_cost
        } else {
            grid_total
        };
        let rows_total =
            self.shading_pass.frame_batches().count() as f64 * self.settings.height as f64;
        let shade_total = rows_total * shade_cost;
        let shade_done = r.rows_done as f64 * shade_cost;
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
            fraction,
            stats: r.stats,
        }
    }

    /// Shadow-grid entries that shading batch `batch` reads: the lights' up to the batch's last.
    fn grid_entries_for(&self, batch: u32) -> u32 {
        let total = self.shadow_grid.entry_count();
        match self.shading_pass.frame_batches().nth(batch as usize) {
            Some(b) => ((b.first + b.count) * SWEEP_SLOTS).min(total),
            None => total,
        }
    }

    /// A shadow-grid unit towards `target` entries, or None when they are built.
    fn grid_unit(&mut self, target: u32) -> Option<WorkUnit> {
        let r = &mut self.refinement;
        if r.grid_done >= target {
            return None;
        }
        let count = r.items(
            r.grid_cost,
            GUESS_GRID_ENTRY_S,
            r.grid_last,
            target - r.grid_done,
        );
        r.grid_last = count;
        let first = r.grid_done;
        r.grid_done += count;
        Some(WorkUnit::ShadowGrid { first, count })
    }

    /// The next unit of the plan (sized to the budget); advances the plan past it. The shadow grid is
    /// built light batch by light batch, each just before the first shading batch that reads it: the
    /// first light batch's part before the visibility pass clears the image (the last image stays on
    /// screen meanwhile), the others between shading batches, so the image fills in light batch by
    /// light batch instead of after the whole grid.
    fn next_unit(&mut self) -> Option<WorkUnit> {
        let height = self.settings.height;
        let batches = self.shading_pass.frame_batches().count() as u32;
        let grid_needed = self.grid_needed();
        match self.refinement.stage {
            Stage::Volume => {
                self.refinement.stage = Stage::ShadowGrid;
                Some(WorkUnit::Volume)
            }
            Stage::ShadowGrid => {
                if grid_needed && let Some(unit) = self.grid_unit(self.grid_entries_for(0)) {
                    return Some(unit);
                }
                self.refinement.stage = Stage::Visibility;
                self.next_unit()
            }
            Stage::Visibility => {
                self.refinement.stage = if batches == 0 {
                    Stage::Converged
                } else {
                    Stage::Shade { batch: 0, row: 0 }
                };
                Some(WorkUnit::Visibility)
            }
            Stage::Shade { batch, row } => {
                if grid_needed
                    && row == 0
                    && let Some(unit) = self.grid_unit(self.grid_entries_for(batch))
                {
                    return Some(unit);
                }
                let r = &mut self.refinement;
                let mut rows = r.shade_rows(row, height);
                // Whole workgroups (8 rows) where the budget allows.
                if rows >= 8 && rows < height - row {
                    rows -= rows % 8;
                }
                r.rows_done += rows as u64;
                r.shade_last = rows;
                r.stage = if row + rows < height {
                    Stage::Shade {
                        batch,
                        row: row + rows,
                    }
                } else if batch + 1 < batches {
                    Stage::Shade {
                        batch: batch + 1,
                        row: 0,
                    }
                } else {
                    Stage::Converged
                };
                Some(WorkUnit::Shade {
                    batch,
                    row0: row,
                    rows,
                })
            }
            Stage::Converged => None,
        }
    }

    fn encode_unit(&mut self, ctx: &GpuContext, enc: &mut wgpu::CommandEncoder, unit: WorkUnit) {
        let device = &ctx.device;
        match unit {
            WorkUnit::Volume => {
                self.density_pass
                    .encode(device, enc, &self.hair, &self.volume, None);
                self.pyramid_pass
                    .encode(device, enc, &self.volume, &self.pyramid, None);
                self.volume_dirty = false;
                self.shadow_grid_dirty = true;
                self.refinement.grid_done = 0;
            }
            WorkUnit::ShadowGrid { first, count } => {
                let inputs = self.shadow_grid_inputs();
                self.shadow_grid_pass.encode(
                    device,
                    enc,
                    &inputs,
                    &self.shadow_grid,
                    first,
                    count,
                    None,
                );
                if first + count >= self.shadow_grid.entry_count() {
                    self.shadow_grid_dirty = false;
                }
            }
            WorkUnit::Visibility => {
                self.visibility_pass.encode(
                    device,
                    enc,
                    &self.camera,
                    &self.hair,
                    &self.targets,
                    None,
                );
                ShadingPass::clear(enc, &self.targets);
                self.encode_resolve(device, enc, 0..self.settings.height);
            }
            WorkUnit::Shade { batch, row0, rows } => {
                let Some(b) = self.shading_pass.frame_batches().nth(batch as usize) else {
                    return;
                };
                let b = ShadeBatch { row0, rows, ..*b };
                let inputs = self.shading_inputs();
                self.shading_pass
                    .encode_batch(device, enc, &inputs, &self.targets, &b, None);
                self.encode_resolve(device, enc, row0..row0 + rows);
            }
        }
    }

    fn encode_resolve(
        &self,
        device: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        rows: std::ops::Range<u32>,
    ) {
        self.resolve_pass.encode(
            device,
            enc,
            &self.camera,
            &self.resolve_info,
            &self.targets,
            rows,
            None,
        );
    }
}
