//! Dye colours to absorption, and the per-point absorption a render starts from.
//!
//! Colour to sigma_a: Chiang et al. 2016, "A Practical and Controllable Hair and Fur Model for
//! Production Path Tracing", Eq. (9): for a desired multiple-scattering albedo c (linear RGB, per
//! channel) and azimuthal roughness beta_N,
//!   sigma_a = (ln c / (5.969 - 0.215 beta_N + 2.532 beta_N^2 - 10.73 beta_N^3 + 5.574 beta_N^4 + 0.245 beta_N^5))^2.
//! Their sigma_a is per unit fiber radius along the chord 2 cos(gamma_t), strandlight's convention.
//! Marschner's model has no azimuthal roughness; beta_N is a parameter of the inversion only
//! (default 0.3, Chiang's default).

use crate::hair::Hair;
use rand_core::{Rng, SeedableRng};

/// Chiang 2016's default azimuthal roughness for the inversion.
pub const DEFAULT_BETA_N: f64 = 0.3;

/// Chiang 2016 Eq. (9), per channel; colours are clamped to [1e-4, 1 - 1e-6] (white has no finite
/// inverse and black no finite absorption).
pub fn sigma_a_from_colour(colour: [f64; 3], beta_n: f64) -> [f64; 3] {
    let b = beta_n;
    let d = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3)
        + 5.574 * b.powi(4)
        + 0.245 * b.powi(5);
    colour.map(|c| (c.clamp(1e-4, 1.0 - 1e-6).ln() / d).powi(2))
}

/// How the per-point absorption is made.
#[derive(Clone, Debug, PartialEq)]
pub struct AbsorptionSpec {
    /// Absorption at the root and at the tip (equal: uniform), interpolated linearly in sigma_a
    /// along the normalised arc length.
    pub root: [f32; 3],
    pub tip: [f32; 3],
    /// Per-strand log-normal variation: each strand's sigma_a is scaled by exp(variation z),
    /// z standard normal, seeded.
    pub variation: f32,
    pub seed: u64,
}

impl AbsorptionSpec {
    pub fn uniform(sigma_a: [f32; 3]) -> Self {
        Self {
            root: sigma_a,
            tip: sigma_a,
            variation: 0.0,
            seed: 1,
        }
    }

    /// One RGB absorption per point of `hair`.
    pub fn per_point(&self, hair: &Hair) -> Vec<[f32; 3]> {
        let t = hair.root_to_tip();
        let mut out = Vec::with_capacity(hair.point_count());
        for s in 0..hair.strand_count() {
            let scale = if self.variation > 0.0 {
                let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(
                    self.seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ s as u64,
                );
                let mut u = || ((rng.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
                // Box-Muller.
                let z = (-2.0 * u().ln()).sqrt() * (std::f64::consts::TAU * u()).cos();
                (self.variation as f64 * z).exp() as f32
            } else {
                1.0
            };
            for p in hair.strand_range(s) {
                let w = t[p];
                out.push(std::array::from_fn(|c| {
                    scale * (self.root[c] + w * (self.tip[c] - self.root[c]))
                }));
            }
        }
        out
    }
}

/// Parses a colour: `#rrggbb` (sRGB, decoded to linear) or `r,g,b` (linear, 0..1).
pub fn parse_colour(s: &str) -> Result<[f64; 3], String> {
    let s = s.trim();
    if let Some(hex) = s.strip_prefix('#') {
        if hex.len() != 6 || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
            return Err(format!("'{s}' is not a #rrggbb colour"));
        }
        let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).unwrap_or(0) as f64 / 255.0;
        let decode = crate::colour::srgb_decode;
        return Ok([decode(byte(0)), decode(byte(2)), decode(byte(4))]);
    }
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!("'{s}' is neither #rrggbb nor r,g,b"));
    }
    let mut c = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        let v: f64 = p
            .trim()
            .parse()
            .map_err(|_| format!("'{p}' in '{s}' is not a number"))?;
        if !(0.0..=1.0).contains(&v) {
            return Err(format!("'{s}': linear colour components lie in [0, 1]"));
        }
        c[k] = v;
    }
    Ok(c)
}

/// The colour a sigma_a gives (the inverse of [`sigma_a_from_colour`]: the multiple-scattering
/// albedo c = exp(-sqrt(sigma_a) d(beta_N)), per channel), linear RGB; the painted hair's colour as
/// other tools see it (USD displayColor, cyHair colours).
pub fn colour_from_sigma_a(sigma_a: [f64; 3], beta_n: f64) -> [f64; 3] {
    let b = beta_n;
    let d = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3)
        + 5.574 * b.powi(4)
        + 0.245 * b.powi(5);
    sigma_a.map(|s| (-s.max(0.0).sqrt() * d).exp())
}

#[cfg(test)]
mod colour_tests {
    use super::*;

    #[test]
    fn colour_and_absorption_invert_each_other() {
        for c in [[0.5, 0.03, 0.04], [0.9, 0.8, 0.6], [0.01, 0.02, 0.2]] {
            let back = colour_from_sigma_a(sigma_a_from_colour(c, DEFAULT_BETA_N), DEFAULT_BETA_N);
            for k in 0..3 {
                assert!((back[k] - c[k]).abs() < 1e-9, "{back:?} {c:?}");
            }
        }
    }
}
