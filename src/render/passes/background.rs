//! What shows behind the hair: the environment seen through the camera (its image, or the SRBF
//! reconstruction when only lights are known), a flat colour, or nothing (transparent).
//!
//! The resolve pass looks the environment up for every pixel's centre ray (`background_radiance` in
//! `shaders/resolve.wgsl`, twin of [`BackgroundMap::radiance`]) into the frame's background target;
//! the composite (beauty + (1 - alpha) background) happens where a picture is made: the editor's
//! display pass, the PNG, and the EXR only when a background is asked for.

use crate::envmap::EnvMap;
use crate::envmap::direction::{rotate_yaw, uv_from_direction};
use glam::{DVec3, Vec3};
use std::fmt;
use std::str::FromStr;

/// The background of a picture.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Background {
    /// The environment behind the hair, exposed like it.
    #[default]
    Environment,
    /// Nothing: alpha is the hair's coverage.
    Transparent,
    /// A flat sRGB colour (display-encoded, so the picture shows exactly this colour).
    Colour([u8; 3]),
}

impl Background {
    /// The colour as linear RGB (for a linear composite: the EXR).
    pub fn linear_colour(c: [u8; 3]) -> [f32; 3] {
        c.map(|v| crate::colour::srgb_decode(v as f64 / 255.0) as f32)
    }
}

impl FromStr for Background {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim();
        match t.to_ascii_lowercase().as_str() {
            "env" | "environment" => return Ok(Self::Environment),
            "transparent" | "none" => return Ok(Self::Transparent),
            _ => {}
        }
        let hex = t.strip_prefix('#').unwrap_or(t);
        if hex.len() == 6 && hex.chars().all(|c| c.is_ascii_hexdigit()) {
            let byte = |i: usize| u8::from_str_radix(&hex[i..i + 2], 16).unwrap_or(0);
            return Ok(Self::Colour([byte(0), byte(2), byte(4)]));
        }
        Err(format!(
            "background '{s}' is not 'env', 'transparent' or a colour '#rrggbb'"
        ))
    }
}

impl fmt::Display for Background {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Environment => f.write_str("env"),
            Self::Transparent => f.write_str("transparent"),
            Self::Colour([r, g, b]) => write!(f, "#{r:02x}{g:02x}{b:02x}"),
        }
    }
}

impl serde::Serialize for Background {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for Background {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

/// Widest background map kept on the GPU (5.7 texels per degree; larger images are box-filtered down).
pub const MAX_BACKGROUND_WIDTH: usize = 2048;
/// Width of the SRBF reconstruction used when the environment has no image.
pub const RECONSTRUCTION_WIDTH: usize = 512;

/// The environment as the background samples it: RGBA texels (A unused) of a latitude-longitude map
/// and the turn of the world about +Y the lights were given.
#[derive(Clone, Debug, PartialEq)]
pub struct BackgroundMap {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 4]>,
    /// World direction = rotate_yaw(map direction, yaw) (as `SrbfSet::rotated` turns lights).
    pub yaw: f32,
}

impl BackgroundMap {
    pub fn from_map(map: &EnvMap, yaw: f32) -> Self {
        let factor = map.width.div_ceil(MAX_BACKGROUND_WIDTH).max(1);
        let small;
        let map = if factor > 1 {
            small = map.downsample(factor);
            &small
        } else {
            map
        };
        Self {
            width: map.width as u32,
            height: map.height as u32,
            texels: map.pixels.iter().map(|&[r, g, b]| [r, g, b, 0.0]).collect(),
            yaw,
        }
    }

    /// Radiance seen along the unit world direction `d`: the map bilinearly interpolated between texel
    /// centres, wrapping in azimuth and clamped at the poles. Twin of `background_radiance` in
    /// `shaders/resolve.wgsl`.
    pub fn radiance(&self, d: Vec3) -> [f32; 3] {
        let (w, h) = (self.width as i64, self.height as i64);
        if w == 0 || h == 0 {
            return [0.0; 3];
        }
        let m = rotate_yaw(d.as_dvec3(), -(self.yaw as f64));
        let (u, v) = uv_from_direction(DVec3::new(m.x, m.y, m.z).normalize_or_zero());
        let x = u * w as f64 - 0.5;
        let y = (v * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let xi = |k: f64| (k as i64).rem_euclid(w) as usize;
        let yi = |k: f64| (k as i64).clamp(0, h - 1) as usize;
        let at = |xx: usize, yy: usize| self.texels[yy * w as usize + xx];
        let (a, b) = (at(xi(x0), yi(y0)), at(xi(x0 + 1.0), yi(y0)));
        let (c, e) = (at(xi(x0), yi(y0 + 1.0)), at(xi(x0 + 1.0), yi(y0 + 1.0)));
        std::array::from_fn(|k| {
            let top = a[k] + (b[k] - a[k]) * fx;
            let bottom = c[k] + (e[k] - c[k]) * fx;
            top + (bottom - top) * fy
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_prints() {
        for (s, b) in [
            ("env", Background::Environment),
            ("Transparent", Background::Transparent),
            ("#336699", Background::Colour([0x33, 0x66, 0x99])),
            ("FFfF00", Background::Colour([255, 255, 0])),
        ] {
            assert_eq!(s.parse::<Background>(), Ok(b), "{s}");
        }
        for bad in ["", "#12345", "#12345g", "blue", "#1234567"] {
            let e = bad.parse::<Background>().unwrap_err();
            assert!(e.contains("#rrggbb"), "{e}");
        }
        let b = Background::Colour([1, 2, 255]);
        assert_eq!(b.to_string().parse::<Background>(), Ok(b));
        let json = serde_json::to_string(&b).unwrap();
        assert_eq!(json, "\"#0102ff\"");
        assert_eq!(serde_json::from_str::<Background>(&json).unwrap(), b);
    }

    #[test]
    fn looks_up_texel_centres_wrapping_in_azimuth_and_turning_with_the_yaw() {
        use crate::envmap::direction::pixel_direction;
        // A 8x4 map whose texel (x, y) holds (x, y, 1).
        let pixels = (0..32)
            .map(|i| [(i % 8) as f32, (i / 8) as f32, 1.0])
            .collect();
        let map = EnvMap {
            width: 8,
            height: 4,
            pixels,
        };
        let bg = BackgroundMap::from_map(&map, 0.0);
        for (x, y) in [(0, 0), (3, 1), (7, 3)] {
            let d = pixel_direction(x, y, 8, 4).as_vec3();
            let r = bg.radiance(d);
            assert!(
                (r[0] - x as f32).abs() < 1e-4 && (r[1] - y as f32).abs() < 1e-4,
                "{r:?}"
            );
        }
        // Half-way between the last and the first column: the mean of both.
        let d = crate::envmap::direction::direction_from_uv(1.0, 0.375).as_vec3();
        let r = bg.radiance(d);
        assert!((r[0] - 3.5).abs() < 1e-4, "{r:?}");
        // Turned by the yaw as lights are: world = rotate_yaw(map direction, yaw).
        let yaw = 0.7f32;
        let turned = BackgroundMap::from_map(&map, yaw);
        let d = pixel_direction(2, 2, 8, 4);
        let world = rotate_yaw(d, yaw as f64).as_vec3();
        let r = turned.radiance(world);
        assert!(
            (r[0] - 2.0).abs() < 1e-3 && (r[1] - 2.0).abs() < 1e-3,
            "{r:?}"
        );
    }

    #[test]
    fn large_maps_are_filtered_down_and_lights_alone_are_reconstructed() {
        let map = EnvMap {
            width: 4096,
            height: 2048,
            pixels: vec![[2.0, 1.0, 0.5]; 4096 * 2048],
        };
        let bg = BackgroundMap::from_map(&map, 0.0);
        assert_eq!((bg.width, bg.height), (2048, 1024));
        assert!((bg.radiance(Vec3::Y)[0] - 2.0).abs() < 1e-5);
        let mut env = crate::render::scene::default_environment();
        env.image = None;
        let bg = BackgroundMap::from_environment(&env);
        assert_eq!(bg.width as usize, RECONSTRUCTION_WIDTH);
        // The reconstruction against the lights' own radiance, away from the sun's peak.
        let d = DVec3::new(0.3, 0.2, -0.9).normalize();
        let exact = env.lights.radiance(d);
        let r = bg.radiance(d.as_vec3());
        for k in 0..3 {
            let rel = (r[k] as f64 - exact[k]).abs() / exact[k].max(1e-3);
            assert!(rel < 0.05, "channel {k}: {} against {}", r[k], exact[k]);
        }
    }
}
