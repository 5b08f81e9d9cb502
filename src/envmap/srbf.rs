//! SRBF (spherical Gaussian) lights: G(omega; omega_j, lambda_j) = exp(2 (dot(omega, omega_j) - 1) / lambda_j^2)
//! with RGB amplitudes L_j (Xu et al. 2011 Eq. 1), and their versioned JSON file format.

use super::direction::rotate_yaw;
use super::image::EnvMap;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One SRBF light.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SrbfLight {
    /// Unit centre direction omega_j (world space, +Y up).
    pub direction: [f64; 3],
    /// Bandwidth lambda_j (radians-like; the lobe's angular standard deviation is lambda / sqrt(2)).
    pub lambda: f64,
    /// Linear RGB amplitude L_j (radiance at the centre).
    pub rgb: [f64; 3],
}

impl SrbfLight {
    pub fn dir(&self) -> DVec3 {
        DVec3::from_array(self.direction)
    }

    /// G(omega) without the amplitude.
    pub fn lobe(&self, omega: DVec3) -> f64 {
        (2.0 * (omega.dot(self.dir()) - 1.0) / (self.lambda * self.lambda)).exp()
    }

    /// Integral of G over the sphere: pi lambda^2 (1 - exp(-4 / lambda^2)).
    pub fn lobe_integral(&self) -> f64 {
        srbf_integral(self.lambda)
    }

    /// Radiant power per channel.
    pub fn power(&self) -> [f64; 3] {
        let i = self.lobe_integral();
        self.rgb.map(|a| a * i)
    }
}

/// Integral of an SRBF of bandwidth lambda over the sphere.
pub fn srbf_integral(lambda: f64) -> f64 {
    let l2 = lambda * lambda;
    std::f64::consts::PI * l2 * (1.0 - (-4.0 / l2).exp())
}

/// The SRBF averaged over a pixel footprint, approximated by a wider SRBF: bandwidth^2 grows by rho^2
/// and the peak drops by lambda^2 / (lambda^2 + rho^2), so the lobe keeps its energy. Returns
/// (amplitude factor k, effective lambda^2).
pub fn filtered_lobe(lambda: f64, rho2: f64) -> (f64, f64) {
    let l2 = lambda * lambda;
    let mu = l2 + rho2;
    (l2 / mu, mu)
}

/// Footprint rho^2 of a pixel of side d = pi / height: d^2 / pi, the SRBF whose peak-to-power ratio
/// equals the box's (peak V, power V d^2 = V pi rho^2). Matching the variance instead (d^2 / 6)
/// makes a point-sampled least-squares fit lose half the power of sub-pixel suns.
pub fn pixel_rho2(height: usize) -> f64 {
    let d = std::f64::consts::PI / height as f64;
    d * d / std::f64::consts::PI
}

/// Statistics of a fit, stored with it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FitStats {
    /// Solid-angle-weighted relative L2 error ||env - fit|| / ||env|| at the source resolution.
    pub relative_l2: f64,
    /// (fit power - env power) / env power per channel.
    pub power_error: [f64; 3],
    /// Wall time of the fit, seconds.
    pub seconds: f64,
    /// Objective evaluations.
    pub evaluations: usize,
    /// Resolution the optimiser ran on.
    pub fit_width: usize,
}

pub const SRBF_FILE_VERSION: u32 = 1;

/// Narrowest bandwidth a lights file may hold. The fit never goes below 0.01 ([`super::fit::lambda_min`]),
/// and far narrower lights break the renderer's f32 arithmetic: kappa_j = 2 / lambda_j^2 overflows
/// below lambda_j ~ 1e-19 and its Newton search for the longitudinal weight's peak gives NaN.
pub const SRBF_LAMBDA_MIN: f64 = 1e-3;

/// A set of lights approximating an environment (the `.srbf.json` file).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SrbfSet {
    pub version: u32,
    /// Source file name (informative).
    pub source: Option<String>,
    /// BLAKE3 of the source file's bytes (the cache key).
    pub source_hash: Option<String>,
    pub source_size: Option<[usize; 2]>,
    /// Rotation about +Y already applied to the directions, radians.
    #[serde(default)]
    pub yaw: f64,
    pub lights: Vec<SrbfLight>,
    pub fit: Option<FitStats>,
}

#[derive(Debug, thiserror::Error)]
pub enum SrbfFileError {
    #[error("{path}: {source}")]
    Io {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Invalid {
        path: std::path::PathBuf,
        message: String,
    },
}

impl SrbfSet {
    /// Sum of the lights at `omega`.
    pub fn radiance(&self, omega: DVec3) -> [f64; 3] {
        let mut out = [0.0; 3];
        for l in &self.lights {
            let g = l.lobe(omega);
            for c in 0..3 {
                out[c] += l.rgb[c] * g;
            }
        }
        out
    }

    pub fn power(&self) -> [f64; 3] {
        let mut p = [0.0; 3];
        for l in &self.lights {
            let q = l.power();
            for c in 0..3 {
                p[c] += q[c];
            }
        }
        p
    }

    /// The same lights turned about +Y by `yaw` radians (no refit).
    pub fn rotated(&self, yaw: f64) -> SrbfSet {
        let mut s = self.clone();
        for l in &mut s.lights {
            l.direction = rotate_yaw(l.dir(), yaw).to_array();
        }
        s.yaw += yaw;
        s
    }

    /// Pixel-averaged reconstruction as an equirectangular map.
    pub fn render(&self, width: usize, height: usize) -> EnvMap {
        let rho2 = pixel_rho2(height);
        let mut pixels = vec![[0f32; 3]; width * height];
        use rayon::prelude::*;
        pixels
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(y, row)| {
                for (x, px) in row.iter_mut().enumerate() {
                    let w = super::direction::pixel_direction(x, y, width, height);
                    let mut acc = [0f64; 3];
                    for l in &self.lights {
                        let (k, mu) = filtered_lobe(l.lambda, rho2);
                        let g = k * (2.0 * (w.dot(l.dir()) - 1.0) / mu).exp();
                        for c in 0..3 {
                            acc[c] += l.rgb[c] * g;
                        }
                    }
                    *px = acc.map(|a| a as f32);
                }
            });
        EnvMap {
            width,
            height,
            pixels,
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.version != SRBF_FILE_VERSION {
            return Err(format!(
                "version {} is not the supported {SRBF_FILE_VERSION}",
                self.version
            ));
        }
        if self.lights.is_empty() || self.lights.len() > 1024 {
            return Err(format!("{} lights: expected 1 to 1024", self.lights.len()));
        }
        for (k, l) in self.lights.iter().enumerate() {
            let d = l.dir();
            if !(d.is_finite() && (d.length() - 1.0).abs() < 1e-3) {
                return Err(format!("light {k}: direction is not a unit vector"));
            }
            if !(l.lambda.is_finite() && (SRBF_LAMBDA_MIN..=100.0).contains(&l.lambda)) {
                return Err(format!(
                    "light {k}: lambda {} out of [{SRBF_LAMBDA_MIN}, 100]",
                    l.lambda
                ));
            }
            if l.rgb.iter().any(|a| !a.is_finite() || *a < 0.0) {
                return Err(format!("light {k}: amplitudes must be finite and >= 0"));
            }
        }
        Ok(())
    }

    pub fn read(path: &Path) -> Result<SrbfSet, SrbfFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| SrbfFileError::Io {
            path: path.into(),
            source,
        })?;
        let set: SrbfSet = serde_json::from_str(&text).map_err(|e| SrbfFileError::Invalid {
            path: path.into(),
            message: format!("not an SRBF light file: {e}"),
        })?;
        set.validate().map_err(|message| SrbfFileError::Invalid {
            path: path.into(),
            message,
        })?;
        Ok(set)
    }

    pub fn write(&self, path: &Path) -> Result<(), SrbfFileError> {
        let text = serde_json::to_string_pretty(self).map_err(|e| SrbfFileError::Invalid {
            path: path.into(),
            message: e.to_string(),
        })?;
        std::fs::write(path, text).map_err(|source| SrbfFileError::Io {
            path: path.into(),
            source,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lights_bandwidth_outside_its_range_is_an_error() {
        let set = |lambda: f64| SrbfSet {
            version: SRBF_FILE_VERSION,
            source: None,
            source_hash: None,
            source_size: None,
            yaw: 0.0,
            lights: vec![SrbfLight {
                direction: [0.0, 1.0, 0.0],
                lambda,
                rgb: [1.0; 3],
            }],
            fit: None,
        };
        assert!(set(0.01).validate().is_ok());
        for bad in [0.0, 1e-20, 5e-4, 101.0, f64::NAN] {
            let e = set(bad).validate().unwrap_err();
            assert!(e.contains("lambda"), "{bad}: {e}");
        }
    }
}
