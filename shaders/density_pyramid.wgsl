// The fiber-density mip pyramid and the SRBF transmittance by cone marching.
// Twin of src/shadow/cone.rs. The pyramid buffer holds every level, two vec4 per voxel:
// (a, M_xx, M_yy, M_zz), (M_xy, M_xz, M_yz, 0); level 0 is copied from the volume (three vec4 per voxel).

const MAX_LEVELS: u32 = 10u;

struct PyramidLevel {
    dims: vec3<u32>,
    offset: u32, // first voxel of the level in the pyramid buffer (in voxels)
    voxel: f32,
    _p0: f32,
    _p1: f32,
    _p2: f32,
}

struct PyramidInfo {
    origin: vec3<f32>,
    count: u32,
    levels: array<PyramidLevel, MAX_LEVELS>,
}

fn pyramid_index(l: PyramidLevel, i: vec3<i32>) -> i32 {
    if (any(i < vec3<i32>(0)) || any(i >= vec3<i32>(l.dims))) {
        return -1;
    }
    let u = vec3<u32>(i);
    return i32(l.offset + (u.z * l.dims.y + u.y) * l.dims.x + u.x);
}

// sqrt(a^2 - a omega^T M omega).
fn crossings(a: f32, m0: vec3<f32>, m1: vec3<f32>, w: vec3<f32>) -> f32 {
    let q = dot(m0, w * w) + 2.0 * (m1.x * w.x * w.y + m1.y * w.x * w.z + m1.z * w.y * w.z);
    return sqrt(max(a * a - a * q, 0.0));
}

struct Extinction {
    a: f32,
    m0: vec3<f32>,
    m1: vec3<f32>,
}

fn level_sample(l: PyramidLevel, p: vec3<f32>) -> Extinction {
    let q = (p - pyramid_info.origin) / l.voxel - vec3<f32>(0.5);
    let base = floor(q);
    let f = q - base;
    var e = Extinction(0.0, vec3<f32>(0.0), vec3<f32>(0.0));
    for (var corner = 0u; corner < 8u; corner++) {
        let o = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
        let v = pyramid_index(l, vec3<i32>(base) + vec3<i32>(o));
        if (v < 0) {
            continue;
        }
        let w3 = select(vec3<f32>(1.0) - f, f, o == vec3<u32>(1u));
        let w = w3.x * w3.y * w3.z;
        let x0 = pyramid[2 * v];
        let x1 = pyramid[2 * v + 1];
        e.a = e.a + w * x0.x;
        e.m0 = e.m0 + w * x0.yzw;
        e.m1 = e.m1 + w * x1.xyz;
    }
    return e;
}

// (a, M) at p at continuous level `lod` (trilinear in each level, linear between levels).
fn extinction_at(p: vec3<f32>, lod: f32) -> Extinction {
    let top = f32(pyramid_info.count - 1u);
    let l = clamp(lod, 0.0, top);
    let l0 = u32(floor(l));
    let l1 = min(l0 + 1u, pyramid_info.count - 1u);
    let t = l - f32(l0);
    let e0 = level_sample(pyramid_info.levels[l0], p);
    // A whole level (every step of a thin ray, and a cone's first steps) reads one level: the other has
    // weight zero, and mix(e0, e1, 0) is e0 exactly.
    if (t == 0.0 || l1 == l0) {
        return e0;
    }
    let e1 = level_sample(pyramid_info.levels[l1], p);
    return Extinction(mix(e0.a, e1.a, t), mix(e0.m0, e1.m0, t), mix(e0.m1, e1.m1, t));
}

// Crossings per cm along omega at p, at continuous level `lod`.
fn crossings_at(p: vec3<f32>, omega: vec3<f32>, lod: f32) -> f32 {
    let e = extinction_at(p, lod);
    return crossings(e.a, e.m0, e.m1, omega);
}

// Distance from p along omega (unit) to where the ray leaves the pyramid's box.
fn pyramid_exit(p: vec3<f32>, omega: vec3<f32>) -> f32 {
    let l0 = pyramid_info.levels[0];
    let hi = pyramid_info.origin + l0.voxel * vec3<f32>(l0.dims);
    var exit = 3.0e38;
    for (var ax = 0; ax < 3; ax++) {
        let w = omega[ax];
        if (abs(w) > 1e-12) {
            let t = select((pyramid_info.origin[ax] - p[ax]) / w, (hi[ax] - p[ax]) / w, w > 0.0);
            exit = min(exit, t);
        }
    }
    return exit;
}

// One step of a cone march at distance s (tn = tan of the half-angle): (step length, pyramid level).
// The step is half the cone's width there (at least half a level-0 voxel), the level that width's.
fn cone_step(s: f32, tn: f32, exit: f32) -> vec2<f32> {
    let base = pyramid_info.levels[0].voxel;
    let width = max(2.0 * s * tn, base);
    return vec2<f32>(max(min(0.5 * width, exit - s), 1e-6), log2(width / base));
}

fn cone_optical_depth(p: vec3<f32>, omega: vec3<f32>, half_angle: f32, skip: f32) -> f32 {
    let exit = pyramid_exit(p, omega);
    let tn = tan(min(half_angle, 1.5));
    var s = skip;
    var tau = 0.0;
    for (var it = 0; it < 4096; it++) {
        if (s >= exit) {
            break;
        }
        let st = cone_step(s, tn, exit);
        tau = tau + crossings_at(p + omega * (s + 0.5 * st.x), omega, st.y) * st.x;
        s = s + st.x;
    }
    return tau;
}

// Half-angle of the central cone of srbf_transmittance (srbf_cones in cone.rs): the cone holding half
// the SRBF's weight, at least 1e-4.
fn srbf_centre_cone(lambda: f32) -> f32 {
    let kappa = 2.0 / (lambda * lambda);
    let e = exp(-2.0 * kappa);
    return max(acos(clamp(1.0 + log(0.5 * (1.0 - e) + e) / kappa, -1.0, 1.0)), 1e-4);
}

// G-weighted average of exp(-tau) by seven cones (one central, six on a ring).
fn srbf_transmittance(p: vec3<f32>, centre: vec3<f32>, lambda: f32, skip: f32) -> f32 {
    let kappa = 2.0 / (lambda * lambda);
    let e = exp(-2.0 * kappa);
    let inner = acos(clamp(1.0 + log(0.5 * (1.0 - e) + e) / kappa, -1.0, 1.0));
    if (inner < 0.05) {
        return exp(-cone_optical_depth(p, centre, max(inner, 1e-4), skip));
    }
    let ring = acos(clamp(1.0 + log(0.25 * (1.0 - e) + e) / kappa, -1.0, 1.0));
    var e1 = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(centre.x) < 0.9);
    e1 = normalize(e1 - centre * dot(centre, e1));
    let e2 = cross(centre, e1);
    let sub = min(ring * PI / 6.0, ring);
    var t = 0.5 * exp(-cone_optical_depth(p, centre, inner, skip));
    for (var k = 0; k < 6; k++) {
        let a = f32(k) * TAU / 6.0;
        let d = normalize(centre * cos(ring) + (e1 * cos(a) + e2 * sin(a)) * sin(ring));
        t = t + (0.5 / 6.0) * exp(-cone_optical_depth(p, d, sub, skip));
    }
    return t;
}
