// The shadow-grid build pass: one invocation per (grid point, light).

struct GridLight {
    direction: vec3<f32>,
    lambda: f32,
    rgb: vec3<f32>,
    _pad: f32,
}

@group(0) @binding(0) var<uniform> pyramid_info: PyramidInfo;
@group(0) @binding(1) var<storage, read> pyramid: array<vec4<f32>>;
@group(0) @binding(2) var<uniform> shadow_grid: ShadowGridInfo;
@group(0) @binding(3) var<storage, read> grid_lights: array<GridLight>;
@group(0) @binding(4) var<storage, read_write> shadow_values: array<f32>;

@compute @workgroup_size(64)
fn build_shadow_grid(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = id.x + id.y * groups.x * 64u;
    let g = shadow_grid;
    let n = g.dims.x * g.dims.y * g.dims.z;
    if (k >= n * g.light_count) {
        return;
    }
    let light = k / n;
    let i = k % n;
    let l = grid_lights[light];
    shadow_values[k] = srbf_transmittance(grid_point(g, i), l.direction, l.lambda, g.skip);
}
