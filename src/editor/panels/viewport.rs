//! The viewport: the renderer's image, and navigation with Blender's habits (middle-drag orbit,
//! Shift+middle pan, wheel and Ctrl+middle zoom, Alt+left orbit, Home frames, 1/3/7 views).

use crate::editor::app::EditorApp;
use crate::editor::brush_tool::{self, Tool};
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
    match app.live.as_ref().and_then(|l| l.texture_id()) {
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
    brush(app, ui, &response, rect);
}

/// The brush tool: left-drag paints (Alt+left still orbits), the cursor ring shows the radius, F and
/// Shift+F set the radius and strength by the pointer's distance.
fn brush(app: &mut EditorApp, ui: &egui::Ui, response: &egui::Response, rect: egui::Rect) {
    let pointer = response.hover_pos();
    if (response.hovered() || response.has_focus()) && !ui.ctx().egui_wants_keyboard_input() {
        brush_tool::tool_keys(app, ui.ctx(), pointer);
    }
    if app.tool != Tool::Brush {
        app.radius_drag = None;
        return;
    }
    let painter = ui.painter_at(rect);
    let ring = egui::Stroke::new(1.5, egui::Color32::from_white_alpha(200));
    let shadow = egui::Stroke::new(3.0, egui::Color32::from_black_alpha(120));
    if let Some(drag) = app.radius_drag {
        // Adjusting: the ring follows the pointer's distance; a click or Enter confirms.
        if let Some(p) = ui.input(|i| i.pointer.hover_pos()) {
            let d = (p - drag.centre).length();
            if drag.strength {
                app.brush.strength = (d / 200.0).clamp(0.0, 1.0);
            } else {
                app.brush.radius_px = d.clamp(2.0, 500.0);
            }
        }
        painter.circle_stroke(drag.centre, app.brush.radius_px, shadow);
        painter.circle_stroke(drag.centre, app.brush.radius_px, ring);
        let text = if drag.strength {
            format!("strength {:.2}", app.brush.strength)
        } else {
            format!("radius {:.0} px", app.brush.radius_px)
        };
        painter.text(
            drag.centre,
            egui::Align2::CENTER_CENTER,
            text,
            egui::FontId::proportional(14.0),
            egui::Color32::WHITE,
        );
        if ui.input(|i| i.pointer.any_pressed() || i.key_pressed(egui::Key::Enter)) {
            app.radius_drag = None;
            // The click that confirms does not paint.
            app.brush_idle_until_release = ui.input(|i| i.pointer.any_down());
        }
        return;
    }
    if app.brush_idle_until_release {
        app.brush_idle_until_release = ui.input(|i| i.pointer.any_down());
        return;
    }
    if let Some(p) = pointer {
        painter.circle_stroke(p, app.brush.radius_px, shadow);
        painter.circle_stroke(p, app.brush.radius_px, ring);
        painter.circle_stroke(
            p,
            app.brush.radius_px * app.brush.strength.clamp(0.05, 1.0),
            egui::Stroke::new(1.0, egui::Color32::from_white_alpha(90)),
        );
        ui.ctx().set_cursor_icon(egui::CursorIcon::Crosshair);
    }
    let alt = ui.input(|i| i.modifiers.alt);
    let primary = egui::PointerButton::Primary;
    let pressed = response.drag_started_by(primary) && !alt;
    let dragging = response.dragged_by(primary) && !alt;
    let released = response.drag_stopped_by(primary)
        || (app.stroke_active() && !ui.input(|i| i.pointer.primary_down()));
    // A click without a drag is one dab.
    let clicked = response.clicked_by(primary) && !alt;
    // A drag starts where the button went down (egui reports it once the pointer has moved a little).
    let pos = ui
        .input(|i| match pressed && !app.stroke_active() {
            true => i.pointer.press_origin(),
            false => i.pointer.interact_pos(),
        })
        .filter(|_| dragging || pressed || clicked);
    let to = pos.map(|p| render_px(app, rect, p));
    let pressure = ui.input(|i| {
        i.events.iter().rev().find_map(|e| match e {
            egui::Event::Touch { force: Some(f), .. } => Some(*f),
            _ => None,
        })
    });
    let pressure = pressure.unwrap_or(1.0);
    if clicked && !app.stroke_active() {
        app.brush_input(to, true, true, pressure);
    } else if pressed || dragging || released {
        let start = pressed && !app.stroke_active();
        app.brush_input(to, start, released, pressure);
        // The move that started the drag paints from the press to here.
        if start && let Some(p) = ui.input(|i| i.pointer.interact_pos()) {
            app.brush_input(Some(render_px(app, rect, p)), false, false, pressure);
        }
    }
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

/// A viewport position (points) in the render's pixels (the image fills the viewport).
fn render_px(app: &EditorApp, rect: egui::Rect, p: egui::Pos2) -> [f32; 2] {
    let (w, h) = app.render_size();
    [
        (p.x - rect.min.x) / rect.width().max(1.0) * w as f32,
        (p.y - rect.min.y) / rect.height().max(1.0) * h as f32,
    ]
}
