//! The viewport's state: the camera, the view settings, the viewport's size and place, and the live
//! scene shown in it. Once a frame [`Viewport::sync`] tells the live driver what changed and kicks its
//! render thread; nothing here waits for the GPU.

use super::env_preview::EnvPictures;
use super::live_scene::{LiveScene, ViewSettings};
use super::messages::{Level, Messages};
use crate::live::LiveDriver;
use crate::render::Camera;
use crate::session::Session;
use std::sync::Arc;
use std::time::Instant;

/// eframe's renderer, where the display texture is registered.
pub type EguiRenderer = Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>;

pub struct Viewport {
    /// The camera resolved for the hair shown (None until a scene is installed).
    camera: Option<Camera>,
    view: ViewSettings,
    /// The viewport's size in physical pixels and its rectangle in points (last frame).
    px: [u32; 2],
    rect: Option<egui::Rect>,
    live: Option<LiveScene>,
    egui_renderer: Option<EguiRenderer>,
    /// The render thread was found not running (reported once).
    render_thread_lost: bool,
    /// The first scene is still to come (its times count from the launch).
    first_scene: bool,
}

/// The render size for a viewport of `px` physical pixels at `scale` of them.
pub fn render_size(px: [u32; 2], scale: f32) -> (u32, u32) {
    let s = scale.clamp(0.1, 1.0);
    (
        ((px[0] as f32 * s).round() as u32).clamp(16, 4096),
        ((px[1] as f32 * s).round() as u32).clamp(16, 4096),
    )
}

impl Viewport {
    pub fn new(view: ViewSettings, egui_renderer: Option<EguiRenderer>) -> Self {
        Self {
            camera: None,
            view,
            px: [640, 400],
            rect: None,
            live: None,
            egui_renderer,
            render_thread_lost: false,
            first_scene: true,
        }
    }

    pub fn camera(&self) -> Option<Camera> {
        self.camera
    }

    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = Some(camera);
    }

    /// Forgets the camera (another session: it is resolved anew for its hair).
    pub fn reset_camera(&mut self) {
        self.camera = None;
    }

    pub fn view(&self) -> ViewSettings {
        self.view
    }

    pub fn set_view(&mut self, view: ViewSettings) {
        self.view = view;
    }

    pub fn rect(&self) -> Option<egui::Rect> {
        self.rect
    }

    pub fn px(&self) -> [u32; 2] {
        self.px
    }

    /// Where the viewport was laid out this frame.
    pub fn laid_out(&mut self, rect: egui::Rect, px: [u32; 2]) {
        self.rect = Some(rect);
        self.px = px;
    }

    pub fn live(&self) -> Option<&LiveScene> {
        self.live.as_ref()
    }

    pub fn live_mut(&mut self) -> Option<&mut LiveScene> {
        self.live.as_mut()
    }

    /// The render size for the current viewport and view scale.
    pub fn render_size(&self) -> (u32, u32) {
        render_size(self.px, self.view.scale)
    }

    /// The camera for the hair's bounds (framed when the session has no target yet). The aspect is
    /// the viewport render's, as `render --session` frames with the still's.
    pub fn resolve_camera(&self, session: &Session, (lo, hi): (glam::Vec3, glam::Vec3)) -> Camera {
        let (w, h) = self.render_size();
        session.camera.resolve(lo, hi, w as f32 / h.max(1) as f32)
    }

    /// The hair's bounds in the scene shown.
    pub fn bounds(&self) -> Option<(glam::Vec3, glam::Vec3)> {
        self.live.as_ref().map(|l| l.lock().bounds)
    }

    /// Drops the live scene, releasing its egui texture.
    pub fn drop_live(&mut self) {
        if let Some(mut live) = self.live.take()
            && let Some(er) = &self.egui_renderer
        {
            live.release(&mut er.write());
        }
    }

    /// Installs a scene built on a worker: the camera as it is now (the user may have navigated
    /// during the load) and the viewport's size as it is; `launched`: the first scene's times count
    /// from the launch.
    pub fn install(
        &mut self,
        mut driver: LiveDriver,
        pictures: Arc<EnvPictures>,
        session: &Session,
        launched: Instant,
        ui: egui::Context,
        messages: &mut Messages,
    ) {
        self.camera = Some(self.resolve_camera(session, driver.bounds));
        self.drop_live();
        let (w, h) = self.render_size();
        if let Err(e) = driver.resize(w, h) {
            messages.push(Level::Error, e.to_string());
        }
        driver.set_view(self.view);
        if let Some(camera) = self.camera
            && let Err(e) = driver.sync(session, &camera)
        {
            messages.push(Level::Error, e.to_string());
        }
        if self.first_scene {
            self.first_scene = false;
            driver.count_from(launched);
        }
        self.live = Some(LiveScene::new(driver, pictures, ui));
        self.render_thread_lost = false;
    }

    /// Whether the scene shown is the session's hair and environment (else a load must bring it).
    pub fn shows_sources_of(&self, session: &Session) -> bool {
        self.live.as_ref().is_some_and(|l| {
            let d = l.lock();
            d.sources.hair_source == session.hair
                && d.sources.environment_source == session.environment
        })
    }

    /// Whether the session needs another scene than the one shown.
    pub fn needs_rebuild(&self, session: &Session) -> bool {
        self.live
            .as_ref()
            .is_none_or(|l| l.lock().needs_rebuild(session))
    }

    /// The frame's work: a framed camera (no explicit target or distance) follows the hair and the
    /// viewport's aspect; the driver hears of the size, session, camera, view and whether the brush
    /// picks; its render thread is kicked and the display texture registered.
    pub fn sync(&mut self, session: &Session, picking: bool, messages: &mut Messages) {
        if let Some(live) = &self.live
            && (session.camera.target.is_none() || session.camera.distance.is_none())
        {
            let bounds = live.lock().bounds;
            self.camera = Some(self.resolve_camera(session, bounds));
        }
        let (w, h) = self.render_size();
        let (Some(live), Some(camera)) = (&mut self.live, self.camera) else {
            return;
        };
        let (result, paint_warning, errors) = {
            let mut d = live.lock();
            let result = d.resize(w, h).and_then(|_| d.sync(session, &camera));
            d.set_view(self.view);
            d.set_picking(picking);
            (result, d.paint.paint_warning.take(), d.take_errors())
        };
        live.kick();
        let lost = !live.handle().running();
        if let Some(er) = &self.egui_renderer {
            live.texture(&mut er.write());
        }
        if lost && !self.render_thread_lost {
            // No thread could be started for it: nothing refines the image any more.
            self.render_thread_lost = true;
            messages.push(
                Level::Error,
                "the viewport's render thread is not running: the image no longer refines; \
                 reopen the session",
            );
        }
        if let Err(e) = result {
            messages.push(Level::Error, e.to_string());
        }
        for e in errors {
            messages.push(Level::Error, e);
        }
        if let Some(w) = paint_warning {
            messages.push(Level::Warning, w);
        }
    }
}
