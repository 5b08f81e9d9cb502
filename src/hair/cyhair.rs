//! Cem Yuksel's cyHair `.hair` format: a 128-byte header, then optional arrays.
//!
//! Header (little endian): "HAIR", strand count u32, point count u32, array flags u32
//! (1 segments, 2 points, 4 thickness, 8 transparency, 16 colours), default segments u32,
//! default thickness f32, default transparency f32, default colour 3 x f32, 88 bytes of text.
//! Arrays follow in flag order: segments (u16 per strand, points = segments + 1), points
//! (3 x f32 per point), thickness (f32 per point), transparency (f32 per point), colours (3 x f32).

use super::bytes::Reader;
use super::error::{HairError, MAX_POINTS};
use super::model::{CleanReport, Hair, RawStrand, Thickness};
use std::path::Path;

pub const FLAG_SEGMENTS: u32 = 1;
pub const FLAG_POINTS: u32 = 2;
pub const FLAG_THICKNESS: u32 = 4;
pub const FLAG_TRANSPARENCY: u32 = 8;
pub const FLAG_COLOURS: u32 = 16;
const HEADER: u64 = 128;

/// The header, for `info`.
#[derive(Clone, Debug, PartialEq)]
pub struct CyHairHeader {
    pub strands: u32,
    pub points: u32,
    pub flags: u32,
    pub default_segments: u32,
    pub default_thickness: f32,
    pub default_transparency: f32,
    pub default_colour: [f32; 3],
    pub info: String,
}

pub fn read_cyhair(
    bytes: &[u8],
    path: &Path,
) -> Result<(Hair, CyHairHeader, CleanReport), HairError> {
    let r = Reader::new(bytes, path);
    let magic = r.slice(0, 4, "magic")?;
    if magic != b"HAIR" {
        return Err(r.err("not a cyHair file: the first 4 bytes are not \"HAIR\""));
    }
    r.slice(0, HEADER, "the 128-byte header")?;
    let info_bytes = r.slice(40, 88, "header info")?;
    let info_end = info_bytes.iter().position(|&b| b == 0).unwrap_or(88);
    let header = CyHairHeader {
        strands: r.u32_at(4, "strand count")?,
        points: r.u32_at(8, "point count")?,
        flags: r.u32_at(12, "array flags")?,
        default_segments: r.u32_at(16, "default segments")?,
        default_thickness: r.f32_at(20, "default thickness")?,
        default_transparency: r.f32_at(24, "default transparency")?,
        default_colour: [
            r.f32_at(28, "default colour")?,
            r.f32_at(32, "default colour")?,
            r.f32_at(36, "default colour")?,
        ],
        info: String::from_utf8_lossy(&info_bytes[..info_end]).into_owned(),
    };
    let (n_strands, n_points, flags) = (header.strands as u64, header.points as u64, header.flags);
    if flags & !31 != 0 {
        return Err(r.err(format!("unknown array flags 0x{flags:x}")));
    }
    if flags & FLAG_POINTS == 0 {
        return Err(r.err("the file has no points array (flag 2 not set)"));
    }
    if n_strands == 0 {
        return Err(r.err("the file has zero strands"));
    }
    if n_points > MAX_POINTS {
        return Err(r.err(format!(
            "{n_points} points is more than the supported {MAX_POINTS}"
        )));
    }
    // Expected size from the counts, checked before any allocation.
    let per_point = 12
        + if flags & FLAG_THICKNESS != 0 { 4 } else { 0 }
        + if flags & FLAG_TRANSPARENCY != 0 { 4 } else { 0 }
        + if flags & FLAG_COLOURS != 0 { 12 } else { 0 };
    let seg_bytes = if flags & FLAG_SEGMENTS != 0 {
        2 * n_strands
    } else {
        0
    };
    let expected = HEADER + seg_bytes + per_point * n_points;
    if expected != bytes.len() as u64 {
        return Err(r.err(format!(
            "counts disagree with the file size: {n_strands} strands and {n_points} points with flags 0x{flags:x} need {expected} bytes, the file has {}",
            bytes.len()
        )));
    }
    // Every strand has at least one point: bound the strand count before allocating per strand.
    if n_strands > n_points {
        return Err(r.err(format!(
            "{n_strands} strands cannot share {n_points} points"
        )));
    }
    if flags & FLAG_SEGMENTS == 0 && n_strands * (header.default_segments as u64 + 1) != n_points {
        return Err(r.err(format!(
            "{n_strands} strands of {} default segments need {} points but the header says {n_points}",
            header.default_segments,
            n_strands * (header.default_segments as u64 + 1)
        )));
    }
    let mut offset = HEADER;
    let counts: Vec<u64> = if flags & FLAG_SEGMENTS != 0 {
        let b = r.slice(offset, seg_bytes, "segments array")?;
        offset += seg_bytes;
        b.chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]) as u64 + 1)
            .collect()
    } else {
        vec![header.default_segments as u64 + 1; n_strands as usize]
    };
    let sum: u64 = counts.iter().sum();
    if sum != n_points {
        return Err(r.err(format!(
            "segment counts add up to {sum} points but the header says {n_points}"
        )));
    }
    let points = r.points(offset, n_points, 3, "points array")?;
    offset += 12 * n_points;
    let mut per_point_array = |flag: u32, what: &str| -> Result<Option<Vec<f32>>, HairError> {
        if flags & flag == 0 {
            return Ok(None);
        }
        let v = r.f32s(offset, n_points, what)?;
        offset += 4 * n_points;
        Ok(Some(v))
    };
    let thickness = per_point_array(FLAG_THICKNESS, "thickness array")?;
    let transparency = per_point_array(FLAG_TRANSPARENCY, "transparency array")?;
    let colours = if flags & FLAG_COLOURS != 0 {
        let f = r.f32s(offset, 3 * n_points, "colour array")?;
        Some(
            f.chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect::<Vec<_>>(),
        )
    } else {
        None
    };
    if let Some(t) = &thickness
        && let Some(k) = t.iter().position(|&x| x < 0.0)
    {
        return Err(r.err(format!("thickness of point {k} is negative ({})", t[k])));
    }
    let mut strands = Vec::with_capacity(n_strands as usize);
    let mut start = 0usize;
    for &c in &counts {
        let range = start..start + c as usize;
        strands.push(RawStrand {
            points: points[range.clone()].to_vec(),
            thickness: thickness.as_ref().map(|t| t[range.clone()].to_vec()),
            colour: colours.as_ref().map(|t| t[range.clone()].to_vec()),
            transparency: transparency.as_ref().map(|t| t[range.clone()].to_vec()),
            sigma_a: None,
        });
        start = range.end;
    }
    let (hair, report) = Hair::from_strands(strands, header.default_thickness.max(0.0));
    if hair.strand_count() == 0 {
        return Err(r.err("no strand has two or more distinct points"));
    }
    Ok((hair, header, report))
}

/// Writes `hair` as cyHair. The segments array is written only when strands differ in length;
/// thickness is written per point unless uniform; colour and transparency when present.
pub fn write_cyhair(hair: &Hair, info: &str) -> Vec<u8> {
    let n_strands = hair.strand_count();
    let counts: Vec<usize> = (0..n_strands).map(|s| hair.strand_range(s).len()).collect();
    let uniform = counts.windows(2).all(|w| w[0] == w[1]);
    let mut flags = FLAG_POINTS;
    if !uniform {
        flags |= FLAG_SEGMENTS;
    }
    let (per_point_thickness, default_thickness) = match &hair.thickness {
        Thickness::Uniform(t) => (None, *t),
        Thickness::PerStrand(v) => {
            let t: Vec<f32> = (0..n_strands)
                .flat_map(|s| std::iter::repeat_n(v[s], counts[s]))
                .collect();
            (Some(t), v.first().copied().unwrap_or(0.0))
        }
        Thickness::PerPoint(v) => (Some(v.clone()), v.first().copied().unwrap_or(0.0)),
    };
    if per_point_thickness.is_some() {
        flags |= FLAG_THICKNESS;
    }
    if hair.transparency.is_some() {
        flags |= FLAG_TRANSPARENCY;
    }
    if hair.colour.is_some() {
        flags |= FLAG_COLOURS;
    }
    let mut out = Vec::with_capacity(128 + hair.point_count() * 32);
    out.extend_from_slice(b"HAIR");
    out.extend_from_slice(&(n_strands as u32).to_le_bytes());
    out.extend_from_slice(&(hair.point_count() as u32).to_le_bytes());
    out.extend_from_slice(&flags.to_le_bytes());
    let default_segments = counts.first().map_or(0, |c| c.saturating_sub(1)) as u32;
    out.extend_from_slice(&default_segments.to_le_bytes());
    out.extend_from_slice(&default_thickness.to_le_bytes());
    out.extend_from_slice(&0f32.to_le_bytes());
    for c in [1.0f32, 1.0, 1.0] {
        out.extend_from_slice(&c.to_le_bytes());
    }
    let mut text = [0u8; 88];
    let info = info.as_bytes();
    let n = info.len().min(87);
    text[..n].copy_from_slice(&info[..n]);
    out.extend_from_slice(&text);
    if !uniform {
        for c in &counts {
            out.extend_from_slice(&((c - 1).min(u16::MAX as usize) as u16).to_le_bytes());
        }
    }
    for p in &hair.positions {
        for x in p.to_array() {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    let mut floats = |v: &[f32]| {
        v.iter()
            .for_each(|x| out.extend_from_slice(&x.to_le_bytes()))
    };
    if let Some(t) = &per_point_thickness {
        floats(t);
    }
    if let Some(t) = &hair.transparency {
        floats(t);
    }
    if let Some(c) = &hair.colour {
        for rgb in c {
            floats(rgb);
        }
    }
    out
}
