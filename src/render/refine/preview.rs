//! The preview that progressive refinement shows right after a change: the same view at a fraction of
//! the resolution, every light, a K-buffer of four fragments, each shaded (the rest spread over them), shadows from the
//! grid as it stands (a light group whose entries are part-way through a rebuild is shaded
//! unshadowed). Its own small frame targets and camera (shaded by segment, it writes the frame's
//! segment buffers, which the frame's visibility unit clears before the frame shades), so the
//! converged image is still `render_frame`'s. In [`PreviewMode::Auto`] the resolution divisor adapts so that the
//! preview's shading takes about [`preview_target`] of the unit budget. A coarse preview of dense
//! hair draws a quarter of the strands (`Renderer::preview_subset`).

use crate::gpu::GpuContext;
use crate::render::camera::CameraUniform;
use crate::render::frame::Frame;
use crate::render::passes::batch::{ShadeBatch, ShadingInputs};
use crate::render::passes::kbuffer::{SegmentSubset, Tail};
use crate::render::passes::shading::{
    FLAG_MULTIPLE_SCATTERING, FLAG_SEGMENTS, FLAG_SHADOWS, ShadingPass,
};
use crate::render::passes::targets::FrameTargets;
use crate::render::renderer::{RenderError, Renderer};
use std::time::Duration;

/// The preview's K-buffer: four fragments, each shaded, the rest spread over them (one fragment
/// standing for a preview pixel's dozens of fibres made a speckled picture).
const PREVIEW_FRAGMENTS: u32 = 4;

/// Whether, and at what resolution, refinement previews a change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PreviewMode {
    /// No preview (the CLI and `render_frame` users).
    #[default]
    Off,
    /// The image's width and height divided by this (1: no preview).
    Fixed(u32),
    /// A divisor adapted to the measured preview time (the editor).
    Auto,
}

/// The longest shading time an automatic preview aims at, in one unit (the first preview after a
/// change should show within 0.25 s on lavapipe; the rest is the unit in flight when the change
/// comes and the UI frame). On lavapipe this puts the default scene's divisor near Blender's 8-pixel
/// start.
pub const PREVIEW_TARGET: Duration = Duration::from_millis(150);

/// The preview's time target under a unit budget (its shading, which the automatic divisor adapts
/// to): twice the budget, at most [`PREVIEW_TARGET`] (the editor's 35 ms units on a software GPU give
/// 70 ms; 30 ms units on a hardware one, 60 ms). Before its rows' segments are counted, a preview
/// band may take this long (one unit instead of two is a UI frame sooner); counted, its bands keep
/// to the unit budget.
pub fn preview_target(budget: Duration) -> Duration {
    (2 * budget).min(PREVIEW_TARGET).max(budget)
}
/// Pixels of the first automatic preview, before its time is measured.
pub const PREVIEW_PIXELS: u32 = 6_000;
/// A preview at this divisor or coarser is thinned (`Renderer::preview_subset`).
pub const THIN_PREVIEW_FACTOR: u32 = 8;
/// A thinned preview draws one strand in this many, as wide as all of them.
pub const PREVIEW_STRAND_STRIDE: u32 = 4;
/// Hairs with fewer strands are never thinned (the gaps would show).
pub const THIN_PREVIEW_STRANDS: usize = 4000;
/// The coarsest preview (a divisor).
pub const MAX_PREVIEW_FACTOR: u32 = 16;

/// The preview's targets and camera.
pub(in crate::render) struct Preview {
    pub factor: u32,
    pub targets: FrameTargets,
    pub camera: wgpu::Buffer,
    /// The visibility pass has drawn the current camera (a parameter change reuses it).
    pub visible: bool,
    /// Its K-buffer's visible segments per row ([`crate::render::passes::row_segments`]) and their read-back.
    pub row_segments: Option<Vec<u32>>,
    pub row_readback: Option<crate::render::passes::row_segments::RowSegmentsReadback>,
}

impl Preview {
    /// The preview size of a `width` x `height` image at divisor `factor`.
    pub fn size(width: u32, height: u32, factor: u32) -> (u32, u32) {
        let f = factor.max(1);
        (width.div_ceil(f), height.div_ceil(f))
    }
}

impl Renderer {
    /// Whether changes are previewed (the editor: [`PreviewMode::Auto`]).
    pub fn set_preview(&mut self, mode: PreviewMode) {
        if mode != self.preview_mode {
            self.preview_mode = mode;
            self.replan();
        }
    }

    /// The image size changed: the preview's targets go (made again at the new size), and the
    /// automatic divisor scales with the image's side so the preview keeps its cost.
    pub(in crate::render) fn resized_preview(&mut self, width: u32, height: u32) {
        self.preview = None;
        // Adapted at the old size.
        self.refinement.preview_state.deferred_factor = None;
        let old = self.settings.width as f64 * self.settings.height as f64;
        let new = width as f64 * height as f64;
        if let Some(f) = &mut self.refinement.preview_state.auto_factor {
            let scaled = (*f as f64 * (new / old.max(1.0)).sqrt()).round() as u32;
            *f = scaled.clamp(2, MAX_PREVIEW_FACTOR);
        }
    }

    /// The preview's resolution divisor now (1: none; tiles of a still are never previewed).
    pub fn preview_factor(&self) -> u32 {
        if self.view.tile.is_some() {
            return 1;
        }
        let pixels = self.settings.width as f64 * self.settings.height as f64;
        let first = (pixels / PREVIEW_PIXELS as f64).sqrt().ceil() as u32;
        match self.preview_mode {
            PreviewMode::Off => 1,
            PreviewMode::Fixed(f) => f.max(1),
            PreviewMode::Auto if first < 2 => 1,
            PreviewMode::Auto => self
                .refinement
                .preview_state
                .auto_factor
                .unwrap_or(first)
                .clamp(2, MAX_PREVIEW_FACTOR),
        }
    }

    /// Makes the preview's targets for the current size and divisor; its height, or None when there
    /// is no preview.
    pub(in crate::render) fn prepare_preview(&mut self, device: &wgpu::Device) -> Option<u32> {
        let factor = self.preview_factor();
        if factor < 2 {
            return None;
        }
        let (w, h) = Preview::size(self.settings.width, self.settings.height, factor);
        let fits = self
            .preview
            .as_ref()
            .is_some_and(|p| p.factor == factor && (p.targets.width, p.targets.height) == (w, h));
        if !fits {
            let camera = self.preview_camera(factor);
            self.preview = Some(Preview {
                factor,
                targets: FrameTargets::new(
                    device,
                    w,
                    h,
                    self.settings.samples,
                    (PREVIEW_FRAGMENTS, Tail::Spread),
                ),
                camera: crate::gpu::context::buffer_init(
                    device,
                    "preview camera",
                    bytemuck::bytes_of(&camera),
                    wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                ),
                visible: false,
                row_segments: None,
                row_readback: None,
            });
            self.refinement.costs.preview_bands_reset();
        }
        Some(h)
    }

    /// The preview's camera: the frame's view at the preview's size, its least fibre width (when the
    /// settings ask for one) the frame's in the scene (a preview pixel's 1/factor); a thinned
    /// preview's ribbons as wide as the strands each stands for.
    fn preview_camera(&self, factor: u32) -> CameraUniform {
        let (w, h) = Preview::size(self.settings.width, self.settings.height, factor);
        let mut c = self
            .view
            .camera_view
            .uniform(w, h, self.settings.min_width_px / factor as f32);
        if let Some(s) = self.preview_subset(factor) {
            c.width_scale = s.stride as f32;
        }
        c
    }

    /// The strands a preview at divisor `factor` draws, when it is thinned: one in
    /// [`PREVIEW_STRAND_STRIDE`] at [`THIN_PREVIEW_FACTOR`] or coarser, of a hair with at least
    /// [`THIN_PREVIEW_STRANDS`] strands. A preview pixel then spans 8 x 8 or more of the frame's and
    /// its visibility pass (nearly all of a new view's preview time) draws a quarter of the segments.
    pub(in crate::render) fn preview_subset(&self, factor: u32) -> Option<&SegmentSubset> {
        self.scene
            .preview_strands
            .as_ref()
            .filter(|_| factor >= THIN_PREVIEW_FACTOR)
    }

    /// The segments the preview's visibility pass draws.
    pub(in crate::render) fn preview_draw_count(&self) -> u32 {
        self.preview_draws_at(self.preview.as_ref().map_or(1, |p| p.factor))
    }

    /// The segments a preview at divisor `factor` draws.
    fn preview_draws_at(&self, factor: u32) -> u32 {
        self.preview_subset(factor)
            .map_or(self.scene.hair.segment_count, |s| s.count)
    }

    /// Whether the preview's visibility shows the current camera.
    pub(in crate::render) fn preview_visible(&self) -> bool {
        self.preview.as_ref().is_some_and(|p| p.visible)
    }

    /// The camera, the image size or the fibres' width changed: both visibility passes must run again.
    pub(in crate::render) fn invalidate_visibility(&mut self) {
        self.stale.visibility_valid = false;
        self.forget_row_segments();
        // The preview draws its visibility anyway: a divisor that waited for it applies.
        if let Some(f) = self.refinement.preview_state.deferred_factor.take() {
            self.refinement.preview_state.auto_factor = Some(f);
        }
        if let Some(p) = &mut self.preview {
            p.visible = false;
        }
    }

    /// Encodes the preview's visibility pass with the current camera.
    pub(in crate::render) fn encode_preview_visibility(
        &mut self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        range: std::ops::Range<u32>,
    ) {
        let Some(p) = &self.preview else {
            return;
        };
        if range.start == 0 {
            let camera = self.preview_camera(p.factor);
            ctx.queue
                .write_buffer(&p.camera, 0, bytemuck::bytes_of(&camera));
        }
        let last = range.end >= self.preview_draw_count();
        self.passes.visibility_pass.encode(
            &ctx.device,
            enc,
            &p.camera,
            &self.scene.hair,
            self.scene.occluder.as_ref().map(|o| &o.gpu),
            &p.targets,
            range,
            self.preview_subset(p.factor),
            None,
        );
        if last && let Some(p) = &mut self.preview {
            p.visible = true;
        }
        if last {
            self.encode_preview_row_segments(&ctx.device, enc);
        }
    }

    /// Encodes preview rows [row0, row0 + rows) (the first unit clears the preview's components):
    /// every light batch, then the rows' resolve. Shaded as the frame is: by segment when the frame
    /// shades segments (a segment's shading does not depend on the image's resolution, only on the
    /// eye), in the frame's segment buffers, whose markers the first unit clears (the frame's
    /// visibility unit clears them again before the frame shades); else per fragment, one dispatch
    /// per K-buffer slot.
    pub(in crate::render) fn encode_preview(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        row0: u32,
        rows: u32,
    ) {
        let Some(p) = &self.preview else {
            return;
        };
        let device = &ctx.device;
        let segments = self
            .view
            .segment_targets
            .as_ref()
            .filter(|_| self.by_segment);
        if row0 == 0 {
            ShadingPass::clear(enc, &p.targets, segments);
        }
        let inputs = ShadingInputs {
            camera: &p.camera,
            segment_targets: segments,
            ..self.shading_inputs()
        };
        let batches = ShadingPass::batches(self.scene.light_count, self.settings.lights_per_pass);
        for (b, (first, count)) in batches.into_iter().enumerate() {
            let partial = self
                .refinement
                .grid
                .partial
                .get(b)
                .copied()
                .unwrap_or(false);
            let mut flags = 0;
            if self.settings.shadows && !partial {
                flags |= FLAG_SHADOWS;
            }
            if self.settings.multiple_scattering {
                flags |= FLAG_MULTIPLE_SCATTERING;
            }
            if segments.is_some() {
                flags |= FLAG_SEGMENTS;
            }
            let slots = if segments.is_some() {
                1
            } else {
                PREVIEW_FRAGMENTS
            };
            for slot in 0..slots {
                let batch = ShadeBatch {
                    first,
                    count,
                    flags,
                    slots: PREVIEW_FRAGMENTS,
                    slot,
                    row0,
                    rows,
                    lights: self.scene.light_count,
                };
                self.passes
                    .shading_pass
                    .encode_batch(device, enc, &inputs, &p.targets, &batch, None);
            }
        }
        self.passes.resolve_pass.encode(
            device,
            enc,
            &p.camera,
            &self.view.resolve_info,
            &self.scene.background_map,
            &p.targets,
            row0..row0 + rows,
            (true, false),
            None,
        );
    }

    /// A preview of this change took `preview_time` (its units): the automatic divisor moves
    /// towards [`preview_target`] (time goes with the pixels, the square of the divisor).
    pub(in crate::render) fn adapt_preview(&mut self, preview_time: Duration) {
        if self.preview_mode != PreviewMode::Auto {
            return;
        }
        let f = self.preview_factor();
        if f < 2 {
            return;
        }
        let target = preview_target(self.refinement.costs.budget()).as_secs_f64();
        let ideal = f as f64 * (preview_time.as_secs_f64() / target).sqrt();
        let next = if ideal > 1.25 * f as f64 || ideal < 0.7 * f as f64 {
            (ideal.ceil() as u32).clamp(2, MAX_PREVIEW_FACTOR)
        } else {
            f
        };
        // A new divisor draws the preview's visibility again. Where it still shows this view and
        // the preview is not far over its target, the change waits for the next camera move unless
        // the shading it saves the next preview outweighs that redraw (a finer divisor, which costs
        // more, waits).
        let visible = self.preview.as_ref().is_some_and(|p| p.visible);
        let r = &self.refinement;
        let redraw = r.costs.preview_visibility_cost.unwrap_or(f64::INFINITY)
            * self.preview_draws_at(next) as f64;
        let seconds = preview_time.as_secs_f64();
        let saving = seconds * (1.0 - (f as f64 / next as f64).powi(2));
        if next != f && visible && saving <= redraw && seconds <= 1.5 * target {
            self.refinement.preview_state.deferred_factor = Some(next);
        } else {
            self.refinement.preview_state.auto_factor = Some(next);
            self.refinement.preview_state.deferred_factor = None;
        }
    }

    /// The last preview as drawn (None: no preview made yet) with the current camera at its size
    /// (the one it was drawn with unless the camera moved since; tests: the CPU twin shades its
    /// fragments). A thinned preview's camera has its `width_scale`: its K-buffer holds only the
    /// listed strands' fragments (`Renderer::preview_subset`).
    pub fn read_preview(
        &self,
        ctx: &GpuContext,
    ) -> Result<Option<(Frame, CameraUniform)>, RenderError> {
        match &self.preview {
            None => Ok(None),
            Some(p) => Ok(Some((
                self.read_targets(ctx, &p.targets)?,
                self.preview_camera(p.factor),
            ))),
        }
    }
}
