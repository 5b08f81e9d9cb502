//! The renderer the CLI, the benchmarks and the live driver drive: GPU resources for one hairstyle,
//! updated in place when parameters, absorption, lights or the camera change, and `render_frame`,
//! which encodes the passes in order (fiber density and pyramid when geometry or absorption changed,
//! the per-light shadow grid when they or the lights changed, visibility, shading batches, resolve).

pub mod absorption;
pub mod frame_passes;
pub mod look;
pub mod readback;
pub mod scene_buffers;
pub mod settings;
pub mod stale;
pub mod table_cache;
pub mod view;

pub use look::{HairLook, ParamTables, TableBuild, build_draft_table, build_tables, same_tables};
pub use readback::FrameReadBack;
pub use settings::RenderSettings;

use crate::envmap::SrbfLight;
use crate::gpu::GpuContext;
use crate::gpu::context::binding_limit;
use crate::gpu::density_pyramid::{DensityPyramidPass, GpuDensityPyramid};
use crate::gpu::dual_eval::dual_tables_texels;
use crate::gpu::fast_eval::GpuLuts;
use crate::gpu::fiber_density::{FiberDensityPass, GpuFiberDensity, GpuHair};
use crate::gpu::forward::upload_forward_table;
use crate::hair::Hair;
use crate::render::camera::Camera;
use crate::render::passes::background::BackgroundMap;
use crate::render::passes::kbuffer::{KBufferTargets, MAX_FRAGMENTS};
use crate::render::passes::resolve::{ResolveInfo, ResolvePass};
use crate::render::passes::segment_shading::SegmentTargets;
use crate::render::passes::shading::{GpuLight, ShadingPass};
use crate::render::passes::shadow_grid::{GpuShadowGrid, ShadowGridPass};
use crate::render::passes::targets::{FrameTargets, MAX_SEGMENTS};
use crate::render::passes::visibility::VisibilityPass;
use crate::render::refine::Refinement;
use crate::render::refine::preview::{Preview, PreviewMode};
use crate::render::refine::repaint::RepaintState;
use crate::render::timing::PassTimer;
use crate::scattering::azimuthal_table::AzimuthalTable;
use crate::scattering::lut::Luts;
use frame_passes::FramePasses;
use glam::Vec3;
use look::LookTables;
use scene_buffers::{SceneBuffers, SceneOccluder};
use stale::Staleness;
use view::ViewTargets;
use wgpu::util::DeviceExt;

/// The passes, in the order `render_frame` runs them (timestamp names).
pub const PASSES: [&str; 7] = [
    "fiber_density",
    "density_pyramid",
    "grid_samples",
    "shadow_grid",
    "visibility",
    "shading",
    "resolve",
];

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("image size {0}x{1} is out of range (1..={2} per side)")]
    Size(u32, u32, u32),
    #[error("{0} fragments per pixel are not supported (use 1 to 32)")]
    Fragments(u32),
    #[error("{0} samples per pixel are not supported (use 2 or 4)")]
    Samples(u32),
    #[error("{points} points in the hair but {absorption} absorption values")]
    AbsorptionCount { points: usize, absorption: usize },
    #[error("the renderer has {renderer} hair points, the hair given has {given}")]
    HairPoints { renderer: usize, given: usize },
    #[error("{0} hair segments; the visibility pass names at most 2^24")]
    TooManySegments(usize),
    #[error("{what} needs {bytes} bytes, more than the GPU binds in one buffer ({limit})")]
    TooLarge {
        what: String,
        bytes: u64,
        limit: u64,
    },
    #[error("the GPU: {0}")]
    Gpu(String),
}

/// The largest angle (radians) a segment may subtend from the eye for the frame to shade it once:
/// about half the narrowest default lobe (TT's longitudinal width, beta_R / 2 = 3.75 degrees). Over a
/// segment the view direction turns by up to this angle, while each light's response is evaluated
/// once, at the segment's midpoint.
pub const MAX_SEGMENT_ANGLE: f32 = 2.0 * std::f32::consts::PI / 180.0;

/// The hair's longest segment and its bounds.
fn segment_extent(hair: &Hair) -> (f32, Vec3, Vec3) {
    let longest = (0..hair.strand_count())
        .flat_map(|s| {
            let r = hair.strand_range(s);
            hair.positions[r].windows(2).map(|w| w[0].distance(w[1]))
        })
        .fold(0.0f32, f32::max);
    let (lo, hi) = hair.bounds();
    (longest, lo, hi)
}

pub struct Renderer {
    pub settings: RenderSettings,
    /// The frame's batches shade segments (else fragments).
    pub(in crate::render) by_segment: bool,
    /// The visible segments per row, read back after the frame's visibility (band sizes).
    pub(in crate::render) row_readback:
        Option<crate::render::passes::row_segments::RowSegmentsReadback>,
    pub(in crate::render) timer: Option<PassTimer>,
    pub(in crate::render) last_ran: Vec<&'static str>,
    /// Where progressive refinement ([`Renderer::refine`]) stands.
    pub(in crate::render) refinement: Refinement,
    /// Whether and how refinement previews a change, and the preview's targets.
    pub(in crate::render) preview_mode: PreviewMode,
    pub(in crate::render) preview: Option<Preview>,
    /// The look and its tables on the GPU.
    pub(in crate::render) look: LookTables,
    /// The hair, head, lights and the volumes built from them.
    pub(in crate::render) scene: SceneBuffers,
    /// The camera and the targets the frame renders into.
    pub(in crate::render) view: ViewTargets,
    /// The passes, built once.
    pub(in crate::render) passes: FramePasses,
    /// What is out of date.
    pub(in crate::render) stale: Staleness,
    /// A brush dab's repaint under way and those waiting.
    pub(in crate::render) repaint: RepaintState,
}

/// The background map's texels as a storage buffer (one zero texel for none: a binding cannot be
/// empty).
fn environment_buffer(device: &wgpu::Device, map: Option<&BackgroundMap>) -> wgpu::Buffer {
    let zero = [[0f32; 4]];
    let texels: &[[f32; 4]] = map.map_or(&zero, |m| &m.texels);
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("background map"),
        contents: bytemuck::cast_slice(texels),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// [`crate::render::reference::shade::ms_paired`] of every pair of segments 2k, 2k + 1 (index k).
fn all_ms_pairs(segment_first: &[u32], sigma_a: &[[f32; 3]]) -> Vec<bool> {
    (0..segment_first.len().div_ceil(2))
        .map(|k| crate::render::reference::shade::ms_paired(segment_first, sigma_a, 2 * k as u32))
        .collect()
}

fn gpu_lights(lights: &[SrbfLight]) -> Vec<GpuLight> {
    let mut v: Vec<GpuLight> = lights
        .iter()
        .map(|l| GpuLight {
            direction: l.dir().normalize().as_vec3().to_array(),
            lambda: l.lambda as f32,
            rgb: l.rgb.map(|c| c as f32),
            _pad: 0.0,
        })
        .collect();
    if v.is_empty() {
        // A binding cannot be empty; batches never read this one.
        v.push(bytemuck::Zeroable::zeroed());
    }
    v
}

impl Renderer {
    /// Uploads the hair (with one RGB absorption per point), tables and lights, and builds every pass.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        ctx: &GpuContext,
        settings: RenderSettings,
        luts: &Luts,
        hair: &Hair,
        sigma_a: &[[f32; 3]],
        look: &HairLook,
        lights: &[SrbfLight],
        camera: &Camera,
    ) -> Result<Self, RenderError> {
        let tables = build_tables(&look.params, None);
        Self::with_tables(
            ctx, settings, luts, hair, sigma_a, look, lights, camera, tables,
        )
    }

    /// [`Renderer::new`] with the forward and dual tables of `look.params` already built
    /// ([`build_tables`], on a worker thread in the editor).
    #[allow(clippy::too_many_arguments)]
    pub fn with_tables(
        ctx: &GpuContext,
        settings: RenderSettings,
        luts: &Luts,
        hair: &Hair,
        sigma_a: &[[f32; 3]],
        look: &HairLook,
        lights: &[SrbfLight],
        camera: &Camera,
        tables: ParamTables,
    ) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let max = device.limits().max_texture_dimension_2d;
        if settings.width == 0
            || settings.height == 0
            || settings.width > max
            || settings.height > max
        {
            return Err(RenderError::Size(settings.width, settings.height, max));
        }
        if !matches!(settings.samples, 2 | 4) {
            return Err(RenderError::Samples(settings.samples));
        }
        if !(1..=MAX_FRAGMENTS).contains(&settings.fragments) {
            return Err(RenderError::Fragments(settings.fragments));
        }
        // A K-buffer larger than one binding keeps fewer fragments (the editor's viewport; stills
        // are tiled instead, `tiled::tile_side`).
        let requested_fragments = settings.fragments;
        let mut settings = settings;
        settings.fragments = KBufferTargets::fitting(
            binding_limit(device),
            settings.width,
            settings.height,
            requested_fragments,
        );
        if sigma_a.len() != hair.point_count() {
            return Err(RenderError::AbsorptionCount {
                points: hair.point_count(),
                absorption: sigma_a.len(),
            });
        }
        let segments = hair.point_count().saturating_sub(hair.strand_count());
        if segments >= MAX_SEGMENTS as usize {
            return Err(RenderError::TooManySegments(segments));
        }
        let limit = device
            .limits()
            .max_storage_buffer_binding_size
            .min(device.limits().max_buffer_size);
        let check = |what: &str, bytes: u64| {
            if bytes > limit {
                Err(RenderError::TooLarge {
                    what: what.into(),
                    bytes,
                    limit,
                })
            } else {
                Ok(())
            }
        };
        check(
            &format!("a {}x{} image", settings.width, settings.height),
            settings.width as u64 * settings.height as u64 * 16,
        )?;
        check("the azimuthal table", AzimuthalTable::MAX_BYTES)?;
        let grid = settings.shadow_grid(hair);
        check(
            &format!(
                "the shadow grid ({} points x {} lights)",
                grid.point_count(),
                lights.len()
            ),
            grid.point_count() as u64 * lights.len().max(1) as u64 * 32,
        )?;
        check(
            "the shadow sweeps' working memory",
            grid.largest_slice() as u64
                * crate::render::passes::shadow_grid::SCRATCH_BYTES
                * lights.len().max(1) as u64,
        )?;
        check(
            "the shadow sweeps' samples",
            crate::shadow::sweep::MidplaneSamples::layout(&grid).1 as u64
                * crate::render::passes::shadow_grid::SAMPLE_BYTES,
        )?;
        let gpu_hair = GpuHair::new(device, hair, sigma_a);
        let grid = settings.volume_grid(hair);
        let volume = GpuFiberDensity::new(device, grid, gpu_hair.segment_count);
        let pyramid = GpuDensityPyramid::new(device, &volume);
        let uniform = |label: &str, bytes: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            })
        };
        let camera_u = camera.uniform(settings.width, settings.height, settings.min_width_px);
        let resolve_info = ResolveInfo::new(settings.exposure, settings.samples);
        let skip = settings.shadow_skip(hair);
        let shadow_grid = GpuShadowGrid::new(
            device,
            settings.shadow_grid(hair),
            lights.len() as u32,
            skip,
            settings.multiple_scattering,
        );
        let ParamTables {
            forward,
            dual,
            azimuthal,
        } = tables;
        let azimuthal_table = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("azimuthal table"),
            size: AzimuthalTable::MAX_BYTES,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        ctx.queue
            .write_buffer(&azimuthal_table, 0, azimuthal.gpu_bytes());
        let storage = |label: &str, bytes: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            })
        };
        let gpu_hair_segments = gpu_hair.segment_count;
        let segment_first = crate::render::reference::shade::segment_starts(hair);
        let ms_pairs = all_ms_pairs(&segment_first, sigma_a);
        let mut renderer = Self {
            by_segment: false,
            row_readback: None,
            timer: PassTimer::new(ctx, &PASSES),
            last_ran: Vec::new(),
            refinement: Refinement::for_device(ctx),
            preview_mode: PreviewMode::Off,
            preview: None,
            look: LookTables {
                luts: GpuLuts::new(device, luts),
                look: *look,
                tables_for: look.params,
                params: uniform("hair params", bytemuck::bytes_of(&look.fast)),
                forward_table: upload_forward_table(device, &forward),
                dual_tables: storage(
                    "dual tables",
                    bytemuck::cast_slice(&dual_tables_texels(&dual)),
                ),
                azimuthal,
                azimuthal_table,
            },
            scene: SceneBuffers {
                hair: gpu_hair,
                point_count: hair.point_count(),
                skip,
                volume,
                pyramid,
                shadow_grid,
                lights: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("lights"),
                    contents: bytemuck::cast_slice(&gpu_lights(lights)),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                }),
                light_count: lights.len() as u32,
                background_map: environment_buffer(device, None),
                occluder: None,
                segment_extent: segment_extent(hair),
                segment_first,
                preview_strands: (hair.strand_count()
                    >= crate::render::refine::preview::THIN_PREVIEW_STRANDS)
                    .then(|| {
                        let segments: Vec<u32> = (0..hair.strand_count())
                            .map(|s| hair.strand_range(s).len().saturating_sub(1) as u32)
                            .collect();
                        let stride = crate::render::refine::preview::PREVIEW_STRAND_STRIDE;
                        crate::render::passes::kbuffer::SegmentSubset::new(
                            &ctx.device,
                            &segments,
                            stride,
                        )
                    })
                    .flatten(),
                point_data: GpuHair::point_data(hair, 1.0),
            },
            view: ViewTargets {
                camera: uniform("camera", bytemuck::bytes_of(&camera_u)),
                camera_view: *camera,
                tile: None,
                resolve_info: uniform("resolve", bytemuck::bytes_of(&resolve_info)),
                resolve_params: resolve_info,
                targets: FrameTargets::new(
                    device,
                    settings.width,
                    settings.height,
                    settings.samples,
                    settings.kbuffer(),
                ),
                segment_targets: settings
                    .segment_shading
                    .then(|| {
                        SegmentTargets::new(
                            device,
                            gpu_hair_segments,
                            crate::gpu::context::binding_limit(device),
                        )
                    })
                    .flatten(),
                requested_fragments,
            },
            passes: FramePasses {
                density_pass: FiberDensityPass::new(device),
                pyramid_pass: DensityPyramidPass::new(device),
                shadow_grid_pass: ShadowGridPass::new(device),
                visibility_pass: VisibilityPass::new(device, settings.samples),
                shading_pass: ShadingPass::new(device),
                resolve_pass: ResolvePass::new(device),
            },
            stale: Staleness {
                volume_dirty: true,
                converged_rows: u32::MAX,
                volume_stale: false,
                volume_stale_density: false,
                volume_absorption_old: false,
                shadow_grid_dirty: true,
                single_kept: false,
                visibility_valid: false,
            },
            repaint: RepaintState {
                segments: Vec::new(),
                rows: 0..0,
                pending: Vec::new(),
                ms_pairs,
                flips_pending: Vec::new(),
                flips: Vec::new(),
            },
            settings,
        };
        renderer.update_batches(device);
        renderer.grid_buffer_made();
        Ok(renderer)
    }
}
