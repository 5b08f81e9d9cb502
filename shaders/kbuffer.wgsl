// The ordered K-buffer (Yu 2012, Secs. 4 and 5): every hair segment is drawn as its ribbon of the
// fiber's true width, grown by EXPAND_PX pixels on every side so that each pixel the ribbon touches
// gets a fragment (Yu's "view space expansion"); each fragment's coverage of its pixel is the exact
// area of the ribbon inside the pixel square (a box filter: a sub-pixel fiber covers part of a pixel),
// times the share of the occluder's (the head's) depth samples behind it. Fragments of zero opacity
// are dropped. The others are inserted into the pixel's K nearest by a chain of 64-bit atomic maxima
// on the inverted key (depth bits << 32 | segment): the K slots end up holding the K nearest
// fragments sorted front to back, whatever the order of insertion (so drawing the segments in
// several parts gives the same K-buffer). Every fragment, kept or not, also adds its optical depth
// -ln(1 - opacity) in fixed point to the pixel's sums (exact integer sums, in any order): all of
// them, and those in front of the occluder's nearest sample.
// The composite pass then weighs the K fragments front to back (weight = transmittance in front x
// opacity) and, with the folded tail, gives the last one the opacity of everything behind it.
// Twin of src/render/passes/kbuffer.rs. Prepended: circular_gaussian (PI), camera.

struct KBufferInfo {
    // Fragments kept per pixel.
    k: u32,
    // TAIL_DROP, TAIL_FOLD or TAIL_SPREAD.
    tail: u32,
    // 1: an occluder was drawn into the depth (else its samples are not read).
    occluder: u32,
    _p1: u32,
}

const TAIL_DROP: u32 = 0u;
const TAIL_FOLD: u32 = 1u;
const TAIL_SPREAD: u32 = 2u;
// Pixels the drawn ribbon is grown by on every side (a pixel the true ribbon touches has its centre
// within sqrt(2) / 2 of it; the margin covers the slant of a tapering ribbon's sides).
const EXPAND_PX: f32 = 0.75;
// Fixed-point units of optical depth in the pixel sums.
const OPTICAL_DEPTH_SCALE: f32 = 16384.0;
// A fragment's opacity is at most this (its optical depth stays finite).
const MAX_FRAGMENT_OPACITY: f32 = 0.999755859375;

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> points: array<vec4<f32>>; // xyz, diameter (cm)
@group(0) @binding(2) var<storage, read> segments: array<u32>;     // first point of each segment
@group(0) @binding(3) var<storage, read> kinfo: KBufferInfo;
@group(0) @binding(4) var occluder_depth: texture_depth_multisampled_2d;

// A point in pixel coordinates (x right, y down, 0.5 = a pixel centre) and its view depth.
fn to_pixels(p: vec3<f32>) -> vec3<f32> {
    let clip = camera.view_proj * vec4<f32>(p, 1.0);
    let ndc = clip.xy / clip.w;
    let size = vec2<f32>(camera.size);
    return vec3<f32>(0.5 * (ndc.x + 1.0) * size.x, 0.5 * (1.0 - ndc.y) * size.y, dot(p - camera.eye, camera.forward));
}

// A segment's ribbon on the image: its ends, the unit direction from p0 to p1 and the unit normal,
// the half-widths at the ends (pixels). Invalid when an end is not in front of the near plane.
struct RibbonQuad {
    p0: vec2<f32>,
    p1: vec2<f32>,
    dir: vec2<f32>,
    normal: vec2<f32>,
    half_width: vec2<f32>,
    valid: bool,
}

// Half the ribbon's width in pixels at view depth `depth` for a fiber of diameter `diameter` (cm):
// the true width, or camera.min_width_px pixels when that is wider.
fn half_width_px(diameter: f32, depth: f32) -> f32 {
    return camera.width_scale * max(0.5 * diameter / (camera.pixel_angle * depth), 0.5 * camera.min_width_px);
}

// The part of the segment a..b in front of the near plane (moved in by a thousandth of it): an end
// behind it slides along the segment to it. Both behind: the segment is not seen.
struct NearClipped {
    a: vec4<f32>,
    b: vec4<f32>,
    valid: bool,
}

fn clip_near(a: vec4<f32>, b: vec4<f32>) -> NearClipped {
    let plane = 1.001 * camera.near;
    let da = dot(a.xyz - camera.eye, camera.forward);
    let db = dot(b.xyz - camera.eye, camera.forward);
    var out = NearClipped(a, b, da > plane || db > plane);
    if (da < plane && db > plane) {
        out.a = mix(a, b, (plane - da) / (db - da));
    } else if (db < plane && da > plane) {
        out.b = mix(b, a, (plane - db) / (da - db));
    }
    return out;
}

fn ribbon_quad(seg: u32) -> RibbonQuad {
    let i0 = segments[seg];
    let clipped = clip_near(points[i0], points[i0 + 1u]);
    let a = clipped.a;
    let b = clipped.b;
    let pa = to_pixels(a.xyz);
    let pb = to_pixels(b.xyz);
    var q: RibbonQuad;
    q.valid = clipped.valid;
    q.p0 = pa.xy;
    q.p1 = pb.xy;
    let d = pb.xy - pa.xy;
    let len = length(d);
    q.dir = select(vec2<f32>(1.0, 0.0), d / len, len > 1e-6);
    q.normal = vec2<f32>(-q.dir.y, q.dir.x);
    q.half_width = vec2<f32>(half_width_px(a.w, max(pa.z, camera.near)), half_width_px(b.w, max(pb.z, camera.near)));
    return q;
}

// The mean over t in [0, 1] of clamp(y0 + t (y1 - y0), 0, 1): the share of the run above 1, plus
// the share inside (0, 1) times its mean (ratios of differences: exact as y1 - y0 goes to zero).
fn clamped_mean(y0: f32, y1: f32) -> f32 {
    let lo = min(y0, y1);
    let hi = max(y0, y1);
    let dy = hi - lo;
    if (dy <= 1e-20) {
        return clamp(lo, 0.0, 1.0);
    }
    let a = max(lo, 0.0);
    let b = min(hi, 1.0);
    let inside = max(b - a, 0.0);
    return clamp((hi - 1.0) / dy, 0.0, 1.0) + inside / dy * 0.5 * (a + b);
}

// Edge a -> b's term of the area inside the unit square by Green's theorem: the integral of
// clamp(y, 0, 1) dx along the edge over x in [0, 1] (the boundary integral of the polygon's part
// inside the square's slab of x, cut at its bottom and top).
fn edge_area(a: vec2<f32>, b: vec2<f32>) -> f32 {
    let dx = b.x - a.x;
    let lo = max(min(a.x, b.x), 0.0);
    let hi = min(max(a.x, b.x), 1.0);
    if (abs(dx) <= 1e-20 || hi <= lo) {
        return 0.0;
    }
    let ylo = a.y + (lo - a.x) / dx * (b.y - a.y);
    let yhi = a.y + (hi - a.x) / dx * (b.y - a.y);
    return sign(dx) * (hi - lo) * clamped_mean(ylo, yhi);
}

// Coverage below this is the edges' terms' rounding (each term is at most 1, good to ~1e-7): a
// ribbon passing by the pixel, which must leave no fragment (twin: kbuffer.rs).
const MIN_COVERAGE: f32 = 1e-6;

// The area of the ribbon inside pixel (x, y) (the square [x, x + 1] x [y, y + 1]), in [0, 1]: the
// quad's four edges' terms (Green's theorem; no clipped polygon, whose arrays lavapipe keeps in
// memory); 0 below MIN_COVERAGE.
fn pixel_coverage(q: RibbonQuad, pixel: vec2<u32>) -> f32 {
    if (!q.valid) {
        return 0.0;
    }
    // Corners relative to the pixel's corner (small numbers: the terms keep their precision).
    let o = vec2<f32>(pixel);
    let v0 = q.p0 - o - q.half_width.x * q.normal;
    let v1 = q.p1 - o - q.half_width.y * q.normal;
    let v2 = q.p1 - o + q.half_width.y * q.normal;
    let v3 = q.p0 - o + q.half_width.x * q.normal;
    let area = abs(edge_area(v0, v1) + edge_area(v1, v2) + edge_area(v2, v3) + edge_area(v3, v0));
    return select(0.0, min(area, 1.0), area >= MIN_COVERAGE);
}

// The view depth of segment `seg`'s point closest to the ray through pixel `pixel`'s centre (the
// shading point's depth).
fn fragment_depth(seg: u32, pixel: vec2<u32>) -> f32 {
    let i0 = segments[seg];
    let a = points[i0].xyz;
    let b = points[i0 + 1u].xyz;
    let ray = pixel_ray(camera, f32(pixel.x) + 0.5, f32(pixel.y) + 0.5);
    let t = closest_on_segment(ray.origin, ray.dir, a, b);
    return dot(mix(a, b, t) - camera.eye, camera.forward);
}

// The share of the pixel's occluder samples that do not hide a fragment at view depth `depth`, and the
// view depth of the nearest occluder sample (1e10 without one).
fn occluder_cover(pixel: vec2<u32>, depth: f32) -> vec2<f32> {
    if (kinfo.occluder == 0u) {
        return vec2<f32>(1.0, 1e10);
    }
    let n = textureNumSamples(occluder_depth);
    var open = 0u;
    var nearest = 1e10;
    for (var s = 0u; s < n; s++) {
        let d = textureLoad(occluder_depth, vec2<i32>(pixel), i32(s));
        if (d < 1.0) {
            let z = linear_depth(camera, d);
            nearest = min(nearest, z);
            if (z >= depth) {
                open = open + 1u;
            }
        } else {
            open = open + 1u;
        }
    }
    return vec2<f32>(f32(open) / f32(n), nearest);
}

// The optical depth -ln(1 - a) of a fragment of opacity a, in fixed point.
fn optical_depth(a: f32) -> u32 {
    return u32(round(-log(1.0 - min(a, MAX_FRAGMENT_OPACITY)) * OPTICAL_DEPTH_SCALE));
}

// The K-buffer: per pixel, k slots of the inverted key (0: empty); per pixel, the sums (optical depth
// of every fragment, of those in front of the occluder, the fragment count, unused).
@group(0) @binding(5) var<storage, read_write> keys: array<atomic<u64>>;
@group(0) @binding(6) var<storage, read_write> sums: array<atomic<u32>>;

// The ribbon travels with its fragments (flat), not recomputed per fragment.
struct FragmentIn {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) segment: u32,
    @location(1) @interpolate(flat) ends: vec4<f32>,
    @location(2) @interpolate(flat) dir_width: vec4<f32>,
}

@vertex
fn vs_fragments(@builtin(vertex_index) vi: u32) -> FragmentIn {
    return ribbon_vertex(vi / 6u, vi % 6u);
}

// A subset of the segments (a thinned preview: every k-th strand's), listed.
@group(0) @binding(11) var<storage, read> subset: array<u32>;

@vertex
fn vs_fragments_subset(@builtin(vertex_index) vi: u32) -> FragmentIn {
    return ribbon_vertex(subset[vi / 6u], vi % 6u);
}

// Corner `corner` (of six) of segment `seg`'s ribbon.
fn ribbon_vertex(seg: u32, corner: u32) -> FragmentIn {
    // Two triangles: (0, -), (1, -), (0, +) and (0, +), (1, -), (1, +).
    let along = corner == 1u || corner == 4u || corner == 5u;
    let side = select(-1.0, 1.0, corner == 2u || corner == 3u || corner == 5u);
    let q = ribbon_quad(seg);
    var out: FragmentIn;
    out.segment = seg;
    out.ends = vec4<f32>(q.p0, q.p1);
    out.dir_width = vec4<f32>(q.dir, q.half_width);
    if (!q.valid) {
        out.position = vec4<f32>(2.0, 2.0, 0.5, 1.0);
        return out;
    }
    let end = select(q.p0 - EXPAND_PX * q.dir, q.p1 + EXPAND_PX * q.dir, along);
    // The wider end's half-width at both ends: a tapering ribbon's slanted sides keep the margin.
    let hw = max(q.half_width.x, q.half_width.y) + EXPAND_PX;
    let p = end + side * hw * q.normal;
    let size = vec2<f32>(camera.size);
    out.position = vec4<f32>(2.0 * p.x / size.x - 1.0, 1.0 - 2.0 * p.y / size.y, 0.5, 1.0);
    return out;
}

@fragment
fn fs_fragments(in: FragmentIn) {
    let pixel = vec2<u32>(in.position.xy);
    if (pixel.x >= camera.size.x || pixel.y >= camera.size.y) {
        return;
    }
    var ribbon: RibbonQuad;
    ribbon.p0 = in.ends.xy;
    ribbon.p1 = in.ends.zw;
    ribbon.dir = in.dir_width.xy;
    ribbon.normal = vec2<f32>(-ribbon.dir.y, ribbon.dir.x);
    ribbon.half_width = in.dir_width.zw;
    ribbon.valid = true;
    let c = pixel_coverage(ribbon, pixel);
    if (c <= 0.0) {
        return;
    }
    let depth = fragment_depth(in.segment, pixel);
    let occ = occluder_cover(pixel, depth);
    let a = c * occ.x;
    if (a <= 0.0) {
        return;
    }
    let p = pixel.y * camera.size.x + pixel.x;
    let q = optical_depth(a);
    atomicAdd(&sums[4u * p], q);
    if (depth < occ.y) {
        atomicAdd(&sums[4u * p + 1u], q);
    }
    atomicAdd(&sums[4u * p + 2u], 1u);
    // Insert: slot i keeps the larger inverted key (the nearer fragment) and the other moves on.
    let base = p * kinfo.k;
    var v = ~((u64(bitcast<u32>(depth)) << 32u) | u64(in.segment));
    if (atomicLoad(&keys[base + kinfo.k - 1u]) >= v) {
        return;
    }
    for (var i = 0u; i < kinfo.k; i++) {
        let old = atomicMax(&keys[base + i], v);
        if (old == 0lu) {
            break;
        }
        v = min(old, v);
    }
}

// The composite: per pixel, the kept fragments (segment + 1, bitcast weight; 0 after the last) and
// (hair alpha, transmittance of the hair in front of the occluder, nearest fragment's view depth,
// fragment count).
@group(0) @binding(7) var<storage, read> key_words: array<vec2<u32>>;
@group(0) @binding(8) var<storage, read> pixel_sums: array<vec4<u32>>;
@group(0) @binding(9) var<storage, read_write> fragments: array<vec2<u32>>;
@group(0) @binding(10) var<storage, read_write> pixel_info: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn composite(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= camera.size.x || id.y >= camera.size.y) {
        return;
    }
    let pixel = id.xy;
    let p = id.y * camera.size.x + id.x;
    let base = p * kinfo.k;
    var t = 1.0;
    // The kept weights' sum, 1 - t (summed: 1 - t loses its digits when the opacities are small).
    var kept_alpha = 0.0;
    var n = 0u;
    var kept = 0u;
    var nearest = 1e10;
    for (var i = 0u; i < kinfo.k; i++) {
        let w = key_words[base + i];
        if (w.x == 0u && w.y == 0u) {
            break;
        }
        let seg = ~w.x;
        let depth = bitcast<f32>(~w.y);
        nearest = min(nearest, depth);
        let a = min(pixel_coverage(ribbon_quad(seg), pixel) * occluder_cover(pixel, depth).x, 1.0);
        kept = kept + optical_depth(a);
        fragments[base + i] = vec2<u32>(seg + 1u, bitcast<u32>(t * a));
        kept_alpha = kept_alpha + t * a;
        t = t * (1.0 - a);
        n = i + 1u;
    }
    for (var i = n; i < kinfo.k; i++) {
        fragments[base + i] = vec2<u32>(0u, 0u);
    }
    let s = pixel_sums[p];
    if (kinfo.tail != TAIL_DROP && n == kinfo.k) {
        // Everything behind the K-th fragment: with that fragment's radiance, or spread over the kept
        // ones in proportion to their weights (with their mean radiance).
        let rest = select(0u, s.x - kept, s.x > kept);
        let behind = exp(-f32(rest) / OPTICAL_DEPTH_SCALE);
        // (Kept fragments of no weight at all: the tail goes to the last one instead.)
        if (kinfo.tail == TAIL_FOLD || kept_alpha <= 0.0) {
            let last = base + n - 1u;
            fragments[last].y = bitcast<u32>(bitcast<f32>(fragments[last].y) + t * (1.0 - behind));
        } else {
            let scale = 1.0 + t * (1.0 - behind) / kept_alpha;
            for (var i = 0u; i < n; i++) {
                fragments[base + i].y = bitcast<u32>(scale * bitcast<f32>(fragments[base + i].y));
            }
        }
        t = t * behind;
    }
    pixel_info[p] = vec4<f32>(1.0 - t, exp(-f32(s.y) / OPTICAL_DEPTH_SCALE), nearest, f32(s.z));
}
