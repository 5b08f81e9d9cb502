// Batch evaluation of forward_scattering (shaders/forward_scattering.wgsl) for the tests.

struct ForwardQuery {
    p: vec3<f32>,
    skip: f32,
    omega: vec3<f32>,
    half_angle: f32,
}

@group(0) @binding(0) var<uniform> pyramid_info: PyramidInfo;
@group(0) @binding(1) var<storage, read> pyramid: array<vec4<f32>>;
@group(0) @binding(2) var<uniform> volume_info: VolumeInfoF;
@group(0) @binding(3) var<storage, read> volume: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> forward_table: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read> forward_queries: array<ForwardQuery>;
@group(0) @binding(6) var<storage, read_write> forward_results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&forward_queries)) {
        return;
    }
    let q = forward_queries[i];
    let f = forward_scattering(q.p, q.omega, q.half_angle, q.skip);
    forward_results[2u * i] = vec4<f32>(f.transmittance_f, f.direct_fraction);
    forward_results[2u * i + 1u] = vec4<f32>(f.sigma_f2, 0.0);
}
