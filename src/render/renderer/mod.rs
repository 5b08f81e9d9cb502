//! The renderer the CLI, the benchmarks and the live driver drive: GPU resources for one hairstyle,
//! updated in place when parameters, absorption, lights or the camera change, and `render_frame`,
//! which encodes the passes in order (fiber density and pyramid when geometry or absorption changed,
//! the per-light shadow grid when they or the lights changed, visibility, shading batches, resolve).

pub mod absorption;
pub mod frame_passes;
pub mod look;
pub mod readback;
pub mod settings;
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
use crate::render::camera::{Camera, Tile};
use crate::render::passes::background::BackgroundMap;
use crate::render::passes::kbuffer::{KBufferTargets, MAX_FRAGMENTS};
use crate::render::passes::occluder::GpuOccluder;
use crate::render::passes::resolve::{ResolveInfo, ResolvePass};
use crate::render::passes::segment_shading::SegmentTargets;
use crate::render::passes::shading::{GpuLight, ShadingPass};
use crate::render::passes::shadow_grid::{GpuShadowGrid, ShadowGridPass};
use crate::render::passes::targets::{FrameTargets, MAX_SEGMENTS};
use crate::render::passes::visibility::VisibilityPass;
use crate::render::refine::Refinement;
use crate::render::refine::preview::{Preview, PreviewMode};
use crate::render::timing::PassTimer;
use crate::scattering::azimuthal_table::AzimuthalTable;
use crate::scattering::lut::Luts;
use crate::scattering::params::HairParams;
use glam::Vec3;
use std::sync::Arc;
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
    pub(in crate::render) hair: GpuHair,
    pub(in crate::render) point_count: usize,
    pub(in crate::render) skip: f32,
    pub(in crate::render) volume: GpuFiberDensity,
    pub(in crate::render) pyramid: GpuDensityPyramid,
    pub(in crate::render) shadow_grid: GpuShadowGrid,
    pub(in crate::render) luts: GpuLuts,
    pub(in crate::render) look: HairLook,
    /// The exact parameters the forward and dual tables were built for.
    pub(in crate::render) tables_for: HairParams,
    pub(in crate::render) params: wgpu::Buffer,
    pub(in crate::render) forward_table: wgpu::Buffer,
    pub(in crate::render) dual_tables: wgpu::Buffer,
    /// The azimuthal table the buffer holds (sized for the largest, an elliptical fiber's).
    pub(in crate::render) azimuthal: Arc<AzimuthalTable>,
    pub(in crate::render) azimuthal_table: wgpu::Buffer,
    pub(in crate::render) camera: wgpu::Buffer,
    /// The camera the uniform was made from (rewritten when the image size changes).
    pub(in crate::render) camera_view: Camera,
    /// The tile of a larger still the camera renders (None: the whole image).
    pub(in crate::render) tile: Option<Tile>,
    pub(in crate::render) lights: wgpu::Buffer,
    pub(in crate::render) light_count: u32,
    pub(in crate::render) resolve_info: wgpu::Buffer,
    /// What `resolve_info` holds.
    pub(in crate::render) resolve_params: ResolveInfo,
    /// The background's map texels (one zero texel without one).
    pub(in crate::render) background_map: wgpu::Buffer,
    /// The occluder (the head) drawn, shaded and held in the volume as a solid.
    pub(in crate::render) occluder: Option<SceneOccluder>,
    pub(in crate::render) targets: FrameTargets,
    pub(in crate::render) density_pass: FiberDensityPass,
    pub(in crate::render) pyramid_pass: DensityPyramidPass,
    pub(in crate::render) shadow_grid_pass: ShadowGridPass,
    pub(in crate::render) visibility_pass: VisibilityPass,
    pub(in crate::render) shading_pass: ShadingPass,
    /// The frame's per-segment radiance (None: the frame shades per fragment).
    pub(in crate::render) segment_targets: Option<SegmentTargets>,
    /// The hair's longest segment and its bounds (whether segments are short enough, as the eye sees
    /// them, to be shaded once each: [`MAX_SEGMENT_ANGLE`]).
    pub(in crate::render) segment_extent: (f32, Vec3, Vec3),
    /// The frame's batches shade segments (else fragments).
    pub(in crate::render) by_segment: bool,
    pub(in crate::render) resolve_pass: ResolvePass,
    /// The fragments per pixel asked for (`settings.fragments` is fewer when the K-buffer would not
    /// fit one binding at this size).
    pub(in crate::render) requested_fragments: u32,
    pub(in crate::render) volume_dirty: bool,
    /// The rows [0, converged_rows) whose every fragment is shaded (the others, part-way through
    /// progressive refinement, resolve normalised); u32::MAX after `render_frame`.
    pub(in crate::render) converged_rows: u32,
    /// The absorption changed but the volume (and the shadow grid's forward terms) still hold the old
    /// one ([`Renderer::set_absorption_deferred`]).
    pub(in crate::render) volume_stale: bool,
    /// The stale volume's density changed too (a deferred thickness change): its rebuild changes the
    /// grid's transmittance, which single scattering reads.
    pub(in crate::render) volume_stale_density: bool,
    /// The volume holds an old absorption that nothing reads now (multiple scattering off): rebuilt
    /// when multiple scattering is turned on.
    pub(in crate::render) volume_absorption_old: bool,
    pub(in crate::render) shadow_grid_dirty: bool,
    /// The refinement's plan re-shades multiple scattering alone: the segments' single scattering
    /// from the last converged pass still holds (a change that reaches only the forward and
    /// dual-scattering terms: new tables, a deferred absorption's volume).
    pub(in crate::render) single_kept: bool,
    /// Each segment's first point, in segment order (the brush's repaint finds the segments at the
    /// points a dab changed: [`Renderer::repaint_points`]).
    pub(in crate::render) segment_first: Vec<u32>,
    /// The segments a planned repaint shades again (sorted), and the image rows they cover.
    pub(in crate::render) repaint: Vec<u32>,
    pub(in crate::render) repaint_rows: std::ops::Range<u32>,
    /// Segments of dabs that came while a repaint was under way: repainted after it.
    pub(in crate::render) repaint_pending: Vec<u32>,
    /// Whether each pair of segments 2k, 2k + 1 shares its multiple-scattering sample (index k:
    /// [`crate::render::reference::shade::ms_paired`] at the absorption on the GPU), kept to notice a dab that changes it.
    pub(in crate::render) ms_pairs: Vec<bool>,
    /// The pairs (their even segments) whose sharing dabs changed since the last repaint started:
    /// their partners' multiple scattering moved ([`Renderer::repaint_points`]).
    pub(in crate::render) flips_pending: Vec<u32>,
    /// The pairs whose sharing changed for the repaint under way (sorted even segments).
    pub(in crate::render) repaint_flips: Vec<u32>,
    /// Every [`crate::render::refine::preview::PREVIEW_STRAND_STRIDE`]-th strand's segments, which a coarse
    /// preview draws (None for a hair of few strands).
    pub(in crate::render) preview_strands: Option<crate::render::passes::kbuffer::SegmentSubset>,
    /// The visible segments per row, read back after the frame's visibility (band sizes).
    pub(in crate::render) row_readback:
        Option<crate::render::refine::row_segments::RowSegmentsReadback>,
    /// The points as the GPU holds them (position, diameter), for the rows a repaint covers.
    pub(in crate::render) point_data: Vec<[f32; 4]>,
    pub(in crate::render) timer: Option<PassTimer>,
    pub(in crate::render) last_ran: Vec<&'static str>,
    /// Where progressive refinement ([`Renderer::refine`]) stands.
    pub(in crate::render) refinement: Refinement,
    /// Whether and how refinement previews a change, and the preview's targets.
    pub(in crate::render) preview_mode: PreviewMode,
    pub(in crate::render) preview: Option<Preview>,
    /// The frame's visibility pass has drawn the current camera and fibres (refinement reuses it
    /// after a parameter change).
    pub(in crate::render) visibility_valid: bool,
}

/// The occluder as the renderer holds it.
pub(in crate::render) struct SceneOccluder {
    pub(in crate::render) gpu: GpuOccluder,
    /// Its fraction of each voxel of the volume.
    solid: Vec<f32>,
    shadow_offset: f32,
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
            hair: gpu_hair,
            point_count: hair.point_count(),
            skip,
            volume,
            pyramid,
            shadow_grid,
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
            camera: uniform("camera", bytemuck::bytes_of(&camera_u)),
            camera_view: *camera,
            tile: None,
            lights: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lights"),
                contents: bytemuck::cast_slice(&gpu_lights(lights)),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            }),
            light_count: lights.len() as u32,
            resolve_info: uniform("resolve", bytemuck::bytes_of(&resolve_info)),
            resolve_params: resolve_info,
            background_map: environment_buffer(device, None),
            occluder: None,
            targets: FrameTargets::new(
                device,
                settings.width,
                settings.height,
                settings.samples,
                settings.kbuffer(),
            ),
            density_pass: FiberDensityPass::new(device),
            pyramid_pass: DensityPyramidPass::new(device),
            shadow_grid_pass: ShadowGridPass::new(device),
            visibility_pass: VisibilityPass::new(device, settings.samples),
            shading_pass: ShadingPass::new(device),
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
            resolve_pass: ResolvePass::new(device),
            segment_extent: segment_extent(hair),
            by_segment: false,
            volume_dirty: true,
            requested_fragments,
            converged_rows: u32::MAX,
            volume_stale: false,
            volume_stale_density: false,
            volume_absorption_old: false,
            shadow_grid_dirty: true,
            single_kept: false,
            segment_first,
            repaint: Vec::new(),
            repaint_rows: 0..0,
            repaint_pending: Vec::new(),
            ms_pairs,
            flips_pending: Vec::new(),
            repaint_flips: Vec::new(),
            row_readback: None,
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
            timer: PassTimer::new(ctx, &PASSES),
            last_ran: Vec::new(),
            refinement: Refinement::for_device(ctx),
            preview_mode: PreviewMode::Off,
            preview: None,
            visibility_valid: false,
            settings,
        };
        renderer.update_batches(device);
        renderer.grid_buffer_made();
        Ok(renderer)
    }
}
