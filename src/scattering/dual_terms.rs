//! Dual-scattering fiber terms (Zinke et al. 2008 Sec. 3; Xu et al. 2011 Eq. 32-33), sampled into 1D
//! tables over the incident inclination theta and rebuilt on the CPU whenever hair parameters change.
//!
//! NORMALISATION (docs/dual-scattering.md, "Normalisation: energy fractions"). a_f and a_b are
//! ENERGY FRACTIONS: for incident inclination theta, lobe t,
//!   a_{f,t}(theta) = L_t(theta) F_{f,t}(theta),   a_{b,t}(theta) = L_t(theta) F_{b,t}(theta),
//!   L_t(theta) = (1/2) integral_{-pi/2}^{pi/2} M_t((theta + theta_o)/2) d theta_o
//! (the longitudinal fraction: the published M_t integrates to 2 over theta_o, hence the 1/2; L_t = 1 unless the
//! lobe is cut at a pole), or with d'Eon's normalised M (the default, [`LongitudinalModel`])
//!   L_t(theta) = 1
//! (d'Eon's M is a unit density that reflects back at the poles instead of leaving). The factor cos^2(theta_o) / cos^2(theta_d) that (1/2) S cos(theta_o) d omega_o carries is left
//! out: it is 1 on the specular cone and departs from 1 only through the scale tilt alpha (by 4% at
//! alpha = -7.5 deg), which is not an absorption, so a_f + a_b stays the fraction the fiber scatters. And
//!   F_{f,t} = (1/pi) integral_{-pi}^{pi} |phi| N_t(theta, phi) d phi = (1/pi) integral_{-1}^{1} (A_t(h)/2) |phi_t(h)| dh,
//!   F_{b,t} = integral N_t d phi - F_{f,t} = (1/2) integral A_t dh - F_{f,t}.
//! The weights |phi|/pi and 1 - |phi|/pi are Zinke's Eq. 6 / 12 (and Xu's Eq. 33): irradiance spread
//! evenly over the incident azimuths of one side of the fiber, radiance counted on the front / back half
//! of the outgoing azimuths; Xu's "2 integral_0^pi phi N dphi" is the same integral. So
//! a_f + a_b = sum_t L_t (1/2) integral A_t dh <= 1 (~0.99 at eta = 1.55, sigma_a = 0).
//! N_t is evaluated at the difference angle of the lobe's centre, theta_d = alpha_t - theta (theta_o = 2 alpha_t - theta;
//! Xu Eq. 33 takes theta_o = -theta, which at theta = 45 deg and sigma_a = 1.5 put a_f 12% off), for a
//! circular fiber (Zinke: eccentricity is averaged away by the isotropic azimuthal irradiance).
//!
//! alpha_f, beta_f^2 (and _b): lobe shifts and variances averaged with the per-lobe a_{f,t} as weights.
//! A_b, Delta_b, sigma_b: Zinke Eq. 11-17 ([`backscatter_attenuation`], [`backscatter_shift`],
//! [`backscatter_width`]). Eq. 17's denominator is printed garbled in the extracted text
//! ("a_b + a_b^3 (2 beta_f + 3 beta_b)", which mixes a number with an angle); it is the sum of the weights
//! a_b + a_b^3 of the two averaged standard deviations, and is implemented so.

use super::frame::wrap_angle;
use super::marschner::{AzimuthalLobe, longitudinal_m_p, phi_p};
use super::numeric::{integrate_fixed, integrate_fixed_slice, lobe_breaks};
use super::params::{HairParams, Lobe, LongitudinalModel, ModelVariant};
use std::f64::consts::{FRAC_PI_2, PI};

/// Samples of the incident inclination theta over [-pi/2, pi/2] (sample i at -pi/2 + pi i / (N - 1)).
pub const DUAL_SAMPLES: usize = 128;

/// L_t(theta), the longitudinal energy fraction of lobe t (see the module notes): the part of the lobe that
/// leaves into theta_o in [-pi/2, pi/2]. Published: (1/2) integral M_t((theta + theta_o)/2) d theta_o, cut at the
/// poles. Normalised: 1, since d'Eon's M is a unit density that reflects back at the poles instead of leaving
/// (as a function of theta_o for fixed theta, M(theta_o, theta - 2 alpha_t) cos(theta_o) integrates to 1 exactly; the
/// tilt moves the lobe, it absorbs nothing).
pub fn longitudinal_fraction(
    params: &HairParams,
    variant: ModelVariant,
    lobe: Lobe,
    theta: f64,
) -> f64 {
    if variant.longitudinal == LongitudinalModel::Normalized {
        return 1.0;
    }
    let breaks = lobe_breaks(
        2.0 * params.alpha(lobe) - theta,
        2.0 * params.beta(lobe),
        &[-6.0, -3.0, -1.5, 0.0, 1.5, 3.0, 6.0],
    );
    let [v] = integrate_fixed(
        |theta_o| [0.5 * longitudinal_m_p(params, lobe, 0.5 * (theta + theta_o))],
        &breaks,
        2,
    );
    v
}

/// (F_f, F_b) of lobe t at theta_d, per channel (see the module notes), by h = sin t quadrature.
pub fn azimuthal_split(
    params: &HairParams,
    variant: ModelVariant,
    lobe: Lobe,
    theta_d: f64,
) -> ([f64; 3], [f64; 3]) {
    let mut p = *params;
    p.eccentricity = 1.0;
    let az = AzimuthalLobe::new(&p, variant, lobe, theta_d, 0.0);
    let s = split_sums(&az, &az.sigma_a_prime);
    ([s[0].0, s[1].0, s[2].0], [s[0].1, s[1].1, s[2].1])
}

/// [`azimuthal_split`] of lobe t at theta_d for each absorption of `sigmas` (every channel at it):
/// each node's geometry is found once for all of them ([`split_sums`]).
pub fn azimuthal_split_rows(
    params: &HairParams,
    variant: ModelVariant,
    lobe: Lobe,
    theta_d: f64,
    sigmas: &[f64],
) -> Vec<([f64; 3], [f64; 3])> {
    let mut p = *params;
    p.eccentricity = 1.0;
    // sigma_a' of each absorption (the lobe's geometry does not depend on it).
    let sigma_primes: Vec<f64> = sigmas
        .iter()
        .map(|&s| {
            p.sigma_a = [s; 3];
            AzimuthalLobe::new(&p, variant, lobe, theta_d, 0.0).sigma_a_prime[0]
        })
        .collect();
    let az = AzimuthalLobe::new(&p, variant, lobe, theta_d, 0.0);
    split_sums(&az, &sigma_primes)
        .iter()
        .map(|&(f, b)| ([f; 3], [b; 3]))
        .collect()
}

/// (F_f, F_b) of lobe `az` for each sigma_a' of `sigma_primes`, by h = sin t quadrature: each
/// node's geometry (h, gamma_i, gamma_t, Fresnel factors, chord, phi) once, its attenuation
/// exp(-2 p sigma_a' cos gamma_t) per sigma_a' (the same arithmetic as
/// [`AzimuthalLobe::attenuation_a_p`] per channel).
fn split_sums(az: &AzimuthalLobe, sigma_primes: &[f64]) -> Vec<(f64, f64)> {
    let p = az.p();
    let mut sums = vec![0.0; 2 * sigma_primes.len()];
    integrate_fixed_slice(
        |t, v| {
            let h = t.sin();
            let hc = h.clamp(-1.0, 1.0);
            let gamma_i = hc.asin();
            let gamma_t = (hc / az.eta_perp).clamp(-1.0, 1.0).asin();
            let g = az.attenuation_geometry(hc, gamma_i, gamma_t);
            let w = t.cos() * 0.5;
            let frac = wrap_angle(phi_p(p, h, az.eta_perp)).abs() / PI;
            for (j, &s) in sigma_primes.iter().enumerate() {
                let a = az.attenuation_of(&g, s);
                v[2 * j] = w * a * frac;
                v[2 * j + 1] = w * a;
            }
        },
        &[-FRAC_PI_2, -0.75, 0.0, 0.75, FRAC_PI_2],
        6,
        &mut sums,
    );
    sums.chunks_exact(2)
        .map(|fe| (fe[0], fe[1] - fe[0]))
        .collect()
}

/// A_b = a_b a_f^2 / (1 - a_f^2) + a_b^3 a_f^2 / (1 - a_f^2)^3 (Zinke Eq. 11, 13, 14).
pub fn backscatter_attenuation(a_f: f32, a_b: f32) -> f32 {
    let f2 = a_f * a_f;
    let q = (1.0 - f2).max(1e-6);
    a_b * f2 / q + a_b * a_b * a_b * f2 / (q * q * q)
}

/// The part of A_b that hair of optical depth `depth` behind the point returns (the point's own
/// fiber excluded). Zinke's A_b sums back-scattering over infinitely many layers behind the point:
/// A_1 = a_b sum_{i >= 1} a_f^{2i}. With n layers the sum stops at i = n, which keeps the fraction
/// 1 - a_f^{2n} of it; with fibers placed at random the number of layers crossed along a line of
/// optical depth tau is Poisson with mean tau, and E[1 - a_f^{2N}] = 1 - exp(-tau (1 - a_f^2)).
/// Applied to the whole A_b (A_3 needs three back-scatterings behind the point, so it falls faster: on
/// thin hair this slightly overstates it). `depth = f32::INFINITY` is Zinke's unbounded hair.
pub fn backscatter_depth_fraction(a_f: f32, depth: f32) -> f32 {
    let k = (1.0 - a_f * a_f).max(1e-6);
    if depth == f32::INFINITY {
        return 1.0;
    }
    1.0 - (-depth.max(0.0) * k).exp()
}

/// How much hair lies behind a shading point, for M^L's finite-depth fraction of A_b.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HairBehind {
    /// The volume's optical depth tau (a Poisson number of layers of mean tau):
    /// [`backscatter_depth_fraction`]; `f32::INFINITY` is Zinke's unbounded hair.
    OpticalDepth(f32),
    /// Exactly n fibers (the reference's count along its reversed shadow ray): A_1's sum stopped at
    /// i = n, 1 - a_f^{2n}.
    Fibers(u32),
}

impl HairBehind {
    /// The part of A_b this hair returns, for a fiber forward-scattering a_f.
    pub fn fraction(self, a_f: f32) -> f32 {
        match self {
            HairBehind::OpticalDepth(depth) => backscatter_depth_fraction(a_f, depth),
            HairBehind::Fibers(n) => 1.0 - (a_f * a_f).powi(n.min(1 << 20) as i32),
        }
    }
}

/// Delta_b (Zinke Eq. 16).
pub fn backscatter_shift(a_f: f32, a_b: f32, alpha_f: f32, alpha_b: f32) -> f32 {
    let f2 = a_f * a_f;
    let q = (1.0 - f2).max(1e-6);
    alpha_b * (1.0 - 2.0 * a_b * a_b / (q * q))
        + alpha_f * (2.0 * q * q + 4.0 * f2 * a_b * a_b) / (q * q * q)
}

/// sigma_b, a standard deviation (Zinke Eq. 17, denominator a_b + a_b^3; see the module notes).
pub fn backscatter_width(a_f: f32, a_b: f32, beta_f2: f32, beta_b2: f32) -> f32 {
    let b3 = a_b * a_b * a_b;
    let den = (a_b + b3).max(1e-30);
    (1.0 + 0.7 * a_f * a_f)
        * (a_b * (2.0 * beta_f2 + beta_b2).sqrt() + b3 * (2.0 * beta_f2 + 3.0 * beta_b2).sqrt())
        / den
}

/// The dual-scattering terms at one inclination, per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DualSample {
    pub a_f: [f32; 3],
    pub a_b: [f32; 3],
    pub alpha_f: [f32; 3],
    pub alpha_b: [f32; 3],
    pub beta_f2: [f32; 3],
    pub beta_b2: [f32; 3],
    pub big_a_b: [f32; 3],
    pub delta_b: [f32; 3],
    pub sigma_b: [f32; 3],
}

/// Computes every term at theta from the exact model (variant: the fast model's Fresnel).
pub fn dual_sample(params: &HairParams, variant: ModelVariant, theta: f64) -> DualSample {
    let splits =
        Lobe::ALL.map(|lobe| azimuthal_split(params, variant, lobe, params.alpha(lobe) - theta));
    dual_sample_of_splits(
        params,
        longitudinal_fractions(params, variant, theta),
        splits,
    )
}

/// Each lobe's [`longitudinal_fraction`] at theta (absorption plays no part).
fn longitudinal_fractions(params: &HairParams, variant: ModelVariant, theta: f64) -> [f64; 3] {
    Lobe::ALL.map(|lobe| longitudinal_fraction(params, variant, lobe, theta))
}

/// [`dual_sample`] at theta for each absorption of `sigmas` (every channel at it; `params`' own
/// absorption is not read), equal to it to the bit: each lobe's split of all absorptions at once
/// ([`azimuthal_split_rows`]).
pub fn dual_samples_across(
    params: &HairParams,
    variant: ModelVariant,
    theta: f64,
    sigmas: &[f64],
) -> Vec<DualSample> {
    let splits = Lobe::ALL.map(|lobe| {
        azimuthal_split_rows(params, variant, lobe, params.alpha(lobe) - theta, sigmas)
    });
    let fractions = longitudinal_fractions(params, variant, theta);
    (0..sigmas.len())
        .map(|j| {
            let p = HairParams {
                sigma_a: [sigmas[j]; 3],
                ..*params
            };
            dual_sample_of_splits(&p, fractions, splits.each_ref().map(|s| s[j]))
        })
        .collect()
}

/// dual_sample from each lobe's longitudinal fraction and (F_f, F_b) ([`azimuthal_split`] at
/// theta_d = alpha_t - theta).
fn dual_sample_of_splits(
    params: &HairParams,
    fractions: [f64; 3],
    splits: [([f64; 3], [f64; 3]); 3],
) -> DualSample {
    let mut s = DualSample::default();
    let (mut wf, mut wb) = ([0f64; 3], [0f64; 3]);
    let (mut af, mut ab, mut bf, mut bb) = ([0f64; 3], [0f64; 3], [0f64; 3], [0f64; 3]);
    for ((lobe, l), (ff, fb)) in Lobe::ALL.into_iter().zip(fractions).zip(splits) {
        let (alpha, beta2) = (params.alpha(lobe), params.beta(lobe).powi(2));
        for c in 0..3 {
            let (f, b) = (l * ff[c], l * fb[c]);
            wf[c] += f;
            wb[c] += b;
            af[c] += f * alpha;
            ab[c] += b * alpha;
            bf[c] += f * beta2;
            bb[c] += b * beta2;
        }
    }
    for c in 0..3 {
        // Lobes evaluated at their own theta_d can together pass 1 near the poles (each is a fraction
        // of a different cone); keep the total a fraction so A_b's 1 / (1 - a_f^2) stays finite.
        let total = wf[c] + wb[c];
        let k = if total > 0.999 { 0.999 / total } else { 1.0 };
        s.a_f[c] = (k * wf[c]) as f32;
        s.a_b[c] = (k * wb[c]) as f32;
        let (nf, nb) = (wf[c].max(1e-300), wb[c].max(1e-300));
        s.alpha_f[c] = (af[c] / nf) as f32;
        s.alpha_b[c] = (ab[c] / nb) as f32;
        s.beta_f2[c] = (bf[c] / nf) as f32;
        s.beta_b2[c] = (bb[c] / nb) as f32;
        s.big_a_b[c] = backscatter_attenuation(s.a_f[c], s.a_b[c]);
        s.delta_b[c] = backscatter_shift(s.a_f[c], s.a_b[c], s.alpha_f[c], s.alpha_b[c]);
        s.sigma_b[c] = backscatter_width(s.a_f[c], s.a_b[c], s.beta_f2[c], s.beta_b2[c]);
    }
    s
}

/// The 1D tables over theta for one absorption, with summed-area tables of Delta_b and sigma_b (Xu
/// Sec. 4.3.2): one row of [`DualTables`].
#[derive(Clone, Debug, PartialEq)]
pub struct DualRow {
    pub samples: Vec<DualSample>,
    /// sat_delta[i][c] = sum_{k < i} delta_b[k][c] (DUAL_SAMPLES + 1 entries).
    pub sat_delta: Vec<[f32; 3]>,
    pub sat_sigma: Vec<[f32; 3]>,
    /// ln A_b and ln a_f per sample ([`ln_floored`], component 0): M^L's integrand interpolates
    /// them log-linearly ([`DualTables::backscatter_in_cell`]; the GPU's texels hold a row's in .x
    /// and .y, the next row's in .z and .w: `dual_tables_texels`).
    pub ln_big_a_b: Vec<f32>,
    pub ln_a_f: Vec<f32>,
}

/// ln of a term that falls off about exponentially (A_b, a_f), floored at 1e-30 (a row of strong
/// absorption underflows to 0 in f32): e^(-69) contributes nothing a pixel shows. Where a sample is 0
/// the log-linear reading moves geometrically towards 1e-30 where `geometric_mix` fell back to linear
/// interpolation: values under 1e-30 either way.
pub fn ln_floored(v: f32) -> f32 {
    v.max(1e-30).ln()
}

/// theta of sample i.
pub fn dual_theta(i: usize) -> f64 {
    -FRAC_PI_2 + PI * i as f64 / (DUAL_SAMPLES - 1) as f64
}

impl DualRow {
    /// Builds the row for `params` as they are, absorption included (rayon; a few ms on two cores).
    pub fn build(params: &HairParams, variant: ModelVariant) -> Self {
        use rayon::prelude::*;
        let samples: Vec<DualSample> = (0..DUAL_SAMPLES)
            .into_par_iter()
            .map(|i| dual_sample(params, variant, dual_theta(i)))
            .collect();
        Self::from_samples(samples)
    }

    /// The row of these samples (at [`dual_theta`] 0..DUAL_SAMPLES) and their summed-area tables.
    pub fn from_samples(samples: Vec<DualSample>) -> Self {
        let prefix = |f: &dyn Fn(&DualSample) -> [f32; 3]| {
            let mut out = vec![[0f32; 3]];
            let mut acc = [0f64; 3];
            for s in &samples {
                let v = f(s);
                for c in 0..3 {
                    acc[c] += v[c] as f64;
                }
                out.push(acc.map(|x| x as f32));
            }
            out
        };
        let sat_delta = prefix(&|s| s.delta_b);
        let sat_sigma = prefix(&|s| s.sigma_b);
        let ln_big_a_b = samples.iter().map(|s| ln_floored(s.big_a_b[0])).collect();
        let ln_a_f = samples.iter().map(|s| ln_floored(s.a_f[0])).collect();
        Self {
            samples,
            sat_delta,
            sat_sigma,
            ln_big_a_b,
            ln_a_f,
        }
    }

    /// The samples around theta (clamped to [-pi/2, pi/2]): the lower one and the weight of the next.
    fn position(theta: f32) -> (usize, f32) {
        let x = ((theta + std::f32::consts::FRAC_PI_2) / std::f32::consts::PI).clamp(0.0, 1.0)
            * (DUAL_SAMPLES - 1) as f32;
        let i = (x as usize).min(DUAL_SAMPLES - 2);
        (i, x - i as f32)
    }

    /// ln A_b and ln a_f at theta, linear between the samples (WGSL twin: `dual_rows_ln`, this row's and the next).
    pub fn ln_backscatter_at(&self, theta: f32) -> (f32, f32) {
        let (i, w) = Self::position(theta);
        let lerp = |v: &[f32]| v[i] + w * (v[i + 1] - v[i]);
        (lerp(&self.ln_big_a_b), lerp(&self.ln_a_f))
    }

    /// Linear interpolation of the terms at theta (clamped to [-pi/2, pi/2]).
    pub fn lookup(&self, theta: f32) -> DualSample {
        let (i, w) = Self::position(theta);
        let (a, b) = (&self.samples[i], &self.samples[i + 1]);
        let mix = |u: [f32; 3], v: [f32; 3]| std::array::from_fn(|c| u[c] + w * (v[c] - u[c]));
        DualSample {
            a_f: mix(a.a_f, b.a_f),
            a_b: mix(a.a_b, b.a_b),
            alpha_f: mix(a.alpha_f, b.alpha_f),
            alpha_b: mix(a.alpha_b, b.alpha_b),
            beta_f2: mix(a.beta_f2, b.beta_f2),
            beta_b2: mix(a.beta_b2, b.beta_b2),
            big_a_b: mix(a.big_a_b, b.big_a_b),
            delta_b: mix(a.delta_b, b.delta_b),
            sigma_b: mix(a.sigma_b, b.sigma_b),
        }
    }

    /// Means of Delta_b and sigma_b over theta in [lo, hi] from the SATs (Xu Eq. 31); the SAT is read
    /// with linear interpolation between its entries, so the mean is exact for the piecewise-constant
    /// reading of the samples.
    pub fn mean_delta_sigma(&self, lo: f32, hi: f32) -> ([f32; 3], [f32; 3]) {
        let m = [0, 1, 2].map(|c| self.mean_delta_sigma_of(lo, hi, c));
        (m.map(|x| x.0), m.map(|x| x.1))
    }

    /// [`Self::mean_delta_sigma`] of component c alone (the tables' rows hold one absorption: M^L
    /// reads component 0; the three together cost it a quarter of its time on the CPU).
    pub fn mean_delta_sigma_of(&self, lo: f32, hi: f32, c: usize) -> (f32, f32) {
        let pos = |t: f32| {
            ((t + std::f32::consts::FRAC_PI_2) / std::f32::consts::PI).clamp(0.0, 1.0)
                * (DUAL_SAMPLES - 1) as f32
                + 0.5
        };
        let (a, b) = (pos(lo.min(hi)), pos(lo.max(hi)));
        if b - a < 1e-4 {
            let (i, w) = Self::position(0.5 * (lo + hi));
            let (s0, s1) = (&self.samples[i], &self.samples[i + 1]);
            let lerp = |u: f32, v: f32| u + w * (v - u);
            return (
                lerp(s0.delta_b[c], s1.delta_b[c]),
                lerp(s0.sigma_b[c], s1.sigma_b[c]),
            );
        }
        // The SAT's entry below x and the weight of the next (it has DUAL_SAMPLES + 1 entries).
        let entry = |x: f32| {
            let i = (x as usize).min(DUAL_SAMPLES - 1);
            (i, x - i as f32)
        };
        let ((ia, wa), (ib, wb)) = (entry(a), entry(b));
        let mean = |sat: &[[f32; 3]]| {
            let u = sat[ia][c] + wa * (sat[ia + 1][c] - sat[ia][c]);
            let v = sat[ib][c] + wb * (sat[ib + 1][c] - sat[ib][c]);
            (v - u) / (b - a)
        };
        (mean(&self.sat_delta), mean(&self.sat_sigma))
    }
}

/// The absorption axis of the tables that each point reads at its own sigma_a (the forward table, the
/// dual-scattering tables): 0, then SIGMA_SAMPLES - 1 values log-spaced over [SIGMA_MIN, SIGMA_MAX]
/// (per unit fibre radius). `shaders/forward_scattering.wgsl` and `dual_response.wgsl` read the same.
pub const SIGMA_SAMPLES: usize = 33;
pub const SIGMA_MIN: f32 = 0.005;
pub const SIGMA_MAX: f32 = 50.0;

/// sigma_a of axis sample j of `n` (0, then n - 1 log-spaced over [SIGMA_MIN, SIGMA_MAX]).
pub fn axis_sigma(j: usize, n: usize) -> f32 {
    if j == 0 {
        0.0
    } else {
        SIGMA_MIN * (SIGMA_MAX / SIGMA_MIN).powf((j - 1) as f32 / (n - 2) as f32)
    }
}

/// Continuous index of sigma_a on an axis of `n` samples (linear between 0 and SIGMA_MIN,
/// logarithmic above).
pub fn axis_pos(s: f32, n: usize) -> f32 {
    if s <= SIGMA_MIN {
        (s / SIGMA_MIN).max(0.0)
    } else {
        1.0 + (s / SIGMA_MIN).ln() / (SIGMA_MAX / SIGMA_MIN).ln() * (n - 2) as f32
    }
}

/// sigma_a of sample j of the forward table's axis.
pub fn sigma_at(j: usize) -> f32 {
    axis_sigma(j, SIGMA_SAMPLES)
}

/// Continuous index on the forward table's axis.
pub fn sigma_pos(s: f32) -> f32 {
    axis_pos(s, SIGMA_SAMPLES)
}

/// Rows of the dual-scattering tables' absorption axis: A_b falls off fast with the absorption, so
/// its axis is twice as fine as the forward table's (same range).
pub const DUAL_SIGMA_SAMPLES: usize = 65;

/// The dual tables' axis cell of sigma_a: the lower row and the weight of the one above (clamped).
pub fn sigma_cell(s: f32) -> (usize, f32) {
    let n = DUAL_SIGMA_SAMPLES;
    let y = axis_pos(s, n).clamp(0.0, (n - 1) as f32);
    let j = (y as usize).min(n - 2);
    (j, y - j as f32)
}

/// Interpolation between two rows of the absorption axis for a term that falls off about
/// exponentially with the absorption (A_b, a_f): geometric, which linear interpolation overstates by up
/// to 16 % between the axis' samples (linear where either is 0).
pub fn geometric_mix(a: f32, b: f32, w: f32) -> f32 {
    if a > 0.0 && b > 0.0 {
        (a.ln() + w * (b.ln() - a.ln())).exp()
    } else {
        a + w * (b - a)
    }
}

/// The dual-scattering tables over (theta, sigma_a): one [`DualRow`] per absorption of the axis, so that
/// each point's local multiple scattering reads its own absorption (a painted strand's, not the hair's
/// mean) and an absorption change needs no rebuild. Each channel reads the rows at its own sigma_a.
#[derive(Clone, Debug, PartialEq)]
pub struct DualTables {
    pub rows: Vec<DualRow>,
}

impl DualTables {
    /// Builds every row for the other parameters of `params` (its sigma_a is not used).
    pub fn build(params: &HairParams, variant: ModelVariant) -> Self {
        use rayon::prelude::*;
        // By inclination, every absorption at once (dual_samples_across: the exact model's geometry
        // once per node for all rows), then the rows: the same samples as a build row by row
        // (DualRow::build at each absorption), about 12x faster.
        let sigmas: Vec<f64> = (0..DUAL_SIGMA_SAMPLES)
            .map(|j| axis_sigma(j, DUAL_SIGMA_SAMPLES) as f64)
            .collect();
        let columns: Vec<Vec<DualSample>> = (0..DUAL_SAMPLES)
            .into_par_iter()
            .map(|i| dual_samples_across(params, variant, dual_theta(i), &sigmas))
            .collect();
        let rows = (0..DUAL_SIGMA_SAMPLES)
            .map(|j| DualRow::from_samples(columns.iter().map(|c| c[j]).collect()))
            .collect();
        Self { rows }
    }

    /// The terms at theta, channel c read at absorption sigma_a[c] (bilinear in theta and the axis).
    pub fn lookup(&self, theta: f32, sigma_a: [f32; 3]) -> DualSample {
        let mut out = DualSample::default();
        for (c, s) in sigma_a.iter().enumerate() {
            let (j, w) = sigma_cell(*s);
            let (a, b) = (self.rows[j].lookup(theta), self.rows[j + 1].lookup(theta));
            let mix = |u: [f32; 3], v: [f32; 3]| u[0] + w * (v[0] - u[0]);
            let geo = |u: [f32; 3], v: [f32; 3]| geometric_mix(u[0], v[0], w);
            out.a_f[c] = geo(a.a_f, b.a_f);
            out.a_b[c] = mix(a.a_b, b.a_b);
            out.alpha_f[c] = mix(a.alpha_f, b.alpha_f);
            out.alpha_b[c] = mix(a.alpha_b, b.alpha_b);
            out.beta_f2[c] = mix(a.beta_f2, b.beta_f2);
            out.beta_b2[c] = mix(a.beta_b2, b.beta_b2);
            out.big_a_b[c] = geo(a.big_a_b, b.big_a_b);
            out.delta_b[c] = mix(a.delta_b, b.delta_b);
            out.sigma_b[c] = mix(a.sigma_b, b.sigma_b);
        }
        out
    }

    /// A_b and a_f at theta for one channel of absorption sigma_a (what M^L's integrand reads).
    pub fn backscatter_at(&self, theta: f32, sigma_a: f32) -> (f32, f32) {
        self.backscatter_in_cell(theta, sigma_cell(sigma_a))
    }

    /// [`Self::backscatter_at`] in the axis cell of the absorption ([`sigma_cell`], found once per
    /// point): log-linear in theta and along the axis, from the rows' logarithms (WGSL twin:
    /// `dual_backscatter`). Both terms fall off about exponentially; against [`Self::lookup`]'s
    /// linear reading in theta the rows' 128 samples differ by the curvature of ln A_b over 1.4
    /// degrees, and the logarithms stored save the GPU four logarithms a channel and node.
    pub fn backscatter_in_cell(&self, theta: f32, (j, w): (usize, f32)) -> (f32, f32) {
        let (a, b) = (
            self.rows[j].ln_backscatter_at(theta),
            self.rows[j + 1].ln_backscatter_at(theta),
        );
        ((a.0 + w * (b.0 - a.0)).exp(), (a.1 + w * (b.1 - a.1)).exp())
    }

    /// [`DualRow::mean_delta_sigma`], channel c at absorption sigma_a[c].
    pub fn mean_delta_sigma(&self, lo: f32, hi: f32, sigma_a: [f32; 3]) -> ([f32; 3], [f32; 3]) {
        let (mut delta, mut sigma) = ([0.0; 3], [0.0; 3]);
        for (c, s) in sigma_a.iter().enumerate() {
            (delta[c], sigma[c]) = self.mean_delta_sigma_in_cell(lo, hi, sigma_cell(*s));
        }
        (delta, sigma)
    }

    /// [`Self::mean_delta_sigma`] of one channel in its absorption's axis cell.
    pub fn mean_delta_sigma_in_cell(&self, lo: f32, hi: f32, (j, w): (usize, f32)) -> (f32, f32) {
        let (a, b) = (
            self.rows[j].mean_delta_sigma_of(lo, hi, 0),
            self.rows[j + 1].mean_delta_sigma_of(lo, hi, 0),
        );
        (a.0 + w * (b.0 - a.0), a.1 + w * (b.1 - a.1))
    }
}
