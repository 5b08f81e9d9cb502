// The camera (twin of src/render/camera.rs) and the fiber frame (twin of src/scattering/frame.rs and
// src/render/reference/shade.rs): rays through pixels, the closest point of a segment to a ray.

struct Camera {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    pixel_angle: f32,
    forward: vec3<f32>,
    min_width_px: f32,
    size: vec2<u32>,
    near: f32,
    far: f32,
    // Ribbons drawn this many times as wide (a thinned preview); 1 otherwise.
    width_scale: f32,
    _p0: f32,
    _p1: f32,
    _p2: f32,
}

// A visibility sample's value: -(triangle + 1) for the occluder, 0 for nothing (twin of
// render/passes/occluder.rs: occluder_triangle; the hair is in the K-buffer).
fn visible_occluder(v: f32) -> u32 {
    return select(0u, u32(-v + 0.5), v < -0.5);
}

// The occluder's samples in the resolved sample ids: triangle + 1 with the top bit set.
const OCCLUDER_ID_BIT: u32 = 0x80000000u;

// Distance along the view axis of a [0, 1] depth (directx-style right-handed projection).
fn linear_depth(c: Camera, d: f32) -> f32 {
    return c.near * c.far / (c.far - d * (c.far - c.near));
}

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

// The ray through pixel coordinates (x, y), y down, 0.5 = a pixel centre.
fn pixel_ray(c: Camera, x: f32, y: f32) -> Ray {
    let ndc = vec2<f32>(2.0 * x / f32(c.size.x) - 1.0, 1.0 - 2.0 * y / f32(c.size.y));
    let far = c.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    return Ray(c.eye, normalize(far.xyz / far.w - c.eye));
}

// t in [0, 1] of the point of segment a..b closest to the ray (o, d).
fn closest_on_segment(o: vec3<f32>, d: vec3<f32>, a: vec3<f32>, b: vec3<f32>) -> f32 {
    let e = b - a;
    let w = a - o;
    let ee = dot(e, e);
    let ed = dot(e, d);
    let den = ee - ed * ed;
    if (den <= 1e-12 * max(ee, 1e-30)) {
        return 0.5;
    }
    return clamp((ed * dot(w, d) - dot(w, e)) / den, 0.0, 1.0);
}

// FiberFrame::from_tangent: u the tangent, v from a helper axis, w = u x v.
struct FiberFrame {
    u: vec3<f32>,
    v: vec3<f32>,
    w: vec3<f32>,
}

fn fiber_frame(tangent: vec3<f32>) -> FiberFrame {
    let u = normalize(tangent);
    let helper = select(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(1.0, 0.0, 0.0), abs(u.x) < 0.9);
    let v = normalize(helper - u * dot(helper, u));
    return FiberFrame(u, v, cross(u, v));
}

// (theta, phi) of a unit world direction in the frame.
fn fiber_angles(f: FiberFrame, omega: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(asin_precise(clamp(dot(omega, f.u), -1.0, 1.0)), atan2(dot(omega, f.w), dot(omega, f.v)));
}
