//! The renderer's white furnace: lossless hair (sigma_a = 0) in a uniform white environment
//! must render at the environment's radiance, not at twice it. The environment is a uniform white map
//! fitted with the project's SRBF fit, as a user would load it; the renderer runs on the adapter
//! (lavapipe in CI). Run with `--nocapture` for the table.

mod common;

use glam::DVec3;
use std::path::Path;
use strandlight::envmap::EnvMap;
use strandlight::envmap::fit::{FitOptions, fit_srbf};
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::render::Frame;
use strandlight::scattering::LongitudinalModel;
use strandlight::scattering::lut::Luts;
use strandlight::scattering::params::Preset;

/// Mean and extremes of the SRBF reconstruction over a Fibonacci sphere of directions.
fn reconstruction_stats(set: &strandlight::envmap::SrbfSet) -> (f64, f64, f64) {
    let n = 4000;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let (mut sum, mut lo, mut hi) = (0.0, f64::MAX, f64::MIN);
    for k in 0..n {
        let y = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
        let r = (1.0 - y * y).sqrt();
        let phi = golden * k as f64;
        let l = set.radiance(DVec3::new(r * phi.cos(), y, r * phi.sin()))[1];
        sum += l;
        lo = lo.min(l);
        hi = hi.max(l);
    }
    (sum / n as f64, lo, hi)
}

#[test]
fn lossless_hair_disappears_in_a_white_furnace() {
    let start = std::time::Instant::now();
    let ctx = GpuContext::new_headless(&GpuOptions::from_env()).expect("a GPU adapter (lavapipe)");
    println!("adapter: {} ({})", ctx.summary.name, ctx.summary.backend);
    let luts = Luts::default_tables();
    let (env, _) = EnvMap::new(64, 32, vec![[1.0; 3]; 64 * 32], Path::new("white.exr"))
        .expect("a uniform map");
    let set = fit_srbf(&env, &FitOptions::default(), |_| {}).expect("fit");
    let (mean_env, lo, hi) = reconstruction_stats(&set);
    println!(
        "uniform white map, {} SRBF lights: reconstruction mean {mean_env:.4}, min {lo:.4}, max {hi:.4}",
        set.lights.len()
    );
    assert!((mean_env - 1.0).abs() < 0.02, "the fit's mean {mean_env}");

    let mut params = Preset::Blond.params();
    params.sigma_a = [0.0; 3];
    let furnace = |multiple: bool, shadows: bool, d: f32, longitudinal| -> [f64; 3] {
        let mut s = common::bob_scene(600, 80, 60, params, multiple);
        s.settings.shadows = shadows;
        s.look = s.look.with_dual(d, d).with_longitudinal(longitudinal);
        let frame: Frame = s.render(&ctx, &luts, &set.lights);
        common::mean_radiance(&frame).map(|m| m / mean_env)
    };
    let ss = furnace(false, false, 0.7, LongitudinalModel::Normalized);
    let ss_shadows = furnace(false, true, 0.7, LongitudinalModel::Normalized);
    let full_07 = furnace(true, true, 0.7, LongitudinalModel::Normalized);
    let full_10 = furnace(true, true, 1.0, LongitudinalModel::Normalized);
    let published_ss = furnace(false, false, 0.7, LongitudinalModel::Published);
    let published_full = furnace(true, true, 0.7, LongitudinalModel::Published);
    println!("mean radiance of the hair / the environment's (expected <= 1, full transport = 1):");
    for (name, v) in [
        ("single scattering, no shadows", ss),
        ("single scattering, shadows", ss_shadows),
        ("single + dual, shadows, d_f = d_b = 0.7", full_07),
        ("single + dual, shadows, d_f = d_b = 1.0", full_10),
        ("published M: single scattering, no shadows", published_ss),
        ("published M: single + dual, shadows, 0.7", published_full),
    ] {
        println!("  {name:45} {:.4} {:.4} {:.4}", v[0], v[1], v[2]);
    }
    for c in 0..3 {
        assert!(
            (ss[c] - 1.0).abs() <= 0.03,
            "single scattering without shadows: {} not within 1 +- 3 %",
            ss[c]
        );
        assert!(
            (0.8..=1.1).contains(&full_07[c]),
            "single + dual scattering with shadows at d = 0.7: {} outside [0.8, 1.1]",
            full_07[c]
        );
        assert!(ss_shadows[c] < ss[c], "shadows remove light");
        assert!(full_10[c] > full_07[c], "d_f = d_b = 1 returns more light");
        assert!(
            published_ss[c] > 1.5 && published_full[c] > 1.5,
            "the published form is about twice too bright"
        );
    }
    println!("furnace: {:.1} s", start.elapsed().as_secs_f64());
}
