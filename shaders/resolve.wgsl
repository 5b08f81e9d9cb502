// Resolve pass: per pixel, coverage (alpha) from the visibility samples, the nearest sample's view
// depth, the segment ids under the pixel (for picking and the CPU twin), and the beauty = sum of the
// accumulated components times the exposure scale 2^EV. Linear, premultiplied by coverage; no tonemap.
// Prepended: camera.

struct ResolveInfo {
    exposure_scale: f32,
    samples: u32,
    _p0: u32,
    _p1: u32,
}

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> info: ResolveInfo;
@group(0) @binding(2) var visibility: texture_multisampled_2d<f32>;
@group(0) @binding(3) var depth: texture_depth_multisampled_2d;
@group(0) @binding(4) var<storage, read> aov_r: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> aov_tt: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> aov_trt: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> aov_ms_global: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read> aov_ms_local: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> beauty: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> view_depth: array<f32>;
@group(0) @binding(11) var<storage, read_write> sample_ids: array<vec4<u32>>;
// The rows resolved: [row0, row0 + rows) (a band after progressive refinement shaded it).
struct ResolveRows {
    row0: u32,
    rows: u32,
    _p0: u32,
    _p1: u32,
}
@group(0) @binding(12) var<storage, read> band: ResolveRows;

// Distance along the view axis of a [0, 1] depth (directx-style right-handed projection).
fn linear_depth(d: f32) -> f32 {
    return camera.near * camera.far / (camera.far - d * (camera.far - camera.near));
}

@compute @workgroup_size(8, 8)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.y >= band.rows) {
        return;
    }
    let id = vec3<u32>(gid.x, gid.y + band.row0, gid.z);
    if (id.x >= camera.size.x || id.y >= camera.size.y) {
        return;
    }
    let pixel = id.y * camera.size.x + id.x;
    var ids = vec4<u32>(0u);
    var covered = 0u;
    var nearest = 1.0;
    for (var s = 0u; s < info.samples; s++) {
        let v = u32(textureLoad(visibility, vec2<i32>(id.xy), i32(s)).x);
        ids[s] = v;
        if (v != 0u) {
            covered = covered + 1u;
            nearest = min(nearest, textureLoad(depth, vec2<i32>(id.xy), i32(s)));
        }
    }
    let alpha = f32(covered) / f32(info.samples);
    let sum = aov_r[pixel].xyz + aov_tt[pixel].xyz + aov_trt[pixel].xyz + aov_ms_global[pixel].xyz + aov_ms_local[pixel].xyz;
    beauty[pixel] = vec4<f32>(info.exposure_scale * sum, alpha);
    view_depth[pixel] = select(1e10, linear_depth(nearest), covered > 0u);
    sample_ids[pixel] = ids;
}
