//! What refinement's units cost: a model fed by every finished unit's time (per grid entry, sweep
//! sample, deposited segment, voxel, visible segment and light, pixel, row band) that sizes the next
//! unit to the time budget. Plain data: the plan asks it, the tests drive it without a GPU.

use super::{DEFAULT_UNIT_BUDGET, WorkUnit};
use crate::gpu::GpuContext;
use std::time::Duration;

/// First guesses, before a unit of the kind has been measured: conservative (lavapipe on two cores
/// sweeps a light of a 48-point grid in about 60 ms, 8 entries, and shades about 15 ms per row of a
/// 16-light batch at 720 pixels).
pub(super) const GUESS_GRID_ENTRY_S: f64 = 10e-3;
/// A sample of the shadow grid's sweeps (`MidplaneSamples`; lavapipe, two cores: 350-500 ns; a guess
/// of 50 ns would put S1's 343k samples in one 110-140 ms unit).
pub(super) const GUESS_GRID_SAMPLE_S: f64 = 500e-9;
pub(super) const GUESS_SHADE_ROW_S: f64 = 40e-3;
/// A voxel resolved (lavapipe, two cores: 100-580 ns depending on the machine; a guess of 400 ns can
/// make S1's first resolve unit of 87.5k voxels take 51 ms at 35 ms units).
pub(super) const GUESS_VOXEL_S: f64 = 600e-9;
/// The fewest voxels a resolve unit and rows a backdrop unit hold (a unit's fixed cost, which a tiny
/// budget cannot hold, would otherwise shrink them to one of each).
pub(super) const MIN_RESOLVE_VOXELS: u32 = 16_384;
pub(super) const MIN_BACKDROP_ROWS: u32 = 8;
/// A deposited segment (lavapipe: ~0.4 us each past the sums' clear).
pub(super) const GUESS_SEGMENT_S: f64 = 1e-6;
/// A segment drawn into the K-buffer (lavapipe, two cores: with a guess of 1 us, S0's preview drew
/// 30000 segments in one 406 ms unit, the shader's compilation included).
pub(super) const GUESS_VISIBILITY_SEGMENT_S: f64 = 8e-6;
/// A visible segment under one light, shaded by segment (lavapipe, two cores: 2.7 us on S1).
pub(super) const GUESS_SEGMENT_LIGHT_S: f64 = 10e-6;
/// A pixel of a shading unit's rows (the claim, gather and resolve; lavapipe, two cores: ~0.7 us
/// on S1).
pub(super) const GUESS_PIXEL_S: f64 = 0.5e-6;
/// A pixel of a repaint's gather and resolve, and what the last light batch's gather adds to a
/// pixel of its band (lavapipe, two cores: 0.65-0.95 us on S1, and 0.3-0.9 us).
pub(super) const GUESS_GATHER_PIXEL_S: f64 = 1e-6;
/// A shading unit listing fewer segments does not update the cost per segment.
pub(super) const MIN_MEASURED_SEGMENTS: u64 = 64;
/// The row width and the lights of that guess.
pub(super) const GUESS_ROW_PIXELS: f64 = 720.0;
pub(super) const GUESS_ROW_LIGHTS: f64 = 16.0;
/// K-buffer slots with their own shading bands (the slots behind the fourth share the last).
pub(super) const MAX_SLOTS: usize = 4;

/// A cost estimate after a measurement: the mean of the last estimate and the measurement (so one slow
/// unit does not halve the next ones), or the measurement when there was none.
pub(super) fn ema(old: Option<f64>, new: f64) -> Option<f64> {
    Some(old.map_or(new, |o| 0.5 * (o + new)))
}

/// The bands of K-buffer slot `slot`.
pub(super) fn slot_bands(slot: u32) -> usize {
    (slot as usize).min(MAX_SLOTS - 1)
}

/// Row bands of one image (the frame's or the preview's), sized from measured costs.
#[derive(Default)]
pub(super) struct Bands {
    /// Mean seconds per row of one unit's work (None: not measured yet).
    pub(super) cost: Option<f64>,
    /// Measured seconds per row, per image row (0: not measured yet). A row costs about the same in
    /// every batch (the same pixels under as many lights), so a band is sized from its own rows'
    /// costs, not from the mean of the (often empty) rows above it.
    pub(super) row_cost: Vec<f64>,
    /// Rows of the last band.
    pub(super) last: u32,
}

impl Bands {
    /// Rows of a band from `row` (of `height`): as many as `budget` holds by the rows' own measured
    /// costs (else the `prior` ones: an upper bound, the front slot's for the others; else the mean
    /// row's, or `guess`, and then at most twice the last band); at least one; whole workgroups (8
    /// rows) where the budget allows.
    pub(super) fn rows(
        &self,
        row: u32,
        height: u32,
        budget: f64,
        guess: f64,
        prior: &[f64],
    ) -> u32 {
        let fallback = self.cost.unwrap_or(guess).max(1e-12);
        let (mut t, mut n, mut unknown) = (0.0, 0u32, false);
        for r in row..height {
            let own = self.row_cost.get(r as usize).copied().unwrap_or(0.0);
            let c = if own > 0.0 {
                own
            } else {
                prior.get(r as usize).copied().unwrap_or(0.0)
            };
            unknown |= c <= 0.0;
            let c = if c > 0.0 { c } else { fallback };
            if n > 0 && t + c > budget {
                break;
            }
            t += c;
            n += 1;
        }
        if unknown {
            n = n.min(2 * self.last.max(1));
        }
        let mut n = n.max(1);
        if n >= 8 && n < height - row {
            n -= n % 8;
        }
        n
    }

    /// A band of `rows` rows from `row0` took `elapsed` seconds.
    pub(super) fn measured(&mut self, row0: u32, rows: u32, elapsed: f64) {
        let per = elapsed / rows.max(1) as f64;
        self.cost = ema(self.cost, per);
        let end = (row0 + rows) as usize;
        if self.row_cost.len() < end {
            self.row_cost.resize(end, 0.0);
        }
        self.row_cost[row0 as usize..end].fill(per);
    }

    /// The image width changed by `ratio`: a row costs about that much more (or less), and the next
    /// band starts small.
    pub(super) fn resized(&mut self, ratio: f64) {
        if let Some(c) = &mut self.cost {
            *c *= ratio.max(1e-6);
        }
        self.row_cost.clear();
        self.last = 1;
    }
}

/// A light batch as a band's sizing sees it: its lights, and whether it gathers the band's segments
/// into pixels (and resolves them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct BandShape {
    pub(super) lights: u32,
    pub(super) gathers: bool,
}

/// The cost model of refinement's units (owned by the [`super::Refinement`]).
pub(in crate::render) struct CostModel {
    pub(super) budget: Duration,
    /// The part of the budget units are sized to, but the preview's shading ([`crate::render::Renderer::set_budget_share`]).
    pub(super) budget_share: f64,
    /// Seconds per shadow-grid entry, per sample of its sweeps and per deposited segment (None: not
    /// measured yet).
    pub(super) grid_cost: Option<f64>,
    pub(super) samples_cost: Option<f64>,
    pub(super) volume_cost: Option<f64>,
    /// Seconds per voxel resolved, and per row of the image's resolve before shading.
    pub(super) resolve_cost: Option<f64>,
    pub(super) backdrop_cost: Option<f64>,
    /// Rows of the last backdrop unit.
    pub(super) backdrop_last: u32,
    /// Seconds per segment drawn by the visibility pass (the frame's and the preview's).
    pub(super) visibility_cost: Option<f64>,
    /// The same for the preview's visibility.
    pub(super) preview_visibility_cost: Option<f64>,
    /// The frame's shading bands per K-buffer slot (costs per light: the front slot shades every
    /// covered pixel, the others only where more fragments lie, cheaper), and
    /// the preview's (costs per row of all lights).
    pub(super) bands: [Bands; MAX_SLOTS],
    pub(super) preview_bands: Bands,
    /// The frame's visible segments per row, topmost row (None: not read back for this view yet);
    /// shading by segment, a band's cost is about its rows' count times `segment_cost` per light
    /// ([`crate::render::passes::row_segments`]).
    pub(in crate::render) row_segments: Option<Vec<u32>>,
    /// Measured seconds per listed segment and light of a shading unit, and per pixel of its rows.
    pub(super) segment_cost: Option<f64>,
    pub(super) pixel_cost: Option<f64>,
    /// Measured seconds per pixel of a repaint's gather (and resolve).
    pub(super) gather_cost: Option<f64>,
    /// Measured seconds per pixel that a shading unit which gathers (by segment, the last light
    /// batch's and the preview's) costs over the others (S1's top band, no segments: 25 ms under a
    /// light batch, 63 ms under the last).
    pub(super) batch_gather_cost: Option<f64>,
    /// Measured seconds per segment and light of a repaint's units.
    pub(super) repaint_cost: Option<f64>,
    /// Items of the last grid unit.
    pub(super) grid_last: u32,
    /// Workgroups the device runs side by side when that is a handful (a software rasteriser's
    /// threads: lavapipe gives each thread whole workgroups), else 1. A grid unit of fewer entries
    /// (one workgroup each) than a multiple of it leaves threads idle.
    pub(super) parallel_workgroups: u32,
}

impl Default for CostModel {
    fn default() -> Self {
        Self {
            budget: DEFAULT_UNIT_BUDGET,
            budget_share: 1.0,
            grid_cost: None,
            samples_cost: None,
            volume_cost: None,
            resolve_cost: None,
            backdrop_cost: None,
            backdrop_last: MIN_BACKDROP_ROWS,
            visibility_cost: None,
            preview_visibility_cost: None,
            bands: Default::default(),
            preview_bands: Bands::default(),
            row_segments: None,
            segment_cost: None,
            pixel_cost: None,
            gather_cost: None,
            batch_gather_cost: None,
            repaint_cost: None,
            grid_last: 1,
            parallel_workgroups: 1,
        }
    }
}

impl CostModel {
    /// The model's first state for the context's device.
    pub(super) fn for_device(ctx: &GpuContext) -> Self {
        Self {
            parallel_workgroups: parallel_workgroups(ctx),
            ..Self::default()
        }
    }

    /// The longest time one unit should take.
    pub(in crate::render) fn budget(&self) -> Duration {
        self.budget
    }

    /// Seconds a unit after the preview is sized to: the budget's share.
    pub(super) fn unit_seconds(&self) -> f64 {
        self.budget.as_secs_f64() * self.budget_share
    }

    /// Items a unit may hold: the budget over the measured (or guessed) cost per item, at most twice
    /// the previous unit of the kind (`last`: costs are uneven, empty rows and empty sweep slots cost
    /// almost nothing, so one cheap unit must not size a huge next one); at least one, at most what
    /// remains.
    pub(super) fn items(
        &self,
        per_item: Option<f64>,
        guess: f64,
        last: u32,
        remaining: u32,
    ) -> u32 {
        let per_item = per_item.unwrap_or(guess).max(1e-12);
        let n = (self.unit_seconds() / per_item)
            .floor()
            .min(2.0 * last.max(1) as f64);
        (n.min(remaining as f64) as u32)
            .max(1)
            .min(remaining.max(1))
    }

    /// Seconds per row and light of a shading batch at K-buffer slot `slot` (measured or guessed).
    pub(super) fn light_row_cost(&self, slot: u32) -> f64 {
        self.bands[slot_bands(slot)]
            .cost
            .unwrap_or(GUESS_SHADE_ROW_S / GUESS_ROW_LIGHTS)
    }

    /// A finished preview (at divisor `factor`, `lights` lights) gives the first-sample bands the
    /// cost of the rows not measured yet (the first bands of a new view are sized from the picture,
    /// not from the mean of the empty rows above it). Per fragment a preview row costs what `factor`
    /// frame rows of its width under every light do, so a frame row costs about its preview row's
    /// cost times `factor` over the lights. `by_segment` a preview row shades the segments of its
    /// `factor` frame rows that its four fragments a pixel keep: at most 11k of 59k on S1 at divisor
    /// 11, so a frame row costs about its preview row's over the lights (S1 on lavapipe: about 13 ms a
    /// preview row and 14 ms a frame row, every light). `new_view`: the preview drew its visibility,
    /// so the rows measured before show another picture.
    pub(super) fn seed_from_preview(
        &mut self,
        (factor, lights, height): (u32, u32, u32),
        by_segment: bool,
        new_view: bool,
    ) {
        let f = factor.max(1);
        let scale = if by_segment { 1.0 } else { f as f64 };
        let seeded: Vec<f64> = (0..height)
            .map(|y| {
                let measured = self.bands[0]
                    .row_cost
                    .get(y as usize)
                    .copied()
                    .unwrap_or(0.0);
                let preview = self
                    .preview_bands
                    .row_cost
                    .get((y / f) as usize)
                    .copied()
                    .unwrap_or(0.0);
                if measured > 0.0 && !(new_view && preview > 0.0) {
                    measured
                } else {
                    preview * scale / lights.max(1) as f64
                }
            })
            .collect();
        self.bands[0].row_cost = seeded;
    }

    /// The preview's targets were made anew: its rows' costs are unknown.
    pub(in crate::render) fn preview_bands_reset(&mut self) {
        self.preview_bands = Bands::default();
    }

    /// The image width changed by `ratio`.
    pub(in crate::render) fn resized(&mut self, ratio: f64) {
        for b in &mut self.bands {
            b.resized(ratio);
        }
        self.preview_bands = Bands::default();
        // A segment's fragments go with the image's width.
        for c in [
            &mut self.visibility_cost,
            &mut self.preview_visibility_cost,
            &mut self.backdrop_cost,
        ] {
            *c = c.map(|c| c * ratio.max(1e-6));
        }
    }

    /// Folds a finished unit's time into the cost per item (mean of the last estimate and the
    /// measurement, so one slow unit does not halve the next ones); `batch`: a shading unit's
    /// K-buffer slot and light count.
    /// `listed`: the segments a shading unit (the frame's or the preview's) listed, when counted,
    /// and its pixels.
    pub(super) fn measured(
        &mut self,
        unit: WorkUnit,
        elapsed: Duration,
        batch: Option<(u32, u32)>,
        (listed, gathers): (Option<(u64, u64)>, bool),
    ) {
        let seconds = elapsed.as_secs_f64();
        match unit {
            WorkUnit::ShadowGrid { count, .. } => {
                let per = seconds / count.max(1) as f64;
                self.grid_cost = ema(self.grid_cost, per);
            }
            WorkUnit::GridSamples { count, .. } => {
                let per = seconds / count.max(1) as f64;
                self.samples_cost = ema(self.samples_cost, per);
            }
            WorkUnit::Shade { row0, rows, .. } => {
                let (slot, lights) = batch.unwrap_or((0, 1));
                let per_light = seconds / lights.max(1) as f64;
                self.bands[slot_bands(slot)].measured(row0, rows, per_light);
                self.segments_measured(seconds, lights, listed, gathers);
            }
            WorkUnit::Preview { row0, rows } => {
                self.preview_bands.measured(row0, rows, seconds);
                let lights = batch.map_or(1, |b| b.1);
                self.segments_measured(seconds, lights, listed, gathers);
            }
            WorkUnit::Volume { count, .. } => {
                let per = seconds / count.max(1) as f64;
                self.volume_cost = ema(self.volume_cost, per);
            }
            // The clear, composite and resolve of the last part ride along: an overstatement. The
            // frame's and the preview's apart: a segment leaves fragments in proportion to the
            // image's resolution.
            WorkUnit::Visibility { count, .. } if count > 0 => {
                let per = seconds / count as f64;
                self.visibility_cost = ema(self.visibility_cost, per);
            }
            WorkUnit::PreviewVisibility { count, .. } if count > 0 => {
                let per = seconds / count as f64;
                self.preview_visibility_cost = ema(self.preview_visibility_cost, per);
            }
            WorkUnit::Backdrop { rows, .. } => {
                let per = seconds / rows.max(1) as f64;
                self.backdrop_cost = ema(self.backdrop_cost, per);
            }
            WorkUnit::VolumeResolve { count, .. } => {
                let per = seconds / count.max(1) as f64;
                self.resolve_cost = ema(self.resolve_cost, per);
            }
            WorkUnit::Repaint { segments, .. } => {
                let lights = batch.map_or(1, |b| b.1);
                self.segments_measured(seconds, lights, listed, false);
                if segments as u64 >= MIN_MEASURED_SEGMENTS {
                    let per = seconds / (lights.max(1) * segments) as f64;
                    self.repaint_cost = ema(self.repaint_cost, per);
                }
            }
            // The gather and resolve of its rows: the cost per pixel.
            WorkUnit::RepaintGather { .. } => {
                if let Some((_, pixels)) = listed.filter(|l| l.1 > 0) {
                    self.gather_cost = ema(self.gather_cost, seconds / pixels as f64);
                }
            }
            WorkUnit::DensityPyramid
            | WorkUnit::Visibility { .. }
            | WorkUnit::PreviewVisibility { .. } => {}
        }
    }

    /// A shading unit under `lights` lights took `seconds` over `listed` = (segments, pixels): a
    /// unit of a few segments measures the cost per pixel (the claim; with `gathers`, what the
    /// gather and resolve add to it), the others the cost per segment and light past it.
    pub(super) fn segments_measured(
        &mut self,
        seconds: f64,
        lights: u32,
        listed: Option<(u64, u64)>,
        gathers: bool,
    ) {
        let Some((segments, pixels)) = listed else {
            return;
        };
        let pixel = self.pixel_cost.unwrap_or(GUESS_PIXEL_S);
        let gather = match gathers {
            true => self.batch_gather_cost.unwrap_or(GUESS_GATHER_PIXEL_S),
            false => 0.0,
        };
        if segments < MIN_MEASURED_SEGMENTS {
            // Only where the segments' own part is small: a preview row of 42 segments under 40
            // lights took 10 ms, and taken for its 45 pixels' cost it made a pixel 400 times dearer
            // than it is (every later band then held one row).
            let listed = (lights.max(1) as u64 * segments) as f64
                * self.segment_cost.unwrap_or(GUESS_SEGMENT_LIGHT_S);
            if pixels > 0 && listed < 0.25 * seconds {
                let per = (seconds - listed) / pixels as f64;
                if gathers {
                    // At once up, slowly down: the same band's gather took 0.3 to 0.9 us a pixel
                    // from one run to the next, and a band sized at the lower overran by 60 %.
                    let past = (per - pixel).max(0.1 * per);
                    self.batch_gather_cost = Some(match self.batch_gather_cost {
                        Some(c) if c > past => 0.8 * c + 0.2 * past,
                        _ => past,
                    });
                } else {
                    self.pixel_cost = ema(self.pixel_cost, per);
                }
            }
            return;
        }
        let fixed = pixels as f64 * (pixel + gather);
        let per = (seconds - fixed).max(0.5 * seconds) / (lights.max(1) as u64 * segments) as f64;
        self.segment_cost = ema(self.segment_cost, per);
    }

    /// Rows of a band from `row` (of `height`, `width` pixels a row) by `counts`, the segments
    /// each row lists, under each of `shapes` (the light batches that shade the band): as many as
    /// `budget` seconds hold under the dearest at the measured costs per segment and light, per
    /// pixel and per pixel gathered; at least one, whole workgroups (8 rows) where the budget
    /// allows.
    pub(super) fn segment_band_rows(
        &self,
        counts: &[u32],
        (row, height, width): (u32, u32, u32),
        shapes: &[BandShape],
        budget: f64,
    ) -> u32 {
        let segment = self.segment_cost.unwrap_or(GUESS_SEGMENT_LIGHT_S);
        let pixel = self.pixel_cost.unwrap_or(GUESS_PIXEL_S) * width as f64;
        let gather = self.batch_gather_cost.unwrap_or(GUESS_GATHER_PIXEL_S) * width as f64;
        let row_cost = |n: f64| {
            shapes
                .iter()
                .map(|b| {
                    let gathered = if b.gathers { gather } else { 0.0 };
                    n * segment * b.lights.max(1) as f64 + pixel + gathered
                })
                .fold(0.0, f64::max)
        };
        let (mut t, mut n) = (0.0, 0u32);
        for r in row..height {
            let c = row_cost(counts.get(r as usize).copied().unwrap_or(0) as f64);
            if n > 0 && t + c > budget {
                break;
            }
            t += c;
            n += 1;
        }
        let mut n = n.max(1);
        if n >= 8 && n < height - row {
            n -= n % 8;
        }
        n
    }
}

/// [`CostModel::parallel_workgroups`] of the context's device: a software adapter's threads
/// (lavapipe runs `LP_NUM_THREADS`, by default one per core, at most 32), 1 on hardware.
fn parallel_workgroups(ctx: &GpuContext) -> u32 {
    if ctx.adapter.get_info().device_type != wgpu::DeviceType::Cpu {
        return 1;
    }
    std::env::var("LP_NUM_THREADS")
        .ok()
        .and_then(|v| v.trim().parse::<u32>().ok())
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get() as u32))
        .clamp(1, 32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit of few segments measures the cost per pixel only where the segments' part is small:
    /// S1's preview rows (42 segments under 40 lights, 45 pixels, 10 ms) once made a pixel 400
    /// times dearer than it is.
    #[test]
    fn few_segments_under_many_lights_do_not_price_the_pixels() {
        let mut r = CostModel {
            segment_cost: Some(6e-6),
            pixel_cost: Some(0.5e-6),
            ..Default::default()
        };
        r.segments_measured(0.010, 40, Some((42, 45)), true);
        assert_eq!((r.pixel_cost, r.batch_gather_cost), (Some(0.5e-6), None));
        // No segments: the pixels' cost, and the gather's past it for a unit that gathers.
        r.segments_measured(0.012, 16, Some((0, 40_000)), false);
        assert!((r.pixel_cost.unwrap_or(0.0) - 0.4e-6).abs() < 1e-12);
        r.pixel_cost = Some(0.5e-6);
        r.segments_measured(0.060, 8, Some((0, 40_000)), true);
        let gather = r.batch_gather_cost.unwrap_or(0.0);
        assert!((gather - 1.0e-6).abs() < 1e-9, "gather {gather}");
        // Up at once, down slowly.
        r.segments_measured(0.030, 8, Some((0, 40_000)), true);
        let lower = r.batch_gather_cost.unwrap_or(0.0);
        assert!(lower < gather && lower > 0.8 * gather, "gather {lower}");
        // Many segments: the cost per segment and light past the pixels (and the gather).
        r.batch_gather_cost = Some(1e-6);
        r.segments_measured(0.080 + 0.060, 8, Some((1000, 40_000)), true);
        // (0.140 - 40 000 x 1.5 us) / (8 x 1000) = 10 us, averaged with the 6 us before.
        let segment = r.segment_cost.unwrap_or(0.0);
        assert!((segment - 8e-6).abs() < 1e-12, "segment {segment}");
    }

    /// A band of the first pass fits the dearest of its light batches: rows without segments under
    /// the last batch, which gathers, hold fewer rows than the claim alone would.
    #[test]
    fn first_pass_bands_fit_the_batch_that_gathers() {
        let r = CostModel {
            segment_cost: Some(5e-6),
            pixel_cost: Some(0.5e-6),
            batch_gather_cost: Some(1e-6),
            ..Default::default()
        };
        let counts = vec![0u32; 480];
        let shape = |lights, gathers| BandShape { lights, gathers };
        let size = (0, 480, 720);
        let claim = r.segment_band_rows(&counts, size, &[shape(16, false)], 0.035);
        let batches = [shape(16, false), shape(16, false), shape(8, true)];
        let gathered = r.segment_band_rows(&counts, size, &batches, 0.035);
        println!("rows of a band: {claim} claimed, {gathered} with the gather");
        // 720 pixels at 0.5 us (0.36 ms a row), at 1.5 us with the gather (1.08 ms).
        assert_eq!((claim, gathered), (96, 32));
        // With segments, the first batch's 16 lights are the dearer: a row of 100 segments costs
        // 8.36 ms under them (5.08 ms under the last batch), four fit 35 ms.
        let dense = vec![100u32; 480];
        assert_eq!(r.segment_band_rows(&dense, size, &batches, 0.035), 4);
    }
}
