// Resolve pass: per pixel, coverage (alpha: the hair's composited K-buffer coverage, plus the occluder's
// samples' share behind the hair in front of them), the nearest view depth (hair or occluder), the
// occluder's sample ids (its triangle + 1 with the top bit set; for the CPU twins), and the beauty = sum of the accumulated components
// and the occluder's radiance times the exposure scale 2^EV. Linear, premultiplied by coverage; no tonemap.
// Also the background behind each pixel: the environment map along the pixel's centre ray, exposed
// (zero without a map); the composite is the picture's business (render/passes/background.rs).
// Prepended: circular_gaussian (PI), camera.

struct ResolveInfo {
    exposure_scale: f32,
    samples: u32,
    // The background's latitude-longitude map (0 x 0: none) and its turn about +Y, radians.
    env_width: u32,
    env_height: u32,
    env_yaw: f32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
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
    // 1: also look the background up (it depends on the camera alone: a shading band's resolve skips it).
    background: u32,
    // 1: progressive refinement has shaded part of the fragments: the hair's radiance is scaled by its
    // alpha over the weight shaded so far (the unshaded fragments take the shaded ones' mean), by at
    // most MAX_NORMALISE (a sliver in front, shaded first, would otherwise stand for a whole pixel).
    normalise: u32,
}
@group(0) @binding(12) var<storage, read> band: ResolveRows;
@group(0) @binding(13) var<storage, read> environment: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read_write> background: array<vec4<f32>>;
// The occluder's radiance (coverage-weighted, like the components); zero without one.
@group(0) @binding(15) var<storage, read> occluder: array<vec4<f32>>;
// The K-buffer's per-pixel summary (hair alpha, transmittance of the hair in front of the occluder,
// nearest hair depth, fragment count).
@group(0) @binding(16) var<storage, read> pixel_info: array<vec4<f32>>;

// Radiance of the environment along the unit world direction d: the map turned back by the yaw
// (envmap/direction.rs: rotate_yaw, uv_from_direction), bilinear between texel centres, wrapping in
// azimuth, clamped at the poles. Twin of BackgroundMap::radiance (src/render/passes/background.rs).
fn background_radiance(d: vec3<f32>) -> vec3<f32> {
    let w = i32(info.env_width);
    let h = i32(info.env_height);
    if (w == 0 || h == 0) {
        return vec3<f32>(0.0);
    }
    let s = sin(-info.env_yaw);
    let c = cos(-info.env_yaw);
    let m = normalize(vec3<f32>(c * d.x + s * d.z, d.y, -s * d.x + c * d.z));
    let theta = acos(clamp(m.y, -1.0, 1.0));
    let phi = atan2(m.x, -m.z);
    let u = fract(phi / (2.0 * PI) + 0.5);
    let v = theta / PI;
    let x = u * f32(w) - 0.5;
    let y = clamp(v * f32(h) - 0.5, 0.0, f32(h - 1));
    let x0 = floor(x);
    let y0 = floor(y);
    let f = vec2<f32>(x - x0, y - y0);
    let xa = ((i32(x0) % w) + w) % w;
    let xb = (xa + 1) % w;
    let ya = clamp(i32(y0), 0, h - 1);
    let yb = clamp(i32(y0) + 1, 0, h - 1);
    let a = environment[ya * w + xa].xyz;
    let b = environment[ya * w + xb].xyz;
    let e = environment[yb * w + xa].xyz;
    let g = environment[yb * w + xb].xyz;
    let top = a + (b - a) * f.x;
    let bottom = e + (g - e) * f.x;
    return top + (bottom - top) * f.y;
}

const MAX_NORMALISE: f32 = 4.0;

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
    // The occluder's samples (the hair is in the K-buffer: render/passes/kbuffer.rs).
    var ids = vec4<u32>(0u);
    var covered = 0u;
    var nearest = 1.0;
    for (var s = 0u; s < info.samples; s++) {
        let tri = visible_occluder(textureLoad(visibility, vec2<i32>(id.xy), i32(s)).x);
        if (tri != 0u) {
            ids[s] = OCCLUDER_ID_BIT | tri;
            covered = covered + 1u;
            nearest = min(nearest, textureLoad(depth, vec2<i32>(id.xy), i32(s)));
        }
    }
    // The hair's composited coverage, and the occluder's behind the hair in front of it.
    let hair = pixel_info[pixel];
    let alpha = min(hair.x + f32(covered) / f32(info.samples) * hair.y, 1.0);
    var hair_sum = aov_r[pixel].xyz + aov_tt[pixel].xyz + aov_trt[pixel].xyz + aov_ms_global[pixel].xyz + aov_ms_local[pixel].xyz;
    let shaded = aov_r[pixel].w;
    if (band.normalise != 0u && shaded > 0.0) {
        hair_sum = hair_sum * min(hair.x / shaded, MAX_NORMALISE);
    }
    let sum = hair_sum + occluder[pixel].xyz;
    beauty[pixel] = vec4<f32>(info.exposure_scale * sum, alpha);
    view_depth[pixel] = min(hair.z, select(1e10, linear_depth(camera, nearest), covered > 0u));
    sample_ids[pixel] = ids;
    if (band.background != 0u) {
        let ray = pixel_ray(camera, f32(id.x) + 0.5, f32(id.y) + 0.5);
        background[pixel] = vec4<f32>(info.exposure_scale * background_radiance(ray.dir), 1.0);
    }
}
