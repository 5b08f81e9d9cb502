//! The shadow-grid pass (`shaders/shadow_grid_build.wgsl`): every light's transmittance and
//! forward-scattering terms at every point of a coarse grid by light-space sweeps, one workgroup per
//! light, rebuilt when the volume, the lights or the forward table change ([`crate::shadow::sweep`] is
//! the CPU twin).

use crate::gpu::context::{bind_buffers, buffer_init, compute_pipeline};
use crate::gpu::density_pyramid::GpuDensityPyramid;
use crate::gpu::fiber_density::GpuFiberDensity;
use crate::gpu::shaders;
use crate::shadow::grid::ShadowGrid;
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ShadowGridInfo {
    pub origin: [f32; 3],
    pub spacing: f32,
    pub dims: [u32; 3],
    pub light_count: u32,
    pub skip: f32,
    /// 1: the forward-scattering terms are computed (multiple scattering on).
    pub forward: u32,
    pub _pad: [f32; 2],
}

const _: () = assert!(std::mem::size_of::<ShadowGridInfo>() == 48);

/// The grid's uniform and its values (two vec4 per grid point and light, light-major: ln transmittance,
/// ln T_f RGB; sigma_f^2 RGB, optical depth behind the point along the light's travel).
pub struct GpuShadowGrid {
    pub grid: ShadowGrid,
    pub info: wgpu::Buffer,
    pub values: wgpu::Buffer,
    /// Two slices of path integrals per light (two vec4 per point, [`SCRATCH_BYTES`]), the sweeps'
    /// working memory.
    pub scratch: wgpu::Buffer,
    /// What the sweeps read on the planes between the grid's slices (six words a point:
    /// [`crate::shadow::sweep::MidplaneSamples`]), built after each new pyramid.
    pub samples: wgpu::Buffer,
    pub light_count: u32,
    pub forward: bool,
}

/// Bytes of one of the sweeps' samples ([`crate::shadow::sample_packing`]).
pub const SAMPLE_BYTES: u64 = 24;

/// Bytes of the sweeps' working memory per point of a light's largest slice: two slices (the previous
/// and the current one) of two vec4, (tau, mass) and (spread, 0) (`sweep_scratch` in
/// `shaders/shadow_grid_build.wgsl`).
pub const SCRATCH_BYTES: u64 = 2 * 2 * 16;

impl GpuShadowGrid {
    pub fn new(
        device: &wgpu::Device,
        grid: ShadowGrid,
        light_count: u32,
        skip: f32,
        forward: bool,
    ) -> Self {
        let info = ShadowGridInfo {
            origin: grid.origin.to_array(),
            spacing: grid.spacing,
            dims: grid.dims,
            light_count,
            skip,
            forward: forward as u32,
            _pad: [0.0; 2],
        };
        Self {
            grid,
            info: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("shadow grid info"),
                contents: bytemuck::bytes_of(&info),
                // Also storage: the build pass reads it so (shadow_grid_build.wgsl).
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::STORAGE,
            }),
            values: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow grid"),
                size: grid.point_count() as u64 * light_count.max(1) as u64 * 32,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            scratch: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow sweep scratch"),
                size: grid.largest_slice() as u64 * SCRATCH_BYTES * light_count.max(1) as u64,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
            samples: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow grid samples"),
                size: crate::shadow::sweep::MidplaneSamples::layout(&grid)
                    .1
                    .max(1) as u64
                    * SAMPLE_BYTES,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
            light_count,
            forward,
        }
    }

    /// The grid for `light_count` lights and the multiple-scattering toggle `forward`: new values and
    /// scratch, the same samples (they depend on the pyramid and the volume alone: a change of the
    /// light count or of the toggle does not rebuild them).
    pub fn with_lights(
        &self,
        device: &wgpu::Device,
        light_count: u32,
        skip: f32,
        forward: bool,
    ) -> Self {
        Self {
            samples: self.samples.clone(),
            ..Self::new(device, self.grid, light_count, skip, forward)
        }
    }

    /// Units of the build: [`SWEEP_SLOTS`] per light (its sweeps, then its values finished).
    pub fn entry_count(&self) -> u32 {
        self.light_count * SWEEP_SLOTS
    }

    /// The sweeps' samples ([`crate::shadow::sweep::MidplaneSamples::layout`]).
    pub fn sample_count(&self) -> u32 {
        crate::shadow::sweep::MidplaneSamples::layout(&self.grid).1 as u32
    }
}

/// What the grid is built from.
pub struct ShadowGridInputs<'a> {
    pub pyramid: &'a GpuDensityPyramid,
    pub volume: &'a GpuFiberDensity,
    pub forward_table: &'a wgpu::Buffer,
    pub lights: &'a wgpu::Buffer,
    /// Lights per group of entries (the shading pass's light batch): a group's entries run slot by
    /// slot over its lights, so a unit of a few entries still sweeps several lights side by side.
    pub light_group: u32,
}

/// Entries of a light in the build: its sweeps' slots (the centre, three on the ring,
/// [`crate::shadow::sweep::SWEEP_RING`], the centre reversed), some empty (`slot_direction` in
/// `shaders/shadow_grid_build.wgsl`).
pub const SWEEP_SLOTS: u32 = 2 + crate::shadow::sweep::SWEEP_RING;

pub struct ShadowGridPass {
    pipeline: wgpu::ComputePipeline,
    samples_pipeline: wgpu::ComputePipeline,
}

impl ShadowGridPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shadow_grid_build"),
            source: wgpu::ShaderSource::Wgsl(shaders::shadow_grid_build_module().into()),
        });
        Self {
            pipeline: compute_pipeline(device, &module, "build_shadow_grid"),
            samples_pipeline: compute_pipeline(device, &module, "build_midplane_samples"),
        }
    }

    /// Encodes the sweeps' samples `range` of
    /// [`MidplaneSamples::layout`](crate::shadow::sweep::MidplaneSamples::layout) (read from the
    /// pyramid and volume, `build_midplane_samples`): every sweep reads them, so they are built
    /// after each new pyramid (or new grid buffers) and before the grid's first entry.
    pub fn encode_samples(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadowGridInputs,
        target: &GpuShadowGrid,
        range: std::ops::Range<u32>,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let count = range.end.saturating_sub(range.start);
        let range = buffer_init(
            device,
            "shadow grid samples range",
            bytemuck::cast_slice(&[range.start, count, 0, 0, 0, 0, 0, 0]),
            wgpu::BufferUsages::STORAGE,
        );
        let list = [
            (0, &inputs.pyramid.info_buffer),
            (1, &inputs.pyramid.pyramid),
            (2, &target.info),
            (5, &inputs.volume.info),
            (6, &inputs.volume.volume),
            (8, &range),
            (10, &target.samples),
        ];
        let bind = bind_buffers(
            device,
            &self.samples_pipeline,
            "shadow grid samples",
            &[],
            entries(&list),
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shadow grid samples"),
            timestamp_writes: timestamps,
        });
        let groups = count.div_ceil(64).max(1);
        pass.set_pipeline(&self.samples_pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(groups.min(65535), groups.div_ceil(65535), 1);
    }

    /// Encodes the build of entries [first, first + count) ([`SWEEP_SLOTS`] per light: its sweeps;
    /// ordered by light group, then slot, then light; one workgroup per light of the groups touched),
    /// the range in a storage buffer (see `shadow_grid_build.wgsl`). The sweeps read the samples
    /// ([`Self::encode_samples`]).
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadowGridInputs,
        target: &GpuShadowGrid,
        first: u32,
        count: u32,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let group = inputs.light_group.max(1);
        let lights = target.light_count.max(1);
        let g0 = first / (SWEEP_SLOTS * group);
        let g1 = (first + count.max(1) - 1) / (SWEEP_SLOTS * group);
        // The smallest group touched (only the last one may be short).
        let smallest = group.min(lights - (g1 * group).min(lights - 1));
        let per_entry = count <= smallest;
        let workgroups = if per_entry {
            count.max(1)
        } else {
            ((g1 + 1) * group).min(lights) - g0 * group
        };
        let x = workgroups.min(65535);
        let y = workgroups.div_ceil(x);
        let range = buffer_init(
            device,
            "shadow grid range",
            bytemuck::cast_slice(&[first, count, x, group, per_entry as u32, 0, 0, 0]),
            wgpu::BufferUsages::STORAGE,
        );
        let list = [
            (2, &target.info),
            (3, inputs.lights),
            (4, &target.values),
            (5, &inputs.volume.info),
            (6, &inputs.volume.volume),
            (7, inputs.forward_table),
            (8, &range),
            (9, &target.scratch),
            (10, &target.samples),
        ];
        let bind = bind_buffers(device, &self.pipeline, "shadow grid", &[], entries(&list));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shadow grid"),
            timestamp_writes: timestamps,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// Bind group entries at the given bindings.
fn entries<'a>(list: &[(u32, &'a wgpu::Buffer)]) -> Vec<wgpu::BindGroupEntry<'a>> {
    list.iter()
        .map(|&(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect()
}
