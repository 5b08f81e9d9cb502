// The shadow-grid build pass: light-space sweeps (twin of src/shadow/sweep.rs). After each new pyramid,
// `build_midplane_samples` reads what the sweeps need on the planes between the grid's slices (the
// pyramid's (a, M), the voxel's absorption and solid share: light-independent); then one workgroup per
// light (all lights for a whole frame, a range of their sweeps per unit of progressive refinement)
// sweeps the grid slice by slice along each of the light's directions (sweep_direction), adding each
// point's transmittance (and, when multiple scattering is on, the forward-scattering terms T_f and
// sigma_f^2, and the optical depth of the hair behind the point along the light's travel) to the
// point's entry, then turns the sums into what the shading pass reads (finish).
// Prepended: circular_gaussian, density_pyramid, forward_scattering, shadow_grid.

// The three descriptions are read as storage, not uniforms: lavapipe recompiles a shader whose loops
// depend on small uniforms with their values inlined at every new bind group (15-25 ms and ~3.4 MB kept
// per dispatch of this shader, seen with a bind group per unit of progressive refinement).
@group(0) @binding(0) var<storage, read> pyramid_info: PyramidInfo;
@group(0) @binding(1) var<storage, read> pyramid: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> shadow_grid: ShadowGridInfo;
@group(0) @binding(3) var<storage, read> grid_lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read_write> shadow_values: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> volume_info: VolumeInfoF;
@group(0) @binding(6) var<storage, read> volume: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> forward_table: array<vec2<f32>>;

// The entries this dispatch builds, [first, first + count) (SWEEP_SLOTS per light, ordered by group of
// lights, then slot, then light: a unit of a few entries sweeps several lights side by side; one
// workgroup per light of the groups touched), and the dispatch's workgroups along x
// (a small buffer per dispatch, so the grid's uniform stays the one the shading pass reads). For
// `build_midplane_samples`, first and count are samples.
struct BuildRange {
    first: u32,
    count: u32,
    // Workgroups along x of the dispatch, in place of @builtin(num_workgroups).
    groups_x: u32,
    // Lights per group of entries (the shading pass's light batch).
    group: u32,
    // 1: one workgroup per entry (a unit of no more entries than a group has lights: each its own
    // light, so the workgroups spread over the adapter's threads however it splits them), 0: one per
    // light of the groups touched.
    per_entry: u32,
    _p0: u32,
    _p1: u32,
    _p2: u32,
}
@group(0) @binding(8) var<storage, read> build_range: BuildRange;

// Per light of the dispatch (from the first one's): two slices (the previous and the current one) of path
// integrals, two vec4 per point: (tau, mass), (spread, 0) (SCRATCH_BYTES in src/render/passes/shadow_grid.rs).
@group(0) @binding(9) var<storage, read_write> sweep_scratch: array<vec4<f32>>;

const SWEEP_GROUP: u32 = 128u;
// The fewest points of a run a sweep's invocation walks along c (build_shadow_grid).
const RUN_MIN: u32 = 8u;

struct SweepDirection {
    omega: vec3<f32>,
    weight: f32,
    behind: bool,
}

// The light's sweeps (sweep_directions in sweep.rs): srbf_cones_on_ring's directions with their weights
// (one of weight 1 when the inner half of G is narrower than 0.05 rad, else the centre (1/2) and
// SWEEP_RING on the ring (1/6 each)), then with multiple scattering the centre reversed.
const SWEEP_RING: u32 = 3u;
fn sweep_direction_count(lambda: f32, forward: bool) -> u32 {
    let kappa = 2.0 / (lambda * lambda);
    let e = exp(-2.0 * kappa);
    let inner = acos(clamp(1.0 + log(0.5 * (1.0 - e) + e) / kappa, -1.0, 1.0));
    return select(1u + SWEEP_RING, 1u, inner < 0.05) + select(0u, 1u, forward);
}

fn sweep_direction(centre: vec3<f32>, lambda: f32, j: u32, count: u32, forward: bool) -> SweepDirection {
    if (forward && j + 1u == count) {
        return SweepDirection(-centre, 1.0, true);
    }
    let cones = count - select(0u, 1u, forward);
    if (cones == 1u) {
        return SweepDirection(centre, 1.0, false);
    }
    if (j == 0u) {
        return SweepDirection(centre, 0.5, false);
    }
    let kappa = 2.0 / (lambda * lambda);
    let e = exp(-2.0 * kappa);
    let ring = acos(clamp(1.0 + log(0.25 * (1.0 - e) + e) / kappa, -1.0, 1.0));
    var e1 = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(centre.x) < 0.9);
    e1 = normalize(e1 - centre * dot(centre, e1));
    let e2 = cross(centre, e1);
    let a = f32(j - 1u) * TAU / f32(SWEEP_RING);
    return SweepDirection(normalize(centre * cos(ring) + (e1 * cos(a) + e2 * sin(a)) * sin(ring)), 0.5 / f32(SWEEP_RING), false);
}

// SweepAxes in sweep.rs: slices across axis a (omega's largest component, ties to the lower axis),
// the others b < c; towards_high: the sweep starts at the high indices of a.
struct SweepAxes {
    a: u32,
    b: u32,
    c: u32,
    towards_high: bool,
    step: f32,
    shift: vec2<f32>,
}

fn sweep_axes(g: ShadowGridInfo, omega: vec3<f32>) -> SweepAxes {
    let m = abs(omega);
    var a = 2u;
    if (m.x >= m.y && m.x >= m.z) {
        a = 0u;
    } else if (m.y >= m.z) {
        a = 1u;
    }
    let b = select(0u, 1u, a == 0u);
    let c = select(2u, 1u, a == 2u);
    let wa = max(m[a], 1e-6);
    return SweepAxes(a, b, c, omega[a] > 0.0, g.spacing / wa, vec2<f32>(omega[b] / wa, omega[c] / wa));
}

// MidplaneSamples in sweep.rs: per point of the planes between the slices across each axis a (plane j
// in 0..=dims[a], MIDPLANE_REFINE points per spacing along b < c, at (i + 1/2) / R spacings; the
// lattices of axes 0, 1, 2 one after another), three vec2<u32> a sample (sample_packing.rs):
// (a as f32 (negative outside the volume: no hair, zero integrands), unorm n_xx n_yy),
// (unorm n_zz solid, snorm n_xy n_xz), (f16 sigma_a r g, f16 sigma_a b | snorm n_yz << 16), with
// n = M / a.
@group(0) @binding(10) var<storage, read_write> grid_samples: array<vec2<u32>>;

// The largest finite f16.
const F16_MAX: f32 = 65504.0;

// sweep_lod in sweep.rs: the coarsest level whose voxel is at most half the spacing.
fn sweep_lod(g: ShadowGridInfo) -> f32 {
    return floor(max(log2(g.spacing / pyramid_info.levels[0].voxel) - 0.99, 0.0));
}

// MIDPLANE_REFINE in sweep.rs: samples per grid spacing across the planes.
const MIDPLANE_REFINE: u32 = 2u;

// The first sample of axis a's lattice ((dims[a] + 1) (R dims[b]) (R dims[c]) samples each).
fn midplane_offset(g: ShadowGridInfo, a: u32) -> u32 {
    let d = g.dims;
    let r2 = MIDPLANE_REFINE * MIDPLANE_REFINE;
    let s0 = (d.x + 1u) * d.y * d.z * r2;
    let s1 = (d.y + 1u) * d.x * d.z * r2;
    return select(select(0u, s0, a >= 1u), s0 + s1, a >= 2u);
}

@compute @workgroup_size(64)
fn build_midplane_samples(@builtin(global_invocation_id) id: vec3<u32>) {
    let g = shadow_grid;
    let d = g.dims;
    let total = midplane_offset(g, 2u) + (d.z + 1u) * d.x * d.y * MIDPLANE_REFINE * MIDPLANE_REFINE;
    // Samples [first, first + count) (build_range; a unit of progressive refinement builds a part).
    // Rows of the dispatch are 65535 workgroups wide whenever there is more than one.
    let k = id.x + id.y * 65535u * 64u;
    let i = build_range.first + k;
    if (k >= build_range.count || i >= total) {
        return;
    }
    // MidplaneSamples::coordinates and position.
    var a = 0u;
    if (i >= midplane_offset(g, 2u)) {
        a = 2u;
    } else if (i >= midplane_offset(g, 1u)) {
        a = 1u;
    }
    let b = select(0u, 1u, a == 0u);
    let c = select(2u, 1u, a == 2u);
    let r = i - midplane_offset(g, a);
    let nb = d[b] * MIDPLANE_REFINE;
    let nc = d[c] * MIDPLANE_REFINE;
    var q = vec3<f32>(0.0);
    q[a] = f32(r / (nb * nc));
    q[b] = (f32(r % nb) + 0.5) / f32(MIDPLANE_REFINE);
    q[c] = (f32((r / nb) % nc) + 0.5) / f32(MIDPLANE_REFINE);
    let x = g.origin + q * g.spacing;
    let v = forward_voxel_at(x);
    if (v < 0) {
        // GridSample::OUTSIDE: a = -1.
        grid_samples[3u * i] = vec2<u32>(bitcast<u32>(-1.0), 0u);
        grid_samples[3u * i + 1u] = vec2<u32>(0u);
        grid_samples[3u * i + 2u] = vec2<u32>(0u);
        return;
    }
    let e = extinction_at(x, sweep_lod(g));
    let s = volume[3u * u32(v) + 2u];
    let inv = select(0.0, 1.0 / e.a, e.a > 0.0);
    let n0 = e.m0 * inv;
    let n1 = e.m1 * inv;
    grid_samples[3u * i] = vec2<u32>(bitcast<u32>(e.a), pack2x16unorm(n0.xy));
    grid_samples[3u * i + 1u] = vec2<u32>(pack2x16unorm(vec2<f32>(n0.z, s.w)), pack2x16snorm(n1.xy));
    // The absorption within f16's range (GridSample::pack).
    let sigma = min(s.xyz, vec3<f32>(F16_MAX));
    let low = pack2x16float(vec2<f32>(sigma.z, 0.0)) & 0xffffu;
    let high = pack2x16snorm(vec2<f32>(0.0, n1.z)) & 0xffff0000u;
    grid_samples[3u * i + 2u] = vec2<u32>(pack2x16float(sigma.xy), low | high);
}

// Without multiple scattering only tau is swept: one vec4 read and written per point.
fn scratch_load(base: u32, i: u32, forward: bool) -> PathIntegrals {
    let x0 = sweep_scratch[base + 2u * i];
    if (!forward) {
        return PathIntegrals(x0.x, vec3<f32>(0.0), vec3<f32>(0.0));
    }
    return PathIntegrals(x0.x, x0.yzw, sweep_scratch[base + 2u * i + 1u].xyz);
}

fn scratch_store(base: u32, i: u32, f: PathIntegrals, forward: bool) {
    sweep_scratch[base + 2u * i] = vec4<f32>(f.tau, f.mass);
    if (forward) {
        sweep_scratch[base + 2u * i + 1u] = vec4<f32>(f.spread, 0.0);
    }
}

// SweepLattice in sweep.rs: where a sweep reads, alike for all its points (the shift is the sweep's).
// Point (ib, ic) reads the previous slice at (ib, ic) + shift: columns ib + slice_offset.x and the next
// with weights 1 - slice_frac.x and slice_frac.x, rows alike; and the plane's fine samples at
// (R ib, R ic) + mid_offset and the next, with weights from mid_frac.
struct SweepLattice {
    slice_offset: vec2<i32>,
    slice_frac: vec2<f32>,
    mid_offset: vec2<i32>,
    mid_frac: vec2<f32>,
}

fn sweep_lattice(ax: SweepAxes) -> SweepLattice {
    let s = floor(ax.shift);
    // The midpoint (ib + 1/2 + shift / 2) spacings is (ib + 1/2 + shift / 2) R - 1/2 in fine points
    // (point i at (i + 1/2) / R spacings): R ib + m.
    let r = f32(MIDPLANE_REFINE);
    let m = vec2<f32>(0.5 * (r - 1.0)) + 0.5 * r * ax.shift;
    let mf = floor(m);
    return SweepLattice(vec2<i32>(s), ax.shift - s, vec2<i32>(mf), m - mf);
}

// slice_row in sweep.rs: row iv of the previous slice read between columns u0 and u0 + 1 (weights
// 1 - f and f), zero off the slice.
fn slice_row(base: u32, nb: u32, nc: u32, u0: i32, f: f32, iv: i32, forward: bool) -> PathIntegrals {
    var out = path_zero();
    if (iv < 0 || iv >= i32(nc)) {
        return out;
    }
    let row = u32(iv) * nb;
    if (u0 >= 0 && u0 < i32(nb)) {
        out = path_add_scaled(out, scratch_load(base, row + u32(u0), forward), 1.0 - f);
    }
    if (u0 + 1 >= 0 && u0 + 1 < i32(nb)) {
        out = path_add_scaled(out, scratch_load(base, row + u32(u0 + 1), forward), f);
    }
    return out;
}

// accumulate in sweep.rs: one direction's path integrals added to the point's entry, (sum w direct,
// sum w T_f), (sum w (T_f - direct) sigma_f^2, depth behind); the first direction writes it.
fn accumulate(e: u32, d: SweepDirection, f: PathIntegrals, forward: bool, first: bool) {
    let direct = exp(-f.tau);
    if (!forward) {
        // Only the direct fraction (v1 is written by finish).
        var t = 0.0;
        if (!first) {
            t = shadow_values[2u * e].x;
        }
        shadow_values[2u * e] = vec4<f32>(t + d.weight * direct, 0.0, 0.0, 0.0);
        return;
    }
    var v0 = vec4<f32>(0.0);
    var v1 = vec4<f32>(0.0);
    if (!first) {
        v0 = shadow_values[2u * e];
        v1 = shadow_values[2u * e + 1u];
    }
    if (d.behind) {
        v1.w = f.tau;
    } else {
        v0.x = v0.x + d.weight * direct;
        let tf3 = exp(-path_loss(f));
        for (var ch = 0u; ch < 3u; ch++) {
            let tf = tf3[ch];
            let s = d.weight * max(tf - direct, 0.0);
            v0[1u + ch] = v0[1u + ch] + d.weight * tf;
            v1[ch] = v1[ch] + s * forward_spread_weighted(f.mass[ch], f.spread[ch]);
        }
    }
    shadow_values[2u * e] = v0;
    shadow_values[2u * e + 1u] = v1;
}

// finish in sweep.rs: the stored value from the sums (transmittances as logarithms: attenuation falls
// off exponentially into the hair, so interpolating its logarithm follows it between grid points far
// better).
// A point in a voxel more than half inside the occluder gets depth_behind = GRID_INSIDE_SOLID and ln T
// stored with its sign bit clear (grid_ln_t_stored): the lookup leaves it out of its interpolation
// (FiberDensity::inside_solid). ln T is at most 0 (the sweeps' sums may round above 1).
fn finish(e: u32, g: ShadowGridInfo) {
    let v0 = shadow_values[2u * e];
    let v1 = shadow_values[2u * e + 1u];
    let t = min(log(max(v0.x, GRID_MIN_TRANSMITTANCE)), 0.0);
    let n = g.dims.x * g.dims.y * g.dims.z;
    let voxel = forward_voxel_at(grid_point(g, e % n));
    let inside = voxel >= 0 && volume[3u * u32(voxel) + 2u].w > 0.5;
    if (g.forward == 0u) {
        shadow_values[2u * e] = vec4<f32>(grid_ln_t_stored(t, inside), vec3<f32>(t));
        shadow_values[2u * e + 1u] = vec4<f32>(0.0, 0.0, 0.0, select(0.0, GRID_INSIDE_SOLID, inside));
        return;
    }
    shadow_values[2u * e] = vec4<f32>(grid_ln_t_stored(t, inside), log(max(v0.yzw, vec3<f32>(GRID_MIN_TRANSMITTANCE))));
    let behind = select(v1.w, GRID_INSIDE_SOLID, inside);
    shadow_values[2u * e + 1u] = vec4<f32>(v1.xyz / max(v0.yzw - vec3<f32>(v0.x), vec3<f32>(1e-12)), behind);
}

// A light's sweeps are slots 0-4 of its entries: 0 the centre, 1-3 the ring (empty for a narrow
// light), 4 the centre reversed (empty without multiple scattering), after which its entries are
// finished. A unit of refinement may hold part of a light's slots.
const SWEEP_SLOTS: u32 = 2u + SWEEP_RING;

// The slot's direction, or none (weight 0) for an empty slot.
fn slot_direction(l: GpuLight, slot: u32, forward: bool) -> SweepDirection {
    let count = sweep_direction_count(l.lambda, forward);
    let cones = count - select(0u, 1u, forward);
    var j = slot;
    if (slot == SWEEP_SLOTS - 1u) {
        j = count - 1u;
        if (!forward) {
            return SweepDirection(l.direction, 0.0, false);
        }
    } else if (slot >= cones) {
        return SweepDirection(l.direction, 0.0, false);
    }
    return sweep_direction(l.direction, l.lambda, j, count, forward);
}

// MidplaneSamples::midpoint: the samples at the midpoint of the path from slice k's point (ib, ic) to
// the previous slice (on their plane, `midplane`, at (ib, ic) + shift / 2), bilinear in that plane, the
// absorption weighted by the extinction; (a, M), (solid, sigma_a) and whether any sample around was
// inside the volume.
struct MidpointSample {
    e: Extinction,
    solid: f32,
    sigma_a: vec3<f32>,
    inside: bool,
}

// A sweep's plane: its first sample and its fine points along b and c (once per slice, not per point:
// dynamic vector indexing in the loop is spilled to memory by lavapipe).
struct Midplane {
    base: u32,
    nb: u32,
    nc: u32,
}

// The plane between slice k and the previous one of sweep ax.
fn midplane(g: ShadowGridInfo, ax: SweepAxes, k: u32) -> Midplane {
    let j = select(k, k + 1u, ax.towards_high);
    let nb = g.dims[ax.b] * MIDPLANE_REFINE;
    let nc = g.dims[ax.c] * MIDPLANE_REFINE;
    return Midplane(midplane_offset(g, ax.a) + j * nc * nb, nb, nc);
}

fn midplane_sample(plane: Midplane, lat: SweepLattice, ib: u32, ic: u32) -> MidpointSample {
    let u0 = i32(MIDPLANE_REFINE * ib) + lat.mid_offset.x;
    let v0 = i32(MIDPLANE_REFINE * ic) + lat.mid_offset.y;
    var out = MidpointSample(Extinction(0.0, vec3<f32>(0.0), vec3<f32>(0.0)), 0.0, vec3<f32>(0.0), false);
    var absorbing = 0.0;
    for (var corner = 0u; corner < 4u; corner++) {
        let high_u = (corner & 1u) == 1u;
        let high_v = corner >= 2u;
        let iu = u0 + select(0, 1, high_u);
        let iv = v0 + select(0, 1, high_v);
        if (iu < 0 || iv < 0 || iu >= i32(plane.nb) || iv >= i32(plane.nc)) {
            continue;
        }
        let i = plane.base + u32(iv) * plane.nb + u32(iu);
        let s0 = grid_samples[3u * i];
        let a = bitcast<f32>(s0.x);
        if (a < 0.0) {
            continue;
        }
        let s1 = grid_samples[3u * i + 1u];
        let s2 = grid_samples[3u * i + 2u];
        let n_xx_yy = unpack2x16unorm(s0.y);
        let n_zz_solid = unpack2x16unorm(s1.x);
        let n_xy_xz = unpack2x16snorm(s1.y);
        let sigma_rg = unpack2x16float(s2.x);
        let w = select(1.0 - lat.mid_frac.x, lat.mid_frac.x, high_u) * select(1.0 - lat.mid_frac.y, lat.mid_frac.y, high_v);
        let wa = w * a;
        out.inside = true;
        out.e.a = out.e.a + wa;
        out.e.m0 = out.e.m0 + wa * vec3<f32>(n_xx_yy, n_zz_solid.x);
        out.e.m1 = out.e.m1 + wa * vec3<f32>(n_xy_xz, unpack2x16snorm(s2.y).y);
        out.solid = out.solid + w * n_zz_solid.y;
        out.sigma_a = out.sigma_a + wa * vec3<f32>(sigma_rg, unpack2x16float(s2.y).x);
        absorbing = absorbing + wa;
    }
    out.sigma_a = out.sigma_a / max(absorbing, 1e-30);
    return out;
}

// sweep_integrand in sweep.rs: the integrands at sample s along omega; with `carried` all of them, else
// the optical depth alone (the depth behind: hair only, the solid's share left out).
fn sweep_integrand(s: MidpointSample, omega: vec3<f32>, carried: bool, behind: bool) -> PathIntegrals {
    if (!s.inside) {
        return path_zero();
    }
    if (carried) {
        return forward_integrand_of(s.e, s.sigma_a, omega);
    }
    var f = path_zero();
    f.tau = crossings(s.e.a, s.e.m0, s.e.m1, omega) * select(1.0, 1.0 - s.solid, behind);
    return f;
}

@compute @workgroup_size(128)
fn build_shadow_grid(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let g = shadow_grid;
    let end = build_range.first + build_range.count;
    let w = group.x + group.y * build_range.groups_x;
    let group_entries = SWEEP_SLOTS * build_range.group;
    var light = 0u;
    var slot0 = 0u;
    var slot1 = 0u;
    var scratch_slot = w;
    if (build_range.per_entry != 0u) {
        if (w >= build_range.count) {
            return;
        }
        // Entry e of its group: slot e / size, light e % size.
        let e = build_range.first + w;
        let group_first = e / group_entries * build_range.group;
        let size = min(build_range.group, g.light_count - group_first);
        let in_group = e - group_first * SWEEP_SLOTS;
        light = group_first + in_group % size;
        slot0 = in_group / size;
        slot1 = slot0 + 1u;
    } else {
        let light0 = build_range.first / group_entries * build_range.group;
        light = light0 + w;
        scratch_slot = w;
        if (light >= g.light_count) {
            return;
        }
        // The light's slots inside [first, end): its entries are base + slot * size.
        let group_first = light / build_range.group * build_range.group;
        let size = min(build_range.group, g.light_count - group_first);
        let base = group_first * SWEEP_SLOTS + (light - group_first);
        if (build_range.first > base) {
            slot0 = (build_range.first - base + size - 1u) / size;
        }
        if (end > base) {
            slot1 = min((end - base + size - 1u) / size, SWEEP_SLOTS);
        }
    }
    if (slot0 >= slot1) {
        return;
    }
    let l = grid_lights[light];
    let n = g.dims.x * g.dims.y * g.dims.z;
    let forward = g.forward != 0u;
    let area = max(max(g.dims.x * g.dims.y, g.dims.x * g.dims.z), g.dims.y * g.dims.z);
    let scratch = 4u * area * scratch_slot;
    for (var slot = slot0; slot < slot1; slot++) {
        let d = slot_direction(l, slot, forward);
        if (d.weight == 0.0) {
            continue;
        }
        let ax = sweep_axes(g, d.omega);
        let na = g.dims[ax.a];
        let nb = g.dims[ax.b];
        let nc = g.dims[ax.c];
        // Index strides along a, b, c (no dynamic vector indexing in the loop: lavapipe spills it to
        // memory per invocation).
        let strides = vec3<u32>(1u, g.dims.x, g.dims.x * g.dims.y);
        let sa = strides[ax.a];
        let sb = strides[ax.b];
        let sc = strides[ax.c];
        // Whether the path carries the forward-scattering terms (the depth behind reads tau alone).
        let carried = forward && !d.behind;
        let lat = sweep_lattice(ax);
        // An invocation walks a run of column ib along c: point ic reads the previous slice's rows
        // ic + slice_offset.y (lo) and the next (hi), each row read once for the run. The columns
        // are cut into as many runs as the workgroup has invocations for, as long as a run keeps
        // RUN_MIN points (a column's last run may be shorter), so that a GPU keeps more of its lanes
        // busy; the run's first point reads two rows.
        let runs = max(min(SWEEP_GROUP / nb, nc / RUN_MIN), 1u);
        let run = (nc + runs - 1u) / runs;
        let fu = lat.slice_frac.x;
        let fv = lat.slice_frac.y;
        for (var i = 0u; i < na; i++) {
            let k = select(i, na - 1u - i, ax.towards_high);
            let cur = scratch + 2u * area * (i & 1u);
            let prev = scratch + 2u * area * ((i + 1u) & 1u);
            let plane = midplane(g, ax, k);
            for (var t = lid; t < nb * runs; t += SWEEP_GROUP) {
                let ib = t % nb;
                let ic0 = (t / nb) * run;
                let ic1 = min(ic0 + run, nc);
                let u0 = i32(ib) + lat.slice_offset.x;
                var lo = path_zero();
                var hi = path_zero();
                if (i > 0u) {
                    lo = slice_row(prev, nb, nc, u0, fu, i32(ic0) + lat.slice_offset.y, carried);
                    hi = slice_row(prev, nb, nc, u0, fu, i32(ic0) + lat.slice_offset.y + 1, carried);
                }
                for (var ic = ic0; ic < ic1; ic++) {
                    var up = path_zero();
                    if (i > 0u) {
                        up = path_add_scaled(path_add_scaled(path_zero(), lo, 1.0 - fv), hi, fv);
                        if (ic + 1u < ic1) {
                            lo = hi;
                            hi = slice_row(prev, nb, nc, u0, fu, i32(ic) + lat.slice_offset.y + 2, carried);
                        }
                    }
                    let p = k * sa + ib * sb + ic * sc;
                    let f = sweep_integrand(midplane_sample(plane, lat, ib, ic), d.omega, carried, d.behind);
                    scratch_store(cur, ic * nb + ib, path_add_scaled(up, f, ax.step), carried);
                    accumulate(light * n + p, d, path_add_scaled(up, f, max(ax.step - g.skip, 0.0)), forward, slot == 0u);
                }
            }
            storageBarrier();
        }
    }
    if (slot1 == SWEEP_SLOTS) {
        for (var p = lid; p < n; p += SWEEP_GROUP) {
            finish(light * n + p, g);
        }
    }
}
