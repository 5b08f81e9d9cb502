// Forward scattering along a shadow path from the fiber-density volume: the direct fraction,
// T_f = E[prod a_f] and sigma_f^2 (weighted by the light each path transmits), with the crossed fibers' own absorption. Twin of
// src/shadow/forward.rs. Reads the pyramid (level 0: trilinear crossings and tensor), the volume
// (nearest voxel's absorption) and the (theta, sigma_a) table of a_f and beta_f^2.
// Bindings declared by the including module: pyramid_info, pyramid, volume_info, volume, forward_table.

const FWD_THETA_SAMPLES: u32 = 64u;
const FWD_SIGMA_SAMPLES: u32 = 33u;
const FWD_SIGMA_MIN: f32 = 0.005;
const FWD_SIGMA_MAX: f32 = 50.0;

// The volume's placement (twin of VolumeInfo in src/gpu/fiber_density.rs).
struct VolumeInfoF {
    origin: vec3<f32>,
    voxel: f32,
    dims: vec3<u32>,
    segment_count: u32,
}

struct ForwardScattering {
    direct_fraction: f32,
    transmittance_f: vec3<f32>,
    sigma_f2: vec3<f32>,
}

fn forward_sigma_pos(s: f32) -> f32 {
    if (s <= FWD_SIGMA_MIN) {
        return max(s / FWD_SIGMA_MIN, 0.0);
    }
    return 1.0 + log(s / FWD_SIGMA_MIN) / log(FWD_SIGMA_MAX / FWD_SIGMA_MIN) * f32(FWD_SIGMA_SAMPLES - 2u);
}

// The means over +-theta of a_f and of a_f beta_f^2 at (theta, sigma_a), bilinear; the table holds the
// nodes' means (ForwardTable::symmetric_node), theta fastest. Twin of ForwardTable::lookup_symmetric.
fn forward_lookup(theta: f32, sigma_a: f32) -> vec2<f32> {
    let x = clamp((theta + FRAC_PI_2) / PI, 0.0, 1.0) * f32(FWD_THETA_SAMPLES - 1u);
    let y = clamp(forward_sigma_pos(sigma_a), 0.0, f32(FWD_SIGMA_SAMPLES - 1u));
    let i = min(u32(x), FWD_THETA_SAMPLES - 2u);
    let j = min(u32(y), FWD_SIGMA_SAMPLES - 2u);
    let wx = x - f32(i);
    let wy = y - f32(j);
    let v00 = forward_table[j * FWD_THETA_SAMPLES + i];
    let v10 = forward_table[j * FWD_THETA_SAMPLES + i + 1u];
    let v01 = forward_table[(j + 1u) * FWD_THETA_SAMPLES + i];
    let v11 = forward_table[(j + 1u) * FWD_THETA_SAMPLES + i + 1u];
    return mix(mix(v00, v10, wx), mix(v01, v11, wx), wy);
}

fn forward_voxel_at(p: vec3<f32>) -> i32 {
    let q = floor((p - volume_info.origin) / volume_info.voxel);
    if (any(q < vec3<f32>(0.0)) || any(q >= vec3<f32>(volume_info.dims))) {
        return -1;
    }
    let i = vec3<u32>(q);
    return i32((i.z * volume_info.dims.y + i.y) * volume_info.dims.x + i.x);
}

// The integrals of a shadow path (twin of PathIntegrals in src/shadow/forward.rs): tau = integral c ds,
// per channel integral c a_f ds, integral c a_f beta_f^2 ds; per cm at a point. T_f's loss integral
// c (1 - a_f) ds is tau - mass (path_loss).
struct PathIntegrals {
    tau: f32,
    mass: vec3<f32>,
    spread: vec3<f32>,
}

fn path_add_scaled(s: PathIntegrals, o: PathIntegrals, h: f32) -> PathIntegrals {
    return PathIntegrals(s.tau + h * o.tau, s.mass + h * o.mass, s.spread + h * o.spread);
}

fn path_zero() -> PathIntegrals {
    return PathIntegrals(0.0, vec3<f32>(0.0), vec3<f32>(0.0));
}

// PathIntegrals::loss: per channel tau - mass, at least 0.
fn path_loss(s: PathIntegrals) -> vec3<f32> {
    return max(vec3<f32>(s.tau) - s.mass, vec3<f32>(0.0));
}

// The integrands at x along omega, the pyramid read at level `lod`: crossing density and inclination
// from the same (a, M), absorption from the level-0 voxel (an empty one holds its neighbours'); zero
// outside the volume.
fn forward_integrand(x: vec3<f32>, omega: vec3<f32>, lod: f32) -> PathIntegrals {
    let v = forward_voxel_at(x);
    if (v < 0) {
        return path_zero();
    }
    return forward_integrand_of(extinction_at(x, lod), volume[3 * v + 2].xyz, omega);
}

// The integrands along omega where the volume reads extinction e and absorption sig (what
// forward_integrand reads at a point; the shadow grid's sweeps read it at their midpoints, from their
// samples).
fn forward_integrand_of(e: Extinction, sig: vec3<f32>, omega: vec3<f32>) -> PathIntegrals {
    var out = path_zero();
    let c = crossings(e.a, e.m0, e.m1, omega);
    if (c <= 0.0) {
        return out;
    }
    let w = omega;
    let q = (dot(e.m0, w * w) + 2.0 * (e.m1.x * w.x * w.y + e.m1.y * w.x * w.z + e.m1.z * w.y * w.z)) / max(e.a, 1e-30);
    let theta = asin_precise(sqrt(clamp(q, 0.0, 1.0)));
    out.tau = c;
    for (var ch = 0u; ch < 3u; ch++) {
        let f = forward_lookup(theta, sig[ch]);
        out.mass[ch] = c * f.x;
        out.spread[ch] = c * f.y;
    }
    return out;
}

// The direct fraction, T_f and sigma_f^2 of a path with these integrals.
fn path_scattering(s: PathIntegrals) -> ForwardScattering {
    var out: ForwardScattering;
    out.direct_fraction = exp(-s.tau);
    out.transmittance_f = exp(-path_loss(s));
    for (var ch = 0u; ch < 3u; ch++) {
        out.sigma_f2[ch] = forward_spread_weighted(s.mass[ch], s.spread[ch]);
    }
    return out;
}

// A cone of half-angle `half_angle` marched as cone_optical_depth marches it (steps of half its
// width, pyramid levels of that width; 0: a thin ray on level 0), so the direct fraction is that
// cone's exp(-tau). The reference the shadow grid's sweeps are tested against.
fn forward_scattering(p: vec3<f32>, omega: vec3<f32>, half_angle: f32, skip: f32) -> ForwardScattering {
    let exit = pyramid_exit(p, omega);
    let tn = tan(min(half_angle, 1.5));
    var sums = path_zero();
    var s = skip;
    for (var it = 0; it < 4096; it++) {
        if (s >= exit) {
            break;
        }
        let st = cone_step(s, tn, exit);
        let x = p + omega * (s + 0.5 * st.x);
        s = s + st.x;
        sums = path_add_scaled(sums, forward_integrand(x, omega, st.y), st.x);
    }
    return path_scattering(sums);
}

// sigma_f^2 = T_f W / (T_f - direct) = W / (1 - exp(-A)), A = integral c a_f ds, W = integral c a_f beta_f^2 ds
// (twin of forward_spread_weighted in src/shadow/forward.rs).
fn forward_spread_weighted(forward_mass: f32, weighted_spread: f32) -> f32 {
    if (forward_mass <= 0.0 || weighted_spread <= 0.0) {
        return 0.0;
    }
    var scattered = 1.0 - exp(-forward_mass);
    if (forward_mass < 1e-3) {
        scattered = forward_mass * (1.0 - 0.5 * forward_mass);
    }
    return weighted_spread / scattered;
}
