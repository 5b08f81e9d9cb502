//! The editor's frame loop. The app owns the document, the viewport, the tools, the background
//! jobs and the messages, each a small struct of its own; once a frame it polls the jobs and the
//! device, reads the shortcuts, tells the live driver what changed, shows the panels with a
//! read-only [`PanelContext`], and handles the commands they sent ([`EditorApp::handle`], in
//! `app/handling.rs`), edits among them, in one place. The app's parts are private to it (and to
//! its handling, a child module).

mod handling;

use super::command::{AppCommand, DEFAULT_LIGHTS, Dialog};
use super::context::{JobsView, PanelContext};
use super::device::DeviceWatch;
use super::document::Document;
use super::export::Exports;
use super::live_scene::{LiveScene, ViewSettings};
use super::loading::Loader;
use super::messages::{Level, Messages};
use super::options::EditorOptions;
use super::panels;
use super::recent::RecentFiles;
use super::timing::FrameTiming;
use super::tools::{Tool, Tools};
use super::viewport::Viewport;
use crate::gpu::GpuContext;
use crate::jobs::Wake;
use crate::paint::Brush;
use crate::render::Camera;
use crate::scattering::lut::Luts;
use crate::session::autosave::{self, Autosave};
use crate::session::{History, Session};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

pub struct EditorApp {
    doc: Document,
    viewport: Viewport,
    tools: Tools,
    loader: Loader,
    exports: Exports,
    device: DeviceWatch,
    gpu: Option<GpuContext>,
    luts: Arc<Luts>,
    messages: Messages,
    recent: RecentFiles,
    /// A recovery file of an earlier run: the file, the session file it belonged to, the session.
    recovery_offer: Option<(PathBuf, PathBuf, Session)>,
    timing: FrameTiming,
    options: EditorOptions,
    started: Instant,
    ctx: egui::Context,
    /// Asks egui for a frame (what background jobs call when they are done).
    wake: Wake,
}

impl EditorApp {
    pub fn new(cc: &eframe::CreationContext<'_>, options: EditorOptions) -> Self {
        let gpu = cc.wgpu_render_state.as_ref().map(|rs| {
            GpuContext::from_parts(
                rs.instance.clone(),
                rs.adapter.clone(),
                rs.device.clone(),
                rs.queue.clone(),
            )
        });
        let egui_renderer = cc.wgpu_render_state.as_ref().map(|rs| rs.renderer.clone());
        install_fonts(&cc.egui_ctx);
        let mut messages = Messages::default();
        let (session, session_path) = options.first_session(&mut messages);
        if gpu.is_none() {
            messages.push(
                Level::Error,
                "eframe gave no wgpu device: the viewport cannot render",
            );
        }
        let state_dir = options
            .state_dir
            .clone()
            .unwrap_or_else(crate::session::io::state_dir);
        let autosave = Autosave::new(
            state_dir.clone(),
            session_path.as_deref(),
            options.instance.unwrap_or_else(std::process::id),
        );
        let recovery_offer = options
            .offer_recovery
            .then(|| autosave.recovery_found())
            .flatten();
        let ctx = cc.egui_ctx.clone();
        let wake: Wake = {
            let ctx = ctx.clone();
            Arc::new(move || ctx.request_repaint())
        };
        let view = gpu.as_ref().map_or_else(ViewSettings::default, |g| {
            ViewSettings::for_adapter(g.adapter.get_info().device_type)
        });
        let mut app = Self {
            doc: Document::new(session, session_path, autosave),
            viewport: Viewport::new(view, egui_renderer),
            tools: Tools::default(),
            loader: Loader::new(wake.clone()),
            exports: Exports::default(),
            device: gpu.as_ref().map_or_else(DeviceWatch::default, |g| {
                DeviceWatch::watch(g, wake.clone())
            }),
            gpu,
            luts: Arc::new(Luts::default_tables()),
            messages,
            recent: RecentFiles::read(state_dir),
            recovery_offer,
            timing: FrameTiming::default(),
            started: options.launched.unwrap_or_else(Instant::now),
            options,
            ctx,
            wake,
        };
        if let Some(file) = app.options.recover.clone() {
            match autosave::read_recovery(&file) {
                Ok((path, session, warning)) => {
                    app.adopt_recovery(&file, path, session);
                    app.messages.push(
                        Level::Info,
                        format!("reopened the session from {}", file.display()),
                    );
                    if let Some(w) = warning {
                        app.messages.push(Level::Warning, w);
                    }
                }
                Err(e) => app.messages.push(Level::Error, e.to_string()),
            }
        }
        app.load_scene();
        app
    }

    /// Keyboard shortcuts that act on the document.
    fn shortcuts(&mut self, ctx: &egui::Context) {
        use egui::{Key, KeyboardShortcut, Modifiers};
        let cmd = Modifiers::COMMAND;
        let cmd_shift = Modifiers::COMMAND | Modifiers::SHIFT;
        // Shift is ignored when matching (egui's logical matching): the Shift chords go first.
        let (redo, save_as, undo, redo_y, save, open, export) = ctx.input_mut(|i| {
            (
                i.consume_shortcut(&KeyboardShortcut::new(cmd_shift, Key::Z)),
                i.consume_shortcut(&KeyboardShortcut::new(cmd_shift, Key::S)),
                i.consume_shortcut(&KeyboardShortcut::new(cmd, Key::Z)),
                i.consume_shortcut(&KeyboardShortcut::new(cmd, Key::Y)),
                i.consume_shortcut(&KeyboardShortcut::new(cmd, Key::S)),
                i.consume_shortcut(&KeyboardShortcut::new(cmd, Key::O)),
                i.consume_shortcut(&KeyboardShortcut::new(cmd, Key::E)),
            )
        });
        let commands = [
            (redo || redo_y, AppCommand::Redo),
            (undo && !(redo || redo_y), AppCommand::Undo),
            (save_as, AppCommand::Dialog(Dialog::SaveAs)),
            (save && !save_as, AppCommand::Save),
            (open, AppCommand::Dialog(Dialog::OpenSession)),
            (export, AppCommand::Dialog(Dialog::ExportStill)),
        ];
        for (_, c) in commands.into_iter().filter(|(on, _)| *on) {
            self.handle(c);
        }
    }

    /// Files dropped on the window: hair, environments and sessions, by extension.
    fn dropped_files(&mut self, ctx: &egui::Context) {
        let files: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        for path in files {
            let ext = path
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase())
                .unwrap_or_default();
            let command = match ext.as_str() {
                "hair" | "tfx" | "gltf" | "glb" | "usd" | "usda" | "usdc" | "usdz" | "abc" => {
                    AppCommand::OpenHair(path)
                }
                "hdr" | "exr" | "json" => AppCommand::LoadEnvironment {
                    path,
                    lights: DEFAULT_LIGHTS,
                },
                "slsession" => AppCommand::OpenSession(path),
                _ => {
                    self.messages.push(
                        Level::Error,
                        format!(
                            "{}: not a hair file (.hair, .tfx, .gltf, .glb, USD, .abc), an environment (.hdr, .exr, .srbf.json) or a session (.slsession)",
                            path.display()
                        ),
                    );
                    continue;
                }
            };
            self.handle(command);
        }
    }

    /// The viewport's per-frame work: a load when the session needs another scene, then the
    /// driver told what changed. Nothing here waits for the GPU.
    fn update_viewport(&mut self) {
        if self.gpu.is_none() {
            return;
        }
        let session = self.doc.session();
        if self.viewport.needs_rebuild(session) {
            if self.loader.should_load(session) {
                self.load_scene();
            }
            if !self.viewport.shows_sources_of(self.doc.session()) {
                return;
            }
        }
        let picking = self.tools.active() == Tool::Brush;
        self.viewport
            .sync(self.doc.session(), picking, &mut self.messages);
        if self.options.log_times
            && let Some(live) = self.viewport.live()
        {
            self.timing.log_times(&live.lock());
        }
    }

    /// The panels for one frame, then the commands they sent.
    fn panels(&mut self, ui: &mut egui::Ui) {
        let mut ctx = PanelContext::new(
            self.doc.session(),
            self.doc.history(),
            self.doc.path(),
            self.doc.modified(),
            self.recent.list(),
            &self.viewport,
            self.gpu.as_ref(),
            &self.messages,
        );
        ctx.jobs = JobsView {
            loading: self.loader.scene_label(),
            export: self.exports.still_progress(),
        };
        ctx.frame_ms = self.timing.smoothed_ms();
        ctx.recovery_offer = self.recovery_offer.as_ref().map(|(_, p, _)| p.as_path());
        panels::show(&ctx, &mut self.tools, ui);
        for command in ctx.into_commands() {
            self.handle(command);
        }
    }
}

/// The views the tests and the benchmark read (the app's parts are private to the editor).
impl EditorApp {
    pub fn session(&self) -> &Session {
        self.doc.session()
    }

    pub fn session_path(&self) -> Option<&Path> {
        self.doc.path()
    }

    pub fn history(&self) -> &History {
        self.doc.history()
    }

    pub fn modified(&self) -> bool {
        self.doc.modified()
    }

    pub fn autosave(&self) -> &Autosave {
        self.doc.autosave()
    }

    pub fn autosave_mut(&mut self) -> &mut Autosave {
        self.doc.autosave_mut()
    }

    pub fn live(&self) -> Option<&LiveScene> {
        self.viewport.live()
    }

    pub fn gpu(&self) -> Option<&GpuContext> {
        self.gpu.as_ref()
    }

    pub fn camera(&self) -> Option<Camera> {
        self.viewport.camera()
    }

    pub fn view(&self) -> ViewSettings {
        self.viewport.view()
    }

    pub fn viewport_rect(&self) -> Option<egui::Rect> {
        self.viewport.rect()
    }

    pub fn messages(&self) -> &Messages {
        &self.messages
    }

    pub fn tool(&self) -> Tool {
        self.tools.active()
    }

    pub fn brush(&self) -> &Brush {
        self.tools.brush().settings()
    }

    pub fn set_brush(&mut self, brush: Brush) {
        *self.tools.brush_mut().settings_mut() = brush;
    }

    pub fn brush_stats(&self) -> super::tools::brush::BrushStats {
        self.tools.brush().stats()
    }

    /// The brush radius in render pixels (the panel's radius is in screen points).
    pub fn brush_radius_render_px(&self) -> f32 {
        self.tools.brush().radius_render_px(&self.viewport)
    }

    /// A scene or a hair, head or environment file is loading.
    pub fn loading(&self) -> bool {
        self.loader.loading_scene() || self.loader.loading_source()
    }

    pub fn loading_scene(&self) -> bool {
        self.loader.loading_scene()
    }

    pub fn exporting(&self) -> bool {
        self.exports.exporting_still()
    }

    pub fn recovery_offered(&self) -> bool {
        self.recovery_offer.is_some()
    }

    /// After a lost device: the arguments of the editor that takes over (`edit --recover FILE`).
    pub fn relaunch(&self) -> Option<&[std::ffi::OsString]> {
        self.device.relaunch()
    }

    /// UI frames whose cost was measured (at most the number kept).
    pub fn frames_measured(&self) -> usize {
        self.timing.frames_measured()
    }

    /// How long ago the last refinement converged (tests and the status bar).
    pub fn converged(&self) -> Option<Duration> {
        self.viewport.live().and_then(|l| {
            let l = l.lock();
            l.clock
                .progress
                .filter(|p| p.converged && !l.tables_pending())
                .and(l.clock.converged_in)
        })
    }
}

/// egui's proportional font lacks a few symbols the panels use (the reset arrow): the bundled
/// monospace font covers them as a fallback.
fn install_fonts(ctx: &egui::Context) {
    let mut fonts = egui::FontDefinitions::default();
    if let Some(list) = fonts.families.get_mut(&egui::FontFamily::Proportional)
        && fonts.font_data.contains_key("Hack")
        && !list.iter().any(|f| f == "Hack")
    {
        list.push("Hack".into());
    }
    ctx.set_fonts(fonts);
}

impl eframe::App for EditorApp {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        self.timing.start();
        self.check_device();
        self.poll_jobs();
        self.dropped_files(ctx);
        self.shortcuts(ctx);
        if !ctx.input(|i| i.pointer.any_down()) {
            self.doc.end_gesture();
        }
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        // The renderer's step first (with last frame's viewport size), so this frame paints the
        // image and the progress it produced.
        self.update_viewport();
        self.panels(ui);
        self.timing.end();
    }

    fn on_exit(&mut self) {
        self.closing();
    }
}
