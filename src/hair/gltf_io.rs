//! glTF 2.0 (`.gltf`, `.glb`): LINES and LINE_STRIP primitives become strands, TRIANGLES an
//! occluder mesh. Node transforms of the default scene (or every scene) are applied.

use super::error::{HairError, MAX_POINTS};
use super::mesh::{TriangleMesh, validate_mesh};
use super::model::RawStrand;
use glam::{Mat4, Vec3};
use gltf::mesh::Mode;
use std::path::Path;

/// What a glTF file holds for strandlight.
#[derive(Debug, Default)]
pub struct GltfContent {
    pub strands: Vec<RawStrand>,
    pub mesh: TriangleMesh,
    /// Primitives of other modes (points, triangle strips and fans), skipped.
    pub skipped_primitives: usize,
}

/// Parses a glTF or GLB from bytes; external buffers are resolved next to `path` when `base` is given.
///
/// The `gltf` crate (1.4) panics on some malformed files (unchecked accessor indices while
/// validating, `unreachable!` for float index accessors while reading). [`precheck`] rejects the
/// cases the fuzz tests found; the whole read also runs under `catch_unwind` so that any other
/// such panic becomes an error instead of taking the editor down.
pub fn read_gltf(bytes: &[u8], path: &Path, base: Option<&Path>) -> Result<GltfContent, HairError> {
    let err = |m: String| HairError::format(path, m);
    precheck(bytes).map_err(|m| err(format!("invalid glTF: {m}")))?;
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        read_gltf_unchecked(bytes, path, base)
    }))
    .unwrap_or_else(|_| {
        Err(err(
            "invalid glTF: the glTF library failed on malformed data".into(),
        ))
    })
}

fn read_gltf_unchecked(
    bytes: &[u8],
    path: &Path,
    base: Option<&Path>,
) -> Result<GltfContent, HairError> {
    let err = |m: String| HairError::format(path, m);
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| err(format!("invalid glTF: {e}")))?;
    let buffers = gltf::import_buffers(&gltf.document, base, gltf.blob.clone())
        .map_err(|e| err(format!("glTF buffers: {e}")))?;
    let mut out = GltfContent::default();
    let scenes: Vec<gltf::Scene> = match gltf.document.default_scene() {
        Some(s) => vec![s],
        None => gltf.document.scenes().collect(),
    };
    let mut stack: Vec<(gltf::Node, Mat4, u32)> = scenes
        .iter()
        .flat_map(|s| s.nodes().map(|n| (n, Mat4::IDENTITY, 0)))
        .collect();
    let mut points = 0u64;
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 64 {
            return Err(err("node hierarchy deeper than 64 levels (a cycle?)".into()));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(err(format!(
                "node {} has a non-finite transform",
                node.index()
            )));
        }
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
        let Some(mesh) = node.mesh() else { continue };
        for prim in mesh.primitives() {
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(pos) = reader.read_positions() else {
                return Err(err(format!(
                    "mesh {} has a primitive without positions",
                    mesh.index()
                )));
            };
            let pos: Vec<Vec3> = pos
                .map(|p| world.transform_point3(Vec3::from_array(p)))
                .collect();
            points += pos.len() as u64;
            if points > MAX_POINTS {
                return Err(err(format!("more than {MAX_POINTS} points")));
            }
            if let Some(k) = pos.iter().position(|p| !p.is_finite()) {
                return Err(err(format!(
                    "mesh {}: vertex {k} is not finite",
                    mesh.index()
                )));
            }
            let idx: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..pos.len() as u32).collect(),
            };
            if let Some(&bad) = idx.iter().find(|&&i| i as usize >= pos.len()) {
                return Err(err(format!(
                    "mesh {}: index {bad} past the {} vertices",
                    mesh.index(),
                    pos.len()
                )));
            }
            match prim.mode() {
                Mode::LineStrip => out.strands.push(RawStrand {
                    points: idx.iter().map(|&i| pos[i as usize]).collect(),
                    ..Default::default()
                }),
                Mode::Lines => chain_segments(&idx, &pos, &mut out.strands),
                Mode::Triangles => {
                    let part = TriangleMesh {
                        positions: pos,
                        triangles: idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
                    };
                    validate_mesh(&part, path)?;
                    out.mesh.append(&part);
                }
                _ => out.skipped_primitives += 1,
            }
        }
    }
    Ok(out)
}

/// Every accessor index a mesh primitive names (attributes, indices, morph targets) must exist
/// (gltf-json 1.4's validation indexes `accessors` with them unchecked), and index accessors must be
/// unsigned integers (5121, 5123, 5125) as the specification requires (gltf 1.4 hits
/// `unreachable!` otherwise).
fn precheck(bytes: &[u8]) -> Result<(), String> {
    let json: &[u8] = if bytes.starts_with(b"glTF") {
        // GLB: 12-byte header, then the JSON chunk (length, type, data).
        let len = bytes
            .get(12..16)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
            .ok_or("truncated GLB header")?;
        bytes
            .get(20..20usize.saturating_add(len))
            .ok_or("GLB JSON chunk runs past the end of the file")?
    } else {
        bytes
    };
    let root: serde_json::Value = serde_json::from_slice(json).map_err(|e| e.to_string())?;
    let accessors = root
        .get("accessors")
        .and_then(|a| a.as_array())
        .map_or(0, |a| a.len()) as u64;
    let check = |v: &serde_json::Value| -> Result<(), String> {
        match v.as_u64() {
            Some(i) if i >= accessors => Err(format!(
                "accessor {i} does not exist ({accessors} accessors)"
            )),
            _ => Ok(()),
        }
    };
    let meshes = root.get("meshes").and_then(|m| m.as_array());
    for prim in meshes
        .into_iter()
        .flatten()
        .filter_map(|m| m.get("primitives").and_then(|p| p.as_array()))
        .flatten()
    {
        for attrs in std::iter::once(prim.get("attributes"))
            .chain(
                prim.get("targets")
                    .and_then(|t| t.as_array())
                    .into_iter()
                    .flatten()
                    .map(Some),
            )
            .flatten()
        {
            if let Some(obj) = attrs.as_object() {
                obj.values().try_for_each(check)?;
            }
        }
        if let Some(i) = prim.get("indices") {
            check(i)?;
            let component = i.as_u64().and_then(|k| {
                root.get("accessors")?
                    .get(k as usize)?
                    .get("componentType")?
                    .as_u64()
            });
            if let Some(c) = component
                && !matches!(c, 5121 | 5123 | 5125)
            {
                return Err(format!(
                    "index accessor has component type {c}, not an unsigned integer"
                ));
            }
        }
    }
    Ok(())
}

/// LINES: consecutive segments (a, b), (b, c), ... form one strand; a segment whose start is not
/// the previous end starts a new strand.
fn chain_segments(idx: &[u32], pos: &[Vec3], strands: &mut Vec<RawStrand>) {
    let mut current: Vec<Vec3> = Vec::new();
    let mut last: Option<u32> = None;
    for seg in idx.chunks_exact(2) {
        if last != Some(seg[0]) {
            if current.len() >= 2 {
                strands.push(RawStrand {
                    points: std::mem::take(&mut current),
                    ..Default::default()
                });
            }
            current.clear();
            current.push(pos[seg[0] as usize]);
        }
        current.push(pos[seg[1] as usize]);
        last = Some(seg[1]);
    }
    if current.len() >= 2 {
        strands.push(RawStrand {
            points: current,
            ..Default::default()
        });
    }
}
