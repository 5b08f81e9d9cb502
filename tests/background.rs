//! What shows behind the hair: the resolve's environment lookup against its CPU twin
//! (`BackgroundMap::radiance`) on lavapipe, turned by a yaw; the composite; and `render --background`
//! end to end (the PNG over the environment or a colour, transparent, and the EXR only when asked).

mod common;

use std::process::Command;
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::render::passes::background::{Background, BackgroundMap};
use strandlight::render::scene::default_environment;
use strandlight::scattering::lut::Luts;
use strandlight::scattering::params::HairParams;

#[test]
fn the_resolve_looks_the_environment_up_as_its_cpu_twin_does() {
    let ctx = GpuContext::new_headless(&GpuOptions::from_env()).expect("a GPU adapter (lavapipe)");
    let mut scene = common::bob_scene(200, 120, 80, HairParams::default(), false);
    scene.settings.shadows = false;
    scene.settings.exposure = 0.5;
    let env = default_environment();
    let map = BackgroundMap::from_environment(&env);
    let luts = Luts::default_tables();
    let mut renderer = strandlight::render::Renderer::new(
        &ctx,
        scene.settings.clone(),
        &luts,
        &scene.hair,
        &scene.sigma_a,
        &scene.look,
        &env.lights.lights,
        &scene.camera,
    )
    .expect("renderer");
    let (w, h) = (scene.settings.width, scene.settings.height);
    for yaw in [0.0f32, 1.3] {
        renderer.set_background(&ctx, Some(&map), yaw);
        renderer.render_frame(&ctx);
        let frame = renderer.read_frame(&ctx).expect("read back");
        assert_eq!(frame.background.len(), frame.pixel_count());
        let turned = BackgroundMap { yaw, ..map.clone() };
        let scale = scene.settings.exposure.exp2();
        let mut worst = 0.0f32;
        for y in 0..h {
            for x in 0..w {
                let (_, d) = scene.camera.ray(w, h, x as f32 + 0.5, y as f32 + 0.5);
                let want = turned.radiance(d).map(|v| v * scale);
                let got = frame.background[(y * w + x) as usize];
                for c in 0..3 {
                    worst = worst.max((got[c] - want[c]).abs() / want[c].abs().max(1e-3));
                }
            }
        }
        println!(
            "yaw {yaw}: GPU background against BackgroundMap::radiance, worst relative {worst:.2e}"
        );
        assert!(worst < 2e-3, "{worst}");
        // The composite: the environment where there is no hair, hair + (1 - alpha) background elsewhere.
        let over = frame.composited(Background::Environment);
        let mut partial = 0;
        for ((o, &[r, g, b, a]), bg) in over.iter().zip(&frame.beauty).zip(&frame.background) {
            assert_eq!(o[3], 1.0);
            for (c, v) in [r, g, b].into_iter().enumerate() {
                let want = v + (1.0 - a) * bg[c];
                assert!((o[c] - want).abs() <= 1e-6 * want.abs().max(1.0));
            }
            partial += (a > 0.0 && a < 1.0) as usize;
        }
        assert!(partial > 0, "no partly covered pixel to composite");
        assert_eq!(
            frame.composited(Background::Transparent),
            frame.beauty,
            "transparent leaves the beauty alone"
        );
    }
    // No map: nothing behind the hair, and nothing read back.
    renderer.set_background(&ctx, None, 0.0);
    renderer.render_frame(&ctx);
    let frame = renderer.read_frame(&ctx).expect("read back");
    assert!(frame.background.is_empty());
    assert_eq!(frame.composited(Background::Environment), frame.beauty);
}

fn strandlight() -> Command {
    common::strandlight_command()
}

fn tmp(name: &str) -> std::path::PathBuf {
    common::temp_file("background", name)
}

/// `render` of a small bob with extra arguments (outputs included).
fn render(extra: &[&std::ffi::OsStr]) {
    let out = strandlight()
        .args([
            "render",
            "--style",
            "bob",
            "--strands",
            "300",
            "--points",
            "8",
            "--width",
            "64",
            "--height",
            "48",
            "--no-shadows",
            "--single-scattering",
        ])
        .args(extra)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
}

#[test]
fn render_puts_the_hair_over_the_background_asked_for() {
    let os = |p: &std::path::Path| p.as_os_str().to_owned();
    // Default: the PNG over the environment, the EXR transparent.
    let (exr, png) = (tmp("default.exr"), tmp("default.png"));
    render(&[
        "-o".as_ref(),
        &os(&exr),
        "--png".as_ref(),
        &os(&png),
        "--aovs".as_ref(),
    ]);
    let c = common::read_exr_channels(&exr, &["R", "A"]);
    let empty: Vec<usize> = (0..c[1].len()).filter(|&i| c[1][i] == 0.0).collect();
    assert!(!empty.is_empty() && empty.iter().all(|&i| c[0][i] == 0.0));
    let picture = image::open(&png).expect("PNG").to_rgba8();
    let corner = picture.get_pixel(0, 0).0;
    println!("default PNG corner {corner:?}");
    assert_eq!(corner[3], 255, "the PNG is opaque over the environment");
    assert!(corner[2] > 40, "the sky shows in the corner: {corner:?}");
    // A colour: exactly that colour where there is no hair, in the PNG; the EXR over its linear value
    // with alpha 1, the coverage kept, and the layers still adding up to the beauty.
    let (exr, png) = (tmp("colour.exr"), tmp("colour.png"));
    render(&[
        "--background".as_ref(),
        "#336699".as_ref(),
        "-o".as_ref(),
        &os(&exr),
        "--png".as_ref(),
        &os(&png),
        "--aovs".as_ref(),
    ]);
    let picture = image::open(&png).expect("PNG").to_rgba8();
    assert_eq!(picture.get_pixel(0, 0).0, [0x33, 0x66, 0x99, 255]);
    let names = [
        "R",
        "A",
        "coverage",
        "background.R",
        "R.R",
        "TT.R",
        "TRT.R",
        "MS.global.R",
        "MS.local.R",
        "occluder.R",
    ];
    let c = common::read_exr_channels(&exr, &names);
    let linear = Background::linear_colour([0x33, 0x66, 0x99])[0];
    let mut worst = 0.0f32;
    let mut hair = 0;
    for i in 0..c[0].len() {
        assert_eq!(c[1][i], 1.0);
        let cov = c[2][i];
        assert!((c[3][i] - (1.0 - cov) * linear).abs() < 1e-6);
        let sum: f32 = c[3..].iter().map(|l| l[i]).sum();
        worst = worst.max((sum - c[0][i]).abs() / c[0][i].abs().max(1e-6));
        hair += (cov > 0.0) as usize;
    }
    println!(
        "colour background: {hair} covered pixels (hair and head); layers against the beauty: worst {worst:.2e}"
    );
    assert!(hair > 20 && worst < 1e-5);
    // Transparent: the PNG keeps the coverage as alpha.
    let png = tmp("transparent.png");
    render(&[
        "--background".as_ref(),
        "transparent".as_ref(),
        "--png".as_ref(),
        &os(&png),
    ]);
    let picture = image::open(&png).expect("PNG").to_rgba8();
    assert_eq!(picture.get_pixel(0, 0).0[3], 0);
    // A bad value is refused by name.
    let out = strandlight()
        .args(["render", "--background", "#12345", "--png"])
        .arg(tmp("never.png"))
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("#rrggbb"),
        "{stderr}"
    );
}

#[test]
fn lights_alone_show_their_reconstruction_behind_the_hair() {
    // The built-in sky's lights as a .srbf.json: no image, so the background is their reconstruction.
    let env = default_environment();
    let lights = tmp("sky.srbf.json");
    env.lights.write(&lights).expect("write lights");
    let exr = tmp("lights.exr");
    let os = |p: &std::path::Path| p.as_os_str().to_owned();
    render(&[
        "--env".as_ref(),
        &os(&lights),
        "--background".as_ref(),
        "env".as_ref(),
        "-o".as_ref(),
        &os(&exr),
    ]);
    let c = common::read_exr_channels(&exr, &["R", "G", "B", "coverage"]);
    // The scene that render assembled (the same session as its flags), for each pixel's direction.
    let (yaw, pitch) = strandlight::render::Camera::preset("three-quarter").expect("preset");
    let session = strandlight::session::Session {
        hair: strandlight::session::HairSource::generated(
            strandlight::hair::procedural::Style::Bob,
            300,
            8,
            1,
        ),
        environment: strandlight::session::EnvironmentSource::File {
            path: lights.clone(),
            lights: 40,
            blake3: None,
            fitted: None,
        },
        camera: strandlight::session::ViewCamera {
            yaw,
            pitch,
            fov_y: 30.0,
            target: None,
            distance: None,
        },
        render: strandlight::session::RenderOptions {
            width: 64,
            height: 48,
            ..Default::default()
        },
        ..strandlight::session::Session::neutral(strandlight::session::HairSource::generated(
            strandlight::hair::procedural::Style::Bob,
            300,
            8,
            1,
        ))
    };
    let scene = strandlight::session::Scene::assemble(&session).expect("the scene");
    let camera = scene.camera;
    let mut worst = 0.0f64;
    let mut checked = 0;
    for y in 0..48u32 {
        for x in 0..64u32 {
            let i = (y * 64 + x) as usize;
            if c[3][i] > 0.0 {
                continue;
            }
            let (_, d) = camera.ray(64, 48, x as f32 + 0.5, y as f32 + 0.5);
            let want = env.lights.radiance(d.as_dvec3());
            for k in 0..3 {
                worst = worst.max((c[k][i] as f64 - want[k]).abs() / want[k].max(1e-3));
            }
            checked += 1;
        }
    }
    println!("{checked} background pixels against the lights' radiance: worst relative {worst:.3}");
    assert!(checked > 1000 && worst < 0.05, "{worst}");
}
