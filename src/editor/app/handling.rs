//! Where the app handles what the panels, tools, shortcuts and jobs ask of it: the one place the
//! document, the viewport and the jobs change (as rerun's `command_handling.rs`). Edits go through
//! the document's history, so undo, autosave and the tests replay the same values.

use super::EditorApp;
use crate::editor::command::{AppCommand, Dialog};
use crate::editor::device::{DeviceEvent, Restart};
use crate::editor::loading::Loaded;
use crate::editor::messages::Level;
use crate::paint::PaintDelta;
use crate::render::Camera;
use crate::session::{Edit, OccluderOptions, Session, ViewCamera};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A device lost this soon after a start that recovered from one is not restarted again (no loop).
const RELAUNCH_GUARD: Duration = Duration::from_secs(60);

/// How often the UI wakes to poll an export while it runs (its renderer is refined in UI frames).
const REFINE_POLL: Duration = Duration::from_millis(30);

impl EditorApp {
    /// Handles one command.
    pub fn handle(&mut self, command: AppCommand) {
        match command {
            AppCommand::Edit { edit, gesture } => self.perform(edit, gesture),
            AppCommand::Undo => self.undo(),
            AppCommand::Redo => self.redo(),
            AppCommand::Dialog(d) => {
                if let Some(c) = d.run() {
                    self.handle(c);
                }
            }
            AppCommand::OpenSession(p) => self.open_session(&p),
            AppCommand::Save => match self.doc.path().map(Path::to_path_buf) {
                Some(p) => self.save_session(&p),
                None => self.handle(AppCommand::Dialog(Dialog::SaveAs)),
            },
            AppCommand::SaveSession(p) => self.save_session(&p),
            AppCommand::OpenHair(p) => self.loader.open_hair(p),
            AppCommand::OpenOccluder(p) => {
                let normalization = self
                    .viewport
                    .live()
                    .map_or(crate::session::assemble::GENERATOR_SPACE, |l| {
                        l.lock().normalization
                    });
                self.loader.open_occluder(p, normalization);
            }
            AppCommand::LoadEnvironment { path, lights } => {
                self.loader.load_environment(path, lights)
            }
            AppCommand::ExportStill { exr, tile } => self.export_still(exr, tile),
            AppCommand::ExportHair(out) => match self.viewport.live() {
                Some(live) => self.exports.start_hair(
                    &live.lock(),
                    self.doc.session(),
                    out,
                    self.wake.clone(),
                ),
                None => self
                    .messages
                    .push(Level::Error, "export: the scene is still loading"),
            },
            AppCommand::CancelExport => {
                self.exports.cancel_still();
                self.messages.push(Level::Info, "export cancelled");
            }
            AppCommand::ReloadScene => self.load_scene(),
            AppCommand::FrameHair => self.frame_hair(),
            AppCommand::SetCamera(c) => self.set_camera(c),
            AppCommand::SetView(v) => self.viewport.set_view(v),
            AppCommand::ViewportLaidOut { rect, px } => self.viewport.laid_out(rect, px),
            AppCommand::Stroke(input) => self.tools.brush_mut().stroke_input(
                input,
                &mut self.doc,
                &self.viewport,
                &mut self.messages,
                &mut self.timing,
            ),
            AppCommand::EndStroke => self.end_stroke(),
            AppCommand::ClearPaint => {
                self.end_stroke();
                let s = self.doc.session();
                if s.paint_layer.is_some() || s.paint.is_some() {
                    self.perform(Edit::PaintLayer(Box::new((None, None))), false);
                }
            }
            AppCommand::Recover => {
                if let Some((file, path, session)) = self.recovery_offer.take() {
                    self.adopt_recovery(&file, path, session);
                    self.load_scene();
                    self.messages
                        .push(Level::Info, "recovered the unsaved session");
                }
            }
            AppCommand::DiscardRecovery => {
                if let Some((file, _, _)) = self.recovery_offer.take() {
                    crate::session::autosave::remove_recovery(&file);
                }
            }
            AppCommand::DismissErrors => self.messages.dismiss_errors(),
        }
    }

    /// Applies an edit as an undo step (`gesture`: part of a drag that continues).
    pub fn perform(&mut self, edit: Edit, gesture: bool) {
        self.doc.perform(edit, gesture);
    }

    pub fn undo(&mut self) {
        self.end_stroke();
        if let Some(e) = self.doc.undo() {
            self.applied_paint(&e);
        }
    }

    pub fn redo(&mut self) {
        self.end_stroke();
        if let Some(e) = self.doc.redo() {
            self.applied_paint(&e);
        }
    }

    fn end_stroke(&mut self) {
        self.tools
            .brush_mut()
            .end_stroke(&mut self.doc, &self.viewport, &mut self.messages);
    }

    /// Undo or redo applied `edit`: a paint delta's points go to the renderer alone.
    fn applied_paint(&mut self, edit: &Edit) {
        let (Edit::Paint(delta), Some(live)) = (edit, self.viewport.live()) else {
            return;
        };
        let PaintDelta { indices, .. } = delta.as_ref();
        let r = {
            let mut d = live.lock();
            d.paint_points(self.doc.session(), indices)
                .and_then(|_| d.paint_finished(self.doc.session()))
        };
        live.kick();
        if let Err(e) = r {
            self.messages.push(Level::Error, e.to_string());
        }
    }

    /// Loads the session's hair and environment and prepares the renderer's CPU work off the UI
    /// thread; the live scene is rebuilt when they arrive.
    pub fn load_scene(&mut self) {
        self.loader.load_scene(
            self.doc.session(),
            self.gpu.clone(),
            self.luts.clone(),
            self.viewport.render_size(),
        );
    }

    /// Opens a session file; on error the current session stays.
    pub fn open_session(&mut self, path: &Path) {
        let mut s = match Session::read(path) {
            Ok(s) => s,
            Err(e) => return self.messages.push(Level::Error, e.to_string()),
        };
        if let Err(e) = s.load_paint() {
            self.messages
                .push(Level::Warning, format!("{e}; the hair is shown unpainted"));
        }
        self.end_stroke();
        // The unsaved work stays in its recovery file (offered at the next start).
        match self.doc.keep_unsaved() {
            Ok(Some(kept)) => self.messages.push(
                Level::Warning,
                format!("the unsaved changes were kept in {}", kept.display()),
            ),
            Ok(None) => {}
            Err(e) => self.messages.push(Level::Warning, e.to_string()),
        }
        self.doc.replace(s, path);
        self.viewport.reset_camera();
        self.viewport.drop_live();
        self.loader.forget_failure();
        self.load_scene();
        self.remember(path);
        self.messages
            .push(Level::Info, format!("opened {}", path.display()));
    }

    /// Saves to `path` (atomically); the session is then unmodified.
    pub fn save_session(&mut self, path: &Path) {
        self.end_stroke();
        match self.doc.save(path) {
            Ok(()) => {
                self.remember(path);
                self.messages
                    .push(Level::Info, format!("saved {}", path.display()));
            }
            Err(e) => self.messages.push(Level::Error, e.to_string()),
        }
    }

    /// Loads a hair file on a worker; when it loads it becomes the session's hair (an edit), when
    /// it fails the error names the file and the scene stays.
    pub fn open_hair(&mut self, path: PathBuf) {
        self.handle(AppCommand::OpenHair(path));
    }

    /// Loads an environment file (fitting it when it is an image) on a worker and applies it as an
    /// edit when done; a failure names the file and changes nothing.
    pub fn load_environment(&mut self, path: PathBuf, lights: usize) {
        self.handle(AppCommand::LoadEnvironment { path, lights });
    }

    fn remember(&mut self, path: &Path) {
        if let Err(e) = self.recent.remember(path) {
            self.messages.push(Level::Warning, e);
        }
    }

    /// Takes over a recovery file's session (the prompt's Recover, or `edit --recover`).
    pub(super) fn adopt_recovery(&mut self, file: &Path, path: PathBuf, session: Session) {
        let kept = self.doc.adopt_recovery(file, path, session);
        self.viewport.reset_camera();
        self.viewport.drop_live();
        self.loader.forget_failure();
        if let Err(e) = kept {
            self.messages.push(Level::Warning, e.to_string());
        }
    }

    fn export_still(&mut self, exr: PathBuf, tile: Option<u32>) {
        if self.exports.exporting_still() {
            return self.messages.push(
                Level::Error,
                "an export is running: cancel it or wait for it first",
            );
        }
        let Some(live) = self.viewport.live() else {
            return self
                .messages
                .push(Level::Error, "export: the scene is still loading");
        };
        let started = self.exports.start_still(
            &live.lock(),
            &self.luts,
            self.doc.session(),
            exr,
            tile,
            self.wake.clone(),
        );
        if let Err(e) = started {
            self.messages.push(Level::Error, e);
        }
    }

    /// Frames the hair (Home): the session keeps "framed" (no target, no distance) and follows the
    /// hair.
    fn frame_hair(&mut self) {
        self.end_stroke();
        self.doc.unframe();
        if let Some(bounds) = self.viewport.bounds() {
            let c = self.viewport.resolve_camera(self.doc.session(), bounds);
            self.viewport.set_camera(c);
            let mut framed = self.doc.session().camera;
            framed.yaw = c.yaw;
            framed.pitch = c.pitch;
            self.doc.set_camera(framed);
        }
    }

    /// Moves the camera (not an edit; saved with the session). A stroke under way ends: its dabs
    /// were placed in the old view.
    fn set_camera(&mut self, c: Camera) {
        if self.viewport.camera() != Some(c) {
            self.end_stroke();
        }
        self.viewport.set_camera(c);
        self.doc.set_camera(ViewCamera::from_camera(&c));
    }

    /// A lost GPU device: reported, the viewport stops and the session goes to the recovery file
    /// (eframe owns the device; the editor cannot recreate it, a restart offers the recovery).
    pub(super) fn check_device(&mut self) {
        let why = match self.device.poll() {
            None => return,
            Some(DeviceEvent::Error(e)) => {
                return self.messages.push(Level::Error, format!("GPU error: {e}"));
            }
            Some(DeviceEvent::Lost(why)) => why,
        };
        self.exports.cancel_still();
        self.viewport.drop_live();
        self.gpu = None;
        let kept = match self.doc.closing(true) {
            Ok(()) => format!(
                "the session is kept in {}",
                self.doc.autosave().path.display()
            ),
            Err(e) => {
                return self.messages.push(
                    Level::Error,
                    format!(
                        "the GPU device was lost ({why}) and the session could not be kept: {e}"
                    ),
                );
            }
        };
        let looping = self.options.recover.is_some() && self.started.elapsed() < RELAUNCH_GUARD;
        let start = self.options.relaunch_on_device_loss && !looping;
        let recovery = self.doc.autosave().path.clone();
        match self.device.restart(&recovery, start) {
            Restart::Started => {
                self.messages.push(
                    Level::Info,
                    format!("the GPU device was lost ({why}); {kept} and a new editor opens it"),
                );
                self.ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            Restart::Failed(e) => self.messages.push(
                Level::Error,
                format!("the GPU device was lost ({why}); {kept}; restarting failed: {e}"),
            ),
            Restart::NotTried => self.messages.push(
                Level::Error,
                format!("the GPU device was lost ({why}); the viewport stopped, {kept}: save it and restart strandlight"),
            ),
        }
    }

    /// Polls the background jobs: scenes are installed, loaded files become edits, exports advance,
    /// the recovery file is written when due.
    pub(super) fn poll_jobs(&mut self) {
        // Scenes are installed once the viewport has been laid out (the renderer follows its size).
        if self.viewport.rect().is_some()
            && let Some((result, _)) = self.loader.poll_scene()
        {
            match result {
                // A scene built for a device lost since is not installed.
                Ok(Loaded::Scene { .. }) if self.gpu.is_none() => {}
                Ok(Loaded::Scene {
                    driver,
                    pictures,
                    warnings,
                }) => {
                    for w in warnings {
                        self.messages.push(Level::Warning, w);
                    }
                    self.viewport.install(
                        *driver,
                        pictures,
                        self.doc.session(),
                        self.started,
                        self.ctx.clone(),
                        &mut self.messages,
                    );
                }
                Ok(_) => {}
                Err(e) => self.messages.push(Level::Error, e),
            }
        }
        if let Some(result) = self.loader.poll_source() {
            self.loaded_source(result);
        }
        if self.exports.exporting_still() {
            self.ctx.request_repaint_after(REFINE_POLL);
        }
        let (done, _) = self.exports.poll(self.gpu.as_ref());
        for (level, text) in done {
            self.messages.push(level, text);
        }
        match self.doc.autosave_tick(&self.wake) {
            Ok(Some(due)) => self.ctx.request_repaint_after(due),
            Ok(None) => {}
            Err(e) => self.messages.push(Level::Warning, e.to_string()),
        }
    }

    /// A hair, head or environment file loaded: it becomes an edit. A failure leaves the session
    /// untouched.
    fn loaded_source(&mut self, result: Result<Loaded, String>) {
        match result {
            Ok(Loaded::Occluder { path }) => {
                let occluder = OccluderOptions {
                    show: true,
                    mesh: Some(path),
                    ..self.doc.session().occluder.clone()
                };
                self.perform(Edit::Occluder(Box::new(occluder)), false);
            }
            Ok(Loaded::Hair { source, restored }) => {
                self.perform(Edit::Hair(source), false);
                self.doc.unframe();
                if let Some(restored) = restored {
                    let (look, layer) = *restored;
                    self.perform(Edit::Look(Box::new(look)), false);
                    let layer = crate::paint::layer::SharedLayer::new(layer);
                    self.perform(Edit::PaintLayer(Box::new((Some(layer), None))), false);
                    self.messages.push(
                        Level::Info,
                        "restored the look and paint strandlight exported with this groom",
                    );
                }
            }
            Ok(Loaded::Environment {
                environment,
                pictures,
                source,
            }) => {
                self.perform(Edit::Environment(Box::new(source.clone())), false);
                let loading = self.loader.loading_scene();
                let session = self.doc.session();
                if let Some(live) = self.viewport.live_mut()
                    && !loading
                    && live.lock().sources.hair_source == session.hair
                {
                    live.set_environment(*environment, *pictures, source, session.env_yaw);
                }
            }
            Ok(Loaded::Scene { .. }) => {}
            Err(e) => self.messages.push(Level::Error, e),
        }
    }

    /// When the app closes: the recovery file is written if there are unsaved changes.
    pub fn closing(&mut self) {
        // A recovery still on offer belongs to an earlier run: leave it for the next start.
        if self.recovery_offer.is_some() || self.device.relaunching() {
            return;
        }
        if let Err(e) = self.doc.closing(false) {
            eprintln!("warning: {e}");
        }
    }
}
