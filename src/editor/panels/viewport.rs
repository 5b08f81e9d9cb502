//! The viewport: the renderer's image, and the tools' input over it (navigation always, the brush
//! when it is the tool).

use crate::editor::command::AppCommand;
use crate::editor::context::PanelContext;
use crate::editor::tools::{Tool, Tools, navigate};

pub fn show(ctx: &PanelContext, tools: &mut Tools, ui: &mut egui::Ui) {
    let rect = ui.available_rect_before_wrap();
    let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
    let ppp = ui.ctx().pixels_per_point();
    let px = [
        (rect.width() * ppp).round().max(16.0) as u32,
        (rect.height() * ppp).round().max(16.0) as u32,
    ];
    if px != ctx.viewport.px() {
        // The renderer steps before the panels: one more frame resizes it.
        ui.ctx().request_repaint();
    }
    ctx.send(AppCommand::ViewportLaidOut { rect, px });
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, egui::Color32::from_rgb(41, 41, 43));
    match ctx.live().and_then(|l| l.texture_id()) {
        Some(id) => {
            painter.image(
                id,
                rect,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                egui::Color32::WHITE,
            );
        }
        None => {
            painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "loading the scene…",
                egui::FontId::proportional(16.0),
                ui.visuals().weak_text_color(),
            );
        }
    }
    navigate::input(ctx, ui, &response, rect);
    let pointer = response.hover_pos();
    if (response.hovered() || response.has_focus()) && !ui.ctx().egui_wants_keyboard_input() {
        tools.keys(ctx, ui.ctx(), pointer);
    }
    if tools.active() == Tool::Brush {
        tools
            .brush_mut()
            .viewport_input(ctx, ui, &response, rect, px);
    } else {
        tools.brush_mut().drop_adjustment();
    }
}
