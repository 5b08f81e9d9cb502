//! What a render needs besides settings: the default scene (a generated hairstyle under the project's
//! own sunny environment), the benchmark scenes S0-S3, and environments from files (.srbf.json as is;
//! .hdr / .exr fitted through the cache, and kept as images for the reference mode).

use crate::envmap::cache::{FitError, fit_file};
use crate::envmap::image::decode_exr;
use crate::envmap::srbf::SrbfFileError;
use crate::envmap::{EnvError, EnvMap, FitOptions, SrbfSet, load_env};
use crate::hair::Hair;
use crate::hair::procedural::{Style, StyleParams, generate};
use crate::render::passes::background::{BackgroundMap, RECONSTRUCTION_WIDTH};
use std::path::Path;

const SUNNY_SRBF: &str = include_str!("../../envmaps/sunny.srbf.json");
const SUNNY_EXR: &[u8] = include_bytes!("../../envmaps/sunny.exr");

#[derive(Debug, thiserror::Error)]
pub enum EnvironmentError {
    #[error(transparent)]
    Lights(#[from] SrbfFileError),
    #[error(transparent)]
    Fit(#[from] FitError),
    #[error(transparent)]
    Image(#[from] EnvError),
}

/// Lights and, when known, the environment they were fitted to.
#[derive(Clone, Debug)]
pub struct Environment {
    pub lights: SrbfSet,
    pub image: Option<EnvMap>,
    pub name: String,
}

/// The project's own sunny sky and its committed 40-light fit (both made by `make-env`).
pub fn default_environment() -> Environment {
    let lights: SrbfSet = serde_json::from_str(SUNNY_SRBF).unwrap_or_else(|e| {
        unreachable!("the embedded envmaps/sunny.srbf.json is checked by the tests: {e}")
    });
    let image = decode_exr(SUNNY_EXR, Path::new("envmaps/sunny.exr"))
        .ok()
        .map(|(env, _)| env);
    Environment {
        lights,
        image,
        name: "envmaps/sunny (built in)".into(),
    }
}

/// An environment file: `.srbf.json` (lights only) or `.hdr` / `.exr` (fitted with `lights` SRBFs
/// through the fit cache, the image kept).
pub fn load_environment(path: &Path, lights: usize) -> Result<Environment, EnvironmentError> {
    let name = path.display().to_string();
    if name.to_ascii_lowercase().ends_with(".json") {
        let set = SrbfSet::read(path)?;
        return Ok(Environment {
            lights: set,
            image: None,
            name,
        });
    }
    let options = FitOptions {
        lights,
        ..Default::default()
    };
    let fit = fit_file(path, &options, true, |_| {})?;
    let (image, _) = load_env(path)?;
    Ok(Environment {
        lights: fit.set,
        image: Some(image),
        name,
    })
}

/// The default hairstyle: wavy, clumped, 10k strands of 27 points (the size of Xu's "animation" scene).
pub fn default_hair() -> Hair {
    generated_hair(Style::Wavy, 10_000, 27, 1)
}

pub fn generated_hair(style: Style, strands: usize, points: usize, seed: u64) -> Hair {
    generate(&StyleParams::new(style, strands, points, seed))
        .unwrap_or_else(|e| unreachable!("fixed style parameters are valid: {e}"))
}

/// A standard benchmark scene (`strandlight bench`, docs/benchmarks.md).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct StandardScene {
    pub name: &'static str,
    pub strands: usize,
    pub points: usize,
    pub lights: usize,
    pub width: u32,
    pub height: u32,
}

pub const STANDARD_SCENES: [StandardScene; 4] = [
    // A small scene for CI-sized machines (seconds per frame on lavapipe).
    StandardScene {
        name: "S0",
        strands: 2_000,
        points: 16,
        lights: 40,
        width: 320,
        height: 240,
    },
    StandardScene {
        name: "S1",
        strands: 10_000,
        points: 27,
        lights: 40,
        width: 720,
        height: 480,
    },
    StandardScene {
        name: "S2",
        strands: 50_000,
        points: 25,
        lights: 41,
        width: 720,
        height: 480,
    },
    StandardScene {
        name: "S3",
        strands: 50_000,
        points: 25,
        lights: 40,
        width: 1920,
        height: 1080,
    },
];

impl StandardScene {
    pub fn by_name(name: &str) -> Option<Self> {
        STANDARD_SCENES
            .iter()
            .copied()
            .find(|s| s.name.eq_ignore_ascii_case(name))
    }

    /// The generated head under every scene's hair (as under the default render's).
    pub fn occluder(&self) -> crate::render::passes::occluder::Occluder {
        crate::render::passes::occluder::Occluder::new(
            crate::hair::procedural::Head::default().occluder_mesh(),
            crate::render::passes::occluder::SKIN_ALBEDO,
        )
    }

    /// S0 and S1 are wavy (Xu's animated character), S2 and S3 straight (Xu's "straight").
    pub fn hair(&self) -> Hair {
        let style = if matches!(self.name, "S0" | "S1") {
            Style::Wavy
        } else {
            Style::StraightLong
        };
        generated_hair(style, self.strands, self.points, 1)
    }
}

/// The background map of an environment is made here, where environments are, so that the
/// background pass needs nothing of scenes.
impl BackgroundMap {
    /// The environment's image (turned by the lights' yaw), or, without one, the reconstruction of its
    /// lights (already turned).
    pub fn from_environment(env: &Environment) -> Self {
        match &env.image {
            Some(image) => Self::from_map(image, env.lights.yaw as f32),
            None => Self::from_map(
                &env.lights
                    .render(RECONSTRUCTION_WIDTH, RECONSTRUCTION_WIDTH / 2),
                0.0,
            ),
        }
    }
}
