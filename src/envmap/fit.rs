//! Fitting SRBF lights to an environment (Xu et al. 2011 Eq. 1, following Ren et al. 2010).
//!
//! Minimises the solid-angle-weighted squared error between the (box-downsampled, power-preserving)
//! environment and the sum of pixel-filtered SRBFs ([`filtered_lobe`]) over free centres,
//! bandwidths and non-negative RGB amplitudes:
//! 0. Strong compact sources (suns) are taken out at full resolution by moment matching
//!    ([`extract_suns`]): right direction and power, and the rest of the sky is not sacrificed to
//!    the residual of a sub-pixel disc.
//! 1. Initialisation by energy-weighted spherical k-means of the remaining pixels (clustering the
//!    environment's energy distribution).
//! 2. Joint refinement with L-BFGS (argmin) on (direction vector, ln lambda, ln amplitude) per light,
//!    with analytic gradients evaluated in parallel (rayon).
//!
//! Deterministic: no randomness, and parallel sums are reduced in a fixed chunk order.

use super::image::EnvMap;
use super::srbf::{FitStats, SRBF_FILE_VERSION, SrbfLight, SrbfSet, pixel_rho2};
use argmin::core::{CostFunction, Error as ArgminError, Executor, Gradient, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

#[derive(Clone, Debug)]
pub struct FitOptions {
    /// Number of lights, 1..=128.
    pub lights: usize,
    /// Width of the map the optimiser works on (the source is box-filtered down to it).
    pub fit_width: usize,
    /// L-BFGS iterations at most.
    pub max_iters: u64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            lights: 40,
            fit_width: 128,
            max_iters: 150,
        }
    }
}

/// Progress of a fit, for a progress bar or the editor.
#[derive(Clone, Copy, Debug)]
pub struct FitProgress {
    pub stage: &'static str,
    pub done: u64,
    pub total: u64,
}

const PER_LIGHT: usize = 7;
/// Weight of the squared relative power error against the relative squared L2 error.
const POWER_WEIGHT: f64 = 10.0;
const CHUNK: usize = 256;

/// The optimiser's view of the downsampled environment.
struct Problem {
    dirs: Vec<DVec3>,
    weights: Vec<f64>,
    targets: Vec<[f64; 3]>,
    rho2: f64,
    norm: f64,
    /// Environment power per channel, and the weight of the relative power error in the objective.
    power: [f64; 3],
    power_weight: f64,
    evals: AtomicUsize,
    progress: Box<dyn Fn(usize) + Sync + Send>,
}

struct Unpacked {
    dir: DVec3,
    /// d dir / d v: (I - d d^T) / |v|
    inv_len: f64,
    lambda2: f64,
    /// d lambda^2 / ds divided by 2 lambda^2 (the floor makes lambda^2 = lambda_min^2 + e^(2s)).
    ds_factor: f64,
    amp: [f64; 3],
}

/// Smallest bandwidth a fitted light gets: the fit pixel's footprint, and never below 0.01 (about the
/// sun's angular diameter). Narrower lobes are unresolvable at the fit resolution: they would fit
/// a pixel-sized blob there and turn into spikes at full resolution.
pub fn lambda_min(rho2: f64) -> f64 {
    rho2.sqrt().max(0.01)
}

fn unpack(x: &[f64], lambda_min: f64) -> Vec<Unpacked> {
    x.chunks_exact(PER_LIGHT)
        .map(|p| {
            let v = DVec3::new(p[0], p[1], p[2]);
            let len = v.length().max(1e-12);
            let e2s = (2.0 * p[3].clamp(-20.0, 4.0)).exp();
            let lambda2 = lambda_min * lambda_min + e2s;
            Unpacked {
                dir: v / len,
                inv_len: 1.0 / len,
                lambda2,
                ds_factor: e2s / lambda2,
                amp: [p[4], p[5], p[6]].map(|b| b.clamp(-60.0, 60.0).exp()),
            }
        })
        .collect()
}

impl Problem {
    /// Cost and (optionally) gradient.
    fn evaluate(&self, x: &[f64], want_grad: bool) -> (f64, Vec<f64>) {
        let lights = unpack(x, lambda_min(self.rho2));
        let n = lights.len();
        let per_light: Vec<(f64, f64)> = lights
            .iter()
            .map(|l| {
                let mu = l.lambda2 + self.rho2;
                (l.lambda2 / mu, mu)
            })
            .collect();
        let chunks: Vec<(f64, Vec<f64>)> = (0..self.dirs.len().div_ceil(CHUNK))
            .into_par_iter()
            .map(|ci| {
                let mut cost = 0.0;
                let mut grad = if want_grad {
                    vec![0.0; n * PER_LIGHT]
                } else {
                    Vec::new()
                };
                let mut g = vec![0.0; n];
                let range = ci * CHUNK..((ci + 1) * CHUNK).min(self.dirs.len());
                for p in range {
                    let w = self.dirs[p];
                    let mut model = [0.0; 3];
                    for (j, l) in lights.iter().enumerate() {
                        let (k, mu) = per_light[j];
                        let e = 2.0 * (w.dot(l.dir) - 1.0) / mu;
                        // exp(-40) ~ 4e-18: such a lobe contributes nothing at this pixel.
                        g[j] = if e > -40.0 { k * e.exp() } else { 0.0 };
                        for c in 0..3 {
                            model[c] += l.amp[c] * g[j];
                        }
                    }
                    let r: [f64; 3] = std::array::from_fn(|c| model[c] - self.targets[p][c]);
                    let wp = self.weights[p];
                    cost += wp * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
                    if !want_grad {
                        continue;
                    }
                    for (j, l) in lights.iter().enumerate() {
                        if g[j] == 0.0 {
                            continue;
                        }
                        let (_, mu) = per_light[j];
                        let base = j * PER_LIGHT;
                        let q = 2.0 * wp * (r[0] * l.amp[0] + r[1] * l.amp[1] + r[2] * l.amp[2]);
                        // d/d dir of G = G (2 / mu) omega, projected through the normalisation.
                        let dd = w * (q * g[j] * 2.0 / mu);
                        let dv = (dd - l.dir * dd.dot(l.dir)) * l.inv_len;
                        grad[base] += dv.x;
                        grad[base + 1] += dv.y;
                        grad[base + 2] += dv.z;
                        // d/ds (lambda = e^s): G (2 rho^2 / mu - 4 lambda^2 (cos - 1) / mu^2).
                        let cosm1 = w.dot(l.dir) - 1.0;
                        grad[base + 3] += l.ds_factor
                            * q
                            * g[j]
                            * (2.0 * self.rho2 / mu - 4.0 * l.lambda2 * cosm1 / (mu * mu));
                        // d/db_c (a_c = e^b_c): 2 w r_c a_c G.
                        for c in 0..3 {
                            grad[base + 4 + c] += 2.0 * wp * r[c] * l.amp[c] * g[j];
                        }
                    }
                }
                (cost, grad)
            })
            .collect();
        let mut cost = 0.0;
        let mut grad = vec![0.0; if want_grad { n * PER_LIGHT } else { 0 }];
        for (c, g) in chunks {
            cost += c;
            for (a, b) in grad.iter_mut().zip(g) {
                *a += b;
            }
        }
        cost /= self.norm;
        grad.iter_mut().for_each(|v| *v /= self.norm);
        // Energy conservation: + w sum_c ((P_c - P_env,c) / P_env,c)^2 with
        // P_c = sum_j a_jc pi lambda_j^2 (1 - exp(-4 / lambda_j^2)).
        let integrals: Vec<(f64, f64)> = lights
            .iter()
            .map(|l| {
                let e = (-4.0 / l.lambda2).exp();
                let i = std::f64::consts::PI * l.lambda2 * (1.0 - e);
                // dI/ds with lambda = e^s: dI/d(lambda^2) * 2 lambda^2.
                let di =
                    std::f64::consts::PI * (1.0 - e * (1.0 + 4.0 / l.lambda2)) * 2.0 * l.lambda2;
                (i, di)
            })
            .collect();
        for c in 0..3 {
            if self.power[c] <= 0.0 {
                continue;
            }
            let p: f64 = lights
                .iter()
                .zip(&integrals)
                .map(|(l, (i, _))| l.amp[c] * i)
                .sum();
            let rel = (p - self.power[c]) / self.power[c];
            cost += self.power_weight * rel * rel;
            if want_grad {
                let k = 2.0 * self.power_weight * rel / self.power[c];
                for (j, (l, (i, di))) in lights.iter().zip(&integrals).enumerate() {
                    grad[j * PER_LIGHT + 3] += k * l.amp[c] * di * l.ds_factor;
                    grad[j * PER_LIGHT + 4 + c] += k * l.amp[c] * i;
                }
            }
        }
        let e = self.evals.fetch_add(1, Ordering::Relaxed) + 1;
        (self.progress)(e);
        (cost, grad)
    }
}

impl CostFunction for Problem {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Self::Param) -> Result<f64, ArgminError> {
        Ok(self.evaluate(x, false).0)
    }
}

impl Gradient for Problem {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, x: &Self::Param) -> Result<Vec<f64>, ArgminError> {
        Ok(self.evaluate(x, true).1)
    }
}

/// Largest factor <= `ideal` that divides both dimensions.
fn downsample_factor(env: &EnvMap, fit_width: usize) -> usize {
    let ideal = (env.width / fit_width.max(2)).max(1);
    (1..=ideal)
        .rev()
        .find(|f| env.width.is_multiple_of(*f) && env.height.is_multiple_of(*f))
        .unwrap_or(1)
}

/// Initial lights by energy-weighted spherical k-means over the fit pixels (see module docs).
/// Seeds: the most energetic pixel, then repeatedly the pixel maximising energy x squared distance
/// to the nearest seed (a deterministic k-means++). Each cluster gives a centre (mean direction),
/// a bandwidth from its spread (for an SRBF, E[1 - cos] = lambda^2 / 2) and amplitudes that carry
/// its power. Returns the packed parameter vector.
fn initialise(p: &Problem, lights: usize) -> Vec<f64> {
    let lum = |c: &[f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let energy: Vec<f64> = p
        .targets
        .iter()
        .zip(&p.weights)
        .map(|(t, w)| lum(t).max(0.0) * w)
        .collect();
    let n = p.dirs.len();
    let first = (0..n)
        .max_by(|&a, &b| energy[a].total_cmp(&energy[b]))
        .unwrap_or(0);
    let mut centres = vec![p.dirs[first]];
    let mut nearest = vec![f64::MIN; n];
    while centres.len() < lights {
        let c = *centres.last().unwrap_or(&DVec3::Y);
        for (k, d) in p.dirs.iter().enumerate() {
            nearest[k] = nearest[k].max(d.dot(c));
        }
        let next = (0..n)
            .max_by(|&a, &b| {
                let sa = energy[a] * (1.0 - nearest[a]).powi(2);
                let sb = energy[b] * (1.0 - nearest[b]).powi(2);
                sa.total_cmp(&sb)
            })
            .unwrap_or(0);
        centres.push(p.dirs[next]);
    }
    let mut assign = vec![0usize; n];
    for _ in 0..20 {
        assign.par_iter_mut().zip(&p.dirs).for_each(|(a, d)| {
            *a = (0..centres.len())
                .max_by(|&i, &j| d.dot(centres[i]).total_cmp(&d.dot(centres[j])))
                .unwrap_or(0);
        });
        let mut sums = vec![DVec3::ZERO; centres.len()];
        for k in 0..n {
            sums[assign[k]] += p.dirs[k] * energy[k];
        }
        for (c, s) in centres.iter_mut().zip(&sums) {
            if s.length() > 0.0 {
                *c = s.normalize();
            }
        }
    }
    let lmin = lambda_min(p.rho2);
    let mut x = Vec::with_capacity(lights * PER_LIGHT);
    for (j, c) in centres.iter().enumerate() {
        let (mut e, mut r, mut power) = (0.0, DVec3::ZERO, [0.0; 3]);
        for k in (0..n).filter(|&k| assign[k] == j) {
            e += energy[k];
            r += p.dirs[k] * energy[k];
            for ch in 0..3 {
                power[ch] += p.targets[k][ch].max(0.0) * p.weights[k];
            }
        }
        let spread = if e > 0.0 { 1.0 - r.length() / e } else { 0.5 };
        let lambda = (2.0 * spread).sqrt().clamp(lmin * 1.01, 2.0);
        let integral = super::srbf::srbf_integral(lambda);
        let amp = power.map(|q| (q / integral).max(1e-12));
        x.extend([
            c.x,
            c.y,
            c.z,
            0.5 * (lambda * lambda - lmin * lmin).max(1e-12).ln(),
        ]);
        x.extend(amp.map(f64::ln));
    }
    x
}

/// Compact sources brighter than this multiple of the 99th-percentile luminance are suns.
const SUN_THRESHOLD: f32 = 20.0;
/// Pixels within this angle of a sun's brightest pixel belong to it.
const SUN_RADIUS_DEG: f64 = 5.0;

/// Takes strong compact sources (suns, lamps) out of `env` at full resolution: pixels brighter than
/// `SUN_THRESHOLD` x the 99th-percentile luminance, grouped within `SUN_RADIUS_DEG` of the brightest,
/// each become one light by moment matching (energy-weighted centroid direction, exact power,
/// bandwidth from the spread: E[1 - cos] = lambda^2 / 2, at least 0.01). Extended bright regions
/// (softboxes, overcast skies) cover more than 1 % of the sphere and never qualify. Returns the
/// lights and the environment with those pixels set to 0.
pub fn extract_suns(env: &EnvMap, max_suns: usize) -> (Vec<SrbfLight>, EnvMap) {
    let lum = |c: [f32; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    let l: Vec<f32> = env.pixels.iter().map(|c| lum(*c)).collect();
    let mut sorted = l.clone();
    let k = (((sorted.len() as f64) * 0.99) as usize).min(sorted.len().saturating_sub(1));
    let p99 = *sorted.select_nth_unstable_by(k, f32::total_cmp).1;
    let threshold = SUN_THRESHOLD * p99.max(1e-6);
    let mut candidates: Vec<usize> = (0..l.len()).filter(|&i| l[i] > threshold).collect();
    candidates.sort_by(|&a, &b| l[b].total_cmp(&l[a]));
    let mut grouped = vec![false; candidates.len()];
    let mut out = env.clone();
    let mut suns = Vec::new();
    let cos_r = SUN_RADIUS_DEG.to_radians().cos();
    for a in 0..candidates.len() {
        if grouped[a] || suns.len() >= max_suns {
            continue;
        }
        let seed = env.direction(candidates[a] % env.width, candidates[a] / env.width);
        let (mut power, mut m, mut e) = ([0f64; 3], DVec3::ZERO, 0f64);
        for b in a..candidates.len() {
            let i = candidates[b];
            let (x, y) = (i % env.width, i / env.width);
            let d = env.direction(x, y);
            if grouped[b] || d.dot(seed) < cos_r {
                continue;
            }
            grouped[b] = true;
            let sa = env.solid_angle(y);
            for c in 0..3 {
                power[c] += env.pixels[i][c] as f64 * sa;
            }
            m += d * (l[i] as f64 * sa);
            e += l[i] as f64 * sa;
            out.pixels[i] = [0.0; 3];
        }
        let spread = (1.0 - m.length() / e.max(1e-300)).max(0.0);
        let lambda = (2.0 * spread).sqrt().max(0.01);
        let integral = super::srbf::srbf_integral(lambda);
        suns.push(SrbfLight {
            direction: m.normalize_or(seed).to_array(),
            lambda,
            rgb: power.map(|p| p / integral),
        });
    }
    (suns, out)
}

/// Fits `options.lights` SRBF lights to `env`. `progress` receives coarse progress.
pub fn fit_srbf(
    env: &EnvMap,
    options: &FitOptions,
    progress: impl Fn(FitProgress) + Send + Sync + 'static,
) -> Result<SrbfSet, String> {
    if !(1..=128).contains(&options.lights) {
        return Err(format!(
            "light count must be 1 to 128, got {}",
            options.lights
        ));
    }
    let start = Instant::now();
    // Suns first (at most a quarter of the lights), then the rest of the map.
    let (suns, rest) = extract_suns(env, options.lights / 4);
    let remaining = options.lights - suns.len();
    let factor = downsample_factor(env, options.fit_width);
    let small = rest.downsample(factor);
    let (w, h) = (small.width, small.height);
    let mut dirs = Vec::with_capacity(w * h);
    let mut weights = Vec::with_capacity(w * h);
    let mut targets = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            dirs.push(small.direction(x, y));
            weights.push(small.solid_angle(y));
            targets.push(small.pixels[y * w + x].map(|v| v as f64));
        }
    }
    let norm = targets
        .iter()
        .zip(&weights)
        .map(|(t, w)| w * (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]))
        .sum::<f64>()
        .max(1e-300);
    let total = options.max_iters;
    let progress = std::sync::Arc::new(progress);
    let counter = std::sync::Arc::new(AtomicUsize::new(0));
    let (c2, p2) = (counter.clone(), progress.clone());
    progress(FitProgress {
        stage: "initialising",
        done: 0,
        total,
    });
    let problem = Problem {
        dirs,
        weights,
        targets,
        rho2: pixel_rho2(h),
        norm,
        power: small.power(),
        power_weight: POWER_WEIGHT,
        evals: AtomicUsize::new(0),
        // Objective evaluations as progress (about one or two per L-BFGS iteration).
        progress: Box::new(move |e| {
            c2.store(e, Ordering::Relaxed);
            p2(FitProgress {
                stage: "optimising",
                done: (e as u64).min(total),
                total,
            })
        }),
    };
    let x0 = initialise(&problem, remaining);
    let linesearch = MoreThuenteLineSearch::new();
    let solver = LBFGS::new(linesearch, 8)
        .with_tolerance_cost(1e-12)
        .map_err(|e| e.to_string())?;
    let result = if remaining > 0 {
        Executor::new(problem, solver)
            .configure(|state| state.param(x0.clone()).max_iters(total))
            .run()
    } else {
        Err(ArgminError::msg("every light is a sun"))
    };
    let (x, evaluations) = match result {
        Ok(r) => {
            let evals = r
                .problem
                .problem
                .as_ref()
                .map_or(0, |p| p.evals.load(Ordering::Relaxed));
            let best = r.state().get_best_param().cloned().unwrap_or(x0);
            (best, evals)
        }
        // A failed line search leaves the initial guess, which is already a valid fit.
        Err(_) => (x0, counter.load(Ordering::Relaxed)),
    };
    let lights: Vec<SrbfLight> = suns
        .into_iter()
        .chain(
            unpack(&x, lambda_min(pixel_rho2(h)))
                .into_iter()
                .map(|l| SrbfLight {
                    direction: l.dir.to_array(),
                    lambda: l.lambda2.sqrt(),
                    rgb: l.amp,
                }),
        )
        .collect();
    let mut set = SrbfSet {
        version: SRBF_FILE_VERSION,
        source: None,
        source_hash: None,
        source_size: Some([env.width, env.height]),
        yaw: 0.0,
        lights,
        fit: None,
    };
    let mut stats = fit_error(env, &set);
    stats.seconds = start.elapsed().as_secs_f64();
    stats.evaluations = evaluations;
    stats.fit_width = w;
    set.fit = Some(stats);
    Ok(set)
}

/// Relative L2 error and power error of `set` against `env` at the env's resolution.
pub fn fit_error(env: &EnvMap, set: &SrbfSet) -> FitStats {
    let recon = set.render(env.width, env.height);
    let (mut num, mut den) = (0.0, 0.0);
    for y in 0..env.height {
        let sa = env.solid_angle(y);
        for x in 0..env.width {
            let (a, b) = (
                env.pixels[y * env.width + x],
                recon.pixels[y * env.width + x],
            );
            for c in 0..3 {
                num += sa * ((a[c] - b[c]) as f64).powi(2);
                den += sa * (a[c] as f64).powi(2);
            }
        }
    }
    let pe = env.power();
    let pf = set.power();
    FitStats {
        relative_l2: (num / den.max(1e-300)).sqrt(),
        power_error: std::array::from_fn(|c| {
            if pe[c] > 0.0 {
                (pf[c] - pe[c]) / pe[c]
            } else {
                0.0
            }
        }),
        ..Default::default()
    }
}
