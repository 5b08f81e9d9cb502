//! Batch evaluation of the fast per-SRBF response on the GPU (`shaders/fast_eval.wgsl`): the harness
//! that checks the WGSL fast-form functions against their Rust twins, and the LUTs as storage buffers
//! (the renderer binds the same buffers).

use super::context::{GpuContext, compute_pipeline};
use super::shaders;
use crate::scattering::fast_params::FastHairParams;
use crate::scattering::lut::{LutTexture, Luts};
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

/// The three tables as storage buffers (texels as in [`LutTexture`]).
pub struct GpuLuts {
    pub c: wgpu::Buffer,
    pub h_tt: wgpu::Buffer,
    pub h_trt: wgpu::Buffer,
}

impl GpuLuts {
    pub fn new(device: &wgpu::Device, luts: &Luts) -> Self {
        let make = |label: &str, t: &LutTexture| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(&t.texels),
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        Self {
            c: make("lut C_k", &luts.c),
            h_tt: make("lut H_TT", &luts.h_tt),
            h_trt: make("lut H_TRT", &luts.h_trt),
        }
    }
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

    /// M_R, M_TT, M_TRT (RGB) per query.
    pub fn evaluate(
        &self,
        ctx: &GpuContext,
        luts: &GpuLuts,
        queries: &[FastQuery],
    ) -> Result<Vec<[[f32; 3]; 3]>, String> {
        if queries.is_empty() {
            return Ok(Vec::new());
        }
        let device = &ctx.device;
        let q = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("fast_eval queries"),
            contents: bytemuck::cast_slice(queries),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let size = (queries.len() * 3 * 16) as u64;
        let results = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fast_eval results"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fast_eval"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: luts.c.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: luts.h_tt.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: luts.h_trt.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: q.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: results.as_entire_binding(),
                },
            ],
        });
        let mut enc = device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(queries.len().div_ceil(64) as u32, 1, 1);
        }
        ctx.queue.submit([enc.finish()]);
        let v: Vec<[f32; 4]> = ctx.read_buffer(&results)?;
        Ok((0..queries.len())
            .map(|i| std::array::from_fn(|t| [v[3 * i + t][0], v[3 * i + t][1], v[3 * i + t][2]]))
            .collect())
    }
}
