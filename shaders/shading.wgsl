// Shading pass (Xu 2011 Sec. 5): for every pixel, the hair fragments of its K-buffer are shaded
// under one batch of up to 16 SRBF lights with the fast per-SRBF response (R, TT, TRT), each light
// scaled by its transmittance (swept through the fiber-density pyramid at the points of the shadow
// grid, read trilinearly), and accumulated per lobe weighted by the fragments' composite weights
// (kbuffer.wgsl). Twin of src/render/shade.rs (shade_point).
// With multiple scattering on, every light also adds Zinke's dual scattering in Xu's per-SRBF form
// (global M^G and local M^L, from the light's T_f, sigma_f^2 and the optical depth behind the point on
// the grid) to MS.global and MS.local.
// Prepended: circular_gaussian, lut, fast_azimuthal, azimuthal_table, fast_response,
// dual_response, shadow_grid, camera.

const FLAG_MULTIPLE_SCATTERING: u32 = 2u;


@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> params: FastHairParams;
@group(0) @binding(2) var<uniform> batch: ShadeBatch;
@group(0) @binding(3) var<uniform> shadow_grid: ShadowGridInfo;
@group(0) @binding(4) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> segments: array<u32>;
@group(0) @binding(6) var<storage, read> absorption: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(8) var<storage, read> lut_c: array<f32>;
@group(0) @binding(9) var<storage, read> lut_h_tt: array<f32>;
@group(0) @binding(10) var<storage, read> lut_h_trt: array<f32>;
@group(0) @binding(11) var<storage, read> shadow_values: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> dual_tables: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read_write> aov_r: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read_write> aov_tt: array<vec4<f32>>;
@group(0) @binding(15) var<storage, read_write> aov_trt: array<vec4<f32>>;
@group(0) @binding(16) var<storage, read_write> aov_ms_global: array<vec4<f32>>;
@group(0) @binding(17) var<storage, read_write> aov_ms_local: array<vec4<f32>>;
@group(0) @binding(18) var<storage, read> fragments: array<vec2<u32>>;
@group(0) @binding(19) var<storage, read> azimuthal_table: array<vec4<f32>>;

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

// Radiance towards omega_o from lights [first, first + count) at one shading point, per component.
fn shade_point(sp: ShadingPoint, omega_o: vec3<f32>, first: u32, count: u32, shadows: bool, multiple: bool) -> LobeRadiance {
    var p = params;
    p.sigma_a = vec4<f32>(sp.sigma_a, 0.0);
    let frame = fiber_frame(sp.tangent);
    let o = fiber_angles(frame, omega_o);
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
        out.r = out.r + k * srbf_response_lobe(p, 0u, light, o.x, o.y);
        out.tt = out.tt + k * srbf_response_lobe(p, 1u, light, o.x, o.y);
        out.trt = out.trt + k * srbf_response_lobe(p, 2u, light, o.x, o.y);
        if (multiple) {
            // One spread for the three channels: their mean sigma_f^2.
            let s2 = (sh.sigma_f2.x + sh.sigma_f2.y + sh.sigma_f2.z) / 3.0;
            // Only what Zinke's combination does not multiply by zero: the forward-scattered part where
            // T_f exceeds the direct fraction, the direct part where light arrives directly; the local
            // term once when the spread is zero (both are then the same).
            var global = vec3<f32>(0.0);
            var local = vec3<f32>(0.0);
            var local_direct = vec3<f32>(0.0);
            if (sh.transmittance > 0.0) {
                local_direct = local_response(p, light, o.x, o.y, 0.0, sh.depth_behind);
            }
            if (any(sh.transmittance_f > vec3<f32>(sh.transmittance))) {
                global = global_response_lobe(p, 0u, light, o.x, o.y, s2) + global_response_lobe(p, 1u, light, o.x, o.y, s2) + global_response_lobe(p, 2u, light, o.x, o.y, s2);
                if (s2 == 0.0 && sh.transmittance > 0.0) {
                    local = local_direct;
                } else {
                    local = local_response(p, light, o.x, o.y, s2, sh.depth_behind);
                }
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
    let l = shade_point(sp, -ray.dir, batch.first, batch.count, (batch.flags & FLAG_SHADOWS) != 0u, (batch.flags & FLAG_MULTIPLE_SCATTERING) != 0u);
    // .w of R: the weight shaded so far, each batch adding its share of the lights (the resolve
    // scales a partly shaded image by the pixel's hair alpha over it while refinement runs).
    let share = f32(batch.count) / f32(max(batch.lights, 1u));
    aov_r[pixel] = aov_r[pixel] + vec4<f32>(w * l.r, w * share);
    aov_tt[pixel] = aov_tt[pixel] + vec4<f32>(w * l.tt, 0.0);
    aov_trt[pixel] = aov_trt[pixel] + vec4<f32>(w * l.trt, 0.0);
    aov_ms_global[pixel] = aov_ms_global[pixel] + vec4<f32>(w * l.ms_global, 0.0);
    aov_ms_local[pixel] = aov_ms_local[pixel] + vec4<f32>(w * l.ms_local, 0.0);
}
