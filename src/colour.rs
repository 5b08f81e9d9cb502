//! Colour transfer functions every layer shares: the sRGB curve both ways and the filmic tone curve
//! the display and the PNG previews apply.

/// Narkowicz 2015's fit of the ACES filmic curve (linear in, display-linear [0, 1] out).
pub fn aces_filmic(x: f32) -> f32 {
    let x = x.max(0.0) * 0.6;
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// sRGB-encoded value to linear (the inverse of [`srgb_encode`]).
pub fn srgb_decode(v: f64) -> f64 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}
