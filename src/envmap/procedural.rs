//! The project's own environments (`strandlight make-env`), generated, never downloaded.
//!
//! - `sunny`: Preetham, Shirley & Smits 1999, "A Practical Analytic Model for Daylight": the Perez
//!   sky distribution F(theta, gamma) = (1 + A e^(B / cos theta))(1 + C e^(D gamma) + E cos^2 gamma) for
//!   luminance Y and chromaticities x, y with the paper's turbidity fits (Table 2 / Appendix A.2),
//!   converted xyY -> XYZ -> linear Rec.709. The sun is a disc of 0.53 degrees whose normal-incidence
//!   illuminance is `SUN_TO_SKY` times the sky's horizontal illuminance (clear-sky ratios of direct
//!   normal to diffuse horizontal illuminance are roughly 4 to 8), tinted by an air-mass extinction.
//!   Radiance is normalised so the sky's mean radiance over the upper hemisphere is 1.
//! - `overcast`: the CIE standard overcast sky L(theta) = L_z (1 + 2 cos theta) / 3, L_z = 1.
//! - `studio`: three soft-edged rectangular softboxes (key, fill, rim) in a dark room.
//!
//! Below the horizon every environment has a grey ground of albedo 0.15 lit by its sky.

use super::direction::pixel_direction;
use super::image::EnvMap;
use glam::DVec3;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EnvKind {
    Sunny,
    Overcast,
    Studio,
}

impl EnvKind {
    pub const ALL: [EnvKind; 3] = [EnvKind::Sunny, EnvKind::Overcast, EnvKind::Studio];

    pub fn name(self) -> &'static str {
        match self {
            EnvKind::Sunny => "sunny",
            EnvKind::Overcast => "overcast",
            EnvKind::Studio => "studio",
        }
    }
}

/// Sun direct-normal illuminance over sky horizontal illuminance.
pub const SUN_TO_SKY: f64 = 6.0;
const GROUND_ALBEDO: f64 = 0.15;

/// Direction of the sun in the `sunny` environment: 35 degrees above the horizon, azimuth towards
/// -Z rotated 40 degrees towards +X.
pub fn sunny_sun_direction() -> DVec3 {
    let elevation = 35f64.to_radians();
    let azimuth = 40f64.to_radians();
    DVec3::new(
        elevation.cos() * azimuth.sin(),
        elevation.sin(),
        -elevation.cos() * azimuth.cos(),
    )
}

fn perez(theta: f64, gamma: f64, c: [f64; 5]) -> f64 {
    let [a, b, cc, d, e] = c;
    (1.0 + a * (b / theta.cos().max(0.01)).exp())
        * (1.0 + cc * (d * gamma).exp() + e * gamma.cos().powi(2))
}

/// Preetham sky radiance (linear Rec.709, unnormalised) for a view direction above the horizon.
pub fn preetham_sky(view: DVec3, sun: DVec3, turbidity: f64) -> [f64; 3] {
    let t = turbidity;
    let theta_s = sun.y.clamp(-1.0, 1.0).acos();
    let theta = view.y.clamp(0.0, 1.0).acos();
    let gamma = view.dot(sun).clamp(-1.0, 1.0).acos();
    let cy = [
        0.1787 * t - 1.4630,
        -0.3554 * t + 0.4275,
        -0.0227 * t + 5.3251,
        0.1206 * t - 2.5771,
        -0.0670 * t + 0.3703,
    ];
    let cx = [
        -0.0193 * t - 0.2592,
        -0.0665 * t + 0.0008,
        -0.0004 * t + 0.2125,
        -0.0641 * t - 0.8989,
        -0.0033 * t + 0.0452,
    ];
    let cyy = [
        -0.0167 * t - 0.2608,
        -0.0950 * t + 0.0092,
        -0.0079 * t + 0.2102,
        -0.0441 * t - 1.6537,
        -0.0109 * t + 0.0529,
    ];
    let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * theta_s);
    let y_z = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
    let (s1, s2, s3) = (theta_s, theta_s * theta_s, theta_s * theta_s * theta_s);
    let x_z = t * t * (0.00166 * s3 - 0.00375 * s2 + 0.00209 * s1)
        + t * (-0.02903 * s3 + 0.06377 * s2 - 0.03202 * s1 + 0.00394)
        + (0.11693 * s3 - 0.21196 * s2 + 0.06052 * s1 + 0.25886);
    let yy_z = t * t * (0.00275 * s3 - 0.00610 * s2 + 0.00317 * s1)
        + t * (-0.04214 * s3 + 0.08970 * s2 - 0.04153 * s1 + 0.00516)
        + (0.15346 * s3 - 0.26756 * s2 + 0.06670 * s1 + 0.26688);
    let lum = y_z * perez(theta, gamma, cy) / perez(0.0, theta_s, cy);
    let x = x_z * perez(theta, gamma, cx) / perez(0.0, theta_s, cx);
    let y = yy_z * perez(theta, gamma, cyy) / perez(0.0, theta_s, cyy);
    xyy_to_rec709(x, y, lum.max(0.0))
}

fn xyy_to_rec709(x: f64, y: f64, lum: f64) -> [f64; 3] {
    let y = y.max(1e-6);
    let (cx, cy, cz) = (x / y * lum, lum, (1.0 - x - y) / y * lum);
    [
        (3.2404542 * cx - 1.5371385 * cy - 0.4985314 * cz).max(0.0),
        (-0.9692660 * cx + 1.8760108 * cy + 0.0415560 * cz).max(0.0),
        (0.0556434 * cx - 0.2040259 * cy + 1.0572252 * cz).max(0.0),
    ]
}

/// Soft-edged rectangle of angular half-extents (a, b) radians around `centre`, with `up` fixing
/// its orientation; 1 inside, 0 outside, a 1.5-degree smooth edge.
fn softbox(view: DVec3, centre: DVec3, up: DVec3, half: (f64, f64)) -> f64 {
    let c = centre.normalize();
    let cosang = view.dot(c);
    if cosang <= 0.0 {
        return 0.0;
    }
    let right = up.cross(c).normalize();
    let u = c.cross(right);
    let p = view / cosang - c; // gnomonic projection onto the tangent plane
    let (a, b) = (p.dot(right).atan(), p.dot(u).atan());
    let edge = 1.5f64.to_radians();
    let f = |x: f64, h: f64| (((h - x.abs()) / edge) + 0.5).clamp(0.0, 1.0);
    f(a, half.0) * f(b, half.1)
}

/// Renders one of the environments at `width` x `width / 2`.
pub fn make_env(kind: EnvKind, width: usize) -> EnvMap {
    let height = width / 2;
    let mut pixels = vec![[0f32; 3]; width * height];
    let sun = sunny_sun_direction();
    let sky = |d: DVec3| -> [f64; 3] {
        match kind {
            EnvKind::Sunny => preetham_sky(d, sun, 3.0),
            EnvKind::Overcast => [(1.0 + 2.0 * d.y.max(0.0)) / 3.0; 3],
            EnvKind::Studio => {
                let boxes = [
                    // (centre, half extents in degrees, radiance): key front-left high, fill front-right, rim behind.
                    (
                        DVec3::new(-0.6, 0.6, -0.55),
                        (18.0, 12.0),
                        [40.0, 38.0, 35.0],
                    ),
                    (DVec3::new(0.8, 0.15, -0.55), (25.0, 18.0), [7.0, 7.5, 8.0]),
                    (DVec3::new(0.1, 0.5, 0.85), (10.0, 25.0), [25.0, 25.0, 25.0]),
                ];
                let mut c = [0.02; 3];
                for (centre, (a, b), rgb) in boxes {
                    let (a, b): (f64, f64) = (a, b);
                    let w = softbox(d, centre, DVec3::Y, (a.to_radians(), b.to_radians()));
                    for k in 0..3 {
                        c[k] += w * rgb[k];
                    }
                }
                c
            }
        }
    };
    // Sky above the horizon; horizontal illuminance for the ground and the sun.
    let mut e_h = [0.0f64; 3];
    let mut sky_mean = 0.0;
    let mut sky_sa = 0.0;
    for y in 0..height {
        let sa = super::direction::pixel_solid_angle(y, width, height);
        for x in 0..width {
            let d = pixel_direction(x, y, width, height);
            if d.y <= 0.0 && kind != EnvKind::Studio {
                continue;
            }
            let c = sky(d);
            pixels[y * width + x] = c.map(|v| v as f32);
            if d.y > 0.0 {
                for k in 0..3 {
                    e_h[k] += c[k] * d.y * sa;
                }
                sky_mean += (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) * sa;
                sky_sa += sa;
            }
        }
    }
    let scale = if kind == EnvKind::Sunny {
        sky_sa / sky_mean.max(1e-12)
    } else {
        1.0
    };
    if kind != EnvKind::Studio {
        // Ground: Lambertian albedo lit by the sky (and the sun, for the sunny sky).
        let sun_e = if kind == EnvKind::Sunny {
            SUN_TO_SKY * sun.y
        } else {
            0.0
        };
        let ground = e_h.map(|e| GROUND_ALBEDO * e * (1.0 + sun_e) / PI);
        for y in 0..height {
            for x in 0..width {
                if pixel_direction(x, y, width, height).y <= 0.0 {
                    pixels[y * width + x] = ground.map(|g| g as f32);
                }
            }
        }
    }
    for p in &mut pixels {
        *p = p.map(|v| v * scale as f32);
    }
    if kind == EnvKind::Sunny {
        // Sun: power = SUN_TO_SKY x sky horizontal illuminance (at normal incidence), tinted by an
        // air-mass extinction, splatted bilinearly so its centroid is the sun direction.
        let air_mass = 1.0 / (sun.y + 0.15 * (93.885 - sun.y.acos().to_degrees()).powf(-1.253));
        let tau: [f64; 3] = [0.03, 0.06, 0.13];
        let tint: Vec<f64> = tau.iter().map(|t| (-t * air_mass).exp()).collect();
        let tint_lum = 0.2126 * tint[0] + 0.7152 * tint[1] + 0.0722 * tint[2];
        let e_lum = (0.2126 * e_h[0] + 0.7152 * e_h[1] + 0.0722 * e_h[2]) * scale;
        let power: Vec<f64> = tint
            .iter()
            .map(|t| SUN_TO_SKY * e_lum * t / tint_lum)
            .collect();
        let (u, v) = super::direction::uv_from_direction(sun);
        let (fx, fy) = (u * width as f64 - 0.5, v * height as f64 - 0.5);
        let (x0, y0) = (fx.floor(), fy.floor());
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let wx = if dx == 0 { 1.0 - (fx - x0) } else { fx - x0 };
            let wy = if dy == 0 { 1.0 - (fy - y0) } else { fy - y0 };
            let x = ((x0 as i64 + dx).rem_euclid(width as i64)) as usize;
            let y = ((y0 as i64 + dy).clamp(0, height as i64 - 1)) as usize;
            let sa = super::direction::pixel_solid_angle(y, width, height);
            for k in 0..3 {
                pixels[y * width + x][k] += (wx * wy * power[k] / sa) as f32;
            }
        }
    }
    EnvMap {
        width,
        height,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preetham_sky_is_brighter_near_the_sun_and_bluer_away_from_it() {
        let sun = sunny_sun_direction();
        let near = preetham_sky((sun + DVec3::new(0.0, 0.1, 0.0)).normalize(), sun, 3.0);
        let far = preetham_sky(DVec3::new(-sun.x, 0.6, -sun.z).normalize(), sun, 3.0);
        let lum = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
        assert!(lum(near) > 2.0 * lum(far));
        assert!(
            far[2] > far[0],
            "clear sky away from the sun is blue: {far:?}"
        );
    }

    #[test]
    fn environments_have_the_stated_structure() {
        let sunny = make_env(EnvKind::Sunny, 256);
        let p = sunny.power();
        assert!(p.iter().all(|x| x.is_finite() && *x > 0.0));
        let overcast = make_env(EnvKind::Overcast, 128);
        // Zenith is three times the horizon for the CIE overcast sky.
        let zen = overcast.pixels[0][1];
        let hor = overcast.pixels[31 * 128][1];
        assert!((zen / hor - 3.0).abs() < 0.2, "{zen} {hor}");
        let studio = make_env(EnvKind::Studio, 128);
        let max = studio.pixels.iter().map(|c| c[0]).fold(0.0, f32::max);
        assert!(max > 30.0);
    }
}
