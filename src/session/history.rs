//! Undo and redo of [`Edit`]s: each step keeps the edit that undoes it. A gesture (a slider drag, a
//! colour-picker drag) is one step: while it is open, edits of the same kind replace the step's redo
//! value and keep its undo value (rerun adds undo points only when no drag is in progress). The history
//! is bounded by a step count.

use super::edit::{Edit, EditKind, apply};
use super::model::Session;

/// The default number of undo steps kept.
pub const DEFAULT_UNDO_STEPS: usize = 512;

#[derive(Clone, Debug)]
struct Step {
    /// Applying this undoes the step.
    undo: Edit,
    /// Applying this redoes it.
    redo: Edit,
}

#[derive(Clone, Debug)]
pub struct History {
    undo: Vec<Step>,
    redo: Vec<Step>,
    /// The kind of the step a gesture is still extending.
    open: Option<EditKind>,
    limit: usize,
}

impl Default for History {
    fn default() -> Self {
        Self::new(DEFAULT_UNDO_STEPS)
    }
}

impl History {
    pub fn new(limit: usize) -> Self {
        Self {
            undo: Vec::new(),
            redo: Vec::new(),
            open: None,
            limit: limit.max(1),
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
        match self.undo.last_mut() {
            Some(step) if self.open == Some(kind) => step.redo = edit,
            _ => {
                self.undo.push(Step {
                    undo: inverse,
                    redo: edit,
                });
                if self.undo.len() > self.limit {
                    self.undo.remove(0);
                }
            }
        }
        self.open = gesture.then_some(kind);
        true
    }

    /// Closes the open gesture (the pointer was released): the next edit starts a new step. A drag
    /// that came back to where it started leaves no step.
    pub fn end_gesture(&mut self) {
        if self.open.take().is_some()
            && let Some(step) = self.undo.last()
            && step.undo == step.redo
        {
            self.undo.pop();
        }
    }

    /// Undoes the last step; returns the edit applied (None: nothing to undo).
    pub fn undo(&mut self, session: &mut Session) -> Option<Edit> {
        self.open = None;
        let step = self.undo.pop()?;
        apply(session, step.undo.clone());
        let applied = step.undo.clone();
        self.redo.push(step);
        Some(applied)
    }

    /// Redoes the last undone step; returns the edit applied.
    pub fn redo(&mut self, session: &mut Session) -> Option<Edit> {
        self.open = None;
        let step = self.redo.pop()?;
        apply(session, step.redo.clone());
        let applied = step.redo.clone();
        self.undo.push(step);
        Some(applied)
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Label of the step Ctrl+Z would undo.
    pub fn undo_label(&self) -> Option<&'static str> {
        self.undo.last().map(|s| s.redo.label())
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
        let mut h = History::default();
        for y in [10.0, 20.0, 30.0] {
            assert!(h.perform(&mut s, Edit::EnvYaw(y), true));
        }
        h.end_gesture();
        assert!(h.perform(&mut s, Edit::EnvYaw(45.0), false));
        assert_eq!(yaw(&s), 45.0);
        h.undo(&mut s);
        assert_eq!(yaw(&s), 30.0);
        h.undo(&mut s);
        assert_eq!(yaw(&s), 0.0);
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
        let mut h = History::default();
        h.perform(&mut s, Edit::EnvYaw(10.0), false);
        h.undo(&mut s);
        assert!(h.can_redo());
        assert!(!h.perform(&mut s, Edit::EnvYaw(0.0), false));
        assert!(h.can_redo());
        h.perform(&mut s, Edit::EnvYaw(5.0), false);
        assert!(!h.can_redo());
    }

    #[test]
    fn a_drag_back_to_its_start_leaves_no_step() {
        let mut s = Session::default();
        let mut h = History::default();
        h.perform(&mut s, Edit::EnvYaw(10.0), true);
        h.perform(&mut s, Edit::EnvYaw(0.0), true);
        h.end_gesture();
        assert!(!h.can_undo());
        assert_eq!(yaw(&s), 0.0);
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
}
