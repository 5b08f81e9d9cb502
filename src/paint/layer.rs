//! The paint layer: painted absorption per hair point, as the editor saves it and `render --paint`
//! reads it. Little-endian binary:
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `SLPAINT1` |
//! | 4 | u32 format version (1) |
//! | 4 | u32 reserved (0) |
//! | 8 | u64 point count N (must equal the hair's) |
//! | 8 | u64 strand count (must equal the hair's) |
//! | 16 N | per point f32 sigma_a R, G, B and f32 weight in [0, 1] |
//!
//! A point's absorption is mix(base, painted, weight): weight 0 keeps the base (unpainted).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

pub const MAGIC: &[u8; 8] = b"SLPAINT1";
pub const VERSION: u32 = 1;
const HEADER: usize = 32;

#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PaintLayer {
    pub strand_count: u64,
    /// (sigma_a RGB, weight) per point.
    pub points: Vec<[f32; 4]>,
}

#[derive(Debug, thiserror::Error)]
pub enum PaintLayerError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
}

impl PaintLayer {
    /// Parses the bytes of a layer; errors name `path` and the problem.
    pub fn decode(bytes: &[u8], path: &Path) -> Result<Self, PaintLayerError> {
        let bad = |message: String| PaintLayerError::Format {
            path: path.into(),
            message,
        };
        if bytes.len() < HEADER || &bytes[..8] != MAGIC {
            return Err(bad(
                "not a strandlight paint layer (no SLPAINT1 header)".into()
            ));
        }
        let u32_at =
            |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
        let u64_at = |o: usize| u64::from_le_bytes(std::array::from_fn(|k| bytes[o + k]));
        let version = u32_at(8);
        if version != VERSION {
            return Err(bad(format!(
                "format version {version}, this build reads {VERSION}"
            )));
        }
        let (n, strands) = (u64_at(16), u64_at(24));
        let body = (bytes.len() - HEADER) as u64;
        if n.checked_mul(16) != Some(body) {
            return Err(bad(format!(
                "declares {n} points but holds {body} bytes of point data ({} expected)",
                n.saturating_mul(16)
            )));
        }
        let mut points = Vec::with_capacity(n as usize);
        for (k, chunk) in bytes[HEADER..].chunks_exact(16).enumerate() {
            let v: [f32; 4] = std::array::from_fn(|c| {
                f32::from_le_bytes([
                    chunk[4 * c],
                    chunk[4 * c + 1],
                    chunk[4 * c + 2],
                    chunk[4 * c + 3],
                ])
            });
            if v[..3].iter().any(|x| !x.is_finite() || *x < 0.0) {
                return Err(bad(format!(
                    "point {k}: absorption {:?} is not finite and >= 0",
                    &v[..3]
                )));
            }
            if !(0.0..=1.0).contains(&v[3]) {
                return Err(bad(format!("point {k}: weight {} outside [0, 1]", v[3])));
            }
            points.push(v);
        }
        Ok(Self {
            strand_count: strands,
            points,
        })
    }

    pub fn read(path: &Path) -> Result<Self, PaintLayerError> {
        let bytes = std::fs::read(path).map_err(|source| PaintLayerError::Io {
            path: path.into(),
            source,
        })?;
        Self::decode(&bytes, path)
    }

    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(HEADER + 16 * self.points.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        out.extend_from_slice(&(self.points.len() as u64).to_le_bytes());
        out.extend_from_slice(&self.strand_count.to_le_bytes());
        for p in &self.points {
            for v in p {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        out
    }

    /// Writes the layer atomically (temporary file, fsync, rename).
    pub fn write(&self, path: &Path) -> Result<(), PaintLayerError> {
        crate::files::write_atomic(path, &self.encode()).map_err(|source| PaintLayerError::Io {
            path: path.into(),
            source,
        })
    }

    /// An unpainted layer for a hair.
    pub fn empty(points: usize, strands: usize) -> Self {
        Self {
            strand_count: strands as u64,
            points: vec![[0.0; 4]; points],
        }
    }

    /// A layer that dyes every point with the absorption its file colour gives (Chiang's
    /// inversion at `beta_n`, `paint::dye`), at full weight; None when the hair has no colours.
    /// A groom's colours from another tool become strandlight's dye this way.
    pub fn from_colours(hair: &crate::hair::Hair, beta_n: f64) -> Option<Self> {
        let colours = hair.colour.as_ref()?;
        let mut layer = Self::empty(hair.point_count(), hair.strand_count());
        for (p, c) in layer.points.iter_mut().zip(colours) {
            let s = super::dye::sigma_a_from_colour(c.map(f64::from), beta_n);
            *p = [s[0] as f32, s[1] as f32, s[2] as f32, 1.0];
        }
        Some(layer)
    }

    /// Whether the layer was painted on a hair of this many points and strands.
    pub fn fits(&self, points: usize, strands: usize) -> bool {
        self.points.len() == points && self.strand_count == strands as u64
    }

    /// Applies the layer over `base` (one absorption per point of a hair of `strands` strands).
    pub fn apply(
        &self,
        base: &mut [[f32; 3]],
        strands: usize,
        path: &Path,
    ) -> Result<(), PaintLayerError> {
        if self.points.len() != base.len() || self.strand_count != strands as u64 {
            return Err(PaintLayerError::Format {
                path: path.into(),
                message: format!(
                    "painted for {} points in {} strands, the hair has {} points in {strands} strands",
                    self.points.len(),
                    self.strand_count,
                    base.len()
                ),
            });
        }
        for (b, p) in base.iter_mut().zip(&self.points) {
            for c in 0..3 {
                b[c] += p[3] * (p[c] - b[c]);
            }
        }
        Ok(())
    }
}

/// Revisions of shared layers: every change takes a new number, so equal numbers mean equal values.
static REVISION: AtomicU64 = AtomicU64::new(1);

/// A paint layer shared by the session, its saved copy, the undo history's view of it and the scene
/// loader: cloned without copying, changed copy-on-write, equal when their values are (compared by
/// revision first, so the editor's per-frame "modified?" check costs nothing while nothing changed).
#[derive(Clone, Debug)]
pub struct SharedLayer {
    layer: Arc<PaintLayer>,
    revision: u64,
}

impl SharedLayer {
    pub fn new(layer: PaintLayer) -> Self {
        Self {
            layer: Arc::new(layer),
            revision: REVISION.fetch_add(1, Ordering::Relaxed),
        }
    }

    pub fn get(&self) -> &PaintLayer {
        &self.layer
    }

    /// The layer to change (copied first when shared); takes a new revision.
    pub fn make_mut(&mut self) -> &mut PaintLayer {
        self.revision = REVISION.fetch_add(1, Ordering::Relaxed);
        Arc::make_mut(&mut self.layer)
    }

    /// Changes with every [`SharedLayer::make_mut`].
    pub fn revision(&self) -> u64 {
        self.revision
    }
}

/// Edits are data: a layer serialises as its plain values.
impl serde::Serialize for SharedLayer {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.layer.serialize(s)
    }
}

impl<'de> serde::Deserialize<'de> for SharedLayer {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        PaintLayer::deserialize(d).map(SharedLayer::new)
    }
}

impl PartialEq for SharedLayer {
    fn eq(&self, other: &Self) -> bool {
        self.revision == other.revision
            || Arc::ptr_eq(&self.layer, &other.layer)
            || (self.layer.strand_count == other.layer.strand_count
                && bytemuck::cast_slice::<[f32; 4], u8>(&self.layer.points)
                    == bytemuck::cast_slice::<[f32; 4], u8>(&other.layer.points))
    }
}
