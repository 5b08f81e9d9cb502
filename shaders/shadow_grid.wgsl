// Per-light transmittance on a coarse grid (twin of src/shadow/grid.rs): `build_shadow_grid` evaluates
// srbf_transmittance at every grid point for every light; `grid_transmittance` reads it trilinearly.
// Prepended: circular_gaussian, density_pyramid (with pyramid_info, pyramid bound by the includer).

struct ShadowGridInfo {
    origin: vec3<f32>,
    spacing: f32,
    dims: vec3<u32>,
    light_count: u32,
    skip: f32,
    _p0: f32,
    _p1: f32,
    _p2: f32,
}

fn grid_point(g: ShadowGridInfo, i: u32) -> vec3<f32> {
    let c = vec3<u32>(i % g.dims.x, (i / g.dims.x) % g.dims.y, i / (g.dims.x * g.dims.y));
    return g.origin + (vec3<f32>(c) + vec3<f32>(0.5)) * g.spacing;
}

fn grid_transmittance(g: ShadowGridInfo, p: vec3<f32>, light: u32) -> f32 {
    let hi = vec3<f32>(g.dims) - vec3<f32>(1.0);
    let q = clamp((p - g.origin) / g.spacing - vec3<f32>(0.5), vec3<f32>(0.0), hi);
    let base = min(floor(q), max(hi - vec3<f32>(1.0), vec3<f32>(0.0)));
    let f = q - base;
    let n = g.dims.x * g.dims.y * g.dims.z;
    var t = 0.0;
    for (var corner = 0u; corner < 8u; corner++) {
        let o = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
        let idx = min(vec3<u32>(base) + o, g.dims - vec3<u32>(1u));
        let w3 = select(vec3<f32>(1.0) - f, f, o == vec3<u32>(1u));
        let i = (idx.z * g.dims.y + idx.y) * g.dims.x + idx.x;
        t = t + w3.x * w3.y * w3.z * shadow_values[light * n + i];
    }
    return t;
}
