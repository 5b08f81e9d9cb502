//! Autosave and recovery: a recovery file written atomically on a worker 30 s after a change (and on
//! quit when there are unsaved changes), removed when the session is saved; the next start offers it.
//! It is the session's business, not the window's: a [`Job`] does the writing and a wake function
//! (the editor's asks egui for a repaint) says when to look again.
//!
//! Each running editor writes its own file, `recovery-<pid>.slsession` in the state folder, which
//! records the session file it belongs to. At start, files of processes that are no longer running are
//! offered (the newest); a file of a live process belongs to another open editor and is left alone.

use super::io::SessionError;
use super::model::Session;
use crate::files::write_atomic;
use crate::jobs::{Job, Wake};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Why a recovery file could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum AutosaveError {
    #[error("autosave: cannot create {}: {source}", dir.display())]
    CreateDir {
        dir: PathBuf,
        source: std::io::Error,
    },
    #[error("autosave to {}: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: cannot read the recovery file: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a recovery file: {source}", path.display())]
    Format {
        path: PathBuf,
        source: serde_json::Error,
    },
    #[error(transparent)]
    Session(#[from] SessionError),
    /// The worker writing the file stopped without a result.
    #[error("{0}")]
    Worker(String),
}

pub const AUTOSAVE_INTERVAL: Duration = Duration::from_secs(30);
const PREFIX: &str = "recovery-";
const SUFFIX: &str = ".slsession";

/// The recovery file: the session and the file it belongs to.
#[derive(Serialize, Deserialize)]
struct Recovery {
    session_path: Option<PathBuf>,
    session: serde_json::Value,
    /// The paint layer in memory, written beside the recovery file (SLPAINT1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    paint_layer: Option<PathBuf>,
}

/// What a recovery write puts on disk: the JSON, and the paint layer's bytes and file.
struct Contents {
    json: Vec<u8>,
    /// Encoded where it is written (a worker for the periodic writes).
    layer: Option<(PathBuf, crate::paint::SharedLayer)>,
}

pub struct Autosave {
    instance: u32,
    dir: PathBuf,
    /// This editor's recovery file.
    pub path: PathBuf,
    session_path: Option<PathBuf>,
    dirty_since: Option<Instant>,
    pub interval: Duration,
    writing: Option<Job<Result<(), AutosaveError>>>,
    /// The session was saved while a write was in flight: delete the file when it lands.
    delete_when_written: bool,
    /// Recovery files written (tests).
    pub writes: u32,
}

impl Autosave {
    /// `instance`: the process id (tests give other numbers to play several editors).
    pub fn new(dir: PathBuf, session_path: Option<&Path>, instance: u32) -> Self {
        Self {
            instance,
            path: dir.join(format!("{PREFIX}{instance}{SUFFIX}")),
            dir,
            session_path: session_path.map(Path::to_path_buf),
            dirty_since: None,
            interval: AUTOSAVE_INTERVAL,
            writing: None,
            delete_when_written: false,
            writes: 0,
        }
    }

    pub fn set_session_path(&mut self, p: Option<&Path>) {
        self.session_path = p.map(Path::to_path_buf);
    }

    /// The session changed: a recovery file is due one interval from the first unsaved change.
    pub fn changed(&mut self) {
        self.dirty_since.get_or_insert_with(Instant::now);
    }

    fn contents(&self, session: &Session) -> Contents {
        let layer_file = self.path.with_extension("slpaint");
        let layer = session
            .paint_layer
            .as_ref()
            .map(|l| (layer_file.clone(), l.clone()));
        let r = Recovery {
            session_path: self.session_path.clone(),
            session: serde_json::to_value(session).unwrap_or_default(),
            paint_layer: layer.as_ref().map(|_| layer_file),
        };
        Contents {
            json: serde_json::to_vec_pretty(&r).unwrap_or_default(),
            layer,
        }
    }

    /// Removes the recovery file and its paint layer.
    fn remove(&self) {
        remove_recovery(&self.path);
    }

    /// Once a frame: starts the write when due (the worker calls `wake` when it is done). Returns
    /// how long until a write is due, for the caller to look again then; an error when a write
    /// failed (it is retried one interval later).
    pub fn tick(
        &mut self,
        session: &Session,
        wake: &Wake,
    ) -> Result<Option<Duration>, AutosaveError> {
        if let Some(job) = &mut self.writing {
            let Some(result) = job.poll() else {
                return Ok(None);
            };
            self.writing = None;
            if std::mem::take(&mut self.delete_when_written) {
                self.remove();
            }
            match result.map_err(AutosaveError::Worker).and_then(|r| r) {
                Ok(()) => self.writes += 1,
                Err(e) => {
                    self.dirty_since.get_or_insert_with(Instant::now);
                    return Err(e);
                }
            }
        }
        let Some(since) = self.dirty_since else {
            return Ok(None);
        };
        let elapsed = since.elapsed();
        if elapsed < self.interval {
            return Ok(Some(self.interval - elapsed));
        }
        self.dirty_since = None;
        let contents = self.contents(session);
        let path = self.path.clone();
        let wake = wake.clone();
        self.writing = Some(Job::spawn(
            "autosave",
            move || wake(),
            move |_| write_recovery(&path, &contents),
        ));
        Ok(None)
    }

    /// The session was saved: no recovery needed (a write in flight is deleted when it lands).
    pub fn saved(&mut self, session_path: Option<&Path>) {
        self.session_path = session_path.map(Path::to_path_buf);
        self.dirty_since = None;
        self.delete_when_written = self.writing.is_some();
        self.remove();
    }

    /// On quit (or before another session replaces an unsaved one): keep unsaved work in the
    /// recovery file, else remove it.
    pub fn on_exit(&mut self, session: &Session, modified: bool) -> Result<(), AutosaveError> {
        // A write in flight targets the same file: it must land before this one (or the deletion).
        while let Some(job) = &mut self.writing {
            if job.poll().is_some() {
                self.writing = None;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        self.delete_when_written = false;
        // Written (or removed) now: no periodic write is due after this.
        self.dirty_since = None;
        if modified {
            write_recovery(&self.path, &self.contents(session))
        } else {
            self.remove();
            Ok(())
        }
    }

    /// A recovery file left by an editor that is no longer running (the newest): its path, the
    /// session file it belonged to and the session.
    pub fn recovery_found(&self) -> Option<(PathBuf, PathBuf, Session)> {
        let mut found: Vec<(std::time::SystemTime, PathBuf)> = std::fs::read_dir(&self.dir)
            .ok()?
            .filter_map(|e| e.ok())
            .filter_map(|e| {
                let name = e.file_name().to_string_lossy().into_owned();
                let pid = name.strip_prefix(PREFIX)?.strip_suffix(SUFFIX)?;
                let pid: u32 = pid.parse().ok()?;
                if pid == self.instance || process_alive(pid) {
                    return None;
                }
                Some((e.metadata().ok()?.modified().ok()?, e.path()))
            })
            .collect();
        found.sort();
        let (_, file) = found.pop()?;
        let (path, session, _) = read_recovery(&file).ok()?;
        Some((file, path, session))
    }
}

/// A recovery file's session and the session file it belongs to (empty: an unsaved session).
/// A warning comes with it when the layer beside it could not be read (the rest of the work opens).
pub fn read_recovery(file: &Path) -> Result<(PathBuf, Session, Option<String>), AutosaveError> {
    let text = std::fs::read_to_string(file).map_err(|source| AutosaveError::Read {
        path: file.into(),
        source,
    })?;
    let format = |source| AutosaveError::Format {
        path: file.into(),
        source,
    };
    let r: Recovery = serde_json::from_str(&text).map_err(format)?;
    let json = serde_json::to_string(&r.session).map_err(format)?;
    let mut session = Session::from_json(&json, file)?;
    let mut warning = None;
    if let Some(layer) = &r.paint_layer {
        // A missing or damaged layer costs the paint, not the rest of the work.
        match crate::paint::PaintLayer::read(layer) {
            Ok(l) => session.paint_layer = Some(crate::paint::SharedLayer::new(l)),
            Err(e) => {
                warning = Some(format!(
                    "{e}; the recovered session opens with its saved paint instead"
                ));
                let _ = session.load_paint();
            }
        }
    } else {
        // The work had no layer in memory: the paint is the session's file, as saved.
        let _ = session.load_paint();
    }
    Ok((r.session_path.unwrap_or_default(), session, warning))
}

/// Whether a process with this id runs (Linux: /proc; elsewhere assumed gone).
fn process_alive(pid: u32) -> bool {
    Path::new("/proc").join(pid.to_string()).exists()
}

fn write_recovery(path: &Path, contents: &Contents) -> Result<(), AutosaveError> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|source| AutosaveError::CreateDir {
            dir: dir.into(),
            source,
        })?;
    }
    let write = |file: &Path, bytes: &[u8]| {
        write_atomic(file, bytes).map_err(|source| AutosaveError::Write {
            path: file.into(),
            source,
        })
    };
    // The layer first: a recovery file never names a layer that is not there.
    match &contents.layer {
        Some((file, layer)) => write(file, &layer.get().encode())?,
        None => {
            let _ = std::fs::remove_file(path.with_extension("slpaint"));
        }
    }
    write(path, &contents.json)
}

/// Removes a recovery file and the paint layer beside it.
pub fn remove_recovery(file: &Path) {
    let _ = std::fs::remove_file(file);
    let _ = std::fs::remove_file(file.with_extension("slpaint"));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paint::{PaintLayer, SharedLayer};

    #[test]
    fn a_recovery_file_carries_the_paint_layer_and_goes_with_it() {
        let dir = std::env::temp_dir().join(format!("sl-autosave-{}", std::process::id()));
        let mut a = Autosave::new(dir.clone(), Some(Path::new("/x/look.slsession")), 77);
        let mut layer = PaintLayer::empty(6, 2);
        layer.points[3] = [0.1, 0.2, 0.3, 0.5];
        let session = Session {
            paint_layer: Some(SharedLayer::new(layer)),
            ..Default::default()
        };
        a.on_exit(&session, true).unwrap();
        let layer_file = a.path.with_extension("slpaint");
        assert!(a.path.is_file() && layer_file.is_file());
        let (path, back, warning) = read_recovery(&a.path).unwrap();
        assert!(warning.is_none());
        assert_eq!(path, PathBuf::from("/x/look.slsession"));
        assert!(back == session, "the layer comes back");
        // Without a layer the old one goes; saving removes both.
        a.on_exit(&Session::default(), true).unwrap();
        assert!(!layer_file.exists());
        a.on_exit(&session, true).unwrap();
        a.saved(None);
        assert!(!a.path.exists() && !layer_file.exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
