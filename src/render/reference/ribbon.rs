//! The ribbon a segment draws and the exact area of it inside a pixel: the CPU twins of the coverage
//! functions of `shaders/kbuffer.wgsl` (the K-buffer pass, [`crate::render::passes::kbuffer`]).

use crate::render::camera::{CameraUniform, closest_on_segment, pixel_ray};
use crate::render::passes::kbuffer::{MAX_FRAGMENT_OPACITY, OPTICAL_DEPTH_SCALE};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// A point in pixel coordinates (x right, y down) and its view depth (twin of `to_pixels`).
pub fn to_pixels(c: &CameraUniform, p: Vec3) -> Vec3 {
    let clip = Mat4::from_cols_array_2d(&c.view_proj) * p.extend(1.0);
    let ndc = clip.truncate().truncate() / clip.w;
    let (w, h) = (c.size[0] as f32, c.size[1] as f32);
    Vec3::new(
        0.5 * (ndc.x + 1.0) * w,
        0.5 * (1.0 - ndc.y) * h,
        (p - Vec3::from(c.eye)).dot(Vec3::from(c.forward)),
    )
}

/// A segment's ribbon on the image (twin of `RibbonQuad`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RibbonQuad {
    pub p0: Vec2,
    pub p1: Vec2,
    pub dir: Vec2,
    pub normal: Vec2,
    pub half_width: Vec2,
    pub valid: bool,
}

/// Half the ribbon's width in pixels (twin of `half_width_px`).
pub fn half_width_px(c: &CameraUniform, diameter: f32, depth: f32) -> f32 {
    c.width_scale * (0.5 * diameter / (c.pixel_angle * depth)).max(0.5 * c.min_width_px)
}

/// The part of the segment a..b in front of the near plane, moved in by a thousandth of it (twin of
/// `clip_near`): None when both ends are behind it.
pub fn clip_near(c: &CameraUniform, a: Vec4, b: Vec4) -> Option<(Vec4, Vec4)> {
    let plane = 1.001 * c.near;
    let (eye, forward) = (Vec3::from(c.eye), Vec3::from(c.forward));
    let da = (a.truncate() - eye).dot(forward);
    let db = (b.truncate() - eye).dot(forward);
    if da <= plane && db <= plane {
        return None;
    }
    if da < plane && db > plane {
        return Some((a + (b - a) * ((plane - da) / (db - da)), b));
    }
    if db < plane && da > plane {
        return Some((a, b + (a - b) * ((plane - db) / (da - db))));
    }
    Some((a, b))
}

/// The ribbon of the segment between points `a` and `b` (xyz, diameter; twin of `ribbon_quad`).
pub fn ribbon_quad(c: &CameraUniform, a: Vec4, b: Vec4) -> RibbonQuad {
    let valid = clip_near(c, a, b).is_some();
    let (a, b) = clip_near(c, a, b).unwrap_or((a, b));
    let pa = to_pixels(c, a.truncate());
    let pb = to_pixels(c, b.truncate());
    let d = pb.truncate() - pa.truncate();
    let len = d.length();
    let dir = if len > 1e-6 { d / len } else { Vec2::X };
    RibbonQuad {
        p0: pa.truncate(),
        p1: pb.truncate(),
        dir,
        normal: Vec2::new(-dir.y, dir.x),
        half_width: Vec2::new(
            half_width_px(c, a.w, pa.z.max(c.near)),
            half_width_px(c, b.w, pb.z.max(c.near)),
        ),
        valid,
    }
}

/// The mean over t in [0, 1] of clamp(y0 + t (y1 - y0), 0, 1) (twin of `clamped_mean`).
fn clamped_mean(y0: f32, y1: f32) -> f32 {
    let (lo, hi) = (y0.min(y1), y0.max(y1));
    let dy = hi - lo;
    if dy <= 1e-20 {
        return lo.clamp(0.0, 1.0);
    }
    let (a, b) = (lo.max(0.0), hi.min(1.0));
    let inside = (b - a).max(0.0);
    ((hi - 1.0) / dy).clamp(0.0, 1.0) + inside / dy * 0.5 * (a + b)
}

/// Edge a -> b's term of the area inside the unit square by Green's theorem: the integral of
/// clamp(y, 0, 1) dx along the edge over x in [0, 1] (twin of `edge_area`).
fn edge_area(a: Vec2, b: Vec2) -> f32 {
    let dx = b.x - a.x;
    let (lo, hi) = (a.x.min(b.x).max(0.0), a.x.max(b.x).min(1.0));
    if dx.abs() <= 1e-20 || hi <= lo {
        return 0.0;
    }
    let ylo = a.y + (lo - a.x) / dx * (b.y - a.y);
    let yhi = a.y + (hi - a.x) / dx * (b.y - a.y);
    dx.signum() * (hi - lo) * clamped_mean(ylo, yhi)
}

/// The ribbon's corners relative to pixel (x, y)'s corner, in order around it.
fn ribbon_corners(q: &RibbonQuad, x: u32, y: u32) -> [Vec2; 4] {
    let o = Vec2::new(x as f32, y as f32);
    [
        q.p0 - o - q.half_width.x * q.normal,
        q.p1 - o - q.half_width.y * q.normal,
        q.p1 - o + q.half_width.y * q.normal,
        q.p0 - o + q.half_width.x * q.normal,
    ]
}

/// Coverage below this is the edges' terms' rounding (each term is at most 1, good to ~1e-7): a ribbon
/// passing by the pixel, which leaves no fragment (twin of `MIN_COVERAGE`).
pub const MIN_COVERAGE: f32 = 1e-6;

/// The area of the ribbon inside pixel (x, y), in [0, 1], by the quad's edges' Green's-theorem terms;
/// 0 below [`MIN_COVERAGE`] (twin of `pixel_coverage`).
pub fn pixel_coverage(q: &RibbonQuad, x: u32, y: u32) -> f32 {
    if !q.valid {
        return 0.0;
    }
    let v = ribbon_corners(q, x, y);
    let area = (edge_area(v[0], v[1])
        + edge_area(v[1], v[2])
        + edge_area(v[2], v[3])
        + edge_area(v[3], v[0]))
    .abs();
    if area >= MIN_COVERAGE {
        area.min(1.0)
    } else {
        0.0
    }
}

/// Sutherland–Hodgman: the part of the convex polygon where p · nrm ≤ off.
fn clip_half_plane(poly: &[Vec2], nrm: Vec2, off: f32) -> Vec<Vec2> {
    let mut out = Vec::with_capacity(8);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        let (da, db) = (a.dot(nrm) - off, b.dot(nrm) - off);
        if da <= 0.0 {
            out.push(a);
        }
        if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    out
}

/// The brute-force twin of [`pixel_coverage`]: the quad clipped by the pixel's four sides
/// (Sutherland–Hodgman) and the clipped polygon's area (the shoelace formula).
pub fn pixel_coverage_by_clipping(q: &RibbonQuad, x: u32, y: u32) -> f32 {
    if !q.valid {
        return 0.0;
    }
    let mut poly = ribbon_corners(q, x, y).to_vec();
    for (nrm, off) in [
        (Vec2::new(-1.0, 0.0), 0.0),
        (Vec2::new(1.0, 0.0), 1.0),
        (Vec2::new(0.0, -1.0), 0.0),
        (Vec2::new(0.0, 1.0), 1.0),
    ] {
        poly = clip_half_plane(&poly, nrm, off);
    }
    let mut twice = 0.0;
    for (i, a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        twice += a.x * b.y - a.y * b.x;
    }
    (0.5 * f32::abs(twice)).clamp(0.0, 1.0)
}

/// View depth of the segment's point closest to the ray through pixel (x, y)'s centre (twin of
/// `fragment_depth`).
pub fn fragment_depth(c: &CameraUniform, a: Vec3, b: Vec3, x: u32, y: u32) -> f32 {
    let (o, d) = pixel_ray(c, x as f32 + 0.5, y as f32 + 0.5);
    let t = closest_on_segment(o, d, a, b);
    (a + (b - a) * t - Vec3::from(c.eye)).dot(Vec3::from(c.forward))
}

/// −ln(1 − a) in fixed point (twin of `optical_depth`).
pub fn optical_depth(a: f32) -> u32 {
    (-(1.0 - a.min(MAX_FRAGMENT_OPACITY)).ln() * OPTICAL_DEPTH_SCALE).round() as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The edges' Green's-theorem terms against the clipped polygon's area, over ribbons of every
    /// direction, width and taper around a pixel (some thinner than 1e-3 pixel, some covering it).
    #[test]
    fn coverage_by_edges_equals_the_clipped_polygon() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rand = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut worst = 0.0f32;
        for k in 0..20000 {
            let p0 = Vec2::new(10.0 + 4.0 * rand() - 2.0, 20.0 + 4.0 * rand() - 2.0);
            let angle = std::f32::consts::TAU * rand();
            let len = if k % 10 == 0 { 1e-4 } else { 3.0 * rand() };
            let dir = Vec2::new(angle.cos(), angle.sin());
            let width = |r: f32| if k % 7 == 0 { 1e-4 * r } else { 1.5 * r };
            let q = RibbonQuad {
                p0,
                p1: p0 + len * dir,
                dir,
                normal: Vec2::new(-dir.y, dir.x),
                half_width: Vec2::new(width(rand()), width(rand())),
                valid: true,
            };
            let (a, b) = (
                pixel_coverage(&q, 10, 20),
                pixel_coverage_by_clipping(&q, 10, 20),
            );
            worst = worst.max((a - b).abs());
        }
        println!("worst |edges - clipped| {worst:.2e}");
        assert!(worst <= MIN_COVERAGE, "{worst}");
    }
}
