//! Batch evaluation of the fast per-SRBF response on the GPU (`shaders/fast_eval.wgsl`): the harness
//! that checks the WGSL fast-form functions against their Rust twins, and the LUTs as storage buffers
//! (the renderer binds the same buffers).

use super::context::{GpuContext, compute_pipeline};
use super::shaders;
use crate::scattering::azimuthal_table::AzimuthalTable;
use crate::scattering::fast_params::FastHairParams;
use crate::scattering::lut::Luts;
use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

/// One query: parameters, light (fiber frame, radians) and view.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct FastQuery {
    pub params: FastHairParams,
    pub theta_j: f32,
    pub phi_j: f32,
    pub lambda: f32,
    pub theta_o: f32,
    pub phi_o: f32,
    pub _pad: [f32; 3],
}

const _: () = assert!(std::mem::size_of::<FastQuery>() == 112);

/// The C_k table and the R table as one storage buffer (C_k's texels as in
/// [`crate::scattering::lut::LutTexture`], as f32 bits; the H_k tables feed only the CPU's
/// circular-Gaussian fits, which the GPU does not evaluate).
pub struct GpuLuts {
    pub c: wgpu::Buffer,
}

impl GpuLuts {
    /// `lut_c` (lut.wgsl): C_k's texels, then the R table's entries.
    pub fn new(device: &wgpu::Device, luts: &Luts) -> Self {
        let words: Vec<u32> = (luts.c.texels.iter().map(|v| v.to_bits()))
            .chain(luts.r.gpu.iter().copied())
            .collect();
        Self {
            c: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lut C_k and R"),
                contents: bytemuck::cast_slice(&words),
                usage: wgpu::BufferUsages::STORAGE,
            }),
        }
    }
}

/// The azimuthal table as a storage buffer ([`AzimuthalTable::gpu`]; the renderer binds the same).
pub fn upload_azimuthal_table(device: &wgpu::Device, table: &AzimuthalTable) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("azimuthal table"),
        contents: table.gpu_bytes(),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    })
}

pub struct FastEvalPipeline {
    pipeline: wgpu::ComputePipeline,
}

impl FastEvalPipeline {
    pub fn new(device: &wgpu::Device) -> Self {
        let source = format!("{}\n{}", shaders::fast_model_library(), shaders::FAST_EVAL);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("fast_eval"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        Self {
            pipeline: compute_pipeline(device, &module, "main"),
        }
    }

    /// M_R, M_TT, M_TRT (RGB) per query; every query's eta and eccentricity are the table's.
    pub fn evaluate(
        &self,
        ctx: &GpuContext,
        luts: &GpuLuts,
        table: &wgpu::Buffer,
        queries: &[FastQuery],
    ) -> Result<Vec<[[f32; 3]; 3]>, String> {
        let v: Vec<[f32; 4]> = ctx.run_batch(&self.pipeline, &[&luts.c, table], queries, 3)?;
        Ok((0..queries.len())
            .map(|i| std::array::from_fn(|t| [v[3 * i + t][0], v[3 * i + t][1], v[3 * i + t][2]]))
            .collect())
    }
}
