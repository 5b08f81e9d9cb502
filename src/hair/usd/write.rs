//! USD ASCII (`.usda`) export of a hairstyle: one `BasisCurves` prim (linear, non-periodic) with the
//! strands' points, per-vertex `widths` (the fibre diameter) and per-vertex `primvars:displayColor`
//! (linear RGB), in centimetres (`metersPerUnit = 0.01`), +Y up. Blender and Unreal read USD curves;
//! the colours carry the painted dye to them.

use crate::hair::Hair;
use std::fmt::Write;

/// The `.usda` text of `hair` with one linear RGB colour per point (`colours`; None: no colour).
pub fn write_usda(hair: &Hair, colours: Option<&[[f32; 3]]>, doc: &str) -> String {
    let n = hair.point_count();
    let mut s = String::with_capacity(64 + n * 80);
    let doc = doc.replace(['"', '\\', '\n'], " ");
    let _ = write!(
        s,
        "#usda 1.0\n(\n    defaultPrim = \"hair\"\n    doc = \"{doc}\"\n    metersPerUnit = 0.01\n    upAxis = \"Y\"\n)\n\n"
    );
    s.push_str("def BasisCurves \"hair\"\n{\n");
    s.push_str("    uniform token type = \"linear\"\n");
    s.push_str("    uniform token wrap = \"nonperiodic\"\n");
    s.push_str("    int[] curveVertexCounts = [");
    for k in 0..hair.strand_count() {
        let _ = write!(
            s,
            "{}{}",
            if k > 0 { ", " } else { "" },
            hair.strand_range(k).len()
        );
    }
    s.push_str("]\n    point3f[] points = [");
    for (k, p) in hair.positions.iter().enumerate() {
        let _ = write!(s, "{}({}, {}, {})", sep(k), p.x, p.y, p.z);
    }
    s.push_str("]\n    float[] widths = [");
    let mut k = 0;
    for strand in 0..hair.strand_count() {
        for i in hair.strand_range(strand) {
            let _ = write!(s, "{}{}", sep(k), hair.thickness_at(strand, i));
            k += 1;
        }
    }
    s.push_str("] (\n        interpolation = \"vertex\"\n    )\n");
    if let Some(c) = colours.filter(|c| c.len() == n) {
        s.push_str("    color3f[] primvars:displayColor = [");
        for (k, rgb) in c.iter().enumerate() {
            let _ = write!(s, "{}({}, {}, {})", sep(k), rgb[0], rgb[1], rgb[2]);
        }
        s.push_str("] (\n        interpolation = \"vertex\"\n    )\n");
    }
    s.push_str("}\n");
    s
}

fn sep(k: usize) -> &'static str {
    if k == 0 { "" } else { ", " }
}
