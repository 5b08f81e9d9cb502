//! The ordered K-buffer (Yu et al. 2012, Secs. 4 and 5: translucency and anti-aliasing of hair),
//! `shaders/kbuffer.wgsl`, and its CPU twins.
//!
//! Every segment is a ribbon of the fiber's true width; each pixel it touches gets a fragment whose
//! opacity is the exact area of the ribbon inside the pixel square (a box filter, so a fiber a tenth
//! of a pixel wide covers a tenth of the pixels it crosses) times the share of the occluder's depth
//! samples behind it. The K nearest fragments of every pixel are kept in order by a chain of 64-bit
//! atomic maxima (independent of the order of insertion); every fragment's optical depth
//! −ln(1 − opacity) is summed in fixed point. The composite weighs the kept fragments front to back,
//! w_i = a_i Π_{j<i} (1 − a_j), and gives the opacity of all the fragments behind the K-th to the
//! K-th ([`Tail::Fold`]) or to all the kept ones ([`Tail::Spread`]), so the pixel's alpha counts every
//! fragment. [`abuffer`] builds every
//! fragment of every pixel on the CPU (the A-buffer reference: all fragments, sorted).

use super::camera::{CameraUniform, closest_on_segment, pixel_ray};
use crate::gpu::context::compute_pipeline;
use crate::gpu::fiber_density::GpuHair;
use crate::gpu::shaders;
use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

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

/// A point in pixel coordinates (x right, y down) and its view depth (twin of `to_pixels`).
pub fn to_pixels(c: &CameraUniform, p: Vec3) -> Vec3 {
    let clip = Mat4::from_cols_array_2d(&c.view_proj) * p.extend(1.0);
    let ndc = clip.truncate().truncate() / clip.w;
    let (w, h) = (c.size[0] as f32, c.size[1] as f32);
    Vec3::new(
        0.5 * (ndc.x + 1.0) * w,
        0.5 * (1.0 - ndc.y) * h,
        (p - Vec3::from(c.eye)).dot(Vec3::from(c.forward)),
    )
}

/// A segment's ribbon on the image (twin of `RibbonQuad`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RibbonQuad {
    pub p0: Vec2,
    pub p1: Vec2,
    pub dir: Vec2,
    pub normal: Vec2,
    pub half_width: Vec2,
    pub valid: bool,
}

/// Half the ribbon's width in pixels (twin of `half_width_px`).
pub fn half_width_px(c: &CameraUniform, diameter: f32, depth: f32) -> f32 {
    c.width_scale * (0.5 * diameter / (c.pixel_angle * depth)).max(0.5 * c.min_width_px)
}

/// The part of the segment a..b in front of the near plane, moved in by a thousandth of it (twin of
/// `clip_near`): None when both ends are behind it.
pub fn clip_near(c: &CameraUniform, a: Vec4, b: Vec4) -> Option<(Vec4, Vec4)> {
    let plane = 1.001 * c.near;
    let (eye, forward) = (Vec3::from(c.eye), Vec3::from(c.forward));
    let da = (a.truncate() - eye).dot(forward);
    let db = (b.truncate() - eye).dot(forward);
    if da <= plane && db <= plane {
        return None;
    }
    if da < plane && db > plane {
        return Some((a + (b - a) * ((plane - da) / (db - da)), b));
    }
    if db < plane && da > plane {
        return Some((a, b + (a - b) * ((plane - db) / (da - db))));
    }
    Some((a, b))
}

/// The ribbon of the segment between points `a` and `b` (xyz, diameter; twin of `ribbon_quad`).
pub fn ribbon_quad(c: &CameraUniform, a: Vec4, b: Vec4) -> RibbonQuad {
    let valid = clip_near(c, a, b).is_some();
    let (a, b) = clip_near(c, a, b).unwrap_or((a, b));
    let pa = to_pixels(c, a.truncate());
    let pb = to_pixels(c, b.truncate());
    let d = pb.truncate() - pa.truncate();
    let len = d.length();
    let dir = if len > 1e-6 { d / len } else { Vec2::X };
    RibbonQuad {
        p0: pa.truncate(),
        p1: pb.truncate(),
        dir,
        normal: Vec2::new(-dir.y, dir.x),
        half_width: Vec2::new(
            half_width_px(c, a.w, pa.z.max(c.near)),
            half_width_px(c, b.w, pb.z.max(c.near)),
        ),
        valid,
    }
}

/// The mean over t in [0, 1] of clamp(y0 + t (y1 - y0), 0, 1) (twin of `clamped_mean`).
fn clamped_mean(y0: f32, y1: f32) -> f32 {
    let (lo, hi) = (y0.min(y1), y0.max(y1));
    let dy = hi - lo;
    if dy <= 1e-20 {
        return lo.clamp(0.0, 1.0);
    }
    let (a, b) = (lo.max(0.0), hi.min(1.0));
    let inside = (b - a).max(0.0);
    ((hi - 1.0) / dy).clamp(0.0, 1.0) + inside / dy * 0.5 * (a + b)
}

/// Edge a -> b's term of the area inside the unit square by Green's theorem: the integral of
/// clamp(y, 0, 1) dx along the edge over x in [0, 1] (twin of `edge_area`).
fn edge_area(a: Vec2, b: Vec2) -> f32 {
    let dx = b.x - a.x;
    let (lo, hi) = (a.x.min(b.x).max(0.0), a.x.max(b.x).min(1.0));
    if dx.abs() <= 1e-20 || hi <= lo {
        return 0.0;
    }
    let ylo = a.y + (lo - a.x) / dx * (b.y - a.y);
    let yhi = a.y + (hi - a.x) / dx * (b.y - a.y);
    dx.signum() * (hi - lo) * clamped_mean(ylo, yhi)
}

/// The ribbon's corners relative to pixel (x, y)'s corner, in order around it.
fn ribbon_corners(q: &RibbonQuad, x: u32, y: u32) -> [Vec2; 4] {
    let o = Vec2::new(x as f32, y as f32);
    [
        q.p0 - o - q.half_width.x * q.normal,
        q.p1 - o - q.half_width.y * q.normal,
        q.p1 - o + q.half_width.y * q.normal,
        q.p0 - o + q.half_width.x * q.normal,
    ]
}

/// Coverage below this is the edges' terms' rounding (each term is at most 1, good to ~1e-7): a ribbon
/// passing by the pixel, which leaves no fragment (twin of `MIN_COVERAGE`).
pub const MIN_COVERAGE: f32 = 1e-6;

/// The area of the ribbon inside pixel (x, y), in [0, 1], by the quad's edges' Green's-theorem terms;
/// 0 below [`MIN_COVERAGE`] (twin of `pixel_coverage`).
pub fn pixel_coverage(q: &RibbonQuad, x: u32, y: u32) -> f32 {
    if !q.valid {
        return 0.0;
    }
    let v = ribbon_corners(q, x, y);
    let area = (edge_area(v[0], v[1])
        + edge_area(v[1], v[2])
        + edge_area(v[2], v[3])
        + edge_area(v[3], v[0]))
    .abs();
    if area >= MIN_COVERAGE {
        area.min(1.0)
    } else {
        0.0
    }
}

/// Sutherland–Hodgman: the part of the convex polygon where p · nrm ≤ off.
fn clip_half_plane(poly: &[Vec2], nrm: Vec2, off: f32) -> Vec<Vec2> {
    let mut out = Vec::with_capacity(8);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        let (da, db) = (a.dot(nrm) - off, b.dot(nrm) - off);
        if da <= 0.0 {
            out.push(a);
        }
        if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    out
}

/// The brute-force twin of [`pixel_coverage`]: the quad clipped by the pixel's four sides
/// (Sutherland–Hodgman) and the clipped polygon's area (the shoelace formula).
pub fn pixel_coverage_by_clipping(q: &RibbonQuad, x: u32, y: u32) -> f32 {
    if !q.valid {
        return 0.0;
    }
    let mut poly = ribbon_corners(q, x, y).to_vec();
    for (nrm, off) in [
        (Vec2::new(-1.0, 0.0), 0.0),
        (Vec2::new(1.0, 0.0), 1.0),
        (Vec2::new(0.0, -1.0), 0.0),
        (Vec2::new(0.0, 1.0), 1.0),
    ] {
        poly = clip_half_plane(&poly, nrm, off);
    }
    let mut twice = 0.0;
    for (i, a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        twice += a.x * b.y - a.y * b.x;
    }
    (0.5 * f32::abs(twice)).clamp(0.0, 1.0)
}

/// View depth of the segment's point closest to the ray through pixel (x, y)'s centre (twin of
/// `fragment_depth`).
pub fn fragment_depth(c: &CameraUniform, a: Vec3, b: Vec3, x: u32, y: u32) -> f32 {
    let (o, d) = pixel_ray(c, x as f32 + 0.5, y as f32 + 0.5);
    let t = closest_on_segment(o, d, a, b);
    (a + (b - a) * t - Vec3::from(c.eye)).dot(Vec3::from(c.forward))
}

/// −ln(1 − a) in fixed point (twin of `optical_depth`).
pub fn optical_depth(a: f32) -> u32 {
    (-(1.0 - a.min(MAX_FRAGMENT_OPACITY)).ln() * OPTICAL_DEPTH_SCALE).round() as u32
}

/// One fragment of the A-buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawFragment {
    pub segment: u32,
    pub depth: f32,
    pub opacity: f32,
}

impl RawFragment {
    /// The K-buffer's order: depth, then segment (the key's bits).
    fn key(&self) -> u64 {
        ((self.depth.to_bits() as u64) << 32) | self.segment as u64
    }
}

/// Every fragment of every pixel, sorted front to back (no occluder): the A-buffer.
pub struct ABuffer {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec<RawFragment>>,
}

/// The A-buffer of the segments (first points `segments` into `points`: xyz, diameter) seen by the
/// camera, by brute force on the CPU: every pixel of each ribbon's grown bounding box whose coverage
/// is positive.
pub fn abuffer(c: &CameraUniform, points: &[[f32; 4]], segments: &[u32]) -> ABuffer {
    let (w, h) = (c.size[0], c.size[1]);
    let per_segment: Vec<Vec<(u32, RawFragment)>> = segments
        .par_iter()
        .enumerate()
        .map(|(seg, &i0)| {
            let (a, b) = (
                Vec4::from(points[i0 as usize]),
                Vec4::from(points[i0 as usize + 1]),
            );
            let q = ribbon_quad(c, a, b);
            let mut out = Vec::new();
            if !q.valid {
                return out;
            }
            let grow = q.half_width.max_element() + EXPAND_PX;
            let lo = q.p0.min(q.p1) - Vec2::splat(grow);
            let hi = q.p0.max(q.p1) + Vec2::splat(grow);
            let x0 = lo.x.floor().max(0.0) as u32;
            let y0 = lo.y.floor().max(0.0) as u32;
            let x1 = (hi.x.ceil().max(0.0) as u32).min(w);
            let y1 = (hi.y.ceil().max(0.0) as u32).min(h);
            for y in y0..y1 {
                for x in x0..x1 {
                    let cover = pixel_coverage(&q, x, y);
                    if cover > 0.0 {
                        let depth = fragment_depth(c, a.truncate(), b.truncate(), x, y);
                        let f = RawFragment {
                            segment: seg as u32,
                            depth,
                            opacity: cover,
                        };
                        out.push((y * w + x, f));
                    }
                }
            }
            out
        })
        .collect();
    let mut pixels = vec![Vec::new(); w as usize * h as usize];
    for (p, f) in per_segment.into_iter().flatten() {
        pixels[p as usize].push(f);
    }
    pixels
        .par_iter_mut()
        .for_each(|l| l.sort_by_key(RawFragment::key));
    ABuffer {
        width: w,
        height: h,
        pixels,
    }
}

/// The composite of one pixel's fragments (sorted front to back) keeping `k` (twin of `composite`,
/// without an occluder): the k slots and the pixel's summary.
pub fn composite(list: &[RawFragment], k: usize, tail: Tail) -> (Vec<Fragment>, PixelFragments) {
    let mut slots = vec![Fragment::default(); k];
    let mut t = 1.0f32;
    let mut kept_alpha = 0.0f32;
    let mut kept = 0u32;
    let n = list.len().min(k);
    for (slot, f) in slots.iter_mut().zip(&list[..n]) {
        let a = f.opacity.min(1.0);
        kept += optical_depth(a);
        *slot = Fragment {
            id: f.segment + 1,
            weight: t * a,
        };
        kept_alpha += t * a;
        t *= 1.0 - a;
    }
    let all: u32 = list.iter().map(|f| optical_depth(f.opacity)).sum();
    if tail != Tail::Drop && n == k && k > 0 {
        let behind = (-(all.saturating_sub(kept) as f32) / OPTICAL_DEPTH_SCALE).exp();
        if tail == Tail::Fold || kept_alpha <= 0.0 {
            slots[n - 1].weight += t * (1.0 - behind);
        } else {
            let scale = 1.0 + t * (1.0 - behind) / kept_alpha;
            for f in &mut slots[..n] {
                f.weight *= scale;
            }
        }
        t *= behind;
    }
    let info = PixelFragments {
        alpha: 1.0 - t,
        occluder_transmittance: 1.0,
        depth: list.first().map_or(1e10, |f| f.depth),
        count: list.len() as f32,
    };
    (slots, info)
}

impl ABuffer {
    /// The K-buffer of every pixel from the A-buffer ([`composite`]): `k` slots per pixel, and the
    /// pixels' summaries.
    pub fn kbuffer(&self, k: usize, tail: Tail) -> (Vec<Fragment>, Vec<PixelFragments>) {
        let per: Vec<(Vec<Fragment>, PixelFragments)> = self
            .pixels
            .par_iter()
            .map(|l| composite(l, k, tail))
            .collect();
        let mut slots = Vec::with_capacity(per.len() * k);
        let mut info = Vec::with_capacity(per.len());
        for (s, i) in per {
            slots.extend(s);
            info.push(i);
        }
        (slots, info)
    }

    /// The most fragments any pixel holds.
    pub fn depth_complexity(&self) -> usize {
        self.pixels.iter().map(Vec::len).max().unwrap_or(0)
    }
}

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

    /// The edges' Green's-theorem terms against the clipped polygon's area, over ribbons of every
    /// direction, width and taper around a pixel (some thinner than 1e-3 pixel, some covering it).
    #[test]
    fn coverage_by_edges_equals_the_clipped_polygon() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rand = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut worst = 0.0f32;
        for k in 0..20000 {
            let p0 = Vec2::new(10.0 + 4.0 * rand() - 2.0, 20.0 + 4.0 * rand() - 2.0);
            let angle = std::f32::consts::TAU * rand();
            let len = if k % 10 == 0 { 1e-4 } else { 3.0 * rand() };
            let dir = Vec2::new(angle.cos(), angle.sin());
            let width = |r: f32| if k % 7 == 0 { 1e-4 * r } else { 1.5 * r };
            let q = RibbonQuad {
                p0,
                p1: p0 + len * dir,
                dir,
                normal: Vec2::new(-dir.y, dir.x),
                half_width: Vec2::new(width(rand()), width(rand())),
                valid: true,
            };
            let (a, b) = (
                pixel_coverage(&q, 10, 20),
                pixel_coverage_by_clipping(&q, 10, 20),
            );
            worst = worst.max((a - b).abs());
        }
        println!("worst |edges - clipped| {worst:.2e}");
        assert!(worst <= MIN_COVERAGE, "{worst}");
    }
}
