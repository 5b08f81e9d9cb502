//! Dual scattering on the GPU (`shaders/dual_response.wgsl`): the DualTables as a storage buffer (the
//! renderer binds the same) and a batch evaluator that tests the WGSL against
//! [`crate::scattering::dual_response`].

use super::context::{GpuContext, compute_pipeline};
use super::fast_eval::FastQuery;
use super::shaders;
use crate::scattering::dual_terms::{DUAL_SAMPLES, DualTables};
use wgpu::util::DeviceExt;

/// Per row of the absorption axis ([`DUAL_ROW`] vec4): A_b, Delta_b, sigma_b, a_f per sample (4 vec4),
/// then the prefix sums of Delta_b and sigma_b (2 vec4 per entry), as `dual_response.wgsl` reads them.
/// A row's channels are equal (one absorption): A_b's and a_f's texels are (value, its logarithm
/// [`crate::scattering::dual_terms::DualRow::ln_big_a_b`] / `ln_a_f`, 0, 0), and the shader reads the logarithms and the prefix sums'
/// component 0 (the values and the per-sample Delta_b and sigma_b stay for the CPU's layout; unread
/// there).
pub fn dual_tables_texels(t: &DualTables) -> Vec<[f32; 4]> {
    let v4 = |x: [f32; 3]| [x[0], x[1], x[2], 0.0];
    let mut out = Vec::with_capacity(t.rows.len() * DUAL_ROW);
    for row in &t.rows {
        // A_b and a_f with their logarithms in .y (M^L's log-linear reading).
        let with_ln = |v: f32, ln: f32| [v, ln, 0.0, 0.0];
        out.extend(row.samples.iter().enumerate().flat_map(|(i, s)| {
            [
                with_ln(s.big_a_b[0], row.ln_big_a_b[i]),
                v4(s.delta_b),
                v4(s.sigma_b),
                with_ln(s.a_f[0], row.ln_a_f[i]),
            ]
        }));
        for (d, s) in row.sat_delta.iter().zip(&row.sat_sigma) {
            out.push(v4(*d));
            out.push(v4(*s));
        }
    }
    debug_assert_eq!(out.len(), t.rows.len() * DUAL_ROW);
    out
}

/// vec4 per row of the absorption axis in the dual tables' buffer.
pub const DUAL_ROW: usize = 4 * DUAL_SAMPLES + 2 * (DUAL_SAMPLES + 1);

pub fn upload_dual_tables(device: &wgpu::Device, t: &DualTables) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("dual tables"),
        contents: bytemuck::cast_slice(&dual_tables_texels(t)),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    })
}

/// M_R^G, M_TT^G, M_TRT^G, M^L (RGB) per query; the query's `_pad[0]` is sigma_f^2, `_pad[1]` the
/// optical depth of hair behind the point (M^L's finite-depth fraction).
pub fn evaluate_dual(
    ctx: &GpuContext,
    tables: &wgpu::Buffer,
    azimuthal_table: &wgpu::Buffer,
    queries: &[FastQuery],
) -> Result<Vec<[[f32; 3]; 4]>, String> {
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("dual_eval"),
            source: wgpu::ShaderSource::Wgsl(shaders::dual_eval_module().into()),
        });
    let pipeline = compute_pipeline(&ctx.device, &module, "main");
    let v: Vec<[f32; 4]> = ctx.run_batch(&pipeline, &[tables, azimuthal_table], queries, 4)?;
    Ok((0..queries.len())
        .map(|i| std::array::from_fn(|t| [v[4 * i + t][0], v[4 * i + t][1], v[4 * i + t][2]]))
        .collect())
}
