//! Loading any supported hair or mesh file into world space (cm, +Y up).

use super::alembic::read_alembic;
use super::curve_file::CurveFile;
use super::error::HairError;
use super::gltf_io::read_gltf;
use super::mesh::{TriangleMesh, read_obj};
use super::model::{CleanReport, Hair, Thickness};
use super::normalize::{Normalization, Units, UpAxis, detect_units, detect_up};
use super::tressfx::read_tressfx;
use super::usd::{CurveSelection, read_usd};
use glam::Vec3;
use serde::Serialize;
use std::path::Path;

/// User overrides of the detected or declared orientation and units, and which curves of a
/// production file (USD, Alembic) to read.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    pub up: Option<UpAxis>,
    pub units: Option<Units>,
    /// Extra scale after unit conversion.
    pub scale: f32,
    pub curves: CurveSelection,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            up: None,
            units: None,
            scale: 1.0,
            curves: CurveSelection::default(),
        }
    }
}

/// Which optional data the source file carried.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ArraysPresent {
    pub segments: bool,
    pub thickness: bool,
    pub transparency: bool,
    pub colour: bool,
    pub strand_uvs: bool,
}

/// A hair file in world space: what was read (hair and mesh already transformed) and how.
pub struct LoadedHair {
    pub file: RawHairFile,
    /// Bounds in the file's own space.
    pub source_bounds: (Vec3, Vec3),
    pub normalization: Normalization,
}

fn read_file(path: &Path) -> Result<Vec<u8>, HairError> {
    std::fs::read(path).map_err(|e| HairError::io(path, e))
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// A hair file as read.
pub struct RawHairFile {
    /// What a production curves file (USD, Alembic) declared and held beyond the strands.
    pub curves: Option<CurveFile>,
    pub hair: Hair,
    /// Occluder triangles found in the same file (glTF).
    pub mesh: Option<TriangleMesh>,
    pub format: &'static str,
    /// Strand and point counts the file declares (before cleaning).
    pub declared: (u64, u64),
    pub arrays: ArraysPresent,
    pub clean: CleanReport,
}

/// Reads a hair file (.hair, .tfx, .gltf, .glb, USD) without normalising it.
pub fn read_hair_raw(path: &Path, curves: &CurveSelection) -> Result<RawHairFile, HairError> {
    let ext = extension(path);
    if matches!(ext.as_str(), "usd" | "usda" | "usdc" | "usdz") {
        if !path.is_file() {
            return Err(HairError::io(
                path,
                std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
            ));
        }
        let file = read_usd(path, curves).map_err(|e| HairError::format(path, e))?;
        return from_curve_file(path, "USD", file);
    }
    let bytes = read_file(path)?;
    match ext.as_str() {
        "abc" => {
            let file = read_alembic(&bytes, curves).map_err(|e| HairError::format(path, e))?;
            from_curve_file(path, "Alembic", file)
        }
        "hair" => {
            let (hair, h, clean) = read_cyhair(&bytes, path)?;
            use super::cyhair::{
                FLAG_COLOURS, FLAG_SEGMENTS, FLAG_THICKNESS, FLAG_TRANSPARENCY, read_cyhair,
            };
            let arrays = ArraysPresent {
                segments: h.flags & FLAG_SEGMENTS != 0,
                thickness: h.flags & FLAG_THICKNESS != 0,
                transparency: h.flags & FLAG_TRANSPARENCY != 0,
                colour: h.flags & FLAG_COLOURS != 0,
                strand_uvs: false,
            };
            Ok(RawHairFile {
                curves: None,
                hair,
                mesh: None,
                format: "cyHair",
                declared: (h.strands as u64, h.points as u64),
                arrays,
                clean,
            })
        }
        "tfx" => {
            let (hair, info, clean) = read_tressfx(&bytes, path)?;
            let arrays = ArraysPresent {
                strand_uvs: info.strand_uvs.is_some(),
                ..Default::default()
            };
            let fmt = if info.version < 4.0 {
                "TressFX 3.x"
            } else {
                "TressFX 4.x"
            };
            let n = info.strands as u64;
            Ok(RawHairFile {
                curves: None,
                hair,
                mesh: None,
                format: fmt,
                declared: (n, n * info.vertices_per_strand as u64),
                arrays,
                clean,
            })
        }
        "gltf" | "glb" => {
            let content = read_gltf(&bytes, path, path.parent())?;
            if content.strands.is_empty() {
                return Err(HairError::format(
                    path,
                    "the glTF file has no LINES or LINE_STRIP primitives (no strands)",
                ));
            }
            let declared = (
                content.strands.len() as u64,
                content.strands.iter().map(|s| s.points.len() as u64).sum(),
            );
            let (hair, clean) =
                Hair::from_strands(content.strands, super::model::DEFAULT_FIBER_DIAMETER);
            if hair.strand_count() == 0 {
                return Err(HairError::format(
                    path,
                    "no strand has two or more distinct points",
                ));
            }
            let mesh = (!content.mesh.triangles.is_empty()).then_some(content.mesh);
            Ok(RawHairFile {
                curves: None,
                hair,
                mesh,
                format: "glTF",
                declared,
                arrays: ArraysPresent::default(),
                clean,
            })
        }
        _ => Err(HairError::UnknownType { path: path.into() }),
    }
}

/// The strands of a production curves file, cleaned.
fn from_curve_file(
    path: &Path,
    format: &'static str,
    mut file: CurveFile,
) -> Result<RawHairFile, HairError> {
    let strands = std::mem::take(&mut file.strands);
    let (hair, clean) = Hair::from_strands(strands, super::model::DEFAULT_FIBER_DIAMETER);
    if hair.strand_count() == 0 {
        return Err(HairError::format(
            path,
            "no curve has two or more distinct points",
        ));
    }
    Ok(RawHairFile {
        hair,
        mesh: None,
        format,
        declared: file.declared,
        arrays: ArraysPresent {
            thickness: file.widths,
            colour: file.colour.is_some(),
            ..Default::default()
        },
        clean,
        curves: Some(file),
    })
}

/// Reads a hair file and brings it into world space (cm, +Y up), detecting what is not given.
pub fn load_hair(path: &Path, options: &LoadOptions) -> Result<LoadedHair, HairError> {
    let mut file = read_hair_raw(path, &options.curves)?;
    let declared_up = file.curves.as_ref().and_then(|c| c.up);
    let declared_cm = file.curves.as_ref().and_then(|c| c.cm_per_unit);
    let RawHairFile {
        hair,
        mesh,
        format,
        arrays,
        ..
    } = &mut file;
    let format = *format;
    let source_bounds = hair.bounds();
    let roots: Vec<Vec3> = (0..hair.strand_count())
        .map(|s| hair.strand(s)[0])
        .collect();
    let tips: Vec<Vec3> = (0..hair.strand_count())
        .map(|s| *hair.strand(s).last().unwrap_or(&Vec3::ZERO))
        .collect();
    let extent = (source_bounds.1 - source_bounds.0).max_element();
    if !(options.scale.is_finite() && options.scale > 0.0) {
        return Err(HairError::format(
            path,
            format!("scale must be positive, got {}", options.scale),
        ));
    }
    let normalization = Normalization {
        up: options.up.or(declared_up).unwrap_or_else(|| match format {
            "cyHair" => detect_up(&roots, &tips, source_bounds),
            _ => UpAxis::PosY,
        }),
        up_source: match (options.up, declared_up, format) {
            (Some(_), _, _) => "given",
            (None, Some(_), _) => "declared by the file",
            (None, None, "cyHair") => "detected",
            (None, None, _) => "format convention",
        },
        units: options.units.unwrap_or_else(|| detect_units(extent)),
        units_detected: options.units.is_none() && declared_cm.is_none(),
        declared_cm_per_unit: declared_cm.filter(|_| options.units.is_none()),
        scale: options.scale,
    };
    let k = normalization.length_factor();
    // A file without thickness gets the format's default in centimetres already: scale only real data.
    let thickness_scale = if arrays.thickness || format == "cyHair" {
        k
    } else {
        1.0
    };
    hair.transform(|p| normalization.apply(p), thickness_scale);
    if let Some(m) = mesh {
        m.positions
            .iter_mut()
            .for_each(|p| *p = normalization.apply(*p));
    }
    if let Thickness::Uniform(t) = hair.thickness
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(HairError::format(
            path,
            format!("default thickness {t} is invalid"),
        ));
    }
    Ok(LoadedHair {
        file,
        source_bounds,
        normalization,
    })
}

/// Reads an occluder mesh (.obj, .gltf, .glb) and applies `normalization` (usually the hair's, so
/// both land in the same space).
pub fn load_mesh(path: &Path, normalization: &Normalization) -> Result<TriangleMesh, HairError> {
    let bytes = read_file(path)?;
    let mut mesh = match extension(path).as_str() {
        "obj" => read_obj(&bytes, path)?,
        "gltf" | "glb" => {
            let content = read_gltf(&bytes, path, path.parent())?;
            if content.mesh.triangles.is_empty() {
                return Err(HairError::format(
                    path,
                    "the glTF file has no TRIANGLES primitives",
                ));
            }
            content.mesh
        }
        _ => return Err(HairError::UnknownType { path: path.into() }),
    };
    mesh.positions
        .iter_mut()
        .for_each(|p| *p = normalization.apply(*p));
    Ok(mesh)
}
