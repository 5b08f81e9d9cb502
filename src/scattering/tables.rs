//! Xu et al. 2011 Section 5 tables, built on the CPU (rayon) and stored under `luts/`.
//!
//! - C_k(lambda', dphi), k = 0..6 (Xu Eq. 14): integral_{-pi}^{pi} |cos^k((dphi - x)/2)| g^c(x; 0, lambda') dx with
//!   g^c(x; 0, lambda') = exp(2 (cos x - 1) / lambda'^2). Only geometry: no hair parameter.
//! - H_k^TT(eta, theta_d) = integral_{-1}^{1} (1 - F)^2 h^k dh and H_k^TRT = integral (1 - F)^2 F h^k dh,
//!   k = 0, 2, 4 (Xu Eq. 19, 23), with Xu's Schlick F(eta, theta_d, h).
//!
//! Sampling (texel i of N holds the value at the sample; a GPU samples texel centres, so
//! u = (i + 0.5) / N for sample i, i.e. u = (t * (N - 1) + 0.5) / N for t in [0, 1] along the axis):
//! - lambda': N = 128, log-spaced, lambda'_i = 0.001 * 10^(4 i / 127) (t = log10(lambda' / 0.001) / 4).
//! - dphi: N = 64, linear in [0, pi], dphi_j = pi j / 63 (C_k is even and 2 pi-periodic in dphi).
//! - eta: N = 128, log-spaced, eta_i = 10^(i / 127) in [1, 10] (t = log10(eta)).
//! - theta_d: N = 64, linear in [0, pi/2], theta_j = (pi/2) j / 63 (H is even in theta_d).

use super::fresnel::fresnel_schlick_xu;
use super::numeric::{integrate_fixed, integrate_piecewise_relative};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};

/// Bumped when the tables' definition or sampling changes.
pub const TABLES_VERSION: u32 = 1;
const REL_TOL: f64 = 1e-8;

/// One sampled axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    pub name: String,
    /// "log10" or "linear".
    pub spacing: String,
    pub min: f64,
    pub max: f64,
    pub samples: usize,
}

impl Axis {
    fn log(name: &str, min: f64, max: f64, samples: usize) -> Self {
        Self {
            name: name.into(),
            spacing: "log10".into(),
            min,
            max,
            samples,
        }
    }
    fn linear(name: &str, min: f64, max: f64, samples: usize) -> Self {
        Self {
            name: name.into(),
            spacing: "linear".into(),
            min,
            max,
            samples,
        }
    }

    /// The value at sample i.
    pub fn value(&self, i: usize) -> f64 {
        let t = i as f64 / (self.samples - 1) as f64;
        if self.spacing == "log10" {
            self.min * (self.max / self.min).powf(t)
        } else {
            self.min + (self.max - self.min) * t
        }
    }
}

/// A 2D table with several channels; `data[c][y * width + x]`, x along `x_axis`.
#[derive(Clone, Debug, PartialEq)]
pub struct Table2D {
    pub name: String,
    pub x_axis: Axis,
    pub y_axis: Axis,
    pub channels: Vec<String>,
    pub data: Vec<Vec<f32>>,
}

/// Where the C_k integrand needs splitting: the Gaussian's centre and multiples of its width, and
/// the kink of |cos((dphi - x)/2)| at x = dphi - pi.
fn c_breaks(lambda: f64, dphi: f64) -> Vec<f64> {
    let mut breaks = vec![-PI, PI, 0.0, dphi - PI];
    for m in [1.0, 2.0, 4.0, 8.0, 16.0] {
        breaks.extend([-m * lambda, m * lambda]);
    }
    breaks.retain(|b| (-PI..=PI).contains(b));
    breaks.sort_by(f64::total_cmp);
    breaks.dedup_by(|a, b| (*a - *b).abs() < 1e-15);
    breaks
}

/// C_k(lambda', dphi) for one point (Xu Eq. 14), by quadrature split at the Gaussian's centre and at
/// the kink of |cos| (x = dphi - pi).
pub fn cos_gaussian_integral(k: u32, lambda: f64, dphi: f64) -> f64 {
    let kappa = 2.0 / (lambda * lambda);
    let f =
        |x: f64| ((0.5 * (dphi - x)).cos().abs()).powi(k as i32) * (kappa * (x.cos() - 1.0)).exp();
    let breaks = c_breaks(lambda, dphi);
    integrate_piecewise_relative(&f, &breaks, REL_TOL)
}

/// H_k(eta, theta_d) for TT ((1 - F)^2) or TRT ((1 - F)^2 F) (Xu Eq. 19, 23).
pub fn fresnel_moment(trt: bool, k: u32, eta: f64, theta_d: f64) -> f64 {
    let f = |h: f64| {
        let fr = fresnel_schlick_xu(eta, theta_d, h);
        let w = (1.0 - fr).powi(2) * if trt { fr } else { 1.0 };
        w * h.powi(k as i32)
    };
    integrate_piecewise_relative(&f, &[-1.0, 0.0, 1.0], REL_TOL)
}

/// All seven C_k at one (lambda', dphi), sharing the Gaussian: fixed composite Gauss-Legendre split at
/// the centre, at multiples of lambda' and at the |cos| kink. Matches [`cos_gaussian_integral`] to
/// ~1e-7 relative (tested).
pub fn cos_gaussian_integrals(lambda: f64, dphi: f64) -> [f64; 7] {
    let kappa = 2.0 / (lambda * lambda);
    let breaks = c_breaks(lambda, dphi);
    integrate_fixed(
        |x| {
            let g = (kappa * (x.cos() - 1.0)).exp();
            let c = (0.5 * (dphi - x)).cos().abs();
            let mut out = [g; 7];
            for k in 1..7 {
                out[k] = out[k - 1] * c;
            }
            out
        },
        &breaks,
        2,
    )
}

/// H_0, H_2, H_4 for TT then TRT at one (eta, theta_d), integrated over t with h = sin t so that
/// sqrt(1 - h^2) = cos t is smooth at the ends. Matches [`fresnel_moment`] (tested).
pub fn fresnel_moments(eta: f64, theta_d: f64) -> [f64; 6] {
    integrate_fixed(
        |t| {
            let (h, dh) = (t.sin(), t.cos());
            let f = fresnel_schlick_xu(eta, theta_d, h);
            let tt = (1.0 - f).powi(2) * dh;
            let (h2, h4) = (h * h, h * h * h * h);
            [tt, tt * h2, tt * h4, tt * f, tt * f * h2, tt * f * h4]
        },
        &[-FRAC_PI_2, 0.0, FRAC_PI_2],
        3,
    )
}

fn build<const K: usize>(
    x_axis: &Axis,
    y_axis: &Axis,
    f: impl Fn(f64, f64) -> [f64; K] + Sync,
) -> Vec<Vec<f32>> {
    let (w, h) = (x_axis.samples, y_axis.samples);
    let values: Vec<[f64; K]> = (0..w * h)
        .into_par_iter()
        .map(|i| f(x_axis.value(i % w), y_axis.value(i / w)))
        .collect();
    (0..K)
        .map(|k| values.iter().map(|v| v[k] as f32).collect())
        .collect()
}

/// C_k, k = 0..6: x = lambda', y = dphi.
pub fn build_c_tables() -> Table2D {
    let (x_axis, y_axis) = (
        Axis::log("lambda_prime", 0.001, 10.0, 128),
        Axis::linear("dphi", 0.0, PI, 64),
    );
    let data = build(&x_axis, &y_axis, cos_gaussian_integrals);
    Table2D {
        name: "C_k".into(),
        x_axis,
        y_axis,
        channels: (0..7).map(|k| format!("C{k}")).collect(),
        data,
    }
}

/// H_k^TT and H_k^TRT, k = 0, 2, 4: x = eta, y = theta_d.
pub fn build_h_tables() -> [Table2D; 2] {
    let (x_axis, y_axis) = (
        Axis::log("eta", 1.0, 10.0, 128),
        Axis::linear("theta_d", 0.0, FRAC_PI_2, 64),
    );
    let mut data = build(&x_axis, &y_axis, fresnel_moments);
    let trt = data.split_off(3);
    let channels: Vec<String> = ["H0", "H2", "H4"].map(String::from).to_vec();
    [
        Table2D {
            name: "H_TT".into(),
            x_axis: x_axis.clone(),
            y_axis: y_axis.clone(),
            channels: channels.clone(),
            data,
        },
        Table2D {
            name: "H_TRT".into(),
            x_axis,
            y_axis,
            channels,
            data: trt,
        },
    ]
}

/// All tables.
pub fn build_all() -> Vec<Table2D> {
    let [tt, trt] = build_h_tables();
    vec![build_c_tables(), tt, trt]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn c0_is_the_bessel_form() {
        // C_0 = integral of g^c = 2 pi e^-kappa I0(kappa); for small lambda -> sqrt(pi) lambda.
        let l: f64 = 0.01;
        let v = cos_gaussian_integral(0, l, 1.0);
        // Asymptotic 2 pi e^-k I0(k) ~ sqrt(2 pi / k) (1 + 1/(8k)), k = 2 / l^2.
        let k = 2.0 / (l * l);
        let asym = (2.0 * PI / k).sqrt() * (1.0 + 1.0 / (8.0 * k));
        assert!((v / asym - 1.0).abs() < 1e-6, "{v} vs {asym}");
        // lambda large: g^c -> 1, C_0 -> 2 pi e^-k I0(k) ~ 2 pi (1 - k) for tiny k.
        let v = cos_gaussian_integral(0, 1000.0, 0.3);
        assert!((v / (2.0 * PI) - 1.0).abs() < 1e-5, "{v}");
        // C_2 = integral cos^2((dphi - x)/2) g = (C_0 + integral cos(dphi - x) g) / 2.
        let (l, d) = (0.7, 0.9);
        let c0 = cos_gaussian_integral(0, l, d);
        let c2 = cos_gaussian_integral(2, l, d);
        let kappa = 2.0 / (l * l);
        let cosint = integrate_piecewise_relative(
            &|x: f64| (d - x).cos() * (kappa * (x.cos() - 1.0)).exp(),
            &[-PI, 0.0, PI],
            1e-10,
        );
        assert!(((c2 - 0.5 * (c0 + cosint)) / c2).abs() < 1e-7);
    }

    #[test]
    fn h_tables_are_bounded_by_the_fresnel_free_moments() {
        // 0 <= (1 - F)^2 <= 1, so H_k^TT <= 2 / (k + 1), and H^TRT <= H^TT.
        for &(eta, td) in &[(1.55, 0.0), (1.2, 0.8), (3.0, 1.3)] {
            for k in [0u32, 2, 4] {
                let tt = fresnel_moment(false, k, eta, td);
                let trt = fresnel_moment(true, k, eta, td);
                assert!(
                    tt > 0.0 && tt <= 2.0 / (k as f64 + 1.0) && trt < tt,
                    "{eta} {td} {k}: {tt} {trt}"
                );
            }
        }
    }
}
