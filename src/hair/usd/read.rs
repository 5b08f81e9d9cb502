//! USD curves in (`.usda`, `.usdc`, `.usdz`, `.usd`) through the `openusd` crate, which composes
//! the stage (sublayers, references, payloads, variants) as Pixar's library does.
//!
//! Every `BasisCurves` prim under the default prim (the whole stage where none is set, or the
//! prim the user picks) is read with its world transform (the `xformOp`s of it and its
//! ancestors, `!resetXformStack!` honoured), at the time asked for or the earliest sample.
//! Guide curves (`purpose = "guide"` on the prim or an ancestor, or Unreal's
//! `primvars:groom_guide`) are skipped, as are invisible prims; both are reported. The colour
//! comes from `primvars:groom_color` (Unreal's groom convention), `displayColor` or `color`, in
//! that order, indexed primvars expanded.

use super::isolate::{Limits, Wire, get_pods, in_child, put_pods};
use crate::hair::curve_file::{CurveBatch, CurveFile, Primvar};
use crate::hair::curves::{Basis, CurveKind, Interpolation, Wrap};
use crate::hair::normalize::UpAxis;
use glam::{DMat4, Vec3};
use openusd::schemas::geom::{Imageable, Xformable};
use openusd::sdf::Value;
use openusd::usd::{Attribute, Prim, PrimPredicate, SchemaBase, SchemaKind, Stage, TimeCode};
use std::path::Path;
use std::time::Duration;

/// Which curves of a stage to read, and when.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CurveSelection {
    /// A prim path (`/Groom/hair`) whose subtree is read; None: the default prim.
    pub prim: Option<String>,
    /// A time code for time-sampled values; None: the earliest sample.
    pub time: Option<f64>,
}

/// strandlight's own per-vertex absorption and look (its export, `write.rs`).
const SIGMA_A_PRIMVAR: &str = "primvars:strandlight:sigma_a";
const LOOK_ATTRIBUTE: &str = "strandlight:look";

/// The colour primvars read, most specific first.
const COLOUR_PRIMVARS: [&str; 3] = ["groom_color", "displayColor", "color"];

/// Reads the curves of the USD stage at `path`. Errors name the prim and the problem; the caller
/// prefixes the file.
pub fn read_usd(path: &Path, selection: &CurveSelection) -> Result<CurveFile, String> {
    let root = path
        .to_str()
        .ok_or("the path is not valid UTF-8, which the USD reader needs")?;
    // The stage is read in a child process (isolate.rs); checking and sampling the curves runs
    // here, so a mistake of ours still shows as one.
    let size = std::fs::metadata(path).map_or(0, |m| m.len());
    let limits = Limits {
        extra_memory: (4 << 30) + 32 * size,
        deadline: Duration::from_secs(60 + size / (1 << 19)),
    };
    let stage = in_child(&limits, || read_stage(root, selection))?;
    let mut out = CurveFile {
        up: stage.up,
        cm_per_unit: stage.cm_per_unit,
        skipped: stage.skipped,
        time: stage.time,
        ..CurveFile::default()
    };
    for b in &stage.batches {
        CurveBatch {
            name: &b.name,
            kind: b.kind,
            counts: &b.counts,
            points: &b.points,
            widths: b.widths.as_ref().map(|(i, v)| Primvar {
                name: "widths",
                interpolation: *i,
                values: v,
            }),
            colour: b.colour.as_ref().map(|(n, i, v)| Primvar {
                name: n,
                interpolation: *i,
                values: v,
            }),
            sigma_a: b.sigma_a.as_ref().map(|(i, v)| Primvar {
                name: SIGMA_A_PRIMVAR,
                interpolation: *i,
                values: v,
            }),
        }
        .append_to(&mut out)?;
        if out.look.is_none() {
            out.look.clone_from(&b.look);
        }
    }
    Ok(out)
}

/// What the stage holds for strandlight: the declared space and the curve prims.
#[derive(Debug, Default, PartialEq)]
struct StageCurves {
    up: Option<UpAxis>,
    cm_per_unit: Option<f32>,
    skipped: Vec<String>,
    time: Option<f64>,
    batches: Vec<PrimCurves>,
}

/// One `BasisCurves` prim's data as the stage holds it, points in world space.
#[derive(Debug, PartialEq)]
struct PrimCurves {
    name: String,
    kind: CurveKind,
    counts: Vec<i32>,
    points: Vec<Vec3>,
    widths: Option<(Interpolation, Vec<f32>)>,
    colour: Option<(String, Interpolation, Vec<Vec3>)>,
    sigma_a: Option<(Interpolation, Vec<Vec3>)>,
    look: Option<String>,
}

fn read_stage(root: &str, selection: &CurveSelection) -> Result<StageCurves, String> {
    let stage = Stage::open(root).map_err(|e| format!("not a readable USD stage: {e:#}"))?;
    let mut out = StageCurves {
        up: match stage_meta(&stage, "upAxis")? {
            Some(Value::Token(t)) if t.as_str() == "Z" => Some(UpAxis::PosZ),
            Some(Value::Token(t)) if t.as_str() == "Y" => Some(UpAxis::PosY),
            Some(other) => return Err(format!("upAxis {other:?} is neither \"Y\" nor \"Z\"")),
            None => Some(UpAxis::PosY),
        },
        cm_per_unit: match stage_meta(&stage, "metersPerUnit")? {
            Some(Value::Double(m)) if m.is_finite() && m > 0.0 => Some((m * 100.0) as f32),
            Some(Value::Float(m)) if m.is_finite() && m > 0.0 => Some(m * 100.0),
            Some(other) => return Err(format!("metersPerUnit {other:?} is not a positive number")),
            // USD's fallback is centimetres.
            None => Some(1.0),
        },
        ..StageCurves::default()
    };
    let subtree = match (&selection.prim, stage.default_prim()) {
        (Some(p), _) => p.trim_end_matches('/').to_string(),
        (None, Some(d)) => format!("/{}", d.as_str()),
        (None, None) => String::new(),
    };
    let mut paths = Vec::new();
    stage
        .traverse(PrimPredicate::DEFAULT_PROXIES, |p| {
            let s = p.as_str();
            if subtree.is_empty() || s == subtree || s.starts_with(&format!("{subtree}/")) {
                paths.push(p.clone());
            }
        })
        .map_err(|e| format!("cannot traverse the stage: {e:#}"))?;
    if paths.is_empty() {
        return Err(match &selection.prim {
            Some(p) => format!("no prim {p} in the stage"),
            None => format!("the default prim {subtree} holds no prims"),
        });
    }
    let time = selection.time.map(TimeCode::new);
    for path in paths {
        let prim = stage.prim(path.clone());
        let name = path.as_str().to_string();
        let ty = prim.type_name().map_err(|e| format!("{name}: {e:#}"))?;
        match ty.as_ref().map(|t| t.as_str()) {
            Some("BasisCurves") => {}
            Some(t @ ("NurbsCurves" | "HermiteCurves")) => {
                out.skipped
                    .push(format!("{name}: {t} (only BasisCurves are read)"));
                continue;
            }
            _ => continue,
        }
        if let Some(why) = skip_reason(&prim)? {
            out.skipped.push(format!("{name}: {why}"));
            continue;
        }
        let curves = read_curves(&prim, name, time, &mut out)?;
        out.batches.push(curves);
    }
    let errors = stage.composition_errors();
    if let Some(e) = errors.first() {
        return Err(format!("the stage does not compose: {e}"));
    }
    if out.batches.is_empty() {
        let skipped = if out.skipped.is_empty() {
            String::new()
        } else {
            format!(" (skipped: {})", out.skipped.join("; "))
        };
        let under = if subtree.is_empty() {
            "the stage"
        } else {
            &subtree
        };
        return Err(format!("no BasisCurves prim under {under}{skipped}"));
    }
    Ok(out)
}

fn stage_meta(stage: &Stage, field: &str) -> Result<Option<Value>, String> {
    stage
        .stage_metadata(field)
        .map_err(|e| format!("cannot read {field}: {e:#}"))
}

/// Why a curves prim is not hair to render: guide curves, or invisible.
fn skip_reason(prim: &Prim) -> Result<Option<String>, String> {
    let mut at = Some(prim.clone());
    while let Some(p) = at {
        match token(&p.attribute("purpose"))?.as_deref() {
            Some("guide") => return Ok(Some("guide curves (purpose = \"guide\")".into())),
            Some("proxy") => return Ok(Some("proxy geometry (purpose = \"proxy\")".into())),
            _ => {}
        }
        if token(&p.attribute("visibility"))?.as_deref() == Some("invisible") {
            return Ok(Some("invisible".into()));
        }
        at = p
            .path()
            .parent()
            .filter(|q| !q.is_abs_root())
            .map(|q| p.stage().prim(q));
    }
    let guide = value(&prim.attribute("primvars:groom_guide"), None)?;
    let is_guide = match guide {
        Some(Value::Int(v)) => v != 0,
        Some(Value::Bool(v)) => v,
        Some(Value::IntVec(v)) => v.iter().any(|&x| x != 0),
        Some(Value::BoolVec(v)) => v.iter().any(|&x| x),
        _ => false,
    };
    Ok(is_guide.then(|| "guide curves (primvars:groom_guide)".into()))
}

fn value(attr: &Attribute, time: Option<TimeCode>) -> Result<Option<Value>, String> {
    // With no time asked for, a time-sampled value is read at its earliest sample.
    attr.get_at::<Value>(Some(time.unwrap_or(TimeCode::EARLIEST)))
        .map_err(|e| format!("{}: {e:#}", attr.path()))
}

fn token(attr: &Attribute) -> Result<Option<String>, String> {
    Ok(match value(attr, None)? {
        Some(Value::Token(t)) => Some(t.as_str().to_string()),
        Some(Value::String(s)) => Some(s),
        _ => None,
    })
}

fn read_curves(
    prim: &Prim,
    name: String,
    time: Option<TimeCode>,
    out: &mut StageCurves,
) -> Result<PrimCurves, String> {
    let kind = curve_kind(prim, &name)?;
    let points_attr = prim.attribute("points");
    if points_attr.num_time_samples().unwrap_or(0) > 0 {
        let first = points_attr
            .time_sample_times()
            .ok()
            .and_then(|t| t.first().copied());
        out.time = time.map(|t| t.value()).or(first);
    }
    let counts = match value(&prim.attribute("curveVertexCounts"), time)? {
        Some(Value::IntVec(v)) => v,
        Some(other) => return Err(format!("{name}: curveVertexCounts is {}", kind_of(&other))),
        None => return Err(format!("{name}: no curveVertexCounts")),
    };
    let points = match value(&points_attr, time)? {
        Some(v) => vec3s(&v).ok_or_else(|| format!("{name}: points are {}", kind_of(&v)))?,
        None => return Err(format!("{name}: no points")),
    };
    let world = world_transform(prim, time.unwrap_or(TimeCode::EARLIEST))
        .map_err(|e| format!("{name}: its transform: {e}"))?;
    let points = points
        .iter()
        .map(|p| world.transform_point3(p.as_dvec3()).as_vec3())
        .collect();
    // Widths are diameters in the prim's space: scaled by the transform's mean scale.
    let scale = world.determinant().abs().cbrt() as f32;
    let widths = read_primvar(prim, "widths", time, Interpolation::Vertex, floats)?
        .map(|(i, w)| (i, w.into_iter().map(|x| x * scale).collect()));
    let mut colour = None;
    for c in COLOUR_PRIMVARS {
        let attr = format!("primvars:{c}");
        match read_primvar(prim, &attr, time, Interpolation::Constant, vec3s) {
            Ok(Some((i, v))) => {
                colour = Some((attr, i, v));
                break;
            }
            Ok(None) => {}
            // A colour of another type costs the colour, not the groom.
            Err(e) => out.skipped.push(format!("colour {e}")),
        }
    }
    let sigma_a = read_primvar(prim, SIGMA_A_PRIMVAR, time, Interpolation::Vertex, vec3s)?;
    let look = match value(&prim.attribute(LOOK_ATTRIBUTE), None)? {
        Some(Value::String(s)) => Some(s),
        _ => None,
    };
    Ok(PrimCurves {
        name,
        kind,
        counts,
        points,
        widths,
        colour,
        sigma_a,
        look,
    })
}

fn curve_kind(prim: &Prim, name: &str) -> Result<CurveKind, String> {
    let ty = token(&prim.attribute("type"))?;
    let basis = token(&prim.attribute("basis"))?;
    let wrap = token(&prim.attribute("wrap"))?;
    // The schema's fallbacks: cubic, bezier, nonperiodic.
    let basis = match (ty.as_deref().unwrap_or("cubic"), basis.as_deref()) {
        ("linear", _) => Basis::Linear,
        ("cubic", None | Some("bezier")) => Basis::Bezier,
        ("cubic", Some("bspline")) => Basis::Bspline,
        ("cubic", Some("catmullRom")) => Basis::CatmullRom,
        ("cubic", Some(b)) => return Err(format!("{name}: unknown basis \"{b}\"")),
        (t, _) => return Err(format!("{name}: unknown curve type \"{t}\"")),
    };
    let wrap = match wrap.as_deref() {
        None | Some("nonperiodic") => Wrap::NonPeriodic,
        Some("periodic") => Wrap::Periodic,
        Some("pinned") => Wrap::Pinned,
        Some(w) => return Err(format!("{name}: unknown wrap \"{w}\"")),
    };
    Ok(CurveKind { basis, wrap })
}

/// A primvar's interpolation and values, indexed ones expanded; None where it is not authored.
fn read_primvar<T: Copy>(
    prim: &Prim,
    attr_name: &str,
    time: Option<TimeCode>,
    fallback: Interpolation,
    decode: fn(&Value) -> Option<Vec<T>>,
) -> Result<Option<(Interpolation, Vec<T>)>, String> {
    let attr = prim.attribute(attr_name);
    let Some(v) = value(&attr, time)? else {
        return Ok(None);
    };
    let name = attr.path().to_string();
    let values = decode(&v).ok_or_else(|| format!("{name} is {}", kind_of(&v)))?;
    let interpolation = match attr
        .get_metadata::<Value>("interpolation")
        .map_err(|e| format!("{name}: {e:#}"))?
    {
        Some(Value::Token(t)) => Interpolation::from_token(t.as_str())
            .ok_or_else(|| format!("{name}: unknown interpolation \"{}\"", t.as_str()))?,
        _ if values.len() == 1 => Interpolation::Constant,
        _ => fallback,
    };
    let indices = prim.attribute(format!("{attr_name}:indices").as_str());
    let values = match value(&indices, time)? {
        Some(Value::IntVec(ix)) => ix
            .iter()
            .map(|&i| {
                usize::try_from(i)
                    .ok()
                    .and_then(|i| values.get(i).copied())
                    .ok_or_else(|| format!("{name}: index {i} is out of range"))
            })
            .collect::<Result<Vec<T>, String>>()?,
        _ => values,
    };
    Ok(Some((interpolation, values)))
}

fn floats(v: &Value) -> Option<Vec<f32>> {
    Some(match v {
        Value::FloatVec(x) => x.clone(),
        Value::DoubleVec(x) => x.iter().map(|&d| d as f32).collect(),
        Value::HalfVec(x) => x.iter().map(|h| h.to_f32()).collect(),
        Value::Float(x) => vec![*x],
        Value::Double(x) => vec![*x as f32],
        _ => return None,
    })
}

fn vec3s(v: &Value) -> Option<Vec<Vec3>> {
    Some(match v {
        Value::Vec3fVec(x) => x.iter().map(|p| Vec3::new(p.x, p.y, p.z)).collect(),
        Value::Vec3dVec(x) => x
            .iter()
            .map(|p| Vec3::new(p.x as f32, p.y as f32, p.z as f32))
            .collect(),
        Value::Vec3hVec(x) => x
            .iter()
            .map(|p| Vec3::new(p.x.to_f32(), p.y.to_f32(), p.z.to_f32()))
            .collect(),
        // Blender writes curve colours as color4f: the alpha is dropped.
        Value::Vec4fVec(x) => x.iter().map(|p| Vec3::new(p.x, p.y, p.z)).collect(),
        Value::Vec3f(p) => vec![Vec3::new(p.x, p.y, p.z)],
        _ => return None,
    })
}

fn kind_of(v: &Value) -> String {
    let s = format!("{v:?}");
    let head = s.split(['(', ' ', '{']).next().unwrap_or("a value");
    format!("of type {head}, not what the schema asks for")
}

/// Any prim, seen through the `Xformable` API to compose its `xformOp`s.
struct Transformable(Prim);

impl SchemaBase for Transformable {
    const KIND: SchemaKind = SchemaKind::ConcreteTyped;
    fn prim(&self) -> &Prim {
        &self.0
    }
}
impl Imageable for Transformable {}
impl Xformable for Transformable {}

/// The prim's local-to-world matrix (column vectors) at `time`.
fn world_transform(prim: &Prim, time: TimeCode) -> Result<DMat4, String> {
    let mut world = DMat4::IDENTITY;
    let mut at = Some(prim.clone());
    while let Some(p) = at {
        let x = Transformable(p.clone());
        let local = x
            .local_to_parent_transform(time)
            .map_err(|e| format!("{e:#}"))?;
        // USD's matrices act on row vectors: read row-major, they are glam's column-major.
        world = DMat4::from_cols_array(&local.0) * world;
        if x.resets_xform_stack().map_err(|e| format!("{e:#}"))? {
            break;
        }
        at = p
            .path()
            .parent()
            .filter(|q| !q.is_abs_root())
            .map(|q| p.stage().prim(q));
    }
    if !world.is_finite() {
        return Err("it is not finite".into());
    }
    Ok(world)
}

impl Wire for StageCurves {
    fn put(&self, out: &mut Vec<u8>) {
        let up = match self.up {
            None => 0u8,
            Some(UpAxis::PosZ) => 2,
            Some(_) => 1,
        };
        up.put(out);
        self.cm_per_unit.map(f64::from).put(out);
        self.skipped.put(out);
        self.time.put(out);
        self.batches.put(out);
    }
    fn get(input: &mut &[u8]) -> Option<Self> {
        Some(Self {
            up: match u8::get(input)? {
                0 => None,
                1 => Some(UpAxis::PosY),
                2 => Some(UpAxis::PosZ),
                _ => return None,
            },
            cm_per_unit: Option::<f64>::get(input)?.map(|c| c as f32),
            skipped: Wire::get(input)?,
            time: Wire::get(input)?,
            batches: Wire::get(input)?,
        })
    }
}

const BASES: [Basis; 4] = [
    Basis::Linear,
    Basis::Bezier,
    Basis::Bspline,
    Basis::CatmullRom,
];
const WRAPS: [Wrap; 3] = [Wrap::NonPeriodic, Wrap::Periodic, Wrap::Pinned];
const INTERPOLATIONS: [Interpolation; 4] = [
    Interpolation::Constant,
    Interpolation::Uniform,
    Interpolation::Varying,
    Interpolation::Vertex,
];

fn put_index<T: PartialEq>(all: &[T], v: &T, out: &mut Vec<u8>) {
    (all.iter().position(|x| x == v).unwrap_or(0) as u8).put(out);
}

fn get_index<T: Copy>(all: &[T], input: &mut &[u8]) -> Option<T> {
    all.get(u8::get(input)? as usize).copied()
}

/// An optional primvar: a flag, its interpolation, its values.
fn put_primvar<T: bytemuck::Pod>(v: &Option<(Interpolation, Vec<T>)>, out: &mut Vec<u8>) {
    match v {
        None => 0u8.put(out),
        Some((i, values)) => {
            1u8.put(out);
            put_index(&INTERPOLATIONS, i, out);
            put_pods(values, out);
        }
    }
}

fn get_primvar<T: bytemuck::Pod>(input: &mut &[u8]) -> Option<Option<(Interpolation, Vec<T>)>> {
    match u8::get(input)? {
        0 => Some(None),
        1 => Some(Some((get_index(&INTERPOLATIONS, input)?, get_pods(input)?))),
        _ => None,
    }
}

impl Wire for PrimCurves {
    fn put(&self, out: &mut Vec<u8>) {
        self.name.put(out);
        put_index(&BASES, &self.kind.basis, out);
        put_index(&WRAPS, &self.kind.wrap, out);
        put_pods(&self.counts, out);
        put_pods(&self.points, out);
        put_primvar(&self.widths, out);
        match &self.colour {
            None => 0u8.put(out),
            Some((name, i, c)) => {
                1u8.put(out);
                name.put(out);
                put_index(&INTERPOLATIONS, i, out);
                put_pods(c, out);
            }
        }
        put_primvar(&self.sigma_a, out);
        self.look.put(out);
    }
    fn get(input: &mut &[u8]) -> Option<Self> {
        let name = String::get(input)?;
        let kind = CurveKind {
            basis: get_index(&BASES, input)?,
            wrap: get_index(&WRAPS, input)?,
        };
        let counts = get_pods(input)?;
        let points = get_pods(input)?;
        let widths = get_primvar(input)?;
        let colour = match u8::get(input)? {
            0 => None,
            1 => Some((
                String::get(input)?,
                get_index(&INTERPOLATIONS, input)?,
                get_pods(input)?,
            )),
            _ => return None,
        };
        let sigma_a = get_primvar(input)?;
        Some(Self {
            name,
            kind,
            counts,
            points,
            widths,
            colour,
            sigma_a,
            look: Wire::get(input)?,
        })
    }
}
