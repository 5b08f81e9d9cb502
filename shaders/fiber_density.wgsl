// The fiber-density volume on the GPU. Twin of FiberDensity::build (src/shadow/fiber_density.rs):
// `deposit` runs one invocation per segment and adds its sub-sampled length, orientation tensor,
// absorption and diameter into the voxels in fixed point (portable u32 atomics; one add per run of
// sub-samples in a voxel); `resolve` runs one
// invocation per voxel and turns the sums into the extinction a = rho_L D, the tensor M = rho_L D <u u^T>,
// the mean absorption and rho_L.

struct VolumeInfo {
    origin: vec3<f32>,
    voxel: f32,
    dims: vec3<u32>,
    segment_count: u32,
}

// Fixed-point scale of the sums: 2^20 units per cm (a voxel may hold up to 4096 cm of fiber).
const FIXED_SCALE: f32 = 1048576.0;
const CHANNELS: u32 = 11u; // length, 6 tensor, 3 absorption, diameter (each x length)

@group(0) @binding(0) var<uniform> info: VolumeInfo;
// Point positions (xyz) and diameter (w), cm.
@group(0) @binding(1) var<storage, read> points: array<vec4<f32>>;
// Per-point sigma_a (xyz).
@group(0) @binding(2) var<storage, read> absorption: array<vec4<f32>>;
// First point of each segment (the segment joins it to the next point).
@group(0) @binding(3) var<storage, read> segments: array<u32>;
@group(0) @binding(4) var<storage, read_write> sums: array<atomic<u32>>;
// Three vec4 per voxel: (a, M_xx, M_yy, M_zz), (M_xy, M_xz, M_yz, rho_L), (sigma_a.rgb, solid fraction).
@group(0) @binding(5) var<storage, read_write> volume: array<vec4<f32>>;
// The segments a deposit dispatch adds: [first, first + count) (all of them for a whole build, a
// range per unit of progressive refinement; fixed-point sums make the parts add up exactly).
struct SegmentRange {
    first: u32,
    count: u32,
    _p0: u32,
    _p1: u32,
}
@group(0) @binding(6) var<storage, read> range: SegmentRange;
// The fraction of each voxel inside the occluder (0 without one; src/shadow/solid.rs).
@group(0) @binding(7) var<storage, read> solid: array<f32>;

// The occluder as an opaque solid (src/shadow/solid.rs): crossings per voxel of path, and its absorption.
const SOLID_DEPTH_PER_VOXEL: f32 = 8.0;
const SOLID_SIGMA_A: f32 = 50.0;

fn voxel_index(p: vec3<f32>) -> i32 {
    let q = floor((p - info.origin) / info.voxel);
    if (any(q < vec3<f32>(0.0)) || any(q >= vec3<f32>(info.dims))) {
        return -1;
    }
    let i = vec3<u32>(q);
    return i32((i.z * info.dims.y + i.y) * info.dims.x + i.x);
}

fn add_fixed(v: u32, c: u32, x: f32) {
    atomicAdd(&sums[v * CHANNELS + c], u32(round(max(x, 0.0) * FIXED_SCALE)));
}

@compute @workgroup_size(64)
fn deposit(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Flat index over a 2D dispatch (a dimension holds at most 65535 workgroups).
    let k = id.x + id.y * groups.x * 64u;
    let s = range.first + k;
    if (k >= range.count || s >= info.segment_count) {
        return;
    }
    let i = segments[s];
    let a = points[i].xyz;
    let b = points[i + 1u].xyz;
    let l = distance(a, b);
    if (l <= 0.0) {
        return;
    }
    let u = (b - a) / l;
    let sig = 0.5 * (absorption[i].xyz + absorption[i + 1u].xyz);
    let d = 0.5 * (points[i].w + points[i + 1u].w);
    let steps = max(u32(ceil(l / (0.25 * info.voxel))), 1u);
    let dl = l / f32(steps);
    // Consecutive sub-samples in the same voxel are added as one run (a segment's direction,
    // absorption and diameter are its own): about a quarter of the atomics of one add per sub-sample.
    var run_voxel = -1;
    var run_steps = 0u;
    for (var k = 0u; k < steps; k++) {
        let x = a + (b - a) * ((f32(k) + 0.5) / f32(steps));
        let v = voxel_index(x);
        if (v != run_voxel) {
            if (run_voxel >= 0) {
                deposit_run(u32(run_voxel), f32(run_steps) * dl, u, sig, d);
            }
            run_voxel = v;
            run_steps = 0u;
        }
        run_steps = run_steps + 1u;
    }
    if (run_voxel >= 0) {
        deposit_run(u32(run_voxel), f32(run_steps) * dl, u, sig, d);
    }
}

// A run of length `len` of a segment (unit direction u, absorption sig, diameter d) added to voxel vi.
// The tensor's off-diagonal terms can be negative: store u u^T + 1 (all >= 0) and remove the offset
// in `resolve` (the sum of the lengths is the length channel).
fn deposit_run(vi: u32, len: f32, u: vec3<f32>, sig: vec3<f32>, d: f32) {
    add_fixed(vi, 0u, len);
    add_fixed(vi, 1u, len * u.x * u.x);
    add_fixed(vi, 2u, len * u.y * u.y);
    add_fixed(vi, 3u, len * u.z * u.z);
    add_fixed(vi, 4u, len * (u.x * u.y + 1.0));
    add_fixed(vi, 5u, len * (u.x * u.z + 1.0));
    add_fixed(vi, 6u, len * (u.y * u.z + 1.0));
    add_fixed(vi, 7u, len * sig.x);
    add_fixed(vi, 8u, len * sig.y);
    add_fixed(vi, 9u, len * sig.z);
    add_fixed(vi, 10u, len * d);
}

// The sums' index of neighbour n (0..27, x fastest) of voxel i, or -1 outside the volume.
fn neighbour_voxel(i: vec3<i32>, n: u32) -> i32 {
    let d = info.dims;
    let q = i + vec3<i32>(i32(n % 3u), i32((n / 3u) % 3u), i32(n / 9u)) - vec3<i32>(1);
    if (any(q < vec3<i32>(0)) || any(q >= vec3<i32>(d))) {
        return -1;
    }
    return i32((u32(q.z) * d.y + u32(q.y)) * d.x + u32(q.x));
}

// The absorption of an empty voxel: the length-weighted mean over its 26 neighbours (0 if they are
// empty too), so the forward march sees the absorption of the fibers its trilinear density counts.
// The lengths first: most empty voxels have no hair around them, and their absorption sums are not
// read (a neighbour of no length holds no absorption, unless its runs were all under the fixed
// point's 2^-20 cm, whose absorption is left out).
fn neighbour_absorption(v: u32) -> vec3<f32> {
    let d = info.dims;
    let i = vec3<i32>(vec3<u32>(v % d.x, (v / d.x) % d.y, v / (d.x * d.y)));
    var len = 0.0;
    for (var n = 0u; n < 27u; n++) {
        let u = neighbour_voxel(i, n);
        if (u >= 0) {
            len = len + f32(atomicLoad(&sums[u32(u) * CHANNELS])) / FIXED_SCALE;
        }
    }
    if (len <= 0.0) {
        return vec3<f32>(0.0);
    }
    var sig = vec3<f32>(0.0);
    for (var n = 0u; n < 27u; n++) {
        let u = neighbour_voxel(i, n);
        if (u >= 0 && atomicLoad(&sums[u32(u) * CHANNELS]) != 0u) {
            sig = sig + vec3<f32>(
                f32(atomicLoad(&sums[u32(u) * CHANNELS + 7u])),
                f32(atomicLoad(&sums[u32(u) * CHANNELS + 8u])),
                f32(atomicLoad(&sums[u32(u) * CHANNELS + 9u])),
            ) / FIXED_SCALE;
        }
    }
    return sig / len;
}

@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Voxels [range.first, range.first + range.count) (progressive refinement resolves in parts).
    let i = id.x + id.y * groups.x * 64u;
    let v = range.first + i;
    if (i >= range.count || v >= info.dims.x * info.dims.y * info.dims.z) {
        return;
    }
    var s: array<f32, 11>;
    for (var c = 0u; c < CHANNELS; c++) {
        s[c] = f32(atomicLoad(&sums[v * CHANNELS + c])) / FIXED_SCALE;
    }
    let len = s[0];
    // The occluder's isotropic extinction, its absorption mixed in by extinction (FiberDensity::add_solid).
    let a_s = SOLID_DEPTH_PER_VOXEL * solid[v] / info.voxel;
    if (len <= 0.0) {
        volume[3u * v] = vec4<f32>(a_s, 0.0, 0.0, 0.0);
        volume[3u * v + 1u] = vec4<f32>(0.0);
        var sig = vec3<f32>(SOLID_SIGMA_A);
        if (a_s <= 0.0) {
            sig = neighbour_absorption(v);
        }
        volume[3u * v + 2u] = vec4<f32>(sig, solid[v]);
        return;
    }
    let rho = len / (info.voxel * info.voxel * info.voxel);
    let d = s[10] / len;
    let k = rho * d / len;
    let a_h = rho * d;
    let sig = vec3<f32>(s[7], s[8], s[9]) / len;
    volume[3u * v] = vec4<f32>(a_h + a_s, k * s[1], k * s[2], k * s[3]);
    volume[3u * v + 1u] = vec4<f32>(k * (s[4] - len), k * (s[5] - len), k * (s[6] - len), rho);
    volume[3u * v + 2u] = vec4<f32>((a_h * sig + a_s * SOLID_SIGMA_A) / (a_h + a_s), solid[v]);
}
