//! The menu bar (File, Edit, View) and the file dialogs behind Ctrl+O, Ctrl+S, Ctrl+Shift+S, Ctrl+E.

use crate::editor::app::{EditorApp, Level};
use crate::editor::export::ExportJob;

pub fn bar(app: &mut EditorApp, ui: &mut egui::Ui) {
    egui::MenuBar::new().ui(ui, |ui| {
        ui.menu_button("File", |ui| {
            if ui.button("Open session…  (Ctrl+O)").clicked() {
                open_dialog(app);
            }
            let recent = app.recent.clone();
            ui.add_enabled_ui(!recent.is_empty(), |ui| {
                ui.menu_button("Open recent", |ui| {
                    for p in recent {
                        if ui.button(p.display().to_string()).clicked() {
                            app.open_session(&p);
                        }
                    }
                });
            });
            if ui.button("Save  (Ctrl+S)").clicked() {
                match app.session_path.clone() {
                    Some(p) => app.save_session(&p),
                    None => save_as_dialog(app),
                }
            }
            if ui.button("Save as…  (Ctrl+Shift+S)").clicked() {
                save_as_dialog(app);
            }
            ui.separator();
            if ui.button("Open hair…").clicked() {
                hair_dialog(app);
            }
            if ui.button("Open environment…").clicked() {
                environment_dialog(app);
            }
            ui.separator();
            if ui.button("Export still…  (Ctrl+E)").clicked() {
                export_dialog(app);
            }
            if ui
                .button("Export painted hair…")
                .on_hover_text("The groom with its dye and look as USD (.usda, for Unreal and Blender) or cyHair colours (.hair)")
                .clicked()
            {
                hair_export_dialog(app);
            }
        });
        ui.menu_button("Edit", |ui| {
            let undo = app
                .history
                .undo_label()
                .map_or("Undo".to_string(), |l| format!("Undo {l}"));
            if ui
                .add_enabled(
                    app.history.can_undo(),
                    egui::Button::new(format!("{undo}  (Ctrl+Z)")),
                )
                .clicked()
            {
                app.undo();
            }
            if ui
                .add_enabled(
                    app.history.can_redo(),
                    egui::Button::new("Redo  (Ctrl+Shift+Z)"),
                )
                .clicked()
            {
                app.redo();
            }
        });
        ui.menu_button("View", |ui| {
            if ui.button("Frame hair  (Home)").clicked() {
                app.frame_hair();
            }
            ui.label("Front 1 · Side 3 · Top 7 (Ctrl: opposite)");
            ui.separator();
            for (name, yaw, pitch) in crate::render::camera::CAMERA_PRESETS {
                if ui.button(name).clicked()
                    && let Some(mut c) = app.camera
                {
                    c.yaw = yaw;
                    c.pitch = pitch;
                    app.set_camera(c);
                }
            }
        });
        let name = app
            .session_path
            .as_ref()
            .and_then(|p| p.file_name())
            .map_or("untitled".to_string(), |n| n.to_string_lossy().into_owned());
        let star = if app.modified() { " •" } else { "" };
        ui.weak(format!("{name}{star}"));
    });
}

pub fn open_dialog(app: &mut EditorApp) {
    if let Some(p) = rfd::FileDialog::new()
        .add_filter("strandlight session", &["slsession", "json"])
        .pick_file()
    {
        app.open_session(&p);
    }
}

pub fn save_as_dialog(app: &mut EditorApp) {
    if let Some(mut p) = rfd::FileDialog::new()
        .add_filter("strandlight session", &["slsession"])
        .set_file_name("look.slsession")
        .save_file()
    {
        if p.extension().is_none() {
            p.set_extension("slsession");
        }
        app.save_session(&p);
    }
}

pub fn hair_dialog(app: &mut EditorApp) {
    if let Some(p) = rfd::FileDialog::new()
        .add_filter(
            "hair",
            &[
                "hair", "tfx", "gltf", "glb", "usd", "usda", "usdc", "usdz", "abc",
            ],
        )
        .pick_file()
    {
        app.open_hair(p);
    }
}

pub fn occluder_dialog(app: &mut EditorApp) {
    if let Some(p) = rfd::FileDialog::new()
        .add_filter("mesh", &["obj", "gltf", "glb"])
        .pick_file()
    {
        app.open_occluder(p);
    }
}

pub fn environment_dialog(app: &mut EditorApp) {
    if let Some(p) = rfd::FileDialog::new()
        .add_filter("environment", &["hdr", "exr", "json"])
        .pick_file()
    {
        app.load_environment(p, 40);
    }
}

pub fn hair_export_dialog(app: &mut EditorApp) {
    if let Some(mut p) = rfd::FileDialog::new()
        .add_filter("USD curves", &["usda"])
        .add_filter("cyHair", &["hair"])
        .set_file_name("hair.usda")
        .save_file()
    {
        if p.extension().is_none() {
            p.set_extension("usda");
        }
        app.export_hair(p);
    }
}

pub fn export_dialog(app: &mut EditorApp) {
    if let Some(mut p) = rfd::FileDialog::new()
        .add_filter("OpenEXR", &["exr"])
        .set_file_name("still.exr")
        .save_file()
    {
        if p.extension().is_none() {
            p.set_extension("exr");
        }
        start_export(app, p);
    }
}

/// Starts exporting the session's still to `exr` (and a PNG preview beside it).
pub fn start_export(app: &mut EditorApp, exr: std::path::PathBuf) {
    start_export_tiled(app, exr, None);
}

/// [`start_export`] in tiles of at most `tile` pixels a side (None: only when the image needs them).
pub fn start_export_tiled(app: &mut EditorApp, exr: std::path::PathBuf, tile: Option<u32>) {
    if app.export.is_some() {
        app.message(
            Level::Error,
            "an export is running: cancel it or wait for it first",
        );
        return;
    }
    let Some(live) = &app.live else {
        app.message(Level::Error, "export: the scene is still loading");
        return;
    };
    let png = Some(ExportJob::preview_path(&exr));
    let started = ExportJob::start(
        &live.lock(),
        app.luts(),
        &app.session,
        exr,
        png,
        app.egui_ctx(),
        tile,
    );
    match started {
        Ok(job) => app.export = Some(job),
        Err(e) => app.message(Level::Error, format!("export: {e}")),
    }
}
