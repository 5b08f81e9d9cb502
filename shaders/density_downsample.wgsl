// Builds the fiber-density mip pyramid (twin of DensityPyramid::build, src/shadow/cone.rs):
// `copy_level0` copies (a, M) out of the volume, `downsample` averages the 8 children of each voxel
// of the next level (children outside the level count as empty space).

struct DownsampleInfo {
    src_dims: vec3<u32>,
    src_offset: u32,
    dst_dims: vec3<u32>,
    dst_offset: u32,
}

@group(0) @binding(0) var<uniform> ds: DownsampleInfo;
@group(0) @binding(1) var<storage, read> volume: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> pyramid_out: array<vec4<f32>>;

@compute @workgroup_size(64)
fn copy_level0(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = id.x + id.y * groups.x * 64u;
    if (v >= ds.dst_dims.x * ds.dst_dims.y * ds.dst_dims.z) {
        return;
    }
    pyramid_out[2u * v] = volume[3u * v];
    pyramid_out[2u * v + 1u] = vec4<f32>(volume[3u * v + 1u].xyz, 0.0);
}

@compute @workgroup_size(64)
fn downsample(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let v = id.x + id.y * groups.x * 64u;
    let d = ds.dst_dims;
    if (v >= d.x * d.y * d.z) {
        return;
    }
    let i = v % d.x;
    let j = (v / d.x) % d.y;
    let k = v / (d.x * d.y);
    var x0 = vec4<f32>(0.0);
    var x1 = vec4<f32>(0.0);
    for (var c = 0u; c < 8u; c++) {
        let ci = 2u * i + (c & 1u);
        let cj = 2u * j + ((c >> 1u) & 1u);
        let ck = 2u * k + ((c >> 2u) & 1u);
        if (ci >= ds.src_dims.x || cj >= ds.src_dims.y || ck >= ds.src_dims.z) {
            continue;
        }
        let u = ds.src_offset + (ck * ds.src_dims.y + cj) * ds.src_dims.x + ci;
        x0 = x0 + 0.125 * pyramid_out[2u * u];
        x1 = x1 + 0.125 * pyramid_out[2u * u + 1u];
    }
    let w = ds.dst_offset + v;
    pyramid_out[2u * w] = x0;
    pyramid_out[2u * w + 1u] = x1;
}
