//! The editor's first scene: the default session's hair fills a portrait viewport and hides the
//! scalp, and the generated head with a face is a closed, outward mesh whose implicit agrees with it
//! over the scalp. The render runs on lavapipe at half the editor's default viewport.

mod common;

use glam::Vec3;
use std::collections::HashMap;
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::hair::TriangleMesh;
use strandlight::hair::procedural::Head;
use strandlight::hair::procedural::head::HEAD_MESH_RINGS;
use strandlight::render::passes::background::Background;
use strandlight::render::{Camera, Frame, Renderer};
use strandlight::scattering::lut::Luts;
use strandlight::session::{HairSource, Scene, Session};

/// Half the editor's default viewport (654 x 734, portrait).
const VIEWPORT: (u32, u32) = (327, 367);

/// The default session rendered at the viewport's size with its default camera, as the editor's
/// viewport shows it, and that camera.
fn render_default() -> (Frame, Camera, strandlight::hair::Hair) {
    let mut session = Session::default();
    (session.render.width, session.render.height) = VIEWPORT;
    let scene = Scene::assemble(&session).expect("the default scene");
    let ctx = GpuContext::new_headless(&GpuOptions::from_env()).expect("a GPU adapter (lavapipe)");
    let luts = Luts::default_tables();
    let mut r = Renderer::new(
        &ctx,
        scene.settings.clone(),
        &luts,
        &scene.hair,
        &scene.sigma_a,
        &scene.look,
        &scene.environment.lights.lights,
        &scene.camera,
    )
    .expect("renderer");
    r.set_occluder(&ctx, scene.occluder.as_ref());
    r.render_frame(&ctx);
    let frame = r.read_frame(&ctx).expect("read back");
    let png = common::temp_file("default-scene", "default.png");
    frame
        .write_png(&png, Background::Environment)
        .expect("the preview");
    println!("the default scene: {}", png.display());
    (frame, scene.camera, scene.hair)
}

/// Rows (top, bottom) of the viewport that the hair's points project into, clipped to it.
fn projected_rows(
    hair: &strandlight::hair::Hair,
    camera: &Camera,
    width: u32,
    height: u32,
) -> (f32, f32) {
    let clip_from_world = camera.projection(width, height) * camera.view();
    let (mut top, mut bottom) = (f32::MAX, f32::MIN);
    for &p in &hair.positions {
        let c = clip_from_world * p.extend(1.0);
        if c.w <= 0.0 {
            continue;
        }
        let row = (0.5 - 0.5 * c.y / c.w) * height as f32;
        top = top.min(row);
        bottom = bottom.max(row);
    }
    (top.max(0.0), bottom.min(height as f32))
}

/// Whether pixel `i` shows the head in any of its samples (behind hair or not).
fn head_at(frame: &Frame, i: usize) -> bool {
    let n = frame.samples.clamp(1, 4) as usize;
    frame.sample_ids[i][..n].iter().any(|&id| id != 0)
}

/// Of the head's pixels in the upper third of its projected rows: (count, the share behind hair of
/// coverage >= 0.5).
fn upper_head_hidden(frame: &Frame) -> (usize, f64) {
    let w = frame.width as usize;
    let rows: Vec<usize> = (0..frame.pixel_count())
        .filter(|&i| head_at(frame, i))
        .map(|i| i / w)
        .collect();
    let (top, bottom) = (rows.iter().min().copied(), rows.iter().max().copied());
    let (Some(top), Some(bottom)) = (top, bottom) else {
        return (0, 0.0);
    };
    let third = top + (bottom + 1 - top) / 3;
    let upper: Vec<usize> = (top * w..third * w)
        .filter(|&i| head_at(frame, i))
        .collect();
    let hidden = upper
        .iter()
        .filter(|&&i| frame.hair_alpha(i) >= 0.5)
        .count();
    (upper.len(), hidden as f64 / upper.len().max(1) as f64)
}

#[test]
fn the_default_hair_fills_the_viewport_and_hides_the_scalp() {
    let session = Session::default();
    let HairSource::Generated {
        strands, points, ..
    } = session.hair
    else {
        panic!("the default hair is generated");
    };
    assert!(strands >= 10_000, "{strands} strands");
    assert!(strands * points >= 160_000, "{} points", strands * points);
    let (frame, camera, hair) = render_default();
    assert_eq!(hair.strand_count(), strands);
    assert!(
        hair.point_count() >= 160_000,
        "{} points",
        hair.point_count()
    );
    let (w, h) = VIEWPORT;
    let (top, bottom) = projected_rows(&hair, &camera, w, h);
    let fill = (bottom - top) / h as f32;
    let (upper, hidden) = upper_head_hidden(&frame);
    println!(
        "hair rows {top:.0}..{bottom:.0} of {h}: {:.1} % of the height; head pixels in the upper third of the head: {upper}, {:.1} % behind hair of coverage >= 0.5",
        100.0 * fill,
        100.0 * hidden
    );
    assert!(fill >= 0.75, "the hair fills {fill} of the height");
    assert!(upper > 500, "only {upper} head pixels in the upper third");
    assert!(hidden >= 0.9, "{hidden} of the upper head is hidden");
}

/// Each undirected edge's count of triangles, with coincident vertices welded (the crown's ring of
/// vertices all lie on the pole) and the triangles that collapse with them left out.
fn edge_uses(mesh: &TriangleMesh) -> HashMap<(u32, u32), usize> {
    let mut welded: HashMap<[i64; 3], u32> = HashMap::new();
    let id: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let key = (*p * 1e4).round().as_i64vec3().to_array();
            let next = welded.len() as u32;
            *welded.entry(key).or_insert(next)
        })
        .collect();
    let mut uses = HashMap::new();
    for t in &mesh.triangles {
        let t = t.map(|i| id[i as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
            continue; // a sliver at the pole: no area, no edge
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    uses
}

/// Signed volume by the divergence theorem (positive for outward winding).
fn signed_volume(mesh: &TriangleMesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn the_head_is_closed_and_wound_outward() {
    let head = Head::default();
    let mesh = head.occluder_mesh();
    let uses = edge_uses(&mesh);
    let open = uses.values().filter(|&&n| n != 2).count();
    let volume = signed_volume(&mesh);
    let r = head.radii;
    let egg = 4.0 / 3.0 * std::f64::consts::PI * (r.x * r.y * r.z) as f64;
    println!(
        "{} triangles, {} edges ({open} not shared by two), volume {volume:.0} cm^3 (the skull's ellipsoid {egg:.0})",
        mesh.triangles.len(),
        uses.len()
    );
    assert_eq!(open, 0);
    assert!(volume > 0.0, "{volume}");
    // Light enough to voxelise and draw every frame.
    assert!(mesh.triangles.len() < 10_000, "{}", mesh.triangles.len());
    // Star-shaped above the neck: every triangle there faces away from the centre.
    let inward = mesh
        .triangles
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let m = (a + b + c) / 3.0;
            let n = (b - a).cross(c - a);
            n.length() > 1e-6
                && m.y > head.centre.y - 0.5 * head.radii.y
                && (b - a).cross(c - a).dot(m - head.centre) <= 0.0
        })
        .count();
    assert_eq!(inward, 0, "{inward} triangles face inward");
}

#[test]
fn the_head_has_a_face_below_the_hairline_and_a_plain_skull_above() {
    let head = Head::default();
    // The nose stands out of the ellipsoid, the jaw is narrower than it, the scalp is the ellipsoid.
    let nose = Vec3::new(0.0, -0.25, 1.0).normalize();
    let jaw = Vec3::new(1.0, -0.8, 0.2).normalize();
    println!(
        "relief: nose {:.3}, jaw {:.3}",
        head.relief(nose),
        head.relief(jaw)
    );
    assert!(head.relief(nose) > 0.1);
    assert!(head.relief(jaw) < -0.05);
    let mut r = common::Uniform::new(5);
    for _ in 0..2000 {
        let d = Vec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::Y);
        if head.on_scalp(d) {
            assert_eq!(head.relief(d), 0.0, "{d}");
        }
    }
}

#[test]
fn the_implicit_agrees_with_the_mesh() {
    let head = Head::default();
    let mesh = head.mesh(HEAD_MESH_RINGS, false);
    // Every vertex lies on the implicit's surface (the mesh is inscribed between them).
    let worst = mesh
        .positions
        .iter()
        .map(|&p| (head.implicit(p) - 1.0).abs())
        .fold(0.0f32, f32::max);
    println!("vertices' worst |implicit - 1|: {worst:.2e}");
    assert!(worst < 1e-3, "{worst}");
    // Over the scalp, the surface point in a direction, its normal and the push out agree with it.
    let mut r = common::Uniform::new(9);
    let mut checked = 0;
    while checked < 500 {
        let d = Vec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-0.2..1.0),
            r.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::Y);
        if !head.on_scalp(d) {
            continue;
        }
        checked += 1;
        let (p, n) = head.surface(d);
        assert!((head.implicit(p) - 1.0).abs() < 1e-4, "{d}");
        let outside = head.implicit(p + 0.05 * n);
        let inside = head.implicit(p - 0.05 * n);
        assert!(outside > 1.0 && inside < 1.0, "{d}: {inside} {outside}");
        let pushed = head.push_out(p - 0.5 * n, 0.01);
        let k = head.implicit(pushed).sqrt();
        assert!((k - 1.01).abs() < 1e-3, "{d}: {k}");
    }
    // Below the hairline too: the face's surface and push out land on the implicit's surface.
    for d in [
        Vec3::new(0.0, -0.25, 1.0),
        Vec3::new(0.6, -0.8, 0.4),
        Vec3::new(0.0, -0.7, -0.7),
    ] {
        let d = d.normalize();
        let (p, n) = head.surface(d);
        assert!((head.implicit(p) - 1.0).abs() < 1e-4, "{d}");
        assert!(n.dot(d) > 0.0, "{d}: {n}");
        let k = head.implicit(head.push_out(0.5 * p, 0.02)).sqrt();
        assert!((k - 1.02).abs() < 1e-3, "{d}: {k}");
    }
}
