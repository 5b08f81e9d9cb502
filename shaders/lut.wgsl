// Xu 2011's tables as the fast model reads them. Twin of src/scattering/lut.rs: texels in storage
// buffers (texels[(y * width + x) * channels + c]), bilinear between samples, clamped, so CPU and
// GPU agree to rounding. Bindings are declared by the module that includes this file:
//   lut_c (u32 words): C_0..C_6 (128 x 64 x 7, f32 bits), then from R_BASE the R table (RTable:
//   128 x 64 x R_TABLE_X half pairs (calC_1, calD), scaled by HALF_SCALE). (The H_k tables feed only
//   the CPU's circular-Gaussian fits.) HALF_SCALE comes from azimuthal_table.wgsl, which every
//   includer of this file prepends too (fast_model_library).

const LUT_W: u32 = 128u;
const LUT_H: u32 = 64u;
const R_TABLE_X: u32 = 64u;
const R_BASE: u32 = LUT_W * LUT_H * 7u;
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
        out[k] = bilinear(bitcast<f32>(lut_c[c.i00 + k]), bitcast<f32>(lut_c[c.i10 + k]), bitcast<f32>(lut_c[c.i01 + k]), bitcast<f32>(lut_c[c.i11 + k]), c.wx, c.wy);
    }
    return out;
}

// One slice of the R table (x sample z): bilinear in (lambda', dphi) at C_k's texels.
fn lut_r_slice(c: LutCoord, z: u32) -> vec2<f32> {
    let base = R_BASE + z * LUT_W * LUT_H;
    let v00 = unpack2x16float(lut_c[base + c.i00]);
    let v10 = unpack2x16float(lut_c[base + c.i10]);
    let v01 = unpack2x16float(lut_c[base + c.i01]);
    let v11 = unpack2x16float(lut_c[base + c.i11]);
    let a = v00 + c.wx * (v10 - v00);
    let b = v01 + c.wx * (v11 - v01);
    return a + c.wy * (b - a);
}

// (calC_1, calD) of the R table at (lambda', dphi, theta_d): bilinear at the two samples of
// x = -cos(theta_d) around it, then linear in x.
fn lut_sample_r(lambda_prime: f32, dphi: f32, cos_theta_d: f32) -> vec2<f32> {
    let l = clamp(lambda_prime, LAMBDA_MIN, LAMBDA_MAX);
    let tx = log(l / LAMBDA_MIN) / log(10.0) / 4.0;
    let c = lut_coord(tx, abs(wrap_angle(dphi)) / PI, 1u);
    let fz = clamp(1.0 - abs(cos_theta_d), 0.0, 1.0) * f32(R_TABLE_X - 1u);
    let z0 = min(u32(fz), R_TABLE_X - 2u);
    let wz = fz - f32(z0);
    let lo = lut_r_slice(c, z0);
    let hi = lut_r_slice(c, z0 + 1u);
    return (lo + wz * (hi - lo)) / HALF_SCALE;
}
