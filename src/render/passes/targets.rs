//! Per-frame GPU targets sized by the image: the multisampled visibility (the occluder's ids) and
//! depth textures, the hair's K-buffer, the per-component accumulation buffers and the resolved
//! outputs.

use crate::render::passes::kbuffer::{KBufferTargets, Tail};

/// Component buffers, in order: R, TT, TRT, MS.global, MS.local (linear radiance, coverage-weighted).
pub const COMPONENTS: [&str; 5] = ["R", "TT", "TRT", "MS.global", "MS.local"];

/// The occluder's -(triangle + 1) as an exact float (R32Uint cannot be multisampled without
/// adapter-specific features; every integer up to 2^24 is exact in f32).
pub const VISIBILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// The most segments a hair may have (ids are u32 everywhere; this keeps ids exact in f32, a bound
/// the buffers' sizes reach first anyway).
pub const MAX_SEGMENTS: u32 = 1 << 24;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

pub struct FrameTargets {
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    pub visibility: wgpu::TextureView,
    pub depth: wgpu::TextureView,
    pub components: [wgpu::Buffer; 5],
    pub beauty: wgpu::Buffer,
    pub view_depth: wgpu::Buffer,
    pub sample_ids: wgpu::Buffer,
    /// The environment behind every pixel, exposed (RGB, A = 1; zero without a background map).
    pub background: wgpu::Buffer,
    /// The occluder's radiance, coverage-weighted like the components (zero without one).
    pub occluder: wgpu::Buffer,
    /// The hair's fragments.
    pub kbuffer: KBufferTargets,
}

impl FrameTargets {
    /// Targets for a width x height image, `samples` occluder samples per pixel and `fragments` hair
    /// fragments kept per pixel.
    pub fn new(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        samples: u32,
        (fragments, tail): (u32, Tail),
    ) -> Self {
        let texture = |label: &str, format| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width,
                        height,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        let pixels = width as u64 * height as u64;
        let buffer = |label: &str, bytes: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: pixels * bytes,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        Self {
            width,
            height,
            samples,
            visibility: texture("visibility", VISIBILITY_FORMAT),
            depth: texture("depth", DEPTH_FORMAT),
            components: COMPONENTS.map(|c| buffer(c, 16)),
            beauty: buffer("beauty", 16),
            view_depth: buffer("view depth", 4),
            sample_ids: buffer("sample ids", 16),
            background: buffer("background", 16),
            occluder: buffer("occluder", 16),
            kbuffer: KBufferTargets::new(device, width, height, fragments, tail),
        }
    }
}
