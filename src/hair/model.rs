//! The one in-memory hair representation used after loading.
//!
//! World units are centimetres with +Y up (see [`super::normalize`]). Strands are stored as
//! structure-of-arrays: all points in one array, `strand_offsets[s]..strand_offsets[s + 1]` the
//! points of strand `s`, root first.

use glam::Vec3;

/// Fiber thickness (diameter, world units).
#[derive(Clone, Debug, PartialEq)]
pub enum Thickness {
    Uniform(f32),
    PerStrand(Vec<f32>),
    PerPoint(Vec<f32>),
}

/// A strand before cleaning, as parsers produce it.
#[derive(Clone, Debug, Default)]
pub struct RawStrand {
    pub points: Vec<Vec3>,
    pub thickness: Option<Vec<f32>>,
    pub colour: Option<Vec<[f32; 3]>>,
    pub transparency: Option<Vec<f32>>,
    /// Absorption per point, where the file carries strandlight's own (its USD export).
    pub sigma_a: Option<Vec<[f32; 3]>>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Hair {
    pub positions: Vec<Vec3>,
    /// Length strands + 1; strand s owns points strand_offsets[s]..strand_offsets[s + 1].
    pub strand_offsets: Vec<u32>,
    /// Index of each strand in the source file (strands dropped while cleaning leave gaps).
    pub strand_ids: Vec<u32>,
    pub thickness: Thickness,
    /// Optional per-point linear RGB colour.
    pub colour: Option<Vec<[f32; 3]>>,
    /// Optional per-point transparency (cyHair).
    pub transparency: Option<Vec<f32>>,
    /// Optional per-point absorption a file carried (strandlight's USD export).
    pub sigma_a: Option<Vec<[f32; 3]>>,
}

/// What cleaning removed, for reporting.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CleanReport {
    pub zero_length_segments_removed: usize,
    pub short_strands_dropped: usize,
}

/// Fiber diameter (cm) for files that carry none (TressFX, glTF): 70 micrometres, a typical human hair.
pub const DEFAULT_FIBER_DIAMETER: f32 = 0.007;

/// Points closer than this (world units) are merged: their segment has no direction.
pub const MIN_SEGMENT_LENGTH: f32 = 1e-6;

impl Hair {
    /// Builds a hair from raw strands: removes zero-length segments, drops strands with fewer than
    /// two distinct points. Non-finite coordinates must have been rejected by the parser.
    pub fn from_strands(strands: Vec<RawStrand>, default_thickness: f32) -> (Self, CleanReport) {
        let mut report = CleanReport::default();
        let mut positions = Vec::new();
        let mut offsets = vec![0u32];
        let mut ids = Vec::new();
        let any_thickness = strands.iter().any(|s| s.thickness.is_some());
        let any_colour = strands.iter().any(|s| s.colour.is_some());
        let any_transparency = strands.iter().any(|s| s.transparency.is_some());
        let any_sigma_a = strands.iter().any(|s| s.sigma_a.is_some());
        let mut sigma_a = Vec::new();
        let mut thickness = Vec::new();
        let mut colour = Vec::new();
        let mut transparency = Vec::new();
        for (id, s) in strands.into_iter().enumerate() {
            let mut keep: Vec<usize> = Vec::with_capacity(s.points.len());
            for (k, p) in s.points.iter().enumerate() {
                match keep.last() {
                    Some(&last) if s.points[last].distance(*p) < MIN_SEGMENT_LENGTH => {
                        report.zero_length_segments_removed += 1
                    }
                    _ => keep.push(k),
                }
            }
            if keep.len() < 2 {
                report.short_strands_dropped += 1;
                continue;
            }
            for &k in &keep {
                positions.push(s.points[k]);
                if any_thickness {
                    thickness.push(s.thickness.as_ref().map_or(default_thickness, |t| t[k]));
                }
                if any_colour {
                    colour.push(s.colour.as_ref().map_or([1.0; 3], |c| c[k]));
                }
                if any_transparency {
                    transparency.push(s.transparency.as_ref().map_or(0.0, |t| t[k]));
                }
                if any_sigma_a {
                    sigma_a.push(s.sigma_a.as_ref().map_or([0.0; 3], |a| a[k]));
                }
            }
            offsets.push(positions.len() as u32);
            ids.push(id as u32);
        }
        let hair = Hair {
            positions,
            strand_offsets: offsets,
            strand_ids: ids,
            thickness: if any_thickness {
                Thickness::PerPoint(thickness)
            } else {
                Thickness::Uniform(default_thickness)
            },
            colour: any_colour.then_some(colour),
            transparency: any_transparency.then_some(transparency),
            sigma_a: any_sigma_a.then_some(sigma_a),
        };
        (hair, report)
    }

    pub fn strand_count(&self) -> usize {
        self.strand_offsets.len() - 1
    }

    pub fn point_count(&self) -> usize {
        self.positions.len()
    }

    pub fn strand_range(&self, s: usize) -> std::ops::Range<usize> {
        self.strand_offsets[s] as usize..self.strand_offsets[s + 1] as usize
    }

    pub fn strand(&self, s: usize) -> &[Vec3] {
        &self.positions[self.strand_range(s)]
    }

    /// The points of the strand that holds point `i` (global indices).
    pub fn strand_of_point(&self, i: u32) -> std::ops::Range<u32> {
        let o = &self.strand_offsets;
        let s = o.partition_point(|&x| x <= i).saturating_sub(1);
        o[s]..o[(s + 1).min(o.len() - 1)]
    }

    /// Thickness (diameter) at a point.
    pub fn thickness_at(&self, strand: usize, point: usize) -> f32 {
        match &self.thickness {
            Thickness::Uniform(t) => *t,
            Thickness::PerStrand(v) => v[strand],
            Thickness::PerPoint(v) => v[point],
        }
    }

    /// Arc length of each strand.
    pub fn strand_lengths(&self) -> Vec<f32> {
        (0..self.strand_count())
            .map(|s| self.strand(s).windows(2).map(|w| w[0].distance(w[1])).sum())
            .collect()
    }

    /// Root-to-tip parameter in [0, 1] per point (normalised arc length along its strand).
    pub fn root_to_tip(&self) -> Vec<f32> {
        let mut t = vec![0.0; self.point_count()];
        for s in 0..self.strand_count() {
            let r = self.strand_range(s);
            let pts = &self.positions[r.clone()];
            let mut acc = 0.0;
            let mut cum = vec![0.0f32; pts.len()];
            for k in 1..pts.len() {
                acc += pts[k].distance(pts[k - 1]);
                cum[k] = acc;
            }
            for (k, c) in cum.iter().enumerate() {
                t[r.start + k] = if acc > 0.0 { c / acc } else { 0.0 };
            }
        }
        t
    }

    /// Unit tangents per point, root to tip: the normalised sum of the unit directions of the
    /// adjacent segments (one-sided at the ends). Never zero: cleaning removed zero-length
    /// segments, and a hairpin (opposite segments) falls back to the incoming direction.
    pub fn tangents(&self) -> Vec<Vec3> {
        let mut out = vec![Vec3::Y; self.point_count()];
        for s in 0..self.strand_count() {
            let r = self.strand_range(s);
            let p = &self.positions[r.clone()];
            let n = p.len();
            for k in 0..n {
                let incoming = (k > 0).then(|| (p[k] - p[k - 1]).normalize_or_zero());
                let outgoing = (k + 1 < n).then(|| (p[k + 1] - p[k]).normalize_or_zero());
                let t = match (incoming, outgoing) {
                    (Some(a), Some(b)) => (a + b).try_normalize().unwrap_or(a),
                    (Some(a), None) => a,
                    (None, Some(b)) => b,
                    (None, None) => Vec3::Y,
                };
                out[r.start + k] = if t.is_finite() && t != Vec3::ZERO {
                    t
                } else {
                    Vec3::Y
                };
            }
        }
        out
    }

    /// Axis-aligned bounds (min, max). Empty hair gives (0, 0).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if self.positions.is_empty() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        self.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        )
    }

    /// Applies `f` to every position and scales thickness by `thickness_scale`.
    pub fn transform(&mut self, f: impl Fn(Vec3) -> Vec3, thickness_scale: f32) {
        for p in &mut self.positions {
            *p = f(*p);
        }
        match &mut self.thickness {
            Thickness::Uniform(t) => *t *= thickness_scale,
            Thickness::PerStrand(v) | Thickness::PerPoint(v) => {
                v.iter_mut().for_each(|t| *t *= thickness_scale)
            }
        }
    }

    /// Catmull-Rom resampling of every strand to `points` points evenly spaced in arc length
    /// (centripetal parameterisation is unnecessary: segments are already near-uniform).
    /// Per-point attributes are interpolated linearly.
    pub fn resample_points(&self, points: usize) -> Hair {
        let points = points.max(2);
        self.resample_with(|_| points)
    }

    /// Resampling to a target segment length (world units); every strand keeps at least 2 points.
    pub fn resample_segment_length(&self, length: f32) -> Hair {
        let lengths = self.strand_lengths();
        self.resample_with(|s| {
            ((lengths[s] / length.max(1e-6)).round() as usize + 1).clamp(2, 4096)
        })
    }

    fn resample_with(&self, count: impl Fn(usize) -> usize) -> Hair {
        let mut strands = Vec::with_capacity(self.strand_count());
        for s in 0..self.strand_count() {
            let r = self.strand_range(s);
            let p = &self.positions[r.clone()];
            let mut cum = vec![0.0f32; p.len()];
            for k in 1..p.len() {
                cum[k] = cum[k - 1] + p[k].distance(p[k - 1]);
            }
            let total = cum[p.len() - 1];
            let n = count(s);
            let mut raw = RawStrand::default();
            let per_point_thickness = matches!(self.thickness, Thickness::PerPoint(_));
            for j in 0..n {
                let target = total * j as f32 / (n - 1) as f32;
                let seg = cum.partition_point(|&c| c <= target).clamp(1, p.len() - 1) - 1;
                let len = cum[seg + 1] - cum[seg];
                let u = if len > 0.0 {
                    ((target - cum[seg]) / len).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let p0 = if seg > 0 {
                    p[seg - 1]
                } else {
                    2.0 * p[seg] - p[seg + 1]
                };
                let p3 = if seg + 2 < p.len() {
                    p[seg + 2]
                } else {
                    2.0 * p[seg + 1] - p[seg]
                };
                raw.points.push(catmull_rom(p0, p[seg], p[seg + 1], p3, u));
                let lerp = |a: f32, b: f32| a + (b - a) * u;
                if per_point_thickness {
                    let a = self.thickness_at(s, r.start + seg);
                    let b = self.thickness_at(s, r.start + seg + 1);
                    raw.thickness.get_or_insert_with(Vec::new).push(lerp(a, b));
                }
                if let Some(c) = &self.colour {
                    let (a, b) = (c[r.start + seg], c[r.start + seg + 1]);
                    raw.colour
                        .get_or_insert_with(Vec::new)
                        .push(std::array::from_fn(|i| lerp(a[i], b[i])));
                }
                if let Some(t) = &self.transparency {
                    raw.transparency
                        .get_or_insert_with(Vec::new)
                        .push(lerp(t[r.start + seg], t[r.start + seg + 1]));
                }
                if let Some(c) = &self.sigma_a {
                    let (a, b) = (c[r.start + seg], c[r.start + seg + 1]);
                    raw.sigma_a
                        .get_or_insert_with(Vec::new)
                        .push(std::array::from_fn(|i| lerp(a[i], b[i])));
                }
            }
            strands.push(raw);
        }
        let default_thickness = match &self.thickness {
            Thickness::Uniform(t) => *t,
            _ => 0.0,
        };
        let (mut hair, _) = Hair::from_strands(strands, default_thickness);
        if let Thickness::PerStrand(v) = &self.thickness {
            hair.thickness =
                Thickness::PerStrand(hair.strand_ids.iter().map(|&i| v[i as usize]).collect());
        }
        hair.strand_ids = hair
            .strand_ids
            .iter()
            .map(|&i| self.strand_ids[i as usize])
            .collect();
        hair
    }
}

/// Uniform Catmull-Rom segment between p1 and p2 at u in [0, 1].
fn catmull_rom(p0: Vec3, p1: Vec3, p2: Vec3, p3: Vec3, u: f32) -> Vec3 {
    let u2 = u * u;
    let u3 = u2 * u;
    0.5 * ((2.0 * p1)
        + (-p0 + p2) * u
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u2
        + (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * u3)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strand(points: &[[f32; 3]]) -> RawStrand {
        RawStrand {
            points: points.iter().map(|p| Vec3::from_array(*p)).collect(),
            ..Default::default()
        }
    }

    #[test]
    fn cleaning_removes_zero_length_segments_and_short_strands() {
        let (hair, report) = Hair::from_strands(
            vec![
                strand(&[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
                strand(&[[1.0, 1.0, 1.0], [1.0, 1.0, 1.0]]),
                strand(&[[2.0, 0.0, 0.0]]),
                strand(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]),
            ],
            0.01,
        );
        assert_eq!(hair.strand_count(), 2);
        assert_eq!(hair.strand_ids, vec![0, 3]);
        assert_eq!(report.zero_length_segments_removed, 2);
        assert_eq!(report.short_strands_dropped, 2);
        let t = hair.tangents();
        assert!(t.iter().all(|v| (v.length() - 1.0).abs() < 1e-5));
        let u = hair.root_to_tip();
        assert_eq!((u[2], u[3], u[4]), (0.0, 0.5, 1.0));
    }

    #[test]
    fn resampling_keeps_ends_and_follows_the_curve() {
        let pts: Vec<[f32; 3]> = (0..20)
            .map(|k| {
                let a = k as f32 * 0.2;
                [a.cos(), a.sin(), 0.1 * a]
            })
            .collect();
        let (hair, _) = Hair::from_strands(vec![strand(&pts)], 0.01);
        let r = hair.resample_points(60);
        assert_eq!(r.point_count(), 60);
        assert!(r.positions[0].distance(hair.positions[0]) < 1e-6);
        assert!(r.positions[59].distance(hair.positions[19]) < 1e-5);
        // Points stay near the helix of radius 1.
        for p in &r.positions {
            assert!(((p.x * p.x + p.y * p.y).sqrt() - 1.0).abs() < 0.01, "{p}");
        }
        let lengths = (hair.strand_lengths()[0], r.strand_lengths()[0]);
        assert!((lengths.0 - lengths.1).abs() / lengths.0 < 0.01);
    }
}
