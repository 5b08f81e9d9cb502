// Occluder shading (the head): for every pixel, the distinct occluder triangles among its visibility
// samples, each shaded at the pixel ray's hit on the triangle's plane with the interpolated vertex
// normal, as a diffuse surface under one batch of SRBF lights: albedo / pi times each light's
// irradiance (Hill's fitted SG-cosine convolution, `sg_irradiance`) times its transmittance through
// the hair, read from the shadow grid a little off the surface (clamped at the grid's faces, fading to 1
// within a grid spacing outside it). Weighted by the
// samples' coverage and the transmittance of the hair in front (the K-buffer's), and added to the
// occluder buffer. Twin of src/render/passes/occluder.rs (shade_occluder).
// Prepended: circular_gaussian (PI), shadow_grid (GpuLight, ShadeBatch, FLAG_SHADOWS), camera.

struct OccluderInfo {
    albedo: vec3<f32>,
    // How far off the surface, along its normal, the shadow grid is read (cm).
    normal_offset: f32,
}

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> batch: ShadeBatch;
@group(0) @binding(2) var<uniform> shadow_grid: ShadowGridInfo;
@group(0) @binding(3) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read> shadow_values: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> normals: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> triangles: array<u32>;
@group(0) @binding(8) var<storage, read> info: OccluderInfo;
@group(0) @binding(9) var visibility: texture_multisampled_2d<f32>;
@group(0) @binding(10) var<storage, read_write> occluder: array<vec4<f32>>;
// The K-buffer's per-pixel summary: .y is the transmittance of the hair in front of the occluder.
@group(0) @binding(11) var<storage, read> pixel_info: array<vec4<f32>>;

// Irradiance of an SRBF of unit amplitude, G(w) = exp(2 (w.xi - 1) / lambda^2), on a surface whose
// normal makes cosine `mu` with its centre: Hill 2016's fitted convolution with the clamped cosine
// (sharpness s = 2 / lambda^2), normalised, times 2 pi / s. Twin of sg_irradiance in occluder.rs.
fn sg_irradiance(mu: f32, lambda: f32) -> f32 {
    let s = 2.0 / (lambda * lambda);
    let c0 = 0.36;
    let c1 = 1.0 / (4.0 * c0);
    let eml = exp(-s);
    let em2l = eml * eml;
    let rl = 1.0 / s;
    let scale = 1.0 + 2.0 * em2l - rl;
    let bias = (eml - em2l) * rl - em2l;
    let x = sqrt(max(1.0 - scale, 0.0));
    let x0 = c0 * mu;
    let x1 = c1 * x;
    let n = x0 + x1;
    var y = clamp(mu, 0.0, 1.0);
    if (abs(x0) <= x1 && x > 0.0) {
        y = n * n / x;
    }
    // Hill normalises by the approximate integral 2 pi / s.
    return max(scale * y + bias, 0.0) * 2.0 * PI / s;
}

// The hit of the ray on triangle `tri`'s plane and the barycentric normal there (facing the ray).
struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
}

fn occluder_surface(tri: u32, ray: Ray) -> Surface {
    let i = vec3<u32>(triangles[3u * tri], triangles[3u * tri + 1u], triangles[3u * tri + 2u]);
    let a = positions[i.x].xyz;
    let b = positions[i.y].xyz;
    let c = positions[i.z].xyz;
    let e1 = b - a;
    let e2 = c - a;
    let face = cross(e1, e2);
    let den = dot(face, ray.dir);
    var t = 0.0;
    if (abs(den) > 1e-20) {
        t = dot(face, a - ray.origin) / den;
    }
    let p = ray.origin + t * ray.dir;
    // Barycentrics of p (clamped to the triangle: a sample's centre can lie just outside it).
    let d00 = dot(e1, e1);
    let d01 = dot(e1, e2);
    let d11 = dot(e2, e2);
    let w = p - a;
    let d20 = dot(w, e1);
    let d21 = dot(w, e2);
    let det = max(d00 * d11 - d01 * d01, 1e-30);
    let v = clamp((d11 * d20 - d01 * d21) / det, 0.0, 1.0);
    let u = clamp((d00 * d21 - d01 * d20) / det, 0.0, 1.0 - v);
    var n = normals[i.x].xyz * (1.0 - u - v) + normals[i.y].xyz * v + normals[i.z].xyz * u;
    n = normalize(n);
    if (dot(n, ray.dir) > 0.0) {
        n = -n;
    }
    return Surface(p, n);
}

// How far p lies outside the grid's box, in grid spacings, clamped to [0, 1]: the grid's reading
// (clamped at its faces) fades to unshadowed over one spacing outside it (a bust's shoulders lie far
// outside the hair's grid, where the nearest face's values mean nothing).
fn grid_outside(g: ShadowGridInfo, p: vec3<f32>) -> f32 {
    let q = (p - g.origin) / g.spacing;
    let d = max(max(-q, q - vec3<f32>(g.dims)), vec3<f32>(0.0));
    return clamp(length(d), 0.0, 1.0);
}

// Radiance of the occluder's surface towards the camera under the batch's lights.
fn shade_occluder(s: Surface) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let shadowed = (batch.flags & FLAG_SHADOWS) != 0u;
    let q = s.position + info.normal_offset * s.normal;
    let outside = grid_outside(shadow_grid, q);
    for (var k = 0u; k < batch.count; k++) {
        let j = batch.first + k;
        let l = lights[j];
        let e = sg_irradiance(dot(s.normal, l.direction), l.lambda);
        // A light that does not reach the surface costs no grid lookup.
        if (e <= 0.0) {
            continue;
        }
        var t = 1.0;
        if (shadowed) {
            t = mix(grid_transmittance(shadow_grid, q, j), 1.0, outside);
        }
        sum = sum + t * e * l.rgb;
    }
    return info.albedo / PI * sum;
}

// The occluder's triangle (+ 1; 0: none) at each of the pixel's samples, each sample read once (a
// multisampled load is dear on lavapipe); 0 past the texture's samples (2 or 4).
fn occluder_samples(xy: vec2<i32>) -> vec4<u32> {
    var ids = vec4<u32>(visible_occluder(textureLoad(visibility, xy, 0).x), visible_occluder(textureLoad(visibility, xy, 1).x), 0u, 0u);
    if (textureNumSamples(visibility) > 2u) {
        ids.z = visible_occluder(textureLoad(visibility, xy, 2).x);
        ids.w = visible_occluder(textureLoad(visibility, xy, 3).x);
    }
    return ids;
}

// Component s of v (no dynamic vector indexing: lavapipe spills it to memory).
fn sample_id(v: vec4<u32>, s: u32) -> u32 {
    return select(select(select(v.x, v.y, s == 1u), v.z, s == 2u), v.w, s == 3u);
}

@compute @workgroup_size(8, 8)
fn shade(@builtin(global_invocation_id) id: vec3<u32>) {
    let y = batch.row0 + id.y;
    if (id.x >= camera.size.x || id.y >= batch.rows || y >= camera.size.y) {
        return;
    }
    let xy = vec2<i32>(vec2<u32>(id.x, y));
    let ids = occluder_samples(xy);
    if (all(ids == vec4<u32>(0u))) {
        return;
    }
    let pixel = y * camera.size.x + id.x;
    let ray = pixel_ray(camera, f32(id.x) + 0.5, f32(y) + 0.5);
    var sum = vec3<f32>(0.0);
    let samples = textureNumSamples(visibility);
    for (var s = 0u; s < samples; s++) {
        let tri = sample_id(ids, s);
        if (tri == 0u) {
            continue;
        }
        // Each distinct triangle once (at its first sample), with its share of the samples.
        let same = ids == vec4<u32>(tri);
        if (any(same & (vec4<u32>(0u, 1u, 2u, 3u) < vec4<u32>(s)))) {
            continue;
        }
        let c = select(vec4<u32>(0u), vec4<u32>(1u), same);
        let count = c.x + c.y + c.z + c.w;
        sum = sum + f32(count) / f32(samples) * shade_occluder(occluder_surface(tri - 1u, ray));
    }
    // Seen through the hair in front of it.
    occluder[pixel] = occluder[pixel] + vec4<f32>(pixel_info[pixel].y * sum, 0.0);
}
