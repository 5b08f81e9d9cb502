//! The brush tool (B; V or Esc back to navigation): left-drag paints absorption onto the strands under
//! the cursor. Dabs are spaced along the pointer path at a fraction of the radius; each changes the
//! session's paint layer at the points it touches and sends only those to the renderer. A stroke is
//! one undo step holding the touched points' previous values.

use super::app::{EditorApp, Level};
use crate::paint::brush::Stroke;
use crate::paint::pick::dabs_along;
use crate::paint::{PaintDelta, PaintLayer, SharedLayer};
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
    /// Dabs that found no picker for the view yet (painted once it is ready).
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

    /// Dabs at `centres` (render pixels).
    fn dab_at(&mut self, centres: &[[f32; 2]], pressure: f32) {
        let t = Instant::now();
        let radius = self.brush_radius_render_px();
        let Some(live) = &mut self.live else {
            return;
        };
        let Some(picker) = live.picker() else {
            if let Some(s) = &mut self.stroke
                && !s.waiting
            {
                s.waiting = true;
                self.message(
                    Level::Info,
                    "the brush waits for the view's depth (a moment after the view changes)",
                );
            }
            return;
        };
        let hair = live.hair.clone();
        let (points, strands) = (hair.point_count(), hair.strand_count());
        let layer = self
            .session
            .paint_layer
            .get_or_insert_with(|| SharedLayer::new(PaintLayer::empty(points, strands)));
        if !layer.get().fits(points, strands) {
            self.stroke = None;
            self.message(
                Level::Error,
                "the paint layer was made for another hair: it cannot be painted on this one",
            );
            return;
        }
        let Some(stroke) = &mut self.stroke else {
            return;
        };
        let eumelanin = crate::scattering::params::sigma_a_from_melanin(1.0, 0.0).map(|x| x as f32);
        let offsets = &hair.strand_offsets;
        let strand_of = |i: u32| {
            let s = offsets.partition_point(|&o| o <= i).saturating_sub(1);
            offsets[s]..offsets[s + 1]
        };
        let mut changed: Vec<u32> = Vec::new();
        let points_mut = &mut layer.make_mut().points;
        for &c in centres {
            let under = picker.dab(&self.brush, c, radius, pressure);
            changed.extend(stroke.stroke.dab(
                &self.brush,
                &under,
                points_mut,
                &live.base_sigma_a,
                strand_of,
                eumelanin,
            ));
        }
        changed.sort_unstable();
        changed.dedup();
        let n = changed.len();
        if let Err(e) = live.paint_points(&self.session, &changed) {
            self.message(Level::Error, e.to_string());
        }
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let st = &mut self.brush_stats;
        st.dabs += centres.len() as u64;
        st.last_dab_ms = ms / centres.len().max(1) as f64;
        st.mean_dab_ms += (st.last_dab_ms - st.mean_dab_ms) * centres.len() as f64 / st.dabs as f64;
        st.last_points = n;
    }

    /// The stroke ends: it becomes one undo step.
    pub fn end_stroke(&mut self) {
        let Some(s) = self.stroke.take() else {
            return;
        };
        let Some(layer) = &self.session.paint_layer else {
            return;
        };
        if let Some(delta) = s.stroke.finish(&layer.get().points) {
            self.history.record(Edit::Paint(Box::new(delta)));
            self.autosave.changed();
        }
        if let Some(live) = &mut self.live
            && let Err(e) = live.paint_finished(&self.session)
        {
            self.message(Level::Error, e.to_string());
        }
    }

    /// Writes the hair with its look and paint to `out` (.usda or .hair) on a worker.
    pub fn export_hair(&mut self, out: std::path::PathBuf) {
        let Some(live) = &self.live else {
            self.message(Level::Error, "export: the scene is still loading");
            return;
        };
        let (hair, sigma_a) = (live.hair.clone(), live.sigma_a.clone());
        let scale = self.session.look.thickness_scale;
        let wake = self.egui_ctx();
        self.hair_export = Some(super::jobs::Job::spawn(
            "exporting the hair",
            move || wake.request_repaint(),
            move |_| {
                let mut h = (*hair).clone();
                h.transform(|p| p, scale);
                crate::session::export_hair::write_painted_hair(&h, &sigma_a, &out)
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
        if let Some(live) = &mut self.live {
            let r = live
                .paint_points(&self.session, indices)
                .and_then(|_| live.paint_finished(&self.session));
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
    let (b, v, esc, smaller, larger) = ctx.input(|i| {
        (
            i.key_pressed(Key::B),
            i.key_pressed(Key::V),
            i.key_pressed(Key::Escape),
            i.key_pressed(Key::OpenBracket),
            i.key_pressed(Key::CloseBracket),
        )
    });
    // F with the modifiers it was pressed with (Shift may be released within the same frame).
    let f = ctx.input(|i| {
        i.events.iter().find_map(|e| match e {
            egui::Event::Key {
                key: Key::F,
                pressed: true,
                repeat: false,
                modifiers,
                ..
            } => Some(modifiers.shift),
            _ => None,
        })
    });
    let (f, shift) = (f.is_some(), f.unwrap_or(false));
    if b {
        app.tool = Tool::Brush;
    }
    if (v || esc) && app.radius_drag.take().is_none() {
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
        app.radius_drag = Some(RadiusDrag {
            centre: p - egui::vec2(d, 0.0),
            strength: shift,
        });
    }
}
