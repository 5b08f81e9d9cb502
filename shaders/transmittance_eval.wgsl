// Batch evaluation of srbf_transmittance (shaders/density_pyramid.wgsl) for the tests.

struct TransmittanceQuery {
    p: vec3<f32>,
    lambda: f32,
    centre: vec3<f32>,
    skip: f32,
}

@group(0) @binding(0) var<uniform> pyramid_info: PyramidInfo;
@group(0) @binding(1) var<storage, read> pyramid: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> transmittance_queries: array<TransmittanceQuery>;
@group(0) @binding(3) var<storage, read_write> transmittance_results: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&transmittance_queries)) {
        return;
    }
    let q = transmittance_queries[i];
    transmittance_results[i] = srbf_transmittance(q.p, q.centre, q.lambda, q.skip);
}
