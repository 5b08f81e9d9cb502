//! The fiber-density mip pyramid on the GPU (`shaders/density_downsample.wgsl`) and the SRBF
//! transmittance read from it (`shaders/density_pyramid.wgsl`); twins of [`crate::shadow::cone`].

use super::context::{GpuContext, compute_pipeline};
use super::fiber_density::{GpuFiberDensity, dispatch_2d};
use super::shaders;
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

/// Levels the shader's uniform holds (a 256^3 volume needs 9).
pub const MAX_LEVELS: usize = 10;

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PyramidLevel {
    pub dims: [u32; 3],
    /// First voxel of the level in the pyramid buffer.
    pub offset: u32,
    pub voxel: f32,
    pub _pad: [f32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PyramidInfo {
    pub origin: [f32; 3],
    pub count: u32,
    pub levels: [PyramidLevel; MAX_LEVELS],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
struct DownsampleInfo {
    src_dims: [u32; 3],
    src_offset: u32,
    dst_dims: [u32; 3],
    dst_offset: u32,
}

/// One query of the test harness: point, SRBF bandwidth, centre direction, skipped distance.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TransmittanceQuery {
    pub p: [f32; 3],
    pub lambda: f32,
    pub centre: [f32; 3],
    pub skip: f32,
}

const _: () = assert!(std::mem::size_of::<PyramidLevel>() == 32);
const _: () = assert!(std::mem::size_of::<PyramidInfo>() == 336);
const _: () = assert!(std::mem::size_of::<TransmittanceQuery>() == 32);

/// The pyramid's buffers: all levels in one storage buffer (two vec4 per voxel) and its description.
pub struct GpuDensityPyramid {
    pub info: PyramidInfo,
    pub info_buffer: wgpu::Buffer,
    pub pyramid: wgpu::Buffer,
    level_infos: Vec<wgpu::Buffer>,
}

impl GpuDensityPyramid {
    pub fn new(device: &wgpu::Device, volume: &GpuFiberDensity) -> Self {
        let g = volume.grid;
        let mut info = PyramidInfo::zeroed();
        info.origin = g.origin.to_array();
        let mut dims = g.dims.map(|d| d as u32);
        let (mut offset, mut voxel) = (0u32, g.voxel);
        loop {
            let l = info.count as usize;
            info.levels[l] = PyramidLevel {
                dims,
                offset,
                voxel,
                _pad: [0.0; 3],
            };
            info.count += 1;
            offset += dims[0] * dims[1] * dims[2];
            if dims.iter().all(|&d| d == 1) || info.count as usize == MAX_LEVELS {
                break;
            }
            dims = dims.map(|d| d.div_ceil(2));
            voxel *= 2.0;
        }
        let level_infos = (0..info.count as usize)
            .map(|l| {
                let dst = info.levels[l];
                let src = if l == 0 { dst } else { info.levels[l - 1] };
                let ds = DownsampleInfo {
                    src_dims: src.dims,
                    src_offset: src.offset,
                    dst_dims: dst.dims,
                    dst_offset: dst.offset,
                };
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("pyramid level"),
                    contents: bytemuck::bytes_of(&ds),
                    usage: wgpu::BufferUsages::UNIFORM,
                })
            })
            .collect();
        Self {
            info,
            info_buffer: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("pyramid info"),
                contents: bytemuck::bytes_of(&info),
                // Also storage: the shadow-grid build reads it so (shadow_grid_build.wgsl).
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::STORAGE,
            }),
            pyramid: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("density pyramid"),
                size: offset as u64 * 32,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
            level_infos,
        }
    }
}

/// Copies level 0 out of the volume and downsamples level by level.
pub struct DensityPyramidPass {
    copy: wgpu::ComputePipeline,
    downsample: wgpu::ComputePipeline,
}

impl DensityPyramidPass {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("density_downsample"),
            source: wgpu::ShaderSource::Wgsl(shaders::DENSITY_DOWNSAMPLE.into()),
        });
        Self {
            copy: compute_pipeline(device, &module, "copy_level0"),
            downsample: compute_pipeline(device, &module, "downsample"),
        }
    }

    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        volume: &GpuFiberDensity,
        target: &GpuDensityPyramid,
        timestamps: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("density pyramid"),
            timestamp_writes: timestamps,
        });
        for l in 0..target.info.count as usize {
            let pipeline = if l == 0 { &self.copy } else { &self.downsample };
            let mut entries = vec![
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: target.level_infos[l].as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: target.pyramid.as_entire_binding(),
                },
            ];
            if l == 0 {
                entries.push(wgpu::BindGroupEntry {
                    binding: 1,
                    resource: volume.volume.as_entire_binding(),
                });
            }
            let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("density pyramid level"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &entries,
            });
            let d = target.info.levels[l].dims;
            let (x, y) = dispatch_2d(d[0] * d[1] * d[2]);
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}

/// Evaluates `srbf_transmittance` on the GPU for a batch of queries (tests).
pub fn evaluate_transmittance(
    ctx: &GpuContext,
    pyramid: &GpuDensityPyramid,
    queries: &[TransmittanceQuery],
) -> Result<Vec<f32>, String> {
    let device = &ctx.device;
    let source = shaders::transmittance_eval_module();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("transmittance_eval"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = compute_pipeline(device, &module, "main");
    ctx.run_batch(
        &pipeline,
        &[&pyramid.info_buffer, &pyramid.pyramid],
        queries,
        1,
    )
}
