//! What the USD and Alembic readers share: one batch of curves (a `BasisCurves` prim, an `ICurves`
//! object) checked and sampled into strands, and the report of a whole file.

use super::curves::{CurveKind, Interpolation, primvar_at, sample_curve};
use super::normalize::UpAxis;
use super::{MAX_POINTS, RawStrand};
use glam::Vec3;

/// A production curves file read: strands in the file's world space (its own units and up axis,
/// transforms applied), and what the file declared.
#[derive(Debug, Default, serde::Serialize)]
pub struct CurveFile {
    #[serde(skip)]
    pub strands: Vec<RawStrand>,
    /// The up axis the file declares (USD `upAxis`); None where the format declares none.
    pub up: Option<UpAxis>,
    /// Centimetres per file unit the file declares (USD `metersPerUnit` × 100).
    pub cm_per_unit: Option<f32>,
    /// The curve batches read (prim or object paths).
    pub batches: Vec<String>,
    /// Batches skipped, each with why (guide curves, unsupported curve types).
    pub skipped: Vec<String>,
    /// Curves and control points declared by the batches read.
    pub declared: (u64, u64),
    /// Whether widths were read, and the primvar the colours came from.
    pub widths: bool,
    pub colour: Option<String>,
    /// The time the values were read at, where any was sampled over time.
    pub time: Option<f64>,
    /// strandlight's look, where the file is strandlight's own export (JSON of `session::Look`).
    pub look: Option<String>,
    /// Points after sampling, so far.
    #[serde(skip)]
    pub sampled: u64,
}

/// A primvar of one batch: its interpolation and values (already expanded from any indices).
pub struct Primvar<'a, T> {
    pub name: &'a str,
    pub interpolation: Interpolation,
    pub values: &'a [T],
}

/// One batch of curves as its file holds it (points in world space).
pub struct CurveBatch<'a> {
    pub name: &'a str,
    pub kind: CurveKind,
    pub counts: &'a [i32],
    pub points: &'a [Vec3],
    pub widths: Option<Primvar<'a, f32>>,
    pub colour: Option<Primvar<'a, Vec3>>,
    /// strandlight's per-vertex absorption (its own export).
    pub sigma_a: Option<Primvar<'a, Vec3>>,
}

impl CurveBatch<'_> {
    /// Checks counts, values and primvar lengths, then samples every curve into `out`.
    pub fn append_to(&self, out: &mut CurveFile) -> Result<(), String> {
        let name = self.name;
        let mut total = 0u64;
        let mut varying = 0u64;
        for (c, &n) in self.counts.iter().enumerate() {
            let n = usize::try_from(n)
                .map_err(|_| format!("{name}: curve {c} has a negative vertex count {n}"))?;
            self.kind
                .segments(n)
                .map_err(|e| format!("{name}: curve {c} has {e}"))?;
            total += n as u64;
            varying += self.kind.varying_count(n).unwrap_or(0) as u64;
        }
        if total != self.points.len() as u64 {
            return Err(format!(
                "{name}: the vertex counts add up to {total} points, but {} are given",
                self.points.len()
            ));
        }
        if out.declared.1 + total > MAX_POINTS {
            return Err(format!(
                "{name}: more than {MAX_POINTS} points in one hairstyle"
            ));
        }
        if let Some(k) = self.points.iter().position(|p| !p.is_finite()) {
            return Err(format!("{name}: point {k} is not finite"));
        }
        let curves = self.counts.len() as u64;
        let expect = |i: Interpolation| match i {
            Interpolation::Constant => 1,
            Interpolation::Uniform => curves,
            Interpolation::Varying => varying,
            Interpolation::Vertex => total,
        };
        if let Some(w) = &self.widths {
            check_len(
                name,
                w.name,
                w.interpolation,
                w.values.len(),
                expect(w.interpolation),
            )?;
            if let Some(k) = w.values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(format!("{name}: width {k} is {}", w.values[k]));
            }
        }
        for c in self.colour.iter().chain(&self.sigma_a) {
            check_len(
                name,
                c.name,
                c.interpolation,
                c.values.len(),
                expect(c.interpolation),
            )?;
        }
        if let Some(a) = &self.sigma_a
            && let Some(k) = a.values.iter().position(|v| !v.is_finite())
        {
            return Err(format!("{name}: absorption {k} is not finite"));
        }
        let (mut ctrl, mut vary) = (0usize, 0usize);
        for (c, &n) in self.counts.iter().enumerate() {
            let n = n as usize;
            let v = self.kind.varying_count(n).unwrap_or(0);
            let (samples, points) = sample_curve(&self.kind, &self.points[ctrl..ctrl + n])?;
            // Sampling adds points: the cap holds for what is kept, not only what was read.
            out.sampled += points.len() as u64;
            if out.sampled > MAX_POINTS {
                return Err(format!(
                    "{name}: more than {MAX_POINTS} points once sampled"
                ));
            }
            let slice = |i: Interpolation| match i {
                Interpolation::Constant => 0..1,
                Interpolation::Uniform => c..c + 1,
                Interpolation::Varying => vary..vary + v,
                Interpolation::Vertex => ctrl..ctrl + n,
            };
            let thickness = self.widths.as_ref().map(|w| {
                let r = slice(w.interpolation);
                primvar_at(&self.kind, w.interpolation, &w.values[r], &samples)
            });
            let rgb = |p: &Primvar<Vec3>| {
                let r = slice(p.interpolation);
                primvar_at(&self.kind, p.interpolation, &p.values[r], &samples)
                    .into_iter()
                    .map(|v| v.max(Vec3::ZERO).to_array())
                    .collect()
            };
            out.strands.push(RawStrand {
                points,
                thickness: thickness.map(|t| t.into_iter().map(|w| w.max(0.0)).collect()),
                colour: self.colour.as_ref().map(rgb),
                transparency: None,
                sigma_a: self.sigma_a.as_ref().map(rgb),
            });
            ctrl += n;
            vary += v;
        }
        out.declared.0 += curves;
        out.declared.1 += total;
        out.widths |= self.widths.is_some();
        if let Some(c) = &self.colour {
            out.colour.get_or_insert_with(|| c.name.to_string());
        }
        out.batches.push(name.to_string());
        Ok(())
    }
}

fn check_len(
    batch: &str,
    primvar: &str,
    interpolation: Interpolation,
    got: usize,
    expected: u64,
) -> Result<(), String> {
    if got as u64 == expected {
        return Ok(());
    }
    Err(format!(
        "{batch}: {primvar} has {got} values, where {} interpolation on these \
         curves needs {expected}",
        format!("{interpolation:?}").to_lowercase()
    ))
}
