//! Export a still (Ctrl+E): the session rendered off-screen at its render size by a second renderer on
//! the same device, refined a bounded unit per UI frame (the UI never freezes), tile by tile when the
//! image's buffers exceed what the GPU binds at once (an 8K still on lavapipe), then written as EXR (with
//! AOVs and the header `render` writes) and a PNG preview on a worker.

use super::messages::Level;
use crate::gpu::GpuContext;
use crate::jobs::{Job, Wake};
use crate::live::LiveDriver;
use crate::render::Renderer;
use crate::render::camera::Tile;
use crate::render::frame::Frame;
use crate::render::passes::background::Background;
use crate::render::renderer::FrameReadBack;
use crate::render::tiled::{empty_frame, paste};
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
    tiles: Vec<Tile>,
    /// The tile being refined, and the full frame the finished ones are pasted into.
    current: usize,
    frame: Option<Frame>,
    /// The converged tile on its way back from the GPU (polled, never waited for).
    reading: Option<FrameReadBack>,
    writing: Option<Job<Result<String, String>>>,
    pub started: Instant,
    pub fraction: f32,
    wake: Wake,
}

impl ExportJob {
    /// Starts an export of `session` with the live scene's hair and environment.
    /// `tile`: at most this many pixels a side per tile (None: tiles only when the image needs them).
    #[allow(clippy::too_many_arguments)]
    pub fn start(
        live: &LiveDriver,
        luts: &crate::scattering::lut::Luts,
        session: &Session,
        exr: PathBuf,
        png: Option<PathBuf>,
        wake: Wake,
        tile: Option<u32>,
    ) -> Result<Self, String> {
        if live.needs_rebuild(session) {
            return Err("the scene is still loading; export when it is shown".into());
        }
        crate::render::frame::check_output_folders(
            std::iter::once(exr.as_path()).chain(png.as_deref()),
        )
        .map_err(|e| e.to_string())?;
        // The paint the viewport shows: a layer painted on another hair, or a file that cannot be
        // read, is left out as the viewport leaves it out.
        let mut session = session.clone();
        let (layer, _) = crate::live::prepare::paint_for(&session, &live.hair, &mut None);
        if layer.is_none() {
            session.paint = None;
        }
        session.paint_layer = layer;
        let hair = LoadedHairSource {
            hair: (*live.hair).clone(),
            name: live.sources.hair_name.clone(),
            warning: None,
            mesh: live.sources.hair_mesh.clone(),
            normalization: live.normalization,
            look: None,
        };
        // The head the viewport shows.
        let occluder = live.occluder.clone();
        let scene = Scene::from_parts(&session, hair, live.environment.clone(), None, occluder)
            .map_err(|e| e.to_string())?;
        Self::with_scene(live, luts, &session, scene, exr, png, wake, tile)
    }

    #[allow(clippy::too_many_arguments)]
    fn with_scene(
        live: &LiveDriver,
        luts: &crate::scattering::lut::Luts,
        session: &Session,
        scene: Scene,
        exr: PathBuf,
        png: Option<PathBuf>,
        wake: Wake,
        tile: Option<u32>,
    ) -> Result<Self, String> {
        let (w, h) = (scene.settings.width, scene.settings.height);
        let k = scene.settings.fragments;
        let tile = tile.unwrap_or(if crate::render::tiled::needs_tiles(&live.ctx, w, h, k) {
            crate::render::tiled::tile_side(&live.ctx, k)
        } else {
            w.max(h)
        });
        let tiles = Tile::cover(w, h, tile);
        let mut settings = scene.settings.clone();
        settings.width = tiles[0].size[0];
        settings.height = tiles[0].size[1];
        let mut renderer = Renderer::new(
            &live.ctx,
            settings,
            luts,
            &scene.hair,
            &scene.sigma_a,
            &scene.look,
            &scene.environment.lights.lights,
            &scene.camera,
        )
        .map_err(|e| e.to_string())?;
        renderer.set_unit_budget(crate::live::settings::unit_budget(&live.ctx));
        renderer.set_occluder(&live.ctx, scene.occluder.as_ref());
        renderer
            .set_camera_tile(&live.ctx, &scene.camera, tiles[0])
            .map_err(|e| e.to_string())?;
        // The PNG shows the session's background: the live scene's map (made for its unturned lights),
        // turned by the session's yaw. The EXR keeps the hair alone with its alpha.
        if png.is_some() && session.render.background == Background::Environment {
            let map = live.background_map();
            let yaw = map.yaw + session.env_yaw.to_radians() as f32;
            renderer.set_background(&live.ctx, Some(map), yaw);
        }
        Ok(Self {
            exr,
            png,
            session: session.clone(),
            scene,
            renderer,
            tiles,
            current: 0,
            frame: None,
            reading: None,
            writing: None,
            started: Instant::now(),
            fraction: 0.0,
            wake,
        })
    }

    /// One frame of the export; returns the final message when done.
    pub fn poll(&mut self, gpu: Option<&GpuContext>) -> Option<(Level, String)> {
        if let Some(job) = &mut self.writing {
            return job.poll().map(|r| match r.and_then(|r| r) {
                Ok(m) => (Level::Info, m),
                Err(e) => (Level::Error, e),
            });
        }
        let Some(ctx) = gpu else {
            return Some((Level::Error, "export: the GPU went away".into()));
        };
        let n = self.tiles.len();
        let part = if let Some(r) = &self.reading {
            match r.poll(ctx)? {
                Ok(f) => f,
                Err(e) => return Some((Level::Error, format!("export: {e}"))),
            }
        } else {
            let progress = match self.renderer.refine(ctx) {
                Ok(p) => p,
                Err(e) => return Some((Level::Error, format!("export: {e}"))),
            };
            self.fraction = (self.current as f32 + progress.fraction) / n as f32;
            if progress.converged {
                self.reading = Some(self.renderer.start_read_image(ctx));
            }
            return None;
        };
        self.reading = None;
        let s = &self.scene.settings;
        let full = self.frame.get_or_insert_with(|| {
            empty_frame(s.width, s.height, part.samples, part.components.len())
        });
        paste(full, &self.tiles[self.current], &part);
        self.current += 1;
        if self.current < n {
            let t = self.tiles[self.current];
            if let Err(e) = self.renderer.set_camera_tile(ctx, &self.scene.camera, t) {
                return Some((Level::Error, format!("export: {e}")));
            }
            return None;
        }
        let Some(frame) = self.frame.take() else {
            return Some((Level::Error, "export: no tiles".into()));
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
        let background = self.session.render.background;
        let seconds = self.started.elapsed().as_secs_f64();
        let wake = self.wake.clone();
        self.writing = Some(Job::spawn(
            "writing the still",
            move || wake(),
            move |_| {
                frame
                    .write_exr(&exr, &attributes, true, None)
                    .map_err(|e| e.to_string())?;
                if let Some(p) = &png {
                    frame.write_png(p, background).map_err(|e| e.to_string())?;
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

    /// The files are being written (too late to cancel).
    pub fn writing(&self) -> bool {
        self.writing.is_some()
    }

    /// The EXR path with `.png` for the preview.
    pub fn preview_path(exr: &std::path::Path) -> PathBuf {
        exr.with_extension("png")
    }
}

/// The exports under way: a still (refined in UI frames) and a painted hair (written on a worker).
#[derive(Default)]
pub struct Exports {
    still: Option<ExportJob>,
    hair: Option<Job<Result<String, String>>>,
}

impl Exports {
    /// The still under way: its progress and whether its files are being written.
    pub fn still_progress(&self) -> Option<(f32, bool)> {
        self.still.as_ref().map(|e| (e.fraction, e.writing()))
    }

    pub fn exporting_still(&self) -> bool {
        self.still.is_some()
    }

    /// Stops the still (nothing is written; a device that went away takes it too).
    pub fn cancel_still(&mut self) {
        self.still = None;
    }

    /// Starts exporting the session's still to `exr` (and a PNG preview beside it), in tiles of at
    /// most `tile` pixels a side (None: only when the image needs them).
    pub fn start_still(
        &mut self,
        live: &LiveDriver,
        luts: &crate::scattering::lut::Luts,
        session: &Session,
        exr: PathBuf,
        tile: Option<u32>,
        wake: Wake,
    ) -> Result<(), String> {
        if self.still.is_some() {
            return Err("an export is running: cancel it or wait for it first".into());
        }
        let png = Some(ExportJob::preview_path(&exr));
        let job = ExportJob::start(live, luts, session, exr, png, wake, tile)
            .map_err(|e| format!("export: {e}"))?;
        self.still = Some(job);
        Ok(())
    }

    /// Writes the hair with its look and paint to `out` (.usda or .hair) on a worker.
    pub fn start_hair(&mut self, live: &LiveDriver, session: &Session, out: PathBuf, wake: Wake) {
        let (hair, sigma_a) = (live.hair.clone(), live.sigma_a.clone());
        let look = session.look;
        let scale = look.thickness_scale;
        self.hair = Some(Job::spawn(
            "exporting the hair",
            move || wake(),
            move |_| {
                let mut h = (*hair).clone();
                h.transform(|p| p, scale);
                crate::session::export_hair::write_painted_hair(&h, &sigma_a, &look, &out)
                    .map(|_| format!("exported {}", out.display()))
            },
        ));
    }

    /// Once a frame: advances the still and collects what finished. Returns the messages to show
    /// and whether the still still runs (its renderer refines in UI frames: poll again soon).
    pub fn poll(&mut self, gpu: Option<&GpuContext>) -> (Vec<(Level, String)>, bool) {
        let mut done = Vec::new();
        if let Some(job) = &mut self.still
            && let Some(msg) = job.poll(gpu)
        {
            done.push(msg);
            self.still = None;
        }
        if let Some(r) = self.hair.as_mut().and_then(|j| j.poll()) {
            self.hair = None;
            done.push(match r.and_then(|r| r) {
                Ok(m) => (Level::Info, m),
                Err(e) => (Level::Error, e),
            });
        }
        (done, self.still.is_some())
    }
}
