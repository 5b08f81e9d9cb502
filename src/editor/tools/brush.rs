//! The brush tool (B; V or Esc back to navigation): left-drag paints absorption onto the strands under
//! the cursor. It owns its settings, the stroke under way, the F / Shift+F adjustment and what it
//! measured. Dabs are spaced along the pointer path at a fraction of the radius; each is an edit of
//! the session's paint layer at the points it touches, applied through the document's history as
//! part of the stroke's gesture, and only those points go to the renderer. A stroke is one undo step
//! holding the touched points' previous values.

use crate::editor::command::{AppCommand, StrokeInput};
use crate::editor::context::PanelContext;
use crate::editor::document::Document;
use crate::editor::messages::{Level, Messages};
use crate::editor::timing::FrameTiming;
use crate::editor::viewport::{self, Viewport};
use crate::live::{Dab, DabEdit, DabError};
use crate::paint::Brush;
use crate::paint::brush::Stroke;
use crate::paint::pick::dabs_along;
use std::time::Instant;

#[derive(Default)]
pub struct BrushTool {
    settings: Brush,
    stroke: Option<StrokeState>,
    stats: BrushStats,
    /// F / Shift+F held: the pointer's distance sets the radius or the strength.
    adjusting: Option<RadiusDrag>,
    /// The click that confirmed an adjustment is held: the brush ignores it until released.
    idle_until_release: bool,
}

/// A stroke under way: its effect so far, and where the last dab went (render pixels).
struct StrokeState {
    stroke: Stroke,
    last: [f32; 2],
    carry: f32,
    /// Dabs found no picker for the view yet (they are dropped: the stroke paints from where the
    /// picker is ready); reported once.
    waiting: bool,
}

/// What the brush measured (the status bar and the benchmark).
#[derive(Clone, Copy, Debug, Default)]
pub struct BrushStats {
    pub dabs: u64,
    /// CPU time of the last dab (pick, layer, upload), ms; and the mean over the dabs.
    pub last_dab_ms: f64,
    pub mean_dab_ms: f64,
    /// Points the last dab changed.
    pub last_points: usize,
}

/// The adjustment under way (F: the pointer's distance from where F was pressed sets the radius).
#[derive(Clone, Copy, Debug)]
struct RadiusDrag {
    centre: egui::Pos2,
    strength: bool,
    /// The radius and strength before (Esc restores them).
    before: (f32, f32),
}

/// The keys a tool reads this frame, each with the modifiers it was pressed with (Shift may be
/// released within the same frame).
pub struct Keys {
    pub b: bool,
    pub v: bool,
    pub esc: bool,
    smaller: bool,
    larger: bool,
    /// F, and whether with Shift.
    f: Option<bool>,
}

impl Keys {
    pub fn read(ctx: &egui::Context) -> Self {
        use egui::Key;
        // Plain keys only (Ctrl+V pastes, Ctrl+B is not the brush).
        let pressed = |key: Key, shift_ok: bool| {
            ctx.input(|i| {
                i.events.iter().find_map(|e| match e {
                    egui::Event::Key {
                        key: k,
                        pressed: true,
                        repeat: false,
                        modifiers,
                        ..
                    } if *k == key
                        && !modifiers.ctrl
                        && !modifiers.alt
                        && !modifiers.command
                        && (shift_ok || !modifiers.shift) =>
                    {
                        Some(modifiers.shift)
                    }
                    _ => None,
                })
            })
        };
        // [ and ] repeat while held, and are typed with AltGr on many layouts (reported as
        // Ctrl+Alt).
        let bracket = |key: Key| {
            ctx.input(|i| {
                i.events.iter().any(|e| {
                    matches!(e, egui::Event::Key { key: k, pressed: true, modifiers, .. }
                        if *k == key && (modifiers.alt == modifiers.ctrl))
                })
            })
        };
        Self {
            b: pressed(Key::B, false).is_some(),
            v: pressed(Key::V, false).is_some(),
            esc: pressed(Key::Escape, true).is_some(),
            smaller: bracket(Key::OpenBracket),
            larger: bracket(Key::CloseBracket),
            f: pressed(Key::F, true),
        }
    }
}

impl BrushTool {
    pub fn settings(&self) -> &Brush {
        &self.settings
    }

    /// The brush panel's settings (tool state, not the document: no undo step).
    pub fn settings_mut(&mut self) -> &mut Brush {
        &mut self.settings
    }

    pub fn stats(&self) -> BrushStats {
        self.stats
    }

    /// Whether a stroke is under way.
    pub fn stroke_active(&self) -> bool {
        self.stroke.is_some()
    }

    /// Ends an F / Shift+F adjustment, restoring the values before it; false when none was under
    /// way.
    pub fn cancel_adjustment(&mut self) -> bool {
        let Some(d) = self.adjusting.take() else {
            return false;
        };
        (self.settings.radius_px, self.settings.strength) = d.before;
        true
    }

    /// Ends an F / Shift+F adjustment with the values it set (the brush was put away).
    pub fn drop_adjustment(&mut self) {
        self.adjusting = None;
    }

    /// The brush's own keys: [ and ] radius, F radius and Shift+F strength by pointer distance.
    pub(super) fn keys(&mut self, ctx: &PanelContext, keys: &Keys, pointer: Option<egui::Pos2>) {
        let b = &mut self.settings;
        if keys.smaller {
            b.radius_px = (b.radius_px / 1.15).max(2.0);
        }
        if keys.larger {
            b.radius_px = (b.radius_px * 1.15).min(500.0);
        }
        if let (Some(shift), Some(p)) = (keys.f, pointer) {
            // The pointer starts on the ring's edge: the distance to the centre is the value now.
            let d = if shift {
                b.strength * 200.0
            } else {
                b.radius_px
            };
            ctx.send(AppCommand::EndStroke);
            self.adjusting = Some(RadiusDrag {
                centre: p - egui::vec2(d, 0.0),
                strength: shift,
                before: (b.radius_px, b.strength),
            });
        }
    }

    /// The viewport's input while the brush is active: left-drag paints (Alt+left still orbits),
    /// the cursor ring shows the radius, F and Shift+F set the radius and the strength by the
    /// pointer's distance. Strokes go to the app as commands.
    pub fn viewport_input(
        &mut self,
        ctx: &PanelContext,
        ui: &egui::Ui,
        response: &egui::Response,
        rect: egui::Rect,
        px: [u32; 2],
    ) {
        let pointer = response.hover_pos();
        let painter = ui.painter_at(rect);
        let ring = egui::Stroke::new(1.5, egui::Color32::from_white_alpha(200));
        let shadow = egui::Stroke::new(3.0, egui::Color32::from_black_alpha(120));
        let b = &mut self.settings;
        if let Some(drag) = self.adjusting {
            // Adjusting: the ring follows the pointer's distance; a click or Enter confirms.
            if let Some(p) = ui.input(|i| i.pointer.hover_pos()) {
                let d = (p - drag.centre).length();
                if drag.strength {
                    b.strength = (d / 200.0).clamp(0.0, 1.0);
                } else {
                    b.radius_px = d.clamp(2.0, 500.0);
                }
            }
            painter.circle_stroke(drag.centre, b.radius_px, shadow);
            painter.circle_stroke(drag.centre, b.radius_px, ring);
            let text = if drag.strength {
                format!("strength {:.2}", b.strength)
            } else {
                format!("radius {:.0} px", b.radius_px)
            };
            painter.text(
                drag.centre,
                egui::Align2::CENTER_CENTER,
                text,
                egui::FontId::proportional(14.0),
                egui::Color32::WHITE,
            );
            if ui.input(|i| i.pointer.any_pressed() || i.key_pressed(egui::Key::Enter)) {
                self.adjusting = None;
                // The click that confirms does not paint.
                self.idle_until_release = ui.input(|i| i.pointer.any_down());
            }
            return;
        }
        if self.idle_until_release {
            self.idle_until_release = ui.input(|i| i.pointer.any_down());
            return;
        }
        if let Some(p) = pointer {
            painter.circle_stroke(p, b.radius_px, shadow);
            painter.circle_stroke(p, b.radius_px, ring);
            painter.circle_stroke(
                p,
                b.radius_px * b.strength.clamp(0.05, 1.0),
                egui::Stroke::new(1.0, egui::Color32::from_white_alpha(90)),
            );
            ui.ctx().set_cursor_icon(egui::CursorIcon::Crosshair);
        }
        let active = self.stroke_active();
        let alt = ui.input(|i| i.modifiers.alt);
        let primary = egui::PointerButton::Primary;
        let pressed = response.drag_started_by(primary) && !alt;
        let dragging = response.dragged_by(primary) && !alt;
        let released = response.drag_stopped_by(primary)
            || (active && !ui.input(|i| i.pointer.primary_down()));
        // A click without a drag is one dab.
        let clicked = response.clicked_by(primary) && !alt;
        // A drag starts where the button went down (egui reports it once the pointer has moved a
        // little).
        let pos = ui
            .input(|i| match pressed && !active {
                true => i.pointer.press_origin(),
                false => i.pointer.interact_pos(),
            })
            .filter(|_| dragging || pressed || clicked);
        let size = viewport::render_size(px, ctx.viewport.view().scale);
        let to = pos.map(|p| render_px(size, rect, p));
        let pressure = ui
            .input(|i| {
                i.events.iter().rev().find_map(|e| match e {
                    egui::Event::Touch { force: Some(f), .. } => Some(*f),
                    _ => None,
                })
            })
            .unwrap_or(1.0);
        let stroke = |to, pressed, released| {
            ctx.send(AppCommand::Stroke(StrokeInput {
                to,
                pressed,
                released,
                pressure,
            }))
        };
        if clicked && !active {
            stroke(to, true, true);
        } else if pressed || dragging || released {
            let start = pressed && !active;
            stroke(to, start, released);
            // The move that started the drag paints from the press to here.
            if start && let Some(p) = ui.input(|i| i.pointer.interact_pos()) {
                stroke(Some(render_px(size, rect, p)), false, false);
            }
        }
    }

    /// The brush radius in render pixels (the panel's radius is in screen points).
    pub fn radius_render_px(&self, viewport: &Viewport) -> f32 {
        let (w, _) = viewport.render_size();
        let rect_w = viewport.rect().map_or(w as f32, |r| r.width().max(1.0));
        self.settings.radius_px * w as f32 / rect_w
    }

    /// A press, a drag or a release (the app's handling of [`AppCommand::Stroke`]).
    pub fn stroke_input(
        &mut self,
        input: StrokeInput,
        doc: &mut Document,
        viewport: &Viewport,
        messages: &mut Messages,
        timing: &mut FrameTiming,
    ) {
        let StrokeInput {
            to,
            pressed,
            released,
            pressure,
        } = input;
        let radius = self.radius_render_px(viewport);
        if pressed && let Some(p) = to {
            self.end_stroke(doc, viewport, messages);
            self.stroke = Some(StrokeState {
                stroke: Stroke::new(),
                last: p,
                carry: 0.0,
                waiting: false,
            });
            self.dab_at(&[p], pressure, doc, viewport, messages, timing);
        } else if let (Some(p), Some(s)) = (to, &mut self.stroke) {
            let spacing = (radius * self.settings.spacing).max(0.5);
            let (centres, carry) = dabs_along(s.last, p, spacing, s.carry);
            s.last = p;
            s.carry = carry;
            if !centres.is_empty() {
                self.dab_at(&centres, pressure, doc, viewport, messages, timing);
            }
        }
        if released {
            self.end_stroke(doc, viewport, messages);
        }
    }

    /// Dabs at `centres` (render pixels) through the live driver; the dab's edit goes through the
    /// document as part of the stroke's gesture.
    fn dab_at(
        &mut self,
        centres: &[[f32; 2]],
        pressure: f32,
        doc: &mut Document,
        viewport: &Viewport,
        messages: &mut Messages,
        timing: &mut FrameTiming,
    ) {
        let t = Instant::now();
        let radius = self.radius_render_px(viewport);
        let (Some(live), Some(stroke)) = (viewport.live(), &mut self.stroke) else {
            return;
        };
        let (result, restarts) = {
            let mut d = live.lock();
            let r = d
                .dab_edit(
                    doc.session(),
                    &mut stroke.stroke,
                    &self.settings,
                    centres,
                    radius,
                    pressure,
                )
                .and_then(|DabEdit { dab, edit, changed }| {
                    if let Some(edit) = edit
                        && doc.perform(edit, true)
                    {
                        d.paint_points(doc.session(), &changed)?;
                    }
                    Ok(dab)
                });
            (r, d.restarts())
        };
        live.kick();
        if let Ok(Dab::Painted { points: 1.., .. }) = result {
            timing.dab_painted(restarts);
        }
        let n = match result {
            Ok(Dab::Painted { points, .. }) => points,
            Ok(Dab::Waiting) => {
                if !stroke.waiting {
                    stroke.waiting = true;
                    messages.push(
                        Level::Info,
                        "the brush waits for the view's depth (a moment after the view changes)",
                    );
                }
                return;
            }
            Ok(Dab::SceneLoading | Dab::Missed) => return,
            Err(e @ (DabError::UnreadablePaint(_) | DabError::OtherHair)) => {
                self.end_stroke(doc, viewport, messages);
                messages.push(Level::Error, e.to_string());
                return;
            }
            Err(e) => {
                messages.push(Level::Error, e.to_string());
                0
            }
        };
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let st = &mut self.stats;
        st.dabs += centres.len() as u64;
        st.last_dab_ms = ms / centres.len().max(1) as f64;
        st.mean_dab_ms += (st.last_dab_ms - st.mean_dab_ms) * centres.len() as f64 / st.dabs as f64;
        st.last_points = n;
    }

    /// The stroke ends: its gesture closes, so its dabs are one undo step (one that removes the layer
    /// again when the stroke made it).
    pub fn end_stroke(&mut self, doc: &mut Document, viewport: &Viewport, messages: &mut Messages) {
        if self.stroke.take().is_none() {
            return;
        }
        doc.end_gesture();
        let Some(live) = viewport.live() else {
            return;
        };
        // The volume and grid may follow now, whatever the stroke left.
        let finished = {
            let mut d = live.lock();
            d.end_painting();
            d.paint_finished(doc.session())
        };
        live.kick();
        if let Err(e) = finished {
            messages.push(Level::Error, e.to_string());
        }
    }
}

/// A viewport position (points) in the render's pixels (the image fills the viewport).
fn render_px((w, h): (u32, u32), rect: egui::Rect, p: egui::Pos2) -> [f32; 2] {
    [
        (p.x - rect.min.x) / rect.width().max(1.0) * w as f32,
        (p.y - rect.min.y) / rect.height().max(1.0) * h as f32,
    ]
}
