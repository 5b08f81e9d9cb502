//! The document: the session, the file it belongs to, its undo history, the session as last saved
//! (what "modified" compares against) and its recovery file. Every change of the session goes through
//! here: edits through [`Document::perform`] (the one place `session::apply` is called for the
//! editor, by way of the history), camera moves through [`Document::set_camera`] (saved, not undone).

use crate::jobs::Wake;
use crate::session::autosave::{self, Autosave, AutosaveError};
use crate::session::{Edit, History, Session, SessionError, ViewCamera};
use std::path::{Path, PathBuf};
use std::time::Duration;

pub struct Document {
    session: Session,
    path: Option<PathBuf>,
    history: History,
    /// The session as last saved or opened.
    saved: Session,
    autosave: Autosave,
}

impl Document {
    /// `saved`: what the session is unmodified against (the file's session, or the one given).
    pub fn new(session: Session, path: Option<PathBuf>, autosave: Autosave) -> Self {
        Self {
            saved: session.clone(),
            session,
            path,
            history: History::default(),
            autosave,
        }
    }

    pub fn session(&self) -> &Session {
        &self.session
    }

    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    pub fn history(&self) -> &History {
        &self.history
    }

    pub fn autosave(&self) -> &Autosave {
        &self.autosave
    }

    pub fn autosave_mut(&mut self) -> &mut Autosave {
        &mut self.autosave
    }

    /// Whether the session differs from the file it was opened from or saved to.
    pub fn modified(&self) -> bool {
        self.session != self.saved
    }

    /// Applies an edit as an undo step (`gesture`: part of a drag or a stroke that continues);
    /// false when it changed nothing.
    pub fn perform(&mut self, edit: Edit, gesture: bool) -> bool {
        let changed = self.history.perform(&mut self.session, edit, gesture);
        if changed {
            self.autosave.changed();
        }
        changed
    }

    /// Undoes the last step; returns the edit applied.
    pub fn undo(&mut self) -> Option<Edit> {
        let e = self.history.undo(&mut self.session)?;
        self.autosave.changed();
        Some(e)
    }

    /// Redoes the last undone step; returns the edit applied.
    pub fn redo(&mut self) -> Option<Edit> {
        let e = self.history.redo(&mut self.session)?;
        self.autosave.changed();
        Some(e)
    }

    /// The gesture under way ended (the pointer was released, a stroke ended).
    pub fn end_gesture(&mut self) {
        self.history.end_gesture(&self.session);
    }

    /// The camera moved (not an edit; saved with the session).
    pub fn set_camera(&mut self, camera: ViewCamera) {
        if camera != self.session.camera {
            self.session.camera = camera;
            self.autosave.changed();
        }
    }

    /// The camera follows the hair again (no explicit target or distance): a new hair, Home.
    pub fn unframe(&mut self) {
        self.session.camera.target = None;
        self.session.camera.distance = None;
        self.autosave.changed();
    }

    /// Another session replaces this one (opened from `path`): no history, unmodified.
    pub fn replace(&mut self, session: Session, path: &Path) {
        self.saved = session.clone();
        self.session = session;
        self.path = Some(path.to_path_buf());
        self.history.clear();
        self.autosave.set_session_path(Some(path));
    }

    /// Keeps unsaved work in the recovery file (before another session replaces it); returns the
    /// file, None when there was nothing unsaved.
    pub fn keep_unsaved(&mut self) -> Result<Option<PathBuf>, AutosaveError> {
        if !self.modified() {
            return Ok(None);
        }
        self.autosave.on_exit(&self.session, true)?;
        Ok(Some(self.autosave.path.clone()))
    }

    /// Saves to `path` (atomically); the session is then unmodified and needs no recovery file.
    pub fn save(&mut self, path: &Path) -> Result<(), SessionError> {
        self.session.save(path)?;
        self.saved = self.session.clone();
        self.path = Some(path.to_path_buf());
        self.autosave.saved(Some(path));
        Ok(())
    }

    /// Takes over a recovery file's session: the session file it belongs to becomes this
    /// document's, and the work is kept in this editor's own recovery file before the old one is
    /// removed.
    pub fn adopt_recovery(
        &mut self,
        file: &Path,
        path: PathBuf,
        session: Session,
    ) -> Result<(), AutosaveError> {
        self.path = (!path.as_os_str().is_empty()).then_some(path);
        // Unmodified means equal to the file it belongs to, as it is on disk now.
        self.saved = self
            .path
            .as_deref()
            .and_then(|p| Session::read(p).ok())
            .map(|mut s| {
                // An unreadable layer leaves the saved session unpainted: the recovered work then
                // counts as modified, which keeps it safe.
                let _ = s.load_paint();
                s
            })
            .unwrap_or_default();
        self.session = session;
        self.autosave.set_session_path(self.path.as_deref());
        self.history.clear();
        self.autosave.changed();
        self.autosave.on_exit(&self.session, true)?;
        if file != self.autosave.path {
            autosave::remove_recovery(file);
        }
        Ok(())
    }

    /// Once a frame: the recovery file's periodic write. Returns how long until one is due.
    pub fn autosave_tick(&mut self, wake: &Wake) -> Result<Option<Duration>, AutosaveError> {
        self.autosave.tick(&self.session, wake)
    }

    /// The editor closes (or its device was lost): unsaved work goes to the recovery file, else
    /// the file is removed.
    pub fn closing(&mut self, keep: bool) -> Result<(), AutosaveError> {
        let modified = keep || self.modified();
        self.autosave.on_exit(&self.session, modified)
    }
}
