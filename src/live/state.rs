//! The live driver's state in parts: what the renderer has been told, the absorption and its
//! paint, the image shown, the refinement's clock, errors for the UI, and where the scene came from.

use super::prepare::PaintFileCache;
use super::settings::ViewSettings;
use crate::hair::TriangleMesh;
use crate::render::Camera;
use crate::render::passes::background::BackgroundMap;
use crate::render::refine::{ImageReady, Progress};
use crate::session::{EnvironmentSource, HairSource, Look, OccluderOptions, RenderOptions};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// What the renderer was last told.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Applied {
    pub(super) look: Look,
    pub(super) occluder: OccluderOptions,
    pub(super) paint: (Option<std::path::PathBuf>, Option<u64>),
    pub(super) env_yaw: f64,
    pub(super) render: RenderOptions,
    pub(super) camera: Camera,
    /// The fibre thickness scale the renderer's points have.
    pub(super) thickness_scale: f32,
}

/// The absorption the renderer has and where it came from: the look's without paint, the paint
/// file last read, the warnings about it, and a stroke under way.
pub struct PaintState {
    /// The mean absorption of the points (the dual tables' sigma_a), kept while only the look's other
    /// parameters change.
    pub(super) mean_sigma_a: [f64; 3],
    /// Each point's absorption without paint (the brush mixes toward and away from it).
    pub base_sigma_a: Vec<[f32; 3]>,
    /// The session's paint could not be shown (reported once by the app), the last such report, and
    /// the paint file last read.
    pub paint_warning: Option<String>,
    pub(super) last_paint_warning: Option<String>,
    pub(super) paint_file: PaintFileCache,
    /// A dab changed the absorption while a preview was under way: the refinement restarts when
    /// it is done (a restart per dab would never let a preview finish).
    pub(super) paint_restart: bool,
    /// A stroke is under way (its dabs repaint the converged image; the volume and grid follow
    /// once it ends).
    pub(super) painting: bool,
}

/// The image the display shows and the view it shows it in.
pub struct Shown {
    /// Counts the display textures made (each size makes one).
    pub(super) display_generation: u64,
    /// The view the display shows, and the one asked for ([`crate::live::LiveDriver::set_view`]).
    pub(super) view: Option<ViewSettings>,
    pub(super) wanted_view: ViewSettings,
    /// Display passes submitted (each is an image the UI has not drawn yet), and the restart of
    /// the last one.
    pub(super) shown_count: u64,
    pub(super) shown_restart: u64,
    /// The image the display shows, how many previews it has shown, and the full image's sharp rows
    /// it drew over the last.
    pub(super) showing: ImageReady,
    pub(super) shown_sharp: u32,
    pub previews_shown: u64,
    /// The restart whose converged image was displayed.
    pub(super) shown_converged: Option<u64>,
}

/// When the current refinement started, and when its images came.
pub struct RefineClock {
    pub progress: Option<Progress>,
    /// When the current refinement started, and how long it took to converge.
    pub refine_started: Instant,
    pub converged_in: Option<Duration>,
    /// When the preview of the last change was shown, and the full image's first pass.
    pub preview_in: Option<Duration>,
    pub full_image_in: Option<Duration>,
    /// Restarts of the refinement (a change or a refinement of it).
    pub(super) restarts: u64,
}

/// Errors of steps taken on the render thread, for the UI to report.
pub struct Health {
    /// The errors not yet taken; a step failed, and no change has come since; the paint warning
    /// was announced to the UI.
    pub(super) errors: Vec<String>,
    pub(super) failed: bool,
    pub(super) warning_announced: bool,
}

/// Where the hair, head and environment came from.
pub struct Sources {
    pub hair_name: String,
    pub hair_source: HairSource,
    /// The hair's own occluder mesh (an occluder file of the session is brought into the hair's
    /// world space too).
    pub hair_mesh: Option<TriangleMesh>,
    /// The occluder's mesh (the session's file, or the hair's own), shown or not.
    pub(super) occluder_mesh: Option<TriangleMesh>,
    /// What the viewport shows behind the hair (for the unturned lights).
    pub(super) background_map: Arc<BackgroundMap>,
    pub environment_source: EnvironmentSource,
}
