//! Reading the frame's targets back: blocking, or started now and polled ([`FrameReadBack`]).

use super::{RenderError, Renderer};
use crate::gpu::GpuContext;
use crate::render::frame::Frame;
use crate::render::passes::targets::{COMPONENTS, FrameTargets};

/// (width, height, occluder samples, K-buffer slots) of a frame's targets.
type Shape = (u32, u32, u32, u32);

/// What a frame reads besides the always-read buffers.
#[derive(Clone, Copy, Debug)]
pub(super) struct Extras {
    background: bool,
    occluder: bool,
    /// The K-buffer's fragments and summaries (not for a tile of a still: `paste` drops them).
    fragments: bool,
}

/// The buffers a [`Frame`] is read from, in the order [`frame_from_bytes`] takes them: beauty, depth,
/// sample ids, the components, then the K-buffer's, the background and the occluder when there are
/// some.
fn frame_buffers(t: &FrameTargets, extras: Extras) -> Vec<&wgpu::Buffer> {
    let mut v = vec![&t.beauty, &t.view_depth, &t.sample_ids];
    v.extend(t.components.iter());
    if extras.fragments {
        v.extend([&t.kbuffer.fragments, &t.kbuffer.pixel_info]);
    }
    if extras.background {
        v.push(&t.background);
    }
    if extras.occluder {
        v.push(&t.occluder);
    }
    v
}

/// A frame (width, height, samples, fragments per pixel) from its buffers' bytes; the components take
/// the exposure the beauty has.
fn frame_from_bytes(
    (width, height, samples, k): Shape,
    exposure: f32,
    extras: Extras,
    bytes: &[Vec<u8>],
) -> Frame {
    let scale = exposure.exp2();
    let rgb = |b: &Vec<u8>| -> Vec<[f32; 3]> {
        bytemuck::pod_collect_to_vec::<u8, [f32; 4]>(b)
            .into_iter()
            .map(|p| [p[0] * scale, p[1] * scale, p[2] * scale])
            .collect()
    };
    let mut rest = bytes[3 + COMPONENTS.len()..].iter();
    let mut next = |wanted: bool| if wanted { rest.next() } else { None };
    let (fragments, pixel_fragments) = (next(extras.fragments), next(extras.fragments));
    let (background, occluder) = (next(extras.background), next(extras.occluder));
    Frame {
        width,
        height,
        samples,
        beauty: bytemuck::pod_collect_to_vec(&bytes[0]),
        depth: bytemuck::pod_collect_to_vec(&bytes[1]),
        sample_ids: bytemuck::pod_collect_to_vec(&bytes[2]),
        fragments: fragments.map_or_else(Vec::new, |b| bytemuck::pod_collect_to_vec(b)),
        fragments_per_pixel: if extras.fragments { k } else { 0 },
        pixel_fragments: pixel_fragments.map_or_else(Vec::new, |b| bytemuck::pod_collect_to_vec(b)),
        components: bytes[3..3 + COMPONENTS.len()].iter().map(rgb).collect(),
        // Exposed by the resolve already.
        background: background.map_or_else(Vec::new, |b| {
            bytemuck::pod_collect_to_vec::<u8, [f32; 4]>(b)
                .into_iter()
                .map(|p| [p[0], p[1], p[2]])
                .collect()
        }),
        occluder: occluder.map_or_else(Vec::new, rgb),
    }
}

fn shape(t: &FrameTargets) -> Shape {
    (t.width, t.height, t.samples, t.kbuffer.k)
}

/// A frame on its way back from the GPU ([`Renderer::start_read_frame`]).
pub struct FrameReadBack {
    pending: crate::gpu::context::PendingRead,
    shape: Shape,
    exposure: f32,
    extras: Extras,
}

impl FrameReadBack {
    /// The frame once the copies landed (None before; never blocks).
    pub fn poll(&self, ctx: &GpuContext) -> Option<Result<Frame, RenderError>> {
        let bytes = match self.pending.poll(&ctx.device)? {
            Ok(b) => b,
            Err(e) => return Some(Err(RenderError::Gpu(e))),
        };
        Some(Ok(frame_from_bytes(
            self.shape,
            self.exposure,
            self.extras,
            &bytes,
        )))
    }
}

impl Renderer {
    pub(super) fn extras(&self) -> Extras {
        Extras {
            background: self.has_background(),
            occluder: self.scene.occluder.is_some(),
            fragments: true,
        }
    }

    /// Waits for the last frame and reads every output back.
    pub fn read_frame(&self, ctx: &GpuContext) -> Result<Frame, RenderError> {
        self.read_targets(ctx, &self.view.targets)
    }

    /// [`Renderer::read_frame`] without the K-buffer (a tile of a still).
    pub fn read_image(&self, ctx: &GpuContext) -> Result<Frame, RenderError> {
        let extras = Extras {
            fragments: false,
            ..self.extras()
        };
        self.read_with(ctx, &self.view.targets, extras)
    }

    /// Reads every output of `t` (the frame's targets or the preview's) back, waiting for the GPU.
    pub(in crate::render) fn read_targets(
        &self,
        ctx: &GpuContext,
        t: &FrameTargets,
    ) -> Result<Frame, RenderError> {
        self.read_with(ctx, t, self.extras())
    }

    pub(super) fn read_with(
        &self,
        ctx: &GpuContext,
        t: &FrameTargets,
        extras: Extras,
    ) -> Result<Frame, RenderError> {
        let bytes = frame_buffers(t, extras)
            .iter()
            .map(|b| ctx.read_buffer::<u8>(b))
            .collect::<Result<Vec<_>, _>>()
            .map_err(RenderError::Gpu)?;
        Ok(frame_from_bytes(
            shape(t),
            self.settings.exposure,
            extras,
            &bytes,
        ))
    }

    /// Starts reading the frame back without waiting: poll the result once a UI frame.
    pub fn start_read_frame(&self, ctx: &GpuContext) -> FrameReadBack {
        self.start_read(ctx, self.extras())
    }

    /// [`Renderer::start_read_frame`] without the K-buffer (a tile of a still, which keeps only its
    /// image: 8 x K bytes a pixel less to read).
    pub fn start_read_image(&self, ctx: &GpuContext) -> FrameReadBack {
        let extras = Extras {
            fragments: false,
            ..self.extras()
        };
        self.start_read(ctx, extras)
    }

    pub(super) fn start_read(&self, ctx: &GpuContext, extras: Extras) -> FrameReadBack {
        let t = &self.view.targets;
        FrameReadBack {
            pending: ctx.start_read(&frame_buffers(t, extras)),
            shape: shape(t),
            exposure: self.settings.exposure,
            extras,
        }
    }

    /// The shadow grid as built (light-major, logarithms of the transmittances, as
    /// [`crate::shadow::grid::GridValues`] holds them): tests compare it with the CPU twin.
    pub fn read_shadow_grid(
        &self,
        ctx: &GpuContext,
    ) -> Result<Vec<crate::shadow::grid::GridShadow>, RenderError> {
        let v = ctx
            .read_buffer::<[f32; 8]>(&self.scene.shadow_grid.values)
            .map_err(RenderError::Gpu)?;
        Ok(v.into_iter()
            .map(|e| crate::shadow::grid::GridShadow {
                // ln T, the occluder flag in its sign bit (`grid_ln_t_stored`).
                transmittance: -e[0].abs(),
                transmittance_f: [e[1], e[2], e[3]],
                sigma_f2: [e[4], e[5], e[6]],
                depth_behind: e[7],
            })
            .collect())
    }
}
