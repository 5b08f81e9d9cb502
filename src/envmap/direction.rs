//! The equirectangular direction convention, defined once. World space is +Y up.
//!
//! Pixel (x, y) of a W x H (W = 2H) latitude-longitude map covers u = (x + 0.5)/W, v = (y + 0.5)/H at
//! its centre. Polar angle from +Y: theta = pi v (row 0 is the zenith). Azimuth phi = 2 pi (u - 0.5).
//! direction = (sin(theta) sin(phi), cos(theta), -sin(theta) cos(phi)):
//! the image centre looks along -Z, the right quarter (u = 0.75) along +X, the left edge along +Z.

use glam::DVec3;
use std::f64::consts::PI;

/// World direction at fractional image coordinates (u, v) in [0, 1].
pub fn direction_from_uv(u: f64, v: f64) -> DVec3 {
    let theta = PI * v;
    let phi = 2.0 * PI * (u - 0.5);
    let s = theta.sin();
    DVec3::new(s * phi.sin(), theta.cos(), -s * phi.cos())
}

/// Fractional image coordinates (u in [0, 1), v in [0, 1]) of a unit direction.
pub fn uv_from_direction(d: DVec3) -> (f64, f64) {
    let theta = d.y.clamp(-1.0, 1.0).acos();
    let phi = d.x.atan2(-d.z);
    ((phi / (2.0 * PI) + 0.5).rem_euclid(1.0), theta / PI)
}

/// Direction of the centre of pixel (x, y).
pub fn pixel_direction(x: usize, y: usize, width: usize, height: usize) -> DVec3 {
    direction_from_uv(
        (x as f64 + 0.5) / width as f64,
        (y as f64 + 0.5) / height as f64,
    )
}

/// Solid angle of a pixel in row y: (2 pi / W)(pi / H) sin(theta), exact for the row band
/// (integrated over the row: (2 pi / W)(cos theta0 - cos theta1)).
pub fn pixel_solid_angle(y: usize, width: usize, height: usize) -> f64 {
    let t0 = PI * y as f64 / height as f64;
    let t1 = PI * (y + 1) as f64 / height as f64;
    2.0 * PI / width as f64 * (t0.cos() - t1.cos())
}

/// Rotation about +Y by `yaw` radians (positive turns +X towards -Z... i.e. counter-clockwise seen
/// from above), applied to a direction.
pub fn rotate_yaw(d: DVec3, yaw: f64) -> DVec3 {
    let (s, c) = yaw.sin_cos();
    DVec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn convention_round_trips_and_covers_the_sphere() {
        assert!((direction_from_uv(0.5, 0.5) - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-12);
        assert!((direction_from_uv(0.75, 0.5) - DVec3::X).length() < 1e-12);
        assert!((direction_from_uv(0.3, 0.0) - DVec3::Y).length() < 1e-12);
        for &(u, v) in &[(0.1, 0.2), (0.6, 0.7), (0.99, 0.5)] {
            let (a, b) = uv_from_direction(direction_from_uv(u, v));
            assert!((a - u).abs() < 1e-12 && (b - v).abs() < 1e-12);
        }
        let total: f64 = (0..64).map(|y| 128.0 * pixel_solid_angle(y, 128, 64)).sum();
        assert!((total - 4.0 * PI).abs() < 1e-9);
    }
}
