//! The navigate tool, always at hand: viewport navigation with Blender's habits, as pure functions
//! of the orbit camera, and the viewport input that drives them: orbit (middle drag, Alt+left
//! drag), pan (Shift+middle drag), zoom (wheel, Ctrl+middle drag), frame the hair (Home,
//! numpad-style '.'), front/side/top views (1/3/7, Ctrl for the opposite side). It holds no state
//! between frames: the camera is the viewport's, and a move is a command.

use crate::editor::command::AppCommand;
use crate::editor::context::PanelContext;
use crate::render::Camera;
use glam::Vec3;

/// The viewport's pointer and keys for navigation; camera moves go to the app as commands.
pub fn input(ctx: &PanelContext, ui: &egui::Ui, response: &egui::Response, rect: egui::Rect) {
    let Some(mut c) = ctx.viewport.camera() else {
        return;
    };
    let (mods, scroll) = ui.input(|i| (i.modifiers, i.smooth_scroll_delta.y));
    let delta = response.drag_delta();
    let mut moved = false;
    if response.dragged_by(egui::PointerButton::Middle) && delta != egui::Vec2::ZERO {
        if mods.shift {
            pan(&mut c, delta.x, delta.y, rect.height());
        } else if mods.ctrl {
            zoom(&mut c, -delta.y * 2.0);
        } else {
            orbit(&mut c, delta.x, delta.y);
        }
        moved = true;
    } else if response.dragged_by(egui::PointerButton::Primary)
        && mods.alt
        && delta != egui::Vec2::ZERO
    {
        orbit(&mut c, delta.x, delta.y);
        moved = true;
    }
    if response.hovered() && scroll != 0.0 {
        zoom(&mut c, scroll);
        moved = true;
    }
    if moved {
        ctx.send(AppCommand::SetCamera(c));
    }
    if (response.hovered() || response.has_focus()) && !ui.ctx().egui_wants_keyboard_input() {
        keys(ctx, ui.ctx(), c);
    }
}

/// Navigation keys over the viewport: Home or '.' frames the hair, 1 / 3 / 7 the axis views.
fn keys(ctx: &PanelContext, egui_ctx: &egui::Context, mut c: Camera) {
    use egui::Key;
    let (home, one, three, seven, ctrl) = egui_ctx.input(|i| {
        (
            i.key_pressed(Key::Home) || i.key_pressed(Key::Period),
            i.key_pressed(Key::Num1),
            i.key_pressed(Key::Num3),
            i.key_pressed(Key::Num7),
            i.modifiers.ctrl,
        )
    });
    if home {
        ctx.send(AppCommand::FrameHair);
        return;
    }
    let view = if one {
        Some(AxisView::Front)
    } else if three {
        Some(AxisView::Side)
    } else if seven {
        Some(AxisView::Top)
    } else {
        None
    };
    if let Some(v) = view {
        axis_view(&mut c, v, ctrl);
        ctx.send(AppCommand::SetCamera(c));
    }
}

/// Degrees of orbit per point of pointer motion.
pub const ORBIT_DEG_PER_POINT: f32 = 0.4;
/// Zoom factor per point of wheel scroll (Blender steps ~1.2x per notch of 50 points).
pub const ZOOM_PER_POINT: f32 = 0.0036;

/// Turns the camera about its target by a pointer motion (points): right drags turn the view to the
/// right (the camera moves left), up drags look from below.
pub fn orbit(c: &mut Camera, dx: f32, dy: f32) {
    c.yaw = wrap_degrees(c.yaw - dx * ORBIT_DEG_PER_POINT);
    c.pitch = (c.pitch + dy * ORBIT_DEG_PER_POINT).clamp(-89.0, 89.0);
}

/// Moves the target in the view plane so the point under the pointer follows it (`height_points`: the
/// viewport's height in points).
pub fn pan(c: &mut Camera, dx: f32, dy: f32, height_points: f32) {
    let (right, up) = view_axes(c);
    let world_per_point =
        2.0 * c.distance * (0.5 * c.fov_y.to_radians()).tan() / height_points.max(1.0);
    let t = Vec3::from(c.target) - right * dx * world_per_point + up * dy * world_per_point;
    c.target = t.to_array();
}

/// Dollies towards the target: positive `amount` (points of scroll up) moves closer.
pub fn zoom(c: &mut Camera, amount: f32) {
    c.distance = (c.distance * (-amount * ZOOM_PER_POINT).exp()).clamp(0.05, 1.0e5);
}

/// The camera's right and up vectors in world space.
pub fn view_axes(c: &Camera) -> (Vec3, Vec3) {
    let forward = (Vec3::from(c.target) - c.eye()).normalize_or(Vec3::NEG_Z);
    let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
    (right, right.cross(forward))
}

/// Named views: front (1), side (3, from +X), top (7); `opposite` (Ctrl) gives back, other side, bottom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisView {
    Front,
    Side,
    Top,
}

pub fn axis_view(c: &mut Camera, view: AxisView, opposite: bool) {
    let (yaw, pitch) = match (view, opposite) {
        (AxisView::Front, false) => (0.0, 0.0),
        (AxisView::Front, true) => (180.0, 0.0),
        (AxisView::Side, false) => (90.0, 0.0),
        (AxisView::Side, true) => (-90.0, 0.0),
        (AxisView::Top, false) => (0.0, 89.0),
        (AxisView::Top, true) => (0.0, -89.0),
    };
    c.yaw = yaw;
    c.pitch = pitch;
}

fn wrap_degrees(d: f32) -> f32 {
    let w = (d + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 { 180.0 } else { w }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            target: [0.0, 0.0, 0.0],
            yaw: 0.0,
            pitch: 0.0,
            distance: 10.0,
            fov_y: 30.0,
        }
    }

    #[test]
    fn orbit_keeps_the_distance_and_clamps_the_pitch() {
        let mut c = camera();
        orbit(&mut c, 100.0, 1000.0);
        assert!((c.eye().length() - 10.0).abs() < 1e-4);
        assert_eq!(c.pitch, 89.0);
        orbit(&mut c, 900.0, 0.0);
        assert!((-180.0..=180.0).contains(&c.yaw));
    }

    #[test]
    fn pan_moves_the_target_in_the_view_plane() {
        let mut c = camera();
        pan(&mut c, 10.0, 0.0, 100.0);
        let t = Vec3::from(c.target);
        // Front view: right is +X; dragging right moves the target left, so the scene follows the pointer.
        assert!(t.x < 0.0 && t.y.abs() < 1e-6 && t.z.abs() < 1e-6);
        let expected = 2.0 * 10.0 * (15f32).to_radians().tan() / 100.0 * 10.0;
        assert!((t.x + expected).abs() < 1e-5, "{t}");
    }

    #[test]
    fn zoom_in_and_out_return() {
        let mut c = camera();
        zoom(&mut c, 120.0);
        assert!(c.distance < 10.0);
        zoom(&mut c, -120.0);
        assert!((c.distance - 10.0).abs() < 1e-4);
    }
}
