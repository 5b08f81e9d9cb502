//! `strandlight bench`: GPU time per pass (timestamp queries, median over frames after warm-up) for the
//! standard scenes S0-S3, plus the CPU time of their preprocessing, as JSON.

use super::bench_editor::{EditorBench, EditorReport, Times, editor_run};
use anyhow::{Context, bail};
use clap::Args;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;
use strandlight::envmap::{FitOptions, fit_srbf};
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::hair::procedural::Style;
use strandlight::render::reference::shade::ShadingHair;
use strandlight::render::renderer::table_cache;
use strandlight::render::scene::{StandardScene, default_environment};
use strandlight::render::{Camera, HairLook, RenderSettings, Renderer};
use strandlight::scattering::Preset;
use strandlight::scattering::lut::Luts;
use strandlight::session::{HairSource, Look, Session};

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scenes to run (S0, S1, S2, S3).
    #[arg(long, value_delimiter = ',', default_value = "S0,S1,S2,S3")]
    pub scenes: Vec<String>,
    /// Timed frames per scene (20 give stable medians on a GPU; software adapters may need fewer).
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
    /// Skip the editor's scenarios (the scene opened on the editor's live driver, a preset, an eta
    /// and a camera change, a brush stroke, each until converged).
    #[arg(long)]
    pub no_editor: bool,
    /// Skip `render --session` of each scene's session (the editor scenarios' yardstick).
    #[arg(long)]
    pub no_yardstick: bool,
    /// Brush dabs of the editor's stroke (each refined until it shows); 0 skips it.
    #[arg(long, default_value_t = 100)]
    pub dabs: usize,
    /// Run the editor's scenarios on this session too, after the scenes (`default`: the editor's
    /// first scene).
    #[arg(long)]
    pub session: Option<PathBuf>,
    /// The size `--session` is rendered at, WxH (default: the session's render size).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
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
    /// The scene's session in the editor's live driver (`--no-editor` skips it).
    #[serde(skip_serializing_if = "Option::is_none")]
    editor: Option<EditorReport>,
}

#[derive(Serialize)]
struct Report {
    adapter: strandlight::gpu::context::AdapterSummary,
    scenes: Vec<SceneReport>,
    /// The editor's scenarios on `--session`.
    #[serde(skip_serializing_if = "Option::is_none")]
    session: Option<EditorReport>,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    v[v.len() / 2]
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
    for name in args.scenes.iter().filter(|n| !n.is_empty()) {
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
        let editor = if args.no_editor {
            None
        } else {
            let session = scene_session(&scene, &args);
            let report = editor_run(&ctx, &luts, &session, &editor_options(&args, &session))?;
            print_editor(scene.name, &report);
            Some(report)
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
            editor,
        });
    }
    let session = match &args.session {
        Some(path) => {
            let mut s = if path.as_os_str() == "default" {
                Session::default()
            } else {
                let mut s = Session::read(path)?;
                s.load_paint()?;
                s
            };
            if let Some((w, h)) = args.size {
                s.render.width = w;
                s.render.height = h;
            }
            let luts = Luts::default_tables();
            let report = editor_run(&ctx, &luts, &s, &editor_options(&args, &s))?;
            print_editor("session", &report);
            Some(report)
        }
        None => None,
    };
    let json = serde_json::to_string_pretty(&Report {
        adapter: ctx.summary.clone(),
        scenes: reports,
        session,
    })?;
    println!("{json}");
    if let Some(o) = &args.output {
        std::fs::write(o, &json).with_context(|| format!("writing {}", o.display()))?;
    }
    Ok(())
}

/// The session the editor would have for a standard scene: its generated hair on the generated head
/// under the built-in sky, the brown preset, the default camera, the bench's render options.
fn scene_session(scene: &StandardScene, args: &BenchArgs) -> Session {
    let style = if matches!(scene.name, "S0" | "S1") {
        Style::Wavy
    } else {
        Style::StraightLong
    };
    // The standard scenes keep the renderer's own settings, not the first scene's art direction.
    let mut session = Session {
        look: Look::from_preset(Preset::Brown),
        ..Session::neutral(HairSource::generated(style, scene.strands, scene.points, 1))
    };
    session.render.width = scene.width;
    session.render.height = scene.height;
    session.render.shadows = !args.no_shadows;
    session.render.multiple_scattering = !args.single_scattering;
    session.occluder.show = !args.no_head;
    session
}

fn editor_options(args: &BenchArgs, session: &Session) -> EditorBench {
    EditorBench {
        size: (session.render.width, session.render.height),
        dabs: args.dabs,
        yardstick: !args.no_yardstick,
        software: args.software,
    }
}

fn print_editor(name: &str, r: &EditorReport) {
    let t = |t: &Times| {
        let f = |v: Option<f64>| v.map_or_else(|| "-".into(), |v| format!("{v:.0}"));
        format!(
            "first {} ms, sharp {} ms, converged {:.0} ms ({} units)",
            f(t.first_ms),
            f(t.sharp_ms),
            t.converged_ms,
            t.units
        )
    };
    eprintln!(
        "{name} editor {}x{}: open: {}",
        r.size[0],
        r.size[1],
        t(&r.open)
    );
    if let Some(y) = &r.yardstick {
        eprintln!(
            "{name} render --session: {:.0} ms process, {:.0} ms frame",
            y.process_ms, y.frame_ms
        );
    }
    eprintln!("{name} editor: preset: {}", t(&r.preset));
    eprintln!("{name} editor: eta: {}", t(&r.eta));
    eprintln!("{name} editor: camera: {}", t(&r.camera));
    eprintln!(
        "{name} editor: idle gap median {:.2} ms, p95 {:.2} ms ({} gaps)",
        r.idle_gap_ms_median, r.idle_gap_ms_p95, r.idle_gaps
    );
    if let Some(b) = &r.brush {
        eprintln!(
            "{name} editor: brush ready {:.0} ms after the stroke began; {} dabs visible after {:.0} ms (max {:.0}); converged {:.0} ms after the stroke",
            b.picker_ready_ms,
            b.visible_dabs,
            b.visible_ms_median,
            b.visible_ms_max,
            b.stroke_converged_ms
        );
    }
}

/// "WxH" as a size.
fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("a size is WxH, got '{text}'"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (16..=16384).contains(v))
            .ok_or_else(|| format!("a side is 16 to 16384 pixels, got '{v}'"))
    };
    Ok((parse(w)?, parse(h)?))
}
