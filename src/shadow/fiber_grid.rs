//! The hair's explicit fibers in a uniform grid, for rays that must know every fiber they cross: the
//! multiple-scattering reference shoots shadow rays through them (Zinke et al. 2008 Sec. 4.1.1).
//!
//! Each segment is a cylinder of the strand's diameter around the line between its two points. A ray
//! crosses it when its closest approach to the segment's line is nearer than the radius, at a point of
//! the segment in [0, 1) (half-open, so a ray through a joint counts one of the two segments). Cells are
//! walked in order (Amanatides and Woo 1987); a segment listed in several cells is reported only by the
//! cell that holds the ray's point of closest approach, so every crossing is reported once.

use super::voxels::box_exit;
use crate::hair::Hair;
use glam::Vec3;

/// One segment as rays see it. Segments are numbered as the renderer numbers them
/// ([`crate::render::reference::shade::segment_starts`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FiberSegment {
    pub a: Vec3,
    pub b: Vec3,
    pub radius: f32,
    pub strand: u32,
    /// sigma_a at a and at b.
    pub sigma_a: [[f32; 3]; 2],
}

/// Where a ray crosses a segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    pub segment: u32,
    /// Ray parameter of the closest approach.
    pub t: f32,
    /// Position along the segment, in [0, 1).
    pub u: f32,
}

/// Uniform grid over the segments.
#[derive(Clone, Debug)]
pub struct FiberGrid {
    pub segments: Vec<FiberSegment>,
    pub origin: Vec3,
    pub cell: f32,
    pub dims: [usize; 3],
    /// cell_start[c]..cell_start[c + 1] index `cell_items` for cell c.
    cell_start: Vec<u32>,
    /// Each cell's segments, in the form the ray test reads (a cell's items are contiguous).
    cell_items: Vec<CellItem>,
}

/// A segment as the ray test reads it: its start a, its extent e = b - a, e.e and radius^2, and its
/// index.
#[derive(Clone, Copy, Debug, PartialEq)]
struct CellItem {
    a: Vec3,
    e: Vec3,
    e_dot_e: f32,
    radius2: f32,
    segment: u32,
}

impl CellItem {
    fn new(segment: u32, s: &FiberSegment) -> Self {
        let e = s.b - s.a;
        Self {
            a: s.a,
            e,
            e_dot_e: e.dot(e),
            radius2: s.radius * s.radius,
            segment,
        }
    }

    /// Closest approach of the ray o + t d (d unit): Some((t, u)) when the ray passes within the
    /// radius at a point u in [0, 1) of the segment. Rays parallel to the fiber never cross it.
    #[inline]
    fn intersect(&self, o: Vec3, d: Vec3) -> Option<(f32, f32)> {
        let (e, c) = (self.e, self.e_dot_e);
        let w0 = o - self.a;
        let b = d.dot(e);
        let denom = c - b * b;
        if denom <= 1e-10 * c {
            return None;
        }
        // The lines' distance is |w0 . (d x e)| / |d x e|, and |d x e|^2 = c - b^2: most segments
        // a ray meets in a cell pass far from it, and leave here without a division (with a margin,
        // so the test below decides every near case as it would alone).
        // (Only where denom is well above its rounding: a ray nearly along the fiber is left to
        // the test below, as before.)
        let w = w0.dot(d.cross(e));
        if denom > 1e-3 * c && w * w > 1.25 * self.radius2 * denom {
            return None;
        }
        let (dd, ee) = (d.dot(w0), e.dot(w0));
        let t = (b * ee - c * dd) / denom;
        let u = (ee - b * dd) / denom;
        if !(0.0..1.0).contains(&u) {
            return None;
        }
        let gap = w0 + d * t - e * u;
        (gap.length_squared() < self.radius2).then_some((t, u))
    }
}

/// Cells per axis at most.
const MAX_CELLS: usize = 256;

impl FiberGrid {
    /// The hair's segments with their interpolable absorption (`sigma_a` per point).
    pub fn build(hair: &Hair, sigma_a: &[[f32; 3]]) -> Self {
        let mut segments = Vec::new();
        for s in 0..hair.strand_count() {
            let r = hair.strand_range(s);
            for i in r.start..r.end.saturating_sub(1) {
                let d = 0.5 * (hair.thickness_at(s, i) + hair.thickness_at(s, i + 1));
                segments.push(FiberSegment {
                    a: hair.positions[i],
                    b: hair.positions[i + 1],
                    radius: 0.5 * d,
                    strand: s as u32,
                    sigma_a: [sigma_a[i], sigma_a[i + 1]],
                });
            }
        }
        Self::from_segments(segments)
    }

    pub fn from_segments(segments: Vec<FiberSegment>) -> Self {
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for s in &segments {
            lo = lo.min(s.a.min(s.b) - Vec3::splat(s.radius));
            hi = hi.max(s.a.max(s.b) + Vec3::splat(s.radius));
        }
        if segments.is_empty() {
            (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        }
        // About two cells per segment, cubic cells.
        let extent = (hi - lo).max(Vec3::splat(1e-4));
        let target = (2 * segments.len()).max(1) as f32;
        let mut cell = (extent.x * extent.y * extent.z / target).cbrt();
        cell = cell.max(extent.max_element() / MAX_CELLS as f32 * 1.001);
        let dims = [0, 1, 2].map(|a| ((extent[a] / cell).ceil() as usize).clamp(1, MAX_CELLS));
        let index = |q: [usize; 3]| (q[2] * dims[1] + q[1]) * dims[0] + q[0];
        let cell_of = |p: Vec3| -> [usize; 3] {
            let q = (p - lo) / cell;
            [0, 1, 2].map(|a| (q[a].max(0.0) as usize).min(dims[a] - 1))
        };
        // Counting sort of (cell, segment) pairs over each segment's bounds grown by its radius.
        let mut counts = vec![0u32; dims[0] * dims[1] * dims[2] + 1];
        let ranges: Vec<([usize; 3], [usize; 3])> = segments
            .iter()
            .map(|s| {
                let r = Vec3::splat(s.radius);
                (cell_of(s.a.min(s.b) - r), cell_of(s.a.max(s.b) + r))
            })
            .collect();
        // A segment is listed in the cells its capsule can reach: those whose box, grown by the
        // radius, the segment meets. A crossing's closest approach lies inside the capsule, so the
        // cell that holds it lists the segment; a diagonal segment's bounds hold several times the
        // cells its capsule reaches.
        let each = |k: usize, f: &mut dyn FnMut(usize)| {
            let ((q0, q1), s) = (ranges[k], &segments[k]);
            // (A margin of 1 % of a cell against the walk's accumulated boundaries.)
            let grow = Vec3::splat(s.radius + 1e-2 * cell);
            for z in q0[2]..=q1[2] {
                for y in q0[1]..=q1[1] {
                    for x in q0[0]..=q1[0] {
                        let c0 = lo + cell * Vec3::new(x as f32, y as f32, z as f32);
                        if segment_meets_box(s.a, s.b, c0 - grow, c0 + Vec3::splat(cell) + grow) {
                            f(index([x, y, z]));
                        }
                    }
                }
            }
        };
        for k in 0..segments.len() {
            each(k, &mut |c| counts[c + 1] += 1);
        }
        for c in 1..counts.len() {
            counts[c] += counts[c - 1];
        }
        let mut fill = counts.clone();
        let mut items = vec![0u32; *counts.last().unwrap_or(&0) as usize];
        for k in 0..segments.len() {
            each(k, &mut |c| {
                items[fill[c] as usize] = k as u32;
                fill[c] += 1;
            });
        }
        let cell_items = items
            .into_iter()
            .map(|k| CellItem::new(k, &segments[k as usize]))
            .collect();
        Self {
            segments,
            origin: lo,
            cell,
            dims,
            cell_start: counts,
            cell_items,
        }
    }

    /// Closest approach of the ray o + t d (d unit) to segment k: Some((t, u)) when the ray passes within
    /// the radius at a point u in [0, 1) of the segment. Rays parallel to the fiber never cross it.
    pub fn intersect(&self, k: u32, o: Vec3, d: Vec3) -> Option<(f32, f32)> {
        CellItem::new(k, &self.segments[k as usize]).intersect(o, d)
    }

    /// Calls `visit` for every crossing of the ray o + t d (d unit), t > t_min, in increasing cell order
    /// (not strictly sorted by t within a cell).
    pub fn crossings(&self, o: Vec3, d: Vec3, t_min: f32, mut visit: impl FnMut(Crossing)) {
        let dims = self.dims;
        let exit = box_exit(self.origin, self.cell, dims, o, d);
        // Entry into the box (the ray may start outside it).
        let hi =
            self.origin + self.cell * Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
        let mut entry = t_min;
        for a in 0..3 {
            if d[a].abs() > 1e-12 {
                let (t0, t1) = ((self.origin[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
                entry = entry.max(t0.min(t1));
            } else if o[a] < self.origin[a] || o[a] > hi[a] {
                return;
            }
        }
        if !exit.is_finite() || entry >= exit {
            return;
        }
        let p = o + d * entry;
        let mut q = [0usize; 3];
        let (mut step, mut t_next, mut t_delta) = ([0i64; 3], [f32::INFINITY; 3], [0f32; 3]);
        for a in 0..3 {
            let x = ((p[a] - self.origin[a]) / self.cell).floor();
            q[a] = (x.max(0.0) as usize).min(dims[a] - 1);
            if d[a] > 1e-12 {
                step[a] = 1;
                t_delta[a] = self.cell / d[a];
                t_next[a] = (self.origin[a] + (q[a] + 1) as f32 * self.cell - o[a]) / d[a];
            } else if d[a] < -1e-12 {
                step[a] = -1;
                t_delta[a] = -self.cell / d[a];
                t_next[a] = (self.origin[a] + q[a] as f32 * self.cell - o[a]) / d[a];
            }
        }
        let mut t_in = entry;
        loop {
            // The axis whose boundary comes first (the lowest on ties).
            let axis = if t_next[0] <= t_next[1] {
                if t_next[0] <= t_next[2] { 0 } else { 2 }
            } else if t_next[1] <= t_next[2] {
                1
            } else {
                2
            };
            let t_out = t_next[axis].min(exit);
            let c = (q[2] * dims[1] + q[1]) * dims[0] + q[0];
            let items =
                &self.cell_items[self.cell_start[c] as usize..self.cell_start[c + 1] as usize];
            for item in items {
                if let Some((t, u)) = item.intersect(o, d)
                    && t > t_min
                    && t >= t_in
                    && t < t_out
                {
                    visit(Crossing {
                        segment: item.segment,
                        t,
                        u,
                    });
                }
            }
            if t_out >= exit {
                return;
            }
            let next = q[axis] as i64 + step[axis];
            if next < 0 || next >= dims[axis] as i64 {
                return;
            }
            q[axis] = next as usize;
            t_in = t_out;
            t_next[axis] += t_delta[axis];
        }
    }
}

/// Whether the segment ab meets the box [lo, hi] (slabs).
fn segment_meets_box(a: Vec3, b: Vec3, lo: Vec3, hi: Vec3) -> bool {
    let e = b - a;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for ax in 0..3 {
        if e[ax].abs() < 1e-20 {
            if a[ax] < lo[ax] || a[ax] > hi[ax] {
                return false;
            }
        } else {
            let (ta, tb) = ((lo[ax] - a[ax]) / e[ax], (hi[ax] - a[ax]) / e[ax]);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}
