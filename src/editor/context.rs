//! What a panel sees for one frame (as rerun's `ViewerContext`): the document read-only, the viewport,
//! the messages and jobs, and a queue for the commands it sends. Panels change nothing directly; the
//! app handles the commands after the UI ran.

use super::command::AppCommand;
use super::live_scene::LiveScene;
use super::messages::Messages;
use super::viewport::Viewport;
use crate::gpu::GpuContext;
use crate::session::{History, Session};
use std::cell::RefCell;
use std::path::{Path, PathBuf};

/// The background work the status bar shows.
#[derive(Clone, Copy, Default)]
pub struct JobsView<'a> {
    /// The scene load under way (its label).
    pub loading: Option<&'a str>,
    /// The still export under way: its progress, and whether its files are being written (too late
    /// to cancel).
    pub export: Option<(f32, bool)>,
}

pub struct PanelContext<'a> {
    pub session: &'a Session,
    pub history: &'a History,
    pub session_path: Option<&'a Path>,
    pub modified: bool,
    pub recent: &'a [PathBuf],
    pub viewport: &'a Viewport,
    pub gpu: Option<&'a GpuContext>,
    pub messages: &'a Messages,
    pub jobs: JobsView<'a>,
    /// The UI's own work per frame, smoothed, ms.
    pub frame_ms: f32,
    /// A recovery file of an earlier run on offer: the session file it belongs to (empty: an
    /// unsaved session).
    pub recovery_offer: Option<&'a Path>,
    commands: RefCell<Vec<AppCommand>>,
}

impl<'a> PanelContext<'a> {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        session: &'a Session,
        history: &'a History,
        session_path: Option<&'a Path>,
        modified: bool,
        recent: &'a [PathBuf],
        viewport: &'a Viewport,
        gpu: Option<&'a GpuContext>,
        messages: &'a Messages,
    ) -> Self {
        Self {
            session,
            history,
            session_path,
            modified,
            recent,
            viewport,
            gpu,
            messages,
            jobs: JobsView::default(),
            frame_ms: 0.0,
            recovery_offer: None,
            commands: RefCell::new(Vec::new()),
        }
    }

    /// The live scene shown, if one is installed.
    pub fn live(&self) -> Option<&'a LiveScene> {
        self.viewport.live()
    }

    /// Queues a command for the app (handled after the UI ran, in the order sent).
    pub fn send(&self, command: AppCommand) {
        self.commands.borrow_mut().push(command);
    }

    /// The commands sent this frame.
    pub fn into_commands(self) -> Vec<AppCommand> {
        self.commands.into_inner()
    }
}
