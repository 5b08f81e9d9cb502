//! The reference mode's lights: directions importance-sampled from an environment image, or sampled
//! from SRBF lobes, each carrying its share of the lighting integral.

use crate::envmap::EnvMap;
use crate::envmap::SrbfLight;
use crate::envmap::direction::{direction_from_uv, rotate_yaw};
use glam::DVec3;
use rand_core::{Rng, SeedableRng};

/// A directional light carrying its share of the environment's integral: L(omega) / (pdf N), summed
/// over the samples that fell in the same texel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    pub direction: DVec3,
    pub weight: [f64; 3],
}

/// `n` stratified samples of the environment proportional to luminance x solid angle (texel CDF
/// inversion, uniform within the texel), merged per texel. Their weights sum to the texels' integral of
/// L d omega up to sampling error; `yaw` turns them as `SrbfSet::rotated` turns lights.
pub fn importance_sample_env(env: &EnvMap, n: usize, yaw: f64, seed: u64) -> Vec<DirectionalLight> {
    let (w, h) = (env.width, env.height);
    let mut cdf = Vec::with_capacity(w * h + 1);
    cdf.push(0.0f64);
    let mut total = 0.0;
    for y in 0..h {
        let omega = env.solid_angle(y);
        for x in 0..w {
            let p = env.pixels[y * w + x];
            let lum = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            total += lum.max(0.0) * omega;
            cdf.push(total);
        }
    }
    if total <= 0.0 || n == 0 {
        return Vec::new();
    }
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let mut merged: std::collections::BTreeMap<usize, DirectionalLight> = Default::default();
    for k in 0..n {
        let target = (k as f64 + unit()) / n as f64 * total;
        let i = cdf.partition_point(|&c| c <= target).clamp(1, w * h) - 1;
        let (x, y) = (i % w, i / w);
        let pdf_texel = (cdf[i + 1] - cdf[i]) / total;
        if pdf_texel <= 0.0 {
            continue;
        }
        let omega = env.solid_angle(y);
        let (ju, jv) = (unit(), unit());
        let d = direction_from_uv((x as f64 + ju) / w as f64, (y as f64 + jv) / h as f64);
        let d = rotate_yaw(d, yaw);
        let p = env.pixels[i];
        let scale = omega / (pdf_texel * n as f64);
        let e = merged.entry(i).or_insert(DirectionalLight {
            direction: DVec3::ZERO,
            weight: [0.0; 3],
        });
        // Several samples in one texel: one light along their mean direction.
        e.direction += d;
        for c in 0..3 {
            e.weight[c] += p[c] as f64 * scale;
        }
    }
    merged
        .into_values()
        .map(|mut l| {
            l.direction = l.direction.normalize();
            l
        })
        .collect()
}

/// About `per_light` (the largest rows x cols below it) stratified samples of every SRBF lobe G(omega) = exp(2 (omega . omega_j - 1) / lambda^2):
/// cos of the angle to the centre by inversion of its CDF, the azimuth uniform, each sample weighted
/// L_j integral(G) / per_light. Their sum over a smooth integrand converges to the SRBF's integral.
pub fn sample_srbf_lights(
    lights: &[SrbfLight],
    per_light: usize,
    seed: u64,
) -> Vec<DirectionalLight> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    // A near-square grid of strata over (cos, azimuth).
    let rows = (per_light.max(1) as f64).sqrt().floor().max(1.0) as usize;
    let cols = per_light.max(1) / rows;
    let n = rows * cols;
    let mut out = Vec::with_capacity(lights.len() * n);
    for l in lights {
        let centre = l.dir().normalize();
        let kappa = 2.0 / (l.lambda * l.lambda);
        let e = (-2.0 * kappa).exp();
        let helper = if centre.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let e1 = (helper - centre * centre.dot(helper)).normalize();
        let e2 = centre.cross(e1);
        let weight = l.power().map(|p| p / n as f64);
        for k in 0..n {
            let (row, col) = (k % rows, k / rows);
            let xi1 = (row as f64 + unit()) / rows as f64;
            let xi2 = (col as f64 + unit()) / cols as f64;
            let cos = (1.0 + (xi1 * (1.0 - e) + e).ln() / kappa).clamp(-1.0, 1.0);
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            let a = std::f64::consts::TAU * xi2;
            out.push(DirectionalLight {
                direction: (centre * cos + (e1 * a.cos() + e2 * a.sin()) * sin).normalize(),
                weight,
            });
        }
    }
    out
}
