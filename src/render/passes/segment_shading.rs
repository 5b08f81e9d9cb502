//! Segment shading, the default for the frame and its preview (`claim_segments`, `segment_dispatch`,
//! `shade_segments` and `gather_segments` of `shaders/shading.wgsl`): per light batch, the visible
//! segments of the rows' kept K-buffer fragments are listed once, each is shaded (each light's
//! single-scattering response once at its midpoint, weighted by the light's transmittance at its
//! ends and midpoint; multiple scattering once per pair of consecutive segments of a strand, at the
//! point they share: [`crate::render::reference::shade::ShadingHair::ms_key`]), and once every batch has shaded them the
//! rows' pixels gather their fragments' radiance, single scattering interpolated along each segment.
//! The per-fragment pass ([`crate::render::passes::shading`]) shades the frame and preview without
//! `RenderSettings::segment_shading`, a view in which a segment subtends more than
//! [`crate::render::renderer::MAX_SEGMENT_ANGLE`], and a hair whose segments' radiance would not fit one
//! binding.

use crate::gpu::context::{bind_entries as bind, compute_pipeline};
use crate::render::passes::batch::{ShadeBatch, ShadingInputs};
use crate::render::passes::targets::FrameTargets;

/// Samples of single scattering along a segment: its ends and its midpoint (t = 0, 1/2, 1).
pub const SINGLE_SAMPLES: u64 = 3;

/// Bytes of a single-scattering component's radiance per segment (three samples, RGBA f32); a
/// multiple-scattering component's is a third (one sample per key, indexed by its segment).
pub const RADIANCE_BYTES_PER_SEGMENT: u64 = 16 * SINGLE_SAMPLES;

/// The per-segment buffers (sized by the hair's segments, not by the image).
pub struct SegmentTargets {
    /// Per segment: 1 + the first light of the last batch that shaded it (0: none).
    pub batches: wgpu::Buffer,
    /// [0]: segments listed by the unit's claim, [1]: multiple scattering's keys (`ms_key` of
    /// `shaders/shading.wgsl`, [`crate::render::reference::shade::ShadingHair::ms_key`]), [2]: a repaint's candidates.
    pub work_count: wgpu::Buffer,
    pub work_list: wgpu::Buffer,
    /// Per multiple-scattering key: 1 + the first light of the last batch that claimed it (0: none;
    /// repaints list their keys without it).
    pub ms_batches: wgpu::Buffer,
    /// The keys listed by the unit's claim (or a repaint's, by `list_repaint_keys`).
    pub ms_list: wgpu::Buffer,
    /// A repaint's candidates for multiple scattering (its segments and the partners of the pairs its
    /// dabs joined or split, written by the caller; work_count[2] of them).
    pub ms_candidates: wgpu::Buffer,
    /// Per segment its key, found by the frame's (or a repaint's) first light batch (the others and
    /// the gather read it: the pairing reads the absorption, which a dab may change while the frame
    /// refines).
    pub ms_keys: wgpu::Buffer,
    /// `shade_segments`' indirect dispatch.
    pub work_args: wgpu::Buffer,
    /// R, TT, TRT at each segment's t = 0, 1/2, 1 (index 3 segment + 2 t), MS.global and MS.local
    /// at each key's sample (index key: [`crate::render::reference::shade::ShadingHair::ms_point`]). Written by a
    /// frame's first light batch, added to by the others.
    pub radiance: [wgpu::Buffer; 5],
}

impl SegmentTargets {
    /// Buffers for `segments` segments, or None when one component's radiance would exceed
    /// `binding_limit` bytes (the frame then shades per fragment).
    pub fn new(device: &wgpu::Device, segments: u32, binding_limit: u64) -> Option<Self> {
        let n = segments.max(1) as u64;
        if n * RADIANCE_BYTES_PER_SEGMENT > binding_limit {
            return None;
        }
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: usage | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let none = wgpu::BufferUsages::empty();
        Some(Self {
            batches: buffer("segment batches", 4 * n, none),
            work_count: buffer("segment work count", 12, none),
            work_list: buffer("segment work list", 4 * n, none),
            ms_batches: buffer("multiple scattering batches", 4 * n, none),
            ms_list: buffer("multiple scattering work list", 4 * n, none),
            ms_keys: buffer("multiple scattering keys", 4 * n, none),
            ms_candidates: buffer("multiple scattering candidates", 4 * n, none),
            work_args: buffer("segment dispatch", 12, wgpu::BufferUsages::INDIRECT),
            radiance: std::array::from_fn(|c| {
                let samples = if c < 3 { SINGLE_SAMPLES } else { 1 };
                buffer(
                    crate::render::passes::targets::COMPONENTS[c],
                    n * RADIANCE_BYTES_PER_SEGMENT / SINGLE_SAMPLES * samples,
                    none,
                )
            }),
        })
    }

    /// No segment shaded (the start of a frame's shading; the first light batch overwrites the
    /// radiance of each segment it claims).
    pub fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.clear_buffer(&self.batches, 0, None);
        encoder.clear_buffer(&self.ms_batches, 0, None);
    }
}

/// The five pipelines.
pub struct SegmentShadingPass {
    claim: wgpu::ComputePipeline,
    repaint_keys: wgpu::ComputePipeline,
    dispatch: wgpu::ComputePipeline,
    shade: wgpu::ComputePipeline,
    gather: wgpu::ComputePipeline,
}

/// How a kernel's workgroups are counted: given, or read from a buffer (`shade_segments`).
enum Workgroups<'a> {
    Direct(u32, u32),
    Indirect(&'a wgpu::Buffer),
}

/// One compute pass running `pipeline` with its bind group over `workgroups`.
fn run(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    bind_group: &wgpu::BindGroup,
    workgroups: Workgroups,
    timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    match workgroups {
        Workgroups::Direct(x, y) => pass.dispatch_workgroups(x, y, 1),
        Workgroups::Indirect(args) => pass.dispatch_workgroups_indirect(args, 0),
    }
}

impl SegmentShadingPass {
    pub fn new(device: &wgpu::Device, module: &wgpu::ShaderModule) -> Self {
        Self {
            claim: compute_pipeline(device, module, "claim_segments"),
            repaint_keys: compute_pipeline(device, module, "list_repaint_keys"),
            dispatch: compute_pipeline(device, module, "segment_dispatch"),
            shade: compute_pipeline(device, module, "shade_segments"),
            gather: compute_pipeline(device, module, "gather_segments"),
        }
    }

    /// One light batch over the segments of rows `batch.row0 .. + batch.rows` that it has not shaded
    /// yet: the claim, the dispatch's size, the shading. `timestamps`: the claim's beginning.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_batch(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        targets: &FrameTargets,
        segments: &SegmentTargets,
        batch: &wgpu::Buffer,
        (width, rows): (u32, u32),
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        encoder.clear_buffer(&segments.work_count, 0, None);
        let claim = bind(
            device,
            &self.claim,
            "claim segments",
            &[
                (0, inputs.camera),
                (2, batch),
                (5, inputs.segments),
                (6, inputs.absorption),
                (18, &targets.kbuffer.fragments),
                (20, &segments.batches),
                (21, &segments.work_count),
                (22, &segments.work_list),
                (30, &segments.ms_batches),
                (31, &segments.ms_list),
                (32, &segments.ms_keys),
            ],
        );
        let pixels = Workgroups::Direct(width.div_ceil(8), rows.div_ceil(8));
        run(
            encoder,
            "claim segments",
            &self.claim,
            &claim,
            pixels,
            timestamps,
        );
        self.encode_listed(device, encoder, inputs, segments, batch);
    }

    /// A repaint's multiple-scattering keys: of the `candidates` in `ms_candidates` (written by the
    /// caller, with the counts: work_count[1] zero), those that are their own key, listed in
    /// `ms_list`.
    pub fn encode_repaint_keys(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        segments: &SegmentTargets,
        batch: &wgpu::Buffer,
        candidates: u32,
    ) {
        if candidates == 0 {
            return;
        }
        let keys = bind(
            device,
            &self.repaint_keys,
            "repaint keys",
            &[
                (2, batch),
                (5, inputs.segments),
                (6, inputs.absorption),
                (21, &segments.work_count),
                (31, &segments.ms_list),
                (32, &segments.ms_keys),
                (33, &segments.ms_candidates),
            ],
        );
        let groups = candidates.div_ceil(64);
        let rows = Workgroups::Direct(groups.min(65535), groups.div_ceil(65535));
        run(
            encoder,
            "repaint keys",
            &self.repaint_keys,
            &keys,
            rows,
            None,
        );
    }

    /// One light batch over the segments already listed in `work_list` and the keys in `ms_list`
    /// (`work_count` of them: a repaint's segments written by the caller, its keys by
    /// [`Self::encode_repaint_keys`]): the dispatch's size and the shading, no claim.
    pub fn encode_listed(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        segments: &SegmentTargets,
        batch: &wgpu::Buffer,
    ) {
        let dispatch = bind(
            device,
            &self.dispatch,
            "segment dispatch",
            &[
                (2, batch),
                (21, &segments.work_count),
                (23, &segments.work_args),
            ],
        );
        let one = Workgroups::Direct(1, 1);
        run(
            encoder,
            "segment dispatch",
            &self.dispatch,
            &dispatch,
            one,
            None,
        );
        let mut entries = inputs.shading_entries(batch);
        entries.extend([
            (21, &segments.work_count),
            (22, &segments.work_list),
            (31, &segments.ms_list),
        ]);
        entries.extend((24..).zip(&segments.radiance));
        let shade = bind(device, &self.shade, "shade segments", &entries);
        let listed = Workgroups::Indirect(&segments.work_args);
        run(encoder, "shade segments", &self.shade, &shade, listed, None);
    }

    /// Rows `batch.row0 .. + batch.rows` of the components from the segments' radiance (after every
    /// light batch shaded them). `timestamps`: the pass's end.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_gather(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadingInputs,
        targets: &FrameTargets,
        segments: &SegmentTargets,
        batch: &wgpu::Buffer,
        (width, rows): (u32, u32),
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let mut entries = vec![
            (0, inputs.camera),
            (2, batch),
            (4, inputs.points),
            (5, inputs.segments),
            (18, &targets.kbuffer.fragments),
            (32, &segments.ms_keys),
        ];
        entries.extend((13..).zip(&targets.components));
        entries.extend((24..).zip(&segments.radiance));
        let gather = bind(device, &self.gather, "gather segments", &entries);
        let pixels = Workgroups::Direct(width.div_ceil(8), rows.div_ceil(8));
        run(
            encoder,
            "gather segments",
            &self.gather,
            &gather,
            pixels,
            timestamps,
        );
    }
}

/// Whether `batch` is the frame's last light batch (its gather follows).
pub fn last_light_batch(batch: &ShadeBatch) -> bool {
    batch.first + batch.count >= batch.lights
}
