//! What the panels, the tools and the shortcuts ask of the app, as data: panels change nothing
//! themselves, they send [`AppCommand`]s that the app handles in one place after the UI ran (as
//! rerun's `SystemCommand`s). Session changes among them are [`Edit`]s, applied by the document's
//! history like every other edit.

use crate::render::Camera;
use crate::session::Edit;
use std::path::PathBuf;

#[derive(Clone, Debug)]
pub enum AppCommand {
    /// An edit of the session (`gesture`: part of a drag that continues).
    Edit {
        edit: Edit,
        gesture: bool,
    },
    Undo,
    Redo,
    /// A file dialog; what it picks becomes one of the commands below.
    Dialog(Dialog),
    OpenSession(PathBuf),
    /// Save to the session's file, or ask where when it has none.
    Save,
    SaveSession(PathBuf),
    OpenHair(PathBuf),
    OpenOccluder(PathBuf),
    /// An environment file, fitted with `lights` SRBF lights when it is an image.
    LoadEnvironment {
        path: PathBuf,
        lights: usize,
    },
    /// The session's still to `exr` (and a PNG beside it), in tiles of at most `tile` pixels a side
    /// (None: tiles only where the image needs them).
    ExportStill {
        exr: PathBuf,
        tile: Option<u32>,
    },
    ExportHair(PathBuf),
    CancelExport,
    /// Load the session's scene anew (the built-in environment after a file's).
    ReloadScene,
    /// The camera frames the hair again (Home).
    FrameHair,
    /// The camera moved (saved with the session, not an undo step).
    SetCamera(Camera),
    SetView(crate::live::ViewSettings),
    /// The viewport was laid out: its rectangle in points and its size in physical pixels.
    ViewportLaidOut {
        rect: egui::Rect,
        px: [u32; 2],
    },
    /// The brush's pointer over the viewport.
    Stroke(StrokeInput),
    /// The stroke under way ends (a tool change, an adjustment of the brush).
    EndStroke,
    /// Remove the paint layer (one undo step).
    ClearPaint,
    /// The recovery file on offer: take it over, or delete it.
    Recover,
    DiscardRecovery,
    /// The errors window was closed.
    DismissErrors,
}

/// A press, a drag to `to` or a release of the primary button over the viewport with the brush
/// active: `to` in render pixels, `pressure` in [0, 1] (1 without a tablet).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrokeInput {
    pub to: Option<[f32; 2]>,
    pub pressed: bool,
    pub released: bool,
    pub pressure: f32,
}

/// The file dialogs behind the menu and the shortcuts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dialog {
    OpenSession,
    SaveAs,
    OpenHair,
    OpenOccluder,
    OpenEnvironment,
    ExportStill,
    ExportHair,
}

/// SRBF lights fitted to an environment image opened in the editor.
pub const DEFAULT_LIGHTS: usize = 40;
