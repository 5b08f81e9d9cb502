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
pub mod preview;
pub mod row_segments;

use crate::gpu::GpuContext;
use costs::*;
use crate::render::passes::segment_shading::last_light_batch;
use crate::render::passes::shading::{FLAG_SEGMENTS, FLAG_SINGLE_KEPT, ShadeBatch, ShadingPass};
use crate::render::passes::shadow_grid::SWEEP_SLOTS;
use crate::render::passes::targets::FrameTargets;
use crate::render::reference::shade::strand_partner;
use crate::render::refine::preview::preview_target;
use crate::render::renderer::{RenderError, Renderer};
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
    /// ([`crate::live::driver::budget_share`]).
    pub fn set_budget_share(&mut self, share: f64) {
        self.refinement.costs.budget_share = share.clamp(0.1, 1.0);
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

    /// A change the image on screen does not show yet: the frame's plan starts again from the first
    /// stage the change made stale, with a preview first.
    pub(in crate::render) fn restart_refinement(&mut self) {
        self.refinement.preview_state.owed = true;
        self.single_kept = false;
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
                    && self.repaint_pending.is_empty()
            }
            Stage::Repaint { .. } | Stage::RepaintGather { .. } => false,
            _ => self.single_kept,
        };
        self.restart_as_refinement(change);
        self.single_kept = keep;
    }

    /// A brush dab on an image converged by segment: the segments that join the changed points
    /// `changed` are shaded again under every light, with the multiple scattering of their partners
    /// whose pair the dab joined or split ([`Renderer::repaint_partner`])
    /// ([`WorkUnit::Repaint`] units, light batch by light batch, each in parts sized to the budget),
    /// and the image is gathered from the segments ([`WorkUnit::RepaintGather`] bands), in place of
    /// a restart. The dab shows at full resolution after work on its segments alone; every other
    /// segment's radiance depends on its own points (and its pair's sharing, whose changes are
    /// shaded here) only and stays.
    /// (The volume and grid follow later: [`Renderer::rebuild_stale_volume`].) False, nothing
    /// planned, when the image is not converged by segment: the caller restarts.
    pub fn repaint_points(&mut self, changed: &[u32]) -> bool {
        let r = &self.refinement;
        let ready = self.by_segment
            && self.segment_targets.is_some()
            && self.visibility_valid
            && !r.preview_state.owed
            && matches!(
                r.stage,
                Stage::Converged
                    | Stage::PreparePreview { .. }
                    | Stage::Repaint { .. }
                    | Stage::RepaintGather { .. }
            )
            && self.shading_pass.frame_batches().next().is_some();
        if !ready {
            return false;
        }
        let mut segments: Vec<u32> = changed
            .iter()
            .flat_map(|&i| self.segments_at_point(i))
            .collect();
        if segments.is_empty() {
            return true;
        }
        // The repaint writes its segments' single scattering: nothing is kept across it.
        self.single_kept = false;
        match self.refinement.stage {
            Stage::Repaint { batch, first } if batch > 0 || first > 0 => {
                // Under way: these follow once it ends (starting it again at every dab would never
                // let it finish while the pointer moves).
                self.repaint_pending.extend(segments);
            }
            Stage::RepaintGather { .. } => self.repaint_pending.extend(segments),
            stage => {
                // Converged, or planned and not started: one repaint of them all.
                if !stage.image_converged() {
                    segments.append(&mut self.repaint);
                    self.flips_pending.append(&mut self.repaint_flips);
                }
                segments.append(&mut self.repaint_pending);
                self.start_repaint(segments);
            }
        }
        true
    }

    /// Plans the repaint of `segments` from the first light batch.
    fn start_repaint(&mut self, mut segments: Vec<u32>) {
        segments.sort_unstable();
        segments.dedup();
        let mut flips = std::mem::take(&mut self.flips_pending);
        flips.sort_unstable();
        flips.dedup();
        self.repaint_flips = flips;
        // With multiple scattering the partners' is shaded again too where the paint moved their
        // pair's sample, so their rows are gathered.
        let with_partners: Vec<u32> = segments
            .iter()
            .flat_map(|&s| std::iter::once(s).chain(self.repaint_partner(s)))
            .collect();
        self.repaint_rows = self.rows_covered(&with_partners);
        self.repaint = segments;
        self.refinement.stage = Stage::Repaint { batch: 0, first: 0 };
    }

    /// The segment whose multiple scattering a repaint of segment `s` shades too: its
    /// [`strand_partner`], with multiple scattering on, where the paint joined or split their pair
    /// ([`Renderer::repaint_flips`]: the partner's sample moved between its own midpoint and the
    /// pair's shared point). A pair that stays joined moves its sample only when its shared point's
    /// absorption changes, and both its segments are repainted then; one that stays split keeps
    /// each segment's own.
    fn repaint_partner(&self, s: u32) -> Option<u32> {
        if !self.settings.multiple_scattering
            || self.repaint_flips.binary_search(&(s & !1)).is_err()
        {
            return None;
        }
        strand_partner(&self.segment_first, s)
    }

    /// The image rows where `segments` may leave fragments: their ends' projections, widened by
    /// the ribbon's half width (at least `min_width_px`) and a pixel; every row when an end lies
    /// behind the eye or the frame is a tile.
    fn rows_covered(&self, segments: &[u32]) -> std::ops::Range<u32> {
        let height = self.settings.height;
        let cam = self.view_camera();
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for &k in segments {
            let first = self.segment_first[k as usize] as usize;
            for p in &self.point_data[first..first + 2] {
                let at = glam::Vec3::new(p[0], p[1], p[2]);
                let Some(q) =
                    crate::render::camera::project(&cam, at).filter(|_| self.tile.is_none())
                else {
                    return 0..height;
                };
                let width = (p[3] / (q.depth * cam.pixel_angle)).max(cam.min_width_px);
                lo = lo.min(q.y - 0.5 * width - 1.0);
                hi = hi.max(q.y + 0.5 * width + 1.0);
            }
        }
        let clamp = |y: f32| (y.max(0.0) as u32).min(height);
        clamp(lo.floor())..clamp(hi.ceil())
    }

    /// Whether the refinement under way shades multiple scattering alone, keeping the segments'
    /// single scattering ([`Renderer::set_tables`] after the image converged).
    pub fn keeps_single_scattering(&self) -> bool {
        self.single_kept && !self.refinement.stage.image_converged()
    }

    /// Runs `change` (which restarts the plan) as a refinement of the change already on screen:
    /// no new preview is owed for it (new tables, a deferred volume rebuild).
    pub(in crate::render) fn restart_as_refinement(&mut self, change: impl FnOnce(&mut Self)) {
        let owed = self.refinement.preview_state.owed;
        change(self);
        self.refinement.preview_state.owed = owed;
        self.replan();
    }

    /// The first stage of the frame's plan after the preview.
    fn main_stage(&self) -> Stage {
        if self.volume_dirty {
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
        self.repaint_pending.clear();
        self.flips_pending.clear();
        self.repaint_flips.clear();
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
            WorkUnit::Preview { .. } => Some((0, self.light_count)),
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
                    let size = (factor, self.light_count, self.settings.height);
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
        self.refinement.preview_state.new_view |= matches!(unit, WorkUnit::PreviewVisibility { .. });
        self.refinement.in_flight = Some(InFlight {
            unit,
            submitted: Instant::now(),
            done,
            restart: self.refinement.restarts,
            repaint_end: matches!(unit, WorkUnit::RepaintGather { row0, rows }
                if row0 + rows >= self.repaint_rows.end),
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
        self.visibility_valid
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
            ctx.start_read(&[&self.targets.view_depth]),
            self.view_camera(),
        )
    }

    /// The camera uniform of the whole image as the frame is drawn now.
    pub fn view_camera(&self) -> crate::render::camera::CameraUniform {
        self.camera_view.uniform(
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
            full: &self.targets,
            preview,
        }
    }

    /// Rows of the full image the first pass has finished under every light since the restart.
    pub fn sharp_rows(&self) -> u32 {
        self.refinement.sharp_rows
    }

    /// Whether a batch gathers its rows' segments into pixels (by segment, the last light batch).
    fn batch_gathers(&self, b: &ShadeBatch) -> bool {
        self.by_segment && b.flags & FLAG_SEGMENTS != 0 && last_light_batch(b)
    }

    /// Whether the unit gathers (the last light batch's units by segment, and the preview's).
    fn unit_gathers(&self, unit: WorkUnit) -> bool {
        match unit {
            WorkUnit::Shade { batch, .. } => self
                .shading_pass
                .frame_batches()
                .nth(batch as usize)
                .is_some_and(|b| self.batch_gathers(b)),
            WorkUnit::Preview { .. } => self.by_segment,
            _ => false,
        }
    }

    /// The first pass's light batches as its bands' sizing sees them.
    fn first_pass_shapes(&self) -> Vec<BandShape> {
        self.shading_pass
            .frame_batches()
            .take_while(|b| b.slot == 0)
            .map(|b| BandShape {
                lights: b.count,
                gathers: self.batch_gathers(b),
            })
            .collect()
    }

    /// Frame batch `batch`'s K-buffer slot and light count.
    fn batch_shape(&self, batch: u32) -> Option<(u32, u32)> {
        self.shading_pass
            .frame_batches()
            .nth(batch as usize)
            .map(|b| (b.slot, b.count))
    }

    /// Shading batches of the first pass: every light batch at the front K-buffer slot.
    fn first_pass_batches(&self) -> u32 {
        self.shading_pass
            .frame_batches()
            .take_while(|b| b.slot == 0)
            .count() as u32
    }

    fn progress(
        &self,
        submitted: Option<WorkUnit>,
        busy: bool,
        ready: Option<ImageReady>,
    ) -> Progress {
        let r = &self.refinement;
        let grid_cost = r.costs.grid_cost.unwrap_or(GUESS_GRID_ENTRY_S);
        let samples_cost = r.costs.samples_cost.unwrap_or(GUESS_GRID_SAMPLE_S);
        let entries = self.shadow_grid.entry_count() as f64;
        let samples = self.shadow_grid.sample_count() as f64;
        // The grid's sweeps and the samples they read (rebuilt with the pyramid: done when the
        // grid is not stale).
        let grid_total = if self.grid_used() {
            entries * grid_cost + samples * samples_cost
        } else {
            0.0
        };
        let grid_done = if self.grid_needed() {
            r.grid.done as f64 * grid_cost + (r.grid.samples_done as f64).min(samples) * samples_cost
        } else {
            grid_total
        };
        let height = self.settings.height as f64;
        let shade_total: f64 = self
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
    fn grid_entries_for(&self, batch: u32) -> u32 {
        let total = self.shadow_grid.entry_count();
        match self.shading_pass.frame_batches().nth(batch as usize) {
            Some(b) => ((b.first + b.count) * SWEEP_SLOTS).min(total),
            None => total,
        }
    }

    /// A shadow-grid unit towards `target` entries (after the sweeps' samples), or None when they
    /// are built.
    fn grid_unit(&mut self, target: u32) -> Option<WorkUnit> {
        let samples = self.shadow_grid.sample_count();
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
        let mut count = r.costs.items(r.costs.grid_cost, GUESS_GRID_ENTRY_S, r.costs.grid_last, remaining);
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
    fn visibility_part(&self, first: u32, preview: bool) -> u32 {
        let r = &self.refinement;
        let drawn = match preview {
            true => self.preview_draw_count(),
            false => self.hair.segment_count,
        };
        let remaining = drawn.saturating_sub(first);
        // Before the frame's first part is measured: the preview's cost per segment times its
        // divisor (fragments go with the resolution), or the guess.
        let factor = self.preview.as_ref().map_or(1.0, |p| p.factor as f64);
        let cost = match preview {
            true => r.costs.preview_visibility_cost,
            false => r
                .costs.visibility_cost
                .or(r.costs.preview_visibility_cost.map(|c| c * factor)),
        };
        r.costs.items(cost, GUESS_VISIBILITY_SEGMENT_S, u32::MAX / 2, remaining)
    }

    /// The next unit of the plan (sized to the budget); advances the plan past it. The shadow grid is
    /// built light batch by light batch, each just before the first shading batch that reads it: the
    /// first light batch's part before the visibility pass clears the image (the last image stays on
    /// screen meanwhile), the others between shading batches.
    fn next_unit(&mut self, device: &wgpu::Device) -> Option<WorkUnit> {
        let height = self.settings.height;
        let batches = self.shading_pass.frame_batches().count() as u32;
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
                let segments = self.hair.segment_count;
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
                let voxels = self.volume.grid.voxel_count() as u32;
                let r = &mut self.refinement;
                let count = r
                    .costs.items(r.costs.resolve_cost, GUESS_VOXEL_S, u32::MAX / 2, voxels - first)
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
                let segments = self.hair.segment_count;
                let (first, count) = if self.visibility_valid {
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
                    .costs.items(r.costs.backdrop_cost, guess, r.costs.backdrop_last, height - row)
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
                    let prior: &[f64] = if k > 0 { &r.costs.bands[0].row_cost } else { &[] };
                    let guess = GUESS_SHADE_ROW_S / GUESS_ROW_LIGHTS;
                    let by_counts = r
                        .costs.row_segments
                        .as_deref()
                        .filter(|_| k == 0 && by_segment)
                        .map(|c| {
                            let total = r.costs.unit_seconds();
                            r.costs.segment_band_rows(c, (row, height, width), &shapes, total)
                        });
                    let rows = by_counts
                        .unwrap_or_else(|| r.costs.bands[k].rows(row, height, budget, guess, prior));
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
                let total = self.repaint.len() as u32;
                let lights = self.batch_shape(batch).map_or(1, |b| b.1).max(1) as f64;
                let r = &mut self.refinement;
                // A dab's scattered segments cost more each than a band's (S1: 5.7-6.3 us a
                // segment and light against the bands' 5.3): their own measure, or twice the
                // bands' before one is made (the stroke's first unit, with a quarter over them:
                // 462 segments under 16 lights in 55 ms at 35 ms units, lavapipe on two cores).
                let per = r
                    .costs.repaint_cost
                    .or(r.costs.segment_cost.map(|c| 2.0 * c))
                    .map(|c| c * lights);
                let remaining = total.saturating_sub(first);
                let count = r
                    .costs.items(per, GUESS_SEGMENT_LIGHT_S * lights, u32::MAX / 2, remaining)
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
                        row: self.repaint_rows.start,
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
                let end = self.repaint_rows.end.max(row);
                let r = &mut self.refinement;
                let width = self.settings.width.max(1) as f64;
                let rows = r
                    .costs.items(
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
                if self.repaint_pending.is_empty() {
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
                let pending = std::mem::take(&mut self.repaint_pending);
                self.start_repaint(pending);
                self.next_unit(device)
            }
        }
    }

    /// The segments a frame or preview shading unit listed, by the counts (None: not counted, or
    /// not by segment; a kept single scattering's units cost less and are not counted either).
    fn listed_segments(&self, unit: WorkUnit) -> Option<(u64, u64)> {
        let (counts, row0, rows, width) = match unit {
            WorkUnit::Shade { batch, row0, rows } if !self.single_kept => {
                let slot = self.batch_shape(batch).map_or(0, |b| b.0);
                let counts = self
                    .refinement
                    .costs.row_segments
                    .as_deref()
                    .filter(|_| slot == 0)?;
                (counts, row0, rows, self.settings.width)
            }
            WorkUnit::Preview { row0, rows } => {
                let p = self.preview.as_ref()?;
                (p.row_segments.as_deref()?, row0, rows, p.targets.width)
            }
            WorkUnit::Repaint { segments, .. } if !self.single_kept => {
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
    fn preview_rows(&mut self, row: u32, height: u32) -> u32 {
        // Before the preview is measured: the frame's cost of a row under every light batch, scaled
        // to the preview's width (per fragment), or as it is (by segment: `seed_from_preview`).
        let factor = self.preview.as_ref().map_or(1, |p| p.factor) as f64;
        let by_segment = self.by_segment;
        let light_batches = self.first_pass_batches().max(1) as f64;
        let width = self.settings.width as f64 / factor;
        let r = &mut self.refinement;
        let lights = self.light_count as f64;
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
                r.costs.segment_band_rows(c, size, &[shape], r.costs.budget.as_secs_f64())
            }
            None => r.costs.preview_bands.rows(row, height, budget, guess, &[]),
        };
        r.costs.preview_bands.last = rows;
        rows
    }

    fn encode_unit(&mut self, ctx: &GpuContext, enc: &mut wgpu::CommandEncoder, unit: WorkUnit) {
        let device = &ctx.device;
        match unit {
            WorkUnit::PreviewVisibility { first, count } => {
                self.encode_preview_visibility(ctx, enc, first..first + count)
            }
            WorkUnit::Preview { row0, rows } => self.encode_preview(ctx, enc, row0, rows),
            WorkUnit::Volume { first, count } => {
                self.density_pass.encode_deposit(
                    device,
                    enc,
                    &self.hair,
                    &self.volume,
                    first..first + count,
                );
            }
            WorkUnit::VolumeResolve { first, count } => {
                let voxels = first..first + count;
                self.density_pass
                    .encode_resolve(device, enc, &self.hair, &self.volume, voxels);
            }
            WorkUnit::DensityPyramid => {
                self.pyramid_pass
                    .encode(device, enc, &self.volume, &self.pyramid, None);
                self.volume_dirty = false;
                self.shadow_grid_dirty = true;
                self.refinement.grid.done = 0;
                self.refinement.grid.samples_done = 0;
            }
            WorkUnit::GridSamples { first, count } => {
                let inputs = self.shadow_grid_inputs();
                self.shadow_grid_pass.encode_samples(
                    device,
                    enc,
                    &inputs,
                    &self.shadow_grid,
                    first..first + count,
                    None,
                );
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
                let total = self.shadow_grid.entry_count();
                let group = inputs.light_group * SWEEP_SLOTS;
                self.refinement.grid.built(first, count, group, total);
                if first + count >= total {
                    self.shadow_grid_dirty = false;
                }
            }
            WorkUnit::Visibility { first, count } => {
                if count > 0 {
                    self.visibility_pass.encode(
                        device,
                        enc,
                        &self.camera,
                        &self.hair,
                        self.occluder.as_ref().map(|o| &o.gpu),
                        &self.targets,
                        first..first + count,
                        None,
                        None,
                    );
                }
                if first + count < self.hair.segment_count {
                    return;
                }
                // The last part: the image's visibility is whole; the components restart.
                self.visibility_valid = true;
                self.encode_row_segments(device, enc);
                ShadingPass::clear(enc, &self.targets, self.segment_targets.as_ref());
                self.converged_rows = 0;
            }
            WorkUnit::Backdrop { row0, rows } => {
                self.encode_resolve(device, enc, row0..row0 + rows, (true, true));
            }
            WorkUnit::Repaint {
                batch,
                first,
                segments,
            } => {
                let Some(b) = self.shading_pass.frame_batches().nth(batch as usize) else {
                    return;
                };
                let end = (first + segments).min(self.repaint.len() as u32);
                let start = first.min(end) as usize;
                let part = &self.repaint[start..end as usize];
                let mut candidates = Vec::new();
                if let Some(s) = &self.segment_targets {
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
                            .filter(|p| self.repaint.binary_search(p).is_err())
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
                self.shading_pass
                    .encode_repaint(device, enc, &inputs, b, candidates.len() as u32);
            }
            WorkUnit::RepaintGather { row0, rows } => {
                // The last batch's flags (what the segments hold) over the band.
                let Some(last) = self.shading_pass.frame_batches().last() else {
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
                self.shading_pass
                    .encode_repaint_gather(device, enc, &inputs, &self.targets, &b);
                self.encode_resolve(device, enc, row0..row0 + rows, (false, false));
            }
            WorkUnit::Shade { batch, row0, rows } => {
                let Some(b) = self.shading_pass.frame_batches().nth(batch as usize) else {
                    return;
                };
                let kept = if self.single_kept && b.flags & FLAG_SEGMENTS != 0 {
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
                self.shading_pass
                    .encode_batch(device, enc, &inputs, &self.targets, &b, None);
                // The last batch leaves its rows converged: resolved as render_frame resolves them.
                // (Shaded by segment, rows have no image before it: their pixels gather then.)
                let last = batch + 1 >= self.shading_pass.frame_batches().count() as u32;
                if last {
                    self.converged_rows = self.converged_rows.max(row0 + rows);
                }
                if last || b.flags & FLAG_SEGMENTS == 0 {
                    self.encode_resolve(device, enc, row0..row0 + rows, (false, !last));
                }
            }
        }
    }

    fn encode_resolve(
        &self,
        device: &wgpu::Device,
        enc: &mut wgpu::CommandEncoder,
        rows: std::ops::Range<u32>,
        (background, normalise): (bool, bool),
    ) {
        self.resolve_pass.encode(
            device,
            enc,
            &self.camera,
            &self.resolve_info,
            &self.background_map,
            &self.targets,
            rows,
            (background, normalise),
            None,
        );
    }
}
