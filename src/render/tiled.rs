//! Stills larger than one GPU binding holds (an 8K frame's buffers exceed lavapipe's 128 MiB): the
//! image rendered tile by tile, each through an off-centre narrowing of the full projection
//! ([`Camera::tile_uniform`]), and pasted into one [`Frame`]. The shadow grid is built once and kept
//! across tiles (it does not depend on the camera).

use crate::gpu::GpuContext;
use crate::gpu::context::binding_limit;
use crate::render::camera::{Camera, Tile};
use crate::render::frame::Frame;
use crate::render::passes::kbuffer::KBufferTargets;
use crate::render::renderer::{RenderError, Renderer};

/// Tiles of at most this many pixels a side by default (16 MiB per RGBA float buffer).
pub const DEFAULT_TILE: u32 = 1024;

/// Whether a width x height image with `fragments` K-buffer slots exceeds what the device binds or rasterises at once (then it is
/// rendered in tiles).
pub fn needs_tiles(ctx: &GpuContext, width: u32, height: u32, fragments: u32) -> bool {
    let per_pixel = KBufferTargets::bytes_per_pixel(fragments).max(16);
    width as u64 * height as u64 * per_pixel > binding_limit(&ctx.device)
        || width.max(height) > ctx.device.limits().max_texture_dimension_2d
}

/// The side of the tiles a still with `fragments` K-buffer slots is rendered in: [`DEFAULT_TILE`], or
/// less where a tile's K-buffer would not fit one binding.
pub fn tile_side(ctx: &GpuContext, fragments: u32) -> u32 {
    let per_pixel = KBufferTargets::bytes_per_pixel(fragments).max(16);
    let side = ((binding_limit(&ctx.device) / per_pixel) as f64).sqrt() as u32;
    DEFAULT_TILE.min(side / 16 * 16).max(16)
}

/// An empty full-size frame the tiles are pasted into (96 bytes a pixel: an 8K still needs ~3.2 GB
/// of memory before it is written).
pub fn empty_frame(width: u32, height: u32, samples: u32, components: usize) -> Frame {
    let n = width as usize * height as usize;
    Frame {
        width,
        height,
        samples,
        beauty: vec![[0.0; 4]; n],
        depth: vec![1e10; n],
        sample_ids: vec![[0; 4]; n],
        fragments: Vec::new(),
        fragments_per_pixel: 0,
        pixel_fragments: Vec::new(),
        components: vec![vec![[0.0; 3]; n]; components],
        background: Vec::new(),
        occluder: Vec::new(),
    }
}

/// Copies a tile's frame into the full frame at the tile's origin (not its K-buffer: an 8K still's
/// would take gigabytes).
pub fn paste(full: &mut Frame, tile: &Tile, part: &Frame) {
    let [x0, y0] = tile.origin.map(|v| v as usize);
    let (tw, fw) = (part.width as usize, full.width as usize);
    let n = full.pixel_count();
    for y in 0..part.height as usize {
        let (src, dst) = (y * tw, (y0 + y) * fw + x0);
        full.beauty[dst..dst + tw].copy_from_slice(&part.beauty[src..src + tw]);
        full.depth[dst..dst + tw].copy_from_slice(&part.depth[src..src + tw]);
        full.sample_ids[dst..dst + tw].copy_from_slice(&part.sample_ids[src..src + tw]);
        for (f, p) in full.components.iter_mut().zip(&part.components) {
            f[dst..dst + tw].copy_from_slice(&p[src..src + tw]);
        }
        for (f, p) in [
            (&mut full.background, &part.background),
            (&mut full.occluder, &part.occluder),
        ] {
            if !p.is_empty() {
                if f.is_empty() {
                    *f = vec![[0.0; 3]; n];
                }
                f[dst..dst + tw].copy_from_slice(&p[src..src + tw]);
            }
        }
    }
}

/// Renders `camera`'s width x height still in tiles of at most `tile` pixels a side with `renderer`
/// (whose size becomes each tile's), waiting for each tile (the CLI; the editor's export refines the
/// same tiles progressively).
pub fn render_tiled(
    ctx: &GpuContext,
    renderer: &mut Renderer,
    camera: &Camera,
    width: u32,
    height: u32,
    tile: u32,
) -> Result<Frame, RenderError> {
    let mut full = None;
    for t in Tile::cover(width, height, tile) {
        renderer.set_camera_tile(ctx, camera, t)?;
        renderer.render_frame(ctx);
        let part = renderer.read_image(ctx)?;
        let f = full
            .get_or_insert_with(|| empty_frame(width, height, part.samples, part.components.len()));
        paste(f, &t, &part);
    }
    full.ok_or(RenderError::Size(width, height, 0))
}
