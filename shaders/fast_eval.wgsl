// Batch evaluation of the fast response, one query per invocation: the harness that tests the WGSL
// fast-form functions against their Rust twins (src/gpu/fast_eval.rs).

struct FastQuery {
    params: FastHairParams,
    theta_j: f32,
    phi_j: f32,
    lambda: f32,
    theta_o: f32,
    phi_o: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

@group(0) @binding(0) var<storage, read> lut_c: array<u32>;
@group(0) @binding(1) var<storage, read> azimuthal_table: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> queries: array<FastQuery>;
@group(0) @binding(3) var<storage, read_write> results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&queries)) {
        return;
    }
    let q = queries[i];
    let light = SrbfInFrame(q.theta_j, q.phi_j, q.lambda);
    for (var t = 0u; t < 3u; t++) {
        results[3u * i + t] = vec4<f32>(srbf_response_lobe(q.params, t, light, q.theta_o, q.phi_o), 0.0);
    }
}
