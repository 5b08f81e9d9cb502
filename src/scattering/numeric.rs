//! Slow, obviously-correct numerical integration used by references and tests.
//!
//! Adaptive Gauss-Legendre: a 20-point rule on [a, b] is compared with the rule on both halves,
//! and halves are refined until they agree to the tolerance. For integrands with integrable
//! 1/sqrt singularities at the ends of a piece (N_TRT at its caustics) the substitution
//! x = a + (b - a)(1 - cos(pi u))/2 removes the singularity before integrating in u. Gauss nodes
//! never come closer to an end than ~1e-7 of the piece, where roots of phi(p, h) = phi are still
//! resolved in f64 (tanh-sinh rules sample within 1e-15 of the end, where they are not).

use gauss_quad::GaussLegendre;
use std::f64::consts::PI;
use std::num::NonZeroUsize;
use std::sync::OnceLock;

fn rule() -> &'static GaussLegendre {
    static RULE: OnceLock<GaussLegendre> = OnceLock::new();
    RULE.get_or_init(|| GaussLegendre::new(NonZeroUsize::new(20).expect("20 > 0")))
}

fn panel<F: Fn(f64) -> f64>(f: &F, a: f64, b: f64) -> f64 {
    rule().integrate(a, b, f)
}

fn adaptive<F: Fn(f64) -> f64>(f: &F, a: f64, b: f64, whole: f64, tol: f64, depth: u32) -> f64 {
    let m = 0.5 * (a + b);
    let halves = [panel(f, a, m), panel(f, m, b)];
    adaptive_halves(f, a, b, whole, halves, tol, depth)
}

/// [`adaptive`] with the halves' panels of [a, b] already computed.
fn adaptive_halves<F: Fn(f64) -> f64>(
    f: &F,
    a: f64,
    b: f64,
    whole: f64,
    [l, r]: [f64; 2],
    tol: f64,
    depth: u32,
) -> f64 {
    if (l + r - whole).abs() <= tol || depth == 0 {
        return l + r;
    }
    let m = 0.5 * (a + b);
    adaptive(f, a, m, l, 0.5 * tol, depth - 1) + adaptive(f, m, b, r, 0.5 * tol, depth - 1)
}

/// Deepest bisection: 2^14 panels of 20 nodes at most per piece. Deeper levels only chase the
/// rounding noise of integrands evaluated within ~1e-12 of a singular end.
const MAX_DEPTH: u32 = 14;

/// Integral of `f` over [a, b] to about `tol` absolute error. Like every adaptive rule it can step over
/// a feature narrower than its node spacing: callers split at narrow peaks (lobe centres, caustics).
pub fn integrate<F: Fn(f64) -> f64>(f: &F, a: f64, b: f64, tol: f64) -> f64 {
    if a == b {
        return 0.0;
    }
    adaptive(f, a, b, panel(f, a, b), tol, MAX_DEPTH)
}

/// Integral over [a, b] of a function that may have integrable 1/sqrt singularities at a and b.
pub fn integrate_endpoint_singular<F: Fn(f64) -> f64>(f: &F, a: f64, b: f64, tol: f64) -> f64 {
    EndpointSingular::start(f, a, b).refine(tol)
}

/// [`integrate_endpoint_singular`] in two steps: the first level of the adaptive rule (the whole piece
/// and its halves, in the substitution's u), then the refinement to a tolerance. Pieces integrated
/// twice (a coarse pass that sets the tolerance, then the refined one) share the first level.
struct EndpointSingular<'f, F> {
    f: &'f F,
    a: f64,
    b: f64,
    whole: f64,
    halves: [f64; 2],
}

impl<'f, F: Fn(f64) -> f64> EndpointSingular<'f, F> {
    fn start(f: &'f F, a: f64, b: f64) -> Self {
        let mut piece = Self {
            f,
            a,
            b,
            whole: 0.0,
            halves: [0.0; 2],
        };
        if a != b {
            let g = |u: f64| piece.g(u);
            let (whole, halves) = (
                panel(&g, 0.0, 1.0),
                [panel(&g, 0.0, 0.5), panel(&g, 0.5, 1.0)],
            );
            (piece.whole, piece.halves) = (whole, halves);
        }
        piece
    }

    /// The integrand in u: x - a ~ u^2 near the ends, so a 1/sqrt singularity becomes bounded. Where
    /// two caustics merge (eta' -> 2) the singularity is |x - a|^(-2/3); that case converges more
    /// slowly (worst relative error seen ~1e-5) but a stronger substitution pushes nodes into
    /// rounding noise.
    fn g(&self, u: f64) -> f64 {
        let (a, b) = (self.a, self.b);
        let x = a + (b - a) * 0.5 * (1.0 - (PI * u).cos());
        let dx = (b - a) * 0.5 * PI * (PI * u).sin();
        let v = (self.f)(x) * dx;
        if v.is_finite() { v } else { 0.0 }
    }

    /// The first level's estimate (the adaptive rule's answer at an infinite tolerance).
    fn rough(&self) -> f64 {
        self.halves[0] + self.halves[1]
    }

    /// The integral to about `tol` absolute error: [`integrate`]'s adaptive rule on the substituted
    /// integrand, its first level already done.
    fn refine(&self, tol: f64) -> f64 {
        if self.a == self.b {
            return 0.0;
        }
        let g = |u: f64| self.g(u);
        adaptive_halves(&g, 0.0, 1.0, self.whole, self.halves, tol, MAX_DEPTH)
    }
}

/// Integral over [breaks[0], breaks[last]] to relative accuracy `rel`, split at every break (where
/// `f` may jump or have integrable 1/sqrt singularities). A coarse pass sets the absolute target.
pub fn integrate_piecewise_relative<F: Fn(f64) -> f64>(f: &F, breaks: &[f64], rel: f64) -> f64 {
    integrate_piecewise(f, breaks, rel, 1e-300)
}

/// As [`integrate_piecewise_relative`], but never refining below the absolute error `abs_min`
/// (for integrals whose size only matters next to others).
pub fn integrate_piecewise<F: Fn(f64) -> f64>(
    f: &F,
    breaks: &[f64],
    rel: f64,
    abs_min: f64,
) -> f64 {
    let pieces: Vec<_> = breaks
        .windows(2)
        .filter(|w| w[1] > w[0])
        .map(|w| EndpointSingular::start(f, w[0], w[1]))
        .collect();
    let rough: f64 = pieces.iter().map(|p| p.rough()).sum::<f64>().abs();
    let n = breaks.len().saturating_sub(1).max(1) as f64;
    let tol = (rough * rel / n).max(abs_min / n);
    pieces.iter().map(|p| p.refine(tol)).sum()
}

/// Break points for integrating a lobe over [-pi/2, pi/2]: the two ends and `centre + k width` for every k
/// of `multiples` that falls strictly inside, sorted.
pub fn lobe_breaks(centre: f64, width: f64, multiples: &[f64]) -> Vec<f64> {
    let half = std::f64::consts::FRAC_PI_2;
    let mut breaks = vec![-half, half];
    breaks.extend(
        multiples
            .iter()
            .map(|k| centre + k * width)
            .filter(|x| x.abs() < half),
    );
    breaks.sort_by(f64::total_cmp);
    breaks
}

/// Fixed composite Gauss-Legendre (20 points on each of `panels` equal panels per piece) of a
/// vector-valued integrand, split at `breaks`. For smooth pieces where all components share the
/// expensive part of the integrand (tables of moments).
pub fn integrate_fixed<const K: usize>(
    f: impl Fn(f64) -> [f64; K],
    breaks: &[f64],
    panels: usize,
) -> [f64; K] {
    let mut acc = [0.0; K];
    fixed_nodes(breaks, panels, |x, cw| {
        let v = f(x);
        for k in 0..K {
            acc[k] += cw * v[k];
        }
    });
    acc
}

/// The nodes of [`integrate_fixed`]'s rule in order, each with its weight (the panel's half-width
/// times the rule's weight).
fn fixed_nodes(breaks: &[f64], panels: usize, mut node: impl FnMut(f64, f64)) {
    let pairs = rule().as_node_weight_pairs();
    for w in breaks.windows(2) {
        let (a, b) = (w[0], w[1]);
        if b <= a {
            continue;
        }
        let h = (b - a) / panels as f64;
        for p in 0..panels {
            let (lo, hi) = (a + h * p as f64, a + h * (p + 1) as f64);
            let (c, d) = (0.5 * (hi - lo), 0.5 * (hi + lo));
            for &(x, wt) in pairs {
                node(c * x + d, c * wt);
            }
        }
    }
}

/// [`integrate_fixed`] of a vector-valued integrand of run-time length `acc.len()` (`f` writes its
/// values into the slice it is given), the same nodes and sums in the same order: each component
/// equals integrate_fixed's to the bit.
pub fn integrate_fixed_slice(
    mut f: impl FnMut(f64, &mut [f64]),
    breaks: &[f64],
    panels: usize,
    acc: &mut [f64],
) {
    acc.fill(0.0);
    let mut v = vec![0.0; acc.len()];
    fixed_nodes(breaks, panels, |x, cw| {
        f(x, &mut v);
        for (s, vk) in acc.iter_mut().zip(&v) {
            *s += cw * vk;
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slice_rule_sums_as_the_fixed_rule() {
        let f = |x: f64| [x.sin(), (3.0 * x).exp(), 1.0 / (1.1 + x)];
        let breaks = [-1.0, -0.25, 0.5, 1.0];
        let fixed = integrate_fixed(f, &breaks, 3);
        let mut slice = [0.0; 3];
        integrate_fixed_slice(|x, v| v.copy_from_slice(&f(x)), &breaks, 3, &mut slice);
        assert_eq!(fixed.map(f64::to_bits), slice.map(f64::to_bits));
    }

    #[test]
    fn narrow_peak_and_endpoint_singularity() {
        let s: f64 = 0.002;
        let g = |x: f64| (-(x - 0.3) * (x - 0.3) / (2.0 * s * s)).exp();
        let exact = s * (2.0 * PI).sqrt();
        let v = integrate_piecewise_relative(&g, &[-1.5, 0.29, 0.3, 0.31, 1.5], 1e-12);
        assert!((v / exact - 1.0).abs() < 1e-9, "{v} vs {exact}");
        // 1/sqrt(x) + 1/sqrt(1 - x) on [0, 1] integrates to 4.
        let f = |x: f64| 1.0 / x.sqrt() + 1.0 / (1.0 - x).sqrt();
        let v = integrate_piecewise_relative(&f, &[0.0, 1.0], 1e-10);
        assert!((v - 4.0).abs() < 1e-8, "{v}");
    }
}
