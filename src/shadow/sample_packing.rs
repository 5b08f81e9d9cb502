//! The sweeps' samples as the GPU stores them (`grid_samples` in `shaders/shadow_grid_build.wgsl`,
//! three `vec2<u32>` a sample, 24 B where three f32 vec4 would take 48): the sweeps read four of
//! them at every point of every sweep, and their bytes are the largest part of the grid's reads.
//!
//! | word | holds | as |
//! |---|---|---|
//! | 0 | the extinction a (negative: outside the volume) | f32 |
//! | 1 | n_xx, n_yy | unorm16 |
//! | 2 | n_zz, the solid share | unorm16 |
//! | 3 | n_xy, n_xz | snorm16 |
//! | 4 | sigma_a r, g | f16 |
//! | 5 | sigma_a b (low half), n_yz (high half) | f16, snorm16 |
//!
//! n = M / a is the orientation tensor per unit extinction (trace 1: diagonal in [0, 1], off-diagonal
//! in [-1/2, 1/2]), so the crossings' 1 - omega^T n omega keeps 2^-16 (diagonal) or 2^-15
//! (off-diagonal) absolute where M itself in f16 would have kept 2^-11 of a: a fiber nearly along the
//! light crosses few paths, and that small difference is what the sweep integrates. The absorption in
//! f16 is within 2^-11 relative. The CPU twin ([`crate::shadow::sweep::MidplaneSamples`]) holds the
//! samples as [`GridSample::quantised`] gives them: the values the GPU unpacks.

use super::sweep::GridSample;
use half::f16;

/// WGSL's pack2x16unorm of one component: floor(0.5 + 65535 clamp(x, 0, 1)).
fn unorm16(x: f32) -> u32 {
    (0.5 + 65535.0 * x.clamp(0.0, 1.0)).floor() as u32
}

/// WGSL's pack2x16snorm of one component: floor(0.5 + 32767 clamp(x, -1, 1)) as 16 bits.
fn snorm16(x: f32) -> u32 {
    ((0.5 + 32767.0 * x.clamp(-1.0, 1.0)).floor() as i32 as i16) as u16 as u32
}

fn from_unorm16(bits: u32) -> f32 {
    (bits & 0xffff) as f32 / 65535.0
}

fn from_snorm16(bits: u32) -> f32 {
    ((bits & 0xffff) as u16 as i16 as f32 / 32767.0).max(-1.0)
}

/// f16 bits of x, clamped to f16's largest finite value (65504; WGSL leaves larger ones undefined).
fn f16_bits(x: f32) -> u32 {
    f16::from_f32(x.min(f16::MAX.to_f32())).to_bits() as u32
}

fn from_f16(bits: u32) -> f32 {
    f16::from_bits((bits & 0xffff) as u16).to_f32()
}

/// Two 16-bit halves in one word (low, high), as WGSL's pack2x16* lay them out.
fn word(low: u32, high: u32) -> u32 {
    low | (high << 16)
}

impl GridSample {
    /// The six words of `grid_samples` for this sample (`build_midplane_samples` in the WGSL).
    pub fn pack(&self) -> [u32; 6] {
        let inv = if self.a > 0.0 { 1.0 / self.a } else { 0.0 };
        let n = self.m.map(|m| m * inv);
        [
            self.a.to_bits(),
            word(unorm16(n[0]), unorm16(n[1])),
            word(unorm16(n[2]), unorm16(self.solid)),
            word(snorm16(n[3]), snorm16(n[4])),
            word(f16_bits(self.sigma_a[0]), f16_bits(self.sigma_a[1])),
            word(f16_bits(self.sigma_a[2]), snorm16(n[5])),
        ]
    }

    /// A point outside the volume (`None` of [`crate::shadow::sweep::MidplaneSamples`]).
    pub const OUTSIDE: [u32; 6] = [0xbf80_0000, 0, 0, 0, 0, 0];

    /// The sample the words hold, or None outside the volume (`midplane_sample` in the WGSL).
    pub fn unpack(w: [u32; 6]) -> Option<Self> {
        let a = f32::from_bits(w[0]);
        if a < 0.0 {
            return None;
        }
        let n = [
            from_unorm16(w[1]),
            from_unorm16(w[1] >> 16),
            from_unorm16(w[2]),
            from_snorm16(w[3]),
            from_snorm16(w[3] >> 16),
            from_snorm16(w[5] >> 16),
        ];
        Some(Self {
            a,
            m: n.map(|n| a * n),
            sigma_a: [from_f16(w[4]), from_f16(w[4] >> 16), from_f16(w[5])],
            solid: from_unorm16(w[2] >> 16),
        })
    }

    /// The sample as the GPU reads it back.
    pub fn quantised(&self) -> Self {
        Self::unpack(self.pack()).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packing_keeps_the_crossings_and_the_absorption() {
        // A fiber bundle along u (tensor a u u^T) mixed with an isotropic part, at several
        // extinctions; the crossings sqrt(a^2 - a omega^T M omega) along directions near u.
        let mut worst_crossings = 0f32;
        let mut worst_sigma = 0f32;
        for (k, a) in [0.01f32, 1.0, 37.5, 900.0].into_iter().enumerate() {
            let u = glam::Vec3::new(0.3, 0.8 - 0.1 * k as f32, 0.52).normalize();
            let iso = 0.05;
            let t =
                |i: usize, j: usize| (1.0 - iso) * u[i] * u[j] + iso / 3.0 * (i == j) as u8 as f32;
            let m = [t(0, 0), t(1, 1), t(2, 2), t(0, 1), t(0, 2), t(1, 2)].map(|x| a * x);
            let s = GridSample {
                a,
                m,
                sigma_a: [0.31, 1.7, 4.2 + k as f32],
                solid: 0.25 * k as f32,
            };
            let q = s.quantised();
            assert_eq!(q.a, s.a);
            assert!((q.solid - s.solid).abs() < 1e-4);
            for c in 0..3 {
                worst_sigma = worst_sigma.max((q.sigma_a[c] / s.sigma_a[c] - 1.0).abs());
            }
            for angle in [0.0f32, 0.02, 0.1, 0.5, 1.5] {
                let w = (u + angle * glam::Vec3::new(-u.y, u.x, 0.0).normalize()).normalize();
                let cross = |m: &[f32; 6]| {
                    let q = m[0] * w.x * w.x
                        + m[1] * w.y * w.y
                        + m[2] * w.z * w.z
                        + 2.0 * (m[3] * w.x * w.y + m[4] * w.x * w.z + m[5] * w.y * w.z);
                    (a * a - a * q).max(0.0).sqrt()
                };
                worst_crossings = worst_crossings.max((cross(&q.m) - cross(&s.m)).abs() / a);
            }
        }
        println!(
            "packed samples: worst crossings error {worst_crossings:.2e} of a, absorption {worst_sigma:.2e} relative"
        );
        // (A bundle exactly along omega, no isotropic part, would be off by the square root of the
        // tensor's 2^-16 steps, 4e-3 of a, where the crossings are 0.)
        assert!(worst_crossings < 5e-4, "{worst_crossings}");
        assert!(worst_sigma < 4.9e-4, "{worst_sigma}");
        assert_eq!(GridSample::unpack(GridSample::OUTSIDE), None);
    }
}
