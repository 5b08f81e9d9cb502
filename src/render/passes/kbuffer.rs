//! The ordered K-buffer pass (Yu et al. 2012, Secs. 4 and 5: translucency and anti-aliasing of hair),
//! `shaders/kbuffer.wgsl`: every segment is a ribbon of the fiber's true width; each pixel it touches
//! gets a fragment whose opacity is the exact area of the ribbon inside the pixel square (a box
//! filter, so a fiber a tenth of a pixel wide covers a tenth of the pixels it crosses) times the share
//! of the occluder's depth samples behind it. The K nearest fragments of every pixel are kept in order
//! by a chain of 64-bit atomic maxima (independent of the order of insertion); every fragment's optical
//! depth −ln(1 − opacity) is summed in fixed point. The composite weighs the kept fragments front to
//! back, w_i = a_i Π_{j<i} (1 − a_j), and gives the opacity of all the fragments behind the K-th to the
//! K-th ([`Tail::Fold`]) or to all the kept ones ([`Tail::Spread`]), so the pixel's alpha counts every
//! fragment. The CPU twins are [`crate::render::reference::ribbon`] (coverage) and
//! [`crate::render::reference::abuffer`] (every fragment, sorted).

use crate::gpu::context::compute_pipeline;
use crate::gpu::fiber_density::GpuHair;
use crate::gpu::shaders;
use bytemuck::{Pod, Zeroable};

/// Pixels the drawn ribbon is grown by on every side (a pixel the true ribbon touches has its centre
/// within √2 / 2 of it).
pub const EXPAND_PX: f32 = 0.75;
/// Fixed-point units of optical depth in the pixel sums.
pub const OPTICAL_DEPTH_SCALE: f32 = 16384.0;
/// A fragment's opacity is at most this (its optical depth stays finite).
pub const MAX_FRAGMENT_OPACITY: f32 = 0.999_755_86;
/// The default fragments kept per pixel, chosen from the K against A-buffer curve (tests/kbuffer.rs,
/// a 2000-strand bob at 720x480, relative RMSE over hair pixels with the spread tail: K = 8 15.8 %,
/// 16 6.0 %, 20 3.7 %, 32 0.8 %, shading 5.8, 8.2, 8.8 and 9.7 fragments a hair pixel).
pub const DEFAULT_FRAGMENTS: u32 = 20;
/// The most fragments a pixel may keep.
pub const MAX_FRAGMENTS: u32 = 32;

/// What becomes of the fragments behind the K kept.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tail {
    /// Dropped (Yu 2012): the pixel's alpha counts the K kept fragments only.
    Drop,
    /// Folded into the K-th fragment: its weight takes the opacity of everything behind it.
    Fold,
    /// Spread over the kept fragments in proportion to their weights (the tail takes their mean
    /// radiance).
    #[default]
    Spread,
}

impl std::str::FromStr for Tail {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "drop" => Ok(Tail::Drop),
            "fold" => Ok(Tail::Fold),
            "spread" => Ok(Tail::Spread),
            _ => Err(format!("unknown tail '{s}' (drop, fold or spread)")),
        }
    }
}

/// The K-buffer passes' parameters (a storage buffer, as the occluder's).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct KBufferInfo {
    pub k: u32,
    pub tail: u32,
    /// 1: an occluder was drawn into the depth the passes read.
    pub occluder: u32,
    pub _p1: u32,
}

const _: () = assert!(std::mem::size_of::<KBufferInfo>() == 16);

impl KBufferInfo {
    pub fn new(k: u32, tail: Tail, occluder: bool) -> Self {
        Self {
            k,
            tail: tail as u32,
            occluder: occluder as u32,
            _p1: 0,
        }
    }
}

/// One kept fragment as the composite writes it: segment + 1 (0: none) and its weight.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Fragment {
    pub id: u32,
    pub weight: f32,
}

const _: () = assert!(std::mem::size_of::<Fragment>() == 8);

/// A pixel's K-buffer summary.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PixelFragments {
    /// The hair's composited coverage (the sum of the kept fragments' weights).
    pub alpha: f32,
    /// Transmittance of the hair in front of the occluder's nearest sample (1 without one).
    pub occluder_transmittance: f32,
    /// View depth of the nearest fragment (1e10: none).
    pub depth: f32,
    /// Fragments drawn into the pixel (kept or not).
    pub count: f32,
}

const _: () = assert!(std::mem::size_of::<PixelFragments>() == 16);

/// The K-buffer's GPU buffers, per frame target.
pub struct KBufferTargets {
    pub k: u32,
    /// The image's size (the composite's dispatch).
    pub width: u32,
    pub height: u32,
    /// Per pixel, k inverted keys (u64).
    pub keys: wgpu::Buffer,
    /// Per pixel, four u32 sums.
    pub sums: wgpu::Buffer,
    /// Per pixel, k [`Fragment`]s.
    pub fragments: wgpu::Buffer,
    /// Per pixel, a [`PixelFragments`].
    pub pixel_info: wgpu::Buffer,
    /// The raster pass's attachment (nothing is written to it).
    pub raster_target: wgpu::TextureView,
    pub tail: Tail,
}

impl KBufferTargets {
    pub fn new(device: &wgpu::Device, width: u32, height: u32, k: u32, tail: Tail) -> Self {
        let pixels = width as u64 * height as u64;
        let buffer = |label: &str, bytes: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (pixels * bytes).max(16),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let k = k.clamp(1, MAX_FRAGMENTS);
        let raster_target = device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("k-buffer raster target"),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R8Unorm,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
            .create_view(&Default::default());
        Self {
            k,
            width,
            height,
            keys: buffer("k-buffer keys", 8 * k as u64),
            sums: buffer("k-buffer sums", 16),
            fragments: buffer("k-buffer fragments", 8 * k as u64),
            pixel_info: buffer("k-buffer pixels", 16),
            raster_target,
            tail,
        }
    }

    /// The passes' parameters, with or without an occluder in the depth.
    fn info(&self, device: &wgpu::Device, occluder: bool) -> wgpu::Buffer {
        crate::gpu::context::buffer_init(
            device,
            "k-buffer info",
            bytemuck::bytes_of(&KBufferInfo::new(self.k, self.tail, occluder)),
            wgpu::BufferUsages::STORAGE,
        )
    }

    /// The most of `k` fragments a width x height K-buffer can keep within `limit` bytes a binding (at
    /// least 1).
    pub fn fitting(limit: u64, width: u32, height: u32, k: u32) -> u32 {
        let pixels = (width as u64 * height as u64).max(1);
        let most = (limit / (8 * pixels)).min(MAX_FRAGMENTS as u64) as u32;
        k.clamp(1, most.max(1))
    }

    /// Bytes per pixel of the K-buffer with `k` slots (the largest per-pixel buffer: tiling).
    pub fn bytes_per_pixel(k: u32) -> u64 {
        8 * k.clamp(1, MAX_FRAGMENTS) as u64
    }
}

/// The raster pass (fragments into the K-buffer) and the composite.
pub struct KBufferPass {
    raster: wgpu::RenderPipeline,
    /// The raster pass over a listed subset of the segments ([`SegmentSubset`]).
    raster_subset: wgpu::RenderPipeline,
    composite: wgpu::ComputePipeline,
}

/// Segments to draw in place of all of them: a thinned preview's, every k-th strand's (drawn k times
/// as wide by the camera's `width_scale`).
pub struct SegmentSubset {
    pub list: wgpu::Buffer,
    pub count: u32,
    /// k: one strand of every `stride` is listed.
    pub stride: u32,
}

impl SegmentSubset {
    /// The segments of every `stride`-th strand of a hair whose strands have `segments` segments
    /// each, in the hair's segment order (None when nothing would be listed).
    pub fn new(device: &wgpu::Device, segments: &[u32], stride: u32) -> Option<Self> {
        let list = strided_segments(segments, stride);
        (!list.is_empty()).then(|| Self {
            list: crate::gpu::context::buffer_init(
                device,
                "segment subset",
                bytemuck::cast_slice(&list),
                wgpu::BufferUsages::STORAGE,
            ),
            count: list.len() as u32,
            stride,
        })
    }
}

/// The segment indices of every `stride`-th strand, given each strand's segment count.
pub fn strided_segments(segments: &[u32], stride: u32) -> Vec<u32> {
    let mut first = 0u32;
    let mut list = Vec::new();
    for (s, &n) in segments.iter().enumerate() {
        if s % stride.max(1) as usize == 0 {
            list.extend(first..first + n);
        }
        first += n;
    }
    list
}

impl KBufferPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("k-buffer"),
            source: wgpu::ShaderSource::Wgsl(shaders::kbuffer_module().into()),
        });
        let pipeline = |entry: &str| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("k-buffer raster"),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_fragments"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: wgpu::TextureFormat::R8Unorm,
                        blend: None,
                        write_mask: wgpu::ColorWrites::empty(),
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        Self {
            raster: pipeline("vs_fragments"),
            raster_subset: pipeline("vs_fragments_subset"),
            composite: compute_pipeline(device, &module, "composite"),
        }
    }

    /// Draws segments `range` into the K-buffer (clearing it first when `clear`), and composites it
    /// when the range reaches the last segment; `occluder_depth` is the occluder's multisampled depth
    /// and whether an occluder was drawn into it. The order segments arrive in does not matter. With
    /// `subset`, `range` indexes its list.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        camera: &wgpu::Buffer,
        hair: &GpuHair,
        (occluder_depth, occluder): (&wgpu::TextureView, bool),
        kb: &KBufferTargets,
        range: std::ops::Range<u32>,
        clear: bool,
        subset: Option<&SegmentSubset>,
        timestamps: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        if clear {
            encoder.clear_buffer(&kb.keys, 0, None);
            encoder.clear_buffer(&kb.sums, 0, None);
        }
        let info = kb.info(device, occluder);
        let shared = inputs(camera, hair, &info, occluder_depth);
        let total = subset.map_or(hair.segment_count, |s| s.count);
        let end = range.end.min(total);
        if end > range.start {
            let mut entries = shared.clone();
            entries.extend([entry(5, &kb.keys), entry(6, &kb.sums)]);
            let raster = match subset {
                Some(s) => {
                    entries.push(entry(11, &s.list));
                    &self.raster_subset
                }
                None => &self.raster,
            };
            self.encode_raster(
                device,
                encoder,
                raster,
                &entries,
                kb,
                6 * range.start..6 * end,
                timestamps,
            );
        }
        if range.end >= total {
            let mut entries = shared;
            entries.extend([
                entry(7, &kb.keys),
                entry(8, &kb.sums),
                entry(9, &kb.fragments),
                entry(10, &kb.pixel_info),
            ]);
            self.encode_composite(device, encoder, &entries, kb);
        }
    }

    /// The raster pass over `vertices` (six a segment).
    #[allow(clippy::too_many_arguments)]
    fn encode_raster(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        raster: &wgpu::RenderPipeline,
        entries: &[wgpu::BindGroupEntry],
        kb: &KBufferTargets,
        vertices: std::ops::Range<u32>,
        timestamps: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("k-buffer raster"),
            layout: &raster.get_bind_group_layout(0),
            entries,
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("k-buffer raster"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &kb.raster_target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Discard,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(raster);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(vertices, 0..1);
    }

    /// The composite of every pixel.
    fn encode_composite(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        entries: &[wgpu::BindGroupEntry],
        kb: &KBufferTargets,
    ) {
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("k-buffer composite"),
            layout: &self.composite.get_bind_group_layout(0),
            entries,
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("k-buffer composite"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.composite);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(kb.width.div_ceil(8), kb.height.div_ceil(8), 1);
    }
}

/// The bindings both passes read: the camera, the hair, the parameters and the head's depth.
fn inputs<'a>(
    camera: &'a wgpu::Buffer,
    hair: &'a GpuHair,
    info: &'a wgpu::Buffer,
    occluder_depth: &'a wgpu::TextureView,
) -> Vec<wgpu::BindGroupEntry<'a>> {
    vec![
        entry(0, camera),
        entry(1, &hair.points),
        entry(2, &hair.segments),
        entry(3, info),
        wgpu::BindGroupEntry {
            binding: 4,
            resource: wgpu::BindingResource::TextureView(occluder_depth),
        },
    ]
}

fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: buffer.as_entire_binding(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every second strand's segments, in the hair's segment order.
    #[test]
    fn strided_segments_list_every_kth_strand() {
        assert_eq!(strided_segments(&[2, 3, 1, 4, 2], 2), vec![0, 1, 5, 10, 11]);
        assert_eq!(strided_segments(&[2, 3], 1), vec![0, 1, 2, 3, 4]);
        assert!(strided_segments(&[], 4).is_empty());
    }
}
