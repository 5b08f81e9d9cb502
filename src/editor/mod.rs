//! The editor (eframe + egui on wgpu): a session edited live in a window. The session model, scene
//! assembly and renderer live in the library and serve the CLI too; this module holds the app state and
//! frame loop ([`app`]), the live driver's image in egui ([`live`]), navigation, background jobs,
//! export and one module per panel (autosave and recovery are the session's: `session::autosave`).

pub mod app;
pub mod brush_tool;
pub mod env_preview;
pub mod export;
pub mod live;
pub mod navigation;
pub mod panels;

pub use app::{EditorApp, EditorOptions};

use crate::gpu::GpuContext;
use std::sync::Arc;

/// eframe's wgpu setup asking for what the renderer needs: the adapter's own limits and the optional
/// features (eframe requests only defaults unless told; docs/gpu.md).
pub fn wgpu_setup() -> egui_wgpu::WgpuSetup {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.instance_descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    setup.device_descriptor = Arc::new(GpuContext::device_descriptor);
    egui_wgpu::WgpuSetup::CreateNew(setup)
}

/// Whether a window can be opened here (Linux needs an X11 or Wayland display).
pub fn display_available() -> bool {
    if cfg!(target_os = "linux") {
        std::env::var_os("DISPLAY").is_some() || std::env::var_os("WAYLAND_DISPLAY").is_some()
    } else {
        true
    }
}

/// Opens the editor window and runs until it is closed.
pub fn run(options: EditorOptions) -> anyhow::Result<()> {
    if !display_available() {
        anyhow::bail!(
            "no display to open the editor on (neither DISPLAY nor WAYLAND_DISPLAY is set); \
             render stills without one with `strandlight render`"
        );
    }
    let mut native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("strandlight")
            .with_inner_size([1280.0, 800.0]),
        ..Default::default()
    };
    native.wgpu_options.wgpu_setup = wgpu_setup();
    eframe::run_native(
        "strandlight",
        native,
        Box::new(move |cc| Ok(Box::new(EditorApp::new(cc, options)))),
    )
    .map_err(|e| anyhow::anyhow!("the editor window: {e}"))
}
