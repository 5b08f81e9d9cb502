//! Curves as production tools write them (USD `BasisCurves`, Alembic `ICurves`): linear or cubic
//! (Bézier, B-spline, Catmull-Rom) with non-periodic, periodic or pinned wrap, sampled to the
//! polylines the renderer draws, with their primvars carried along. docs/file-formats.md states the
//! rules; this module follows the USD specification's (`UsdGeomBasisCurves`).
//!
//! Sampling is adaptive: each cubic segment is cut into 1, 2, 4, 8 or 16 pieces, the fewest for
//! which every piece's midpoint lies within [`FLATNESS`] of its chord length from the chord, so
//! straight runs cost no extra points and curls keep their shape. Segment ends are always samples,
//! so an interpolating basis (Catmull-Rom, linear) passes through its control points.

use glam::Vec3;
use std::ops::{Add, Mul};

/// A piece's midpoint may sit this fraction of the piece's chord away from the chord.
pub const FLATNESS: f32 = 0.03;

/// Most pieces one cubic segment is cut into.
pub const MAX_PIECES: usize = 16;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Basis {
    Linear,
    Bezier,
    Bspline,
    CatmullRom,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    NonPeriodic,
    Periodic,
    /// B-spline and Catmull-Rom curves through their end points: a phantom point 2·P0 − P1 before
    /// the first and 2·Pn−1 − Pn−2 after the last. Bézier curves pinned are non-periodic ones.
    Pinned,
}

/// How a primvar's values map onto the curves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Constant,
    /// One value per curve.
    Uniform,
    /// One value per segment end (per vertex for linear curves).
    Varying,
    /// One value per control point, interpolated by the basis like the points.
    Vertex,
}

impl Interpolation {
    /// The USD token (`faceVarying` reads as `varying`, as the specification says for curves).
    pub fn from_token(t: &str) -> Option<Self> {
        Some(match t {
            "constant" => Self::Constant,
            "uniform" => Self::Uniform,
            "varying" | "faceVarying" => Self::Varying,
            "vertex" => Self::Vertex,
            _ => return None,
        })
    }
}

/// The shape rules shared by every curve of one prim.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CurveKind {
    pub basis: Basis,
    pub wrap: Wrap,
}

impl std::fmt::Display for CurveKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let basis = match self.basis {
            Basis::Linear => "linear",
            Basis::Bezier => "cubic Bézier",
            Basis::Bspline => "cubic B-spline",
            Basis::CatmullRom => "cubic Catmull-Rom",
        };
        let wrap = match self.wrap {
            Wrap::NonPeriodic => "non-periodic",
            Wrap::Periodic => "periodic",
            Wrap::Pinned => "pinned",
        };
        write!(f, "a {wrap} {basis} curve")
    }
}

impl CurveKind {
    fn pinned(&self) -> bool {
        self.wrap == Wrap::Pinned && matches!(self.basis, Basis::Bspline | Basis::CatmullRom)
    }

    /// The number of segments of a curve of `n` control points, or why `n` is not valid.
    pub fn segments(&self, n: usize) -> Result<usize, String> {
        let periodic = self.wrap == Wrap::Periodic;
        let bad = |need: &str| Err(format!("{n} control points, where {self} needs {need}"));
        match self.basis {
            Basis::Linear if n < 2 => bad("at least 2"),
            Basis::Linear => Ok(if periodic { n } else { n - 1 }),
            Basis::Bezier if periodic => match n {
                n if n >= 3 && n % 3 == 0 => Ok(n / 3),
                _ => bad("a multiple of 3"),
            },
            Basis::Bezier => match n {
                n if n >= 4 && (n - 4) % 3 == 0 => Ok((n - 4) / 3 + 1),
                _ => bad("4 + 3k"),
            },
            _ if periodic && n < 3 => bad("at least 3"),
            _ if periodic => Ok(n),
            _ if self.pinned() && n < 2 => bad("at least 2"),
            _ if self.pinned() => Ok(n - 1),
            _ if n < 4 => bad("at least 4"),
            _ => Ok(n - 3),
        }
    }

    /// The number of values a `varying` primvar has on a curve of `n` control points.
    pub fn varying_count(&self, n: usize) -> Result<usize, String> {
        let segments = self.segments(n)?;
        Ok(if self.wrap == Wrap::Periodic {
            segments
        } else {
            segments + 1
        })
    }

    /// The basis weights at `t` in [0, 1] over the segment's four control values.
    fn weights(&self, t: f32) -> [f32; 4] {
        let (t2, t3) = (t * t, t * t * t);
        let s = 1.0 - t;
        match self.basis {
            Basis::Linear => [s, t, 0.0, 0.0],
            Basis::Bezier => [s * s * s, 3.0 * t * s * s, 3.0 * t2 * s, t3],
            Basis::Bspline => [
                s * s * s / 6.0,
                (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
                (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
                t3 / 6.0,
            ],
            Basis::CatmullRom => [
                0.5 * (-t3 + 2.0 * t2 - t),
                0.5 * (3.0 * t3 - 5.0 * t2 + 2.0),
                0.5 * (-3.0 * t3 + 4.0 * t2 + t),
                0.5 * (t3 - t2),
            ],
        }
    }

    /// The value of a `vertex`-interpolated quantity (the points themselves, or a primvar) on
    /// segment `seg` at `t`.
    pub fn eval<T>(&self, ctrl: &[T], seg: usize, t: f32) -> T
    where
        T: Copy + Add<Output = T> + Mul<f32, Output = T>,
    {
        let n = ctrl.len() as isize;
        let periodic = self.wrap == Wrap::Periodic;
        // Control index k of the extended sequence (phantoms at -1 and n when pinned).
        let at = |k: isize| -> T {
            if periodic {
                ctrl[k.rem_euclid(n) as usize]
            } else if k < 0 {
                ctrl[0] * 2.0 + ctrl[1] * -1.0
            } else if k >= n {
                ctrl[(n - 1) as usize] * 2.0 + ctrl[(n - 2) as usize] * -1.0
            } else {
                ctrl[k as usize]
            }
        };
        let seg = seg as isize;
        let (first, count) = match self.basis {
            Basis::Linear => (seg, 2),
            Basis::Bezier => (3 * seg, 4),
            _ if self.pinned() => (seg - 1, 4),
            _ => (seg, 4),
        };
        let w = self.weights(t);
        let mut v = at(first) * w[0];
        for (j, wj) in w.iter().enumerate().take(count).skip(1) {
            v = v + at(first + j as isize) * *wj;
        }
        v
    }
}

/// Where a sample of the polyline lies on its curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub segment: usize,
    pub t: f32,
}

/// The polyline of one curve: its samples (segment and parameter) and their points.
pub fn sample_curve(kind: &CurveKind, ctrl: &[Vec3]) -> Result<(Vec<Sample>, Vec<Vec3>), String> {
    let segments = kind.segments(ctrl.len())?;
    let mut samples = Vec::with_capacity(segments + 1);
    let mut points = Vec::with_capacity(segments + 1);
    for seg in 0..segments {
        let pieces = if kind.basis == Basis::Linear {
            1
        } else {
            pieces_for(kind, ctrl, seg)
        };
        for j in 0..pieces {
            let t = j as f32 / pieces as f32;
            samples.push(Sample { segment: seg, t });
            points.push(kind.eval(ctrl, seg, t));
        }
    }
    samples.push(Sample {
        segment: segments - 1,
        t: 1.0,
    });
    points.push(kind.eval(ctrl, segments - 1, 1.0));
    Ok((samples, points))
}

/// The fewest pieces (a power of two up to [`MAX_PIECES`]) whose midpoints stay within
/// [`FLATNESS`] of their chords.
fn pieces_for(kind: &CurveKind, ctrl: &[Vec3], seg: usize) -> usize {
    let mut pieces = 1;
    while pieces < MAX_PIECES {
        let flat = (0..pieces).all(|j| {
            let (a, b) = (j as f32 / pieces as f32, (j + 1) as f32 / pieces as f32);
            let (pa, pb) = (kind.eval(ctrl, seg, a), kind.eval(ctrl, seg, b));
            let mid = kind.eval(ctrl, seg, 0.5 * (a + b));
            mid.distance(0.5 * (pa + pb)) <= FLATNESS * pa.distance(pb)
        });
        if flat {
            break;
        }
        pieces *= 2;
    }
    pieces
}

/// A primvar's values at the samples of one curve. `values` are the curve's own values for its
/// interpolation (one, one per segment end, or one per control point).
pub fn primvar_at<T>(
    kind: &CurveKind,
    interpolation: Interpolation,
    values: &[T],
    samples: &[Sample],
) -> Vec<T>
where
    T: Copy + Add<Output = T> + Mul<f32, Output = T>,
{
    match interpolation {
        Interpolation::Constant | Interpolation::Uniform => vec![values[0]; samples.len()],
        Interpolation::Vertex => samples
            .iter()
            .map(|s| kind.eval(values, s.segment, s.t))
            .collect(),
        Interpolation::Varying => samples
            .iter()
            .map(|s| {
                let a = values[s.segment];
                let b = values[(s.segment + 1) % values.len()];
                a * (1.0 - s.t) + b * s.t
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn helix(n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|k| {
                let a = k as f32 * 0.9;
                Vec3::new(a.cos(), k as f32 * 0.3, a.sin())
            })
            .collect()
    }

    #[test]
    fn segment_counts_follow_the_usd_rules() {
        let k = |basis, wrap| CurveKind { basis, wrap };
        use Basis::*;
        use Wrap::*;
        assert_eq!(k(Linear, NonPeriodic).segments(5), Ok(4));
        assert_eq!(k(Linear, Periodic).segments(5), Ok(5));
        assert_eq!(k(Bezier, NonPeriodic).segments(7), Ok(2));
        assert!(k(Bezier, NonPeriodic).segments(6).is_err());
        assert_eq!(k(Bezier, Periodic).segments(6), Ok(2));
        assert_eq!(k(Bezier, Pinned).segments(7), Ok(2));
        assert_eq!(k(CatmullRom, NonPeriodic).segments(6), Ok(3));
        assert_eq!(k(CatmullRom, Pinned).segments(6), Ok(5));
        assert_eq!(k(Bspline, Periodic).segments(6), Ok(6));
        assert!(k(Bspline, NonPeriodic).segments(3).is_err());
        assert_eq!(k(CatmullRom, Pinned).varying_count(6), Ok(6));
        assert_eq!(k(Bspline, NonPeriodic).varying_count(6), Ok(4));
        assert_eq!(k(Bspline, Periodic).varying_count(6), Ok(6));
    }

    #[test]
    fn interpolating_bases_pass_through_their_points_and_bsplines_pin_their_ends() {
        let p = helix(9);
        let cr = CurveKind {
            basis: Basis::CatmullRom,
            wrap: Wrap::Pinned,
        };
        let (_, line) = sample_curve(&cr, &p).unwrap();
        for q in &p {
            let d = line.iter().map(|l| l.distance(*q)).fold(f32::MAX, f32::min);
            assert!(d < 1e-5, "control point {q} is {d} from the polyline");
        }
        let bs = CurveKind {
            basis: Basis::Bspline,
            wrap: Wrap::Pinned,
        };
        let (_, line) = sample_curve(&bs, &p).unwrap();
        assert!(line[0].distance(p[0]) < 1e-5 && line.last().unwrap().distance(p[8]) < 1e-5);
        // A non-periodic Catmull-Rom runs from the second point to the one before last.
        let np = CurveKind {
            basis: Basis::CatmullRom,
            wrap: Wrap::NonPeriodic,
        };
        let (_, line) = sample_curve(&np, &p).unwrap();
        assert!(line[0].distance(p[1]) < 1e-5 && line.last().unwrap().distance(p[7]) < 1e-5);
    }

    #[test]
    fn sampling_is_flat_to_its_tolerance_and_straight_runs_stay_sparse() {
        let p = helix(12);
        let kind = CurveKind {
            basis: Basis::Bspline,
            wrap: Wrap::NonPeriodic,
        };
        let (samples, line) = sample_curve(&kind, &p).unwrap();
        // Brute force: the curve at 64 parameters per segment against the polyline's chords.
        for w in samples.windows(2).zip(line.windows(2)) {
            let ((s, l), _) = (w, ());
            let (a, b) = (l[0], l[1]);
            let seg = s[0].segment;
            let t1 = if s[1].segment == seg { s[1].t } else { 1.0 };
            for j in 0..=64 {
                let t = s[0].t + (t1 - s[0].t) * j as f32 / 64.0;
                let c = kind.eval(&p, seg, t);
                let ab = b - a;
                let u = ((c - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                let d = c.distance(a + ab * u);
                assert!(d <= 2.0 * FLATNESS * ab.length() + 1e-6, "{d}");
            }
        }
        let straight: Vec<Vec3> = (0..10).map(|k| Vec3::Y * k as f32).collect();
        let (_, line) = sample_curve(&kind, &straight).unwrap();
        assert_eq!(line.len(), kind.segments(10).unwrap() + 1);
    }

    #[test]
    fn primvars_follow_their_interpolation() {
        let kind = CurveKind {
            basis: Basis::CatmullRom,
            wrap: Wrap::Pinned,
        };
        let samples = [
            Sample { segment: 0, t: 0.0 },
            Sample { segment: 1, t: 0.5 },
            Sample { segment: 2, t: 1.0 },
        ];
        let vertex = [1.0f32, 2.0, 3.0, 4.0];
        let v = primvar_at(&kind, Interpolation::Vertex, &vertex, &samples);
        assert_eq!(v, vec![1.0, 2.5, 4.0]);
        let varying = [0.0f32, 10.0, 20.0, 30.0];
        let v = primvar_at(&kind, Interpolation::Varying, &varying, &samples);
        assert_eq!(v, vec![0.0, 15.0, 30.0]);
        let v = primvar_at(&kind, Interpolation::Uniform, &[7.0f32], &samples);
        assert_eq!(v, vec![7.0; 3]);
    }
}
