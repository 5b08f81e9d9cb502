//! The menu bar (File, Edit, View); its items send commands (the file dialogs among them, shown by
//! the app).

use crate::editor::command::{AppCommand, Dialog};
use crate::editor::context::PanelContext;

pub fn bar(ctx: &PanelContext, ui: &mut egui::Ui) {
    let send = |c| ctx.send(c);
    egui::MenuBar::new().ui(ui, |ui| {
        ui.menu_button("File", |ui| {
            if ui.button("Open session…  (Ctrl+O)").clicked() {
                send(AppCommand::Dialog(Dialog::OpenSession));
            }
            ui.add_enabled_ui(!ctx.recent.is_empty(), |ui| {
                ui.menu_button("Open recent", |ui| {
                    for p in ctx.recent {
                        if ui.button(p.display().to_string()).clicked() {
                            send(AppCommand::OpenSession(p.clone()));
                        }
                    }
                });
            });
            if ui.button("Save  (Ctrl+S)").clicked() {
                send(AppCommand::Save);
            }
            if ui.button("Save as…  (Ctrl+Shift+S)").clicked() {
                send(AppCommand::Dialog(Dialog::SaveAs));
            }
            ui.separator();
            if ui.button("Open hair…").clicked() {
                send(AppCommand::Dialog(Dialog::OpenHair));
            }
            if ui.button("Open environment…").clicked() {
                send(AppCommand::Dialog(Dialog::OpenEnvironment));
            }
            ui.separator();
            if ui.button("Export still…  (Ctrl+E)").clicked() {
                send(AppCommand::Dialog(Dialog::ExportStill));
            }
            if ui
                .button("Export painted hair…")
                .on_hover_text("The groom with its dye and look as USD (.usda, for Unreal and Blender) or cyHair colours (.hair)")
                .clicked()
            {
                send(AppCommand::Dialog(Dialog::ExportHair));
            }
        });
        ui.menu_button("Edit", |ui| {
            let undo = ctx
                .history
                .undo_label()
                .map_or("Undo".to_string(), |l| format!("Undo {l}"));
            if ui
                .add_enabled(
                    ctx.history.can_undo(),
                    egui::Button::new(format!("{undo}  (Ctrl+Z)")),
                )
                .clicked()
            {
                send(AppCommand::Undo);
            }
            if ui
                .add_enabled(
                    ctx.history.can_redo(),
                    egui::Button::new("Redo  (Ctrl+Shift+Z)"),
                )
                .clicked()
            {
                send(AppCommand::Redo);
            }
        });
        ui.menu_button("View", |ui| {
            if ui.button("Frame hair  (Home)").clicked() {
                send(AppCommand::FrameHair);
            }
            ui.label("Front 1 · Side 3 · Top 7 (Ctrl: opposite)");
            ui.separator();
            for (name, yaw, pitch) in crate::render::camera::CAMERA_PRESETS {
                if ui.button(name).clicked()
                    && let Some(mut c) = ctx.viewport.camera()
                {
                    c.yaw = yaw;
                    c.pitch = pitch;
                    send(AppCommand::SetCamera(c));
                }
            }
        });
        let name = ctx
            .session_path
            .and_then(|p| p.file_name())
            .map_or("untitled".to_string(), |n| n.to_string_lossy().into_owned());
        let star = if ctx.modified { " •" } else { "" };
        ui.weak(format!("{name}{star}"));
    });
}
