//! The brush's benchmark inside `bench`: after the scene converged, one stroke of N dabs across the
//! hair as the editor paints it (picking from the frame's view depth, the layer, the points' upload)
//! and, after each dab, refinement until its preview is on screen. CPU time per dab and time until
//! the dab is visible.

use serde::Serialize;
use std::time::Instant;
use strandlight::gpu::GpuContext;
use strandlight::hair::Hair;
use strandlight::paint::brush::{Stroke, effective, eumelanin_unit};
use strandlight::paint::pick::{Picker, ViewDepth};
use strandlight::paint::{Brush, PaintLayer};
use strandlight::render::Renderer;
use strandlight::render::progressive::{Progress, UNIT_PASSES, WorkUnit};

#[derive(Serialize)]
pub struct BrushReport {
    pub dabs: usize,
    /// Brush radius, render pixels.
    pub radius_px: f32,
    /// Reading the view depth back and projecting every point (once per view, on a worker in the
    /// editor): their sum, and each.
    pub picker_ms: f64,
    pub depth_read_ms: f64,
    pub projection_ms: f64,
    /// CPU milliseconds per dab: finding the points, the layer, their absorption and its upload.
    pub cpu_ms_median: f64,
    pub cpu_ms_max: f64,
    pub points_per_dab_mean: f64,
    /// From the dab to its preview being complete, or its repaint of the converged image (the dab
    /// visible), milliseconds, over the dabs that changed points.
    pub visible_dabs: usize,
    /// Their median and largest.
    pub visible_ms_median: f64,
    pub visible_ms_max: f64,
    /// After the stroke: the full image with the new colour converged (single scattering at the new
    /// absorption, the volume and grid of before), milliseconds from the last dab.
    pub stroke_converged_ms: f64,
    /// Then the stroke's shadow and multiple-scattering effects: the volume and the grid's forward
    /// terms rebuilt, multiple scattering shaded again, until converged (milliseconds), and whether
    /// the segments kept their single scattering meanwhile.
    pub follow_up_ms: f64,
    pub follow_up_kept_single: bool,
    /// The follow-up's time per pass (units' submission to completion), milliseconds.
    pub follow_up_pass_ms: std::collections::BTreeMap<&'static str, f64>,
    /// The longest unit the dabs' repaints (or restarts) and the stroke's convergence submitted,
    /// submission to completion as the waiting CPU saw it (milliseconds), and which; then the
    /// follow-up's longest (the renderer's own measure).
    pub longest_unit_ms: f64,
    pub longest_unit: String,
    pub follow_up_longest_unit_ms: f64,
}

/// The longest unit seen ([`Longest::submitted`], [`wait_for_unit`]).
#[derive(Default)]
struct Longest {
    ms: f64,
    unit: String,
    /// The unit submitted last and when `refine` returned it (a unit submitted by the call that
    /// showed a dab is waited for at the next dab).
    in_flight: Option<(WorkUnit, Instant)>,
}

impl Longest {
    /// Notes what a `refine` call submitted.
    fn submitted(&mut self, p: &Progress) {
        if let Some(unit) = p.submitted {
            self.in_flight = Some((unit, Instant::now()));
        }
    }
}

/// Waits for what `p` submitted (or what is still running), timing the unit in flight from the
/// return of the `refine` that submitted it to its completion.
fn wait_for_unit(ctx: &GpuContext, p: &Progress, longest: &mut Longest) -> anyhow::Result<()> {
    if p.submitted.is_none() && !p.busy {
        return Ok(());
    }
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| anyhow::anyhow!("waiting for the GPU: {e}"))?;
    if let Some((unit, t)) = longest.in_flight.take() {
        let ms = t.elapsed().as_secs_f64() * 1e3;
        if ms > longest.ms {
            (longest.ms, longest.unit) = (ms, format!("{unit:?}"));
        }
    }
    Ok(())
}

/// Refines until converged.
fn converge(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    longest: &mut Longest,
) -> anyhow::Result<()> {
    loop {
        let p = renderer.refine(ctx)?;
        longest.submitted(&p);
        if p.converged {
            return Ok(());
        }
        wait_for_unit(ctx, &p, longest)?;
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Paints `dabs` dabs across the converged frame of `renderer` (whose points are `hair`, with the
/// absorption `base` before paint).
pub fn brush_run(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    hair: &Hair,
    base: &[[f32; 3]],
    dabs: usize,
) -> anyhow::Result<BrushReport> {
    // The view depth alone, read back as the editor reads it (the whole frame is ten times the bytes).
    let t = Instant::now();
    let (pending, camera) = renderer.start_read_view_depth(ctx);
    let bytes = loop {
        if let Some(r) = pending.poll(&ctx.device) {
            break r.map_err(anyhow::Error::msg)?;
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    };
    let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes[0]);
    let depth_read_ms = t.elapsed().as_secs_f64() * 1e3;
    let (lo, hi) = hair.bounds();
    let view = ViewDepth {
        width: camera.size[0],
        height: camera.size[1],
        depth: depth.clone(),
        camera,
    };
    let t = Instant::now();
    let picker = Picker::new(hair, view, 0.5 * (lo.x + hi.x));
    let projection_ms = t.elapsed().as_secs_f64() * 1e3;
    let picker_ms = depth_read_ms + projection_ms;
    // A horizontal stroke through the middle of the hair on screen, half the image wide.
    let width = camera.size[0];
    let covered: Vec<usize> = (0..depth.len()).filter(|&i| depth[i] < 1e9).collect();
    anyhow::ensure!(!covered.is_empty(), "no hair on screen to paint");
    let w = width as usize;
    let n = covered.len() as f32;
    let cx = covered.iter().map(|&i| (i % w) as f32 + 0.5).sum::<f32>() / n;
    let cy = covered.iter().map(|&i| (i / w) as f32 + 0.5).sum::<f32>() / n;
    let radius = 0.04 * width as f32;
    let brush = Brush {
        radius_px: radius,
        ..Default::default()
    };
    let length = 0.5 * width as f32;
    let mut layer = PaintLayer::empty(hair.point_count(), hair.strand_count());
    let mut sigma: Vec<[f32; 3]> = base.to_vec();
    let mut stroke = Stroke::new();
    let mut longest = Longest::default();
    let (mut cpu, mut visible, mut points) = (Vec::new(), Vec::new(), 0usize);
    for k in 0..dabs {
        let x = cx - 0.5 * length + length * k as f32 / dabs.max(2).saturating_sub(1) as f32;
        let t = Instant::now();
        let under = picker.dab(&brush, [x, cy], radius, 1.0);
        let changed = stroke.dab(
            &brush,
            &under,
            &mut layer.points,
            base,
            |i| hair.strand_of_point(i),
            eumelanin_unit(),
        );
        for &i in &changed {
            sigma[i as usize] = effective(base[i as usize], layer.points[i as usize]);
        }
        renderer.set_absorption_points_deferred(ctx, &sigma, &changed)?;
        // As the editor: the converged image repaints the dab's segments, or restarts.
        if !renderer.repaint_points(&changed) {
            renderer.restart();
        }
        cpu.push(t.elapsed().as_secs_f64() * 1e3);
        points += changed.len();
        // Refine until the dab shows (its preview, or the full image without one).
        loop {
            let p = renderer.refine(ctx)?;
            longest.submitted(&p);
            if p.ready.is_some() || p.converged {
                break;
            }
            wait_for_unit(ctx, &p, &mut longest)?;
        }
        // A dab that changed no point (off the hair, or where the stroke has saturated) has nothing
        // to show.
        if !changed.is_empty() {
            visible.push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    // The stroke ends: the image converges with the new colour, then (as the editor does once it
    // shows) the volume and grid follow.
    let t = Instant::now();
    converge(ctx, renderer, &mut longest)?;
    let stroke_converged_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let mut follow_up_kept_single = false;
    let mut follow_up_longest_unit_ms = 0.0;
    let mut follow_up_pass_ms = std::collections::BTreeMap::new();
    if renderer.rebuild_stale_volume() {
        follow_up_kept_single = renderer.keeps_single_scattering();
        converge(ctx, renderer, &mut Longest::default())?;
        let stats = renderer.refine_stats();
        follow_up_longest_unit_ms = stats.longest.as_secs_f64() * 1e3;
        for (name, d) in UNIT_PASSES.iter().zip(stats.pass_time) {
            follow_up_pass_ms.insert(*name, d.as_secs_f64() * 1e3);
        }
    }
    let follow_up_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(BrushReport {
        stroke_converged_ms,
        follow_up_ms,
        follow_up_kept_single,
        follow_up_pass_ms,
        dabs,
        radius_px: radius,
        picker_ms,
        depth_read_ms,
        projection_ms,
        cpu_ms_max: cpu.iter().copied().fold(0.0, f64::max),
        cpu_ms_median: median(cpu),
        points_per_dab_mean: points as f64 / dabs.max(1) as f64,
        visible_dabs: visible.len(),
        visible_ms_max: visible.iter().copied().fold(0.0, f64::max),
        visible_ms_median: median(visible),
        longest_unit_ms: longest.ms,
        longest_unit: longest.unit,
        follow_up_longest_unit_ms,
    })
}
