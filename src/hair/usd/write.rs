//! USD ASCII (`.usda`) export of a groom in Unreal's groom convention, which Blender reads too:
//! one `BasisCurves` prim (linear, non-periodic) under an `Xform`, with the `GroomAPI` schema,
//! per-vertex `widths` (the fibre diameter), and the painted look as primvars: `groom_color`
//! (`float3[]`, Unreal's type for it), `displayColor` (`color3f[]`, Blender's), `groom_roughness`,
//! a per-strand `groom_id`, and strandlight's own data to come back exactly: the per-vertex
//! absorption `primvars:strandlight:sigma_a` and the look as custom attributes (`strandlight:look`
//! holds all of it as JSON; the scalar parameters are also written one by one for other tools).
//! Centimetres (`metersPerUnit = 0.01`), +Y up.

use crate::hair::Hair;
use std::fmt::Write;

/// The look written beside the geometry.
pub struct GroomLook<'a> {
    /// Absorption per point (per unit fibre radius).
    pub sigma_a: &'a [[f32; 3]],
    /// Linear RGB colour per point: the absorption run through the dye inversion.
    pub colours: &'a [[f32; 3]],
    /// Unreal's roughness in [0, 1].
    pub roughness: f32,
    /// Named scalar parameters (written as `custom double strandlight:NAME`).
    pub params: Vec<(&'static str, f64)>,
    /// The whole look as JSON (`custom string strandlight:look`).
    pub json: String,
}

/// The prim path the groom is written at.
pub const GROOM_PRIM: &str = "/Groom/hair";

/// The `.usda` text of `hair` with its look (None: geometry only).
pub fn write_usda(hair: &Hair, look: Option<&GroomLook>, doc: &str) -> String {
    let n = hair.point_count();
    let mut s = String::with_capacity(256 + n * 150);
    let doc = doc.replace(['"', '\\', '\n'], " ");
    let _ = write!(
        s,
        "#usda 1.0\n(\n    defaultPrim = \"Groom\"\n    doc = \"{doc}\"\n    metersPerUnit = 0.01\n    upAxis = \"Y\"\n)\n\n"
    );
    s.push_str("def Xform \"Groom\"\n{\n");
    s.push_str("    def BasisCurves \"hair\" (\n        prepend apiSchemas = [\"GroomAPI\"]\n    )\n    {\n");
    s.push_str("        uniform token type = \"linear\"\n");
    s.push_str("        uniform token wrap = \"nonperiodic\"\n");
    array(
        &mut s,
        "int[] curveVertexCounts",
        None,
        hair.strand_count(),
        |s, k| {
            let _ = write!(s, "{}", hair.strand_range(k).len());
        },
    );
    array(&mut s, "point3f[] points", None, n, |s, k| {
        let p = hair.positions[k];
        let _ = write!(s, "({}, {}, {})", p.x, p.y, p.z);
    });
    let widths: Vec<f32> = (0..hair.strand_count())
        .flat_map(|strand| hair.strand_range(strand).map(move |i| (strand, i)))
        .map(|(strand, i)| hair.thickness_at(strand, i))
        .collect();
    array(&mut s, "float[] widths", Some("vertex"), n, |s, k| {
        let _ = write!(s, "{}", widths[k]);
    });
    array(
        &mut s,
        "int[] primvars:groom_id",
        Some("uniform"),
        hair.strand_count(),
        |s, k| {
            let _ = write!(s, "{}", hair.strand_ids[k]);
        },
    );
    if let Some(look) = look.filter(|l| l.sigma_a.len() == n && l.colours.len() == n) {
        let triple = |v: &[[f32; 3]]| {
            let v = v.to_vec();
            move |s: &mut String, k: usize| {
                let _ = write!(s, "({}, {}, {})", v[k][0], v[k][1], v[k][2]);
            }
        };
        array(
            &mut s,
            "color3f[] primvars:displayColor",
            Some("vertex"),
            n,
            triple(look.colours),
        );
        array(
            &mut s,
            "float3[] primvars:groom_color",
            Some("vertex"),
            n,
            triple(look.colours),
        );
        array(
            &mut s,
            "float[] primvars:groom_roughness",
            Some("vertex"),
            n,
            |s, _| {
                let _ = write!(s, "{}", look.roughness);
            },
        );
        array(
            &mut s,
            "float3[] primvars:strandlight:sigma_a",
            Some("vertex"),
            n,
            triple(look.sigma_a),
        );
        for (name, v) in &look.params {
            let _ = writeln!(s, "        custom double strandlight:{name} = {v}");
        }
        let _ = writeln!(
            s,
            "        custom string strandlight:look = {}",
            string_literal(&look.json)
        );
    }
    s.push_str("    }\n}\n");
    s
}

/// One array attribute `decl = [...]`, with its interpolation when given.
fn array(
    s: &mut String,
    decl: &str,
    interpolation: Option<&str>,
    n: usize,
    mut item: impl FnMut(&mut String, usize),
) {
    let _ = write!(s, "        {decl} = [");
    for k in 0..n {
        if k > 0 {
            s.push_str(", ");
        }
        item(s, k);
    }
    s.push(']');
    match interpolation {
        Some(i) => {
            let _ = writeln!(s, " (\n            interpolation = \"{i}\"\n        )");
        }
        None => s.push('\n'),
    }
}

/// A string as a USD text literal. Triple quotes need no escapes for JSON without backslashes
/// (the look's), and not every USD reader undoes escapes; anything else is escaped.
fn string_literal(text: &str) -> String {
    if !text.contains('\\') && !text.contains("\"\"\"") && !text.ends_with('"') {
        return format!("\"\"\"{text}\"\"\"");
    }
    let escaped = text
        .replace('\\', "\\\\")
        .replace('"', "\\\"")
        .replace('\n', "\\n");
    format!("\"{escaped}\"")
}
