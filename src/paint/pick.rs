//! What a dab touches: the hair points inside the brush's footprint, found from the frame's view
//! depth (the visibility pass's nearest hair sample per pixel, read back from the GPU) rather than by
//! a CPU ray cast over the segments.
//!
//! The footprint's world-space region is the part of the cone through the brush circle that lies at
//! most `depth` behind the nearest hair under each pixel: a point is inside when it projects into the
//! circle and its view depth is at most the view depth of the pixel it projects to (the smallest of
//! its 3x3 neighbourhood: a point of a visible fibre lies within one pixel of its ribbon's samples)
//! plus `depth`. The mirror region is that region mirrored across the plane x = `mirror_x`: a point
//! is in it when its mirror image is in the region (the mirrored side may be hidden, so it is not
//! found on screen). Points are projected once per view (a picker lives as long as its camera) and
//! bucketed in screen cells, so a dab visits only the cells under the circle.

use super::brush::{Brush, Touch};
use crate::hair::Hair;
use crate::render::camera::CameraUniform;
pub use crate::render::camera::{Projected, project};
use glam::Vec3;
use rayon::prelude::*;

/// Screen cell size of the buckets, pixels.
const CELL: f32 = 16.0;

/// The frame's nearest hair depth per pixel, as [`crate::render::Frame::depth`] holds it (1e10:
/// no hair), for the camera it was drawn with.
#[derive(Clone, Debug)]
pub struct ViewDepth {
    pub width: u32,
    pub height: u32,
    pub depth: Vec<f32>,
    pub camera: CameraUniform,
}

impl ViewDepth {
    /// The nearest hair depth over the 3x3 pixels around (x, y) (None: no hair there).
    pub fn nearest_around(&self, x: f32, y: f32) -> Option<f32> {
        let (px, py) = (x.floor() as i64, y.floor() as i64);
        let mut best = f32::INFINITY;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let (qx, qy) = (px + dx, py + dy);
                if qx < 0 || qy < 0 || qx >= self.width as i64 || qy >= self.height as i64 {
                    continue;
                }
                let d = self.depth[(qy as u64 * self.width as u64 + qx as u64) as usize];
                if d < 1e9 {
                    best = best.min(d);
                }
            }
        }
        best.is_finite().then_some(best)
    }
}

/// Whether a projected point lies in the footprint region of a dab at `centre` (pixels) of radius
/// `radius` reaching `reach` cm behind the front-most hair; its distance over the radius when it does.
pub fn in_region(
    view: &ViewDepth,
    q: Projected,
    centre: [f32; 2],
    radius: f32,
    reach: f32,
) -> Option<f32> {
    let d = ((q.x - centre[0]).powi(2) + (q.y - centre[1]).powi(2)).sqrt();
    if d > radius {
        return None;
    }
    match view.nearest_around(q.x, q.y) {
        Some(front) if q.depth > front + reach => None,
        _ => Some(d / radius.max(1e-6)),
    }
}

/// Screen-space buckets of projected points.
struct Buckets {
    cols: usize,
    rows: usize,
    /// Start of each cell's run in `items` (cols x rows + 1).
    starts: Vec<u32>,
    /// (point, projection), sorted by cell.
    items: Vec<(u32, Projected)>,
}

impl Buckets {
    fn new(width: u32, height: u32, points: Vec<(u32, Projected)>) -> Self {
        let cols = (width as f32 / CELL).ceil().max(1.0) as usize;
        let rows = (height as f32 / CELL).ceil().max(1.0) as usize;
        let cell = |q: &Projected| {
            let cx = (q.x / CELL).floor() as usize;
            let cy = (q.y / CELL).floor() as usize;
            cy * cols + cx
        };
        let mut items: Vec<(u32, Projected)> = points
            .into_iter()
            .filter(|(_, q)| q.x >= 0.0 && q.y >= 0.0 && q.x < width as f32 && q.y < height as f32)
            .collect();
        // The keys are unique (a point once per buckets): unstable and parallel, the same order.
        items.par_sort_unstable_by_key(|(i, q)| (cell(q), *i));
        let mut starts = vec![0u32; cols * rows + 1];
        for (_, q) in &items {
            starts[cell(q) + 1] += 1;
        }
        for k in 1..starts.len() {
            starts[k] += starts[k - 1];
        }
        Self {
            cols,
            rows,
            starts,
            items,
        }
    }

    /// The points in the cells that overlap the circle.
    fn near(&self, centre: [f32; 2], radius: f32) -> impl Iterator<Item = &(u32, Projected)> {
        let span = |c: f32, n: usize| {
            let lo = ((c - radius) / CELL).floor().max(0.0) as usize;
            let hi = (((c + radius) / CELL).floor().max(0.0) as usize).min(n.saturating_sub(1));
            lo..=hi
        };
        let (xs, ys) = (span(centre[0], self.cols), span(centre[1], self.rows));
        ys.flat_map(move |cy| {
            let xs = xs.clone();
            xs.flat_map(move |cx| {
                let k = cy * self.cols + cx;
                let (a, b) = (self.starts[k] as usize, self.starts[k + 1] as usize);
                self.items[a..b].iter()
            })
        })
    }
}

/// The points of one hair as one view sees them.
pub struct Picker {
    pub view: ViewDepth,
    direct: Buckets,
    /// Mirror images (x -> 2 mirror_x - x) of the points, projected.
    mirrored: Buckets,
    /// Root-to-tip parameter per point (the mask).
    t: Vec<f32>,
}

impl Picker {
    /// Projects every point of `hair` (and its mirror image across x = `mirror_x`) for `view`.
    pub fn new(hair: &Hair, view: ViewDepth, mirror_x: f32) -> Self {
        let c = view.camera;
        let project_all = |mirror: bool| -> Vec<(u32, Projected)> {
            hair.positions
                .par_iter()
                .enumerate()
                .filter_map(|(i, p)| {
                    let p = if mirror {
                        Vec3::new(2.0 * mirror_x - p.x, p.y, p.z)
                    } else {
                        *p
                    };
                    project(&c, p).map(|q| (i as u32, q))
                })
                .collect()
        };
        let (w, h) = (view.width, view.height);
        let ((direct, mirrored), t) = rayon::join(
            || {
                rayon::join(
                    || Buckets::new(w, h, project_all(false)),
                    || Buckets::new(w, h, project_all(true)),
                )
            },
            || hair.root_to_tip(),
        );
        Self {
            direct,
            mirrored,
            t,
            view,
        }
    }

    /// The points a dab of `brush` at `centre` (pixels of the view) with `pressure` touches, with
    /// the dab's strength at each (strength x falloff x mask x pressure; the strongest where a point is
    /// in both the region and its mirror), sorted by index.
    pub fn dab(&self, brush: &Brush, centre: [f32; 2], radius: f32, pressure: f32) -> Vec<Touch> {
        let mut out: Vec<Touch> = Vec::new();
        let mut visit = |b: &Buckets| {
            for &(i, q) in b.near(centre, radius) {
                let Some(r) = in_region(&self.view, q, centre, radius, brush.depth) else {
                    continue;
                };
                let a = brush.strength.clamp(0.0, 1.0)
                    * brush.falloff.weight(r)
                    * brush.mask_weight(self.t[i as usize])
                    * pressure.clamp(0.0, 1.0);
                if a > 0.0 {
                    out.push((i, a));
                }
            }
        };
        visit(&self.direct);
        if brush.mirror {
            visit(&self.mirrored);
        }
        out.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
        out.dedup_by_key(|t| t.0);
        out
    }
}

/// The dab centres along a pointer path from `from` to `to` (pixels) at `spacing` pixels, continuing
/// from `carry` pixels already travelled since the last dab; returns the centres and the new carry.
pub fn dabs_along(from: [f32; 2], to: [f32; 2], spacing: f32, carry: f32) -> (Vec<[f32; 2]>, f32) {
    let spacing = spacing.max(0.5);
    let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
    let len = (dx * dx + dy * dy).sqrt();
    let mut out = Vec::new();
    let mut s = spacing - carry;
    while s <= len {
        let f = s / len.max(1e-6);
        out.push([from[0] + f * dx, from[1] + f * dy]);
        s += spacing;
    }
    let travelled = carry + len;
    let carry = if out.is_empty() {
        travelled
    } else {
        len - (s - spacing)
    };
    (out, carry)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dabs_are_spaced_along_the_path_whatever_the_pointer_steps() {
        // One long move or many short ones give the same dabs.
        let (one, _) = dabs_along([0.0, 0.0], [100.0, 0.0], 10.0, 0.0);
        let mut many = Vec::new();
        let mut carry = 0.0;
        for k in 0..40 {
            let (a, b) = (2.5 * k as f32, 2.5 * (k + 1) as f32);
            let (d, c) = dabs_along([a, 0.0], [b, 0.0], 10.0, carry);
            many.extend(d);
            carry = c;
        }
        assert_eq!(one.len(), 10);
        assert_eq!(many.len(), one.len());
        for (a, b) in one.iter().zip(&many) {
            assert!((a[0] - b[0]).abs() < 1e-3, "{a:?} {b:?}");
        }
    }
}
