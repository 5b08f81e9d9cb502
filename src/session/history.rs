//! Undo and redo of [`Edit`]s. Each step holds one edit: on the undo stack the edit that undoes it,
//! on the redo stack the edit that redoes it (applying an edit returns its inverse, so undo and redo
//! swap them; a paint stroke's sparse delta is stored once). A gesture (a slider drag, a colour-picker
//! drag, a brush stroke) is one step: while it is open, edits of the same kind keep the step's undo
//! edit, and a stroke's dabs add the points they touch first to it, so the step undoes the whole
//! gesture. The history is bounded by a step count and a memory budget: the oldest steps are dropped
//! first.

use super::edit::{Edit, EditKind, apply};
use super::model::Session;

/// The default number of undo steps kept.
pub const DEFAULT_UNDO_STEPS: usize = 512;
/// The default memory budget of the steps (paint strokes hold their points' values).
pub const DEFAULT_UNDO_BYTES: usize = 256 << 20;

#[derive(Clone, Debug)]
pub struct History {
    /// Applying the last undoes the last step.
    undo: Vec<Edit>,
    /// Applying the last redoes the last undone step.
    redo: Vec<Edit>,
    /// The kind of the step a gesture is still extending.
    open: Option<EditKind>,
    limit: usize,
    budget: usize,
}

impl Default for History {
    fn default() -> Self {
        Self::new(DEFAULT_UNDO_STEPS)
    }
}

impl History {
    pub fn new(limit: usize) -> Self {
        Self::with_budget(limit, DEFAULT_UNDO_BYTES)
    }

    /// At most `limit` steps holding at most `budget` bytes (the newest step is always kept).
    pub fn with_budget(limit: usize, budget: usize) -> Self {
        Self {
            undo: Vec::new(),
            redo: Vec::new(),
            open: None,
            limit: limit.max(1),
            budget,
        }
    }

    /// Applies `edit` to `session` as a new step, or, during a gesture of the same kind, as part of
    /// the open step. Returns false (and changes nothing) when the edit changes nothing.
    pub fn perform(&mut self, session: &mut Session, edit: Edit, gesture: bool) -> bool {
        let kind = edit.kind();
        let inverse = apply(session, edit.clone());
        if inverse == edit {
            self.open = if gesture { self.open } else { None };
            return false;
        }
        self.redo.clear();
        let step = match self.open {
            Some(open) if kind.extends(open) && !self.undo.is_empty() => {
                // The step's undo edit restores the state before the gesture; a dab's undo adds the
                // points the stroke had not touched yet.
                if let (Some(Edit::Paint(step)), Edit::Paint(earlier)) =
                    (self.undo.last_mut(), inverse)
                {
                    step.keep_earliest(*earlier);
                    self.trim();
                }
                open
            }
            _ => {
                self.push(inverse);
                kind
            }
        };
        self.open = gesture.then_some(step);
        true
    }

    fn push(&mut self, undo: Edit) {
        self.undo.push(undo);
        self.trim();
    }

    /// Drops the oldest steps beyond the step count or the memory budget (never the newest).
    fn trim(&mut self) {
        let mut held: usize = self.undo.iter().map(Edit::bytes).sum();
        while self.undo.len() > 1 && (self.undo.len() > self.limit || held > self.budget) {
            held -= self.undo[0].bytes();
            self.undo.remove(0);
        }
    }

    /// Memory the steps hold, bytes.
    pub fn bytes(&self) -> usize {
        self.undo.iter().chain(&self.redo).map(Edit::bytes).sum()
    }

    /// Closes the open gesture (the pointer was released): the next edit starts a new step. A drag
    /// that came back to where it started leaves no step.
    pub fn end_gesture(&mut self, session: &Session) {
        if self.open.take().is_none() {
            return;
        }
        let Some(undo) = self.undo.last_mut() else {
            return;
        };
        let unchanged = match (undo, &session.paint_layer) {
            // A stroke: the points it left as they were need no undo (and the layer no copy to
            // find out).
            (Edit::Paint(delta), Some(layer)) => {
                delta.retain_differing(&layer.get().points);
                delta.indices.is_empty()
            }
            (undo, _) => {
                let mut s = session.clone();
                apply(&mut s, undo.clone()) == *undo
            }
        };
        if unchanged {
            self.undo.pop();
        }
    }

    /// Undoes the last step; returns the edit applied (None: nothing to undo).
    pub fn undo(&mut self, session: &mut Session) -> Option<Edit> {
        self.open = None;
        let edit = self.undo.pop()?;
        self.redo.push(apply(session, edit.clone()));
        Some(edit)
    }

    /// Redoes the last undone step; returns the edit applied.
    pub fn redo(&mut self, session: &mut Session) -> Option<Edit> {
        self.open = None;
        let edit = self.redo.pop()?;
        self.undo.push(apply(session, edit.clone()));
        Some(edit)
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Label of the step Ctrl+Z would undo.
    pub fn undo_label(&self) -> Option<&'static str> {
        self.undo.last().map(Edit::label)
    }

    pub fn clear(&mut self) {
        self.undo.clear();
        self.redo.clear();
        self.open = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn yaw(s: &Session) -> f64 {
        s.env_yaw
    }

    #[test]
    fn a_drag_is_one_step_and_undo_redo_are_exact() {
        let mut s = Session::default();
        let start = yaw(&s);
        let mut h = History::default();
        for y in [10.0, 20.0, 30.0] {
            assert!(h.perform(&mut s, Edit::EnvYaw(y), true));
        }
        h.end_gesture(&s);
        assert!(h.perform(&mut s, Edit::EnvYaw(45.0), false));
        assert_eq!(yaw(&s), 45.0);
        h.undo(&mut s);
        assert_eq!(yaw(&s), 30.0);
        h.undo(&mut s);
        assert_eq!(yaw(&s), start);
        assert!(h.undo(&mut s).is_none());
        h.redo(&mut s);
        assert_eq!(yaw(&s), 30.0);
        h.redo(&mut s);
        assert_eq!(yaw(&s), 45.0);
        assert!(!h.can_redo());
    }

    #[test]
    fn a_new_edit_clears_redo_and_no_op_edits_are_not_steps() {
        let mut s = Session::default();
        let start = yaw(&s);
        let mut h = History::default();
        h.perform(&mut s, Edit::EnvYaw(10.0), false);
        h.undo(&mut s);
        assert!(h.can_redo());
        assert!(!h.perform(&mut s, Edit::EnvYaw(start), false));
        assert!(h.can_redo());
        h.perform(&mut s, Edit::EnvYaw(5.0), false);
        assert!(!h.can_redo());
    }

    #[test]
    fn a_drag_back_to_its_start_leaves_no_step() {
        let mut s = Session::default();
        let start = yaw(&s);
        let mut h = History::default();
        h.perform(&mut s, Edit::EnvYaw(10.0), true);
        h.perform(&mut s, Edit::EnvYaw(start), true);
        h.end_gesture(&s);
        assert!(!h.can_undo());
        assert_eq!(yaw(&s), start);
    }

    #[test]
    fn history_is_bounded() {
        let mut s = Session::default();
        let mut h = History::new(3);
        for y in 1..=5 {
            h.perform(&mut s, Edit::EnvYaw(y as f64), false);
        }
        let mut undone = 0;
        while h.undo(&mut s).is_some() {
            undone += 1;
        }
        assert_eq!(undone, 3);
        assert_eq!(yaw(&s), 2.0);
    }

    #[test]
    fn a_paint_stroke_is_one_step_of_20_bytes_a_point_within_the_budget() {
        use crate::paint::{PaintDelta, PaintLayer, SharedLayer};
        let mut s = Session {
            paint_layer: Some(SharedLayer::new(PaintLayer::empty(1000, 10))),
            ..Default::default()
        };
        let before = s.clone();
        // Three strokes of 100 points each; the budget holds two.
        let step = 100 * 20 + std::mem::size_of::<Edit>();
        let mut h = History::with_budget(100, 2 * step + 10);
        for k in 0..3u32 {
            // A stroke of four dabs over 25 points each: one step.
            for dab in 0..4 {
                let indices: Vec<u32> = (100 * k + 25 * dab..100 * k + 25 * dab + 25).collect();
                let stroke = PaintDelta {
                    values: vec![[1.0, 2.0, 3.0, 0.5 + 0.1 * k as f32]; indices.len()],
                    indices,
                };
                assert!(h.perform(&mut s, Edit::Paint(Box::new(stroke)), true));
            }
            h.end_gesture(&s);
        }
        assert_eq!(
            h.undo.last().map(Edit::bytes),
            Some(step),
            "20 bytes a point"
        );
        assert!(h.bytes() <= 2 * step + 10, "{}", h.bytes());
        let painted = s.clone();
        assert!(h.undo(&mut s).is_some() && h.undo(&mut s).is_some());
        assert!(h.undo(&mut s).is_none(), "the oldest stroke was dropped");
        let first = &s.paint_layer.as_ref().unwrap().get().points;
        assert_eq!(first[0], [1.0, 2.0, 3.0, 0.5], "the first stroke stays");
        assert_eq!(first[150], [0.0; 4], "the second is undone");
        h.redo(&mut s);
        h.redo(&mut s);
        assert!(s == painted, "redo restores the strokes bit for bit");
        assert!(s != before);
    }

    #[test]
    fn a_stroke_that_made_the_layer_undoes_to_no_layer() {
        use crate::paint::{PaintDelta, PaintLayer, SharedLayer};
        let mut s = Session::default();
        let before = s.clone();
        let mut h = History::default();
        let mut layer = PaintLayer::empty(10, 2);
        layer.points[1] = [1.0; 4];
        let made = Edit::PaintLayer(Box::new((Some(SharedLayer::new(layer)), None)));
        assert!(h.perform(&mut s, made, true));
        let dab = PaintDelta {
            indices: vec![2, 3],
            values: vec![[2.0; 4]; 2],
        };
        assert!(h.perform(&mut s, Edit::Paint(Box::new(dab)), true));
        h.end_gesture(&s);
        let painted = s.clone();
        assert_eq!(h.undo_label(), Some("paint layer"));
        h.undo(&mut s);
        assert!(s == before && !h.can_undo(), "one step, back to no layer");
        h.redo(&mut s);
        assert!(s == painted);
    }

    #[test]
    fn a_stroke_replays_from_its_edits_as_data() {
        use crate::paint::{PaintDelta, PaintLayer, SharedLayer};
        let start = Session::default();
        let mut layer = PaintLayer::empty(8, 2);
        layer.points[0] = [0.5; 4];
        let dabs = vec![
            Edit::PaintLayer(Box::new((Some(SharedLayer::new(layer)), None))),
            Edit::Paint(Box::new(PaintDelta {
                indices: vec![0, 5],
                values: vec![[1.0; 4], [2.0; 4]],
            })),
            Edit::Paint(Box::new(PaintDelta {
                indices: vec![5, 6],
                values: vec![[3.0; 4], [4.0; 4]],
            })),
        ];
        let mut s = start.clone();
        let mut h = History::default();
        for e in &dabs {
            assert!(h.perform(&mut s, e.clone(), true));
        }
        h.end_gesture(&s);
        // What autosave or a test would keep: the edits as text, applied to the same start.
        let text = serde_json::to_string(&dabs).unwrap();
        let mut replayed = start.clone();
        for e in serde_json::from_str::<Vec<Edit>>(&text).unwrap() {
            apply(&mut replayed, e);
        }
        assert!(replayed == s, "the replay paints the same layer");
        let points = &replayed.paint_layer.as_ref().unwrap().get().points;
        assert_eq!(
            (points[0], points[5], points[6]),
            ([1.0; 4], [3.0; 4], [4.0; 4])
        );
        h.undo(&mut s);
        assert!(s == start && !h.can_undo(), "one undo step for the stroke");
    }

    #[test]
    fn clearing_the_paint_layer_is_one_step_that_undoes() {
        use crate::paint::{PaintLayer, SharedLayer};
        let mut layer = PaintLayer::empty(4, 1);
        layer.points[2] = [1.0, 0.5, 0.25, 1.0];
        let mut s = Session {
            paint_layer: Some(SharedLayer::new(layer)),
            paint: Some("look.slpaint".into()),
            ..Default::default()
        };
        let painted = s.clone();
        let mut h = History::default();
        assert!(h.perform(&mut s, Edit::PaintLayer(Box::new((None, None))), false));
        assert!(s.paint_layer.is_none() && s.paint.is_none());
        assert!(h.bytes() >= 4 * 16, "the step holds the layer");
        h.undo(&mut s);
        assert!(s == painted);
        h.redo(&mut s);
        assert!(s.paint_layer.is_none());
        // Edits are data: the layer serialises with them.
        let e = Edit::PaintLayer(Box::new((painted.paint_layer.clone(), None)));
        let back: Edit = serde_json::from_str(&serde_json::to_string(&e).unwrap()).unwrap();
        assert_eq!(back, e);
    }
}
