//! What starts the editor: `strandlight edit`'s options, and what the tests set.

use super::messages::{Level, Messages};
use crate::session::Session;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Clone, Debug, Default)]
pub struct EditorOptions {
    /// A session to open.
    pub session_path: Option<PathBuf>,
    /// The session to start from when no file is given (the default scene, or `--hair` / `--env`).
    pub session: Option<Session>,
    /// Offer the recovery file when one is found (off in tests that do not want the prompt).
    pub offer_recovery: bool,
    /// Where recovery files go (default [`crate::session::io::state_dir`]).
    pub state_dir: Option<PathBuf>,
    /// Names this editor's recovery file (default: the process id; tests play several editors).
    pub instance: Option<u32>,
    /// A recovery file to open at once (`edit --recover`: the restart after a lost GPU device).
    pub recover: Option<PathBuf>,
    /// After a lost GPU device, start a new editor on the recovery file and close this one (off in
    /// tests, which read [`super::EditorApp::relaunch`] instead).
    pub relaunch_on_device_loss: bool,
    /// When the process started (the first scene's times count from it; default: the app's
    /// creation).
    pub launched: Option<Instant>,
    /// Print each change's times to stderr (`edit --log-times`).
    pub log_times: bool,
}

impl EditorOptions {
    /// The session to start with: the file given (its paint too), else the one given, else the
    /// default scene; a file that does not open is reported and the default used.
    pub fn first_session(&self, messages: &mut Messages) -> (Session, Option<PathBuf>) {
        let fallback = || self.session.clone().unwrap_or_default();
        let Some(path) = &self.session_path else {
            return (fallback(), None);
        };
        match Session::read(path) {
            Ok(mut s) => {
                if let Err(e) = s.load_paint() {
                    messages.push(Level::Warning, format!("{e}; the hair is shown unpainted"));
                }
                (s, Some(path.clone()))
            }
            Err(e) => {
                messages.push(Level::Error, e.to_string());
                (fallback(), None)
            }
        }
    }
}
