//! Autosave: a recovery file written atomically on a worker 30 s after a change (and on quit when there
//! are unsaved changes), removed when the session is saved; the next start offers it.

use super::jobs::Job;
use crate::session::{Session, write_atomic};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

pub const AUTOSAVE_INTERVAL: Duration = Duration::from_secs(30);
pub const RECOVERY_FILE: &str = "recovery.slsession";

/// The recovery file: the session and the file it belongs to.
#[derive(Serialize, Deserialize)]
struct Recovery {
    session_path: Option<PathBuf>,
    session: serde_json::Value,
}

pub struct Autosave {
    pub path: PathBuf,
    session_path: Option<PathBuf>,
    dirty_since: Option<Instant>,
    pub interval: Duration,
    writing: Option<Job<Result<(), String>>>,
    /// Recovery files written (tests).
    pub writes: u32,
}

impl Autosave {
    pub fn new(dir: PathBuf, session_path: Option<&Path>) -> Self {
        Self {
            path: dir.join(RECOVERY_FILE),
            session_path: session_path.map(Path::to_path_buf),
            dirty_since: None,
            interval: AUTOSAVE_INTERVAL,
            writing: None,
            writes: 0,
        }
    }

    pub fn set_session_path(&mut self, p: Option<&Path>) {
        self.session_path = p.map(Path::to_path_buf);
        self.dirty_since = None;
    }

    /// The session changed: a recovery file is due one interval from the first unsaved change.
    pub fn changed(&mut self) {
        self.dirty_since.get_or_insert_with(Instant::now);
    }

    fn contents(&self, session: &Session) -> Vec<u8> {
        let r = Recovery {
            session_path: self.session_path.clone(),
            session: serde_json::to_value(session).unwrap_or_default(),
        };
        serde_json::to_vec_pretty(&r).unwrap_or_default()
    }

    /// Once a frame: starts the write when due; returns an error message when a write failed.
    pub fn tick(&mut self, session: &Session, ctx: &egui::Context) -> Option<String> {
        if let Some(job) = &mut self.writing {
            match job.poll() {
                Some(Ok(())) => {
                    self.writing = None;
                    self.writes += 1;
                }
                Some(Err(e)) => {
                    self.writing = None;
                    return Some(e);
                }
                None => return None,
            }
        }
        let since = self.dirty_since?;
        let elapsed = since.elapsed();
        if elapsed < self.interval {
            ctx.request_repaint_after(self.interval - elapsed);
            return None;
        }
        self.dirty_since = None;
        let bytes = self.contents(session);
        let path = self.path.clone();
        let wake = ctx.clone();
        self.writing = Some(Job::spawn(
            "autosave",
            move || wake.request_repaint(),
            move |_| write_recovery(&path, &bytes),
        ));
        None
    }

    /// The session was saved: no recovery needed.
    pub fn saved(&mut self, session_path: Option<&Path>) {
        self.session_path = session_path.map(Path::to_path_buf);
        self.dirty_since = None;
        let _ = std::fs::remove_file(&self.path);
    }

    /// On quit: keep unsaved work in the recovery file, else remove it.
    pub fn on_exit(&mut self, session: &Session, modified: bool) -> Result<(), String> {
        if modified {
            write_recovery(&self.path, &self.contents(session))
        } else {
            let _ = std::fs::remove_file(&self.path);
            Ok(())
        }
    }

    /// A recovery file left by an earlier run: the file it belonged to and the session.
    pub fn recovery_found(&self) -> Option<(PathBuf, Session)> {
        let text = std::fs::read_to_string(&self.path).ok()?;
        let r: Recovery = serde_json::from_str(&text).ok()?;
        let session =
            Session::from_json(&serde_json::to_string(&r.session).ok()?, &self.path).ok()?;
        Some((r.session_path.unwrap_or_default(), session))
    }

    /// Deletes the recovery file (the user declined it).
    pub fn discard(&self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

fn write_recovery(path: &Path, bytes: &[u8]) -> Result<(), String> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("autosave: cannot create {}: {e}", dir.display()))?;
    }
    write_atomic(path, bytes).map_err(|e| format!("autosave to {}: {e}", path.display()))
}
