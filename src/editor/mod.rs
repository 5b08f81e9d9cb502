//! The editor (eframe + egui on wgpu): a session edited live in a window. The session model, scene
//! assembly, autosave and the renderer live in the library and serve the CLI too; this module holds
//! the frame loop ([`app`]) and what it owns, each in a module of its own: the document
//! ([`document`]), the viewport's state and the live driver's image in egui ([`viewport`],
//! [`live_scene`]), the tools ([`tools`]), loads and exports on workers ([`loading`], [`export`]),
//! the device's health ([`device`]), messages, recent files and frame timing; the panels
//! ([`panels`]) see a per-frame [`context`] and send [`command`]s, which the app handles in one
//! place (`app/handling.rs`).

pub mod app;
pub mod command;
pub mod context;
pub mod device;
pub mod dialogs;
pub mod document;
pub mod env_preview;
pub mod export;
pub mod live_scene;
pub mod loading;
pub mod messages;
pub mod options;
pub mod panels;
pub mod recent;
pub mod timing;
pub mod tools;
pub mod viewport;

pub use app::EditorApp;
pub use command::AppCommand;
pub use options::EditorOptions;

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
