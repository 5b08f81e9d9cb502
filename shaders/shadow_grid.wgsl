// Per-light shadows on a coarse grid (twin of src/shadow/grid.rs): `build_shadow_grid` evaluates, at
// every grid point for every light, the swept transmittance and the forward-scattering terms;
// `grid_shadow` reads them trilinearly. Two vec4 per (point, light), light-major:
// (ln transmittance, ln T_f RGB), (sigma_f^2 RGB, optical depth behind the point along the light's travel).
// ln transmittance (<= 0) is stored with its sign bit set outside the occluder and clear inside
// (`grid_ln_t_stored`), so that `grid_transmittance` reads one word per corner; -abs reads it back.

// One SRBF light (twin of GpuLight in src/render/passes/shading.rs); read by the grid build and shading.
struct GpuLight {
    direction: vec3<f32>,
    lambda: f32,
    rgb: vec3<f32>,
    _pad: f32,
}

// One shading dispatch's batch of lights over rows of the image (twin of ShadeBatch in
// src/render/passes/shading.rs); read by the shading and occluder passes.
struct ShadeBatch {
    first: u32,
    count: u32,
    flags: u32,
    // Fragments per pixel in the K-buffer.
    slots: u32,
    slot: u32,
    // Rows [row0, row0 + rows) of the image (all of them for a whole frame, a band per unit of
    // progressive refinement).
    row0: u32,
    rows: u32,
    // Lights in all the batches (the shaded weight counts a fragment's share of them).
    lights: u32,
}

const FLAG_SHADOWS: u32 = 1u;

struct ShadowGridInfo {
    origin: vec3<f32>,
    spacing: f32,
    dims: vec3<u32>,
    light_count: u32,
    skip: f32,
    forward: u32, // 1: T_f and sigma_f^2 are computed (multiple scattering on)
    _p1: f32,
    _p2: f32,
}

// Transmittances are stored as logarithms, floored here.
const GRID_MIN_TRANSMITTANCE: f32 = 1e-8;
// depth_behind of a point inside the occluder (left out of the interpolation).
const GRID_INSIDE_SOLID: f32 = -1.0;

struct GridShadow {
    transmittance: f32,
    transmittance_f: vec3<f32>,
    sigma_f2: vec3<f32>,
    depth_behind: f32,
}

fn grid_point(g: ShadowGridInfo, i: u32) -> vec3<f32> {
    let c = vec3<u32>(i % g.dims.x, (i / g.dims.x) % g.dims.y, i / (g.dims.x * g.dims.y));
    return g.origin + (vec3<f32>(c) + vec3<f32>(0.5)) * g.spacing;
}

// The grid cell around a point (clamped at the border: ShadowGrid::corners): its lowest point and the
// point's fractions across it.
struct GridCell {
    base: vec3<f32>,
    f: vec3<f32>,
}

fn grid_cell(g: ShadowGridInfo, p: vec3<f32>) -> GridCell {
    let hi = vec3<f32>(g.dims) - vec3<f32>(1.0);
    let q = clamp((p - g.origin) / g.spacing - vec3<f32>(0.5), vec3<f32>(0.0), hi);
    let base = min(floor(q), max(hi - vec3<f32>(1.0), vec3<f32>(0.0)));
    return GridCell(base, q - base);
}

// Corner `corner` of the cell: its index in a light's values and its trilinear weight.
struct GridCorner {
    i: u32,
    w: f32,
}

fn grid_corner(g: ShadowGridInfo, cell: GridCell, corner: u32) -> GridCorner {
    let o = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
    let idx = min(vec3<u32>(cell.base) + o, g.dims - vec3<u32>(1u));
    let w3 = select(vec3<f32>(1.0) - cell.f, cell.f, o == vec3<u32>(1u));
    return GridCorner((idx.z * g.dims.y + idx.y) * g.dims.x + idx.x, w3.x * w3.y * w3.z);
}

fn grid_shadow(g: ShadowGridInfo, p: vec3<f32>, light: u32) -> GridShadow {
    let cell = grid_cell(g, p);
    let n = g.dims.x * g.dims.y * g.dims.z;
    var v0 = vec4<f32>(0.0);
    var v1 = vec4<f32>(0.0);
    // Also the sums without the points inside the occluder (used when any is outside).
    var o0 = vec4<f32>(0.0);
    var o1 = vec4<f32>(0.0);
    var wo = 0.0;
    var any_inside = false;
    for (var corner = 0u; corner < 8u; corner++) {
        let c = grid_corner(g, cell, corner);
        let i = c.i;
        let w = c.w;
        let stored = shadow_values[2u * (light * n + i)];
        let a = vec4<f32>(-abs(stored.x), stored.yzw);
        let b = shadow_values[2u * (light * n + i) + 1u];
        v0 = v0 + w * a;
        v1 = v1 + w * b;
        if (b.w >= 0.0) {
            o0 = o0 + w * a;
            o1 = o1 + w * b;
            wo = wo + w;
        } else {
            any_inside = true;
        }
    }
    if (any_inside && wo > 1e-4) {
        v0 = o0 / wo;
        v1 = o1 / wo;
    }
    return GridShadow(exp(v0.x), exp(v0.yzw), v1.xyz, max(v1.w, 0.0));
}

// ln T (<= 0) as stored: its sign bit set for a point outside the occluder, clear inside.
fn grid_ln_t_stored(ln_t: f32, inside: bool) -> f32 {
    let m = bitcast<u32>(ln_t) & 0x7fffffffu;
    return bitcast<f32>(select(m | 0x80000000u, m, inside));
}

fn grid_ln_t_inside(stored: f32) -> bool {
    return (bitcast<u32>(stored) & 0x80000000u) == 0u;
}

// grid_shadow's transmittance alone (single scattering reads only it, three times per light and
// segment, and the head's shading): per corner one word, the log transmittance with the inside flag
// in its sign bit, where grid_shadow loads two vec4. The same sums in the same order, so the same value.
fn grid_transmittance(g: ShadowGridInfo, p: vec3<f32>, light: u32) -> f32 {
    let cell = grid_cell(g, p);
    let n = g.dims.x * g.dims.y * g.dims.z;
    var v = 0.0;
    var o = 0.0;
    var wo = 0.0;
    var any_inside = false;
    for (var corner = 0u; corner < 8u; corner++) {
        let c = grid_corner(g, cell, corner);
        let i = c.i;
        let w = c.w;
        let stored = shadow_values[2u * (light * n + i)].x;
        let t = -abs(stored);
        v = v + w * t;
        if (!grid_ln_t_inside(stored)) {
            o = o + w * t;
            wo = wo + w;
        } else {
            any_inside = true;
        }
    }
    if (any_inside && wo > 1e-4) {
        v = o / wo;
    }
    return exp(v);
}
