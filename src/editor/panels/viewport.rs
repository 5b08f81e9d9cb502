//! The viewport: the renderer's image, and navigation with Blender's habits (middle-drag orbit,
//! Shift+middle pan, wheel and Ctrl+middle zoom, Alt+left orbit, Home frames, 1/3/7 views).

use crate::editor::app::EditorApp;
use crate::editor::navigation;

pub fn show(app: &mut EditorApp, ui: &mut egui::Ui) {
    let rect = ui.available_rect_before_wrap();
    let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
    let ppp = ui.ctx().pixels_per_point();
    app.viewport_rect = Some(rect);
    let px = [
        (rect.width() * ppp).round().max(16.0) as u32,
        (rect.height() * ppp).round().max(16.0) as u32,
    ];
    if px != app.viewport_px {
        // The renderer steps before the panels: one more frame resizes it.
        ui.ctx().request_repaint();
    }
    app.viewport_px = px;
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, egui::Color32::from_rgb(41, 41, 43));
    match app.live.as_ref().and_then(|l| l.texture) {
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
    navigate(app, ui, &response, rect);
}

fn navigate(app: &mut EditorApp, ui: &egui::Ui, response: &egui::Response, rect: egui::Rect) {
    let Some(mut c) = app.camera else {
        return;
    };
    let (mods, scroll) = ui.input(|i| (i.modifiers, i.smooth_scroll_delta.y));
    let delta = response.drag_delta();
    let mut moved = false;
    if response.dragged_by(egui::PointerButton::Middle) && delta != egui::Vec2::ZERO {
        if mods.shift {
            navigation::pan(&mut c, delta.x, delta.y, rect.height());
        } else if mods.ctrl {
            navigation::zoom(&mut c, -delta.y * 2.0);
        } else {
            navigation::orbit(&mut c, delta.x, delta.y);
        }
        moved = true;
    } else if response.dragged_by(egui::PointerButton::Primary)
        && mods.alt
        && delta != egui::Vec2::ZERO
    {
        navigation::orbit(&mut c, delta.x, delta.y);
        moved = true;
    }
    if response.hovered() && scroll != 0.0 {
        navigation::zoom(&mut c, scroll);
        moved = true;
    }
    if moved {
        app.set_camera(c);
    }
    if (response.hovered() || response.has_focus()) && !ui.ctx().egui_wants_keyboard_input() {
        app.navigation_keys(ui.ctx());
    }
}
