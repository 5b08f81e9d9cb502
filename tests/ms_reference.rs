//! The multiple-scattering reference (Zinke's ray shooting through the explicit fibers) and the
//! renderer's dual scattering against it on a blond clump lit from the front, the side and the back.
#![allow(clippy::needless_range_loop)]

mod common;

use glam::{DVec3, Vec3};
use strandlight::envmap::SrbfLight;
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::render::reference::{
    REFERENCE_VARIANT, ReferenceLighting, ReferenceScene, reference_frame, sample_srbf_lights,
};
use strandlight::render::{Camera, Frame, HairLook, RenderSettings};
use strandlight::scattering::lut::Luts;
use strandlight::scattering::params::Preset;
use strandlight::shadow::DensityPyramid;
use strandlight::shadow::fiber_density::FiberDensity;
use strandlight::shadow::fiber_grid::FiberGrid;
use strandlight::shadow::forward::{ForwardTable, forward_scattering};
use strandlight::shadow::ray_shooting::shoot_forward;

/// Uniform numbers from a seeded PCG.
#[test]
fn fiber_grid_finds_every_crossing_that_brute_force_finds() {
    let hair = common::clump(600, 3);
    let sigma = vec![[0.1f32; 3]; hair.point_count()];
    let grid = FiberGrid::build(&hair, &sigma);
    let mut rng = common::Uniform::new(9);
    let (mut total, mut rays) = (0usize, 0usize);
    for _ in 0..400 {
        let o = Vec3::new(
            rng.random_range(-2.0..2.0),
            rng.random_range(-4.0..4.0),
            rng.random_range(-1.0..1.0),
        );
        let d = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::Z);
        let mut fast: Vec<u32> = Vec::new();
        grid.crossings(o, d, 0.0, |x| fast.push(x.segment));
        let mut brute: Vec<u32> = (0..grid.segments.len() as u32)
            .filter(|&k| grid.intersect(k, o, d).is_some_and(|(t, _)| t > 0.0))
            .collect();
        fast.sort_unstable();
        brute.sort_unstable();
        assert_eq!(fast, brute, "ray from {o} along {d}");
        total += brute.len();
        rays += 1;
    }
    println!("{rays} rays, {total} crossings, all found once by the grid walk");
    assert!(total > 200, "the rays cross fibers");
}

#[test]
fn srbf_samples_carry_the_lobe_power_and_follow_its_shape() {
    let light = SrbfLight {
        direction: [0.0, 0.6, 0.8],
        lambda: 0.3,
        rgb: [1.0, 2.0, 3.0],
    };
    let samples = sample_srbf_lights(&[light], 1024, 1);
    let power: [f64; 3] = std::array::from_fn(|c| samples.iter().map(|s| s.weight[c]).sum::<f64>());
    // Mean cosine to the centre: E[cos] = coth(2 kappa) - 1 / kappa for the vMF of kappa = 2 / lambda^2.
    let kappa = 2.0 / (light.lambda * light.lambda);
    let expected = 1.0 / (2.0 * kappa).tanh() - 1.0 / kappa;
    let mean_cos = samples
        .iter()
        .map(|s| s.direction.dot(light.dir()))
        .sum::<f64>()
        / samples.len() as f64;
    println!(
        "power {power:?} vs {:?}; mean cos {mean_cos:.6} vs {expected:.6}",
        light.power()
    );
    for c in 0..3 {
        assert!((power[c] / light.power()[c] - 1.0).abs() < 1e-9);
    }
    assert!((mean_cos - expected).abs() < 1e-4);
    let mean_dir: DVec3 = samples
        .iter()
        .map(|s| s.direction)
        .sum::<DVec3>()
        .normalize();
    assert!(mean_dir.dot(light.dir()) > 0.99999);
}

/// The volume's Poisson model of crossings (direct fraction exp(-tau), T_f = exp(-integral c (1 - a_f) ds))
/// against the fibers a ray actually crosses (free rays, mean of prod a_f), averaged over rays from
/// points inside a blond clump, for three directions.
#[test]
fn volume_direct_fraction_matches_the_fraction_of_free_rays() {
    let hair = common::clump(3000, 5);
    let params = Preset::Blond.params();
    let sigma = vec![params.sigma_a.map(|s| s as f32); hair.point_count()];
    let grid = FiberGrid::build(&hair, &sigma);
    let volume = FiberDensity::build(&hair, &sigma, 0.0625);
    let pyramid = DensityPyramid::build(&volume);
    let table = ForwardTable::build(&params, REFERENCE_VARIANT);
    let mut rng = common::Uniform::new(11);
    for (name, dir, normal) in [
        ("front", Vec3::new(0.0, 0.3, 1.0).normalize(), Vec3::Z),
        ("side", Vec3::new(1.0, 0.3, 0.0).normalize(), Vec3::X),
        ("back", Vec3::new(0.0, 0.3, -1.0).normalize(), -Vec3::Z),
    ] {
        // Points 0.1..1.5 cm under the lit face (x = 2 or z = +-1), away from the clump's edges.
        let (mut free, mut expected, n) = (0.0f64, 0.0f64, 4000);
        let (mut tf_rays, mut tf_vol) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..n {
            let depth = rng.random_range(0.1..1.5);
            let y = rng.random_range(-2.0..2.0);
            let p = if normal.x != 0.0 {
                Vec3::new(2.0 - depth, y, rng.random_range(-0.8..0.8))
            } else {
                Vec3::new(rng.random_range(-1.6..1.6), y, normal.z * (1.0 - depth))
            };
            let f = shoot_forward(&grid, &table, p, dir, u32::MAX);
            free += f.direct_fraction as f64;
            expected += volume.transmittance(p, dir, 0.0) as f64;
            let v = forward_scattering(&pyramid, &volume, &table, p, dir, 0.0, 0.0);
            for c in 0..3 {
                tf_rays[c] += f.transmittance_f[c] as f64 / n as f64;
                tf_vol[c] += v.transmittance_f[c] as f64 / n as f64;
            }
        }
        let (free, expected) = (free / n as f64, expected / n as f64);
        println!(
            "{name}: fraction of free rays {free:.4}, volume exp(-tau) {expected:.4} ({:+.1}%)",
            100.0 * (expected / free - 1.0)
        );
        let tf_err: [f64; 3] = std::array::from_fn(|c| tf_vol[c] / tf_rays[c] - 1.0);
        println!("   T_f: rays {tf_rays:.4?}, volume march {tf_vol:.4?} ({tf_err:+.3?})");
        assert!(free > 0.05 && free < 0.95, "a partly shadowed layer");
        assert!((expected / free - 1.0).abs() < 0.15);
        assert!(tf_err.iter().all(|e| e.abs() < 0.15), "T_f {tf_err:?}");
    }
}

/// Mean over covered pixels of the beauty (None) or of the MS components' sum (Some(())), RGB.
fn mean(f: &Frame, ms_only: bool) -> [f64; 3] {
    let n = f.covered().count().max(1) as f64;
    std::array::from_fn(|c| {
        f.covered()
            .map(|i| {
                if ms_only {
                    (f.components[3][i][c] + f.components[4][i][c]) as f64
                } else {
                    f.beauty[i][c] as f64
                }
            })
            .sum::<f64>()
            / n
    })
}

/// sqrt(sum |a - b|^2 / sum |b|^2) of the MS components' sum over covered pixels and channels.
fn ms_rmse(a: &Frame, b: &Frame) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for i in b.covered() {
        for c in 0..3 {
            let x = (a.components[3][i][c] + a.components[4][i][c]) as f64;
            let y = (b.components[3][i][c] + b.components[4][i][c]) as f64;
            num += (x - y) * (x - y);
            den += y * y;
        }
    }
    (num / den.max(1e-30)).sqrt()
}

#[test]
fn dual_scattering_matches_the_ray_shooting_reference_on_a_blond_clump() {
    let ctx = GpuContext::new_headless(&GpuOptions::from_env()).expect("a GPU adapter (lavapipe)");
    let luts = Luts::default_tables();
    let hair = common::clump(3000, 1);
    let look = HairLook::new(Preset::Blond.params());
    let (lo, hi) = hair.bounds();
    let camera = Camera::framing(lo, hi, 0.0, 0.0, 0.75, 0.95);
    let settings = RenderSettings {
        width: 48,
        height: 64,
        shadows: true,
        multiple_scattering: true,
        // Every fragment shaded at its own point; by segment (the default) below.
        segment_shading: false,
        ..Default::default()
    };
    let sigma_a = vec![look.fast.sigma_a_rgb(); hair.point_count()];
    let (mut worst, mut worst_segment) = (0.0f64, 0.0f64);
    for (name, dir) in [
        ("front", [0.0, 0.3, 1.0]),
        ("side", [1.0, 0.3, 0.0]),
        ("back", [0.0, 0.3, -1.0]),
    ] {
        let light = SrbfLight {
            direction: DVec3::from_array(dir).normalize().to_array(),
            lambda: 0.1,
            rgb: [30.0; 3],
        };
        let t = std::time::Instant::now();
        let frame = common::render_uniform(
            &ctx,
            &settings,
            &luts,
            &hair,
            &look,
            std::slice::from_ref(&light),
            &camera,
        )
        .0;
        let t_gpu = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let reference = reference_frame(
            &frame,
            &ReferenceScene {
                hair: &hair,
                sigma_a: &sigma_a,
                look: &look,
                lighting: ReferenceLighting::Directional(sample_srbf_lights(&[light], 64, 3)),
                settings: &settings,
                camera: &camera,
            },
        );
        let t_ref = t.elapsed().as_secs_f64();
        // The same frame shaded by segment (`segment_shading`, the default).
        let (by_segment, shaded_by_segment) = common::render_uniform(
            &ctx,
            &RenderSettings {
                segment_shading: true,
                ..settings.clone()
            },
            &luts,
            &hair,
            &look,
            std::slice::from_ref(&light),
            &camera,
        );
        assert!(shaded_by_segment, "the view shades the clump per fragment");
        let component_means = |f: &Frame| -> Vec<f64> {
            let n = f.covered().count().max(1) as f64;
            (0..5)
                .map(|t| {
                    f.covered()
                        .map(|i| f.components[t][i][1] as f64)
                        .sum::<f64>()
                        / n
                })
                .collect()
        };
        println!(
            "  G per component (R, TT, TRT, MS.global, MS.local): per fragment {:.5?}, by segment {:.5?}, reference {:.5?}",
            component_means(&frame),
            component_means(&by_segment),
            component_means(&reference)
        );
        let (m, r) = (mean(&frame, false), mean(&reference, false));
        let (ms, msr) = (mean(&frame, true), mean(&reference, true));
        let err: [f64; 3] = std::array::from_fn(|c| m[c] / r[c] - 1.0);
        let rmse = ms_rmse(&frame, &reference);
        println!(
            "{name} light: mean colour SRBF {m:.4?} vs reference {r:.4?}, relative error {err:+.3?}; \
             MS mean {ms:.4?} vs {msr:.4?}, MS-only relative RMSE {:.1}% ({} pixels; GPU {t_gpu:.1} s, reference {t_ref:.1} s)",
            100.0 * rmse,
            frame.covered().count()
        );
        assert!(
            msr.iter().sum::<f64>() > 0.1 * r.iter().sum::<f64>(),
            "MS matters here"
        );
        let s = mean(&by_segment, false);
        let err_segment: [f64; 3] = std::array::from_fn(|c| s[c] / r[c] - 1.0);
        println!("  shaded by segment: mean colour {s:.4?}, relative error {err_segment:+.3?}");
        for e in err {
            worst = worst.max(e.abs());
        }
        for e in err_segment {
            worst_segment = worst_segment.max(e.abs());
        }
    }
    println!(
        "worst mean-colour error {:.1}% ({:.1}% shaded by segment)",
        100.0 * worst,
        100.0 * worst_segment
    );
    assert!(worst <= 0.15, "mean colour off by {:.1}%", 100.0 * worst);
    assert!(
        worst_segment <= 0.15,
        "shaded by segment, mean colour off by {:.1}%",
        100.0 * worst_segment
    );
}
