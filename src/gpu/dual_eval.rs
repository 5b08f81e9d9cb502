//! Dual scattering on the GPU (`shaders/dual_response.wgsl`): the DualTables as a storage buffer (the
//! renderer binds the same) and a batch evaluator that tests the WGSL against
//! [`crate::scattering::dual_response`].

use super::context::{GpuContext, compute_pipeline};
use super::fast_eval::FastQuery;
use super::shaders;
use crate::scattering::dual_terms::{DUAL_SAMPLES, DualTables};
use wgpu::util::DeviceExt;

/// Per row j of the absorption axis ([`DUAL_ROW`] vec4), as `dual_response.wgsl` reads them: per sample
/// i, (ln A_b, ln a_f) of row j and of row j + 1 ([`crate::scattering::dual_terms::DualRow::ln_big_a_b`],
/// `ln_a_f`), then per entry of the prefix sums, (sum Delta_b, sum sigma_b) of row j and of row j + 1.
/// A channel's absorption lies between two rows ([`DualTables::backscatter_in_cell`],
/// `mean_delta_sigma_in_cell`), so one vec4 holds what it reads of both at a sample: 6 loads per
/// channel of M^L with its one inner node instead of 24 (the last row repeats itself; no cell
/// starts there). A row's channels are equal (one absorption): component 0.
pub fn dual_tables_texels(t: &DualTables) -> Vec<[f32; 4]> {
    let mut out = Vec::with_capacity(t.rows.len() * DUAL_ROW);
    for (j, row) in t.rows.iter().enumerate() {
        let next = &t.rows[(j + 1).min(t.rows.len() - 1)];
        out.extend((0..DUAL_SAMPLES).map(|i| {
            [
                row.ln_big_a_b[i],
                row.ln_a_f[i],
                next.ln_big_a_b[i],
                next.ln_a_f[i],
            ]
        }));
        out.extend((0..=DUAL_SAMPLES).map(|i| {
            [
                row.sat_delta[i][0],
                row.sat_sigma[i][0],
                next.sat_delta[i][0],
                next.sat_sigma[i][0],
            ]
        }));
    }
    debug_assert_eq!(out.len(), t.rows.len() * DUAL_ROW);
    out
}

/// vec4 per row of the absorption axis in the dual tables' buffer.
pub const DUAL_ROW: usize = 2 * DUAL_SAMPLES + 1;

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
