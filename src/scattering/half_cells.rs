//! Table cells in half precision, as the GPU holds them: the shading pass's lookups load half the
//! words (on lavapipe a load costs per word), and the CPU's tables hold the same rounded values, so
//! a WGSL lookup and its Rust twin read the same numbers. Values are scaled by [`HALF_SCALE`] (a
//! power of two: exact either way) so that those from 6e-8 (the smallest normal half float) to 64
//! keep 11 significant bits; larger ones saturate, smaller ones are 0. WGSL: `HALF_SCALE` in
//! `shaders/azimuthal_table.wgsl`, and `unpack2x16float` reads a pair. Users: the azimuthal table's
//! cells and the R table (`lut.rs`, `RTable`).
//!
//! Only for tables whose values enter a lookup without cancellation. The azimuthal table's cells
//! do (a rule's weights times positive exponentials). The C_k table does not: N_R sums C_k's
//! against Fresnel's binomial terms of alternating sign, and in half floats the fast form's R
//! against brute force would err by median 0.19 % / p95 4.5 % instead of 0.11 % / 2.9 %
//! (tests/fast_model.rs), so it stays in f32.

/// The cells' scale in half precision.
pub const HALF_SCALE: f32 = 1024.0;

/// The largest value a scaled half float holds.
pub const HALF_MAX: f32 = 65504.0 / HALF_SCALE;

/// The smallest normal half float: scaled values below it are stored as 0, so that no GPU's
/// handling of subnormal halves (some flush them) can tell it from the CPU's twin (values under
/// 6e-8 before the scale: at most that much absolute).
const HALF_MIN_NORMAL: f32 = 6.103_515_6e-5;

/// The half-precision bits of v (scaled by [`HALF_SCALE`], saturated at the largest half float,
/// flushed to zero below the smallest normal one).
pub fn half_bits(v: f32) -> u16 {
    half::f16::from_f32(scaled_for_half(v)).to_bits()
}

/// v scaled by [`HALF_SCALE`], 0 below the smallest normal half float, clamped to the largest.
fn scaled_for_half(v: f32) -> f32 {
    let s = v * HALF_SCALE;
    if s.abs() < HALF_MIN_NORMAL {
        0.0
    } else {
        s.clamp(-65504.0, 65504.0)
    }
}

/// [`half_bits`] of every value, and the values replaced by what the bits hold: the same bits as
/// value by value, converted eight at a time where the CPU can (F16C), for the tables' builds
/// (a round azimuthal table's 3.6 million values took 35 ms value by value on one core).
pub fn round_to_half_bits(values: &mut [f32]) -> Vec<u16> {
    use half::slice::HalfFloatSliceExt;
    for v in values.iter_mut() {
        *v = scaled_for_half(*v);
    }
    let mut halves = vec![half::f16::ZERO; values.len()];
    halves.convert_from_f32_slice(values);
    halves.convert_to_f32_slice(values);
    for v in values.iter_mut() {
        *v /= HALF_SCALE;
    }
    halves.reinterpret_cast().to_vec()
}

/// The value of [`half_bits`].
pub fn from_half_bits(b: u16) -> f32 {
    half::f16::from_bits(b).to_f32() / HALF_SCALE
}

/// v rounded to the nearest value a half-precision cell holds.
pub fn half_precision(v: f32) -> f32 {
    from_half_bits(half_bits(v))
}

/// Two half floats in one word, `lo` in the low half (WGSL's unpack2x16float: `.x`).
pub fn half_pair(lo: u16, hi: u16) -> u32 {
    lo as u32 | ((hi as u32) << 16)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_cells_round_once_and_keep_small_values() {
        for v in [0.0f32, 1.0, 0.1, 1e-3, 3e-7, 6e-8, 2.07, -0.5, 63.9] {
            let h = half_precision(v);
            assert_eq!(half_precision(h), h, "{v}");
            assert!((h - v).abs() <= v.abs() * 4.9e-4, "{v} -> {h}");
        }
        assert_eq!(half_precision(1e6), HALF_MAX);
        assert_eq!(half_precision(5e-8), 0.0);
        assert!(half_precision(6e-8) > 0.0);
        assert_eq!(half_pair(1, 2), 0x0002_0001);
        let values: Vec<f32> = (0..1000)
            .map(|i| (i as f32 * 0.731).sin() * 10f32.powi(i % 12 - 9))
            .chain([0.0, -0.0, 1e6, -1e6, 5e-8, 6e-8, 2.07])
            .collect();
        let mut rounded = values.clone();
        let bits = round_to_half_bits(&mut rounded);
        for ((v, r), b) in values.iter().zip(&rounded).zip(&bits) {
            assert_eq!(*b, half_bits(*v), "{v}");
            assert_eq!(r.to_bits(), half_precision(*v).to_bits(), "{v}");
        }
    }
}
