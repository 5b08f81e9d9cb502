// Visibility pass: the occluder (the head), opaque, into a multisampled R32Float target holding
// -(triangle + 1) per sample (0 where there is none), with depth. The hair is not drawn here: its
// fragments go into the K-buffer (kbuffer.wgsl), which reads this depth.

@group(0) @binding(0) var<uniform> camera: Camera;

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
