// Shading pass (Xu 2011 Sec. 5): hair points are shaded under one batch of up to 16 SRBF lights with the fast per-SRBF response (R, TT, TRT), each light
// scaled by its transmittance (swept through the fiber-density pyramid at the points of the shadow
// grid, read trilinearly), and accumulated per lobe weighted by the fragments' composite weights
// (kbuffer.wgsl): per visible segment (`claim_segments` .. `gather_segments` below: the default, for
// the frame and its preview) or per fragment (`shade`). Twin of
// src/render/reference/shade.rs (shade_point).
// With multiple scattering on, every light also adds Zinke's dual scattering in Xu's per-SRBF form
// (global M^G and local M^L, from the light's T_f, sigma_f^2 and the optical depth behind the point on
// the grid) to MS.global and MS.local.
// Prepended: circular_gaussian, lut, fast_azimuthal, azimuthal_table, fast_response,
// dual_response, shadow_grid, camera.

const FLAG_MULTIPLE_SCATTERING: u32 = 2u;
// By segment: multiple scattering alone, the segments' single scattering kept (shading.rs).
const FLAG_SINGLE_KEPT: u32 = 8u;


@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> params: FastHairParams;
@group(0) @binding(2) var<storage, read> batch: ShadeBatch;
@group(0) @binding(3) var<uniform> shadow_grid: ShadowGridInfo;
@group(0) @binding(4) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> segments: array<u32>;
@group(0) @binding(6) var<storage, read> absorption: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(8) var<storage, read> lut_c: array<u32>;
@group(0) @binding(11) var<storage, read> shadow_values: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> dual_tables: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read_write> aov_r: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read_write> aov_tt: array<vec4<f32>>;
@group(0) @binding(15) var<storage, read_write> aov_trt: array<vec4<f32>>;
@group(0) @binding(16) var<storage, read_write> aov_ms_global: array<vec4<f32>>;
@group(0) @binding(17) var<storage, read_write> aov_ms_local: array<vec4<f32>>;
@group(0) @binding(18) var<storage, read> fragments: array<vec2<u32>>;
@group(0) @binding(19) var<storage, read> azimuthal_table: array<vec2<u32>>;
// Segment shading (see `claim_segments`).
@group(0) @binding(20) var<storage, read_write> segment_batches: array<atomic<u32>>;
@group(0) @binding(21) var<storage, read_write> work_count: array<atomic<u32>>;
@group(0) @binding(22) var<storage, read_write> work_list: array<u32>;
@group(0) @binding(23) var<storage, read_write> work_args: array<u32>;
@group(0) @binding(24) var<storage, read_write> segment_r: array<vec4<f32>>;
@group(0) @binding(25) var<storage, read_write> segment_tt: array<vec4<f32>>;
@group(0) @binding(26) var<storage, read_write> segment_trt: array<vec4<f32>>;
@group(0) @binding(27) var<storage, read_write> segment_ms_global: array<vec4<f32>>;
@group(0) @binding(28) var<storage, read_write> segment_ms_local: array<vec4<f32>>;
// Multiple scattering's samples (see `ms_key`): per key 1 + the first light of the last batch that
// claimed it, and the keys listed by the claim or by `list_repaint_keys` (work_count[1] of them);
// per segment its key, found by the frame's (or a repaint's) first light batch and read by the
// others and the gather (the pairing reads the absorption, which a brush dab may change while a
// frame refines: each segment keeps the key whose sample was written).
@group(0) @binding(30) var<storage, read_write> ms_batches: array<atomic<u32>>;
@group(0) @binding(31) var<storage, read_write> ms_list: array<u32>;
@group(0) @binding(32) var<storage, read_write> ms_keys: array<u32>;
// A repaint's candidates for multiple scattering (work_count[2] of them, written by the caller):
// its segments and the partners of the pairs its dabs joined or split.
@group(0) @binding(33) var<storage, read> ms_candidates: array<u32>;

struct ShadingPoint {
    position: vec3<f32>,
    tangent: vec3<f32>,
    sigma_a: vec3<f32>,
}

// The point of segment `seg` seen along the ray, its tangent and its absorption (linear along the segment).
fn shading_point(seg: u32, ray: Ray) -> ShadingPoint {
    let i0 = segments[seg];
    let a = points[i0].xyz;
    let b = points[i0 + 1u].xyz;
    let t = closest_on_segment(ray.origin, ray.dir, a, b);
    let s = mix(absorption[i0].xyz, absorption[i0 + 1u].xyz, t);
    return ShadingPoint(mix(a, b, t), b - a, s);
}

struct LobeRadiance {
    r: vec3<f32>,
    tt: vec3<f32>,
    trt: vec3<f32>,
    ms_global: vec3<f32>,
    ms_local: vec3<f32>,
}

// Radiance towards omega_o from lights [first, first + count) at one shading point, per component:
// with `single` R, TT and TRT, with `multiple` MS.global and MS.local.
fn shade_point(sp: ShadingPoint, omega_o: vec3<f32>, first: u32, count: u32, shadows: bool, single: bool, multiple: bool) -> LobeRadiance {
    var p = params;
    p.sigma_a = vec4<f32>(sp.sigma_a, 0.0);
    let frame = fiber_frame(sp.tangent);
    let o = fiber_angles(frame, omega_o);
    let lobes = view_lobes(p, o.x);
    // The dual tables' absorption cells of the point's channels (the local term's).
    let cells = dual_cells(sp.sigma_a);
    var out = LobeRadiance(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    for (var j = first; j < first + count; j++) {
        let l = lights[j];
        let ang = fiber_angles(frame, l.direction);
        var sh = GridShadow(1.0, vec3<f32>(1.0), vec3<f32>(0.0), DEPTH_UNBOUNDED);
        if (shadows) {
            sh = grid_shadow(shadow_grid, sp.position, j);
        }
        let light = SrbfInFrame(ang.x, ang.y, l.lambda);
        let k = sh.transmittance * l.rgb;
        // Each lobe's response is called from one place (its lobe a constant: lavapipe runs every
        // branch of a lobe chosen at run time), the local term from one loop below.
        if (single) {
            out.r = out.r + k * srbf_response_lobe_in_view(p, 0u, lobes[0], light, o.y);
            out.tt = out.tt + k * srbf_response_lobe_in_view(p, 1u, lobes[1], light, o.y);
            out.trt = out.trt + k * srbf_response_lobe_in_view(p, 2u, lobes[2], light, o.y);
        }
        if (multiple) {
            // One spread for the three channels: their mean sigma_f^2.
            let s2 = (sh.sigma_f2.x + sh.sigma_f2.y + sh.sigma_f2.z) / 3.0;
            // Only what Zinke's combination does not multiply by zero: the forward-scattered part where
            // T_f exceeds the direct fraction, the direct part where light arrives directly; the local
            // term once when the spread is zero (both are then the same).
            var global = vec3<f32>(0.0);
            var local = vec3<f32>(0.0);
            var local_direct = vec3<f32>(0.0);
            let lit = sh.transmittance > 0.0;
            let scattered = any(sh.transmittance_f > vec3<f32>(sh.transmittance));
            if (scattered) {
                global = global_response_lobe_in_view(p, 0u, lobes[0], light, o.y, s2) + global_response_lobe_in_view(p, 1u, lobes[1], light, o.y, s2) + global_response_lobe_in_view(p, 2u, lobes[2], light, o.y, s2);
            }
            // Part 0 the direct light's local term (no spread), part 1 the scattered light's.
            let spread_apart = scattered && !(s2 == 0.0 && lit);
            for (var part = select(1u, 0u, lit); part < select(1u, 2u, spread_apart); part++) {
                let v = local_response(p, cells, light, o.x, o.y, select(0.0, s2, part == 1u), sh.depth_behind);
                if (part == 0u) {
                    local_direct = v;
                } else {
                    local = v;
                }
            }
            if (scattered && !spread_apart) {
                local = local_direct;
            }
            let ms = dual_scattering_components(p, sh.transmittance, sh.transmittance_f, local_direct, global, local);
            let power = srbf_integral(l.lambda) * l.rgb;
            out.ms_global = out.ms_global + power * ms.ms_global;
            out.ms_local = out.ms_local + power * ms.ms_local;
        }
    }
    return out;
}

@compute @workgroup_size(8, 8)
fn shade(@builtin(global_invocation_id) id: vec3<u32>) {
    let y = batch.row0 + id.y;
    if (id.x >= camera.size.x || id.y >= batch.rows || y >= camera.size.y) {
        return;
    }
    let xy = vec2<u32>(id.x, y);
    let pixel = y * camera.size.x + id.x;
    // This dispatch shades K-buffer slot `batch.slot` of every pixel with its weight. (One shading
    // call per invocation: looping over a pixel's fragments inside one invocation gave wrong sums on
    // lavapipe.)
    let f = fragments[pixel * batch.slots + batch.slot];
    let w = bitcast<f32>(f.y);
    if (f.x == 0u || w <= 0.0) {
        return;
    }
    let v = f.x;
    let ray = pixel_ray(camera, f32(xy.x) + 0.5, f32(xy.y) + 0.5);
    let sp = shading_point(v - 1u, ray);
    let l = shade_point(sp, -ray.dir, batch.first, batch.count, (batch.flags & FLAG_SHADOWS) != 0u, true, (batch.flags & FLAG_MULTIPLE_SCATTERING) != 0u);
    // .w of R: the weight shaded so far, each batch adding its share of the lights (the resolve
    // scales a partly shaded image by the pixel's hair alpha over it while refinement runs).
    let share = f32(batch.count) / f32(max(batch.lights, 1u));
    aov_r[pixel] = aov_r[pixel] + vec4<f32>(w * l.r, w * share);
    aov_tt[pixel] = aov_tt[pixel] + vec4<f32>(w * l.tt, 0.0);
    aov_trt[pixel] = aov_trt[pixel] + vec4<f32>(w * l.trt, 0.0);
    aov_ms_global[pixel] = aov_ms_global[pixel] + vec4<f32>(w * l.ms_global, 0.0);
    aov_ms_local[pixel] = aov_ms_local[pixel] + vec4<f32>(w * l.ms_local, 0.0);
}

// Segment shading (twin: src/render/reference/shade.rs, `shade_pixels_by_segment`). A segment's
// shading point moves along it from pixel to pixel, but its tangent, the lights and (nearly) the view
// direction do not: each visible segment is shaded once per light batch. Its single scattering
// response to each light is evaluated once, at its midpoint, and weighted by the light's
// transmittance at its ends and its midpoint (`shade_segment_single`); its multiple scattering, which
// varies slowly (spread over sigma_f and read from the coarse shadow grid), once per pair of
// consecutive segments at the point they share (`ms_key`). Every fragment takes the single scattering
// between the three samples at its own point (`between_samples`) and its pair's multiple scattering.
// A full-resolution pixel keeps ~10 fragments of segments that
// cover ~8 pixels each (S1): ~8x fewer responses than one per fragment.

// The point of segment `seg` at t (0: its first point, 1: its second; absorption linear along it).
fn segment_point(seg: u32, t: f32) -> ShadingPoint {
    let i0 = segments[seg];
    let a = points[i0].xyz;
    let b = points[i0 + 1u].xyz;
    return ShadingPoint(mix(a, b, t), b - a, mix(absorption[i0].xyz, absorption[i0 + 1u].xyz, t));
}

// Single scattering of a segment at t = 0, 1/2, 1 (`[0]`, `[1]`, `[2]`) towards omega_o from lights
// [first, first + count): each light's response (R, TT, TRT) at the midpoint `mid` (its tangent and
// view), scaled by the light's transmittance at each sample (`a`, `b`: the segment's ends, their
// positions and absorption). Where the light's transmittance falls steeply along the segment, into
// the hair's shadow, the three samples follow it; the response itself changes by the few degrees the
// segment subtends. One response per light where the two ends' absorption is the same (unpainted
// hair, a uniform dye); where it differs (a painted edge, a gradient) one at each end's absorption, the
// midpoint's between them (log-linear: the absorption attenuates exponentially), so paint keeps its
// gradient along the segment.
struct SegmentSingle {
    r: array<vec3<f32>, SINGLE_SAMPLES>,
    tt: array<vec3<f32>, SINGLE_SAMPLES>,
    trt: array<vec3<f32>, SINGLE_SAMPLES>,
}

const SINGLE_SAMPLES: u32 = 3u;

fn shade_segment_single(mid: ShadingPoint, a: ShadingPoint, b: ShadingPoint, omega_o: vec3<f32>, first: u32, count: u32, shadows: bool) -> SegmentSingle {
    var pa = params;
    pa.sigma_a = vec4<f32>(a.sigma_a, 0.0);
    var pb = params;
    pb.sigma_a = vec4<f32>(b.sigma_a, 0.0);
    let painted = any(a.sigma_a != b.sigma_a);
    let frame = fiber_frame(mid.tangent);
    let o = fiber_angles(frame, omega_o);
    let lobes = view_lobes(params, o.x);
    let zero = vec3<f32>(0.0);
    var r0 = zero; var r1 = zero; var r2 = zero;
    var tt0 = zero; var tt1 = zero; var tt2 = zero;
    var trt0 = zero; var trt1 = zero; var trt2 = zero;
    for (var j = first; j < first + count; j++) {
        let l = lights[j];
        let ang = fiber_angles(frame, l.direction);
        var t = vec3<f32>(1.0);
        if (shadows) {
            t = vec3<f32>(grid_transmittance(shadow_grid, a.position, j), grid_transmittance(shadow_grid, mid.position, j), grid_transmittance(shadow_grid, b.position, j));
        }
        let light = SrbfInFrame(ang.x, ang.y, l.lambda);
        var ra = zero; var tta = zero; var trta = zero;
        var rb = zero; var ttb = zero; var trtb = zero;
        // End a's responses, then end b's when its absorption differs: one call site per lobe.
        for (var e = 0u; e < select(1u, 2u, painted); e++) {
            var pe = pa;
            if (e == 1u) {
                pe = pb;
            }
            let r = l.rgb * srbf_response_lobe_in_view(pe, 0u, lobes[0], light, o.y);
            let tt = l.rgb * srbf_response_lobe_in_view(pe, 1u, lobes[1], light, o.y);
            let trt = l.rgb * srbf_response_lobe_in_view(pe, 2u, lobes[2], light, o.y);
            if (e == 0u) {
                ra = r;
                tta = tt;
                trta = trt;
            } else {
                rb = r;
                ttb = tt;
                trtb = trt;
            }
        }
        // The midpoint's response: end a's unless the ends' absorption differs (no logarithms and
        // exponentials for the unpainted hair's equal ends).
        var rm = ra; var ttm = tta; var trtm = trta;
        if (painted) {
            rm = between_ends(ra, rb, 0.5);
            ttm = between_ends(tta, ttb, 0.5);
            trtm = between_ends(trta, trtb, 0.5);
        } else {
            rb = ra;
            ttb = tta;
            trtb = trta;
        }
        r0 = r0 + t.x * ra; r1 = r1 + t.y * rm; r2 = r2 + t.z * rb;
        tt0 = tt0 + t.x * tta; tt1 = tt1 + t.y * ttm; tt2 = tt2 + t.z * ttb;
        trt0 = trt0 + t.x * trta; trt1 = trt1 + t.y * trtm; trt2 = trt2 + t.z * trtb;
    }
    return SegmentSingle(array(r0, r1, r2), array(tt0, tt1, tt2), array(trt0, trt1, trt2));
}

// Multiple scattering varies slowly along a strand (spread over sigma_f, read from the coarse shadow
// grid): it is evaluated once per pair of consecutive segments of a strand, segments 2k and 2k + 1
// when segment 2k + 1 continues segment 2k and the pair's three points have the same absorption
// (unpainted hair, a uniform dye), at the point they share, and read by both (twin: shade.rs,
// `ms_key`). A segment without such a partner (a strand's first or last segment where the pairs,
// counted over the whole hair, straddle its ends; paint that varies along the pair) keeps its own
// sample at its midpoint. The key of a pair is its even segment.
fn ms_paired(even: u32) -> bool {
    if (even + 1u >= arrayLength(&segments) || segments[even + 1u] != segments[even] + 1u) {
        return false;
    }
    let i0 = segments[even];
    let s = absorption[i0 + 1u].xyz;
    return all(absorption[i0].xyz == s) && all(absorption[i0 + 2u].xyz == s);
}

fn ms_key(seg: u32) -> u32 {
    let even = seg & ~1u;
    return select(seg, even, ms_paired(even));
}

// The point multiple scattering is evaluated at for key `key` (twin: shade.rs, `ms_point`): a pair's
// shared point, its tangent the pair's chord (the first segment's where the pair folds back onto
// its first point), or an unpaired segment's midpoint.
fn ms_point(key: u32) -> ShadingPoint {
    if ((key & 1u) == 1u || !ms_paired(key)) {
        return segment_point(key, 0.5);
    }
    let i0 = segments[key];
    let a = points[i0].xyz;
    let m = points[i0 + 1u].xyz;
    let chord = points[i0 + 2u].xyz - a;
    return ShadingPoint(m, select(m - a, chord, dot(chord, chord) > 0.0), absorption[i0 + 1u].xyz);
}

// The key of a claimed (or repainted) segment: found by the frame's (or the repaint's) first light
// batch, kept for the others.
fn claimed_key(seg: u32) -> u32 {
    if (batch.first == 0u) {
        let key = ms_key(seg);
        ms_keys[seg] = key;
        return key;
    }
    return ms_keys[seg];
}

// Lists the segments of the batch's rows' kept fragments that this light batch has not shaded: a
// segment's `segment_batches` entry holds 1 + the first light of the last batch that claimed it (0:
// none; light batches run in order, so one claim per segment and batch wins). With multiple
// scattering, likewise their multiple scattering's keys (`ms_key`) in `ms_list`.
@compute @workgroup_size(8, 8)
fn claim_segments(@builtin(global_invocation_id) id: vec3<u32>) {
    let y = batch.row0 + id.y;
    if (id.x >= camera.size.x || id.y >= batch.rows || y >= camera.size.y) {
        return;
    }
    let pixel = y * camera.size.x + id.x;
    for (var s = 0u; s < batch.slots; s++) {
        let f = fragments[pixel * batch.slots + s];
        if (f.x == 0u) {
            break;
        }
        if (bitcast<f32>(f.y) > 0.0) {
            let seg = f.x - 1u;
            if (atomicMax(&segment_batches[seg], batch.first + 1u) <= batch.first) {
                work_list[atomicAdd(&work_count[0], 1u)] = seg;
                if ((batch.flags & FLAG_MULTIPLE_SCATTERING) != 0u) {
                    let key = claimed_key(seg);
                    if (atomicMax(&ms_batches[key], batch.first + 1u) <= batch.first) {
                        ms_list[atomicAdd(&work_count[1], 1u)] = key;
                    }
                }
            }
        }
    }
}

// A repaint's multiple-scattering list: of its candidates (its segments, and whole pairs where its
// dabs joined or split them), the keys (`claimed_key`: found on the first light batch, kept for the
// others), one invocation each, in workgroups of 64 as rows of 65535.
@compute @workgroup_size(64)
fn list_repaint_keys(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * 65535u * 64u;
    if (i >= atomicLoad(&work_count[2])) {
        return;
    }
    let seg = ms_candidates[i];
    if (claimed_key(seg) == seg) {
        ms_list[atomicAdd(&work_count[1], 1u)] = seg;
    }
}

// Where a frame's segment shading lies, for progressive refinement's bands (twin:
// src/render/refine/row_segments.rs, `row_segments`): per image row, the segments whose topmost kept
// fragment lies in it, which are exactly the segments a band of rows claims when the bands run from
// the top. `mark_first_rows` leaves height - that row in each visible segment's `segment_batches`
// entry (cleared before and after: the claims' own use of it), `count_first_rows` adds them up.
@group(0) @binding(29) var<storage, read_write> row_segments: array<atomic<u32>>;

@compute @workgroup_size(8, 8)
fn mark_first_rows(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= camera.size.x || id.y >= camera.size.y) {
        return;
    }
    let pixel = id.y * camera.size.x + id.x;
    for (var s = 0u; s < batch.slots; s++) {
        let f = fragments[pixel * batch.slots + s];
        if (f.x == 0u) {
            break;
        }
        // The fragments claim_segments claims.
        if (bitcast<f32>(f.y) > 0.0) {
            atomicMax(&segment_batches[f.x - 1u], camera.size.y - id.y);
        }
    }
}

// One invocation per segment, in rows of 65535 workgroups of 64.
@compute @workgroup_size(64)
fn count_first_rows(@builtin(global_invocation_id) id: vec3<u32>) {
    let seg = id.x + id.y * 65535u * 64u;
    if (seg >= arrayLength(&segment_batches)) {
        return;
    }
    let v = atomicLoad(&segment_batches[seg]);
    if (v > 0u && v <= camera.size.y) {
        atomicAdd(&row_segments[camera.size.y - v], 1u);
    }
}

// The workgroups of `shade_segments`' two kinds: (single scattering, multiple scattering), each kind's
// invocations rounded up to workgroups of 64 on its own.
fn segment_groups() -> vec2<u32> {
    let single = select((atomicLoad(&work_count[0]) + 63u) / 64u, 0u, (batch.flags & FLAG_SINGLE_KEPT) != 0u);
    let multiple = select(0u, (atomicLoad(&work_count[1]) + 63u) / 64u, (batch.flags & FLAG_MULTIPLE_SCATTERING) != 0u);
    return vec2<u32>(single, multiple);
}

// The indirect dispatch of `shade_segments`: one invocation per listed segment (its single scattering)
// (none with FLAG_SINGLE_KEPT) and with multiple scattering one per listed key (its sample's), in
// workgroups of 64 (the kinds' workgroups alternate while both last), as rows of at most 65535
// workgroups.
@compute @workgroup_size(1)
fn segment_dispatch() {
    let g = segment_groups();
    let groups = g.x + g.y;
    work_args[0] = min(groups, 65535u);
    work_args[1] = (groups + 65534u) / 65535u;
    work_args[2] = 1u;
}

// Invocations of the single-scattering kind each shade listed segment j (`shade_segment_single`),
// those of the multiple-scattering kind listed key j at its sample (`ms_point`). A workgroup runs one
// kind, so a SIMD group runs one of them (single and multiple scattering in one light loop spill on
// lavapipe and cost ~3x as much as apart). The first light batch (first == 0, every segment's first:
// the batches run in order) stores the radiance, the others add to it, so nothing needs clearing.
// With FLAG_SINGLE_KEPT every workgroup is of the multiple-scattering kind, and the segments' single
// scattering stays.
@compute @workgroup_size(64)
fn shade_segments(@builtin(global_invocation_id) id: vec3<u32>) {
    // Rows of the indirect dispatch are 65535 workgroups wide whenever there is more than one.
    let g = id.x + id.y * 65535u * 64u;
    let shadows = (batch.flags & FLAG_SHADOWS) != 0u;
    let restart = batch.first == 0u;
    // The workgroups alternate between the kinds while both have some left (even: single, odd:
    // multiple), the rest are the longer kind's, so that every contiguous share of the dispatch holds
    // both (lavapipe gives each of its threads one contiguous share of a dispatch's workgroups: with
    // the kinds in halves, one thread had all of the single scattering and the other all of the
    // multiple, and the slower kind set the time).
    let groups = segment_groups();
    let w = g / 64u;
    let both = min(groups.x, groups.y);
    var multiple = groups.x == 0u;
    var group = w;
    if (w < 2u * both) {
        multiple = (w & 1u) == 1u;
        group = w >> 1u;
    } else if (both > 0u) {
        multiple = groups.y > groups.x;
        group = w - both;
    }
    let j = group * 64u + g % 64u;
    if (!multiple) {
        if (j >= atomicLoad(&work_count[0])) {
            return;
        }
        let seg = work_list[j];
        let mid = segment_point(seg, 0.5);
        let l = shade_segment_single(mid, segment_point(seg, 0.0), segment_point(seg, 1.0), normalize(camera.eye - mid.position), batch.first, batch.count, shadows);
        for (var s = 0u; s < SINGLE_SAMPLES; s++) {
            let k = SINGLE_SAMPLES * seg + s;
            segment_r[k] = select(segment_r[k], vec4<f32>(0.0), restart) + vec4<f32>(l.r[s], 0.0);
            segment_tt[k] = select(segment_tt[k], vec4<f32>(0.0), restart) + vec4<f32>(l.tt[s], 0.0);
            segment_trt[k] = select(segment_trt[k], vec4<f32>(0.0), restart) + vec4<f32>(l.trt[s], 0.0);
        }
    } else if ((batch.flags & FLAG_MULTIPLE_SCATTERING) != 0u && j < atomicLoad(&work_count[1])) {
        let key = ms_list[j];
        let sp = ms_point(key);
        let l = shade_point(sp, normalize(camera.eye - sp.position), batch.first, batch.count, shadows, false, true);
        segment_ms_global[key] = select(segment_ms_global[key], vec4<f32>(0.0), restart) + vec4<f32>(l.ms_global, 0.0);
        segment_ms_local[key] = select(segment_ms_local[key], vec4<f32>(0.0), restart) + vec4<f32>(l.ms_local, 0.0);
    }
}

// Single scattering at t between two samples (twin: shade.rs, `between_ends`): log-linear where
// both are positive (a light's transmittance falls off exponentially into the hair: linear between a
// lit end and a shadowed one overstates the shadowed part by orders of magnitude), linear where either
// is zero.
fn between_ends(a: vec3<f32>, b: vec3<f32>, t: f32) -> vec3<f32> {
    let both = (a > vec3<f32>(0.0)) & (b > vec3<f32>(0.0));
    let tiny = vec3<f32>(1e-30);
    let geometric = exp(mix(log(max(a, tiny)), log(max(b, tiny)), t));
    return select(mix(a, b, t), geometric, both);
}

// Single scattering at t along a segment from its samples a, m, b at t = 0, 1/2, 1, piecewise
// by `between_ends` (twin: shade.rs, `between_samples`). The midpoint matters: a sum of lights each
// exponential along the segment is log-convex, so one log-linear piece over the segment overstates
// it (+11 % TT on the back-lit clump of tests/ms_reference.rs).
fn between_samples(a: vec3<f32>, m: vec3<f32>, b: vec3<f32>, t: f32) -> vec3<f32> {
    if (t < 0.5) {
        return between_ends(a, m, 2.0 * t);
    }
    return between_ends(m, b, 2.0 * t - 1.0);
}

// The batch's rows' components: every kept fragment's weight times its segment's radiance at the
// fragment's point (single scattering between the samples, multiple scattering its key's, `ms_keys`);
// .w of R the weight shaded (the hair's alpha).
@compute @workgroup_size(8, 8)
fn gather_segments(@builtin(global_invocation_id) id: vec3<u32>) {
    let y = batch.row0 + id.y;
    if (id.x >= camera.size.x || id.y >= batch.rows || y >= camera.size.y) {
        return;
    }
    let pixel = y * camera.size.x + id.x;
    let ray = pixel_ray(camera, f32(id.x) + 0.5, f32(y) + 0.5);
    var out = LobeRadiance(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var weight = 0.0;
    for (var s = 0u; s < batch.slots; s++) {
        let f = fragments[pixel * batch.slots + s];
        if (f.x == 0u) {
            break;
        }
        let w = bitcast<f32>(f.y);
        if (w > 0.0) {
            let seg = f.x - 1u;
            let i0 = segments[seg];
            let t = closest_on_segment(ray.origin, ray.dir, points[i0].xyz, points[i0 + 1u].xyz);
            let k = SINGLE_SAMPLES * seg;
            out.r = out.r + w * between_samples(segment_r[k].xyz, segment_r[k + 1u].xyz, segment_r[k + 2u].xyz, t);
            out.tt = out.tt + w * between_samples(segment_tt[k].xyz, segment_tt[k + 1u].xyz, segment_tt[k + 2u].xyz, t);
            out.trt = out.trt + w * between_samples(segment_trt[k].xyz, segment_trt[k + 1u].xyz, segment_trt[k + 2u].xyz, t);
            if ((batch.flags & FLAG_MULTIPLE_SCATTERING) != 0u) {
                let key = ms_keys[seg];
                out.ms_global = out.ms_global + w * segment_ms_global[key].xyz;
                out.ms_local = out.ms_local + w * segment_ms_local[key].xyz;
            }
            weight = weight + w;
        }
    }
    aov_r[pixel] = vec4<f32>(out.r, weight);
    aov_tt[pixel] = vec4<f32>(out.tt, 0.0);
    aov_trt[pixel] = vec4<f32>(out.trt, 0.0);
    aov_ms_global[pixel] = vec4<f32>(out.ms_global, 0.0);
    aov_ms_local[pixel] = vec4<f32>(out.ms_local, 0.0);
}
