//! The shadow-grid pass (`shaders/shadow_grid_build.wgsl`): every light's cone-marched transmittance
//! and forward-scattering terms at every point of a coarse grid, rebuilt when the volume, the lights
//! or the forward table change ([`crate::shadow::grid`] is the CPU twin).

use crate::gpu::context::{bind_buffers, compute_pipeline};
use crate::gpu::density_pyramid::GpuDensityPyramid;
use crate::gpu::fiber_density::{GpuFiberDensity, dispatch_2d};
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
    pub light_count: u32,
    pub forward: bool,
}

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
            light_count,
            forward,
        }
    }

    /// Entries of the grid: (grid point, light) pairs.
    pub fn entry_count(&self) -> u32 {
        self.grid.point_count() as u32 * self.light_count
    }
}

/// What the grid is built from.
pub struct ShadowGridInputs<'a> {
    pub pyramid: &'a GpuDensityPyramid,
    pub volume: &'a GpuFiberDensity,
    pub forward_table: &'a wgpu::Buffer,
    pub lights: &'a wgpu::Buffer,
}

pub struct ShadowGridPass {
    pipeline: wgpu::ComputePipeline,
}

impl ShadowGridPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shadow_grid_build"),
            source: wgpu::ShaderSource::Wgsl(shaders::shadow_grid_build_module().into()),
        });
        Self {
            pipeline: compute_pipeline(device, &module, "build_shadow_grid"),
        }
    }

    /// Encodes the build of entries [first, first + count) (grid point fastest, light-major), the range
    /// in a storage buffer (see `shadow_grid_build.wgsl`).
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
        let (x, y) = dispatch_2d(count);
        let range = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shadow grid range"),
            contents: bytemuck::cast_slice(&[first, count, x, 0]),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let buffers = [
            &inputs.pyramid.info_buffer,
            &inputs.pyramid.pyramid,
            &target.info,
            inputs.lights,
            &target.values,
            &inputs.volume.info,
            &inputs.volume.volume,
            inputs.forward_table,
            &range,
        ];
        let bind = bind_buffers(device, &self.pipeline, "shadow grid", &buffers, Vec::new());
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shadow grid"),
            timestamp_writes: timestamps,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
}
