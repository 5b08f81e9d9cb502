//! The path-traced reference (`--reference=path`): a white furnace with lossless hair (every order of
//! scattering traced: the mean radiance is 1 up to what the kernel itself loses, and radiance plus the
//! estimated loss is 1), its depth study, and the GPU renderer against it on blond and brown bobs
//! under the project's sunny and studio environments.
#![allow(clippy::needless_range_loop)]

mod common;

use std::path::{Path, PathBuf};
use std::time::Instant;
use strandlight::envmap::{EnvMap, SrbfLight, SrbfSet, load_env};
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::hair::Hair;
use strandlight::render::reference::path_trace::{
    PathTraceSettings, path_trace_frame, path_trace_frame_with_stats,
};
use strandlight::render::reference::{ReferenceLighting, ReferenceScene};
use strandlight::render::{Camera, Frame, HairLook, RenderSettings};
use strandlight::scattering::lut::Luts;
use strandlight::scattering::params::Preset;

fn context() -> GpuContext {
    let ctx = GpuContext::new_headless(&GpuOptions::from_env()).expect("a GPU adapter (lavapipe)");
    println!("adapter: {} ({})", ctx.summary.name, ctx.summary.backend);
    ctx
}

/// Strands of the furnace's clump and bob, and its paths per point (cheap: most of the time goes into
/// the 1024 light samples per point, computed once).
const CLUMP_STRANDS: usize = 3000;
const BOB_STRANDS: usize = 1500;
const FURNACE_SPP: u32 = 64;

fn envmaps() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("envmaps")
}

/// What one furnace run measured.
struct Furnace {
    mean: [f64; 3],
    deficit: [f64; 3],
    single: [f64; 3],
}

/// Lossless `hair` in a uniform white environment (1024 directions per point), path traced with every
/// order and with single scattering only; prints the mean per depth cut-off.
fn furnace(
    ctx: &GpuContext,
    luts: &Luts,
    name: &str,
    hair: &Hair,
    camera: &Camera,
    render_settings: &RenderSettings,
) -> Furnace {
    let mut params = Preset::Blond.params();
    params.sigma_a = [0.0; 3];
    let look = HairLook::new(params);
    let sigma_a = vec![[0.0f32; 3]; hair.point_count()];
    // The renderer only supplies the visible points here: any light will do.
    let light = SrbfLight {
        direction: [0.0, 1.0, 0.0],
        lambda: 1.0,
        rgb: [1.0; 3],
    };
    let frame = common::render_uniform(
        ctx,
        render_settings,
        luts,
        hair,
        &look,
        std::slice::from_ref(&light),
        camera,
    )
    .0;
    let (env, _) = EnvMap::new(64, 32, vec![[1.0; 3]; 64 * 32], Path::new("white")).expect("env");
    let max_depth = 64;
    let settings = PathTraceSettings {
        samples_per_pixel: FURNACE_SPP,
        max_depth,
        seed: 1,
    };
    let scene = |s| ReferenceScene {
        hair,
        sigma_a: &sigma_a,
        look: &look,
        lighting: ReferenceLighting::Environment {
            env: &env,
            yaw: 0.0,
            directions: 1024,
        },
        settings: s,
        camera,
    };
    let full = RenderSettings {
        multiple_scattering: true,
        ..render_settings.clone()
    };
    let t = Instant::now();
    let (traced, stats) = path_trace_frame_with_stats(&frame, &scene(&full), &settings);
    let mean = common::mean_radiance(&traced);
    let deficit = stats.furnace_deficit;
    println!(
        "{name}: full transport (max depth {max_depth}, {} spp): mean radiance {mean:.4?} over {} hair pixels, MS share {:.3}; \
         furnace deficit {deficit:.4?}, radiance + deficit {:.4} ({:.1} s)",
        settings.samples_per_pixel,
        traced.covered().count(),
        common::ms_share(&traced),
        mean[1] + deficit[1],
        t.elapsed().as_secs_f64()
    );
    let orders = &stats.orders;
    let total: f64 = orders.iter().map(|o| o[1]).sum();
    let mut cumulative = 0.0;
    let mut line = String::new();
    for (d, o) in orders.iter().enumerate() {
        cumulative += o[1];
        if d <= 24 || d % 8 == 0 {
            line += &format!(
                " D={d}: {cumulative:.4} ({:+.2}%);",
                100.0 * (cumulative / total - 1.0)
            );
        }
    }
    println!("   mean (G) with the depth cut-off at D (change from D = {max_depth}):{line}");
    let single_settings = RenderSettings {
        multiple_scattering: false,
        ..render_settings.clone()
    };
    let t = Instant::now();
    let single = common::mean_radiance(&path_trace_frame(
        &frame,
        &scene(&single_settings),
        &settings,
    ));
    println!(
        "   single scattering with shadows: mean radiance {single:.4?} ({:.1} s)",
        t.elapsed().as_secs_f64()
    );
    Furnace {
        mean,
        deficit,
        single,
    }
}

/// Lossless hair (sigma_a = 0) in a uniform white environment is invisible: every order of scattering
/// traced, the mean radiance of a bob is 1 +- 3 %. A dense clump (3000 fibers in 4 x 2 cm, ~20 % of
/// the environment seen directly) compounds the kernel's own energy loss (its albedo is ~0.99 near
/// normal incidence but falls to ~0.65-0.9 at grazing inclinations, where the three lobes miss what
/// p >= 3 would carry) over ~10 bounces: there only the closure radiance + deficit = 1 is asserted,
/// which holds whatever the kernel's albedo. Prints the mean per depth cut-off (the study behind
/// [`strandlight::render::reference::path_trace::DEFAULT_MAX_DEPTH`]) and single scattering with shadows.
#[test]
fn white_furnace_lossless_hair() {
    let t0 = Instant::now();
    let ctx = context();
    let luts = Luts::default_tables();
    let bob = common::bob_scene(BOB_STRANDS, 64, 48, Preset::Blond.params(), true);
    let b = furnace(
        &ctx,
        &luts,
        &format!("bob ({BOB_STRANDS} strands)"),
        &bob.hair,
        &bob.camera,
        &bob.settings,
    );
    let hair = common::clump(CLUMP_STRANDS, 1);
    let (lo, hi) = hair.bounds();
    let camera = Camera::framing(lo, hi, 0.0, 0.0, 0.75, 0.95);
    let settings = RenderSettings {
        width: 36,
        height: 48,
        shadows: true,
        multiple_scattering: true,
        ..Default::default()
    };
    let c = furnace(
        &ctx,
        &luts,
        &format!("clump ({CLUMP_STRANDS} strands)"),
        &hair,
        &camera,
        &settings,
    );
    println!("test time {:.1} s", t0.elapsed().as_secs_f64());
    for f in [&b, &c] {
        for ch in 0..3 {
            let closure = f.mean[ch] + f.deficit[ch];
            assert!(
                (closure - 1.0).abs() <= 0.02,
                "radiance + deficit {closure} (channel {ch}) is not 1 +- 2%"
            );
        }
        assert!(f.single[1] < f.mean[1], "multiple scattering adds light");
    }
    for ch in 0..3 {
        assert!(
            (b.mean[ch] - 1.0).abs() <= 0.03,
            "bob furnace mean {:?} (channel {ch}) is not 1 +- 3%",
            b.mean
        );
    }
    assert!(c.single[1] < 0.5, "the clump shadows itself");
}

/// Renderer (SRBF, GPU) against the path tracer on a sparse (300-strand) and a denser (1500-strand) bob
/// (64x48), blond and brown, under the project's sunny and studio environments: relative error of the
/// mean colour per channel and the MS share of both, for single scattering with shadows (the R + TT +
/// TRT components of both frames: the renderer's are its shadowed single scattering, the path tracer's
/// its order 0 with shadow rays) and full transport (the beauty).
///
/// Asserted: full transport within 10 % everywhere. Single scattering within 5 % on the sparse bob
/// and 10 % on the denser one, where the fiber-density volume's shadows are lighter than the
/// explicit fibers' in sunny light (measured +9 % blond, +8 % brown). Measured (d_f = d_b =
/// 0.7): full transport within 2 % on the sparse bob and 5 % on the denser one; the renderer's MS share
/// is about half the path tracer's on both (0.024 / 0.045 and 0.089 / 0.165 blond sunny), which the
/// lighter shadows offset on the denser bob.
#[test]
fn renderer_is_close_to_the_path_tracer_on_bobs() {
    let t0 = Instant::now();
    let ctx = context();
    let luts = Luts::default_tables();
    let settings = PathTraceSettings {
        samples_per_pixel: 32,
        ..Default::default()
    };
    let mut worst_single = [0.0f64; 2];
    let mut worst_full = [[0.0f64; 2]; 2];
    println!(
        "{:<7} {:<6} {:<7} {:<6} {:>26} {:>26} {:>24} {:>15}",
        "strands",
        "hair",
        "env",
        "light",
        "renderer mean",
        "path tracer mean",
        "relative error",
        "MS share"
    );
    for (b, strands) in [300, 1500].into_iter().enumerate() {
        for (h, preset) in [Preset::Blond, Preset::Brown].into_iter().enumerate() {
            for name in ["sunny", "studio"] {
                let lights =
                    SrbfSet::read(&envmaps().join(format!("{name}.srbf.json"))).expect("fit");
                let (env, _) = load_env(&envmaps().join(format!("{name}.exr"))).expect("env");
                let t = Instant::now();
                let scene = common::bob_scene(strands, 64, 48, preset.params(), true);
                let frame = scene.render(&ctx, &luts, &lights.lights);
                let t_gpu = t.elapsed().as_secs_f64();
                let t = Instant::now();
                let traced =
                    path_trace_frame(&frame, &scene.reference(&env, lights.yaw), &settings);
                let t_path = t.elapsed().as_secs_f64();
                for (what, single) in [("single", true), ("full", false)] {
                    let mean = |f: &Frame| {
                        if single {
                            common::mean_components(f, 0..3)
                        } else {
                            common::mean_radiance(f)
                        }
                    };
                    let (m, r) = (mean(&frame), mean(&traced));
                    let err: [f64; 3] = std::array::from_fn(|c| m[c] / r[c] - 1.0);
                    let share = if single {
                        String::new()
                    } else {
                        format!(
                            "{:.3} / {:.3}",
                            common::ms_share(&frame),
                            common::ms_share(&traced)
                        )
                    };
                    println!(
                        "{:<7} {:<6} {:<7} {:<6} {:>26} {:>26} {:>24} {:>15}",
                        strands,
                        format!("{preset:?}"),
                        name,
                        what,
                        format!("{m:.4?}"),
                        format!("{r:.4?}"),
                        format!("{err:+.3?}"),
                        share
                    );
                    for e in err {
                        let e = e.abs();
                        if single {
                            worst_single[b] = worst_single[b].max(e);
                        } else {
                            worst_full[b][h] = worst_full[b][h].max(e);
                        }
                    }
                }
                println!(
                    "   ({} hair pixels; GPU render {t_gpu:.1} s, path tracer {t_path:.1} s)",
                    frame.covered().count()
                );
            }
        }
    }
    println!(
        "worst mean-colour error: single scattering {:.1}% (300 strands, limit 5%), {:.1}% (1500, limit 10%); \
         full transport blond {:.1}% / {:.1}%, brown {:.1}% / {:.1}% (300 / 1500 strands, limit 10%); test time {:.1} s",
        100.0 * worst_single[0],
        100.0 * worst_single[1],
        100.0 * worst_full[0][0],
        100.0 * worst_full[1][0],
        100.0 * worst_full[0][1],
        100.0 * worst_full[1][1],
        t0.elapsed().as_secs_f64()
    );
    assert!(
        worst_single[0] <= 0.05 && worst_single[1] <= 0.10,
        "single scattering off by {worst_single:?}"
    );
    for (b, strands) in [300, 1500].into_iter().enumerate() {
        for (h, hair) in ["blond", "brown"].into_iter().enumerate() {
            assert!(
                worst_full[b][h] <= 0.10,
                "{hair} full transport on the {strands}-strand bob off by {}",
                worst_full[b][h]
            );
        }
    }
}
