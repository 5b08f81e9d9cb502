// Batch evaluation of the dual-scattering responses (shaders/dual_response.wgsl) for the tests: per
// query M_R^G, M_TT^G, M_TRT^G and M^L, RGB. The query's first padding float carries sigma_f^2, the second the optical depth behind the point.

struct DualQuery {
    params: FastHairParams,
    theta_j: f32,
    phi_j: f32,
    lambda: f32,
    theta_o: f32,
    phi_o: f32,
    sigma_f2: f32,
    depth_behind: f32,
    _pad2: f32,
}

@group(0) @binding(0) var<storage, read> dual_tables: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> azimuthal_table: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> dual_queries: array<DualQuery>;
@group(0) @binding(3) var<storage, read_write> dual_results: array<vec4<f32>>;
// Declared for the fast-model library's table reads, which these entry points never reach (the
// derived layout leaves them out).
@group(0) @binding(4) var<storage, read> lut_c: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&dual_queries)) {
        return;
    }
    let q = dual_queries[i];
    let light = SrbfInFrame(q.theta_j, q.phi_j, q.lambda);
    dual_results[4u * i] = vec4<f32>(global_response_lobe(q.params, 0u, light, q.theta_o, q.phi_o, q.sigma_f2), 0.0);
    dual_results[4u * i + 1u] = vec4<f32>(global_response_lobe(q.params, 1u, light, q.theta_o, q.phi_o, q.sigma_f2), 0.0);
    dual_results[4u * i + 2u] = vec4<f32>(global_response_lobe(q.params, 2u, light, q.theta_o, q.phi_o, q.sigma_f2), 0.0);
    dual_results[4u * i + 3u] = vec4<f32>(local_response(q.params, dual_cells(q.params.sigma_a.xyz), light, q.theta_o, q.phi_o, q.sigma_f2, q.depth_behind), 0.0);
}
