//! Loads on workers: the scene (hair, environment and the renderer's CPU work, built off the UI
//! thread), and the hair, head or environment files that become edits when they load. Each job wakes
//! the UI when it is done; the app polls them once a frame.

use super::env_preview::{self, EnvPictures};
use crate::gpu::GpuContext;
use crate::jobs::{Job, Wake};
use crate::live::LiveDriver;
use crate::paint::layer::PaintLayer;
use crate::render::scene::Environment;
use crate::scattering::lut::Luts;
use crate::session::assemble::{self, load_environment_source, load_hair_source};
use crate::session::{EnvironmentSource, HairSource, Look, Session};
use std::path::PathBuf;
use std::sync::Arc;

/// What a load job brings back.
pub enum Loaded {
    /// A new scene, its renderer built on the worker too (pipelines compile there: ~1.5 s on
    /// lavapipe that the UI thread does not wait for); its render thread starts when it is installed.
    Scene {
        driver: Box<LiveDriver>,
        pictures: Arc<EnvPictures>,
        warnings: Vec<String>,
    },
    /// A hair file that loaded: it becomes the session's hair (an edit; the scene then reloads).
    Hair {
        source: HairSource,
        /// The look and paint a groom strandlight exported carries back.
        restored: Option<Box<(Look, PaintLayer)>>,
    },
    /// An occluder mesh that loaded: it becomes the session's head (an edit; the scene reloads).
    Occluder { path: PathBuf },
    /// A new environment; applied as an edit when it arrives.
    Environment {
        environment: Box<Environment>,
        pictures: Box<EnvPictures>,
        source: EnvironmentSource,
    },
}

type LoadJob = Job<Result<Loaded, String>>;

/// What a scene is built from, beyond what the renderer changes in place: a failed build is not
/// retried until one of these changes.
#[derive(Clone, Debug, PartialEq)]
struct SceneKey {
    hair: HairSource,
    environment: EnvironmentSource,
    render: (u32, u32, u32),
    paint: Option<PathBuf>,
}

impl SceneKey {
    fn of(s: &Session) -> Self {
        Self {
            hair: s.hair.clone(),
            environment: s.environment.clone(),
            render: (
                s.render.samples,
                s.render.volume_resolution,
                s.render.shadow_grid_resolution,
            ),
            paint: s.paint.clone(),
        }
    }
}

pub struct Loader {
    /// The scene being loaded, and the session it is for (a newer request supersedes it).
    scene: Option<(LoadJob, Session)>,
    /// A hair, head or environment file being loaded for an edit.
    source: Option<LoadJob>,
    /// The scene whose build failed (not retried until the session's sources change).
    failed: Option<SceneKey>,
    wake: Wake,
}

impl Loader {
    pub fn new(wake: Wake) -> Self {
        Self {
            scene: None,
            source: None,
            failed: None,
            wake,
        }
    }

    /// The scene load under way, if any (its label).
    pub fn scene_label(&self) -> Option<&str> {
        self.scene.as_ref().map(|(j, _)| j.label.as_str())
    }

    pub fn loading_scene(&self) -> bool {
        self.scene.is_some()
    }

    pub fn loading_source(&self) -> bool {
        self.source.is_some()
    }

    /// Another session: its scene is tried even if the last one failed.
    pub fn forget_failure(&mut self) {
        self.failed = None;
    }

    /// Whether `session` needs a load started: none under way for it, and it did not fail.
    pub fn should_load(&self, session: &Session) -> bool {
        let key = SceneKey::of(session);
        let pending = self
            .scene
            .as_ref()
            .is_some_and(|(_, s)| SceneKey::of(s) == key);
        !pending && self.failed.as_ref() != Some(&key)
    }

    /// Loads the session's hair and environment and prepares the renderer's CPU work off the UI
    /// thread, for a render of `size`.
    pub fn load_scene(
        &mut self,
        session: &Session,
        gpu: Option<GpuContext>,
        luts: Arc<Luts>,
        size: (u32, u32),
    ) {
        // A load this one supersedes stops before it builds a renderer.
        if let Some((old, _)) = self.scene.take() {
            old.cancel();
        }
        let for_session = session.clone();
        let session = session.clone();
        let wake = self.wake.clone();
        let job = Job::spawn(
            "loading the scene",
            move || wake(),
            move |cancelled| {
                let gpu = gpu.ok_or("no GPU adapter")?;
                let (driver, warnings) =
                    crate::live::load::open(gpu, &luts, &session, size, cancelled)?;
                let pictures = Arc::new(env_preview::pictures(
                    &driver.environment,
                    driver.background_map().clone(),
                ));
                Ok(Loaded::Scene {
                    driver: Box::new(driver),
                    pictures,
                    warnings,
                })
            },
        );
        self.scene = Some((job, for_session));
    }

    /// The scene load's result once it is done, with the session it was for; a failure is
    /// remembered so that the same scene is not tried again.
    pub fn poll_scene(&mut self) -> Option<(Result<Loaded, String>, Session)> {
        let (job, _) = self.scene.as_mut()?;
        let result = job.poll()?.and_then(|r| r);
        let (_, session) = self.scene.take()?;
        match &result {
            Ok(_) => self.failed = None,
            Err(_) => self.failed = Some(SceneKey::of(&session)),
        }
        Some((result, session))
    }

    /// The source load's result once it is done.
    pub fn poll_source(&mut self) -> Option<Result<Loaded, String>> {
        let result = self.source.as_mut()?.poll()?;
        self.source = None;
        Some(result.and_then(|r| r))
    }

    /// Loads an environment file (fitting it when it is an image) on a worker; a failure names the
    /// file.
    pub fn load_environment(&mut self, path: PathBuf, lights: usize) {
        let wake = self.wake.clone();
        self.source = Some(Job::spawn(
            format!("loading {}", path.display()),
            move || wake(),
            move |_| {
                let blake3 = assemble::file_blake3(&path).ok();
                let source = EnvironmentSource::File {
                    path: path.clone(),
                    lights: lights.max(1),
                    blake3: blake3.clone(),
                    fitted: None,
                };
                let (environment, _) =
                    load_environment_source(&source).map_err(|e| e.to_string())?;
                let source = EnvironmentSource::File {
                    path,
                    lights: lights.max(1),
                    blake3,
                    fitted: Some(Box::new(environment.lights.clone())),
                };
                Ok(Loaded::Environment {
                    pictures: Box::new(env_preview::pictures_of(&environment)),
                    environment: Box::new(environment),
                    source,
                })
            },
        ));
    }

    /// Loads a hair file on a worker; a failure names the file.
    pub fn open_hair(&mut self, path: PathBuf) {
        let wake = self.wake.clone();
        self.source = Some(Job::spawn(
            format!("loading {}", path.display()),
            move || wake(),
            move |_| {
                let source = HairSource::File {
                    blake3: assemble::file_blake3(&path).ok(),
                    path,
                    prim: None,
                    time: None,
                };
                let loaded = load_hair_source(&source).map_err(|e| e.to_string())?;
                let restored = assemble::exported_look_and_paint(&loaded);
                Ok(Loaded::Hair {
                    source,
                    restored: restored.map(Box::new),
                })
            },
        ));
    }

    /// Loads an occluder mesh (.obj, .gltf, .glb) on a worker, in the hair's space
    /// (`normalization`); a failure names the file.
    pub fn open_occluder(
        &mut self,
        path: PathBuf,
        normalization: crate::hair::normalize::Normalization,
    ) {
        let wake = self.wake.clone();
        self.source = Some(Job::spawn(
            format!("loading {}", path.display()),
            move || wake(),
            move |_| {
                let mesh = crate::hair::load::load_mesh(&path, &normalization)
                    .map_err(|e| e.to_string())?;
                if mesh.triangles.is_empty() {
                    return Err(format!("{}: the mesh has no triangles", path.display()));
                }
                Ok(Loaded::Occluder { path })
            },
        ));
    }
}
