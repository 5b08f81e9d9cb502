//! Alembic curves in (`.abc`, Ogawa): `ICurves` objects (`AbcGeom_Curve_v2`) with the transforms
//! of the `IXform`s above them, `P`, `nVertices`, `curveBasisAndType`, `width` and the
//! `.arbGeomParams` Unreal's Alembic groom schema uses (`groom_color`, `groom_guide`). Alembic
//! declares no axis or unit: Y up by convention, units from the extent or `--units`.
//!
//! The archive (root group children): 0 archive version, 1 library version, 2 the top object,
//! 3 archive metadata, 4 time samplings, 5 indexed metadata. An object group holds its property
//! compound, its child objects, and last the child objects' headers. A compound group holds its
//! properties and last their headers. A scalar property's sample k is child k; an array property's
//! is child 2k (values, after a 16-byte digest) and 2k + 1 (dimensions).

use super::ogawa::{Node, Ogawa, Reader};
use crate::hair::curve_file::{CurveBatch, CurveFile, Primvar};
use crate::hair::curves::{Basis, CurveKind, Interpolation, Wrap};
use crate::hair::usd::CurveSelection;
use glam::{DMat4, DVec3, Vec3};

/// Reads the curves of an Alembic archive's bytes. `selection.prim` picks an object path's
/// subtree, `selection.time` a time in seconds (default: each property's first sample).
pub fn read_alembic(bytes: &[u8], selection: &CurveSelection) -> Result<CurveFile, String> {
    let (o, root) = Ogawa::open(bytes)?;
    let top = o.children(root)?;
    if top.len() < 6 {
        return Err("the archive's root holds fewer than six entries".into());
    }
    let archive = Archive {
        time_samplings: time_samplings(o.data(top[4])?)?,
        metadata: indexed_metadata(o.data(top[5])?)?,
        o,
    };
    let mut out = CurveFile::default();
    let mut walk = Walk {
        archive: &archive,
        selection,
        out: &mut out,
        objects: 0,
        visited: Default::default(),
    };
    walk.object(top[2], "", DMat4::IDENTITY, None)?;
    if out.batches.is_empty() {
        let skipped = if out.skipped.is_empty() {
            String::new()
        } else {
            format!(" (skipped: {})", out.skipped.join("; "))
        };
        return Err(match &selection.prim {
            Some(p) => format!("no curves object under {p}{skipped}"),
            None => format!("no curves object in the archive{skipped}"),
        });
    }
    Ok(out)
}

/// Objects deeper or more numerous than this are refused (a cycle in a corrupt file ends here).
const MAX_OBJECTS: usize = 1 << 20;
const MAX_DEPTH: usize = 256;

struct Archive<'a> {
    o: Ogawa<'a>,
    time_samplings: Vec<TimeSampling>,
    metadata: Vec<String>,
}

/// When a property's samples fall: `samples` within each cycle of `period` seconds (a single
/// sample: uniform; `period` infinite: acyclic, the samples are all the times).
struct TimeSampling {
    period: f64,
    samples: Vec<f64>,
}

impl TimeSampling {
    /// The time of sample `i`.
    fn time(&self, i: u32) -> f64 {
        let n = self.samples.len().max(1) as u32;
        let cycle = (i / n) as f64;
        let within = self.samples.get((i % n) as usize).copied().unwrap_or(0.0);
        if self.period.is_finite() {
            within + cycle * self.period
        } else {
            within
        }
    }

    /// The last sample index at or before `t` (0 before the first), by bisection: sample times
    /// rise with the index.
    fn index_at(&self, t: f64, count: u32) -> u32 {
        let (mut lo, mut hi) = (0u32, count);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if self.time(mid) <= t + 1e-9 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }
}

fn time_samplings(block: &[u8]) -> Result<Vec<TimeSampling>, String> {
    let mut r = Reader::new(block);
    let mut out = Vec::new();
    while !r.rest.is_empty() {
        let _max_sample = r.u32()?;
        let period = r.f64()?;
        let n = r.u32()? as usize;
        if n > r.rest.len() / 8 {
            return Err("a time sampling longer than its block".into());
        }
        let samples = (0..n).map(|_| r.f64()).collect::<Result<Vec<_>, _>>()?;
        // Alembic marks acyclic sampling with a period of f64::MAX / 32.
        let period = if period >= f64::MAX / 64.0 {
            f64::INFINITY
        } else {
            period
        };
        out.push(TimeSampling { period, samples });
    }
    Ok(out)
}

fn indexed_metadata(block: &[u8]) -> Result<Vec<String>, String> {
    let mut r = Reader::new(block);
    let mut out = vec![String::new()];
    while !r.rest.is_empty() {
        let n = r.u8()? as usize;
        out.push(r.string(n)?);
    }
    Ok(out)
}

/// `key=value;key=value` metadata: the value of `key`.
fn meta<'m>(metadata: &'m str, key: &str) -> Option<&'m str> {
    metadata
        .split(';')
        .filter_map(|kv| kv.split_once('='))
        .find(|(k, _)| *k == key)
        .map(|(_, v)| v)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Compound,
    Scalar,
    Array,
}

struct Property {
    name: String,
    kind: Kind,
    pod: u8,
    extent: u8,
    samples: u32,
    first_changed: u32,
    last_changed: u32,
    time_sampling: usize,
    metadata: String,
    group: Node,
}

impl Property {
    /// The stored sample that holds sample `i` (samples equal to their predecessor are not
    /// stored again).
    fn stored(&self, i: u32) -> u32 {
        let (f, l) = (self.first_changed, self.last_changed);
        if (f == 0 && l == 0) || i < f {
            0
        } else if i >= l {
            l - f + 1
        } else {
            i - f + 1
        }
    }
}

/// Bytes of one POD: bool, u8, i8, u16, i16, u32, i32, u64, i64, f16, f32, f64.
const POD_SIZE: [usize; 12] = [1, 1, 1, 2, 2, 4, 4, 8, 8, 2, 4, 8];
const POD_F32: u8 = 10;
const POD_F64: u8 = 11;
const POD_I32: u8 = 6;
const POD_U8: u8 = 1;
const POD_BOOL: u8 = 0;

impl Archive<'_> {
    /// The property headers of a compound property's group.
    fn properties(&self, group: Node) -> Result<Vec<Property>, String> {
        let children = self.o.children(group)?;
        let Some((&last, groups)) = children.split_last() else {
            return Ok(Vec::new());
        };
        let mut r = Reader::new(self.o.data(last)?);
        let mut out = Vec::new();
        while !r.rest.is_empty() {
            let info = r.u32()?;
            let hint = (info >> 2) & 3;
            let sized = |r: &mut Reader| -> Result<u32, String> {
                match hint {
                    0 => r.u8().map(u32::from),
                    1 => r.u16().map(u32::from),
                    _ => r.u32(),
                }
            };
            let kind = match info & 3 {
                0 => Kind::Compound,
                1 => Kind::Scalar,
                _ => Kind::Array,
            };
            let (mut pod, mut extent, mut samples, mut first, mut last, mut ts) =
                (0, 0, 0, 0, 0, 0);
            if kind != Kind::Compound {
                pod = ((info >> 4) & 0xf) as u8;
                extent = ((info >> 12) & 0xff) as u8;
                samples = sized(&mut r)?;
                if info & 0x200 != 0 {
                    first = sized(&mut r)?;
                    last = sized(&mut r)?;
                } else if info & 0x800 == 0 && samples > 0 {
                    first = 1;
                    last = samples - 1;
                }
                if info & 0x100 != 0 {
                    ts = sized(&mut r)? as usize;
                }
            }
            let name_len = sized(&mut r)? as usize;
            let name = r.string(name_len)?;
            let meta_index = ((info >> 20) & 0xff) as usize;
            let metadata = if meta_index == 0xff {
                let n = sized(&mut r)? as usize;
                r.string(n)?
            } else {
                self.metadata.get(meta_index).cloned().ok_or_else(|| {
                    format!("{name}: metadata index {meta_index} is not in the archive")
                })?
            };
            if last < first || first > samples {
                return Err(format!("{name}: sample indices out of order"));
            }
            let group = *groups
                .get(out.len())
                .ok_or_else(|| format!("{name}: no data for the property"))?;
            out.push(Property {
                name,
                kind,
                pod,
                extent,
                samples,
                first_changed: first,
                last_changed: last,
                time_sampling: ts,
                metadata,
                group,
            });
        }
        Ok(out)
    }

    /// The time a property is read at: its sample's.
    fn sample_time(&self, p: &Property, time: Option<f64>) -> f64 {
        let i = self.sample_index(p, time);
        self.time_samplings
            .get(p.time_sampling)
            .map_or(0.0, |ts| ts.time(i))
    }

    /// The sample index a property is read at.
    fn sample_index(&self, p: &Property, time: Option<f64>) -> u32 {
        match (time, self.time_samplings.get(p.time_sampling)) {
            (Some(t), Some(ts)) if p.samples > 1 => ts.index_at(t, p.samples),
            _ => 0,
        }
    }

    /// The bytes of a scalar or array property's sample (after the 16-byte digest) and the size
    /// of one element.
    fn sample(&self, p: &Property, time: Option<f64>) -> Result<(&[u8], usize), String> {
        if p.kind == Kind::Compound {
            return Err(format!("{} is a compound where values belong", p.name));
        }
        let pod = *POD_SIZE
            .get(p.pod as usize)
            .ok_or_else(|| format!("{} holds strings or an unknown type", p.name))?;
        let element = pod * p.extent.max(1) as usize;
        let k = p.stored(self.sample_index(p, time)) as usize;
        let child = if p.kind == Kind::Array { 2 * k } else { k };
        let children = self.o.children(p.group)?;
        let node = *children
            .get(child)
            .ok_or_else(|| format!("{}: sample {k} is missing", p.name))?;
        let bytes = self.o.data(node)?;
        let values = if bytes.is_empty() {
            bytes
        } else {
            bytes.get(16..).unwrap_or(&[])
        };
        if values.len() % element != 0 {
            return Err(format!(
                "{}: {} bytes are not whole elements",
                p.name,
                values.len()
            ));
        }
        Ok((values, element))
    }

    /// A sample's values of one POD type, decoded from little endian.
    fn numbers<T, const N: usize>(
        &self,
        p: &Property,
        time: Option<f64>,
        (pod, what): (u8, &str),
        from_le: fn([u8; N]) -> T,
    ) -> Result<Vec<T>, String> {
        if p.pod != pod {
            return Err(format!("{} is not {what}", p.name));
        }
        let (bytes, _) = self.sample(p, time)?;
        Ok(bytes
            .chunks_exact(N)
            .map(|b| from_le(b.try_into().unwrap_or([0; N])))
            .collect())
    }

    fn f32s(&self, p: &Property, time: Option<f64>, extent: u8) -> Result<Vec<f32>, String> {
        if p.extent != extent {
            return Err(format!("{} is not {extent} × float32", p.name));
        }
        self.numbers(p, time, (POD_F32, "float32"), f32::from_le_bytes)
    }

    fn f64s(&self, p: &Property, time: Option<f64>) -> Result<Vec<f64>, String> {
        self.numbers(p, time, (POD_F64, "float64"), f64::from_le_bytes)
    }

    fn i32s(&self, p: &Property, time: Option<f64>) -> Result<Vec<i32>, String> {
        self.numbers(p, time, (POD_I32, "int32"), i32::from_le_bytes)
    }

    fn u8s(&self, p: &Property, time: Option<f64>) -> Result<Vec<u8>, String> {
        if p.pod != POD_U8 && p.pod != POD_BOOL {
            return Err(format!("{} is not uint8", p.name));
        }
        Ok(self.sample(p, time)?.0.to_vec())
    }
}

fn find<'p>(props: &'p [Property], name: &str) -> Option<&'p Property> {
    props.iter().find(|p| p.name == name)
}

struct Walk<'a, 'b> {
    archive: &'a Archive<'b>,
    selection: &'a CurveSelection,
    out: &'a mut CurveFile,
    objects: usize,
    /// Object groups already read: a corrupt archive may point at one group many times.
    visited: std::collections::HashSet<Node>,
}

impl Walk<'_, '_> {
    /// Visits an object group: its transform (an xform), its curves, its children.
    fn object(
        &mut self,
        group: Node,
        path: &str,
        parent: DMat4,
        depth: Option<usize>,
    ) -> Result<(), String> {
        let depth = depth.map_or(0, |d| d + 1);
        self.objects += 1;
        // Group 0 is the empty group, which any number of objects may share.
        if group != Node::Group(0) && !self.visited.insert(group) {
            return Err("an object appears twice in the hierarchy".into());
        }
        if depth > MAX_DEPTH || self.objects > MAX_OBJECTS {
            return Err("the object hierarchy is deeper or larger than an archive can be".into());
        }
        let a = self.archive;
        let children = a.o.children(group)?;
        let Some((&headers, rest)) = children.split_last() else {
            return Ok(());
        };
        let headers = a.o.data(headers)?;
        let headers = headers
            .get(..headers.len().saturating_sub(32))
            .unwrap_or(&[]);
        let mut r = Reader::new(headers);
        let mut k = 0;
        while !r.rest.is_empty() {
            let n = r.u32()? as usize;
            let name = r.string(n)?;
            let meta_index = r.u8()? as usize;
            let metadata = if meta_index == 0xff {
                let n = r.u32()? as usize;
                r.string(n)?
            } else {
                a.metadata.get(meta_index).cloned().unwrap_or_default()
            };
            let child = *rest
                .get(1 + k)
                .ok_or_else(|| format!("{path}/{name}: no data for the object"))?;
            k += 1;
            let child_path = format!("{path}/{name}");
            let child_props = match a.o.children(child)?.first() {
                Some(&p) => a.properties(p)?,
                None => Vec::new(),
            };
            let schema = meta(&metadata, "schema").unwrap_or("");
            let mut world = parent;
            match schema {
                "AbcGeom_Xform_v3" => {
                    let (local, inherits) = self.xform(&child_props, &child_path)?;
                    world = if inherits { parent * local } else { local };
                }
                "AbcGeom_Curve_v2" if self.selected(&child_path) => {
                    self.curves(&child_props, &child_path, parent)?;
                }
                _ => {}
            }
            self.object(child, &child_path, world, Some(depth))?;
        }
        Ok(())
    }

    fn selected(&self, path: &str) -> bool {
        match &self.selection.prim {
            None => true,
            Some(p) => {
                let p = p.trim_end_matches('/');
                path == p || path.starts_with(&format!("{p}/"))
            }
        }
    }

    /// An xform's local matrix (column vectors) and whether it inherits its parent's.
    fn xform(&mut self, props: &[Property], path: &str) -> Result<(DMat4, bool), String> {
        let a = self.archive;
        let Some(x) = find(props, ".xform") else {
            return Ok((DMat4::IDENTITY, true));
        };
        let time = self.selection.time;
        let inner = a.properties(x.group)?;
        let inherits = match find(&inner, ".inherits") {
            Some(p) => a.u8s(p, time)?.first().is_none_or(|&b| b != 0),
            None => true,
        };
        let vals = match find(&inner, ".vals") {
            Some(p) => a.f64s(p, time)?,
            None => return Ok((DMat4::IDENTITY, inherits)),
        };
        if let Some(p) = find(&inner, ".vals").filter(|p| p.samples > 1) {
            let t = a.sample_time(p, time);
            self.out.time.get_or_insert(t);
        }
        // Without `.ops`, a sample of 16 values is one matrix.
        let ops = match find(&inner, ".ops") {
            Some(p) => a.u8s(p, time)?,
            None if vals.len() == 16 => vec![3 << 4],
            None => return Ok((DMat4::IDENTITY, inherits)),
        };
        let mut m = DMat4::IDENTITY;
        let mut at = 0;
        for op in ops {
            let channels = match op >> 4 {
                0 | 1 => 3,
                2 => 4,
                3 => 16,
                4..=6 => 1,
                t => return Err(format!("{path}: unknown transform operation {t}")),
            };
            let v = vals
                .get(at..at + channels)
                .ok_or_else(|| format!("{path}: fewer transform values than operations"))?;
            at += channels;
            let op_matrix = match op >> 4 {
                0 => DMat4::from_scale(DVec3::new(v[0], v[1], v[2])),
                1 => DMat4::from_translation(DVec3::new(v[0], v[1], v[2])),
                2 => DMat4::from_axis_angle(
                    DVec3::new(v[0], v[1], v[2])
                        .try_normalize()
                        .unwrap_or(DVec3::Y),
                    v[3].to_radians(),
                ),
                3 => DMat4::from_cols_array(v.try_into().unwrap_or(&[0.0; 16])),
                4 => DMat4::from_rotation_x(v[0].to_radians()),
                5 => DMat4::from_rotation_y(v[0].to_radians()),
                _ => DMat4::from_rotation_z(v[0].to_radians()),
            };
            // Alembic lists operations outermost first (row vectors: op · matrix so far).
            m *= op_matrix;
        }
        if !m.is_finite() {
            return Err(format!("{path}: the transform is not finite"));
        }
        Ok((m, inherits))
    }

    /// One curves object, in world space.
    fn curves(&mut self, props: &[Property], path: &str, world: DMat4) -> Result<(), String> {
        let a = self.archive;
        let time = self.selection.time;
        let geom = find(props, ".geom").ok_or_else(|| format!("{path}: no .geom"))?;
        let g = a.properties(geom.group)?;
        let arb = match find(&g, ".arbGeomParams") {
            Some(p) if p.kind == Kind::Compound => a.properties(p.group)?,
            _ => Vec::new(),
        };
        if let Some(guide) = find(&arb, "groom_guide")
            && let Ok((bytes, _)) = a.sample(guide, time)
            && bytes.iter().any(|&b| b != 0)
        {
            self.out
                .skipped
                .push(format!("{path}: guide curves (groom_guide)"));
            return Ok(());
        }
        let need = |name: &str| find(&g, name).ok_or_else(|| format!("{path}: no {name}"));
        let p = need("P")?;
        if p.samples > 1 {
            let t = a.sample_time(p, time);
            self.out.time.get_or_insert(t);
        }
        let points: Vec<Vec3> = a
            .f32s(p, time, 3)?
            .chunks_exact(3)
            .map(|c| {
                world
                    .transform_point3(Vec3::new(c[0], c[1], c[2]).as_dvec3())
                    .as_vec3()
            })
            .collect();
        let counts = a.i32s(need("nVertices")?, time)?;
        let kind = match a.u8s(need("curveBasisAndType")?, time)?.as_slice() {
            [ty, wrap, basis, ..] => curve_kind(*ty, *wrap, *basis, path)?,
            _ => {
                return Err(format!(
                    "{path}: curveBasisAndType holds fewer than 3 values"
                ));
            }
        };
        let scale = world.determinant().abs().cbrt() as f32;
        let widths = geom_param(a, &g, "width", time, 1)?
            .map(|(i, v)| (i, v.into_iter().map(|w| w * scale).collect::<Vec<f32>>()));
        let mut colour = None;
        for name in ["groom_color", "displayColor", "Cd", "color"] {
            match geom_param(a, &arb, name, time, 3) {
                Ok(Some((i, v))) => {
                    let v: Vec<Vec3> = v.chunks_exact(3).map(Vec3::from_slice).collect();
                    colour = Some((format!(".arbGeomParams/{name}"), i, v));
                    break;
                }
                Ok(None) => {}
                // A colour of another type (half, RGBA) costs the colour, not the groom.
                Err(e) => self.out.skipped.push(format!("{path}: colour {e}")),
            }
        }
        CurveBatch {
            name: path,
            kind,
            counts: &counts,
            points: &points,
            widths: widths.as_ref().map(|(i, v)| Primvar {
                name: "width",
                interpolation: *i,
                values: v,
            }),
            colour: colour.as_ref().map(|(n, i, v)| Primvar {
                name: n,
                interpolation: *i,
                values: v,
            }),
            sigma_a: None,
        }
        .append_to(self.out)
    }
}

fn curve_kind(ty: u8, wrap: u8, basis: u8, path: &str) -> Result<CurveKind, String> {
    let basis = match (ty, basis) {
        (1, _) => Basis::Linear,
        (0, 1) => Basis::Bezier,
        (0, 2) => Basis::Bspline,
        (0, 3) => Basis::CatmullRom,
        (0, 4) => return Err(format!("{path}: Hermite curves are not read")),
        (0, 5) => return Err(format!("{path}: power-basis curves are not read")),
        (0, b) => return Err(format!("{path}: cubic curves with basis {b} are not read")),
        (t, _) => {
            return Err(format!(
                "{path}: curve type {t} (variable order) is not read"
            ));
        }
    };
    let wrap = match wrap {
        0 => Wrap::NonPeriodic,
        1 => Wrap::Periodic,
        w => return Err(format!("{path}: unknown wrap {w}")),
    };
    Ok(CurveKind { basis, wrap })
}

/// A geometry parameter: an array property, or a compound of `.vals` (and `.indices`); its scope
/// (`geoScope` metadata: con, uni, var, vtx, fvr) gives the interpolation.
fn geom_param(
    a: &Archive,
    props: &[Property],
    name: &str,
    time: Option<f64>,
    extent: u8,
) -> Result<Option<(Interpolation, Vec<f32>)>, String> {
    let Some(p) = find(props, name) else {
        return Ok(None);
    };
    let (values, indices, metadata) = match p.kind {
        Kind::Compound => {
            let inner = a.properties(p.group)?;
            let vals = find(&inner, ".vals").ok_or_else(|| format!("{name}: no .vals"))?;
            let indices = match find(&inner, ".indices") {
                Some(ix) if ix.pod == 5 || ix.pod == POD_I32 => {
                    let (bytes, _) = a.sample(ix, time)?;
                    Some(
                        bytes
                            .chunks_exact(4)
                            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                            .collect::<Vec<u32>>(),
                    )
                }
                _ => None,
            };
            (a.f32s(vals, time, extent)?, indices, &p.metadata)
        }
        _ => (a.f32s(p, time, extent)?, None, &p.metadata),
    };
    let values = match indices {
        Some(ix) => {
            let e = extent as usize;
            let mut out = Vec::with_capacity(ix.len().min(values.len() * 4) * e);
            for i in ix {
                let i = i as usize * e;
                out.extend_from_slice(
                    values
                        .get(i..i + e)
                        .ok_or_else(|| format!("{name}: index out of range"))?,
                );
            }
            out
        }
        None => values,
    };
    let interpolation = match meta(metadata, "geoScope") {
        Some("con") => Interpolation::Constant,
        Some("uni") => Interpolation::Uniform,
        Some("var" | "fvr") => Interpolation::Varying,
        _ if values.len() == extent as usize => Interpolation::Constant,
        _ => Interpolation::Vertex,
    };
    Ok(Some((interpolation, values)))
}
