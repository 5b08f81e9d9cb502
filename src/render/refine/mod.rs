//! Progressive refinement, the editor's frame loop: a frame's work cut into units, at most one in
//! flight, each submitted on its own by [`Renderer::refine`]; shadow-grid ranges and shading row bands
//! are sized from the measured cost of the units before them (row bands from each row's own cost in
//! earlier batches) to a time budget, so egui, which shares the queue, does not wait behind a long
//! submission (the volume's resolve is a whole pass, not sized; a unit of one row or one sweep can
//! still pass the budget).
//!
//! The plan after a change: first, when the renderer has one ([`Renderer::set_preview`]), a preview of
//! the change (reduced resolution, all lights, the shadow grid as it stands:
//! [`crate::render::refine::preview`]); then the fiber-density volume (when geometry or absorption changed: its
//! deposit in ranges of segments, whose fixed-point sums add up exactly, then its resolve), the
//! shadow grid in ranges of sweeps (`SWEEP_SLOTS` entries per light, one per direction; when the volume, the
//! lights or the forward table changed), visibility in ranges of segments (the K-buffer's atomic
//! insertion does not depend on their order; the last part composites it), then every shading batch
//! in bands of rows: shading segments, a light batch over the segments of the band's pixels it has
//! not shaded yet, every light batch on a band before the next band, the band's rows gathered and
//! resolved after its last (final then); shading fragments, a light batch at one K-buffer slot, every
//! light batch at the front slot before any at the second, each band followed by a resolve of its
//! rows. The grid's entries for a light batch are built
//! just before the first shading batch that reads them. [`Progress::ready`] says when a finished unit
//! left an image worth showing: the complete preview, then the full image once every light has shaded
//! the front K-buffer slot (the "first pass"; shading segments, every slot: the converged image),
//! updated unit by unit until converged. Every pixel
//! takes its batches in `render_frame`'s order, so the converged image is `render_frame`'s bit for
//! bit. A change (parameters, camera, lights, absorption) restarts the plan; a camera move keeps what
//! the shadow grid has built.

pub mod costs;
pub mod encode;
pub mod plan;
pub mod preview;
pub mod repaint;

use crate::gpu::GpuContext;
use crate::render::passes::targets::FrameTargets;
use crate::render::renderer::{RenderError, Renderer};
use costs::*;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The default longest submission (units should stay under 50 ms, what a UI sharing the queue waits
/// behind at most; the budget leaves room for the estimate's error).
pub const DEFAULT_UNIT_BUDGET: Duration = Duration::from_millis(30);

/// One bounded piece of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorkUnit {
    /// The fiber-density deposit of segments [first, first + count) (the first part clears the sums).
    Volume { first: u32, count: u32 },
    /// The fiber density's resolve of voxels [first, first + count), after every segment was
    /// deposited (the whole volume took 90-100 ms on S1 on lavapipe).
    VolumeResolve { first: u32, count: u32 },
    /// The resolved density's pyramid.
    DensityPyramid,
    /// The shadow-grid sweeps' samples [first, first + count) (`MidplaneSamples`), after a new
    /// pyramid and before the grid's entries.
    GridSamples { first: u32, count: u32 },
    /// Shadow-grid entries [first, first + count) (`SWEEP_SLOTS` per light: its sweeps).
    ShadowGrid { first: u32, count: u32 },
    /// The visibility pass over segments [first, first + count) (the first part clears the targets;
    /// count 0 when the camera, size and fibres are those it last drew); the last part clears the
    /// components.
    Visibility { first: u32, count: u32 },
    /// After the visibility pass: rows [row0, row0 + rows) of the image resolved before any light
    /// shaded them (the background and the head's coverage; the whole image took 50-60 ms on S1 on
    /// lavapipe).
    Backdrop { row0: u32, rows: u32 },
    /// Frame batch `batch` (its lights, at its K-buffer slot when shading fragments) over rows
    /// [row0, row0 + rows).
    Shade { batch: u32, row0: u32, rows: u32 },
    /// The preview's visibility pass over segments [first, first + count) (after a camera move; a
    /// parameter change reuses the last).
    PreviewVisibility { first: u32, count: u32 },
    /// Preview rows [row0, row0 + rows) under every light (the first unit clears the preview).
    Preview { row0: u32, rows: u32 },
    /// A brush dab's repaint ([`Renderer::repaint_points`]): frame batch `batch`'s lights over
    /// `segments` of the segments at the changed points (with the multiple scattering of the
    /// partners whose pair the dab joined or split), from the `first`-th (in parts sized to the
    /// budget: a 1-3k-segment stroke took 100-370 ms a batch on S1 on lavapipe in one part).
    Repaint {
        batch: u32,
        first: u32,
        segments: u32,
    },
    /// After a repaint's last batch: rows [row0, row0 + rows) of those its segments and the
    /// partners it shaded cover gathered from the segments and resolved (in bands sized to the
    /// budget: the rows of a dab's segments took 30-60 ms on S1 on lavapipe, which pushed the last
    /// part that carried them to 60-95 ms).
    RepaintGather { row0: u32, rows: u32 },
}

/// The images a display pass reads: the frame's, and a preview under the frame's first `sharp_rows`
/// rows ([`Renderer::image`]).
#[derive(Clone, Copy)]
pub struct DisplayImage<'a> {
    pub full: &'a FrameTargets,
    pub preview: Option<(&'a FrameTargets, u32)>,
}

/// Which image a finished unit left worth showing ([`Renderer::image`] gives its targets).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageReady {
    /// The preview of the latest change is complete.
    Preview,
    /// The full-resolution image: every light has shaded the front K-buffer slot (or more; shading
    /// segments, every slot: converged).
    Full,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// The preview's visibility from segment `first`.
    PreviewVisibility {
        first: u32,
    },
    /// After convergence, the preview's visibility at a divisor adapted since it was drawn, from
    /// segment `first` (then converged again): the next change's preview only shades.
    PreparePreview {
        first: u32,
    },
    Preview {
        row: u32,
    },
    /// The deposit from segment `first` (then the resolve).
    Volume {
        first: u32,
    },
    /// The density's resolve from voxel `first`.
    Resolve {
        first: u32,
    },
    /// The resolved density's pyramid.
    Pyramid,
    ShadowGrid,
    /// The frame's visibility from segment `first`.
    Visibility {
        first: u32,
    },
    /// The image's resolve before shading, from `row`.
    Backdrop {
        row: u32,
    },
    /// Frame batch `batch` from `row`; `band`: the rows of the band the first pass shades under
    /// every light batch (0: size a new band).
    Shade {
        batch: u32,
        row: u32,
        band: u32,
    },
    /// A dab's segments from the `first`-th under frame batch `batch` (then its next part, the
    /// next batch, or converged).
    Repaint {
        batch: u32,
        first: u32,
    },
    /// The repaint's rows from `row` gathered and resolved (then converged).
    RepaintGather {
        row: u32,
    },
    Converged,
}

struct InFlight {
    unit: WorkUnit,
    submitted: Instant,
    done: Arc<Mutex<Option<Instant>>>,
    /// The restart it was planned under ([`Refinement::restarts`]).
    restart: u64,
    /// A repaint's gather that ends its rows.
    repaint_end: bool,
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
    pub pass_time: [Duration; 5],
    /// From the restart to the completion of the preview, and the first pass of the full image.
    pub preview: Option<Duration>,
    pub first_pass: Option<Duration>,
    /// From the restart to the converged image: before [`Progress::converged`] where the plan then
    /// draws the next preview's visibility at a divisor adapted since.
    pub image_converged: Option<Duration>,
}

/// The passes the units belong to, in [`RefineStats::pass_time`] order.
pub const UNIT_PASSES: [&str; 5] = ["preview", "volume", "shadow grid", "visibility", "shading"];

impl Stage {
    /// The image is converged (the plan may still draw the preview's visibility for the next
    /// change).
    fn image_converged(self) -> bool {
        matches!(self, Stage::Converged | Stage::PreparePreview { .. })
    }
}

/// Where progressive refinement stands (owned by the [`Renderer`]): the stage of the plan, the unit
/// in flight, what the units cost ([`CostModel`]), the shadow grid's progress and the preview's.
pub struct Refinement {
    stage: Stage,
    /// When the last unit finished, until the next is submitted; and the gaps between a unit's
    /// completion and the next submission (what a driver of the refinement leaves idle).
    last_done: Option<Instant>,
    idle_gaps: Vec<Duration>,
    /// Estimated seconds of the shading units submitted since the restart (for the progress).
    shade_done: f64,
    in_flight: Option<InFlight>,
    stats: RefineStats,
    /// When the plan was last restarted, and how many times (a finished unit planned before the
    /// latest restart still shows its image, but does not show the latest change).
    started: Instant,
    pub(in crate::render) restarts: u64,
    /// Rows of the full image that the first pass has finished under every light since the restart.
    sharp_rows: u32,
    pub(in crate::render) costs: CostModel,
    pub(in crate::render) grid: GridProgress,
    pub(in crate::render) preview_state: PreviewState,
}

/// How far the shadow grid is built for the current volume, lights and tables.
#[derive(Default)]
pub(in crate::render) struct GridProgress {
    /// Shadow-grid entries built.
    pub(in crate::render) done: u32,
    /// The sweeps' samples built for the current pyramid (`MidplaneSamples`; a new light count or
    /// multiple-scattering toggle keeps them, `GpuShadowGrid::with_lights`).
    pub(in crate::render) samples_done: u32,
    /// Light groups whose grid entries are part-way through a rebuild (a light's sweeps add into its
    /// entries, finished by the last: such an entry is neither the old value nor the new one, and the
    /// preview shades those lights unshadowed).
    pub(in crate::render) partial: Vec<bool>,
}

impl GridProgress {
    /// A new grid buffer (zeros, not a light's values): every group counts as unbuilt until swept,
    /// so the preview shades them unshadowed.
    pub(in crate::render) fn unbuilt(&mut self, group_entries: u32, total: u32) {
        self.partial = vec![true; total.div_ceil(group_entries.max(1)) as usize];
    }

    /// The whole grid was built in one go (`render_frame`, the benchmark's timing).
    pub(in crate::render) fn complete(&mut self, total: u32) {
        self.partial.clear();
        self.done = total;
    }

    /// Records a grid unit over entries [first, first + count) of `total`, in groups of
    /// `group_entries` (the last may be shorter): a group it leaves part-way is partial, one it
    /// completes is not.
    fn built(&mut self, first: u32, count: u32, group_entries: u32, total: u32) {
        let g = group_entries.max(1);
        let groups = total.div_ceil(g);
        self.partial.resize(groups as usize, false);
        let end = first + count;
        for group in first / g..end.div_ceil(g).min(groups) {
            let group_end = ((group + 1) * g).min(total);
            self.partial[group as usize] = end < group_end;
        }
    }
}

/// What the plan owes and has done of the preview of the latest change.
#[derive(Default)]
pub(in crate::render) struct PreviewState {
    /// A change since the last image shown (preview or full): the plan starts with a preview.
    pub(in crate::render) owed: bool,
    /// The preview's resolution divisor when chosen automatically (adapted to its measured time).
    pub(in crate::render) auto_factor: Option<u32>,
    /// An adapted divisor that waits for the preview's next visibility pass (a camera move).
    pub(in crate::render) deferred_factor: Option<u32>,
    /// A preview unit was submitted since the restart, whether it drew a new view, and the time its
    /// shading units took.
    started: bool,
    new_view: bool,
    shading: Duration,
}

impl Default for Refinement {
    fn default() -> Self {
        Self {
            stage: Stage::Visibility { first: 0 },
            last_done: None,
            idle_gaps: Vec::new(),
            shade_done: 0.0,
            in_flight: None,
            stats: RefineStats::default(),
            started: Instant::now(),
            restarts: 0,
            sharp_rows: 0,
            costs: CostModel::default(),
            grid: GridProgress::default(),
            preview_state: PreviewState::default(),
        }
    }
}

impl Refinement {
    /// A new plan's state for the context's device.
    pub(in crate::render) fn for_device(ctx: &GpuContext) -> Self {
        Self {
            costs: CostModel::for_device(ctx),
            ..Self::default()
        }
    }

    /// `render_frame` did the whole frame.
    pub(in crate::render) fn complete_frame(&mut self) {
        self.stage = Stage::Converged;
        self.preview_state.owed = false;
    }

    /// Folds a finished unit's time into the statistics and the cost model ([`CostModel::measured`]).
    fn measured(
        &mut self,
        unit: WorkUnit,
        elapsed: Duration,
        batch: Option<(u32, u32)>,
        listed: (Option<(u64, u64)>, bool),
    ) {
        if elapsed > self.stats.longest {
            self.stats.longest = elapsed;
            self.stats.longest_unit = Some(unit);
        }
        let pass = match unit {
            WorkUnit::Preview { .. } | WorkUnit::PreviewVisibility { .. } => 0,
            WorkUnit::Volume { .. } | WorkUnit::VolumeResolve { .. } | WorkUnit::DensityPyramid => {
                1
            }
            WorkUnit::GridSamples { .. } | WorkUnit::ShadowGrid { .. } => 2,
            WorkUnit::Visibility { .. } | WorkUnit::Backdrop { .. } => 3,
            WorkUnit::Shade { .. } | WorkUnit::Repaint { .. } | WorkUnit::RepaintGather { .. } => 4,
        };
        self.stats.pass_time[pass] += elapsed;
        if let WorkUnit::Preview { .. } = unit {
            self.preview_state.shading += elapsed;
        }
        self.costs.measured(unit, elapsed, batch, listed);
    }
}

/// Idle gaps kept until [`Renderer::take_idle_gaps`] (a frame has a few hundred units).
pub const MAX_IDLE_GAPS: usize = 4096;

/// What [`Renderer::refine`] reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// The unit submitted by this call (None: busy or converged).
    pub submitted: Option<WorkUnit>,
    /// A unit is still running: nothing was submitted.
    pub busy: bool,
    /// Every unit of the frame has finished: the image is `render_frame`'s.
    pub converged: bool,
    /// The unit whose completion this call noticed left this image worth showing (the preview, or
    /// the full image from its first pass on); None when it noticed none.
    pub ready: Option<ImageReady>,
    /// Estimated fraction of the frame's work done (by the measured costs).
    pub fraction: f32,
    pub stats: RefineStats,
}

impl Renderer {
    /// The longest time one unit should take (default [`DEFAULT_UNIT_BUDGET`]).
    pub fn set_unit_budget(&mut self, budget: Duration) {
        self.refinement.costs.budget = budget.max(Duration::from_micros(100));
    }

    /// Sizes units to `share` (0.1 to 1) of the budget, all but the preview's shading bands (which
    /// keep all of it, as the preview's target does): for a software GPU while a CPU job (the
    /// tables' build) takes part of its cores, which stretches units past their measured costs
    /// ([`crate::live::settings::budget_share`]).
    pub fn set_budget_share(&mut self, share: f64) {
        self.refinement.costs.budget_share = share.clamp(0.1, 1.0);
    }

    /// Whether the refinement will rebuild (some of) the shadow grid before it shades: the volume or
    /// the grid is stale.
    pub fn shadow_grid_stale(&self) -> bool {
        self.grid_used() && (self.stale.volume_dirty || self.stale.shadow_grid_dirty)
    }

    /// A change the image on screen does not show yet: the frame's plan starts again from the first
    /// stage the change made stale, with a preview first.
    pub(in crate::render) fn restart_refinement(&mut self) {
        self.refinement.preview_state.owed = true;
        self.stale.single_kept = false;
        self.replan();
    }

    /// [`Renderer::restart_as_refinement`] for a change that reaches only the forward and
    /// dual-scattering terms (the grid's forward terms, the shading's dual terms): when the image is
    /// converged and shaded by segment, the segments keep their single scattering and the plan shades
    /// multiple scattering alone ([`Renderer::keeps_single_scattering`]).
    pub(in crate::render) fn refine_multiple_only(&mut self, change: impl FnOnce(&mut Self)) {
        // Converged, or kept already (a plan shading multiple scattering alone, its single
        // scattering untouched); not in the middle of a repaint (its segments part-way).
        let keep = match self.refinement.stage {
            Stage::Converged | Stage::PreparePreview { .. } => {
                self.by_segment
                    && self.settings.multiple_scattering
                    && !self.refinement.preview_state.owed
                    && self.repaint.pending.is_empty()
            }
            Stage::Repaint { .. } | Stage::RepaintGather { .. } => false,
            _ => self.stale.single_kept,
        };
        self.restart_as_refinement(change);
        self.stale.single_kept = keep;
    }

    /// Runs `change` (which restarts the plan) as a refinement of the change already on screen:
    /// no new preview is owed for it (new tables, a deferred volume rebuild).
    pub(in crate::render) fn restart_as_refinement(&mut self, change: impl FnOnce(&mut Self)) {
        let owed = self.refinement.preview_state.owed;
        change(self);
        self.refinement.preview_state.owed = owed;
        self.replan();
    }

    /// Notices whether the unit in flight has finished (without waiting): folds its time into the
    /// costs and says which image it left worth showing. [`Renderer::refine`] calls it first; the
    /// editor calls it before, to draw that image before the next unit is queued behind it.
    pub fn poll_refinement(&mut self, ctx: &GpuContext) -> Result<Option<ImageReady>, RenderError> {
        ctx.device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| RenderError::Gpu(format!("polling: {e}")))?;
        self.receive_row_segments();
        let Some(f) = &self.refinement.in_flight else {
            return Ok(None);
        };
        let done = *f
            .done
            .lock()
            .map_err(|_| RenderError::Gpu("poisoned".into()))?;
        let Some(t) = done else {
            return Ok(None);
        };
        let (unit, elapsed, restart, repaint_end) = (
            f.unit,
            t.saturating_duration_since(f.submitted),
            f.restart,
            f.repaint_end,
        );
        self.refinement.in_flight = None;
        self.refinement.last_done = Some(t);
        let batch = match unit {
            WorkUnit::Shade { batch, .. } | WorkUnit::Repaint { batch, .. } => {
                self.batch_shape(batch)
            }
            WorkUnit::Preview { .. } => Some((0, self.scene.light_count)),
            _ => None,
        };
        let listed = self.listed_segments(unit);
        let gathers = self.unit_gathers(unit);
        self.refinement
            .measured(unit, elapsed, batch, (listed, gathers));
        let ready = match unit {
            WorkUnit::Preview { row0, rows } => {
                let height = self.preview.as_ref().map_or(0, |p| p.targets.height);
                (row0 + rows >= height).then_some(ImageReady::Preview)
            }
            WorkUnit::Shade { batch, row0, rows } => {
                let first_pass = self.first_pass_batches();
                if batch + 1 == first_pass && restart == self.refinement.restarts {
                    let r = &mut self.refinement;
                    r.sharp_rows = r.sharp_rows.max(row0 + rows);
                }
                let after = batch + 1 > first_pass
                    || (batch + 1 == first_pass && row0 + rows >= self.settings.height);
                after.then_some(ImageReady::Full)
            }
            WorkUnit::RepaintGather { .. } => repaint_end.then_some(ImageReady::Full),
            _ => None,
        };
        let r = &mut self.refinement;
        // One time for what this unit completed (the first pass and the convergence may be one).
        let since = r.started.elapsed();
        if restart == r.restarts
            && r.stage.image_converged()
            && !matches!(unit, WorkUnit::PreviewVisibility { .. })
        {
            r.stats.image_converged.get_or_insert(since);
        }
        if ready.is_some() && restart == r.restarts {
            // The image shows the latest change.
            r.preview_state.owed = false;
            match ready {
                Some(ImageReady::Preview) => {
                    r.stats.preview.get_or_insert(since);
                    let shading = r.preview_state.shading;
                    let factor = self.preview.as_ref().map_or(1, |p| p.factor);
                    let by_segment = self.by_segment;
                    let new_view = r.preview_state.new_view;
                    let size = (factor, self.scene.light_count, self.settings.height);
                    r.costs.seed_from_preview(size, by_segment, new_view);
                    self.adapt_preview(shading);
                }
                _ => {
                    r.stats.first_pass.get_or_insert(since);
                }
            }
        }
        Ok(ready)
    }

    /// Does the next bounded piece of the frame: returns at once if the previous piece is still
    /// running (the caller draws the last resolved image), otherwise submits one unit sized to the
    /// budget. Call it every UI frame; it never waits for the GPU.
    pub fn refine(&mut self, ctx: &GpuContext) -> Result<Progress, RenderError> {
        let ready = self.poll_refinement(ctx)?;
        if self.refinement.in_flight.is_some() {
            return Ok(self.progress(None, true, ready));
        }
        self.last_ran.clear(); // pass_times belongs to render_frame
        let Some(unit) = self.next_unit(&ctx.device) else {
            // Nothing to do is not idling.
            self.refinement.last_done = None;
            return Ok(self.progress(None, false, ready));
        };
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("refinement unit"),
            });
        self.encode_unit(ctx, &mut enc, unit);
        ctx.queue.submit([enc.finish()]);
        let r = &mut self.refinement;
        if let Some(done) = r.last_done.take()
            && r.idle_gaps.len() < MAX_IDLE_GAPS
        {
            r.idle_gaps.push(done.elapsed());
        }
        self.request_row_segments();
        let done = Arc::new(Mutex::new(None));
        let flag = done.clone();
        ctx.queue.on_submitted_work_done(move || {
            if let Ok(mut d) = flag.lock() {
                *d = Some(Instant::now());
            }
        });
        self.refinement.preview_state.started |= matches!(
            unit,
            WorkUnit::Preview { .. } | WorkUnit::PreviewVisibility { .. }
        );
        self.refinement.preview_state.new_view |=
            matches!(unit, WorkUnit::PreviewVisibility { .. });
        self.refinement.in_flight = Some(InFlight {
            unit,
            submitted: Instant::now(),
            done,
            restart: self.refinement.restarts,
            repaint_end: matches!(unit, WorkUnit::RepaintGather { row0, rows }
                if row0 + rows >= self.repaint.rows.end),
        });
        self.refinement.stats.units += 1;
        Ok(self.progress(Some(unit), false, ready))
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

    /// The gaps between a unit's completion and the next unit's submission since the last call
    /// (at most [`MAX_IDLE_GAPS`] are kept): how long the driver of the refinement left the GPU
    /// without work while work remained.
    pub fn take_idle_gaps(&mut self) -> Vec<Duration> {
        std::mem::take(&mut self.refinement.idle_gaps)
    }

    /// What refinement has measured since its last restart.
    pub fn refine_stats(&self) -> RefineStats {
        self.refinement.stats
    }

    /// Whether the frame's view depth holds the current camera's visibility: the visibility pass and
    /// the resolve after it (its backdrop units, which write the depth) ran and finished (the brush
    /// picks hair from it).
    pub fn view_depth_ready(&self) -> bool {
        let r = &self.refinement;
        self.stale.visibility_valid
            && !matches!(r.stage, Stage::Backdrop { .. })
            && !r.in_flight.as_ref().is_some_and(|f| {
                matches!(
                    f.unit,
                    WorkUnit::Visibility { .. } | WorkUnit::Backdrop { .. }
                )
            })
    }

    /// Starts reading the frame's view depth back (see [`Renderer::view_depth_ready`]) with the
    /// camera it was drawn with.
    pub fn start_read_view_depth(
        &self,
        ctx: &GpuContext,
    ) -> (
        crate::gpu::context::PendingRead,
        crate::render::camera::CameraUniform,
    ) {
        (
            ctx.start_read(&[&self.view.targets.view_depth]),
            self.view_camera(),
        )
    }

    /// The camera uniform of the whole image as the frame is drawn now.
    pub fn view_camera(&self) -> crate::render::camera::CameraUniform {
        self.view.camera_view.uniform(
            self.settings.width,
            self.settings.height,
            self.settings.min_width_px,
        )
    }

    /// Restarts the refinement with a preview: a change made through a deferred setter that did not
    /// restart (a brush dab: [`Renderer::set_absorption_points_deferred`]) shows.
    pub fn restart(&mut self) {
        self.restart_refinement();
    }

    /// Whether a preview is part-way (its first unit submitted, its last not finished).
    pub fn preview_under_way(&self) -> bool {
        let r = &self.refinement;
        let planned = matches!(
            r.stage,
            Stage::PreviewVisibility { .. } | Stage::Preview { .. }
        );
        // (A preview's visibility drawn after convergence for the next change is not a preview
        // under way: no change is owed a preview then.)
        let in_flight = r.preview_state.owed
            && r.in_flight.as_ref().is_some_and(|f| {
                f.restart == r.restarts
                    && matches!(
                        f.unit,
                        WorkUnit::Preview { .. } | WorkUnit::PreviewVisibility { .. }
                    )
            });
        in_flight || (planned && r.preview_state.started)
    }

    /// What shows `image`: the frame's targets, and for the preview its targets with the rows of the
    /// frame that the first pass has finished since (drawn sharp over it).
    pub fn image(&self, image: ImageReady) -> DisplayImage<'_> {
        let preview = match (image, &self.preview) {
            (ImageReady::Preview, Some(p)) => Some((&p.targets, self.refinement.sharp_rows)),
            _ => None,
        };
        DisplayImage {
            full: &self.view.targets,
            preview,
        }
    }

    /// Rows of the full image the first pass has finished under every light since the restart.
    pub fn sharp_rows(&self) -> u32 {
        self.refinement.sharp_rows
    }
}
