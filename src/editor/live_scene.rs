//! The viewport's live scene: the library's [`LiveDriver`] refined on its render thread
//! ([`LiveHandle`]), its display texture registered with egui, and the environment panel's pictures.
//! The UI thread locks the driver briefly to tell it what changed and kicks the thread; the thread
//! wakes the UI when it has an image to draw.

use super::env_preview::EnvPictures;
use crate::live::{LiveDriver, LiveHandle};
use crate::render::scene::Environment;
use crate::session::EnvironmentSource;
use std::sync::{Arc, MutexGuard};

pub use crate::live::settings::ViewSettings;

pub struct LiveScene {
    handle: LiveHandle,
    /// The environment panel's pictures of the environment shown.
    pub environment_pictures: Arc<EnvPictures>,
    /// The egui texture of the display image and the display texture it shows.
    texture: Option<(egui::TextureId, u64)>,
}

impl LiveScene {
    /// Starts refining `driver` on its render thread; the thread wakes `ui` for new images.
    pub fn new(driver: LiveDriver, pictures: Arc<EnvPictures>, ui: egui::Context) -> Self {
        Self {
            handle: LiveHandle::start(driver, move || ui.request_repaint()),
            environment_pictures: pictures,
            texture: None,
        }
    }

    /// The driver (hold it briefly: the render thread takes it between units).
    pub fn lock(&self) -> MutexGuard<'_, LiveDriver> {
        self.handle.lock()
    }

    /// Tells the render thread that the driver was changed.
    pub fn kick(&self) {
        self.handle.kick();
    }

    /// The render thread, for tests and benchmarks that wait on it.
    pub fn handle(&self) -> &LiveHandle {
        &self.handle
    }

    /// A new environment (already loaded, with its pictures), turned by the session's yaw.
    pub fn set_environment(
        &mut self,
        environment: Environment,
        pictures: EnvPictures,
        source: EnvironmentSource,
        env_yaw: f64,
    ) {
        let background = pictures.background.clone();
        self.environment_pictures = Arc::new(pictures);
        self.lock()
            .set_environment(environment, background, source, env_yaw);
        self.kick();
    }

    /// The egui texture of the display image: registered on first use, pointed at the new display
    /// texture after a resize.
    pub fn texture(&mut self, egui_renderer: &mut egui_wgpu::Renderer) -> egui::TextureId {
        let driver = self.handle.lock();
        let generation = driver.display_generation();
        match self.texture {
            Some((id, g)) if g == generation => id,
            Some((id, _)) => {
                egui_renderer.update_egui_texture_from_wgpu_texture(
                    &driver.ctx.device,
                    &driver.display.view,
                    wgpu::FilterMode::Linear,
                    id,
                );
                self.texture = Some((id, generation));
                id
            }
            None => {
                let id = egui_renderer.register_native_texture(
                    &driver.ctx.device,
                    &driver.display.view,
                    wgpu::FilterMode::Linear,
                );
                self.texture = Some((id, generation));
                id
            }
        }
    }

    /// The texture registered so far (the viewport draws it).
    pub fn texture_id(&self) -> Option<egui::TextureId> {
        self.texture.map(|(id, _)| id)
    }

    /// Releases the egui texture (before the scene is dropped or replaced).
    pub fn release(&mut self, egui_renderer: &mut egui_wgpu::Renderer) {
        if let Some((id, _)) = self.texture.take() {
            egui_renderer.free_texture(&id);
        }
    }
}
