//! The Xu 2011 tables as the fast model reads them: f32 texels, bilinear filtering between sample
//! points, clamped at the ends, exactly as the WGSL twin `lut_sample_*` does with `textureLoad`
//! (no hardware filtering, so CPU and GPU agree to rounding).
//!
//! Coordinates follow [`super::tables`]: a value at axis position t in [0, 1] lies between
//! samples floor(t (N - 1)) and the next one.
//!
//! R's window integral is read from [`RTable`], made from C_k when the tables load: the sum over k
//! that Xu Eq. 14 takes per point is taken per cell in f64 along a third axis, theta_d.

use super::half_cells::{half_pair, round_to_half_bits};
use super::tables::{Table2D, build_all};
use super::tables_io::{read_manifest, read_table};
use std::path::Path;

/// Lower end of the lambda' axis of C_k (log10 spacing over 4 decades).
pub const LAMBDA_MIN: f32 = 0.001;
/// Upper end of the lambda' axis.
pub const LAMBDA_MAX: f32 = 10.0;

/// The three tables, each as interleaved f32 texels (`channels` values per texel, row-major, x fastest).
#[derive(Clone, Debug)]
pub struct Luts {
    /// C_k, k = 0..6 (7 channels): x = lambda', y = dphi.
    pub c: LutTexture,
    /// H_0, H_2, H_4 of TT: x = eta, y = theta_d.
    pub h_tt: LutTexture,
    /// H_0, H_2, H_4 of TRT.
    pub h_trt: LutTexture,
    /// calN_R's two parts at (lambda', dphi, theta_d), from `c`.
    pub r: RTable,
}

/// C_k's texels (lambda', dphi) and values per texel: the WGSL's `LUT_W`, `LUT_H` and 7.
pub const C_TEXELS: (usize, usize, usize) = (128, 64, 7);

/// Samples of x = -cos(theta_d) over [-1, 0] in [`RTable`].
pub const R_TABLE_X: usize = 64;

/// R's window integral (Xu Eq. 14) by parts: with Schlick's F = F0 + (1 - F0)(1 + x c)^5,
/// c = |cos(phi/2)| and x = -cos(theta_d), N_R = (1/4) c F, so
///   calN_R = (1/4) (F0 calC_1 + (1 - F0) calD),  calD(lambda', dphi, x) = sum_n binom(5, n) x^n calC_(n+1)
/// (n = 0..5). Each cell holds (calC_1, calD) at a C_k texel and a sample of x, uniform over [-1, 0],
/// in half precision ([`super::half_cells`]): a lookup reads 8 words where C_k's read 24-28 (the GPU's
/// loads cost per word on lavapipe). calD's sum of alternating terms is taken once per cell in
/// f64, and the stored parts are positive: no cancellation is left to the rounding (as it would
/// be with C_k itself in half precision: R against brute force at median 0.19 % / p95 4.5 %
/// instead of 0.11 % / 2.9 %). What it adds to C_k's path: the interpolation in x (calD is a
/// quintic in x) and the rounding (`lut::tests`).
#[derive(Clone, Debug)]
pub struct RTable {
    /// (calC_1, calD) of entry ((ix * height + y) * width + xl): xl along lambda', y along dphi (C_k's
    /// texels), ix along x. Rounded to what the GPU holds.
    pub cells: Vec<[f32; 2]>,
    /// The GPU's entries: each cell's two halves scaled by [`HALF_SCALE`], calC_1 in the low half.
    pub gpu: Vec<u32>,
}

impl RTable {
    pub fn from_c(c: &LutTexture) -> Self {
        const BINOM5: [f64; 6] = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
        let texels = c.width * c.height;
        let mut values = Vec::with_capacity(2 * texels * R_TABLE_X);
        for ix in 0..R_TABLE_X {
            let x = ix as f64 / (R_TABLE_X - 1) as f64 - 1.0;
            for t in 0..texels {
                let ck = &c.texels[t * c.channels..(t + 1) * c.channels];
                let d: f64 = (0..6)
                    .map(|n| BINOM5[n] * x.powi(n as i32) * ck[n + 1] as f64)
                    .sum();
                values.extend([ck[1], d as f32]);
            }
        }
        let bits = round_to_half_bits(&mut values);
        Self {
            cells: values.chunks_exact(2).map(|v| [v[0], v[1]]).collect(),
            gpu: bits
                .chunks_exact(2)
                .map(|b| half_pair(b[0], b[1]))
                .collect(),
        }
    }
}

/// One table as the GPU stores it.
#[derive(Clone, Debug)]
pub struct LutTexture {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    /// texels[(y * width + x) * channels + c]
    pub texels: Vec<f32>,
}

impl LutTexture {
    pub fn from_table(t: &Table2D) -> Self {
        let (width, height, channels) = (t.x_axis.samples, t.y_axis.samples, t.data.len());
        let mut texels = vec![0.0; width * height * channels];
        for (c, d) in t.data.iter().enumerate() {
            for (i, v) in d.iter().enumerate() {
                texels[i * channels + c] = *v;
            }
        }
        Self {
            width,
            height,
            channels,
            texels,
        }
    }

    /// The texel cell at axis positions (tx, ty) in [0, 1] (clamped): its lower corner (x0, y0) and
    /// the weights (wx, wy) of the next texels (WGSL: `lut_coord`).
    pub fn cell(&self, tx: f32, ty: f32) -> (usize, usize, f32, f32) {
        let fx = tx.clamp(0.0, 1.0) * (self.width - 1) as f32;
        let fy = ty.clamp(0.0, 1.0) * (self.height - 1) as f32;
        let (x0, y0) = (
            (fx as usize).min(self.width - 2),
            (fy as usize).min(self.height - 2),
        );
        (x0, y0, fx - x0 as f32, fy - y0 as f32)
    }

    /// Bilinear sample at axis positions (tx, ty) in [0, 1] (clamped), into `out` (one value per channel).
    pub fn sample(&self, tx: f32, ty: f32, out: &mut [f32]) {
        let (x0, y0, wx, wy) = self.cell(tx, ty);
        // The two texels of each row side by side: (x0, x0 + 1) at y0 and at y0 + 1.
        let ch = self.channels;
        let pair = |y: usize| {
            let i = (y * self.width + x0) * ch;
            self.texels[i..i + 2 * ch].split_at(ch)
        };
        let ((a0, a1), (b0, b1)) = (pair(y0), pair(y0 + 1));
        let texels = a0.iter().zip(a1).zip(b0.iter().zip(b1));
        for (o, ((a0, a1), (b0, b1))) in out.iter_mut().zip(texels) {
            let a = a0 + wx * (a1 - a0);
            let b = b0 + wx * (b1 - b0);
            *o = a + wy * (b - a);
        }
    }
}

impl Luts {
    pub fn from_tables(tables: &[Table2D]) -> Result<Self, String> {
        let find = |name: &str| {
            tables
                .iter()
                .find(|t| t.name == name)
                .map(LutTexture::from_table)
                .ok_or_else(|| format!("table {name} missing"))
        };
        let c = find("C_k")?;
        if (c.width, c.height, c.channels) != C_TEXELS {
            return Err(format!(
                "table C_k: {}x{} texels of {} values; the shaders read {}x{}x{} (lut.wgsl)",
                c.width, c.height, c.channels, C_TEXELS.0, C_TEXELS.1, C_TEXELS.2
            ));
        }
        Ok(Self {
            r: RTable::from_c(&c),
            c,
            h_tt: find("H_TT")?,
            h_trt: find("H_TRT")?,
        })
    }

    /// Builds the tables in memory (about 0.1 s on two cores).
    pub fn build() -> Self {
        Self::from_tables(&build_all()).expect("build_all makes every table")
    }

    /// Reads `luts/` (manifest and EXR files); errors name the file.
    pub fn load(dir: &Path) -> Result<Self, String> {
        let manifest = read_manifest(dir)?;
        let tables = manifest
            .tables
            .iter()
            .map(|e| read_table(dir, e))
            .collect::<Result<Vec<_>, _>>()?;
        Self::from_tables(&tables)
    }

    /// The committed tables next to the crate, or built in memory when they are absent.
    pub fn default_tables() -> Self {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("luts");
        Self::load(&dir).unwrap_or_else(|_| Self::build())
    }
}

/// C_0..C_6 at (lambda', dphi) (Xu Eq. 14); dphi is folded into [0, pi] (C_k is even and 2 pi-periodic).
pub fn lut_sample_c(luts: &Luts, lambda_prime: f32, dphi: f32) -> [f32; 7] {
    let (tx, ty) = c_axes(lambda_prime, dphi);
    let mut out = [0.0; 7];
    luts.c.sample(tx, ty, &mut out);
    out
}

/// C_k's axis positions of (lambda', dphi): lambda' clamped and log-spaced, dphi folded into [0, pi].
fn c_axes(lambda_prime: f32, dphi: f32) -> (f32, f32) {
    let l = lambda_prime.clamp(LAMBDA_MIN, LAMBDA_MAX);
    let tx = (l / LAMBDA_MIN).log10() / 4.0;
    (tx, wrap_angle_f32(dphi).abs() / std::f32::consts::PI)
}

/// (calC_1, calD) of [`RTable`] at (lambda', dphi, theta_d): bilinear in (lambda', dphi) as
/// [`lut_sample_c`] at the two samples of x = -cos(theta_d) around it, then linear in x (WGSL twin:
/// `lut_sample_r`).
pub fn lut_sample_r(luts: &Luts, lambda_prime: f32, dphi: f32, cos_theta_d: f32) -> [f32; 2] {
    let c = &luts.c;
    let (tx, ty) = c_axes(lambda_prime, dphi);
    let (x0, y0, wx, wy) = c.cell(tx, ty);
    let fz = (1.0 - cos_theta_d.abs()).clamp(0.0, 1.0) * (R_TABLE_X - 1) as f32;
    let z0 = (fz as usize).min(R_TABLE_X - 2);
    let wz = fz - z0 as f32;
    let cells = &luts.r.cells;
    let slice = |z: usize| -> [f32; 2] {
        let at = |y: usize, x: usize| cells[(z * c.height + y) * c.width + x];
        let (v00, v10, v01, v11) = (
            at(y0, x0),
            at(y0, x0 + 1),
            at(y0 + 1, x0),
            at(y0 + 1, x0 + 1),
        );
        std::array::from_fn(|k| {
            let a = v00[k] + wx * (v10[k] - v00[k]);
            let b = v01[k] + wx * (v11[k] - v01[k]);
            a + wy * (b - a)
        })
    };
    let (lo, hi) = (slice(z0), slice(z0 + 1));
    std::array::from_fn(|k| lo[k] + wz * (hi[k] - lo[k]))
}

/// H_0, H_2, H_4 of TT (`trt` false) or TRT at (eta, theta_d) (Xu Eq. 19, 23); H is even in theta_d.
pub fn lut_sample_h(luts: &Luts, trt: bool, eta: f32, theta_d: f32) -> [f32; 3] {
    let tx = eta.clamp(1.0, 10.0).log10();
    let ty = theta_d.abs() / std::f32::consts::FRAC_PI_2;
    let mut out = [0.0; 3];
    let t = if trt { &luts.h_trt } else { &luts.h_tt };
    t.sample(tx, ty, &mut out);
    out
}

/// Wraps an angle to [-pi, pi].
pub fn wrap_angle_f32(x: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    x - TAU * ((x + PI) / TAU).floor()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scattering::fast_azimuthal::{inner_integral_r, inner_integral_r_ck};

    /// calN_R from the R table against Xu Eq. 14's sum over the seven C_k: what the table's
    /// interpolation in theta_d and its half precision cost, over lambda', dphi, theta_d and eta.
    #[test]
    fn r_table_reads_calnr_as_the_ck_sum() {
        let luts = Luts::default_tables();
        let mut errs = Vec::new();
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..20_000 {
            let lp = 0.005 * 400f32.powf(uniform());
            let dphi = (2.0 * uniform() - 1.0) * std::f32::consts::PI;
            let theta_d = (2.0 * uniform() - 1.0) * 1.5;
            let eta = 1.3 + 0.7 * uniform();
            let reference = inner_integral_r_ck(&luts, eta, theta_d, lp, dphi);
            let got = inner_integral_r(&luts, eta, theta_d, lp, dphi);
            // Relative to the value, with a floor at a thousandth of the window's largest.
            let scale = inner_integral_r_ck(&luts, eta, theta_d, lp, 0.0);
            errs.push((got - reference).abs() / reference.max(1e-3 * scale).max(1e-12));
        }
        errs.sort_by(f32::total_cmp);
        let at = |q: f64| errs[((errs.len() - 1) as f64 * q) as usize];
        let (median, p95, max) = (at(0.5), at(0.95), at(1.0));
        println!("R table against the C_k sum: median {median:.2e}, p95 {p95:.2e}, max {max:.2e}");
        // Measured: median 1.5e-4, p95 6.5e-4, max 1.7e-3 (mostly the half precision).
        assert!(
            median < 5e-4 && p95 < 2e-3 && max < 1e-2,
            "{median} {p95} {max}"
        );
    }
}
