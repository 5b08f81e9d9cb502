//! `strandlight render` end to end (lavapipe in CI).

mod common;

use std::process::Command;

fn strandlight() -> Command {
    common::strandlight_command()
}

fn tmp(name: &str) -> std::path::PathBuf {
    common::temp_file("cli-render", name)
}

#[test]
fn render_writes_a_linear_exr_with_attributes_aovs_and_a_png() {
    let (exr, png) = (tmp("still.exr"), tmp("preview.png"));
    let out = strandlight()
        .args([
            "render",
            "--strands",
            "300",
            "--points",
            "10",
            "--width",
            "48",
            "--height",
            "32",
        ])
        .args([
            "--preset",
            "blond",
            "--camera",
            "side",
            "--aovs",
            "--no-shadows",
            "-o",
        ])
        .arg(&exr)
        .arg("--png")
        .arg(&png)
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stderr}");
    assert!(out.status.success(), "{stderr}");
    use exr::prelude::ReadChannels;
    use exr::prelude::ReadLayers;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(&exr)
        .expect("a readable EXR");
    let layer = &image.layer_data;
    let names: Vec<String> = layer
        .channel_data
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    println!("channels: {names:?}");
    for want in [
        "R",
        "G",
        "B",
        "A",
        "Z",
        "TT.R",
        "TRT.B",
        "MS.global.G",
        "MS.local.R",
    ] {
        assert!(names.iter().any(|n| n == want), "channel {want} missing");
    }
    let attrs: Vec<String> = layer
        .attributes
        .other
        .keys()
        .map(|k| k.to_string())
        .collect();
    println!("attributes: {attrs:?}");
    for want in [
        "strandlight.params",
        "strandlight.camera",
        "strandlight.environment",
    ] {
        assert!(attrs.iter().any(|a| a == want), "attribute {want} missing");
    }
    // Float samples, alpha = coverage in [0, 1], some hair, and R + TT + TRT = beauty.
    let get = |name: &str| -> Vec<f32> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == name)
            .expect("channel");
        match &c.sample_data {
            exr::prelude::FlatSamples::F32(v) => v.clone(),
            other => panic!("{name} is not float32: {other:?}"),
        }
    };
    let (r, a) = (get("R"), get("A"));
    // The generated hair's head is in the picture: its own layer.
    let lobes: Vec<Vec<f32>> = [
        "R.R",
        "TT.R",
        "TRT.R",
        "MS.global.R",
        "MS.local.R",
        "occluder.R",
    ]
    .iter()
    .map(|n| get(n))
    .collect();
    assert!(a.iter().all(|&x| (0.0..=1.0).contains(&x)));
    let covered = a.iter().filter(|&&x| x > 0.0).count();
    println!("{covered} of {} pixels covered", a.len());
    assert!(covered > 20);
    let mut worst = 0.0f32;
    for i in 0..r.len() {
        let sum: f32 = lobes.iter().map(|l| l[i]).sum();
        worst = worst.max((sum - r[i]).abs() / r[i].abs().max(1e-6));
    }
    println!("AOV sum vs beauty: worst relative difference {worst:.2e}");
    assert!(worst < 1e-5);
    let preview = image::open(&png).expect("a readable PNG").to_rgba8();
    assert_eq!(preview.dimensions(), (48, 32));
}

#[test]
fn render_reports_bad_input_without_panicking() {
    let cases: [&[&str]; 4] = [
        &["render", "--width", "0", "-o", "x.exr"],
        &["render", "--camera", "nowhere", "-o", "x.exr"],
        &["render", "--samples", "3", "--strands", "10", "-o", "x.exr"],
        &["render", "--env", "/nonexistent/sky.hdr", "-o", "x.exr"],
    ];
    for args in cases {
        let out = strandlight().args(args).output().expect("runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        println!("{args:?}: {}", stderr.trim());
        assert!(!out.status.success());
        assert!(stderr.contains("error:"));
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

/// `--tile` renders the same still tile by tile (an off-centre narrowing of the projection per tile).
#[test]
fn a_tiled_render_equals_the_untiled_one() {
    let render = |name: &str, tile: Option<&str>| -> Vec<f32> {
        let exr = tmp(name);
        let mut c = strandlight();
        c.args([
            "render",
            "--style",
            "bob",
            "--strands",
            "400",
            "--points",
            "8",
            "--width",
            "150",
            "--height",
            "100",
            "--shadow-grid",
            "16",
            "--volume-resolution",
            "48",
            // The environment behind, looked up per tile through each tile's camera.
            "--background",
            "env",
            "-o",
        ])
        .arg(&exr);
        if let Some(t) = tile {
            c.args(["--tile", t]);
        }
        let out = c.output().expect("runs");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        common::read_exr_channels(&exr, &["coverage", "B", "G", "R"]).concat()
    };
    let whole = render("untiled.exr", None);
    let tiled = render("tiled.exr", Some("64"));
    let peak = whole.iter().copied().fold(1e-6f32, f32::max);
    let diffs: Vec<f32> = whole
        .iter()
        .zip(&tiled)
        .map(|(a, b)| (a - b).abs() / peak)
        .collect();
    let max = diffs.iter().copied().fold(0.0f32, f32::max);
    let mean = diffs.iter().sum::<f32>() / diffs.len() as f32;
    let off = diffs.iter().filter(|&&d| d > 1e-3).count();
    println!(
        "150x100 in 64-pixel tiles against untiled: max {max:.2e}, mean {mean:.2e} of the peak; \
         {off} of {} values differ by more than 1e-3 (visibility samples on a ribbon's edge round \
         differently in the narrowed projection)",
        diffs.len()
    );
    assert_eq!(whole.len(), tiled.len());
    assert!(
        mean < 1e-4 && off * 1000 < diffs.len(),
        "{max} {mean} {off}"
    );
}

/// The grooms Blender and Pixar's library wrote render, the hair covering part of the frame.
#[test]
fn usd_grooms_render() {
    let Some(data) = common::shared_data() else {
        return;
    };
    for (file, prim) in [
        ("hair/usd/ponytail_blender.usdc", None),
        ("hair/usd/ponytail_usdcore.usda", Some("/Groom/hair")),
    ] {
        let exr = tmp(&format!("{}.exr", file.replace('/', "_")));
        let mut c = strandlight();
        c.args(["render", "--hair"])
            .arg(data.join(file))
            .args(["--width", "48", "--height", "48", "-o"])
            .arg(&exr);
        if let Some(p) = prim {
            c.args(["--hair-prim", p]);
        }
        let out = c.output().expect("runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{file}: {stderr}");
        // The ponytail is 4933 guide strands of 0.2 mm: thin, so coverage is partial.
        let alpha = &common::read_exr_channels(&exr, &["A"])[0];
        let touched = alpha.iter().filter(|a| **a > 0.02).count() as f64 / alpha.len() as f64;
        let mean = alpha.iter().sum::<f32>() / alpha.len() as f32;
        println!(
            "{file}: hair in {:.0} % of the pixels, mean coverage {mean:.3}",
            100.0 * touched
        );
        assert!(
            touched > 0.05 && mean > 0.01,
            "{file}: the groom is not in the frame"
        );
    }
}
