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

/// The grid's uniform and its values (two vec4 per grid point and light, light-major: transmittance,
/// T_f RGB; sigma_f^2 RGB, direct fraction of the forward march).
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
                usage: wgpu::BufferUsages::UNIFORM,
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

    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        inputs: &ShadowGridInputs,
        target: &GpuShadowGrid,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let buffers = [
            &inputs.pyramid.info_buffer,
            &inputs.pyramid.pyramid,
            &target.info,
            inputs.lights,
            &target.values,
            &inputs.volume.info,
            &inputs.volume.volume,
            inputs.forward_table,
        ];
        let bind = bind_buffers(device, &self.pipeline, "shadow grid", &buffers, Vec::new());
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shadow grid"),
            timestamp_writes: timestamps,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        let (x, y) = dispatch_2d(target.grid.point_count() as u32 * target.light_count);
        pass.dispatch_workgroups(x, y, 1);
    }
}
