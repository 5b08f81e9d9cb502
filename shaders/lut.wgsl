// Xu 2011's tables as the fast model reads them. Twin of src/scattering/lut.rs: texels in storage
// buffers (texels[(y * width + x) * channels + c]), bilinear between samples, clamped, so CPU and
// GPU agree to rounding. Bindings are declared by the module that includes this file:
//   lut_c (C_0..C_6, 128 x 64 x 7). (The H_k tables feed only the CPU's circular-Gaussian fits.)

const LUT_W: u32 = 128u;
const LUT_H: u32 = 64u;
const LAMBDA_MIN: f32 = 0.001;
const LAMBDA_MAX: f32 = 10.0;

struct LutCoord {
    i00: u32,
    i10: u32,
    i01: u32,
    i11: u32,
    wx: f32,
    wy: f32,
}

fn lut_coord(tx: f32, ty: f32, channels: u32) -> LutCoord {
    let fx = clamp(tx, 0.0, 1.0) * f32(LUT_W - 1u);
    let fy = clamp(ty, 0.0, 1.0) * f32(LUT_H - 1u);
    let x0 = min(u32(fx), LUT_W - 2u);
    let y0 = min(u32(fy), LUT_H - 2u);
    var c: LutCoord;
    c.i00 = (y0 * LUT_W + x0) * channels;
    c.i10 = (y0 * LUT_W + x0 + 1u) * channels;
    c.i01 = ((y0 + 1u) * LUT_W + x0) * channels;
    c.i11 = ((y0 + 1u) * LUT_W + x0 + 1u) * channels;
    c.wx = fx - f32(x0);
    c.wy = fy - f32(y0);
    return c;
}

fn bilinear(v00: f32, v10: f32, v01: f32, v11: f32, wx: f32, wy: f32) -> f32 {
    let a = v00 + wx * (v10 - v00);
    let b = v01 + wx * (v11 - v01);
    return a + wy * (b - a);
}

// C_0..C_6 at (lambda', dphi) (Xu Eq. 14); dphi folded into [0, pi].
fn lut_sample_c(lambda_prime: f32, dphi: f32) -> array<f32, 7> {
    let l = clamp(lambda_prime, LAMBDA_MIN, LAMBDA_MAX);
    let tx = log(l / LAMBDA_MIN) / log(10.0) / 4.0;
    let d = abs(wrap_angle(dphi));
    let c = lut_coord(tx, d / PI, 7u);
    var out: array<f32, 7>;
    for (var k = 0u; k < 7u; k++) {
        out[k] = bilinear(lut_c[c.i00 + k], lut_c[c.i10 + k], lut_c[c.i01 + k], lut_c[c.i11 + k], c.wx, c.wy);
    }
    return out;
}
