//! AMD TressFX `.tfx` binary assets.
//!
//! - 3.x (version float 3.x): a 296-byte header — version f32, strand count u32, vertices per strand
//!   u32, then flags (offset 16: both ends immovable) and reserved bytes — followed by float3 positions.
//! - 4.x (version float 4.x): a 160-byte header — version f32, strand count u32, vertices per strand
//!   u32, then byte offsets of vertex positions, strand UVs, vertex UVs, strand thickness and vertex
//!   colours (0 = absent), reserved — with float4 positions (w = inverse mass) and float2 strand UVs.

use super::bytes::Reader;
use super::error::{HairError, MAX_POINTS};
use super::model::{CleanReport, DEFAULT_FIBER_DIAMETER, Hair, RawStrand};
use glam::Vec3;
use std::path::Path;

#[derive(Clone, Debug, PartialEq)]
pub struct TressFxInfo {
    pub version: f32,
    pub strands: u32,
    pub vertices_per_strand: u32,
    /// Per-strand UVs (4.x only).
    pub strand_uvs: Option<Vec<[f32; 2]>>,
}

pub fn read_tressfx(
    bytes: &[u8],
    path: &Path,
) -> Result<(Hair, TressFxInfo, CleanReport), HairError> {
    let r = Reader::new(bytes, path);
    let version = r.f32_at(0, "version")?;
    let strands = r.u32_at(4, "strand count")?;
    let per = r.u32_at(8, "vertices per strand")?;
    let major = if (3.0..4.0).contains(&version) {
        3
    } else if (4.0..5.0).contains(&version) {
        4
    } else {
        return Err(r.err(format!(
            "not a TressFX file: version field {version} is not 3.x or 4.x"
        )));
    };
    if strands == 0 {
        return Err(r.err("the file has zero strands"));
    }
    if per < 2 {
        return Err(r.err(format!(
            "{per} vertices per strand: a strand needs at least 2"
        )));
    }
    let n_points = strands as u64 * per as u64;
    if n_points > MAX_POINTS {
        return Err(r.err(format!(
            "{n_points} points is more than the supported {MAX_POINTS}"
        )));
    }
    let (positions, strand_uvs) = if major == 3 {
        let expected = 296 + 12 * n_points;
        if (bytes.len() as u64) < expected {
            return Err(r.err(format!(
                "counts disagree with the file size: {strands} strands x {per} vertices need {expected} bytes, the file has {}",
                bytes.len()
            )));
        }
        (r.points(296, n_points, 3, "vertex positions")?, None)
    } else {
        let pos_offset = r.u32_at(12, "position offset")? as u64;
        let uv_offset = r.u32_at(16, "strand UV offset")? as u64;
        if pos_offset < 160 {
            return Err(r.err(format!(
                "vertex positions at byte {pos_offset}, inside the 160-byte header"
            )));
        }
        let end = pos_offset + 16 * n_points;
        if (bytes.len() as u64) < end {
            return Err(r.err(format!(
                "counts disagree with the file size: {strands} strands x {per} float4 vertices from byte {pos_offset} need {end} bytes, the file has {}",
                bytes.len()
            )));
        }
        let pos = r.points(pos_offset, n_points, 4, "vertex positions")?;
        let uvs = if uv_offset != 0 {
            let f = r.f32s(uv_offset, 2 * strands as u64, "strand UVs")?;
            Some(f.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
        } else {
            None
        };
        (pos, uvs)
    };
    let raw: Vec<RawStrand> = positions
        .chunks_exact(per as usize)
        .map(|c: &[Vec3]| RawStrand {
            points: c.to_vec(),
            ..Default::default()
        })
        .collect();
    let (hair, report) = Hair::from_strands(raw, DEFAULT_FIBER_DIAMETER);
    if hair.strand_count() == 0 {
        return Err(r.err("no strand has two or more distinct points"));
    }
    Ok((
        hair,
        TressFxInfo {
            version,
            strands,
            vertices_per_strand: per,
            strand_uvs,
        },
        report,
    ))
}
