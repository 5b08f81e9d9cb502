//! The editor's panels, one module each. Panels read the app and return edits; the app applies them
//! ([`super::app::EditorApp::perform`]).

pub mod brush;
pub mod look;
pub mod menu;
pub mod scene;
pub mod status;
pub mod viewport;
pub mod widgets;

use super::app::{EditorApp, Level};
use crate::session::Edit;

/// The whole window for one frame.
pub fn show(app: &mut EditorApp, ui: &mut egui::Ui) {
    egui::Panel::top("menu").show(ui, |ui| menu::bar(app, ui));
    egui::Panel::bottom("status").show(ui, |ui| status::bar(app, ui));
    egui::Panel::left("look")
        .default_size(310.0)
        .resizable(true)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                brush::tools(app, ui);
                ui.separator();
                if let Some((look, gesture)) = look::panel(ui, &app.session.look) {
                    app.perform(Edit::Look(Box::new(look)), gesture);
                }
            });
        });
    egui::Panel::right("scene")
        .default_size(270.0)
        .resizable(true)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| scene::panel(app, ui));
        });
    egui::CentralPanel::default().show(ui, |ui| viewport::show(app, ui));
    recovery_prompt(app, ui.ctx());
    errors_window(app, ui.ctx());
}

/// After a crash: offer the recovery file.
fn recovery_prompt(app: &mut EditorApp, ctx: &egui::Context) {
    let Some((_, path, _)) = &app.recovery_offer else {
        return;
    };
    let from = if path.as_os_str().is_empty() {
        "an unsaved session".to_string()
    } else {
        path.display().to_string()
    };
    let mut choice = None;
    egui::Window::new("Recover unsaved work?")
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
        .show(ctx, |ui| {
            ui.label(format!(
                "strandlight did not close cleanly. A recovery file of {from} was found."
            ));
            ui.horizontal(|ui| {
                if ui.button("Recover").clicked() {
                    choice = Some(true);
                }
                if ui.button("Discard").clicked() {
                    choice = Some(false);
                }
            });
        });
    let Some(recover) = choice else {
        return;
    };
    let Some((file, path, session)) = app.recovery_offer.take() else {
        return;
    };
    if recover {
        app.adopt_recovery(&file, path, session);
        app.load_scene();
        app.message(Level::Info, "recovered the unsaved session");
    } else {
        crate::session::autosave::remove_recovery(&file);
    }
}

/// Errors stay on screen until dismissed.
fn errors_window(app: &mut EditorApp, ctx: &egui::Context) {
    let errors: Vec<(usize, String)> = app
        .messages
        .iter()
        .enumerate()
        .filter(|(_, m)| m.level == Level::Error)
        .map(|(i, m)| (i, m.text.clone()))
        .collect();
    if errors.is_empty() {
        return;
    }
    let mut dismiss = false;
    egui::Window::new("Error")
        .collapsible(false)
        .anchor(egui::Align2::CENTER_TOP, [0.0, 40.0])
        .show(ctx, |ui| {
            for (_, e) in &errors {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
            ui.label("The scene was left as it was.");
            if ui.button("Dismiss").clicked() {
                dismiss = true;
            }
        });
    if dismiss {
        for m in &mut app.messages {
            if m.level == Level::Error {
                m.level = Level::Warning;
            }
        }
    }
}
