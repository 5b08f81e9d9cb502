//! Scene assembly from a [`Session`]: the hair, the environment's lights (turned by the session's yaw),
//! the per-point absorption, the look in the renderer's form, the camera and the render settings. The
//! CLI's `render` and the editor both build their scenes here.

use super::model::{EnvironmentSource, HairSource, Look, OccluderOptions, Session};
use crate::envmap::{SrbfSet, load_env};
use crate::hair::Hair;
use crate::hair::TriangleMesh;
use crate::hair::load::{LoadOptions, load_hair, load_mesh};
use crate::hair::normalize::Normalization;
use crate::hair::procedural::generate;
use crate::paint::{AbsorptionSpec, PaintLayer};
use crate::render::passes::occluder::Occluder;
use crate::render::scene::{Environment, default_environment, load_environment};
use crate::render::{Camera, HairLook, RenderSettings};
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum AssembleError {
    #[error("{0}")]
    Hair(#[from] crate::hair::HairError),
    #[error("{path}: {message}")]
    Environment { path: String, message: String },
    #[error("{0}")]
    Paint(#[from] crate::paint::PaintLayerError),
    #[error("{0}: no strands to render")]
    NoStrands(String),
    #[error("invalid look: {0}")]
    Look(String),
    #[error("{0}: {1}")]
    Generator(String, String),
}

/// A loaded hair, its name for logs and EXR headers, and a warning when the file changed since the
/// session recorded it.
pub struct LoadedHairSource {
    pub hair: Hair,
    pub name: String,
    pub warning: Option<String>,
    /// The hair's own occluder: the generated head, or the mesh a glTF file carries.
    pub mesh: Option<TriangleMesh>,
    /// How the file came into world space (an occluder file of the session gets the same).
    pub normalization: Normalization,
    /// The look strandlight exported with this groom (its USD), where the file carries one.
    pub look: Option<Look>,
}

/// The generator's space: centimetres, +Y up, as it is.
pub const GENERATOR_SPACE: Normalization = Normalization {
    up: crate::hair::normalize::UpAxis::PosY,
    up_source: "generator",
    units: crate::hair::normalize::Units::Centimetres,
    units_detected: false,
    declared_cm_per_unit: None,
    scale: 1.0,
};

/// BLAKE3 of a file's bytes, hex.
pub fn file_blake3(path: &Path) -> std::io::Result<String> {
    Ok(blake3::hash(&std::fs::read(path)?).to_hex().to_string())
}

fn changed_warning(path: &Path, recorded: &Option<String>) -> Option<String> {
    let recorded = recorded.as_ref()?;
    match file_blake3(path) {
        Ok(h) if &h == recorded => None,
        Ok(_) => Some(format!(
            "{} changed since the session was saved",
            path.display()
        )),
        Err(e) => Some(format!("{}: {e}", path.display())),
    }
}

pub fn load_hair_source(source: &HairSource) -> Result<LoadedHairSource, AssembleError> {
    let loaded = match source {
        HairSource::Generated {
            style,
            strands,
            points,
            ..
        } => {
            let name = format!("generated {style:?} {strands}x{points}");
            let params = source
                .style_params()
                .ok_or_else(|| AssembleError::Generator(name.clone(), "no settings".into()))?;
            LoadedHairSource {
                hair: generate(&params).map_err(|e| AssembleError::Generator(name.clone(), e))?,
                name,
                warning: None,
                mesh: Some(params.head.occluder_mesh()),
                normalization: GENERATOR_SPACE,
                look: None,
            }
        }
        HairSource::File {
            path,
            blake3,
            prim,
            time,
        } => {
            let options = LoadOptions {
                curves: crate::hair::usd::CurveSelection {
                    prim: prim.clone(),
                    time: *time,
                },
                ..LoadOptions::default()
            };
            let loaded = load_hair(path, &options)?;
            // A look this version cannot read (another version's, a hand edit) is left out with a
            // warning: the groom itself still loads.
            let mut warning = changed_warning(path, blake3);
            let look = match loaded.file.curves.as_ref().and_then(|c| c.look.as_deref()) {
                Some(json) => serde_json::from_str::<Look>(json)
                    .map_err(|e| {
                        warning = Some(format!(
                            "{}: its strandlight look is not readable and was left out ({e})",
                            path.display()
                        ))
                    })
                    .ok(),
                None => None,
            };
            LoadedHairSource {
                hair: loaded.file.hair,
                name: path.display().to_string(),
                warning,
                mesh: loaded.file.mesh,
                normalization: loaded.normalization,
                look,
            }
        }
    };
    if loaded.hair.strand_count() == 0 {
        return Err(AssembleError::NoStrands(loaded.name));
    }
    Ok(loaded)
}

/// What a groom strandlight exported carries back: its look, and its per-point absorption as a
/// paint layer of full weight, so the session renders the absorption the export held. None for
/// any other file.
pub fn exported_look_and_paint(loaded: &LoadedHairSource) -> Option<(Look, PaintLayer)> {
    let look = loaded.look?;
    let sigma_a = loaded.hair.sigma_a.as_ref()?;
    let mut layer = PaintLayer::empty(loaded.hair.point_count(), loaded.hair.strand_count());
    for (p, s) in layer.points.iter_mut().zip(sigma_a) {
        *p = [s[0], s[1], s[2], 1.0];
    }
    Some((look, layer))
}

/// The environment (its lights unturned) and a warning when its file changed.
pub fn load_environment_source(
    source: &EnvironmentSource,
) -> Result<(Environment, Option<String>), AssembleError> {
    match source {
        EnvironmentSource::Builtin => Ok((default_environment(), None)),
        EnvironmentSource::File {
            path,
            lights,
            blake3,
            fitted,
        } => {
            // Errors of the loaders already name the file.
            let err = |message: String| {
                let p = path.display().to_string();
                AssembleError::Environment {
                    message: message
                        .strip_prefix(&format!("{p}: "))
                        .map(str::to_string)
                        .unwrap_or(message),
                    path: p,
                }
            };
            let warning = changed_warning(path, blake3);
            match fitted {
                // The saved fit opens without refitting, even when the file moved or changed (that is
                // reported; the image is kept when it still loads, for the reference mode).
                Some(set) => Ok((
                    Environment {
                        lights: (**set).clone(),
                        image: load_env(path).ok().map(|(image, _)| image),
                        name: path.display().to_string(),
                    },
                    warning,
                )),
                None => load_environment(path, *lights)
                    .map(|env| (env, warning))
                    .map_err(|e| err(e.to_string())),
            }
        }
    }
}

/// The per-point absorption of `look` on `hair` (root-to-tip gradient, per-strand variation, an
/// optional paint layer over it) and the look in the renderer's form, with sigma_a set to the mean of
/// the points (what the dual-scattering tables are built for).
pub fn absorption(
    look: &Look,
    hair: &Hair,
    paint: Option<&Path>,
) -> Result<(Vec<[f32; 3]>, HairLook), AssembleError> {
    let layer = paint.map(PaintLayer::read).transpose()?;
    painted_absorption(look, hair, layer.as_ref().zip(paint))
}

/// The look's absorption per point, before any paint (the brush mixes toward and away from it).
pub fn base_absorption(look: &Look, hair: &Hair) -> Result<Vec<[f32; 3]>, AssembleError> {
    look.validate().map_err(AssembleError::Look)?;
    let root = look.root.sigma_a().map(|x| x as f32);
    let tip = look.tip.map_or(root, |t| t.sigma_a().map(|x| x as f32));
    let spec = AbsorptionSpec {
        root,
        tip,
        variation: look.strand_variation.max(0.0),
        seed: look.variation_seed,
    };
    Ok(spec.per_point(hair))
}

/// [`absorption`] with a layer already read (`name`: the file or source it came from, for errors).
pub fn painted_absorption(
    look: &Look,
    hair: &Hair,
    layer: Option<(&PaintLayer, &Path)>,
) -> Result<(Vec<[f32; 3]>, HairLook), AssembleError> {
    let mut sigma_a = base_absorption(look, hair)?;
    if let Some((layer, name)) = layer {
        layer.apply(&mut sigma_a, hair.strand_count(), name)?;
    }
    let mean = mean_absorption(&sigma_a);
    Ok((sigma_a, renderer_look(look, mean)))
}

/// The points' mean absorption (what the dual-scattering tables are built for).
pub fn mean_absorption(sigma_a: &[[f32; 3]]) -> [f64; 3] {
    let n = sigma_a.len().max(1) as f64;
    std::array::from_fn(|c| sigma_a.iter().map(|s| s[c] as f64).sum::<f64>() / n)
}

/// The session's absorption: its paint layer in memory (the editor's) when it has one, else its
/// paint file.
pub fn session_absorption(
    session: &Session,
    hair: &Hair,
) -> Result<(Vec<[f32; 3]>, HairLook), AssembleError> {
    match &session.paint_layer {
        Some(layer) => painted_absorption(
            &session.look,
            hair,
            Some((layer.get(), Path::new("the session's paint layer"))),
        ),
        None => absorption(&session.look, hair, session.paint.as_deref()),
    }
}

/// The look in the renderer's form with `mean_sigma_a` (the points' mean absorption, what the
/// dual-scattering tables are built for).
pub fn renderer_look(look: &Look, mean_sigma_a: [f64; 3]) -> HairLook {
    let params = crate::scattering::HairParams {
        sigma_a: mean_sigma_a,
        ..look.params
    };
    HairLook::new(params)
        .with_dual(look.d_f, look.d_b)
        .with_longitudinal(look.longitudinal)
}

/// The occluder of options `o` for a hair with its own mesh `own` (in world space) that came into
/// world space by `normalization`: none when hidden, else [`occluder_mesh`] with the options' albedo.
pub fn scene_occluder(
    o: &OccluderOptions,
    own: Option<&TriangleMesh>,
    normalization: &Normalization,
) -> Result<Option<Occluder>, AssembleError> {
    if !o.show {
        return Ok(None);
    }
    shown_occluder(o, occluder_mesh(o, own, normalization)?)
}

/// The occluder the options show with `mesh` (their mesh, already resolved): none when hidden.
pub fn shown_occluder(
    o: &OccluderOptions,
    mesh: Option<TriangleMesh>,
) -> Result<Option<Occluder>, AssembleError> {
    o.validate().map_err(AssembleError::Look)?;
    Ok(mesh.filter(|_| o.show).map(|m| Occluder::new(m, o.albedo)))
}

/// The options' mesh file (brought into the hair's space) or the hair's own mesh; none without
/// triangles.
pub fn occluder_mesh(
    o: &OccluderOptions,
    own: Option<&TriangleMesh>,
    normalization: &Normalization,
) -> Result<Option<TriangleMesh>, AssembleError> {
    let mesh = match &o.mesh {
        Some(path) => Some(load_mesh(path, normalization)?),
        None => own.cloned(),
    };
    Ok(mesh.filter(|m| !m.triangles.is_empty()))
}

/// Everything the renderer is built from.
pub struct Scene {
    pub hair: Hair,
    pub hair_name: String,
    /// The environment with its lights turned by the session's yaw.
    pub environment: Environment,
    pub sigma_a: Vec<[f32; 3]>,
    pub look: HairLook,
    pub camera: Camera,
    pub settings: RenderSettings,
    /// The head (or another mesh) the hair sits on.
    pub occluder: Option<Occluder>,
    /// Files that changed since the session recorded them (the scene still opened).
    pub warnings: Vec<String>,
}

impl Scene {
    /// The scene of `session` at the session's render size.
    pub fn assemble(session: &Session) -> Result<Self, AssembleError> {
        let hair = load_hair_source(&session.hair)?;
        let (environment, env_warning) = load_environment_source(&session.environment)?;
        let occluder = scene_occluder(&session.occluder, hair.mesh.as_ref(), &hair.normalization)?;
        Self::from_parts(session, hair, environment, env_warning, occluder)
    }

    /// The scene from an already loaded hair, environment and occluder (the editor reloads only what
    /// changed).
    pub fn from_parts(
        session: &Session,
        mut hair: LoadedHairSource,
        mut environment: Environment,
        env_warning: Option<String>,
        occluder: Option<Occluder>,
    ) -> Result<Self, AssembleError> {
        let (sigma_a, look) = session_absorption(session, &hair.hair)?;
        // The look's thickness scale (after absorption, which validated the look).
        hair.hair.transform(|p| p, session.look.thickness_scale);
        environment.lights = turned_lights(&environment.lights, session.env_yaw);
        let r = &session.render;
        let (lo, hi) = hair.hair.bounds();
        let camera = session
            .camera
            .resolve(lo, hi, r.width as f32 / r.height.max(1) as f32);
        Ok(Self {
            warnings: hair.warning.into_iter().chain(env_warning).collect(),
            hair: hair.hair,
            hair_name: hair.name,
            environment,
            sigma_a,
            look,
            camera,
            settings: r.settings(r.width, r.height),
            occluder,
        })
    }
}

/// The lights turned by `yaw_deg` about +Y (no refit), strongest first (by luminous power): the
/// renderer shades and refines light batch by light batch, so the first batch carries the most light.
pub fn turned_lights(set: &SrbfSet, yaw_deg: f64) -> SrbfSet {
    let mut s = if yaw_deg == 0.0 {
        set.clone()
    } else {
        set.rotated(yaw_deg.to_radians())
    };
    let luminance = |l: &crate::envmap::SrbfLight| {
        let p = l.power();
        0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
    };
    s.lights
        .sort_by(|a, b| luminance(b).total_cmp(&luminance(a)));
    s
}

/// What an EXR still's header records besides the session.
pub struct StillHeader<'a> {
    pub hair_name: &'a str,
    pub environment: &'a Environment,
    pub look: &'a HairLook,
    pub camera: &'a Camera,
    pub settings: &'a RenderSettings,
    pub adapter: &'a str,
    pub mode: &'a str,
}

/// The EXR header attributes of a still (the CLI's `render` and the editor's export write the same):
/// readable summaries and the whole session as JSON, which reopens the picture.
pub fn still_attributes(session: &Session, h: &StillHeader) -> Vec<(String, String)> {
    let s = h.settings;
    vec![
        ("hair".into(), h.hair_name.into()),
        ("environment".into(), h.environment.name.clone()),
        (
            "lights".into(),
            h.environment.lights.lights.len().to_string(),
        ),
        ("params".into(), json(&h.look.params)),
        ("longitudinal".into(), json(&h.look.longitudinal())),
        (
            "absorption".into(),
            format!(
                "root {}, tip {}, strand variation {}, seed {}, paint {:?}",
                json(&session.look.root),
                session
                    .look
                    .tip
                    .map_or_else(|| "as root".to_string(), |t| json(&t)),
                session.look.strand_variation,
                session.look.variation_seed,
                session.paint
            ),
        ),
        ("camera".into(), json(h.camera)),
        ("exposure_ev".into(), s.exposure.to_string()),
        ("samples".into(), s.samples.to_string()),
        (
            "fragments".into(),
            format!("{} per pixel, tail {:?}", s.fragments, s.tail),
        ),
        ("shadows".into(), s.shadows.to_string()),
        (
            "multiple_scattering".into(),
            format!(
                "{} (d_f {}, d_b {})",
                s.multiple_scattering, h.look.fast.d_f, h.look.fast.d_b
            ),
        ),
        ("adapter".into(), h.adapter.into()),
        ("mode".into(), h.mode.into()),
        ("session".into(), json(session)),
    ]
}

/// Compact JSON of plain data (which cannot fail to serialise).
fn json<T: serde::Serialize>(v: &T) -> String {
    serde_json::to_string(v).unwrap_or_else(|e| e.to_string())
}
