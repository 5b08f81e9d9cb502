//! `strandlight bench`: GPU time per pass (timestamp queries, median over frames after warm-up) for the
//! standard scenes S0-S3, plus the CPU time of their preprocessing, as JSON.

use anyhow::{Context, bail};
use clap::Args;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;
use strandlight::envmap::{FitOptions, fit_srbf};
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::render::preview::PreviewMode;
use strandlight::render::progressive::{ImageReady, UNIT_PASSES};
use strandlight::render::renderer::TableBuild;
use strandlight::render::scene::{StandardScene, default_environment};
use strandlight::render::shade::ShadingHair;
use strandlight::render::table_cache;
use strandlight::render::{Camera, HairLook, RenderSettings, Renderer};
use strandlight::scattering::Preset;
use strandlight::scattering::lut::Luts;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scenes to run (S0, S1, S2, S3).
    #[arg(long, value_delimiter = ',', default_value = "S0,S1,S2,S3")]
    pub scenes: Vec<String>,
    /// Timed frames per scene (the issue asks for at least 20; software adapters may need fewer).
    #[arg(long, default_value_t = 20)]
    pub frames: usize,
    /// Untimed frames first.
    #[arg(long, default_value_t = 3)]
    pub warmup: usize,
    /// Rebuilds of the shadow grid alone, timed by wall clock (at least 1; `shadow_grid_wall_ms`: their
    /// median, the upper middle one of an even count).
    #[arg(long, default_value_t = 3)]
    pub grid_runs: usize,
    /// No self-shadowing.
    #[arg(long)]
    pub no_shadows: bool,
    /// Without the generated head (drawn, shaded and shadowing by default, as in `render`)
    #[arg(long)]
    pub no_head: bool,
    /// Single scattering only.
    #[arg(long)]
    pub single_scattering: bool,
    /// Shade every kept K-buffer fragment at its own point instead of each visible segment once
    /// (the default).
    #[arg(long)]
    pub per_fragment: bool,
    /// Keep the fiber-density volume and shadow grid between frames (what a parameter or camera
    /// edit costs); by default they are rebuilt every frame, as when geometry moves, so they are timed.
    #[arg(long)]
    pub keep_volume: bool,
    /// Use a software adapter (lavapipe).
    #[arg(long)]
    pub software: bool,
    /// Skip the progressive-refinement run (one more frame, refined in bounded units).
    #[arg(long)]
    pub no_progressive: bool,
    /// Progressive refinement without its preview (the editor's reduced-resolution first image).
    #[arg(long)]
    pub no_preview: bool,
    /// Progressive refinement's time budget per unit, milliseconds (default: the editor's for the
    /// adapter, 35 on a software GPU, 30 on a hardware one).
    #[arg(long)]
    pub unit_budget_ms: Option<f64>,
    /// Brush dabs painted after the progressive run (one stroke across the hair, each dab refined
    /// until it shows); 0 skips it.
    #[arg(long, default_value_t = 100)]
    pub dabs: usize,
    /// Write the JSON here as well as to stdout.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

#[derive(Serialize)]
struct SceneReport {
    scene: StandardScene,
    segments: usize,
    shadows: bool,
    multiple_scattering: bool,
    frames: usize,
    /// CPU seconds: hairstyle generation, SRBF fit (S2's 41 lights; S1 and S3 use the committed
    /// 40-light fit), LUT build, renderer creation (uploads and pipelines).
    cpu_seconds: BTreeMap<&'static str, f64>,
    /// Median GPU milliseconds per pass, and of their sum per frame.
    gpu_ms_median: BTreeMap<&'static str, f64>,
    gpu_ms_total_median: f64,
    gpu_ms_total_min: f64,
    /// Wall-clock milliseconds from submit to read-back, median.
    wall_ms_median: f64,
    /// Whether the frame shaded its visible segments (the default) or every kept fragment
    /// (`--per-fragment`).
    segment_shading: bool,
    /// Points shaded per frame: each pixel's kept K-buffer fragments, or each visible segment's
    /// midpoint (one response per light, its transmittance read at the ends and the midpoint).
    shaded_points: usize,
    /// Kept fragments with a weight, and the distinct segments among them.
    fragments: usize,
    visible_segments: usize,
    /// Points whose multiple scattering the frame evaluates by segment: one per pair of consecutive
    /// visible segments of a strand that share it (`ShadingHair::ms_key`), one per segment without.
    #[serde(skip_serializing_if = "Option::is_none")]
    ms_points: Option<usize>,
    /// The shading pass's median GPU time per light per shaded point, microseconds (all threads of
    /// the GPU: compare with `bench-fast`'s one-thread CPU figure only as a ratio).
    #[serde(skip_serializing_if = "Option::is_none")]
    shading_us_per_light_per_point: Option<f64>,
    /// The whole shadow grid rebuilt alone and waited for (wall clock, the median of `--grid-runs`
    /// rebuilds, and the fastest): lavapipe's timestamps bracket a compute dispatch's submission, not
    /// its work, so `gpu_ms_median.shadow_grid` reads ~0 there after the first frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    shadow_grid_wall_ms: Option<f64>,
    /// The fastest of those rebuilds.
    #[serde(skip_serializing_if = "Option::is_none")]
    shadow_grid_wall_ms_min: Option<f64>,
    /// The same frame by progressive refinement (volume and grid rebuilt unless --keep-volume).
    #[serde(skip_serializing_if = "Option::is_none")]
    progressive: Option<ProgressiveReport>,
}

#[derive(Serialize)]
struct ProgressiveReport {
    unit_budget_ms: f64,
    /// The preview's resolution divisor at the end (automatic: adapted to its measured time).
    preview_factor: u32,
    units: u32,
    /// The longest unit, submission to completion (wall clock), and which.
    longest_unit_ms: f64,
    longest_unit: String,
    /// Submission to completion of each pass's units, summed (wall clock as the polling saw it).
    pass_ms: std::collections::BTreeMap<&'static str, f64>,
    /// From the change until the preview is complete (reduced resolution, every light, the shadow
    /// grid as it stood), and until the full image's first pass is (every light at the front
    /// K-buffer slot, with the shadow grid).
    #[serde(skip_serializing_if = "Option::is_none")]
    preview_ms: Option<f64>,
    first_pass_ms: f64,
    /// From the change to the converged image (wall clock, as the polling after each unit saw it).
    #[serde(skip_serializing_if = "Option::is_none")]
    image_converged_ms: Option<f64>,
    /// From the change to the end of the plan (wall clock, including the CPU between units): the
    /// converged image and, after it, the next preview's visibility where its divisor changed.
    converged_ms: f64,
    /// Parameter changes after convergence, as the editor makes them (beta_R halved, then restored:
    /// the second with the preview's divisor adapted by the first).
    edits: Vec<EditReport>,
    /// A brush stroke after that (`--dabs`).
    #[serde(skip_serializing_if = "Option::is_none")]
    brush: Option<super::bench_brush::BrushReport>,
}

/// A parameter change as the editor makes it: the uniform at once, the tables on a worker thread,
/// handed over once the full image's first pass is shown.
#[derive(Serialize)]
struct EditReport {
    /// The preview's resolution divisor.
    preview_factor: u32,
    /// CPU milliseconds of the change on the calling (UI) thread.
    cpu_ms: f64,
    /// CPU milliseconds of the tables on the worker.
    tables_ms: f64,
    /// A new eta or eccentricity: CPU milliseconds of the draft of its azimuthal table on the worker
    /// (`TableBuild::Azimuthal`), built at once and handed over when done, as the editor does.
    #[serde(skip_serializing_if = "Option::is_none")]
    draft_tables_ms: Option<f64>,
    /// A new eta or eccentricity: from the change to the first image (a preview, or without one the
    /// first pass) that reads its index (the earlier images keep the old one: no frame reads a table
    /// made for another index).
    #[serde(skip_serializing_if = "Option::is_none")]
    index_shown_ms: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    preview_ms: Option<f64>,
    first_pass_ms: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    image_converged_ms: Option<f64>,
    converged_ms: f64,
    longest_unit_ms: f64,
}

/// What one refinement to convergence measured (times from its start, wall clock).
struct RefineRun {
    stats: strandlight::render::progressive::RefineStats,
    preview_ms: Option<f64>,
    first_pass_ms: Option<f64>,
    /// When a call first saw the image converged since the last restart (the plan may go on with
    /// the next preview's visibility).
    image_converged_ms: Option<f64>,
    converged_ms: f64,
    /// The longest unit over the whole run (a refining restart resets the stats).
    longest_ms: f64,
    /// Whether the plan as the last call left it has shown an image (a preview or the full image
    /// of its latest restart).
    shown: bool,
}

/// Refines to convergence, waiting for each unit, calling `between` after each call (the editor's
/// hand-over of tables).
fn refine_run(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    mut between: impl FnMut(&mut Renderer, &RefineRun),
) -> anyhow::Result<RefineRun> {
    let t = Instant::now();
    let mut run = RefineRun {
        stats: Default::default(),
        preview_ms: None,
        first_pass_ms: None,
        image_converged_ms: None,
        converged_ms: 0.0,
        longest_ms: 0.0,
        shown: false,
    };
    loop {
        let p = renderer.refine(ctx)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        run.shown = p.stats.preview.is_some() || p.stats.first_pass.is_some();
        run.longest_ms = run.longest_ms.max(p.stats.longest.as_secs_f64() * 1e3);
        match p.ready {
            Some(ImageReady::Preview) => {
                run.preview_ms.get_or_insert(ms);
            }
            Some(ImageReady::Full) => {
                run.first_pass_ms.get_or_insert(ms);
            }
            None => {}
        }
        // The stats start again at a restart: so does the image's convergence.
        run.image_converged_ms = p
            .stats
            .image_converged
            .and(run.image_converged_ms.or(Some(ms)));
        if p.converged {
            run.stats = p.stats;
            run.converged_ms = ms;
            return Ok(run);
        }
        between(renderer, &run);
        if p.submitted.is_some() || p.busy {
            ctx.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| anyhow::anyhow!("waiting for the GPU: {e}"))?;
        }
    }
}

#[derive(Serialize)]
struct Report {
    adapter: strandlight::gpu::context::AdapterSummary,
    scenes: Vec<SceneReport>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    v[v.len() / 2]
}

/// Changes the look to `edited` as the editor would (the uniform now, the tables on a worker thread,
/// handed over once the full image's first pass is shown; for a new eta or eccentricity the draft of
/// its azimuthal table first, at once, and the tables once the draft's preview shows) and refines to
/// convergence.
fn edit_run(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    edited: &HairLook,
) -> anyhow::Result<EditReport> {
    let params = edited.params;
    // The tables built anew, as for parameters not seen before (the process keeps recent sets:
    // the restored edit would otherwise take them from the cache).
    table_cache::clear();
    let preview_factor = renderer.preview_factor();
    let t = Instant::now();
    let needs_tables = renderer.set_params_deferred(ctx, edited);
    let cpu_ms = t.elapsed().as_secs_f64() * 1e3;
    let azimuthal = renderer.azimuthal_table().clone();
    let new_index = needs_tables && !azimuthal.made_for_hair(&params);
    let timed = |draft: bool| {
        let azimuthal = azimuthal.clone();
        std::thread::spawn(move || {
            let t = Instant::now();
            let tables = TableBuild::build(&params, Some(&azimuthal), draft);
            (tables, t.elapsed().as_secs_f64() * 1e3)
        })
    };
    let draft = new_index.then(|| timed(true));
    let (mut draft_tables_ms, mut index_shown_ms) = (None, None);
    // Whether the draft (or tables the process kept) went over: the new index shows from there.
    let mut index_handed = false;
    // As the editor: the build starts once the change's preview shows (at once without one; for a
    // new index once its draft's preview shows).
    let mut spawn = needs_tables.then_some(());
    let mut worker = None;
    if renderer.preview_factor() < 2 && !new_index {
        worker = spawn.take().map(|_| timed(false));
    }
    let mut tables_ms = 0.0;
    // The worker's tables to the renderer; their build's milliseconds.
    let hand_over = |r: &mut Renderer, worker: &mut Option<std::thread::JoinHandle<_>>| {
        let (tables, ms) = worker.take()?.join().ok()?;
        r.take_tables(ctx, &params, &tables);
        Some(ms)
    };
    if let Some(d) = draft {
        // As the editor: it refines while the draft is built (an index alone leaves the frame as it
        // is, so there is nothing to do), then hands it over.
        while !d.is_finished() {
            let p = renderer.refine(ctx)?;
            if p.submitted.is_some() || p.busy {
                ctx.device
                    .poll(wgpu::PollType::wait_indefinitely())
                    .map_err(|e| anyhow::anyhow!("waiting for the GPU: {e}"))?;
            } else {
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
        }
        if let Ok((tables, ms)) = d.join() {
            index_handed = true;
            renderer.take_tables(ctx, &params, &tables);
            if tables.azimuthal_only() {
                draft_tables_ms = Some(ms);
                // Without a preview the table is built at once (the editor's).
                if renderer.preview_factor() < 2 && spawn.take().is_some() {
                    worker = Some(timed(false));
                }
            } else {
                // Tables the process kept: nothing more to build.
                tables_ms = ms;
                spawn = None;
            }
        }
    }
    // As the editor: units after the preview take a share of the budget while tables are wanted or
    // built (on a software GPU the build takes its cores).
    let building_share = strandlight::editor::live::budget_share(ctx, true);
    let share = |building: bool| if building { building_share } else { 1.0 };
    renderer.set_budget_share(share(spawn.is_some() || worker.is_some()));
    let run = refine_run(ctx, renderer, |r, run| {
        'between: {
            let ms = t.elapsed().as_secs_f64() * 1e3;
            if new_index {
                if index_handed && index_shown_ms.is_none() && run.shown {
                    index_shown_ms = Some(ms);
                    if spawn.take().is_some() {
                        worker = Some(timed(false));
                    }
                }
                // The table goes over as soon as it is built (the editor's: a new azimuthal table).
                if worker.as_ref().is_some_and(|w| w.is_finished()) {
                    tables_ms = hand_over(r, &mut worker).unwrap_or(tables_ms);
                }
                break 'between;
            }
            if (run.preview_ms.is_some() || run.first_pass_ms.is_some()) && spawn.take().is_some() {
                worker = Some(timed(false));
            }
            if run.first_pass_ms.is_some() && worker.as_ref().is_some_and(|w| w.is_finished()) {
                tables_ms = hand_over(r, &mut worker).unwrap_or(tables_ms);
            }
        }
        r.set_budget_share(share(spawn.is_some() || worker.is_some()));
    })?;
    let (mut converged_ms, mut longest_ms) = (run.converged_ms, run.longest_ms);
    let mut image_converged_ms = run.image_converged_ms;
    if index_handed && index_shown_ms.is_none() {
        // The first image after the draft was the converged one (refine_run returns before its
        // callback sees it: without a preview, the table's hand-over restarted the first pass).
        index_shown_ms = Some(converged_ms);
    }
    if spawn.take().is_some() {
        worker = Some(timed(false));
    }
    if worker.is_some() {
        // Converged before the tables came: they refine it once more.
        tables_ms = hand_over(renderer, &mut worker).unwrap_or(tables_ms);
        let before = t.elapsed().as_secs_f64() * 1e3;
        renderer.set_budget_share(share(false));
        let again = refine_run(ctx, renderer, |_, _| {})?;
        converged_ms = t.elapsed().as_secs_f64() * 1e3;
        image_converged_ms = again.image_converged_ms.map(|ms| before + ms);
        longest_ms = longest_ms.max(again.longest_ms);
        if index_handed && index_shown_ms.is_none() {
            index_shown_ms = again
                .preview_ms
                .or(again.first_pass_ms)
                .map(|ms| before + ms);
        }
    }
    renderer.set_budget_share(share(false));
    Ok(EditReport {
        preview_factor,
        cpu_ms,
        tables_ms,
        draft_tables_ms,
        index_shown_ms,
        preview_ms: run.preview_ms,
        first_pass_ms: run.first_pass_ms.unwrap_or(run.converged_ms),
        image_converged_ms,
        converged_ms,
        longest_unit_ms: longest_ms,
    })
}

pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    let mut options = GpuOptions::from_env();
    options.force_software |= args.software;
    let ctx = GpuContext::new_headless(&options)?;
    eprintln!("adapter: {} ({})", ctx.summary.name, ctx.summary.backend);
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    let mut reports = Vec::new();
    for name in &args.scenes {
        let scene = StandardScene::by_name(name)
            .with_context(|| format!("unknown scene '{name}' (S0, S1, S2 or S3)"))?;
        let mut cpu = BTreeMap::new();
        // Each scene's renderer builds its tables (renderer_creation includes them).
        table_cache::clear();
        let t = Instant::now();
        let hair = scene.hair();
        cpu.insert("hair_generation", t.elapsed().as_secs_f64());
        let env = default_environment();
        let lights = if scene.lights == env.lights.lights.len() {
            env.lights.lights.clone()
        } else {
            let image = env.image.context("the built-in environment image")?;
            let t = Instant::now();
            let options = FitOptions {
                lights: scene.lights,
                ..Default::default()
            };
            let set = fit_srbf(&image, &options, |_| {}).map_err(anyhow::Error::msg)?;
            cpu.insert("srbf_fit", t.elapsed().as_secs_f64());
            set.lights
        };
        let t = Instant::now();
        let luts = Luts::build();
        cpu.insert("lut_build", t.elapsed().as_secs_f64());
        let look = HairLook::new(Preset::Brown.params());
        let (lo, hi) = hair.bounds();
        let aspect = scene.width as f32 / scene.height as f32;
        let camera = Camera::framing(lo, hi, 35.0, 10.0, aspect, 0.9);
        let settings = RenderSettings {
            width: scene.width,
            height: scene.height,
            shadows: !args.no_shadows,
            multiple_scattering: !args.single_scattering,
            segment_shading: !args.per_fragment,
            ..Default::default()
        };
        let sigma_a = vec![look.fast.sigma_a_rgb(); hair.point_count()];
        let t = Instant::now();
        let mut renderer = Renderer::new(
            &ctx, settings, &luts, &hair, &sigma_a, &look, &lights, &camera,
        )?;
        cpu.insert("renderer_creation", t.elapsed().as_secs_f64());
        if !args.no_head {
            // The generated head, as the default render draws it (its voxelisation is CPU work).
            let t = Instant::now();
            renderer.set_occluder(&ctx, Some(&scene.occluder()));
            cpu.insert("head_voxelisation", t.elapsed().as_secs_f64());
        }
        let mut per_pass: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
        let (mut totals, mut walls) = (Vec::new(), Vec::new());
        for f in 0..args.warmup + args.frames {
            if !args.keep_volume {
                renderer.mark_volume_dirty();
            }
            let t = Instant::now();
            renderer.render_frame(&ctx);
            let times = renderer
                .pass_times(&ctx)?
                .context("the adapter has no timestamp queries")?;
            let wall = t.elapsed().as_secs_f64() * 1e3;
            eprintln!(
                "{} frame {f}: {:.2} ms GPU ({})",
                scene.name,
                times.iter().map(|t| t.1).sum::<f64>(),
                if f < args.warmup { "warm-up" } else { "timed" }
            );
            if f < args.warmup {
                continue;
            }
            totals.push(times.iter().map(|t| t.1).sum::<f64>());
            walls.push(wall);
            for (name, ms) in times {
                per_pass.entry(name).or_default().push(ms);
            }
        }
        // The points the shading pass shades: each pixel's kept fragments, or each visible
        // segment's midpoint.
        let frame = renderer.read_frame(&ctx)?;
        let kept = (0..frame.pixel_count())
            .flat_map(|i| frame.kept_fragments(i).iter().filter(|f| f.weight > 0.0));
        let fragments = kept.clone().count();
        let visible: std::collections::HashSet<u32> = kept.map(|f| f.id).collect();
        let visible_segments = visible.len();
        let ms_points = (renderer.shades_segments() && !args.single_scattering).then(|| {
            let shading = ShadingHair::new(&hair, &sigma_a);
            visible
                .iter()
                .map(|&id| shading.ms_key(id - 1))
                .collect::<std::collections::HashSet<_>>()
                .len()
        });
        let shaded_points = if renderer.shades_segments() {
            visible_segments
        } else {
            fragments
        };
        let shading_us_per_light_per_point = per_pass
            .get("shading")
            .map(|v| median(v.clone()) * 1e3 / (lights.len() * shaded_points).max(1) as f64);
        let grid_runs = if args.no_shadows {
            Vec::new()
        } else {
            (0..args.grid_runs.max(1))
                .map(|_| Ok(renderer.time_shadow_grid(&ctx)? * 1e3))
                .collect::<anyhow::Result<Vec<f64>>>()?
        };
        let shadow_grid_wall_ms_min = grid_runs.iter().copied().reduce(f64::min);
        let shadow_grid_wall_ms = (!grid_runs.is_empty()).then(|| median(grid_runs));
        let progressive = if args.no_progressive {
            None
        } else {
            let budget = args.unit_budget_ms.map_or_else(
                || strandlight::editor::live::unit_budget(&ctx),
                |ms| std::time::Duration::from_secs_f64(ms.max(0.1) * 1e-3),
            );
            renderer.set_unit_budget(budget);
            renderer.set_preview(if args.no_preview {
                PreviewMode::Off
            } else {
                PreviewMode::Auto
            });
            if args.keep_volume {
                renderer.set_camera(&ctx, &camera);
            } else {
                renderer.mark_volume_dirty();
            }
            let run = refine_run(&ctx, &mut renderer, |_, _| {})?;
            let stats = run.stats;
            let first_pass_ms = run.first_pass_ms.unwrap_or(run.converged_ms);
            eprintln!(
                "{} progressive: {} units, longest {:.1} ms, preview {}, first pass {first_pass_ms:.0} ms, image converged in {}, plan finished in {:.0} ms",
                scene.name,
                stats.units,
                stats.longest.as_secs_f64() * 1e3,
                run.preview_ms
                    .map_or_else(|| "none".into(), |t| format!("{t:.0} ms")),
                run.image_converged_ms
                    .map_or_else(|| "?".into(), |t| format!("{t:.0} ms")),
                run.converged_ms
            );
            let mut narrow = look.params;
            narrow.beta_r *= 0.5;
            let mut denser = look.params;
            denser.eta = 1.6;
            let mut edits = Vec::new();
            for (what, params) in [
                ("beta_R halved", narrow),
                ("beta_R restored", look.params),
                ("eta 1.6", denser),
                ("eta restored", look.params),
            ] {
                let edit = edit_run(&ctx, &mut renderer, &HairLook::new(params))?;
                eprintln!(
                    "{} edit ({what}): {:.2} ms CPU, preview {} at 1/{}, first pass {:.0} ms, converged in {:.0} ms",
                    scene.name,
                    edit.cpu_ms,
                    edit.preview_ms
                        .map_or_else(|| "none".into(), |t| format!("{t:.0} ms")),
                    edit.preview_factor,
                    edit.first_pass_ms,
                    edit.converged_ms
                );
                edits.push(edit);
            }
            let brush = if args.dabs > 0 {
                let b =
                    super::bench_brush::brush_run(&ctx, &mut renderer, &hair, &sigma_a, args.dabs)?;
                eprintln!(
                    "{} brush: {} dabs of {:.0} px, {:.2} ms CPU per dab (max {:.2}), {:.0} points each, visible after {:.0} ms (max {:.0}, {} dabs that changed points); picker {:.0} ms",
                    scene.name,
                    b.dabs,
                    b.radius_px,
                    b.cpu_ms_median,
                    b.cpu_ms_max,
                    b.points_per_dab_mean,
                    b.visible_ms_median,
                    b.visible_ms_max,
                    b.visible_dabs,
                    b.picker_ms
                );
                eprintln!(
                    "{} brush: after the stroke, converged in {:.0} ms; volume, grid and multiple scattering followed in {:.0} ms (single scattering kept: {}; per pass {:.0?})",
                    scene.name,
                    b.stroke_converged_ms,
                    b.follow_up_ms,
                    b.follow_up_kept_single,
                    b.follow_up_pass_ms
                );
                Some(b)
            } else {
                None
            };
            Some(ProgressiveReport {
                unit_budget_ms: budget.as_secs_f64() * 1e3,
                preview_factor: renderer.preview_factor(),
                units: stats.units,
                longest_unit_ms: stats.longest.as_secs_f64() * 1e3,
                longest_unit: stats
                    .longest_unit
                    .map_or_else(String::new, |u| format!("{u:?}")),
                pass_ms: UNIT_PASSES
                    .iter()
                    .zip(stats.pass_time)
                    .map(|(&name, t)| (name, t.as_secs_f64() * 1e3))
                    .collect(),
                preview_ms: run.preview_ms,
                first_pass_ms,
                image_converged_ms: run.image_converged_ms,
                converged_ms: run.converged_ms,
                edits,
                brush,
            })
        };
        reports.push(SceneReport {
            scene,
            segments: hair.point_count() - hair.strand_count(),
            shadows: !args.no_shadows,
            multiple_scattering: !args.single_scattering,
            segment_shading: !args.per_fragment,
            frames: args.frames,
            cpu_seconds: cpu,
            gpu_ms_median: per_pass.into_iter().map(|(k, v)| (k, median(v))).collect(),
            gpu_ms_total_min: totals.iter().copied().fold(f64::INFINITY, f64::min),
            gpu_ms_total_median: median(totals),
            wall_ms_median: median(walls),
            shaded_points,
            fragments,
            visible_segments,
            ms_points,
            shading_us_per_light_per_point,
            shadow_grid_wall_ms,
            shadow_grid_wall_ms_min,
            progressive,
        });
    }
    let json = serde_json::to_string_pretty(&Report {
        adapter: ctx.summary.clone(),
        scenes: reports,
    })?;
    println!("{json}");
    if let Some(o) = &args.output {
        std::fs::write(o, &json).with_context(|| format!("writing {}", o.display()))?;
    }
    Ok(())
}
