//! The renderer the CLI, the benchmarks and the live driver drive: GPU resources for one hairstyle,
//! updated in place when parameters, absorption, lights or the camera change, and `render_frame`,
//! which encodes the passes in order (fiber density and pyramid when geometry or absorption changed,
//! the per-light shadow grid when they or the lights changed, visibility, shading batches, resolve).

pub mod table_cache;

use crate::envmap::SrbfLight;
use crate::gpu::GpuContext;
use crate::gpu::context::binding_limit;
use crate::gpu::density_pyramid::{DensityPyramidPass, GpuDensityPyramid};
use crate::gpu::dual_eval::dual_tables_texels;
use crate::gpu::fast_eval::GpuLuts;
use crate::gpu::fiber_density::{FiberDensityPass, GpuFiberDensity, GpuHair};
use crate::gpu::forward::{forward_table_texels, upload_forward_table};
use crate::hair::Hair;
use crate::render::camera::{Camera, Tile};
use crate::render::frame::Frame;
use crate::render::passes::background::BackgroundMap;
use crate::render::passes::kbuffer::{DEFAULT_FRAGMENTS, KBufferTargets, MAX_FRAGMENTS, Tail};
use crate::render::passes::occluder::{GpuOccluder, Occluder, SHADOW_OFFSET_SPACINGS};
use crate::render::passes::resolve::{ResolveInfo, ResolvePass};
use crate::render::passes::segment_shading::SegmentTargets;
use crate::render::passes::shading::{
    FLAG_MULTIPLE_SCATTERING, FLAG_SEGMENTS, FLAG_SHADOWS, GpuLight, ShadeBatch, ShadingInputs,
    ShadingPass,
};
use crate::render::passes::shadow_grid::{GpuShadowGrid, ShadowGridInputs, ShadowGridPass};
use crate::render::passes::targets::{COMPONENTS, FrameTargets, MAX_SEGMENTS};
use crate::render::passes::visibility::VisibilityPass;
use crate::render::reference::REFERENCE_VARIANT;
use crate::render::refine::Refinement;
use crate::render::refine::preview::{Preview, PreviewMode};
use crate::render::renderer::table_cache::with_cache;
use crate::render::timing::PassTimer;
use crate::scattering::azimuthal_table::AzimuthalTable;
use crate::scattering::dual_terms::DualTables;
use crate::scattering::fast_params::{DEFAULT_QUADRATURE_SEGMENTS, FastHairParams};
use crate::scattering::lut::Luts;
use crate::scattering::params::{HairParams, LongitudinalModel};
use crate::shadow::forward::ForwardTable;
use crate::shadow::grid::ShadowGrid;
use crate::shadow::solid::solid_fraction;
use crate::shadow::voxels::{MAX_DIM, VolumeGrid};
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

/// The hair parameters in both forms: the exact ones (for the tables built on the CPU) and the fast
/// model's uniform (quadrature segments, d_f, d_b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HairLook {
    pub params: HairParams,
    pub fast: FastHairParams,
}

impl HairLook {
    /// Whether `other` differs from this look in its eta or eccentricity and in nothing else.
    pub fn index_only_change(&self, other: &HairLook) -> bool {
        let mut same = *other;
        same.params.eta = self.params.eta;
        same.params.eccentricity = self.params.eccentricity;
        same.fast.eta = self.fast.eta;
        same.fast.eccentricity = self.fast.eccentricity;
        same == *self && other != self
    }

    /// Xu's m = 4 segments and Zinke's d_f = d_b = 0.7.
    pub fn new(params: HairParams) -> Self {
        Self {
            params,
            fast: FastHairParams::new(&params, DEFAULT_QUADRATURE_SEGMENTS),
        }
    }

    pub fn with_dual(mut self, d_f: f32, d_b: f32) -> Self {
        self.fast.d_f = d_f;
        self.fast.d_b = d_b;
        self
    }

    /// The longitudinal function (normalised by default).
    pub fn with_longitudinal(mut self, model: LongitudinalModel) -> Self {
        self.fast = self.fast.with_longitudinal(model);
        self
    }

    /// The exact model's form of this look's longitudinal function, for the references.
    pub fn longitudinal(&self) -> LongitudinalModel {
        self.fast.longitudinal_model()
    }
}

/// The tables that depend on hair parameters and are built on the CPU: the forward table (eta, alpha,
/// beta; read per crossed fiber's absorption), the dual-scattering tables (all parameters but the
/// absorption, which is their second axis: read per point's) and the azimuthal table of the exact
/// window integrals (eta and eccentricity; read per point's absorption).
/// The editor builds them on a worker thread ([`Renderer::set_params_deferred`], [`Renderer::set_tables`]).
#[derive(Clone)]
pub struct ParamTables {
    pub forward: ForwardTable,
    pub dual: DualTables,
    pub azimuthal: Arc<AzimuthalTable>,
}

/// Whether tables built for `a` serve `b`: every table reads each point's absorption on its own
/// axis, so only the other parameters matter (a melanin, dye or paint change needs no rebuild).
pub fn same_tables(a: &HairParams, b: &HairParams) -> bool {
    HairParams {
        sigma_a: b.sigma_a,
        ..*a
    } == *b
}

/// Builds the [`ParamTables`] of `params`, keeping `reuse` when its eta and eccentricity are the same
/// (and it is no draft);
/// the process keeps the tables of the last few parameter sets ([`crate::render::renderer::table_cache`]), so a set
/// built before is taken from there.
pub fn build_tables(params: &HairParams, reuse: Option<&Arc<AzimuthalTable>>) -> ParamTables {
    // The caller's table where it serves, kept or built: callers tell a new azimuthal table by
    // identity.
    let reuse = reuse.filter(|t| t.fits_hair(params)).cloned();
    if let Some(mut tables) = with_cache(|c| c.get(params)) {
        if let Some(r) = reuse {
            tables.azimuthal = r;
        }
        return tables;
    }
    let reuse = reuse.or_else(|| with_cache(|c| c.azimuthal(params)));
    let azimuthal = || {
        reuse.unwrap_or_else(|| {
            Arc::new(AzimuthalTable::build(
                params.eta as f32,
                params.eccentricity as f32,
            ))
        })
    };
    let ((forward, dual), azimuthal) = rayon::join(
        || {
            rayon::join(
                || ForwardTable::build(params, REFERENCE_VARIANT),
                || DualTables::build(params, REFERENCE_VARIANT),
            )
        },
        azimuthal,
    );
    let tables = ParamTables {
        forward,
        dual,
        azimuthal,
    };
    with_cache(|c| c.keep(params, &tables));
    tables
}

/// The azimuthal table a new eta or eccentricity previews with while [`build_tables`] builds the
/// tables: the process's kept table for that index when it has one, else a draft
/// ([`AzimuthalTable::build_draft`]: on two cores 0.06-0.07 s for a round fiber and 0.22-0.25 s for
/// an elliptical one, against 0.8 s and 3 s). Only the azimuthal table: the forward and dual tables
/// (another 0.1 s) change little with the index and follow with the tables, as for any other
/// parameter ([`Renderer::set_azimuthal_table`]). A draft is never kept.
pub fn build_draft_table(params: &HairParams) -> Arc<AzimuthalTable> {
    with_cache(|c| c.azimuthal(params)).unwrap_or_else(|| {
        Arc::new(AzimuthalTable::build_draft(
            params.eta as f32,
            params.eccentricity as f32,
        ))
    })
}

/// What a worker builds for new hair parameters ([`TableBuild::build`]).
#[derive(Clone)]
pub enum TableBuild {
    /// For a new eta or eccentricity, first: its azimuthal table alone, a draft unless the process
    /// keeps one ([`build_draft_table`], [`Renderer::set_azimuthal_table`]).
    Azimuthal(Arc<AzimuthalTable>),
    Tables(ParamTables),
}

impl TableBuild {
    /// With `draft` (a new eta or eccentricity, shown at once) the draft table, unless the process
    /// keeps the tables of `params` (an undo): then, and without `draft`, the tables. `reuse` as
    /// for [`build_tables`].
    pub fn build(params: &HairParams, reuse: Option<&Arc<AzimuthalTable>>, draft: bool) -> Self {
        if draft && !crate::render::renderer::table_cache::holds(params) {
            Self::Azimuthal(build_draft_table(params))
        } else {
            Self::Tables(build_tables(params, reuse))
        }
    }

    pub fn azimuthal(&self) -> &Arc<AzimuthalTable> {
        match self {
            Self::Azimuthal(t) => t,
            Self::Tables(t) => &t.azimuthal,
        }
    }

    /// The azimuthal table alone: the forward and dual tables are still to be built.
    pub fn azimuthal_only(&self) -> bool {
        matches!(self, Self::Azimuthal(_))
    }
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

/// What does not change from frame to frame without rebuilding targets.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Multisampling of the occluder in the visibility pass (2 or 4).
    pub samples: u32,
    /// Hair fragments kept per pixel by the K-buffer (1 to [`MAX_FRAGMENTS`]).
    pub fragments: u32,
    /// What becomes of the fragments behind the kept ones.
    pub tail: Tail,
    /// Exposure in stops applied by the resolve pass.
    pub exposure: f32,
    pub shadows: bool,
    /// Dual scattering (MS.global, MS.local) on top of single scattering.
    pub multiple_scattering: bool,
    /// Fibers cover at least this many pixels across (0: their true width; 1 draws the old opaque
    /// one-pixel ribbons).
    pub min_width_px: f32,
    /// SRBF lights per shading pass (at most 16).
    pub lights_per_pass: u32,
    /// Voxels along the hair's longest side for the fiber-density volume.
    pub volume_resolution: u32,
    /// Shadow paths skip this many voxels at the grid point (a shaded fiber's own density).
    pub shadow_skip_voxels: f32,
    /// Points of the per-light transmittance grid along the hair's longest side (48: on the blond-clump
    /// test against ray shooting the worst mean-colour error was 16 % at 32 points, 9.5 % at 48).
    pub shadow_grid_resolution: u32,
    /// Shade each visible segment once (each light's single-scattering response at its midpoint,
    /// weighted by the light's transmittance at its ends and midpoint; multiple scattering once per
    /// pair of consecutive segments of a strand with the same absorption, at the point they share:
    /// `shade::ShadingHair::ms_key`) instead of every kept fragment at its own point (false): ~8x
    /// fewer responses at full resolution (S1 on lavapipe: 8.9 s a frame against 101 s per
    /// fragment). On by default; its cost against per-fragment shading is bounded by
    /// `tests/render.rs`, and on the blond clump of `tests/ms_reference.rs` it stays at least as close
    /// to ray shooting (docs/testing.md gives the measured figures). Each light's
    /// response reads the absorption at each of the segment's ends where they differ (the midpoint's
    /// between them), so paint keeps its gradient along the segment; a pair whose points' absorption
    /// differs gets a multiple-scattering sample per segment.
    pub segment_shading: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 720,
            height: 480,
            samples: 4,
            fragments: DEFAULT_FRAGMENTS,
            tail: Tail::Spread,
            exposure: 0.0,
            shadows: true,
            multiple_scattering: true,
            min_width_px: 0.0,
            lights_per_pass: 16,
            volume_resolution: 128,
            shadow_skip_voxels: 0.5,
            shadow_grid_resolution: 48,
            segment_shading: true,
        }
    }
}

impl RenderSettings {
    /// The K-buffer's fragments per pixel and tail.
    pub fn kbuffer(&self) -> (u32, Tail) {
        (self.fragments, self.tail)
    }

    /// The fiber-density grid this renderer builds for `hair` (the CPU twin uses the same).
    pub fn volume_grid(&self, hair: &Hair) -> VolumeGrid {
        VolumeGrid::around(hair, self.voxel_size(hair))
    }

    pub fn voxel_size(&self, hair: &Hair) -> f32 {
        let (lo, hi) = hair.bounds();
        let n = self.volume_resolution.clamp(4, MAX_DIM as u32 - 2) as f32;
        ((hi - lo).max_element() / n).max(1e-3)
    }

    pub fn shadow_skip(&self, hair: &Hair) -> f32 {
        self.shadow_skip_voxels.max(0.0) * self.volume_grid(hair).voxel
    }

    /// The per-light transmittance grid (the CPU twin reads the same).
    pub fn shadow_grid(&self, hair: &Hair) -> ShadowGrid {
        ShadowGrid::around(
            &self.volume_grid(hair),
            self.shadow_grid_resolution.clamp(2, 256),
        )
    }
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

    /// Whether the frame can shade each segment once as the eye sees them now: every segment
    /// subtends at most [`MAX_SEGMENT_ANGLE`] (bounded by the longest over the distance from the eye
    /// to the hair's bounds).
    fn segments_fit_view(&self) -> bool {
        let (longest, lo, hi) = self.segment_extent;
        let c = self.view_camera();
        let eye = Vec3::from(c.eye);
        let distance = (eye.clamp(lo, hi) - eye).length().max(c.near);
        self.segment_targets.is_some() && longest / distance <= MAX_SEGMENT_ANGLE
    }

    /// The camera moved: the frame's batches switch between segments and fragments when the
    /// segments' angular size crossed [`MAX_SEGMENT_ANGLE`].
    fn update_shading_mode(&mut self, device: &wgpu::Device) {
        if self.segments_fit_view() != self.by_segment {
            self.update_batches(device);
        }
    }

    fn update_batches(&mut self, device: &wgpu::Device) {
        self.by_segment = self.segments_fit_view();
        let mut flags = 0;
        if self.settings.shadows {
            flags |= FLAG_SHADOWS;
        }
        if self.settings.multiple_scattering {
            flags |= FLAG_MULTIPLE_SCATTERING;
        }
        let slots = self.settings.fragments;
        let height = self.settings.height;
        let lights = self.light_count;
        // Per fragment, slot-major: every light batch at the front fragment (most of every pixel),
        // then at the ones behind it, so a refining image has all its lights early. Per segment: the
        // light batches, each over the segments of all the slots.
        let light_batches = ShadingPass::batches(self.light_count, self.settings.lights_per_pass);
        let slot_passes = if self.by_segment {
            flags |= FLAG_SEGMENTS;
            1
        } else {
            slots
        };
        let batches: Vec<ShadeBatch> = (0..slot_passes)
            .flat_map(|slot| {
                light_batches.iter().map(move |&(first, count)| ShadeBatch {
                    first,
                    count,
                    flags,
                    slots,
                    slot,
                    row0: 0,
                    rows: height,
                    lights,
                })
            })
            .collect();
        self.shading_pass.set_batches(device, &batches);
        self.restart_refinement();
    }

    /// Hair parameters changed: the uniform is rewritten; when the exact parameters changed, the
    /// forward and dual-scattering tables are rebuilt on the CPU and uploaded, and the shadow grid
    /// (whose T_f reads the forward table) is marked for rebuilding. No geometry, pipeline or volume
    /// rebuild.
    pub fn set_params(&mut self, ctx: &GpuContext, look: &HairLook) {
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&look.fast));
        self.look = *look;
        if self.tables_needed(&look.params) {
            let tables = build_tables(&look.params, Some(&self.azimuthal));
            self.set_tables(ctx, &look.params, &tables);
        }
        self.restart_refinement();
    }

    /// Renders one tile of a larger still with `camera` (the image size becomes the tile's; the
    /// shadow grid is kept from tile to tile).
    pub fn set_camera_tile(
        &mut self,
        ctx: &GpuContext,
        camera: &Camera,
        tile: Tile,
    ) -> Result<(), RenderError> {
        self.set_size(ctx, tile.size[0], tile.size[1])?;
        self.invalidate_visibility();
        self.camera_view = *camera;
        self.tile = Some(tile);
        let u = camera.tile_uniform(&tile, self.settings.min_width_px);
        ctx.queue
            .write_buffer(&self.camera, 0, bytemuck::bytes_of(&u));
        self.update_shading_mode(&ctx.device);
        self.restart_refinement();
        Ok(())
    }

    /// Hair parameters changed, without waiting for the tables: the uniform is rewritten now (single
    /// scattering shows the change in the next frame); returns true when the renderer needs tables for
    /// them ([`Renderer::tables_needed`]), and then the caller builds the tables ([`build_tables`], off
    /// the UI thread) and hands them to [`Renderer::set_tables`]. Until then multiple scattering and
    /// forward transmittance use the old tables, and a new eta or eccentricity waits for an azimuthal
    /// table made for it (the frame keeps the old index: `write_params`); the editor hands it a draft
    /// first ([`TableBuild::build`], [`Renderer::set_azimuthal_table`]).
    pub fn set_params_deferred(&mut self, ctx: &GpuContext, look: &HairLook) -> bool {
        let tables_needed = self.tables_needed(&look.params);
        let (before, index_only) = (self.frame_params(), self.look.index_only_change(look));
        self.look = *look;
        self.write_params(ctx);
        // A new eta or eccentricity alone changes nothing a frame reads until a table made for it
        // arrives: the image stays, and the cores stay free for that table's build. Any other
        // change restarts, even one the frame's parameters do not show (the tables will).
        if !index_only || self.frame_params() != before {
            self.restart_refinement();
        }
        tables_needed
    }

    /// Whether `params` need tables this renderer does not hold: other parameters than the
    /// absorption, or an azimuthal table not made for them (a draft, [`build_draft_table`], or one
    /// shown ahead of its tables for another index: [`Renderer::set_azimuthal_table`]).
    pub fn tables_needed(&self, params: &HairParams) -> bool {
        !same_tables(params, &self.tables_for) || !self.azimuthal.fits_hair(params)
    }

    /// Writes the look's fast parameters, with the azimuthal table's eta and eccentricity while the
    /// table for new ones is being built: a frame never reads a table made for another index (an eta or
    /// eccentricity change shows when a table made for it arrives: in the editor its draft, 0.06-0.07 s
    /// of build on two cores for a round fiber and 0.22-0.25 s for an elliptical one, then the table,
    /// 0.8 s and 3 s).
    fn write_params(&self, ctx: &GpuContext) {
        let fast = self.frame_params();
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&fast));
    }

    /// The fast parameters a frame reads: the look's, with the azimuthal table's eta and
    /// eccentricity while the table for new ones is being built.
    fn frame_params(&self) -> FastHairParams {
        let mut fast = self.look.fast;
        if !self.azimuthal.for_index(&fast) {
            fast.eta = self.azimuthal.eta;
            fast.eccentricity = self.azimuthal.eccentricity;
        }
        fast
    }

    /// The azimuthal table in use (kept by a rebuild for the same eta and eccentricity).
    pub fn azimuthal_table(&self) -> &Arc<AzimuthalTable> {
        &self.azimuthal
    }

    /// Takes what a worker built for `params` ([`TableBuild`]); false when ignored (the look has
    /// moved on since).
    pub fn take_tables(
        &mut self,
        ctx: &GpuContext,
        params: &HairParams,
        built: &TableBuild,
    ) -> bool {
        match built {
            TableBuild::Azimuthal(table) => self.set_azimuthal_table(ctx, params, table),
            TableBuild::Tables(tables) => self.set_tables(ctx, params, tables),
        }
    }

    /// A new eta or eccentricity's azimuthal table ahead of its other tables (its draft,
    /// [`build_draft_table`]): the index shows from the next frame, its single scattering a preview
    /// away. The forward and dual tables, which change little with the index, stay until the tables
    /// arrive ([`Renderer::set_tables`]), as after any other parameter change: the shadow grid is
    /// kept, and the renderer still asks for the tables ([`Renderer::tables_needed`]). Ignored
    /// (false) when the look has moved on or the table is not for its index.
    pub fn set_azimuthal_table(
        &mut self,
        ctx: &GpuContext,
        params: &HairParams,
        table: &Arc<AzimuthalTable>,
    ) -> bool {
        if !same_tables(params, &self.look.params) || !table.made_for_hair(params) {
            return false;
        }
        if !Arc::ptr_eq(&self.azimuthal, table) {
            self.upload_azimuthal(ctx, table);
            self.restart_refinement();
        }
        true
    }

    /// The azimuthal table to the GPU, and the parameters a frame reads with it (`write_params`).
    fn upload_azimuthal(&mut self, ctx: &GpuContext, table: &Arc<AzimuthalTable>) {
        ctx.queue
            .write_buffer(&self.azimuthal_table, 0, table.gpu_bytes());
        self.azimuthal = table.clone();
        self.write_params(ctx);
    }

    /// Uploads tables built for `params`; ignored (false) when the look has moved on since.
    pub fn set_tables(
        &mut self,
        ctx: &GpuContext,
        params: &HairParams,
        tables: &ParamTables,
    ) -> bool {
        if !same_tables(params, &self.look.params) {
            return false;
        }
        ctx.queue.write_buffer(
            &self.forward_table,
            0,
            bytemuck::cast_slice(&forward_table_texels(&tables.forward)),
        );
        ctx.queue.write_buffer(
            &self.dual_tables,
            0,
            bytemuck::cast_slice(&dual_tables_texels(&tables.dual)),
        );
        let azimuthal_changed = !Arc::ptr_eq(&self.azimuthal, &tables.azimuthal);
        // The table after its draft (or after a kept table for its index, shown ahead of its
        // tables): the index is on screen, and the refinement goes on as a refinement. Tables for
        // another index (an undo while a draft shows) owe a preview.
        let after_draft = azimuthal_changed && self.azimuthal.made_for_hair(params);
        // Whether the forward and dual tables are new (the grid's forward terms read the forward
        // table): not for tables of the parameters these were built for.
        let others_changed = !same_tables(params, &self.tables_for);
        if azimuthal_changed {
            self.upload_azimuthal(ctx, &tables.azimuthal);
        }
        self.tables_for = *params;
        // The forward and dual tables are read only with multiple scattering (the grid's forward
        // terms, the shading's dual terms); without it only a new azimuthal table changes the image.
        // A new azimuthal table shows a change not on screen yet (an eta or eccentricity change waits
        // for it): a preview is owed, unless its draft showed it; the others refine the change
        // already shown.
        let regrid = self.settings.multiple_scattering && others_changed;
        if after_draft {
            if regrid {
                self.restart_as_refinement(|r| r.mark_shadow_grid_dirty());
            } else {
                self.restart_as_refinement(|r| r.restart_refinement());
            }
        } else if azimuthal_changed {
            if regrid {
                self.mark_shadow_grid_dirty();
            } else {
                self.restart_refinement();
            }
        } else if regrid {
            // The grid's transmittance and the single scattering read no table: a converged image
            // keeps its single scattering, and only multiple scattering is shaded again.
            self.refine_multiple_only(|r| r.mark_shadow_grid_dirty());
        }
        true
    }

    pub fn set_camera(&mut self, ctx: &GpuContext, camera: &Camera) {
        self.invalidate_visibility();
        self.camera_view = *camera;
        self.tile = None;
        let u = camera.uniform(
            self.settings.width,
            self.settings.height,
            self.settings.min_width_px,
        );
        ctx.queue
            .write_buffer(&self.camera, 0, bytemuck::bytes_of(&u));
        self.update_shading_mode(&ctx.device);
        self.restart_refinement();
    }

    /// Painted absorption (one RGB per point): rewrites the buffer and marks the volume (which carries
    /// the absorption along shadow paths) for rebuilding.
    pub fn set_absorption(
        &mut self,
        ctx: &GpuContext,
        sigma_a: &[[f32; 3]],
    ) -> Result<(), RenderError> {
        self.upload_absorption(ctx, sigma_a)?;
        self.mark_volume_dirty();
        Ok(())
    }

    /// New absorption per point for shading at once, the volume and shadow grid (whose forward terms
    /// carry the crossed fibers' absorption) kept until [`Renderer::rebuild_stale_volume`]: single
    /// scattering, which reads only the grid's transmittance (absorption-free), is exact meanwhile, and
    /// the editor shows a dye or melanin change before spending the grid's rebuild on it.
    pub fn set_absorption_deferred(
        &mut self,
        ctx: &GpuContext,
        sigma_a: &[[f32; 3]],
    ) -> Result<(), RenderError> {
        self.upload_absorption(ctx, sigma_a)?;
        self.absorption_deferred();
        // Shown at once (not left to a parameter change that may not restart).
        self.restart_refinement();
        Ok(())
    }

    /// [`Renderer::set_absorption_deferred`] for a few points (a brush dab): `sigma_a` holds every
    /// point's absorption, and only the points `changed` (sorted) are written, in runs (gaps of a few
    /// unchanged points are written along rather than split). Every point not in `changed` must
    /// hold what the renderer has already (the runs write some of them, and the pairs' sharing,
    /// [`Renderer::ms_pairs`], reads the changed points' neighbours from `sigma_a`).
    pub fn set_absorption_points_deferred(
        &mut self,
        ctx: &GpuContext,
        sigma_a: &[[f32; 3]],
        changed: &[u32],
    ) -> Result<(), RenderError> {
        if sigma_a.len() != self.point_count {
            return Err(RenderError::AbsorptionCount {
                points: self.point_count,
                absorption: sigma_a.len(),
            });
        }
        const GAP: u32 = 16;
        let mut k = 0;
        while k < changed.len() {
            let start = changed[k];
            let mut end = start + 1;
            k += 1;
            while k < changed.len() && changed[k] < end + GAP {
                end = changed[k] + 1;
                k += 1;
            }
            let end = (end as usize).min(sigma_a.len());
            let v: Vec<[f32; 4]> = sigma_a[start as usize..end]
                .iter()
                .map(|s| [s[0], s[1], s[2], 0.0])
                .collect();
            ctx.queue.write_buffer(
                &self.hair.absorption,
                16 * start as u64,
                bytemuck::cast_slice(&v),
            );
        }
        self.note_pair_flips(sigma_a, changed);
        self.absorption_deferred();
        Ok(())
    }

    /// Updates [`Renderer::ms_pairs`] for the pairs holding the points `changed`, now at absorption
    /// `sigma_a`, and lists those whose sharing changed in [`Renderer::flips_pending`].
    fn note_pair_flips(&mut self, sigma_a: &[[f32; 3]], changed: &[u32]) {
        let segments: Vec<u32> = changed
            .iter()
            .flat_map(|&i| self.segments_at_point(i))
            .collect();
        for k in segments {
            let even = k & !1;
            let paired =
                crate::render::reference::shade::ms_paired(&self.segment_first, sigma_a, even);
            let Some(was) = self.ms_pairs.get_mut(k as usize / 2) else {
                continue;
            };
            if *was != paired {
                *was = paired;
                self.flips_pending.push(even);
            }
        }
    }

    /// The segments that join point `i`: the one from it and the one to it (from i - 1, in the
    /// same strand).
    pub(in crate::render) fn segments_at_point(&self, i: u32) -> impl Iterator<Item = u32> + '_ {
        [Some(i), i.checked_sub(1)]
            .into_iter()
            .flatten()
            .filter_map(|p| self.segment_first.binary_search(&p).ok())
            .map(|k| k as u32)
    }

    /// The absorption changed (shown at once): the volume and grid that carry it follow later.
    fn absorption_deferred(&mut self) {
        if self.volume_dirty {
            // A deposit under way holds points or absorption of before: it starts again.
            self.restart_refinement();
            return;
        }
        // Only the grid's forward terms read the volume's absorption.
        if self.settings.shadows && self.settings.multiple_scattering && self.light_count > 0 {
            self.volume_stale = true;
        } else {
            self.volume_absorption_old = true;
        }
    }

    /// Whether a deferred absorption change still waits for its volume and grid.
    pub fn volume_stale(&self) -> bool {
        self.volume_stale
    }

    /// Rebuilds the volume and grid for a deferred absorption change (restarting the refinement);
    /// false when there was none.
    pub fn rebuild_stale_volume(&mut self) -> bool {
        if !self.volume_stale {
            return false;
        }
        // The change itself is on screen (shaded with the old volume): no new preview. After an
        // absorption change the volume's density, and so the grid's transmittance, stays: a converged
        // image keeps its single scattering (shaded at the new absorption already). A thickness
        // change's density shadows single scattering too.
        if self.volume_stale_density {
            self.restart_as_refinement(|r| r.mark_volume_dirty());
        } else {
            self.refine_multiple_only(|r| r.mark_volume_dirty());
        }
        true
    }

    fn upload_absorption(
        &mut self,
        ctx: &GpuContext,
        sigma_a: &[[f32; 3]],
    ) -> Result<(), RenderError> {
        if sigma_a.len() != self.point_count {
            return Err(RenderError::AbsorptionCount {
                points: self.point_count,
                absorption: sigma_a.len(),
            });
        }
        let v: Vec<[f32; 4]> = sigma_a.iter().map(|s| [s[0], s[1], s[2], 0.0]).collect();
        ctx.queue
            .write_buffer(&self.hair.absorption, 0, bytemuck::cast_slice(&v));
        // Every point changes: the refinement restarts, shading every segment whole.
        self.ms_pairs = all_ms_pairs(&self.segment_first, sigma_a);
        self.flips_pending.clear();
        Ok(())
    }

    pub fn set_lights(&mut self, ctx: &GpuContext, lights: &[SrbfLight]) {
        let v = gpu_lights(lights);
        let bytes: &[u8] = bytemuck::cast_slice(&v);
        if bytes.len() as u64 > self.lights.size() {
            self.lights = crate::gpu::context::buffer_init(
                &ctx.device,
                "lights",
                bytes,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            );
        } else {
            ctx.queue.write_buffer(&self.lights, 0, bytes);
        }
        self.light_count = lights.len() as u32;
        if self.light_count != self.shadow_grid.light_count {
            self.shadow_grid = self.shadow_grid.with_lights(
                &ctx.device,
                self.light_count,
                self.skip,
                self.settings.multiple_scattering,
            );
            self.grid_buffer_made();
        }
        // An absorption change made while no grid read it (no lights) waits in the volume: the
        // grid's forward terms read it now.
        if self.volume_absorption_old
            && self.settings.shadows
            && self.settings.multiple_scattering
            && self.light_count > 0
        {
            self.mark_volume_dirty();
        } else {
            self.mark_shadow_grid_dirty();
        }
        self.update_batches(&ctx.device);
    }

    /// Rewrites the points buffer with `hair`'s diameters times `thickness_scale`.
    fn write_thickness(
        &mut self,
        ctx: &GpuContext,
        hair: &Hair,
        thickness_scale: f32,
    ) -> Result<(), RenderError> {
        if hair.point_count() != self.point_count {
            return Err(RenderError::HairPoints {
                renderer: self.point_count,
                given: hair.point_count(),
            });
        }
        let points = GpuHair::point_data(hair, thickness_scale);
        ctx.queue
            .write_buffer(&self.hair.points, 0, bytemuck::cast_slice(&points));
        self.point_data = points;
        // The ribbons' width changed: the visibility passes draw them again.
        self.invalidate_visibility();
        Ok(())
    }

    /// A new shadow-grid buffer holds zeros, not finished entries: its groups count as unbuilt (its
    /// samples are the old grid's, [`GpuShadowGrid::with_lights`], or unbuilt in a new renderer).
    fn grid_buffer_made(&mut self) {
        let group = self
            .settings
            .lights_per_pass
            .clamp(1, crate::render::passes::shading::MAX_LIGHTS_PER_PASS)
            * crate::render::passes::shadow_grid::SWEEP_SLOTS;
        self.refinement
            .grid_unbuilt(group, self.shadow_grid.entry_count());
    }

    /// Every fiber's diameter is `hair`'s times `thickness_scale` (the look's fiber thickness, `hair`
    /// the one the renderer was made with): the points are rewritten and the volume, and with it the
    /// shadow grid, rebuilt; the ribbons in the view follow at once.
    pub fn set_thickness_scale(
        &mut self,
        ctx: &GpuContext,
        hair: &Hair,
        thickness_scale: f32,
    ) -> Result<(), RenderError> {
        self.write_thickness(ctx, hair, thickness_scale)?;
        self.mark_volume_dirty();
        Ok(())
    }

    /// [`Renderer::set_thickness_scale`] for the editor: the ribbons' new width shows at once and, with
    /// shadows, the first image is shaded with the old volume and grid, which
    /// [`Renderer::rebuild_stale_volume`] rebuilds after it (a slider drag is not a volume rebuild
    /// per frame). Without shadows nothing reads the volume until they are turned on: it is rebuilt
    /// then.
    pub fn set_thickness_scale_deferred(
        &mut self,
        ctx: &GpuContext,
        hair: &Hair,
        thickness_scale: f32,
    ) -> Result<(), RenderError> {
        self.write_thickness(ctx, hair, thickness_scale)?;
        if self.volume_dirty {
            // A deposit under way holds points or absorption of before: it starts again.
            self.restart_refinement();
            return Ok(());
        }
        if self.settings.shadows && self.light_count > 0 {
            self.volume_stale = true;
            self.volume_stale_density = true;
            self.restart_refinement();
        } else {
            self.mark_volume_dirty();
        }
        Ok(())
    }

    /// The occluder (None: none): drawn opaque in front of the hair behind it, shaded under the lights,
    /// and added to the fiber-density volume as a solid so that it shadows the hair (the volume and the
    /// shadow grid are rebuilt; the voxelisation runs here, on the CPU: ~10 ms for the generated head).
    pub fn set_occluder(&mut self, ctx: &GpuContext, occluder: Option<&Occluder>) {
        self.occluder = occluder.map(|o| {
            let offset = SHADOW_OFFSET_SPACINGS * self.shadow_grid.grid.spacing;
            SceneOccluder {
                gpu: GpuOccluder::new(&ctx.device, o, offset),
                solid: solid_fraction(&self.volume.grid, &o.mesh),
                shadow_offset: offset,
            }
        });
        self.volume.set_solid(
            &ctx.queue,
            self.occluder.as_ref().map(|o| o.solid.as_slice()),
        );
        self.invalidate_visibility();
        self.mark_volume_dirty();
    }

    /// The occluder's albedo alone changed: its shading restarts, nothing else.
    pub fn set_occluder_albedo(&mut self, ctx: &GpuContext, albedo: [f32; 3]) {
        if let Some(o) = &self.occluder {
            o.gpu.set_albedo(&ctx.queue, albedo);
            self.restart_refinement();
        }
    }

    /// The occluder's voxel fractions and the offset its shadow lookups use (tests: the CPU twins).
    pub fn occluder_solid(&self) -> Option<(&[f32], f32)> {
        self.occluder
            .as_ref()
            .map(|o| (o.solid.as_slice(), o.shadow_offset))
    }

    /// The next frame rebuilds the fiber-density volume (geometry moved; benchmarks time it).
    pub fn mark_volume_dirty(&mut self) {
        self.volume_dirty = true;
        // The sweeps' samples read the pyramid the volume makes.
        self.refinement.samples_done = 0;
        self.volume_stale = false;
        self.volume_stale_density = false;
        self.volume_absorption_old = false;
        self.mark_shadow_grid_dirty();
    }

    /// The next frame rebuilds the per-light transmittance grid (benchmarks time it).
    pub fn mark_shadow_grid_dirty(&mut self) {
        self.shadow_grid_dirty = true;
        self.refinement.grid_done = 0;
        self.restart_refinement();
    }

    pub fn light_count(&self) -> u32 {
        self.light_count
    }

    /// The image size changed (the editor's viewport): new frame targets and shading bands; the
    /// volume and the shadow grid are kept.
    pub fn set_size(
        &mut self,
        ctx: &GpuContext,
        width: u32,
        height: u32,
    ) -> Result<(), RenderError> {
        let max = ctx.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::Size(width, height, max));
        }
        if (width, height) == (self.settings.width, self.settings.height) {
            return Ok(());
        }
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        let bytes = width as u64 * height as u64 * 16;
        if bytes > limit {
            return Err(RenderError::TooLarge {
                what: format!("a {width}x{height} image"),
                bytes,
                limit,
            });
        }
        self.refinement
            .resized(width as f64 / self.settings.width.max(1) as f64);
        self.resized_preview(width, height);
        self.settings.width = width;
        self.settings.height = height;
        self.settings.fragments = KBufferTargets::fitting(
            binding_limit(&ctx.device),
            width,
            height,
            self.requested_fragments,
        );
        self.targets = FrameTargets::new(
            &ctx.device,
            width,
            height,
            self.settings.samples,
            self.settings.kbuffer(),
        );
        // The camera uniform holds the image size (projection aspect, pixel rays); a tile's is written
        // by set_camera_tile after this.
        let camera = self.camera_view;
        self.set_camera(ctx, &camera);
        self.update_batches(&ctx.device);
        Ok(())
    }

    /// Shadows and multiple scattering on or off (no rebuild of anything but the batches; the grid
    /// is built when first needed).
    pub fn set_toggles(&mut self, ctx: &GpuContext, shadows: bool, multiple_scattering: bool) {
        if (shadows, multiple_scattering)
            == (self.settings.shadows, self.settings.multiple_scattering)
        {
            return;
        }
        if multiple_scattering != self.settings.multiple_scattering {
            // The grid's layout (and what it holds) depends on multiple scattering.
            self.shadow_grid = self.shadow_grid.with_lights(
                &ctx.device,
                self.light_count,
                self.skip,
                multiple_scattering,
            );
            self.grid_buffer_made();
            self.shadow_grid_dirty = true;
            self.refinement.grid_done = 0;
        }
        self.settings.shadows = shadows;
        self.settings.multiple_scattering = multiple_scattering;
        self.update_batches(&ctx.device);
        // The grid's forward terms read the volume's absorption, and the grid is rebuilt now: the
        // volume first, so that it is rebuilt once.
        if self.volume_absorption_old && shadows && multiple_scattering {
            self.mark_volume_dirty();
        }
    }

    /// Exposure in stops applied by the resolve pass (and by `read_frame`).
    pub fn set_exposure(&mut self, ctx: &GpuContext, exposure: f32) {
        self.settings.exposure = exposure;
        self.resolve_params.exposure_scale = exposure.exp2();
        self.resolve_again(ctx, "exposure");
    }

    /// The environment seen behind the hair (None: none; the background target holds zeros), turned
    /// by `yaw` radians about +Y (world = rotate_yaw(map direction, yaw); a map made for turned lights
    /// gives its own `yaw`). The resolve writes it with every image; here once more for the current one.
    pub fn set_background(&mut self, ctx: &GpuContext, map: Option<&BackgroundMap>, yaw: f32) {
        let r = &mut self.resolve_params;
        r.env_width = map.map_or(0, |m| m.width);
        r.env_height = map.map_or(0, |m| m.height);
        r.env_yaw = yaw;
        self.background_map = environment_buffer(&ctx.device, map);
        self.resolve_again(ctx, "background");
    }

    /// Turns the background (the environment's yaw changed; no upload).
    pub fn set_background_yaw(&mut self, ctx: &GpuContext, yaw: f32) {
        if self.resolve_params.env_yaw != yaw {
            self.resolve_params.env_yaw = yaw;
            self.resolve_again(ctx, "background yaw");
        }
    }

    /// Writes the resolve's parameters and resolves the current image (and preview) again: only the
    /// resolve changed, which runs after every unit anyway.
    fn resolve_again(&mut self, ctx: &GpuContext, label: &str) {
        ctx.queue.write_buffer(
            &self.resolve_info,
            0,
            bytemuck::bytes_of(&self.resolve_params),
        );
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        // Rows the last shading batch has finished resolve as render_frame's; the others normalised
        // while refinement runs.
        let height = self.settings.height;
        let done = self.converged_rows.min(height);
        for (rows, normalise) in [(0..done, false), (done..height, true)] {
            if rows.is_empty() {
                continue;
            }
            self.resolve_pass.encode(
                &ctx.device,
                &mut enc,
                &self.camera,
                &self.resolve_info,
                &self.background_map,
                &self.targets,
                rows,
                (true, normalise),
                None,
            );
        }
        if let Some(p) = &self.preview {
            self.resolve_pass.encode(
                &ctx.device,
                &mut enc,
                &p.camera,
                &self.resolve_info,
                &self.background_map,
                &p.targets,
                0..p.targets.height,
                (true, false),
                None,
            );
        }
        ctx.queue.submit([enc.finish()]);
    }

    fn extras(&self) -> Extras {
        Extras {
            background: self.has_background(),
            occluder: self.occluder.is_some(),
            fragments: true,
        }
    }

    /// Whether the resolve writes a background (a map was given to [`Renderer::set_background`]).
    pub fn has_background(&self) -> bool {
        self.resolve_params.env_width > 0
    }

    /// The frame's targets (the display pass reads the beauty).
    pub fn targets(&self) -> &FrameTargets {
        &self.targets
    }

    /// The hair parameters the renderer holds.
    pub fn look(&self) -> &HairLook {
        &self.look
    }

    /// What the shadow-grid build reads.
    pub(in crate::render) fn shadow_grid_inputs(&self) -> ShadowGridInputs<'_> {
        ShadowGridInputs {
            pyramid: &self.pyramid,
            volume: &self.volume,
            forward_table: &self.forward_table,
            lights: &self.lights,
            light_group: self
                .settings
                .lights_per_pass
                .clamp(1, crate::render::passes::shading::MAX_LIGHTS_PER_PASS),
        }
    }

    /// What the shading pass reads.
    pub(in crate::render) fn shading_inputs(&self) -> ShadingInputs<'_> {
        ShadingInputs {
            camera: &self.camera,
            params: &self.params,
            shadow_grid: &self.shadow_grid.info,
            points: &self.hair.points,
            segments: &self.hair.segments,
            absorption: &self.hair.absorption,
            lights: &self.lights,
            lut_c: &self.luts.c,
            shadow_values: &self.shadow_grid.values,
            dual_tables: &self.dual_tables,
            azimuthal_table: &self.azimuthal_table,
            occluder: self.occluder.as_ref().map(|o| &o.gpu),
            segment_targets: self.segment_targets.as_ref(),
        }
    }

    /// Whether the frame (and its preview) shades each visible segment once (else every fragment: per-fragment
    /// shading asked for, segment buffers that would not fit a binding, or segments that the eye sees
    /// under more than [`MAX_SEGMENT_ANGLE`]).
    pub fn shades_segments(&self) -> bool {
        self.by_segment
    }

    /// Encodes and submits one frame.
    pub fn render_frame(&mut self, ctx: &GpuContext) {
        let device = &ctx.device;
        let timer = self.timer.as_ref();
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        });
        self.last_ran.clear();
        if self.volume_dirty {
            self.density_pass.encode(
                device,
                &mut enc,
                &self.hair,
                &self.volume,
                timer.and_then(|t| t.compute_writes("fiber_density")),
            );
            self.pyramid_pass.encode(
                device,
                &mut enc,
                &self.volume,
                &self.pyramid,
                timer.and_then(|t| t.compute_writes("density_pyramid")),
            );
            self.last_ran.extend(["fiber_density", "density_pyramid"]);
            self.volume_dirty = false;
            self.shadow_grid_dirty = true;
            self.refinement.grid_done = 0;
            self.refinement.samples_done = 0;
        }
        if self.shadow_grid_dirty && self.settings.shadows && self.light_count > 0 {
            let count = self.shadow_grid.entry_count();
            let inputs = self.shadow_grid_inputs();
            let samples = self.shadow_grid.sample_count();
            let samples_stale = self.refinement.samples_done < samples;
            if samples_stale {
                self.shadow_grid_pass.encode_samples(
                    device,
                    &mut enc,
                    &inputs,
                    &self.shadow_grid,
                    0..samples,
                    timer.and_then(|t| t.compute_writes("grid_samples")),
                );
            }
            self.shadow_grid_pass.encode(
                device,
                &mut enc,
                &inputs,
                &self.shadow_grid,
                0,
                count,
                timer.and_then(|t| t.compute_writes("shadow_grid")),
            );
            if samples_stale {
                self.last_ran.push("grid_samples");
            }
            self.last_ran.push("shadow_grid");
            self.refinement.samples_done = samples;
            self.shadow_grid_dirty = false;
            self.refinement.grid_complete(count);
        }
        self.visibility_pass.encode(
            device,
            &mut enc,
            &self.camera,
            &self.hair,
            self.occluder.as_ref().map(|o| &o.gpu),
            &self.targets,
            0..self.hair.segment_count,
            None,
            timer.and_then(|t| t.render_writes("visibility")),
        );
        let mut readback = self.row_readback.take();
        self.encode_row_segments_into(device, &mut enc, &mut readback);
        self.row_readback = readback;
        let inputs = self.shading_inputs();
        self.shading_pass.encode(
            device,
            &mut enc,
            &inputs,
            &self.targets,
            timer.and_then(|t| t.compute_writes("shading")),
        );
        self.resolve_pass.encode(
            device,
            &mut enc,
            &self.camera,
            &self.resolve_info,
            &self.background_map,
            &self.targets,
            0..self.settings.height,
            (true, false),
            timer.and_then(|t| t.compute_writes("resolve")),
        );
        self.visibility_valid = true;
        self.converged_rows = u32::MAX;
        self.last_ran.extend(["visibility", "shading", "resolve"]);
        if let Some(t) = timer {
            t.resolve(&mut enc);
        }
        ctx.queue.submit([enc.finish()]);
        self.request_row_segments();
        self.refinement.complete_frame();
        // The whole frame is shaded: no dab waits for a repaint, nothing is kept.
        self.repaint_pending.clear();
        self.flips_pending.clear();
        self.single_kept = false;
    }

    /// Rebuilds the whole shadow grid alone, its sweeps' samples included, and waits for it:
    /// wall-clock seconds (benchmarks). On lavapipe
    /// a compute pass's timestamps bracket the dispatch's submission to its thread pool, not its work, so
    /// a pass that no later barrier waits for inside its own bracket (the grid) reads ~0 ms there.
    pub fn time_shadow_grid(&mut self, ctx: &GpuContext) -> Result<f64, RenderError> {
        if !self.settings.shadows || self.light_count == 0 {
            return Ok(0.0);
        }
        let t = std::time::Instant::now();
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("shadow grid alone"),
            });
        let inputs = self.shadow_grid_inputs();
        let samples = self.shadow_grid.sample_count();
        self.shadow_grid_pass.encode_samples(
            &ctx.device,
            &mut enc,
            &inputs,
            &self.shadow_grid,
            0..samples,
            None,
        );
        self.shadow_grid_pass.encode(
            &ctx.device,
            &mut enc,
            &inputs,
            &self.shadow_grid,
            0,
            self.shadow_grid.entry_count(),
            None,
        );
        self.refinement.samples_done = samples;
        ctx.queue.submit([enc.finish()]);
        ctx.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        self.refinement
            .grid_complete(self.shadow_grid.entry_count());
        Ok(t.elapsed().as_secs_f64())
    }

    /// GPU milliseconds per pass of the last frame (None without timestamp queries).
    pub fn pass_times(
        &self,
        ctx: &GpuContext,
    ) -> Result<Option<Vec<(&'static str, f64)>>, RenderError> {
        match &self.timer {
            None => Ok(None),
            Some(t) => t
                .read_ms(ctx, &self.last_ran)
                .map(Some)
                .map_err(RenderError::Gpu),
        }
    }

    /// Waits for the last frame and reads every output back.
    pub fn read_frame(&self, ctx: &GpuContext) -> Result<Frame, RenderError> {
        self.read_targets(ctx, &self.targets)
    }

    /// [`Renderer::read_frame`] without the K-buffer (a tile of a still).
    pub fn read_image(&self, ctx: &GpuContext) -> Result<Frame, RenderError> {
        let extras = Extras {
            fragments: false,
            ..self.extras()
        };
        self.read_with(ctx, &self.targets, extras)
    }

    /// Reads every output of `t` (the frame's targets or the preview's) back, waiting for the GPU.
    pub(in crate::render) fn read_targets(
        &self,
        ctx: &GpuContext,
        t: &FrameTargets,
    ) -> Result<Frame, RenderError> {
        self.read_with(ctx, t, self.extras())
    }

    fn read_with(
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

    fn start_read(&self, ctx: &GpuContext, extras: Extras) -> FrameReadBack {
        let t = &self.targets;
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
            .read_buffer::<[f32; 8]>(&self.shadow_grid.values)
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

/// What a frame reads besides the always-read buffers.
#[derive(Clone, Copy, Debug)]
struct Extras {
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

/// (width, height, occluder samples, K-buffer slots) of a frame's targets.
type Shape = (u32, u32, u32, u32);

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

#[cfg(test)]
mod tests {
    use super::*;

    /// Only an eta or eccentricity change alone leaves the refinement as it is
    /// ([`Renderer::set_params_deferred`]); a change the fast form does not carry restarts it.
    #[test]
    fn an_index_only_change_is_told_apart() {
        let a = HairLook::new(HairParams::default());
        let mut p = a.params;
        p.eta = 1.6;
        p.eccentricity = 0.9;
        assert!(a.index_only_change(&HairLook::new(p)));
        assert!(!a.index_only_change(&a), "the same look is no change");
        let mut q = p;
        q.beta_r *= 0.5;
        assert!(!a.index_only_change(&HairLook::new(q)));
        let mut r = a.params;
        r.glint_scale *= 2.0;
        assert!(!a.index_only_change(&HairLook::new(r)));
    }
}
