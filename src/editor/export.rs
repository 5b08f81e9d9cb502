//! Export a still (Ctrl+E): the session rendered off-screen at its render size by a second renderer on
//! the same device, refined a bounded unit per UI frame (the UI never freezes), then read back and
//! written as EXR (with AOVs and the header `render` writes) and a PNG preview on a worker.

use super::app::Level;
use super::jobs::Job;
use super::live::LiveScene;
use crate::render::Renderer;
use crate::session::Session;
use crate::session::assemble::{LoadedHairSource, Scene, StillHeader, still_attributes};
use std::path::PathBuf;
use std::time::Instant;

pub struct ExportJob {
    pub exr: PathBuf,
    pub png: Option<PathBuf>,
    session: Session,
    scene: Scene,
    renderer: Renderer,
    writing: Option<Job<Result<String, String>>>,
    pub started: Instant,
    pub fraction: f32,
    wake: egui::Context,
}

impl ExportJob {
    /// Starts an export of `session` with the live scene's hair and environment.
    pub fn start(
        live: &LiveScene,
        luts: &crate::scattering::lut::Luts,
        session: &Session,
        exr: PathBuf,
        png: Option<PathBuf>,
        wake: egui::Context,
    ) -> Result<Self, String> {
        if live.needs_rebuild(session) {
            return Err("the scene is still loading; export when it is shown".into());
        }
        for p in std::iter::once(&exr).chain(png.iter()) {
            let dir = match p.parent() {
                Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                _ => PathBuf::from("."),
            };
            if !dir.is_dir() {
                return Err(format!(
                    "{}: the folder {} does not exist",
                    p.display(),
                    dir.display()
                ));
            }
        }
        let hair = LoadedHairSource {
            hair: (*live.hair).clone(),
            name: live.hair_name.clone(),
            warning: None,
        };
        let scene = Scene::from_parts(session, hair, live.environment.clone(), None)
            .map_err(|e| e.to_string())?;
        let renderer = Renderer::new(
            &live.ctx,
            scene.settings.clone(),
            luts,
            &scene.hair,
            &scene.sigma_a,
            &scene.look,
            &scene.environment.lights.lights,
            &scene.camera,
        )
        .map_err(|e| e.to_string())?;
        Ok(Self {
            exr,
            png,
            session: session.clone(),
            scene,
            renderer,
            writing: None,
            started: Instant::now(),
            fraction: 0.0,
            wake,
        })
    }

    /// One frame of the export; returns the final message when done.
    pub fn poll(&mut self, live: &mut Option<LiveScene>) -> Option<(Level, String)> {
        if let Some(job) = &mut self.writing {
            return job.poll().map(|r| match r.and_then(|r| r) {
                Ok(m) => (Level::Info, m),
                Err(e) => (Level::Error, e),
            });
        }
        let Some(live) = live else {
            return Some((Level::Error, "export: the scene went away".into()));
        };
        let ctx = &live.ctx;
        let progress = match self.renderer.refine(ctx) {
            Ok(p) => p,
            Err(e) => return Some((Level::Error, format!("export: {e}"))),
        };
        self.fraction = progress.fraction;
        if !progress.converged {
            return None;
        }
        // Converged: the GPU is idle for this renderer, the read-back is short.
        let frame = match self.renderer.read_frame(ctx) {
            Ok(f) => f,
            Err(e) => return Some((Level::Error, format!("export: {e}"))),
        };
        let attributes = still_attributes(
            &self.session,
            &StillHeader {
                hair_name: &self.scene.hair_name,
                environment: &self.scene.environment,
                look: &self.scene.look,
                camera: &self.scene.camera,
                settings: &self.scene.settings,
                adapter: &ctx.summary.name,
                mode: "srbf",
            },
        );
        let (exr, png) = (self.exr.clone(), self.png.clone());
        let seconds = self.started.elapsed().as_secs_f64();
        let wake = self.wake.clone();
        self.writing = Some(Job::spawn(
            "writing the still",
            move || wake.request_repaint(),
            move |_| {
                frame
                    .write_exr(&exr, &attributes, true)
                    .map_err(|e| e.to_string())?;
                if let Some(p) = &png {
                    frame.write_png(p).map_err(|e| e.to_string())?;
                }
                Ok(format!(
                    "exported {} ({}x{}) in {seconds:.1} s",
                    exr.display(),
                    frame.width,
                    frame.height
                ))
            },
        ));
        None
    }

    /// The EXR path with `.png` for the preview.
    pub fn preview_path(exr: &std::path::Path) -> PathBuf {
        exr.with_extension("png")
    }
}
