//! The editor's panels, one module each. A panel reads the frame's [`PanelContext`] and sends
//! commands (edits among them); it changes nothing itself. The tools own their state, which the
//! tool row and the viewport hand to them.

pub mod brush;
pub mod look;
pub mod menu;
pub mod scene;
pub mod status;
pub mod viewport;
pub mod widgets;

use super::command::AppCommand;
use super::context::PanelContext;
use super::tools::Tools;
use crate::session::Edit;

/// The whole window for one frame.
pub fn show(ctx: &PanelContext, tools: &mut Tools, ui: &mut egui::Ui) {
    egui::Panel::top("menu").show(ui, |ui| menu::bar(ctx, ui));
    egui::Panel::bottom("status").show(ui, |ui| status::bar(ctx, ui));
    egui::Panel::left("look")
        .default_size(310.0)
        .resizable(true)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                brush::tools(ctx, tools, ui);
                ui.separator();
                if let Some((look, gesture)) = look::panel(ui, &ctx.session.look) {
                    ctx.send(AppCommand::Edit {
                        edit: Edit::Look(Box::new(look)),
                        gesture,
                    });
                }
            });
        });
    egui::Panel::right("scene")
        .default_size(270.0)
        .resizable(true)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| scene::panel(ctx, ui));
        });
    egui::CentralPanel::default().show(ui, |ui| viewport::show(ctx, tools, ui));
    recovery_prompt(ctx, ui.ctx());
    errors_window(ctx, ui.ctx());
}

/// After a crash: offer the recovery file.
fn recovery_prompt(ctx: &PanelContext, egui_ctx: &egui::Context) {
    let Some(path) = ctx.recovery_offer else {
        return;
    };
    let from = if path.as_os_str().is_empty() {
        "an unsaved session".to_string()
    } else {
        path.display().to_string()
    };
    egui::Window::new("Recover unsaved work?")
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
        .show(egui_ctx, |ui| {
            ui.label(format!(
                "strandlight did not close cleanly. A recovery file of {from} was found."
            ));
            ui.horizontal(|ui| {
                if ui.button("Recover").clicked() {
                    ctx.send(AppCommand::Recover);
                }
                if ui.button("Discard").clicked() {
                    ctx.send(AppCommand::DiscardRecovery);
                }
            });
        });
}

/// Errors stay on screen until dismissed.
fn errors_window(ctx: &PanelContext, egui_ctx: &egui::Context) {
    if ctx.messages.errors().next().is_none() {
        return;
    }
    egui::Window::new("Error")
        .collapsible(false)
        .anchor(egui::Align2::CENTER_TOP, [0.0, 40.0])
        .show(egui_ctx, |ui| {
            for e in ctx.messages.errors() {
                ui.colored_label(ui.visuals().error_fg_color, &e.text);
            }
            ui.label("The scene was left as it was.");
            if ui.button("Dismiss").clicked() {
                ctx.send(AppCommand::DismissErrors);
            }
        });
}
