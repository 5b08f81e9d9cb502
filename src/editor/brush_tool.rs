//! The brush tool (B; V or Esc back to navigation): left-drag paints absorption onto the strands under
//! the cursor. Dabs are spaced along the pointer path at a fraction of the radius; each is an edit of
//! the session's paint layer at the points it touches, applied through the history as part of the
//! stroke's gesture, and only those points go to the renderer. A stroke is one undo step holding the
//! touched points' previous values.

use super::app::{EditorApp, Level};
use crate::live::{Dab, DabEdit, DabError};
use crate::paint::PaintDelta;
use crate::paint::brush::Stroke;
use crate::paint::pick::dabs_along;
use crate::session::Edit;
use std::time::Instant;

/// The active tool.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tool {
    #[default]
    Navigate,
    Brush,
}

/// A stroke under way: its effect so far, and where the last dab went (render pixels).
pub struct StrokeState {
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

/// The radius adjustment under way (F: the pointer's distance from where F was pressed sets it).
#[derive(Clone, Copy, Debug)]
pub struct RadiusDrag {
    pub centre: egui::Pos2,
    pub strength: bool,
    /// The radius and strength before (Esc restores them).
    pub before: (f32, f32),
}

impl EditorApp {
    /// A press, a drag to `to` or a release of the primary button over the viewport with the brush
    /// active; `to` in render pixels, `pressure` in [0, 1] (1 without a tablet).
    pub fn brush_input(
        &mut self,
        to: Option<[f32; 2]>,
        pressed: bool,
        released: bool,
        pressure: f32,
    ) {
        if pressed && let Some(p) = to {
            self.end_stroke();
            self.stroke = Some(StrokeState {
                stroke: Stroke::new(),
                last: p,
                carry: 0.0,
                waiting: false,
            });
            self.dab_at(&[p], pressure);
        } else if let (Some(p), Some(s)) = (to, &self.stroke) {
            let spacing = (self.brush_radius_render_px() * self.brush.spacing).max(0.5);
            let (centres, carry) = dabs_along(s.last, p, spacing, s.carry);
            if let Some(s) = &mut self.stroke {
                s.last = p;
                s.carry = carry;
            }
            if !centres.is_empty() {
                self.dab_at(&centres, pressure);
            }
        }
        if released {
            self.end_stroke();
        }
    }

    /// Whether a stroke is under way.
    pub fn stroke_active(&self) -> bool {
        self.stroke.is_some()
    }

    /// The brush radius in render pixels (the panel's radius is in screen points).
    pub fn brush_radius_render_px(&self) -> f32 {
        let (w, _) = self.render_size();
        let rect_w = self.viewport_rect.map_or(w as f32, |r| r.width().max(1.0));
        self.brush.radius_px * w as f32 / rect_w
    }

    /// Dabs at `centres` (render pixels) through the live driver.
    fn dab_at(&mut self, centres: &[[f32; 2]], pressure: f32) {
        let t = Instant::now();
        let radius = self.brush_radius_render_px();
        let (Some(live), Some(stroke)) = (&self.live, &mut self.stroke) else {
            return;
        };
        let (result, restarts) = {
            let mut d = live.lock();
            let r = d
                .dab_edit(
                    &self.session,
                    &mut stroke.stroke,
                    &self.brush,
                    centres,
                    radius,
                    pressure,
                )
                .and_then(|DabEdit { dab, edit, changed }| {
                    // The dab is an edit of the stroke's gesture: one undo step for the stroke.
                    if let Some(edit) = edit
                        && self.history.perform(&mut self.session, edit, true)
                    {
                        self.autosave.changed();
                        d.paint_points(&self.session, &changed)?;
                    }
                    Ok(dab)
                });
            (r, d.restarts())
        };
        live.kick();
        if let Ok(Dab::Painted { points: 1.., .. }) = result
            && self.pending_dab.is_none()
        {
            self.pending_dab = Some((self.frame_started.unwrap_or(t), restarts));
        }
        let n = match result {
            Ok(Dab::Painted { points, .. }) => points,
            Ok(Dab::Waiting) => {
                if !stroke.waiting {
                    stroke.waiting = true;
                    self.message(
                        Level::Info,
                        "the brush waits for the view's depth (a moment after the view changes)",
                    );
                }
                return;
            }
            Ok(Dab::SceneLoading | Dab::Missed) => return,
            Err(e @ (DabError::UnreadablePaint(_) | DabError::OtherHair)) => {
                self.end_stroke();
                self.message(Level::Error, e.to_string());
                return;
            }
            Err(e) => {
                self.message(Level::Error, e.to_string());
                0
            }
        };
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let st = &mut self.brush_stats;
        st.dabs += centres.len() as u64;
        st.last_dab_ms = ms / centres.len().max(1) as f64;
        st.mean_dab_ms += (st.last_dab_ms - st.mean_dab_ms) * centres.len() as f64 / st.dabs as f64;
        st.last_points = n;
    }

    /// The stroke ends: its gesture closes, so its dabs are one undo step (one that removes the layer
    /// again when the stroke made it).
    pub fn end_stroke(&mut self) {
        if self.stroke.take().is_none() {
            return;
        }
        if let Some(live) = &self.live {
            // The volume and grid may follow now, whatever the stroke left.
            live.lock().end_painting();
            live.kick();
        }
        self.history.end_gesture(&self.session);
        let finished = self
            .live
            .as_ref()
            .map(|live| live.lock().paint_finished(&self.session));
        if let Some(Err(e)) = finished {
            self.message(Level::Error, e.to_string());
        }
    }

    /// Removes the paint layer (one undo step; the look shows unpainted).
    pub fn clear_paint(&mut self) {
        self.end_stroke();
        if self.session.paint_layer.is_some() || self.session.paint.is_some() {
            self.perform(Edit::PaintLayer(Box::new((None, None))), false);
        }
    }

    /// Writes the hair with its look and paint to `out` (.usda or .hair) on a worker.
    pub fn export_hair(&mut self, out: std::path::PathBuf) {
        let Some(live) = &self.live else {
            self.message(Level::Error, "export: the scene is still loading");
            return;
        };
        let (hair, sigma_a) = {
            let d = live.lock();
            (d.hair.clone(), d.sigma_a.clone())
        };
        let look = self.session.look;
        let scale = look.thickness_scale;
        let wake = self.egui_ctx();
        self.hair_export = Some(crate::jobs::Job::spawn(
            "exporting the hair",
            move || wake.request_repaint(),
            move |_| {
                let mut h = (*hair).clone();
                h.transform(|p| p, scale);
                crate::session::export_hair::write_painted_hair(&h, &sigma_a, &look, &out)
                    .map(|_| format!("exported {}", out.display()))
            },
        ));
    }

    /// Undo or redo applied `edit`: a paint delta's points go to the renderer alone.
    pub(super) fn applied_paint(&mut self, edit: &Edit) {
        let Edit::Paint(delta) = edit else {
            return;
        };
        let PaintDelta { indices, .. } = delta.as_ref();
        if let Some(live) = &self.live {
            let r = {
                let mut d = live.lock();
                d.paint_points(&self.session, indices)
                    .and_then(|_| d.paint_finished(&self.session))
            };
            live.kick();
            if let Err(e) = r {
                self.message(Level::Error, e.to_string());
            }
        }
    }
}

/// Tool and brush keys (while the pointer is over the viewport and no text field has focus): B brush,
/// V / Esc navigate, [ and ] radius, F radius and Shift+F strength by pointer distance.
pub fn tool_keys(app: &mut EditorApp, ctx: &egui::Context, pointer: Option<egui::Pos2>) {
    use egui::Key;
    // Plain keys only (Ctrl+V pastes, Ctrl+B is not the brush); each with the modifiers it was
    // pressed with (Shift may be released within the same frame).
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
    // [ and ] repeat while held, and are typed with AltGr on many layouts (reported as Ctrl+Alt).
    let bracket = |key: Key| {
        ctx.input(|i| {
            i.events.iter().any(|e| {
                matches!(e, egui::Event::Key { key: k, pressed: true, modifiers, .. }
                    if *k == key && (modifiers.alt == modifiers.ctrl))
            })
        })
    };
    let (b, v, esc) = (
        pressed(Key::B, false).is_some(),
        pressed(Key::V, false).is_some(),
        pressed(Key::Escape, true).is_some(),
    );
    let (smaller, larger) = (bracket(Key::OpenBracket), bracket(Key::CloseBracket));
    let f = pressed(Key::F, true);
    let (f, shift) = (f.is_some(), f.unwrap_or(false));
    if b {
        app.tool = Tool::Brush;
    }
    if esc && let Some(d) = app.radius_drag.take() {
        // Esc cancels an adjustment.
        (app.brush.radius_px, app.brush.strength) = d.before;
    } else if v || esc {
        app.radius_drag = None;
        app.end_stroke();
        app.tool = Tool::Navigate;
    }
    if app.tool != Tool::Brush {
        return;
    }
    if smaller {
        app.brush.radius_px = (app.brush.radius_px / 1.15).max(2.0);
    }
    if larger {
        app.brush.radius_px = (app.brush.radius_px * 1.15).min(500.0);
    }
    if f && let Some(p) = pointer {
        // The pointer starts on the ring's edge: the distance to the centre is the current value.
        let d = if shift {
            app.brush.strength * 200.0
        } else {
            app.brush.radius_px
        };
        app.end_stroke();
        app.radius_drag = Some(RadiusDrag {
            centre: p - egui::vec2(d, 0.0),
            strength: shift,
            before: (app.brush.radius_px, app.brush.strength),
        });
    }
}
