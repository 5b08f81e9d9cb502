// Visibility pass: every hair segment drawn as a camera-facing ribbon (the fiber's true width, at least
// camera.min_width_px pixels) into a multisampled R32Float target holding segment + 1 (exact up to 2^24) per sample, with
// depth. The shading pass reads the samples back; 0 means no hair. The occluder (the head) is drawn
// first, opaque, its samples holding -(triangle + 1) (`vs_occluder`, `fs_occluder`).

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> points: array<vec4<f32>>; // xyz, diameter (cm)
@group(0) @binding(2) var<storage, read> segments: array<u32>;     // first point of each segment

struct RibbonOut {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) segment: u32,
}

@vertex
fn vs_ribbon(@builtin(vertex_index) vi: u32) -> RibbonOut {
    let seg = vi / 6u;
    let corner = vi % 6u;
    // Two triangles: (0, -), (1, -), (0, +) and (0, +), (1, -), (1, +).
    let along = corner == 1u || corner == 4u || corner == 5u;
    let side = select(-1.0, 1.0, corner == 2u || corner == 3u || corner == 5u);
    let i0 = segments[seg];
    let a = points[i0];
    let b = points[i0 + 1u];
    let p = select(a, b, along);
    let to_eye = camera.eye - p.xyz;
    let s = cross(b.xyz - a.xyz, to_eye);
    var out: RibbonOut;
    out.segment = seg + 1u;
    let len = length(s);
    if (len < 1e-20) {
        // Degenerate (zero length, or seen end-on): a zero-area triangle.
        out.position = camera.view_proj * vec4<f32>(p.xyz, 1.0);
        return out;
    }
    let depth = max(dot(-to_eye, camera.forward), 1e-6);
    let half_width = max(0.5 * p.w, 0.5 * camera.min_width_px * camera.pixel_angle * depth);
    out.position = camera.view_proj * vec4<f32>(p.xyz + (side * half_width / len) * s, 1.0);
    return out;
}

@fragment
fn fs_ribbon(in: RibbonOut) -> @location(0) f32 {
    return f32(in.segment);
}

// The occluder: triangles pulled from storage (positions xyz, three indices per triangle), each
// sample holding -(triangle + 1).
@group(0) @binding(3) var<storage, read> occluder_positions: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> occluder_triangles: array<u32>;

struct OccluderOut {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) triangle: u32,
}

@vertex
fn vs_occluder(@builtin(vertex_index) vi: u32) -> OccluderOut {
    var out: OccluderOut;
    out.triangle = vi / 3u + 1u;
    let p = occluder_positions[occluder_triangles[vi]].xyz;
    out.position = camera.view_proj * vec4<f32>(p, 1.0);
    return out;
}

@fragment
fn fs_occluder(in: OccluderOut) -> @location(0) f32 {
    return -f32(in.triangle);
}
