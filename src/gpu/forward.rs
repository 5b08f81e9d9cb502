//! Forward scattering along shadow paths on the GPU (`shaders/forward_scattering.wgsl`), the twin of
//! [`crate::shadow::forward`]: the (theta, sigma_a) table as a storage buffer and a batch evaluator for
//! the tests.

use super::context::{GpuContext, compute_pipeline};
use super::density_pyramid::GpuDensityPyramid;
use super::fiber_density::GpuFiberDensity;
use super::shaders;
use crate::shadow::forward::{ForwardScattering, ForwardTable};
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

/// One query: point, skipped distance, direction towards the light, cone half-angle.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ForwardQuery {
    pub p: [f32; 3],
    pub skip: f32,
    pub omega: [f32; 3],
    pub half_angle: f32,
}

const _: () = assert!(std::mem::size_of::<ForwardQuery>() == 32);

/// The table as the shaders read it: per node the means over +-theta of a_f and of a_f beta_f^2
/// ([`ForwardTable::symmetric_node`]), theta fastest.
pub fn forward_table_texels(table: &ForwardTable) -> Vec<[f32; 2]> {
    use crate::shadow::forward::{SIGMA_SAMPLES, THETA_SAMPLES};
    (0..SIGMA_SAMPLES)
        .flat_map(|j| (0..THETA_SAMPLES).map(move |i| table.symmetric_node(i, j)))
        .collect()
}

/// The table as a storage buffer (rebuilt when eta, alpha or beta change).
pub fn upload_forward_table(device: &wgpu::Device, table: &ForwardTable) -> wgpu::Buffer {
    let pairs = forward_table_texels(table);
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("forward table"),
        contents: bytemuck::cast_slice(&pairs),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    })
}

/// Evaluates `forward_scattering` for a batch of queries (tests).
pub fn evaluate_forward(
    ctx: &GpuContext,
    pyramid: &GpuDensityPyramid,
    volume: &GpuFiberDensity,
    table: &wgpu::Buffer,
    queries: &[ForwardQuery],
) -> Result<Vec<ForwardScattering>, String> {
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("forward_eval"),
        source: wgpu::ShaderSource::Wgsl(shaders::forward_eval_module().into()),
    });
    let pipeline = compute_pipeline(device, &module, "main");
    let v: Vec<[f32; 4]> = ctx.run_batch(
        &pipeline,
        &[
            &pyramid.info_buffer,
            &pyramid.pyramid,
            &volume.info,
            &volume.volume,
            table,
        ],
        queries,
        2,
    )?;
    Ok((0..queries.len())
        .map(|i| ForwardScattering {
            direct_fraction: v[2 * i][3],
            transmittance_f: [v[2 * i][0], v[2 * i][1], v[2 * i][2]],
            sigma_f2: [v[2 * i + 1][0], v[2 * i + 1][1], v[2 * i + 1][2]],
        })
        .collect())
}
