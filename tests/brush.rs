//! The brush's picking against brute force: the points a dab touches (found from the frame's view
//! depth, read back from the GPU) against the same footprint computed on the CPU from every segment's
//! fragments in every pixel (brute force); paint-through, the root-to-tip mask and the mirror.

mod common;

use glam::Vec3;
use std::collections::BTreeSet;
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::paint::brush::{Brush, FRONT_DEPTH, Falloff};
use strandlight::paint::pick::{Picker, Projected, ViewDepth, project};
use strandlight::render::camera::CameraUniform;
use strandlight::scattering::Preset;
use strandlight::scattering::lut::Luts;

fn context() -> GpuContext {
    GpuContext::new_headless(&GpuOptions::from_env()).expect("a GPU adapter (lavapipe)")
}

/// The front depth of every pixel by brute force on the CPU: the nearest of the fragments every
/// segment's ribbon (the fibre's true width) leaves in the pixels it touches (the K-buffer's CPU twin,
/// [`strandlight::render::reference::abuffer::abuffer`]), None where no fibre touches the pixel.
struct CpuDepth {
    c: CameraUniform,
    front: Vec<Option<f32>>,
}

impl CpuDepth {
    fn new(hair: &strandlight::hair::Hair, c: CameraUniform) -> Self {
        let points = strandlight::gpu::fiber_density::GpuHair::point_data(hair, 1.0);
        let segments = strandlight::render::reference::shade::segment_starts(hair);
        let ab = strandlight::render::reference::abuffer::abuffer(&c, &points, &segments);
        Self {
            c,
            front: ab
                .pixels
                .iter()
                .map(|l| l.first().map(|f| f.depth))
                .collect(),
        }
    }

    fn pixel(&self, x: i64, y: i64) -> Option<f32> {
        if x < 0 || y < 0 || x >= self.c.size[0] as i64 || y >= self.c.size[1] as i64 {
            return None;
        }
        self.front[(y * self.c.size[0] as i64 + x) as usize]
    }

    fn around(&self, q: Projected) -> Option<f32> {
        let (px, py) = (q.x.floor() as i64, q.y.floor() as i64);
        let mut best: Option<f32> = None;
        for dy in -1..=1 {
            for dx in -1..=1 {
                if let Some(d) = self.pixel(px + dx, py + dy) {
                    best = Some(best.map_or(d, |b| b.min(d)));
                }
            }
        }
        best
    }
}

struct Setup {
    hair: strandlight::hair::Hair,
    camera: CameraUniform,
    picker: Picker,
    mirror_x: f32,
    centre: [f32; 2],
}

fn setup() -> Setup {
    let ctx = context();
    let luts = Luts::default_tables();
    let mut scene = common::bob_scene(500, 160, 120, Preset::Blond.params(), false);
    scene.settings.shadows = false;
    let light = strandlight::envmap::SrbfLight {
        direction: [0.0, 1.0, 0.0],
        lambda: 0.3,
        rgb: [1.0; 3],
    };
    let frame = scene.render(&ctx, &luts, &[light]);
    let camera = scene.camera.uniform(160, 120, scene.settings.min_width_px);
    let view = ViewDepth {
        width: 160,
        height: 120,
        depth: frame.depth.clone(),
        camera,
    };
    let (lo, hi) = scene.hair.bounds();
    let mirror_x = 0.5 * (lo.x + hi.x);
    // A dab on the hair a little right of the centre (so its mirror image is elsewhere).
    let covered: Vec<(f32, f32)> = (0..160 * 120)
        .filter(|&i| frame.depth[i] < 1e9)
        .map(|i| ((i % 160) as f32 + 0.5, (i / 160) as f32 + 0.5))
        .collect();
    let mean_x = covered.iter().map(|c| c.0).sum::<f32>() / covered.len() as f32;
    let mean_y = covered.iter().map(|c| c.1).sum::<f32>() / covered.len() as f32;
    let centre = [mean_x + 28.0, mean_y];
    Setup {
        picker: Picker::new(&scene.hair, view, mirror_x),
        hair: scene.hair,
        camera,
        mirror_x,
        centre,
    }
}

/// The points a dab selects by brute force: (index, in the region) for every point whose projection
/// lies within `radius` + 1 px of the centre, with those in the boundary band (1 px of the rim, or
/// within `band` cm of the depth cut) marked undecided (None).
fn cpu_region(
    s: &Setup,
    positions: &[Vec3],
    centre: [f32; 2],
    radius: f32,
    reach: f32,
    band: f32,
    cpu: &CpuDepth,
) -> Vec<(u32, Option<bool>)> {
    let mut out = Vec::new();
    for (i, p) in positions.iter().enumerate() {
        let Some(q) = project(&s.camera, *p) else {
            continue;
        };
        let d = ((q.x - centre[0]).powi(2) + (q.y - centre[1]).powi(2)).sqrt();
        if d > radius + 1.0 {
            continue;
        }
        if (d - radius).abs() <= 1.0 {
            out.push((i as u32, None));
            continue;
        }
        let decided = match cpu.around(q) {
            None => Some(true),
            Some(front) if (q.depth - (front + reach)).abs() <= band => None,
            Some(front) => Some(q.depth <= front + reach),
        };
        out.push((i as u32, decided));
    }
    out
}

/// Compares the picker's selection with the brute-force region; returns (compared, mismatches).
fn compare(selected: &BTreeSet<u32>, region: &[(u32, Option<bool>)]) -> (usize, usize) {
    let mut compared = 0;
    let mut wrong = 0;
    let near: BTreeSet<u32> = region.iter().map(|(i, _)| *i).collect();
    for &(i, inside) in region {
        if let Some(inside) = inside {
            compared += 1;
            wrong += (selected.contains(&i) != inside) as usize;
        }
    }
    // Nothing farther than the rim band is touched.
    let outside = selected.iter().filter(|i| !near.contains(i)).count();
    (compared, wrong + outside)
}

#[test]
fn a_dab_touches_the_footprint_a_cpu_ray_cast_finds_front_through_masked_and_mirrored() {
    let s = setup();
    let cpu = CpuDepth::new(&s.hair, s.camera);
    let radius = 12.0;
    // Depth differences between the GPU's samples and the CPU's rays are well under a millimetre.
    let band = 0.05;
    let brush = Brush {
        strength: 1.0,
        falloff: Falloff::Constant,
        ..Default::default()
    };
    let run = |b: &Brush| -> BTreeSet<u32> {
        s.picker
            .dab(b, s.centre, radius, 1.0)
            .into_iter()
            .map(|t| t.0)
            .collect()
    };
    // Front only.
    let front = run(&brush);
    let region = cpu_region(
        &s,
        &s.hair.positions,
        s.centre,
        radius,
        FRONT_DEPTH,
        band,
        &cpu,
    );
    let (n, wrong) = compare(&front, &region);
    println!(
        "front: {} points touched, {n} compared with the CPU ray cast, {wrong} differ",
        front.len()
    );
    assert!(front.len() > 20 && n > 20, "the dab reaches hair");
    assert_eq!(wrong, 0, "front-only selection against brute force");
    // Paint-through reaches hidden strands too.
    let deep = Brush {
        depth: 4.0,
        ..brush
    };
    let through = run(&deep);
    let region = cpu_region(&s, &s.hair.positions, s.centre, radius, 4.0, band, &cpu);
    let (n, wrong) = compare(&through, &region);
    println!(
        "paint-through 4 cm: {} points, {n} compared, {wrong} differ",
        through.len()
    );
    assert_eq!(wrong, 0, "paint-through selection against brute force");
    assert!(
        through.len() > front.len() + 10 && front.is_subset(&through),
        "paint-through reaches more, and every front point"
    );
    // The mask: roots only.
    let t = s.hair.root_to_tip();
    let roots = Brush {
        mask: Some([0.0, 0.4, 1e-6]),
        depth: 4.0,
        ..brush
    };
    let masked = run(&roots);
    let want: BTreeSet<u32> = through
        .iter()
        .copied()
        .filter(|&i| t[i as usize] <= 0.4 + 1e-6)
        .collect();
    println!(
        "root mask [0, 0.4]: {} of {} points",
        masked.len(),
        through.len()
    );
    assert_eq!(masked, want, "the mask keeps the points with t in [0, 0.4]");
    // The mirror: the footprint's region mirrored across x = mirror_x.
    let mirrored_brush = Brush {
        mirror: true,
        ..brush
    };
    let both = run(&mirrored_brush);
    let mirror: Vec<Vec3> = s
        .hair
        .positions
        .iter()
        .map(|p| Vec3::new(2.0 * s.mirror_x - p.x, p.y, p.z))
        .collect();
    let region_m = cpu_region(&s, &mirror, s.centre, radius, FRONT_DEPTH, band, &cpu);
    let only_mirror: BTreeSet<u32> = both.difference(&front).copied().collect();
    let near: BTreeSet<u32> = region_m.iter().map(|r| r.0).collect();
    let mut n = 0;
    let mut wrong = only_mirror.iter().filter(|i| !near.contains(i)).count();
    for &(i, inside) in &region_m {
        if let Some(inside) = inside {
            n += 1;
            let got = both.contains(&i);
            // A point outside the mirrored region may still be in the direct one.
            wrong += (inside && !got || !inside && got && !front.contains(&i)) as usize;
        }
    }
    println!(
        "mirror: {} more points, {n} compared with the mirrored brute force, {wrong} differ",
        only_mirror.len()
    );
    assert!(only_mirror.len() > 10, "the mirror side is painted");
    assert_eq!(wrong, 0, "mirror selection against brute force");
    assert!(
        only_mirror
            .iter()
            .all(|&i| (s.hair.positions[i as usize].x - s.mirror_x) < 0.0),
        "the mirrored points lie on the other side of the plane"
    );
}

#[test]
fn falloff_and_pressure_scale_the_dab() {
    let s = setup();
    let brush = Brush {
        strength: 0.8,
        falloff: Falloff::Linear,
        ..Default::default()
    };
    let dab = s.picker.dab(&brush, s.centre, 12.0, 0.5);
    assert!(!dab.is_empty());
    for (i, a) in &dab {
        let q = project(&s.camera, s.hair.positions[*i as usize]).unwrap();
        let r = ((q.x - s.centre[0]).powi(2) + (q.y - s.centre[1]).powi(2)).sqrt() / 12.0;
        let want = 0.8 * (1.0 - r) * 0.5;
        assert!((a - want).abs() < 1e-5, "{a} {want}");
    }
}
