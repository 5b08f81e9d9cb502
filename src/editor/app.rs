//! The editor's state and frame loop: the document (session, path, history), the editor state
//! (camera, view, messages), the live scene and the background jobs. Panels read a per-frame view of
//! this and return [`Edit`]s; [`EditorApp::perform`] is the one place edits are applied.

use super::export::ExportJob;
use super::live::{LiveScene, ViewSettings};
use super::navigation;
use super::panels;
use crate::gpu::GpuContext;
use crate::live::LiveDriver;
use crate::jobs::{Job, Wake};
use crate::render::Camera;
use crate::render::scene::Environment;
use crate::scattering::lut::Luts;
use crate::session::assemble::{load_environment_source, load_hair_source};
use crate::session::autosave::{self, Autosave};
use crate::session::{Edit, EnvironmentSource, HairSource, History, Session, ViewCamera};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What started the editor.
#[derive(Clone, Debug, Default)]
pub struct EditorOptions {
    /// A session to open.
    pub session_path: Option<PathBuf>,
    /// The session to start from when no file is given (the default scene, or `--hair` / `--env`).
    pub session: Option<Session>,
    /// Offer the recovery file when one is found (off in tests that do not want the prompt).
    pub offer_recovery: bool,
    /// Where recovery files go (default [`crate::session::io::state_dir`]).
    pub state_dir: Option<PathBuf>,
    /// Names this editor's recovery file (default: the process id; tests play several editors).
    pub instance: Option<u32>,
    /// A recovery file to open at once (`edit --recover`: the restart after a lost GPU device).
    pub recover: Option<PathBuf>,
    /// After a lost GPU device, start a new editor on the recovery file and close this one (off in
    /// tests, which read [`EditorApp::relaunch`] instead).
    pub relaunch_on_device_loss: bool,
    /// When the process started (the first scene's times count from it; default: the app's
    /// creation).
    pub launched: Option<Instant>,
    /// Print each change's times to stderr (`edit --log-times`).
    pub log_times: bool,
}

/// A device lost this soon after a start that recovered from one is not restarted again (no loop).
const RELAUNCH_GUARD: Duration = Duration::from_secs(60);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    Info,
    Warning,
    Error,
}

#[derive(Clone, Debug)]
pub struct Message {
    pub level: Level,
    pub text: String,
    pub at: Instant,
}

/// What a load job brings back.
pub enum Loaded {
    /// A new scene, its renderer built on the worker too (pipelines compile there: ~1.5 s on
    /// lavapipe that the UI thread does not wait for); its render thread starts when it is installed.
    Scene {
        driver: Box<LiveDriver>,
        pictures: Arc<super::env_preview::EnvPictures>,
        warnings: Vec<String>,
    },
    /// A hair file that loaded: it becomes the session's hair (an edit; the scene then reloads).
    Hair {
        source: HairSource,
        /// The look and paint a groom strandlight exported carries back.
        restored: Option<Box<(crate::session::Look, crate::paint::layer::PaintLayer)>>,
    },
    /// An occluder mesh that loaded: it becomes the session's head (an edit; the scene reloads).
    Occluder { path: PathBuf },
    /// A new environment; applied as an edit when it arrives.
    Environment {
        environment: Box<Environment>,
        pictures: Box<super::env_preview::EnvPictures>,
        source: EnvironmentSource,
    },
}

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

pub struct EditorApp {
    pub session: Session,
    pub session_path: Option<PathBuf>,
    pub history: History,
    /// The session as last saved or opened ("modified" compares against it).
    pub saved: Session,
    pub camera: Option<Camera>,
    pub view: ViewSettings,
    pub live: Option<LiveScene>,
    pub messages: Vec<Message>,
    pub gpu: Option<GpuContext>,
    egui_renderer: Option<Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>>,
    luts: Arc<Luts>,
    /// The scene being loaded (hair, environment, renderer preparation).
    pub loading: Option<Job<Result<Loaded, String>>>,
    /// The session a scene load was started for (a newer request supersedes it).
    loading_for: Option<Session>,
    /// A hair or environment file being loaded for an edit.
    pub source_job: Option<Job<Result<Loaded, String>>>,
    /// The scene whose build failed (not retried until the session's sources change).
    failed: Option<SceneKey>,
    pub autosave: Autosave,
    /// A recovery file of an earlier run: the file, the session file it belonged to, the session.
    pub recovery_offer: Option<(PathBuf, PathBuf, Session)>,
    /// The environment panel's pictures (rebuilt when the environment changes).
    pub env_preview: Option<super::env_preview::EnvPreview>,
    /// Sessions opened or saved lately, newest first (kept in the state folder).
    pub recent: Vec<PathBuf>,
    state_dir: PathBuf,
    pub export: Option<ExportJob>,
    /// The active tool, the brush's settings, the stroke under way and what the brush measured.
    pub tool: super::brush_tool::Tool,
    pub brush: crate::paint::Brush,
    pub(super) stroke: Option<super::brush_tool::StrokeState>,
    pub brush_stats: super::brush_tool::BrushStats,
    /// F / Shift+F held: the pointer's distance sets the radius or the strength.
    pub radius_drag: Option<super::brush_tool::RadiusDrag>,
    /// The click that confirmed a radius adjustment is held: the brush ignores it until released.
    pub brush_idle_until_release: bool,
    /// A hair export being written (its message when done).
    pub hair_export: Option<Job<Result<String, String>>>,
    /// The viewport's size in physical pixels and its rectangle in points (last frame).
    pub viewport_px: [u32; 2],
    pub viewport_rect: Option<egui::Rect>,
    /// The UI's own work per frame (its logic and panels, not the render thread's): smoothed, and
    /// the last frames' costs (the status bar and the editor's measurements read them).
    pub frame_ms: f32,
    pub frame_costs: std::collections::VecDeque<f32>,
    /// The time from one frame's start to the next's, and when the last began: where frames run
    /// back to back (continuous input) this is the whole frame, egui's painting and presenting
    /// included.
    pub frame_intervals: std::collections::VecDeque<f32>,
    last_frame_start: Option<Instant>,
    /// When this frame's work started.
    pub(super) frame_started: Option<Instant>,
    /// A dab not yet seen on screen: when its frame began, and the driver's restart it made
    /// (`--log-times` reports its latency).
    pub(super) pending_dab: Option<(Instant, u64)>,
    /// The viewport's render thread was found not running (reported once).
    render_thread_lost: bool,
    /// The first scene is still to come (its times count from the launch).
    first_scene: bool,
    /// Set by wgpu when the device is lost (reason and message).
    device_lost: Arc<std::sync::Mutex<Option<String>>>,
    /// The first GPU validation error since the last report (wgpu's default handler panics: a
    /// resource made on a device that is being lost, say, must not take the session down).
    gpu_error: Arc<std::sync::Mutex<Option<String>>>,
    /// A GPU error was shown (one message, not one per frame).
    gpu_error_shown: bool,
    /// After a lost device: the arguments of the editor that takes over (`edit --recover FILE`).
    pub relaunch: Option<Vec<std::ffi::OsString>>,
    /// This editor is closing for its replacement: the recovery file stays as it is.
    relaunching: bool,
    options: EditorOptions,
    started: Instant,
    /// The driver's restart and convergence time last logged (`--log-times`), and the UI frames
    /// since.
    logged: Option<(u64, Duration)>,
    frames_since_change: usize,
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
        let mut messages = Vec::new();
        let mut session_path = None;
        let mut session = options.session.clone().unwrap_or_default();
        if let Some(path) = &options.session_path {
            match Session::read(path) {
                Ok(mut s) => {
                    if let Err(e) = s.load_paint() {
                        messages.push(Message {
                            level: Level::Warning,
                            text: format!("{e}; the hair is shown unpainted"),
                            at: Instant::now(),
                        });
                    }
                    session = s;
                    session_path = Some(path.clone());
                }
                Err(e) => messages.push(Message {
                    level: Level::Error,
                    text: e.to_string(),
                    at: Instant::now(),
                }),
            }
        }
        if gpu.is_none() {
            messages.push(Message {
                level: Level::Error,
                text: "eframe gave no wgpu device: the viewport cannot render".into(),
                at: Instant::now(),
            });
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
        let recent = read_recent(&state_dir);
        let recovery_offer = if options.offer_recovery {
            autosave.recovery_found()
        } else {
            None
        };
        let mut app = Self {
            saved: session.clone(),
            session,
            session_path,
            history: History::default(),
            camera: None,
            view: ViewSettings::default(),
            live: None,
            messages,
            gpu,
            egui_renderer,
            luts: Arc::new(Luts::default_tables()),
            loading: None,
            loading_for: None,
            source_job: None,
            failed: None,
            autosave,
            recovery_offer,
            recent,
            state_dir,
            env_preview: None,
            export: None,
            tool: Default::default(),
            brush: Default::default(),
            stroke: None,
            brush_stats: Default::default(),
            radius_drag: None,
            brush_idle_until_release: false,
            hair_export: None,
            viewport_px: [640, 400],
            viewport_rect: None,
            frame_ms: 0.0,
            frame_costs: Default::default(),
            frame_intervals: Default::default(),
            last_frame_start: None,
            frame_started: None,
            pending_dab: None,
            first_scene: true,
            render_thread_lost: false,
            device_lost: Arc::new(std::sync::Mutex::new(None)),
            gpu_error: Arc::new(std::sync::Mutex::new(None)),
            gpu_error_shown: false,
            relaunch: None,
            relaunching: false,
            options: options.clone(),
            started: options.launched.unwrap_or_else(Instant::now),
            logged: None,
            frames_since_change: 0,
            ctx: cc.egui_ctx.clone(),
            wake: {
                let ctx = cc.egui_ctx.clone();
                Arc::new(move || ctx.request_repaint())
            },
        };
        if let Some(file) = &options.recover {
            match autosave::read_recovery(file) {
                Ok((path, session, warning)) => {
                    app.adopt_recovery(file, path, session);
                    app.message(
                        Level::Info,
                        format!("reopened the session from {}", file.display()),
                    );
                    if let Some(w) = warning {
                        app.message(Level::Warning, w);
                    }
                }
                Err(e) => app.message(Level::Error, e.to_string()),
            }
        }
        if let Some(g) = &app.gpu {
            let (flag, wake) = (app.device_lost.clone(), app.ctx.clone());
            g.device.set_device_lost_callback(move |reason, message| {
                if let Ok(mut f) = flag.lock() {
                    *f = Some(format!("{reason:?}: {message}"));
                }
                wake.request_repaint();
            });
            let (first, wake) = (app.gpu_error.clone(), app.ctx.clone());
            g.device
                .on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                    if let Ok(mut f) = first.lock()
                        && f.is_none()
                    {
                        *f = Some(e.to_string());
                    }
                    wake.request_repaint();
                }));
        }
        if let Some(g) = &app.gpu {
            app.view = ViewSettings::for_adapter(g.adapter.get_info().device_type);
        }
        app.load_scene();
        app
    }

    /// A lost GPU device: reported, the viewport stops and the session goes to the recovery file
    /// (eframe owns the device; the editor cannot recreate it, a restart offers the recovery).
    fn check_device(&mut self) {
        let lost = self.device_lost.lock().ok().and_then(|mut f| f.take());
        let error = self.gpu_error.lock().ok().and_then(|mut f| f.take());
        let Some(why) = lost else {
            if let Some(e) = error
                && !self.gpu_error_shown
            {
                self.gpu_error_shown = true;
                self.message(Level::Error, format!("GPU error: {e}"));
            }
            return;
        };
        self.export = None;
        self.drop_live();
        self.gpu = None;
        let kept = match self.autosave.on_exit(&self.session.clone(), true) {
            Ok(()) => format!("the session is kept in {}", self.autosave.path.display()),
            Err(e) => {
                self.message(
                    Level::Error,
                    format!(
                        "the GPU device was lost ({why}) and the session could not be kept: {e}"
                    ),
                );
                return;
            }
        };
        // eframe owns the device and cannot replace it (egui draws with it too): a new editor on a
        // new device takes the session over, unless this one is itself such a restart that lost
        // its device at once.
        let args: Vec<std::ffi::OsString> = vec![
            "edit".into(),
            "--recover".into(),
            self.autosave.path.clone().into(),
        ];
        let looping = self.options.recover.is_some() && self.started.elapsed() < RELAUNCH_GUARD;
        self.relaunch = Some(args.clone());
        if self.options.relaunch_on_device_loss && !looping {
            let spawned = std::env::current_exe()
                .and_then(|exe| std::process::Command::new(exe).args(&args).spawn());
            match spawned {
                Ok(_) => {
                    self.relaunching = true;
                    self.message(
                        Level::Info,
                        format!(
                            "the GPU device was lost ({why}); {kept} and a new editor opens it"
                        ),
                    );
                    self.ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                    return;
                }
                Err(e) => self.message(
                    Level::Error,
                    format!("the GPU device was lost ({why}); {kept}; restarting failed: {e}"),
                ),
            }
            return;
        }
        self.message(
            Level::Error,
            format!("the GPU device was lost ({why}); the viewport stopped, {kept}: save it and restart strandlight"),
        );
    }

    /// Takes over a recovery file's session (the prompt's Recover, or `edit --recover`): the
    /// session file it belongs to becomes this editor's, and the work is kept in this editor's own
    /// recovery file before the old one is removed.
    pub fn adopt_recovery(&mut self, file: &Path, path: PathBuf, session: Session) {
        self.session_path = (!path.as_os_str().is_empty()).then_some(path);
        // Unmodified means equal to the file it belongs to, as it is on disk now.
        self.saved = self
            .session_path
            .as_deref()
            .and_then(|p| Session::read(p).ok())
            .map(|mut s| {
                let _ = s.load_paint();
                s
            })
            .unwrap_or_default();
        self.session = session;
        self.autosave.set_session_path(self.session_path.as_deref());
        self.history.clear();
        self.camera = None;
        self.drop_live();
        self.failed = None;
        self.autosave.changed();
        if let Err(e) = self.autosave.on_exit(&self.session.clone(), true) {
            self.message(Level::Warning, e.to_string());
        } else if file != self.autosave.path {
            autosave::remove_recovery(file);
        }
    }

    pub fn luts(&self) -> &Luts {
        &self.luts
    }

    pub fn egui_ctx(&self) -> egui::Context {
        self.ctx.clone()
    }

    pub fn message(&mut self, level: Level, text: impl Into<String>) {
        let text = text.into();
        match level {
            Level::Error => eprintln!("error: {text}"),
            Level::Warning => eprintln!("warning: {text}"),
            Level::Info => {}
        }
        self.messages.push(Message {
            level,
            text,
            at: Instant::now(),
        });
        if self.messages.len() > 50 {
            self.messages.remove(0);
        }
    }

    /// Whether the session differs from the file it was opened from or saved to.
    pub fn modified(&self) -> bool {
        self.session != self.saved
    }

    /// Applies an edit as an undo step (`gesture`: part of a drag that continues).
    pub fn perform(&mut self, edit: Edit, gesture: bool) {
        if self.history.perform(&mut self.session, edit, gesture) {
            self.autosave.changed();
        }
    }

    pub fn undo(&mut self) {
        self.end_stroke();
        if let Some(e) = self.history.undo(&mut self.session) {
            self.applied_paint(&e);
            self.autosave.changed();
        }
    }

    pub fn redo(&mut self) {
        self.end_stroke();
        if let Some(e) = self.history.redo(&mut self.session) {
            self.applied_paint(&e);
            self.autosave.changed();
        }
    }

    /// Loads the session's hair and environment and prepares the renderer's CPU work off the UI
    /// thread; the live scene is rebuilt when they arrive.
    pub fn load_scene(&mut self) {
        // A load this one supersedes stops before it builds a renderer.
        if let Some(old) = self.loading.take() {
            old.cancel();
        }
        let session = self.session.clone();
        let ctx = self.ctx.clone();
        let (gpu, luts) = (self.gpu.clone(), self.luts.clone());
        let (w, h) = self.render_size();
        self.loading_for = Some(session.clone());
        self.loading = Some(Job::spawn(
            "loading the scene",
            move || ctx.request_repaint(),
            move |cancelled| {
                let gpu = gpu.ok_or("no GPU adapter")?;
                let (driver, warnings) =
                    crate::live::load::open(gpu, &luts, &session, (w, h), cancelled)?;
                let pictures = Arc::new(super::env_preview::pictures(
                    &driver.environment,
                    driver.background_map().clone(),
                ));
                Ok(Loaded::Scene {
                    driver: Box::new(driver),
                    pictures,
                    warnings,
                })
            },
        ));
    }

    /// Loads an environment file (fitting it when it is an image) on a worker and applies it as an
    /// edit when done; a failure names the file and changes nothing.
    pub fn load_environment(&mut self, path: PathBuf, lights: usize) {
        let ctx = self.ctx.clone();
        self.source_job = Some(Job::spawn(
            format!("loading {}", path.display()),
            move || ctx.request_repaint(),
            move |_| {
                let blake3 = crate::session::assemble::file_blake3(&path).ok();
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
                    pictures: Box::new(super::env_preview::pictures(
                        &environment,
                        Arc::new(crate::render::background::BackgroundMap::from_environment(
                            &environment,
                        )),
                    )),
                    environment: Box::new(environment),
                    source,
                })
            },
        ));
    }

    /// Loads a hair file on a worker; when it loads it becomes the session's hair (an edit), when it
    /// fails the error names the file and the scene stays.
    pub fn open_hair(&mut self, path: PathBuf) {
        let ctx = self.ctx.clone();
        self.source_job = Some(Job::spawn(
            format!("loading {}", path.display()),
            move || ctx.request_repaint(),
            move |_| {
                let source = HairSource::File {
                    blake3: crate::session::assemble::file_blake3(&path).ok(),
                    path,
                    prim: None,
                    time: None,
                };
                let loaded = load_hair_source(&source).map_err(|e| e.to_string())?;
                let restored = crate::session::assemble::exported_look_and_paint(&loaded);
                Ok(Loaded::Hair {
                    source,
                    restored: restored.map(Box::new),
                })
            },
        ));
    }

    /// Loads an occluder mesh (.obj, .gltf, .glb) on a worker, in the hair's space; when it loads it
    /// becomes the session's head (an edit), when it fails the error names the file and nothing changes.
    pub fn open_occluder(&mut self, path: PathBuf) {
        let ctx = self.ctx.clone();
        let normalization = self
            .live
            .as_ref()
            .map_or(crate::session::assemble::GENERATOR_SPACE, |l| {
                l.lock().normalization
            });
        self.source_job = Some(Job::spawn(
            format!("loading {}", path.display()),
            move || ctx.request_repaint(),
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
            match ext.as_str() {
                "hair" | "tfx" | "gltf" | "glb" | "usd" | "usda" | "usdc" | "usdz" | "abc" => {
                    self.open_hair(path)
                }
                "hdr" | "exr" | "json" => self.load_environment(path, 40),
                "slsession" => self.open_session(&path),
                _ => self.message(
                    Level::Error,
                    format!(
                        "{}: not a hair file (.hair, .tfx, .gltf, .glb, USD, .abc), an environment (.hdr, .exr, .srbf.json) or a session (.slsession)",
                        path.display()
                    ),
                ),
            }
        }
    }

    /// Opens a session file; on error the current session stays.
    pub fn open_session(&mut self, path: &Path) {
        match Session::read(path) {
            Ok(mut s) => {
                if let Err(e) = s.load_paint() {
                    self.message(Level::Warning, format!("{e}; the hair is shown unpainted"));
                }
                self.end_stroke();
                if self.modified() {
                    // The unsaved work stays in its recovery file (offered at the next start).
                    if let Err(e) = self.autosave.on_exit(&self.session, true) {
                        self.message(Level::Warning, e.to_string());
                    } else {
                        let kept = self.autosave.path.display().to_string();
                        self.message(
                            Level::Warning,
                            format!("the unsaved changes were kept in {kept}"),
                        );
                    }
                }
                self.session = s.clone();
                self.saved = s;
                self.session_path = Some(path.to_path_buf());
                self.history.clear();
                self.camera = None;
                self.autosave.set_session_path(Some(path));
                self.drop_live();
                self.failed = None;
                self.load_scene();
                self.remember(path);
                self.message(Level::Info, format!("opened {}", path.display()));
            }
            Err(e) => self.message(Level::Error, e.to_string()),
        }
    }

    /// Puts `path` first in the recent files (at most 10, written atomically).
    fn remember(&mut self, path: &Path) {
        let p = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        self.recent.retain(|r| r != &p);
        self.recent.insert(0, p);
        self.recent.truncate(10);
        let file = self.state_dir.join(RECENT_FILE);
        let text = serde_json::to_string_pretty(&self.recent).unwrap_or_default();
        let written = std::fs::create_dir_all(&self.state_dir)
            .and_then(|_| crate::files::write_atomic(&file, text.as_bytes()));
        if let Err(e) = written {
            self.message(Level::Warning, format!("{}: {e}", file.display()));
        }
    }

    /// Saves to `path` (atomically); the session is then unmodified.
    pub fn save_session(&mut self, path: &Path) {
        self.end_stroke();
        match self.session.save(path) {
            Ok(()) => {
                self.saved = self.session.clone();
                self.session_path = Some(path.to_path_buf());
                self.autosave.saved(Some(path));
                self.remember(path);
                self.message(Level::Info, format!("saved {}", path.display()));
            }
            Err(e) => self.message(Level::Error, e.to_string()),
        }
    }

    /// The camera resolved for the current hair (framed when the session has no target yet).
    /// The aspect is the viewport render's, as `render --session` frames with the still's.
    fn resolve_camera(&self, (lo, hi): (glam::Vec3, glam::Vec3)) -> Camera {
        let (w, h) = self.render_size();
        self.session
            .camera
            .resolve(lo, hi, w as f32 / h.max(1) as f32)
    }

    /// Frames the hair (Home).
    pub fn frame_hair(&mut self) {
        self.end_stroke();
        self.session.camera.target = None;
        self.session.camera.distance = None;
        if let Some(live) = &self.live {
            // The session keeps "framed" (no target, no distance): it follows the hair.
            let bounds = live.lock().bounds;
            let c = self.resolve_camera(bounds);
            self.camera = Some(c);
            self.session.camera.yaw = c.yaw;
            self.session.camera.pitch = c.pitch;
            self.autosave.changed();
        }
    }

    /// Moves the camera (not an edit; saved with the session). A stroke under way ends: its dabs
    /// were placed in the old view.
    pub fn set_camera(&mut self, c: Camera) {
        if self.camera != Some(c) {
            self.end_stroke();
        }
        self.camera = Some(c);
        let vc = ViewCamera::from_camera(&c);
        if vc != self.session.camera {
            self.session.camera = vc;
            self.autosave.changed();
        }
    }

    /// Polls the background jobs.
    fn poll_jobs(&mut self) {
        // Scenes are installed once the viewport has been laid out (the renderer follows its size).
        let scene = match (&mut self.loading, self.viewport_rect) {
            (Some(job), Some(_)) => job.poll(),
            _ => None,
        };
        if let Some(result) = scene {
            self.loading = None;
            let for_session = self
                .loading_for
                .take()
                .unwrap_or_else(|| self.session.clone());
            match result.and_then(|r| r) {
                // A scene built for a device lost since is not installed.
                Ok(Loaded::Scene { .. }) if self.gpu.is_none() => {}
                Ok(Loaded::Scene {
                    driver,
                    pictures,
                    warnings,
                }) => {
                    for w in warnings {
                        self.message(Level::Warning, w);
                    }
                    // The camera as it is now (the user may have navigated during the load); the
                    // renderer takes it in its next sync, and the size of the viewport as it is.
                    self.camera = Some(self.resolve_camera(driver.bounds));
                    self.drop_live();
                    let mut driver = *driver;
                    let (w, h) = self.render_size();
                    if let Err(e) = driver.resize(w, h) {
                        self.message(Level::Error, e.to_string());
                    }
                    driver.set_view(self.view);
                    if let Some(camera) = self.camera
                        && let Err(e) = driver.sync(&self.session, &camera)
                    {
                        self.message(Level::Error, e.to_string());
                    }
                    if self.first_scene {
                        // The first scene's times count from the launch.
                        self.first_scene = false;
                        driver.count_from(self.started);
                    }
                    self.live = Some(LiveScene::new(driver, pictures, self.ctx.clone()));
                    self.render_thread_lost = false;
                    self.failed = None;
                }
                Ok(_) => {}
                Err(e) => {
                    self.failed = Some(SceneKey::of(&for_session));
                    self.message(Level::Error, e);
                }
            }
        }
        if let Some(result) = self.source_job.as_mut().and_then(|j| j.poll()) {
            self.source_job = None;
            match result.and_then(|r| r) {
                Ok(Loaded::Occluder { path }) => {
                    let occluder = crate::session::OccluderOptions {
                        show: true,
                        mesh: Some(path),
                        ..self.session.occluder.clone()
                    };
                    self.perform(Edit::Occluder(Box::new(occluder)), false);
                }
                Ok(Loaded::Hair { source, restored }) => {
                    self.perform(Edit::Hair(source), false);
                    self.session.camera.target = None;
                    self.session.camera.distance = None;
                    if let Some(restored) = restored {
                        let (look, layer) = *restored;
                        self.perform(Edit::Look(Box::new(look)), false);
                        let layer = crate::paint::layer::SharedLayer::new(layer);
                        self.perform(Edit::PaintLayer(Box::new((Some(layer), None))), false);
                        self.message(
                            Level::Info,
                            "restored the look and paint strandlight exported with this groom"
                                .to_string(),
                        );
                    }
                }
                Ok(Loaded::Environment {
                    environment,
                    pictures,
                    source,
                }) => {
                    self.perform(Edit::Environment(Box::new(source.clone())), false);
                    if let Some(live) = &mut self.live
                        && self.loading.is_none()
                        && live.lock().hair_source == self.session.hair
                    {
                        live.set_environment(*environment, *pictures, source, self.session.env_yaw);
                    }
                }
                Ok(Loaded::Scene { .. }) => {}
                // The session is untouched: a source edit is made only when its file loaded.
                Err(e) => self.message(Level::Error, e),
            }
        }
        if let Some(job) = &mut self.export {
            self.ctx.request_repaint_after(REFINE_POLL);
            if let Some(msg) = job.poll(self.gpu.as_ref()) {
                let (level, text) = msg;
                self.message(level, text);
                self.export = None;
            }
        }
        if let Some(r) = self.hair_export.as_mut().and_then(|j| j.poll()) {
            self.hair_export = None;
            match r.and_then(|r| r) {
                Ok(m) => self.message(Level::Info, m),
                Err(e) => self.message(Level::Error, e),
            }
        }
        match self.autosave.tick(&self.session, &self.wake) {
            Ok(Some(due)) => self.ctx.request_repaint_after(due),
            Ok(None) => {}
            Err(e) => self.message(Level::Warning, e.to_string()),
        }
    }

    /// Drops the live scene, releasing its egui texture.
    pub fn drop_live(&mut self) {
        if let Some(mut live) = self.live.take()
            && let Some(er) = &self.egui_renderer
        {
            live.release(&mut er.write());
        }
    }

    /// The render size for the current viewport and view scale.
    pub fn render_size(&self) -> (u32, u32) {
        let s = self.view.scale.clamp(0.1, 1.0);
        (
            ((self.viewport_px[0] as f32 * s).round() as u32).clamp(16, 4096),
            ((self.viewport_px[1] as f32 * s).round() as u32).clamp(16, 4096),
        )
    }

    /// The viewport's per-frame work: rebuild when the session needs another scene, tell the
    /// driver what changed (size, session, camera, view, whether the brush picks) and kick its render
    /// thread. Nothing here waits for the GPU: the thread refines and wakes the UI for new images.
    pub fn update_viewport(&mut self) {
        if self.gpu.is_none() {
            return;
        }
        let (w, h) = self.render_size();
        let rebuild = self
            .live
            .as_ref()
            .is_none_or(|l| l.lock().needs_rebuild(&self.session));
        if rebuild {
            let key = SceneKey::of(&self.session);
            let pending = self
                .loading_for
                .as_ref()
                .is_some_and(|s| SceneKey::of(s) == key);
            if !pending && self.failed.as_ref() != Some(&key) {
                self.load_scene();
            }
            if self.live.as_ref().is_none_or(|l| {
                let d = l.lock();
                d.hair_source != self.session.hair
                    || d.environment_source != self.session.environment
            }) {
                return;
            }
        }
        // A framed camera (no explicit target or distance) follows the hair and the viewport's aspect.
        if let Some(live) = &self.live
            && (self.session.camera.target.is_none() || self.session.camera.distance.is_none())
        {
            let bounds = live.lock().bounds;
            self.camera = Some(self.resolve_camera(bounds));
        }
        let (Some(live), Some(camera)) = (&mut self.live, self.camera) else {
            return;
        };
        let (result, paint_warning, errors) = {
            let mut d = live.lock();
            let result = d.resize(w, h).and_then(|_| d.sync(&self.session, &camera));
            d.set_view(self.view);
            d.set_picking(self.tool == super::brush_tool::Tool::Brush);
            (result, d.paint_warning.take(), d.take_errors())
        };
        live.kick();
        let lost = !live.handle().running();
        if let Some(er) = &self.egui_renderer {
            live.texture(&mut er.write());
        }
        if self.options.log_times {
            self.log_times();
        }
        if lost && !self.render_thread_lost {
            // No thread could be started for it: nothing refines the image any more.
            self.render_thread_lost = true;
            self.message(
                Level::Error,
                "the viewport's render thread is not running: the image no longer refines; \
                 reopen the session",
            );
        }
        if let Err(e) = result {
            self.message(Level::Error, e.to_string());
        }
        for e in errors {
            self.message(Level::Error, e);
        }
        if let Some(w) = paint_warning {
            self.message(Level::Warning, w);
        }
    }

    /// Prints the times of a change that has converged (once per change).
    fn log_times(&mut self) {
        let Some(live) = &self.live else {
            return;
        };
        let (restarts, first, sharp, converged) = {
            let d = live.lock();
            if let Some((t, r)) = self.pending_dab
                && d.restarts() >= r
                && d.first_image_in().is_some()
            {
                self.pending_dab = None;
                eprintln!(
                    "dab: shown {:.1} ms after the frame that took it",
                    t.elapsed().as_secs_f64() * 1e3
                );
            }
            let done = d.progress.is_some_and(|p| p.converged) && !d.tables_pending();
            (
                d.restarts(),
                d.first_image_in(),
                d.full_image_in,
                d.converged_in.filter(|_| done),
            )
        };
        self.frames_since_change += 1;
        let Some(converged) = converged else {
            return;
        };
        if self
            .logged
            .is_some_and(|(r, c)| r == restarts && c == converged)
        {
            return;
        }
        self.logged = Some((restarts, converged));
        let n = self.frames_since_change;
        let p95 = |v: &std::collections::VecDeque<f32>, keep: &dyn Fn(f32) -> bool| {
            let mut v: Vec<f32> = v
                .iter()
                .rev()
                .take(n)
                .copied()
                .filter(|x| keep(*x))
                .collect();
            v.sort_by(f32::total_cmp);
            let q = v
                .get(((v.len().max(1) - 1) as f32 * 0.95).round() as usize)
                .copied();
            (q.unwrap_or(0.0), v.len())
        };
        let (cost, _) = p95(&self.frame_costs, &|_| true);
        let (whole, back_to_back) = p95(&self.frame_intervals, &|x| x < BACK_TO_BACK_MS);
        let s = |t: Option<Duration>| t.map_or(-1.0, |t| t.as_secs_f64());
        eprintln!(
            "times: first {:.3} s, sharp {:.3} s, converged {:.3} s; UI frames {n}, own work p95 \
             {cost:.1} ms; {back_to_back} frames back to back, whole frame p95 {whole:.1} ms",
            s(first),
            s(sharp),
            converged.as_secs_f64(),
        );
        self.frames_since_change = 0;
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
        if redo || redo_y {
            self.redo();
        } else if undo {
            self.undo();
        }
        if save_as || (save && self.session_path.is_none()) {
            panels::menu::save_as_dialog(self);
        } else if save && let Some(p) = self.session_path.clone() {
            self.save_session(&p);
        }
        if open {
            panels::menu::open_dialog(self);
        }
        if export {
            panels::menu::export_dialog(self);
        }
    }

    /// The end of a frame's work: its cost goes to the smoothed figure and the recent costs.
    fn frame_timing(&mut self) {
        let Some(t) = self.frame_started.take() else {
            return;
        };
        let ms = t.elapsed().as_secs_f32() * 1e3;
        self.frame_ms = if self.frame_ms == 0.0 {
            ms
        } else {
            0.9 * self.frame_ms + 0.1 * ms
        };
        if self.frame_costs.len() == FRAME_COSTS_KEPT {
            self.frame_costs.pop_front();
        }
        self.frame_costs.push_back(ms);
    }

    /// Navigation keys over the viewport.
    pub fn navigation_keys(&mut self, ctx: &egui::Context) {
        use egui::Key;
        let Some(mut c) = self.camera else {
            return;
        };
        let (home, one, three, seven, ctrl) = ctx.input(|i| {
            (
                i.key_pressed(Key::Home) || i.key_pressed(Key::Period),
                i.key_pressed(Key::Num1),
                i.key_pressed(Key::Num3),
                i.key_pressed(Key::Num7),
                i.modifiers.ctrl,
            )
        });
        if home {
            self.frame_hair();
            return;
        }
        let view = if one {
            Some(navigation::AxisView::Front)
        } else if three {
            Some(navigation::AxisView::Side)
        } else if seven {
            Some(navigation::AxisView::Top)
        } else {
            None
        };
        if let Some(v) = view {
            navigation::axis_view(&mut c, v, ctrl);
            self.set_camera(c);
        }
    }

    /// When the app closes: the recovery file is written if there are unsaved changes.
    pub fn closing(&mut self) {
        // A recovery still on offer belongs to an earlier run: leave it for the next start.
        if self.recovery_offer.is_some() || self.relaunching {
            return;
        }
        if let Err(e) = self.autosave.on_exit(&self.session, self.modified()) {
            eprintln!("warning: {e}");
        }
    }

    /// How long ago the last refinement converged (tests and the status bar).
    pub fn converged(&self) -> Option<Duration> {
        self.live.as_ref().and_then(|l| {
            let l = l.lock();
            l.progress
                .filter(|p| p.converged && !l.tables_pending())
                .and(l.converged_in)
        })
    }
}

const RECENT_FILE: &str = "recent.json";

/// How often the UI wakes to poll an export while it runs (its renderer is refined in UI frames).
const REFINE_POLL: Duration = Duration::from_millis(30);

/// Frames less than this apart ran back to back (a frame was asked for while one was drawn).
const BACK_TO_BACK_MS: f32 = 250.0;

/// UI frame costs kept for the status bar and measurements.
const FRAME_COSTS_KEPT: usize = 256;

/// The recent sessions list (missing or unreadable: empty).
fn read_recent(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_to_string(dir.join(RECENT_FILE))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default()
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
        let now = Instant::now();
        if let Some(last) = self.last_frame_start {
            if self.frame_intervals.len() == FRAME_COSTS_KEPT {
                self.frame_intervals.pop_front();
            }
            self.frame_intervals
                .push_back((now - last).as_secs_f32() * 1e3);
        }
        self.last_frame_start = Some(now);
        self.frame_started = Some(now);
        self.check_device();
        self.poll_jobs();
        self.dropped_files(ctx);
        self.shortcuts(ctx);
        if !ctx.input(|i| i.pointer.any_down()) {
            self.history.end_gesture(&self.session);
        }
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        // The renderer's step first (with last frame's viewport size), so this frame paints the
        // image and the progress it produced.
        self.update_viewport();
        panels::show(self, ui);
        self.frame_timing();
    }

    fn on_exit(&mut self) {
        self.closing();
    }
}
