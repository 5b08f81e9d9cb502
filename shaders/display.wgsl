// Display pass: the resolved beauty (linear, premultiplied by coverage) through the viewport's view
// transform into an 8-bit sRGB-encoded image (egui samples it as Rgba8Unorm), over the environment (the
// image's background target, composited in linear light before the transform) or a flat colour.
// A smaller image (the preview) is sampled bilinearly, premultiplied; while the preview shows, the rows
// of the full image its first pass has finished are drawn over it. The EXR never passes here.
// CPU twin: render/display.rs (`displayed_pixel`: `source_sample`, `display_pixel`).

struct DisplayInfo {
    width: u32,
    height: u32,
    // 0: standard (clamp), 1: filmic (Narkowicz's ACES fit).
    transform: u32,
    // 0: the beauty; 1: one component (the `component` binding: R, TT, TRT, MS.global or MS.local) alone.
    solo: u32,
    // 2^EV of the viewport exposure (on top of the render's).
    exposure_scale: f32,
    // 2^EV of the render's exposure (the beauty has it; the components do not).
    render_scale: f32,
    // Size of the full image.
    source: vec2<u32>,
    // Flat background, display-encoded.
    background: vec3<f32>,
    // 1: the beauty over the background target (the environment), in linear light.
    environment: u32,
    // Size of the preview, and the rows of the full image drawn over it (all of them: no preview).
    preview_source: vec2<u32>,
    sharp_rows: u32,
}

@group(0) @binding(0) var<uniform> info: DisplayInfo;
@group(0) @binding(1) var<storage, read> beauty: array<vec4<f32>>;
@group(0) @binding(2) var image: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(3) var<storage, read> component: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> preview_beauty: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> preview_component: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> background: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> preview_background: array<vec4<f32>>;

fn aces_filmic(x: f32) -> f32 {
    let y = max(x, 0.0) * 0.6;
    return clamp((y * (2.51 * y + 0.03)) / (y * (2.43 * y + 0.59) + 0.14), 0.0, 1.0);
}

fn srgb_encode(x: f32) -> f32 {
    if x <= 0.0031308 {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

fn view_transform(x: f32, transform: u32) -> f32 {
    if transform == 1u {
        return srgb_encode(aces_filmic(x));
    }
    return srgb_encode(clamp(x, 0.0, 1.0));
}

// `beauty_px`: the beauty (its alpha is the coverage); `solo_px`: the solo component; `bg_px`: the
// environment behind the pixel.
fn display_pixel(beauty_px: vec4<f32>, solo_px: vec4<f32>, bg_px: vec4<f32>) -> vec4<f32> {
    if info.environment == 1u && info.solo == 0u {
        let lin = info.exposure_scale * (beauty_px.xyz + clamp(1.0 - beauty_px.w, 0.0, 1.0) * bg_px.xyz);
        return vec4<f32>(
            view_transform(lin.x, info.transform),
            view_transform(lin.y, info.transform),
            view_transform(lin.z, info.transform),
            1.0,
        );
    }
    var p = beauty_px;
    if info.solo == 1u {
        p = vec4<f32>(info.render_scale * solo_px.xyz, beauty_px.w);
    }
    let a = clamp(p.w, 0.0, 1.0);
    var un = 0.0;
    if p.w > 0.0 {
        un = info.exposure_scale / p.w;
    }
    let c = vec3<f32>(
        view_transform(p.x * un, info.transform),
        view_transform(p.y * un, info.transform),
        view_transform(p.z * un, info.transform),
    );
    return vec4<f32>(mix(info.background, c, a), 1.0);
}

struct SourceTaps {
    i00: u32,
    i10: u32,
    i01: u32,
    i11: u32,
    f: vec2<f32>,
}

// The source pixels (of a `size` image) under display pixel `id` and their bilinear weights (pixel
// centres aligned).
fn source_taps(id: vec2<u32>, size: vec2<u32>) -> SourceTaps {
    let s = max(size, vec2<u32>(1u));
    let p = max((vec2<f32>(id) + 0.5) * vec2<f32>(s) / vec2<f32>(f32(info.width), f32(info.height)) - 0.5, vec2<f32>(0.0));
    let c0 = min(vec2<u32>(floor(p)), s - 1u);
    let c1 = min(c0 + 1u, s - 1u);
    return SourceTaps(c0.y * s.x + c0.x, c0.y * s.x + c1.x, c1.y * s.x + c0.x, c1.y * s.x + c1.x, p - floor(p));
}

fn bilinear(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>, d: vec4<f32>, f: vec2<f32>) -> vec4<f32> {
    return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
}

@compute @workgroup_size(8, 8)
fn display(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= info.width || id.y >= info.height {
        return;
    }
    // The full image's row under this display row.
    let row = (id.y * info.source.y) / info.height;
    if row >= info.sharp_rows {
        let t = source_taps(id.xy, info.preview_source);
        let b = bilinear(preview_beauty[t.i00], preview_beauty[t.i10], preview_beauty[t.i01], preview_beauty[t.i11], t.f);
        let c = bilinear(preview_component[t.i00], preview_component[t.i10], preview_component[t.i01], preview_component[t.i11], t.f);
        let g = bilinear(preview_background[t.i00], preview_background[t.i10], preview_background[t.i01], preview_background[t.i11], t.f);
        textureStore(image, vec2<i32>(id.xy), display_pixel(b, c, g));
        return;
    }
    if all(info.source == vec2<u32>(info.width, info.height)) {
        let i = id.y * info.width + id.x;
        textureStore(image, vec2<i32>(id.xy), display_pixel(beauty[i], component[i], background[i]));
        return;
    }
    let t = source_taps(id.xy, info.source);
    let b = bilinear(beauty[t.i00], beauty[t.i10], beauty[t.i01], beauty[t.i11], t.f);
    let c = bilinear(component[t.i00], component[t.i10], component[t.i01], component[t.i11], t.f);
    let g = bilinear(background[t.i00], background[t.i10], background[t.i01], background[t.i11], t.f);
    textureStore(image, vec2<i32>(id.xy), display_pixel(b, c, g));
}