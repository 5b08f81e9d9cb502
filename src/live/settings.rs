//! How the live image is shown and paced: the view transform and exposure of the viewport, the
//! unit budget and its share while tables build, how often a UI is woken, and what one step of the
//! render thread reports.

use crate::gpu::GpuContext;
use crate::render::display::{Solo, ViewTransform};
use std::time::Duration;

/// How the viewport shows the linear image (never the EXR).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewSettings {
    pub transform: ViewTransform,
    /// Viewport exposure, stops, on top of the session's.
    pub exposure: f32,
    /// Render resolution as a fraction of the viewport's pixels.
    pub scale: f32,
    /// The beauty or one component alone.
    pub solo: Solo,
}

impl Default for ViewSettings {
    /// Every pixel of the viewport rendered (a hardware GPU's default).
    fn default() -> Self {
        Self {
            transform: ViewTransform::Filmic,
            exposure: 0.0,
            scale: 1.0,
            solo: Solo::Beauty,
        }
    }
}

impl ViewSettings {
    /// The default view for an adapter: the viewport at full resolution, but half of it on a
    /// software GPU, where the live driver alone took 6.6 s to converge a 10000-strand scene at the
    /// default window's full viewport (654x734; `render --session` 4.8 s) and 4.6 s at half of it
    /// (3.7 s), before the editor's own frames: a first look at every change within a few seconds
    /// matters more there than the last pixel; the resolution buttons raise it.
    pub fn for_adapter(device_type: wgpu::DeviceType) -> Self {
        Self {
            scale: if device_type == wgpu::DeviceType::Cpu {
                SOFTWARE_VIEW_SCALE
            } else {
                1.0
            },
            ..Self::default()
        }
    }
}

/// The default render scale on a software GPU ([`ViewSettings::for_adapter`]).
pub const SOFTWARE_VIEW_SCALE: f32 = 0.5;

/// The viewport's background (display-encoded grey).
pub const BACKGROUND: [f32; 3] = [0.16, 0.16, 0.17];

/// The least time between two UI frames for refinement's progress on a software GPU: there a UI
/// frame (egui's 1280x800 window rasterised and presented by lavapipe) costs ~75 ms of the same two
/// cores the refinement runs on, and frames every 100 ms made the default scene converge in 14 s
/// instead of 8.5 s; two a second keep the UI under a fifth of the machine. A hardware GPU draws at
/// display rate.
pub const SOFTWARE_WAKE_INTERVAL: Duration = Duration::from_millis(500);

/// What one step of the render thread left ([`crate::live::LiveDriver::pump_step`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOutcome {
    /// A unit (or a read-back) is on the GPU: wait for it before the next step.
    pub gpu_busy: bool,
    /// Work remains.
    pub working: bool,
    /// A new image (or a warning) for the UI.
    pub news: bool,
    /// The first image of a change, the converged image or an error: the UI draws it at once.
    pub urgent: bool,
}

/// The refinement unit budget for this adapter: on a software GPU egui's own frames run on the same
/// two cores and cost ~50 ms each, so units of the default 30 ms left the refinement a third of the
/// machine; 35 ms units trade some UI rate for throughput there and keep every unit of the default
/// scene under 50 ms (80 ms until the bands were sized by their segments: a UI frame then waited
/// behind units of up to 0.7 s). A hardware GPU keeps the default.
pub fn unit_budget(ctx: &GpuContext) -> std::time::Duration {
    if ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
        SOFTWARE_UNIT_BUDGET
    } else {
        crate::render::refine::DEFAULT_UNIT_BUDGET
    }
}

pub const SOFTWARE_UNIT_BUDGET: std::time::Duration = std::time::Duration::from_millis(35);

/// The share of the unit budget the refinement's units after the preview get while tables are
/// wanted or built on a worker (`building`): on a software GPU the build takes its cores, and units
/// sized to the whole budget from costs measured without it ran 1.5 times as long (S1's eta edits,
/// whose azimuthal table takes 1.3-1.6 s: units of up to 56-63 ms at 35 ms, lavapipe, two
/// cores). A hardware GPU keeps the whole budget ([`crate::render::Renderer::set_budget_share`]).
pub fn budget_share(ctx: &GpuContext, building: bool) -> f64 {
    if building && ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
        SOFTWARE_SHARE_WHILE_BUILDING
    } else {
        1.0
    }
}

pub const SOFTWARE_SHARE_WHILE_BUILDING: f64 = 2.0 / 3.0;

impl StepOutcome {
    /// Nothing more to do, nothing to show.
    pub fn idle() -> Self {
        Self {
            gpu_busy: false,
            working: false,
            news: false,
            urgent: false,
        }
    }
}
