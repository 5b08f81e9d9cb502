// The shadow-grid build pass: one invocation per (grid point, light) entry of [first, first + count)
// (all of them for a whole frame, a range per unit of progressive refinement). Writes the light's cone-marched
// transmittance (the direct fraction for single scattering) and, when multiple scattering is on, the
// forward-scattering terms T_f and sigma_f^2 averaged over the same seven cones (srbf_forward), and the
// optical depth of the hair behind the point along the light's travel (the central cone marched away
// from the light: how much hair there is to back-scatter, dual_response.wgsl's local term).
// Prepended: circular_gaussian, density_pyramid, forward_scattering, shadow_grid.

// The three descriptions are read as storage, not uniforms: lavapipe recompiles a shader whose loops
// depend on small uniforms with their values inlined at every new bind group (15-25 ms and ~3.4 MB kept
// per dispatch of this shader, seen with a bind group per unit of progressive refinement).
@group(0) @binding(0) var<storage, read> pyramid_info: PyramidInfo;
@group(0) @binding(1) var<storage, read> pyramid: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> shadow_grid: ShadowGridInfo;
@group(0) @binding(3) var<storage, read> grid_lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read_write> shadow_values: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> volume_info: VolumeInfoF;
@group(0) @binding(6) var<storage, read> volume: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> forward_table: array<vec2<f32>>;

// The entries this dispatch writes, [first, first + count), and the dispatch's workgroups along x
// (a small buffer per dispatch, so the grid's uniform stays the one the shading pass reads).
struct BuildRange {
    first: u32,
    count: u32,
    // Workgroups along x of the dispatch (dispatch_2d), in place of @builtin(num_workgroups).
    groups_x: u32,
    _pad: u32,
}
@group(0) @binding(8) var<storage, read> build_range: BuildRange;

// forward_scattering over the cones of srbf_transmittance (weights 1/2 for the centre, 1/12 for each
// ring cone), each marched with its own width: the direct fraction is srbf_transmittance; sigma_f^2 is averaged per channel over the forward-scattered light (weights
// w (T_f - direct)).
fn srbf_forward(p: vec3<f32>, centre: vec3<f32>, lambda: f32, skip: f32) -> ForwardScattering {
    let kappa = 2.0 / (lambda * lambda);
    let e = exp(-2.0 * kappa);
    let inner = acos(clamp(1.0 + log(0.5 * (1.0 - e) + e) / kappa, -1.0, 1.0));
    if (inner < 0.05) {
        return forward_scattering(p, centre, max(inner, 1e-4), skip);
    }
    let c = forward_scattering(p, centre, inner, skip);
    let ring = acos(clamp(1.0 + log(0.25 * (1.0 - e) + e) / kappa, -1.0, 1.0));
    var e1 = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(centre.x) < 0.9);
    e1 = normalize(e1 - centre * dot(centre, e1));
    let e2 = cross(centre, e1);
    let sub = min(ring * PI / 6.0, ring);
    var direct = 0.5 * c.direct_fraction;
    var tf = 0.5 * c.transmittance_f;
    var scattered = 0.5 * max(c.transmittance_f - vec3<f32>(c.direct_fraction), vec3<f32>(0.0));
    var spread = scattered * c.sigma_f2;
    for (var k = 0; k < 6; k++) {
        let a = f32(k) * TAU / 6.0;
        let d = normalize(centre * cos(ring) + (e1 * cos(a) + e2 * sin(a)) * sin(ring));
        let f = forward_scattering(p, d, sub, skip);
        let w = 0.5 / 6.0;
        let s = w * max(f.transmittance_f - vec3<f32>(f.direct_fraction), vec3<f32>(0.0));
        direct = direct + w * f.direct_fraction;
        tf = tf + w * f.transmittance_f;
        scattered = scattered + s;
        spread = spread + s * f.sigma_f2;
    }
    return ForwardScattering(direct, tf, spread / max(scattered, vec3<f32>(1e-12)));
}

@compute @workgroup_size(64)
fn build_shadow_grid(@builtin(global_invocation_id) id: vec3<u32>) {
    let g = shadow_grid;
    let local = id.x + id.y * build_range.groups_x * 64u;
    if (local >= build_range.count) {
        return;
    }
    let k = build_range.first + local;
    let n = g.dims.x * g.dims.y * g.dims.z;
    if (k >= n * g.light_count) {
        return;
    }
    let l = grid_lights[k / n];
    let x = grid_point(g, k % n);
    // No shading point reads a grid point with no hair within one spacing (plus a level-0 voxel: hair is
    // deposited at samples a quarter voxel apart, ShadowGrid::value): it stays lit.
    if (!hair_near(x, g.spacing + pyramid_info.levels[0].voxel)) {
        shadow_values[2u * k] = vec4<f32>(0.0);
        shadow_values[2u * k + 1u] = vec4<f32>(0.0);
        return;
    }
    // Transmittances are stored as logarithms: attenuation falls off exponentially into the hair, so
    // interpolating its logarithm follows it between grid points far better.
    if (g.forward == 0u) {
        let t = log(max(srbf_transmittance(x, l.direction, l.lambda, g.skip), GRID_MIN_TRANSMITTANCE));
        shadow_values[2u * k] = vec4<f32>(t, vec3<f32>(t));
        shadow_values[2u * k + 1u] = vec4<f32>(0.0);
        return;
    }
    // The forward march's direct fraction is srbf_transmittance: the same cones, steps and sums of
    // c h, in the same order (marching them twice cost half the build), so d_f = d_b = 0 is single
    // scattering up to rounding.
    let f = srbf_forward(x, l.direction, l.lambda, g.skip);
    let t = log(max(f.direct_fraction, GRID_MIN_TRANSMITTANCE));
    shadow_values[2u * k] = vec4<f32>(t, log(max(f.transmittance_f, vec3<f32>(GRID_MIN_TRANSMITTANCE))));
    let behind = cone_optical_depth(x, -l.direction, srbf_centre_cone(l.lambda), g.skip);
    shadow_values[2u * k + 1u] = vec4<f32>(f.sigma_f2, behind);
}
