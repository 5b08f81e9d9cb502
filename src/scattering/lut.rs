//! The Xu 2011 tables as the fast model reads them: f32 texels, bilinear filtering between sample
//! points, clamped at the ends, exactly as the WGSL twin `lut_sample_*` does with `textureLoad`
//! (no hardware filtering, so CPU and GPU agree to rounding).
//!
//! Coordinates follow [`super::tables`]: a value at axis position t in [0, 1] lies between
//! samples floor(t (N - 1)) and the next one.

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

    /// Bilinear sample at axis positions (tx, ty) in [0, 1] (clamped), into `out` (one value per channel).
    pub fn sample(&self, tx: f32, ty: f32, out: &mut [f32]) {
        let fx = tx.clamp(0.0, 1.0) * (self.width - 1) as f32;
        let fy = ty.clamp(0.0, 1.0) * (self.height - 1) as f32;
        let (x0, y0) = (
            (fx as usize).min(self.width - 2),
            (fy as usize).min(self.height - 2),
        );
        let (wx, wy) = (fx - x0 as f32, fy - y0 as f32);
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
        Ok(Self {
            c: find("C_k")?,
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
    let l = lambda_prime.clamp(LAMBDA_MIN, LAMBDA_MAX);
    let tx = (l / LAMBDA_MIN).log10() / 4.0;
    let d = wrap_angle_f32(dphi).abs();
    let mut out = [0.0; 7];
    luts.c.sample(tx, d / std::f32::consts::PI, &mut out);
    out
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
