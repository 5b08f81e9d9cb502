//! calN_TT and calN_TRT (Xu Eq. 12) from the exact N_p instead of the circular-Gaussian fits.
//!
//! Why: the fits carry the right energy but not the right shape. N_TT has compact support and a flat
//! top, N_TRT has one-sided 1/sqrt caustics; under a light narrower than the lobe the fitted Gaussian
//! tails are off by factors of 2-20 (TT) and the caustic Gaussians by up to 3.7x (TRT) against the
//! brute-force integral. Wide lights average the shape away, but the table serves them too: on a
//! software GPU a SIMD group runs the fits whenever one of its points needs them, and they would
//! cost ~30 % of the shading pass.
//!
//! How: with h = sin t, integral g^c(x; 0, lambda') N_p(dphi - x) dx = integral A_p(sin t)/2 g^c(dphi - Phi(t); 0, lambda') cos t dt,
//! Phi(t) = 2 p asin(sin t / eta') - 2 t + p pi, summed over the pieces of t on which Phi is monotone
//! (split at the TRT caustic). No singularity remains (the caustic is where dPhi/dt = 0). On each piece
//! only the t-interval whose exit azimuth lies within 3.5 lambda' of dphi (mod 2 pi) matters; its ends
//! are found by safeguarded Newton and it is integrated by 8-point Gauss-Legendre on two panels.
//! f32. The renderer does not solve these per point: [`super::azimuthal_table`] tabulates them (built
//! from [`for_each_window_node`]) and the WGSL reads that table.

use super::circular_gaussian::asin_precise;
use super::fast_azimuthal::{
    Rgb32, attenuation_exact, bravais_eta_prime, fresnel_schlick, sigma_a_prime,
};
use std::f32::consts::{FRAC_PI_2, PI, TAU};

/// Half-width of the azimuthal window in units of lambda' (g^c is below e^-12 outside).
const WINDOW: f32 = 3.5;

/// Equal panels of the 8-point rule per window piece.
const PANELS: u32 = 2;

/// 8-point Gauss-Legendre on [-1, 1]: (node, weight).
const GAUSS_LEGENDRE_8: [(f32, f32); 8] = [
    (-0.960_289_9, 0.101_228_54),
    (-0.796_666_5, 0.222_381_03),
    (-0.525_532_4, 0.313_706_65),
    (-0.183_434_64, 0.362_683_78),
    (0.183_434_64, 0.362_683_78),
    (0.525_532_4, 0.313_706_65),
    (0.796_666_5, 0.222_381_03),
    (0.960_289_9, 0.101_228_54),
];

/// Phi(p, t) = 2 p asin(sin t / eta') - 2 t + p pi (Xu Eq. 8 with h = sin t), unwrapped.
pub fn exit_azimuth(p: u32, t: f32, eta_p: f32) -> f32 {
    exit_azimuth_at(p, t, t.sin(), eta_p)
}

/// [`exit_azimuth`] at t whose sine h is known.
fn exit_azimuth_at(p: u32, t: f32, h: f32, eta_p: f32) -> f32 {
    let pf = p as f32;
    2.0 * pf * asin_precise(h / eta_p) - 2.0 * t + pf * PI
}

/// dPhi/dt = 2 p cos t / sqrt(eta'^2 - sin^2 t) - 2.
fn exit_azimuth_dt(p: u32, t: f32, eta_p: f32) -> f32 {
    let s = t.sin();
    2.0 * p as f32 * t.cos() / (eta_p * eta_p - s * s).sqrt() - 2.0
}

/// t with Phi(t) = target on a piece where Phi is monotone: `below` is (t, Phi(t)) at the piece's end of
/// lowest exit azimuth, `above` at its end of highest, Phi(below) <= target <= Phi(above). Safeguarded
/// Newton from the secant between the ends (a bisection step wherever Newton would leave the bracket),
/// until a step is under 1e-7 or the bracket is down to a few ulps of t: near |t| = pi/2 an ulp is
/// 1.2e-7 and the steps alone need not settle (a quarter of the table's inversions would run all
/// 24 iterations; started from the piece's midpoint they take 15 on average, from the secant 4).
pub fn invert_exit_azimuth(
    p: u32,
    eta_p: f32,
    below: (f32, f32),
    above: (f32, f32),
    target: f32,
) -> f32 {
    let (mut lo, mut hi) = (below.0, above.0);
    let span = above.1 - below.1;
    let mut t = if span > 0.0 {
        lo + (hi - lo) * ((target - below.1) / span).clamp(0.0, 1.0)
    } else {
        0.5 * (lo + hi)
    };
    for _ in 0..24 {
        let g = exit_azimuth(p, t, eta_p) - target;
        if g == 0.0 {
            return t;
        }
        if g < 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        let d = exit_azimuth_dt(p, t, eta_p);
        let mut next = t - g / d;
        let (l, u) = (lo.min(hi), lo.max(hi));
        if !(next > l && next < u) || d.abs() < 1e-6 {
            next = 0.5 * (lo + hi);
        }
        if (next - t).abs() < 1e-7 || u - l <= 4.0 * f32::EPSILON * l.abs().max(u.abs()) {
            return next;
        }
        t = next;
    }
    t
}

/// A_p(h)/2 with Xu's Schlick Fresnel and exact absorption: R F, TT (1-F)^2 T, TRT (1-F)^2 F T^2.
pub fn half_attenuation(p: u32, eta: f32, cos_d: f32, eta_p: f32, sigma_p: Rgb32, h: f32) -> Rgb32 {
    let f = fresnel_schlick(eta, cos_d, h);
    std::array::from_fn(|c| {
        let t = attenuation_exact(sigma_p[c], eta_p, h);
        let a = match p {
            0 => f,
            1 => (1.0 - f) * (1.0 - f) * t,
            _ => (1.0 - f) * (1.0 - f) * f * t * t,
        };
        0.5 * a
    })
}

/// The exact calN_p (p = 1 TT, 2 TRT) for index `eta` (eta*-bar for TRT with eccentricity).
pub fn inner_integral_exact(
    p: u32,
    eta: f32,
    sigma_a: Rgb32,
    theta_d: f32,
    lambda_prime: f32,
    dphi: f32,
) -> Rgb32 {
    let kappa = 2.0 / (lambda_prime * lambda_prime);
    azimuthal_window_integral(
        p,
        eta,
        sigma_a,
        theta_d,
        dphi,
        kappa,
        (WINDOW * lambda_prime).min(PI),
    )
}

/// integral over |x| <= half_width of k(x) N_p(theta_d, dphi - x) dx for the exact N_p (p = 0, 1, 2), with the
/// kernel k = g^c(x; 0, lambda'), kappa = 2 / lambda'^2, or k = 1 when kappa = 0 (the box window of the
/// forward-scattered light, Xu Eq. 28).
pub fn azimuthal_window_integral(
    p: u32,
    eta: f32,
    sigma_a: Rgb32,
    theta_d: f32,
    dphi: f32,
    kappa: f32,
    half_width: f32,
) -> Rgb32 {
    let eta_p = bravais_eta_prime(eta, theta_d);
    let cos_d = theta_d.cos();
    let sigma_p: Rgb32 = std::array::from_fn(|c| sigma_a_prime(sigma_a[c], eta, theta_d));
    let mut out = [0.0; 3];
    for_each_window_node(p, eta_p, dphi, kappa, half_width, |h, weight| {
        let a_half = half_attenuation(p, eta, cos_d, eta_p, sigma_p, h);
        for ch in 0..3 {
            out[ch] += weight * a_half[ch];
        }
    });
    out
}

/// The quadrature of [`azimuthal_window_integral`] without the attenuation: calls `node(h, weight)` for every
/// Gauss-Legendre node t, h = sin t, with weight = panel weight x k(dphi - Phi(t)) x cos t, so that
/// sum weight A_p(h) / 2 is the window integral.
pub fn for_each_window_node(
    p: u32,
    eta_p: f32,
    dphi: f32,
    kappa: f32,
    half_width: f32,
    mut node: impl FnMut(f32, f32),
) {
    let w = half_width.min(PI);
    // Monotone pieces of Phi in t.
    let mut ends = [-FRAC_PI_2, FRAC_PI_2, FRAC_PI_2, FRAC_PI_2];
    let mut pieces = 1;
    if p == 2 && eta_p < 2.0 {
        let tc = asin_precise(((4.0 - eta_p * eta_p) / 3.0).sqrt());
        ends = [-FRAC_PI_2, -tc, tc, FRAC_PI_2];
        pieces = 3;
    }
    for k in 0..pieces {
        let (a, b) = (ends[k], ends[k + 1]);
        let (pa, pb) = (exit_azimuth(p, a, eta_p), exit_azimuth(p, b, eta_p));
        let (lo, hi) = (pa.min(pb), pa.max(pb));
        // The ends of the piece at its lowest and highest exit azimuth.
        let (t_lo, t_hi) = if pa <= pb { (a, b) } else { (b, a) };
        // Every 2 pi branch of the window [dphi - w, dphi + w] that meets [lo, hi].
        let m0 = ((lo - (dphi + w)) / TAU).ceil() as i32;
        let m1 = ((hi - (dphi - w)) / TAU).floor() as i32;
        for m in m0..=m1 {
            let c = dphi + TAU * m as f32;
            let (wl, wh) = ((c - w).max(lo), (c + w).min(hi));
            if wh <= wl {
                continue;
            }
            // A window end clipped to the piece's range is the piece's end: no root to find.
            let ta = if wl == lo {
                t_lo
            } else {
                invert_exit_azimuth(p, eta_p, (t_lo, lo), (t_hi, hi), wl)
            };
            // The upper end lies between the lower one and the piece's end.
            let tb = if wh == hi {
                t_hi
            } else {
                invert_exit_azimuth(p, eta_p, (ta, wl), (t_hi, hi), wh)
            };
            let (t0, t1) = (ta.min(tb), ta.max(tb));
            let half = 0.5 * (t1 - t0) / PANELS as f32;
            for panel in 0..PANELS {
                let mid = t0 + half * (2 * panel + 1) as f32;
                for (x, wt) in GAUSS_LEGENDRE_8 {
                    let t = mid + half * x;
                    let (h, cos_t) = t.sin_cos();
                    let g = if kappa > 0.0 {
                        // cos x - 1 = -2 sin^2(x/2), without the cancellation that kappa ~ 1e3 amplifies.
                        let s = (0.5 * (exit_azimuth_at(p, t, h, eta_p) - c)).sin();
                        (-2.0 * kappa * s * s).exp()
                    } else {
                        1.0
                    };
                    node(h, half * wt * g * cos_t);
                }
            }
        }
    }
}
