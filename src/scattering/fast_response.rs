//! Xu et al. 2011 Sec. 4.2: the single-scattering response of one SRBF light,
//!   M_t(omega_j, lambda_j, omega_o) = integral G_j(omega_i) S_t(omega_i, omega_o) cos(theta_i) d omega_i   (Eq. 11)
//!   ~ integral g(theta_i; theta_j, lambda_j) M_t(theta_h) cos^2(theta_i) / cos^2(theta_d) calN_t(lambda', phi_o - phi_j, theta_d) d theta_i
//!   (published), or with M_t(theta_i, theta_o) cos(theta_i) in place of M_t(theta_h) cos^2(theta_i) / cos^2(theta_d) (normalised),
//! with lambda' = lambda_j / sqrt(cos theta_i cos theta_j), and the outer integral done by the linear
//! quadrature of Sec. 4.2.2 against the product Gaussian g(theta_i; theta_j, lambda_j) M_t.
//!
//! The longitudinal function is d'Eon et al. 2011's normalised M_p(theta_i, theta_o) by default (then
//! S cos(theta_i) = M_p calN_p and the weight is cos(theta_i), not cos^2(theta_i)/cos^2(theta_d)); the quadrature
//! still integrates against the Gaussian of M_p's peak and width, and [`LongitudinalLobe::factor`] carries the
//! ratio of the true M_p to that Gaussian into the interpolated factor.
//!
//! Angles are in the fiber frame ([`super::frame`]); f32 as in the WGSL twin.
//!
//! Sample placement (Sec. 4.2.2), m segments: the ends -pi/2 and pi/2 plus m - 1 samples evenly over
//! mu +- (m - 2) lambda / 2 CLIPPED to [-pi/2, pi/2]. For m = 4 and a lobe inside the range this is the
//! paper's rule (mu - lambda, mu, mu + lambda); clipping keeps every sample useful and lets a large m
//! converge to the exact integral (the paper's rule spaces samples by lambda whatever m is).

use super::azimuthal_table::AzimuthalTable;
use super::circular_gaussian::{GaussianEnd, bessel_i0_scaled, gaussian_quadratic_moments_between};
use super::fast_azimuthal::LAMBDA_PRIME_MAX;
use super::fast_azimuthal::{Rgb32, eta_star_mean, inner_integral_r};
use super::fast_params::{FastHairParams, LONGITUDINAL_PUBLISHED};
use super::lut::Luts;
use std::f32::consts::{FRAC_PI_2, PI};

/// The product of Xu's 1D Gaussians g(x; mu1, l1) g(x; mu2, l2) = scale g(x; mu, l)
/// (g(x; mu, l) = exp(-(x - mu)^2 / l^2)). Returns (scale, mu, l).
pub fn gaussian_product(mu1: f32, l1: f32, mu2: f32, l2: f32) -> (f32, f32, f32) {
    let (a, b) = (l1 * l1, l2 * l2);
    let s = a + b;
    let d = mu1 - mu2;
    (
        (-d * d / s).exp(),
        (mu1 * b + mu2 * a) / s,
        (a * b / s).sqrt(),
    )
}

/// Sample s (0..=m) of the quadrature over [-pi/2, pi/2] for a Gaussian (mu, lambda): the ends, and m - 1
/// samples evenly over mu +- (m - 2) lambda / 2 (Xu Sec. 4.2.2). Where that span crosses an end it is
/// clipped and the samples spread evenly strictly inside it, so none coincides with the end.
pub fn quadrature_sample(s: u32, m: u32, mu: f32, lambda: f32) -> f32 {
    if s == 0 {
        return -FRAC_PI_2;
    }
    if s >= m {
        return FRAC_PI_2;
    }
    let half = 0.5 * (m as f32 - 2.0) * lambda;
    let (lo, hi) = (mu - half, mu + half);
    let lo_clipped = lo <= -FRAC_PI_2;
    let hi_clipped = hi >= FRAC_PI_2;
    let (lo, hi) = (
        lo.clamp(-FRAC_PI_2, FRAC_PI_2),
        hi.clamp(-FRAC_PI_2, FRAC_PI_2),
    );
    let inner = m - 1;
    let denom = (inner - 1) + lo_clipped as u32 + hi_clipped as u32;
    if denom == 0 {
        return mu.clamp(-FRAC_PI_2, FRAC_PI_2);
    }
    let k = (s - 1) + lo_clipped as u32;
    lo + (hi - lo) * k as f32 / denom as f32
}

/// integral_{-pi/2}^{pi/2} g(x; mu, lambda) f(x) dx from m + 1 samples of f (Sec. 4.2.2). Xu interpolates f
/// linearly on every segment. Here segments are taken in pairs and f is interpolated by the parabola
/// through each pair's three samples (the paper's suggested "higher order polynomial"); a last unpaired
/// segment (m odd) stays linear. f contains cos^2(theta_i), which vanishes quadratically at the ends
/// +-pi/2: near the poles the linear rule is off by up to 12% from m = 200. f must vanish at the ends
/// (every integrand carries the longitudinal factor's clamped cos(theta_i)): it is evaluated at the
/// m - 1 inner samples only.
pub fn linear_quadrature(m: u32, mu: f32, lambda: f32, mut f: impl FnMut(f32) -> Rgb32) -> Rgb32 {
    let mut q = Quadrature::start(mu, lambda);
    for s in 1..m {
        let x = quadrature_sample(s, m, mu, lambda);
        q.node(s, m, x, f(x));
    }
    q.end(m);
    q.out
}

/// [`linear_quadrature`] node by node (twin of WGSL's `Quadrature`, `quadrature_start`,
/// `quadrature_node` and `quadrature_end`): nodes s = 0..=m are fed in order; each even node closes the pair of segments
/// before it with their parabola, a last odd node (m odd) its linear segment. The shaders call their
/// integrands from one place per quadrature this way (each call site is inlined: three per
/// quadrature take lavapipe seconds to compile).
#[derive(Clone, Copy, Debug)]
pub struct Quadrature {
    pub mu: f32,
    pub lambda: f32,
    x0: f32,
    /// erf and e^(-u^2) at x0 (the next segment's start: each node's found once).
    e0: GaussianEnd,
    f0: Rgb32,
    x1: f32,
    f1: Rgb32,
    pub out: Rgb32,
}

impl Quadrature {
    /// Node 0, the pole -pi/2. Every integrand of the quadratures carries the longitudinal factor's
    /// cos(theta_i) clamped at 0 ([`LongitudinalLobe::factor`]), exactly 0 at both ends in f32
    /// (cos(FRAC_PI_2) < 0; tested in `tests/fast_model.rs`): the ends are not evaluated, only the
    /// m - 1 inner nodes, and [`Self::end`] closes the rule at +pi/2.
    pub fn start(mu: f32, lambda: f32) -> Self {
        Self {
            mu,
            lambda,
            x0: -FRAC_PI_2,
            e0: GaussianEnd::at((-FRAC_PI_2 - mu) / lambda),
            f0: [0.0; 3],
            x1: 0.0,
            f1: [0.0; 3],
            out: [0.0; 3],
        }
    }

    /// Node m, the pole +pi/2 (f = 0 there).
    pub fn end(&mut self, m: u32) {
        self.node(m, m, FRAC_PI_2, [0.0; 3]);
    }

    /// Node s of m at x with f(x).
    pub fn node(&mut self, s: u32, m: u32, x: f32, f: Rgb32) {
        let odd = s & 1 == 1;
        if s > 0 && odd && s < m {
            // The middle of a pair: kept until its end.
            self.x1 = x;
            self.f1 = f;
            return;
        }
        let (x0, f0) = (self.x0, self.f0);
        if s > 0 && x > x0 {
            // The pair's parabola through (x0, x1, x) when its middle lies strictly inside, else the
            // line from x0 (the last node of an odd m, or a pair whose middle was clipped onto an
            // end): the line is the parabola with q2 = 0 (Newton form in y = x - mu).
            let (x1, f1, mu) = (self.x1, self.f1, self.mu);
            let pair = !odd && x1 > x0 && x > x1;
            let end = GaussianEnd::at((x - mu) / self.lambda);
            let mo = gaussian_quadratic_moments_between(self.e0, end, self.lambda);
            self.e0 = end;
            let y0 = x0 - mu;
            for c in 0..3 {
                let (q1, q2, y1) = if pair {
                    let q1 = (f1[c] - f0[c]) / (x1 - x0);
                    (q1, ((f[c] - f1[c]) / (x - x1) - q1) / (x - x0), x1 - mu)
                } else {
                    ((f[c] - f0[c]) / (x - x0), 0.0, 0.0)
                };
                self.out[c] += (f0[c] - q1 * y0 + q2 * (y0 * y1)) * mo[0]
                    + (q1 - q2 * (y0 + y1)) * mo[1]
                    + q2 * mo[2];
            }
        }
        self.x0 = x;
        self.f0 = f;
    }
}

/// An SRBF light in the fiber frame: centre angles (theta_j, phi_j) and bandwidth lambda_j.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SrbfInFrame {
    pub theta: f32,
    pub phi: f32,
    pub lambda: f32,
}

/// lambda' = lambda_j / sqrt(cos theta_i cos theta_j) (Xu Eq. 11), clamped to the table, from cos theta_i
/// (the quadrature node's, shared with its longitudinal factor) and cos theta_j (the light's, found once
/// for its nodes).
pub fn azimuthal_bandwidth(lambda_j: f32, cos_theta_i: f32, cos_theta_j: f32) -> f32 {
    let c = (cos_theta_i * cos_theta_j).max(1e-8);
    (lambda_j / c.sqrt()).min(LAMBDA_PRIME_MAX)
}

/// The tilted outgoing inclination theta_o' = theta_o - 2 alpha, reflected back into [-pi/2, pi/2] past a
/// pole (pbrt-v4 takes |cos theta_o'|), so M stays normalised over theta_i.
pub fn tilted_outgoing(theta_o: f32, alpha: f32) -> f32 {
    let t = theta_o - 2.0 * alpha;
    if t > FRAC_PI_2 {
        PI - t
    } else if t < -FRAC_PI_2 {
        -PI - t
    } else {
        t
    }
}

/// 1 - cos x from sin x and cos x: sin^2 x / (1 + cos x) where cos x > 0, so that no cancellation
/// loses the small values near x = 0 (1 - cos x itself rounds to multiples of 6e-8 there: scaled by a
/// narrow light's kappa_j = 2 / lambda_j^2, 5e-3 of a logarithm at lambda_j = 0.005).
pub fn one_minus_cos(sin_x: f32, cos_x: f32) -> f32 {
    if cos_x > 0.0 {
        sin_x * sin_x / (1.0 + cos_x)
    } else {
        1.0 - cos_x
    }
}

/// x beyond which 1 - e^(-x) rounds to 1 in f32 (e^(-x) < 2^-25 from x = 25 ln 2 = 17.33).
const ONE_MINUS_EXP_IS_ONE: f32 = 17.5;

/// One lobe's longitudinal function for one view, with everything that does not depend on theta_i computed
/// once: it is evaluated at every quadrature sample of every light. Holds the centre of the Gaussian the
/// quadrature integrates against, g(theta_i; mu, 2 sqrt(2) beta) / (sqrt(2 pi) 2 beta) (unit area, standard deviation
/// 2 beta in theta_i), and, normalised, d'Eon's variance, the tilted inclination and the log normalisations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LongitudinalLobe {
    pub longitudinal: u32,
    pub theta_o: f32,
    /// theta_o' ([`tilted_outgoing`]).
    pub tilted: f32,
    /// d'Eon's variance v = (2 beta)^2.
    pub v: f32,
    /// The Gaussian's centre: published, 2 alpha - theta_o (M_t(theta_h)'s peak, possibly past a pole);
    /// normalised, -theta_o' (d'Eon's peak, always inside).
    pub mu: f32,
    /// ln(csch(1/v) / (2v)) + 1/v = -ln v - ln(1 - e^(-2/v)): what ln M adds to its shape.
    pub ln_m_norm: f32,
    /// ln(sqrt(2 pi v)): the log of the Gaussian's normalisation.
    pub ln_gaussian_norm: f32,
    /// cos(theta_o') and sin(theta_o').
    pub cos_tilted: f32,
    pub sin_tilted: f32,
}

impl LongitudinalLobe {
    /// Lobe with shift alpha and width beta (d'Eon's v = (2 beta)^2) seen from theta_o.
    pub fn new(longitudinal: u32, theta_o: f32, alpha: f32, beta: f32) -> Self {
        Self::with_variance(longitudinal, theta_o, alpha, (4.0 * beta * beta).max(1e-8))
    }

    /// Lobe `lobe` (0 = R, 1 = TT, 2 = TRT) of the hair's parameters seen from theta_o.
    pub fn of_lobe(p: &FastHairParams, lobe: u32, theta_o: f32) -> Self {
        let t = lobe as usize;
        Self::new(p.longitudinal, theta_o, p.alpha[t], p.beta[t])
    }

    pub fn with_variance(longitudinal: u32, theta_o: f32, alpha: f32, v: f32) -> Self {
        let tilted = tilted_outgoing(theta_o, alpha);
        let (sin_tilted, cos_tilted) = tilted.sin_cos();
        let ln_v = v.ln();
        // ln(1 - e^(-2/v)) is 0 in f32 once e^(-2/v) is under half an ulp of 1 (2/v > 25 ln 2 = 17.33;
        // every lobe with beta < 0.169): skipped there, the same value.
        let ln_csch_part = if 2.0 / v > ONE_MINUS_EXP_IS_ONE {
            0.0
        } else {
            (1.0 - (-2.0 / v).exp()).ln()
        };
        Self {
            longitudinal,
            theta_o,
            tilted,
            v,
            mu: if longitudinal == LONGITUDINAL_PUBLISHED {
                2.0 * alpha - theta_o
            } else {
                -tilted
            },
            ln_m_norm: -ln_v - ln_csch_part,
            ln_gaussian_norm: 0.5 * ((2.0 * PI).ln() + ln_v),
            cos_tilted,
            sin_tilted,
        }
    }

    /// d'Eon's ln M(theta_i) without its Bessel term: -2 sin^2((theta_i + theta_o')/2) / v - ln v - ln(1 - e^(-2/v)).
    fn ln_m_shape(&self, theta_i: f32) -> f32 {
        let half = (0.5 * (theta_i + self.tilted)).sin();
        -2.0 * half * half / self.v + self.ln_m_norm
    }

    /// d'Eon's Bessel argument a = cos theta_i cos theta_o' / v, from cos theta_i clamped at 0 (the
    /// factor's own `ci`: computed once per node).
    fn bessel_argument(&self, cos_theta_i: f32) -> f32 {
        cos_theta_i * self.cos_tilted / self.v
    }

    /// ln M(theta_i) of d'Eon et al. 2011:
    /// ln M = ln(I0(a) e^-a) - 2 sin^2((theta_i + theta_o')/2) / v - ln v - ln(1 - e^(-2/v)), a = cos theta_i cos theta_o' / v.
    pub fn ln_m(&self, theta_i: f32) -> f32 {
        bessel_i0_scaled(self.bessel_argument(theta_i.cos().max(0.0))).ln()
            + self.ln_m_shape(theta_i)
    }

    /// The longitudinal factor of an outer integrand at theta_i, relative to the Gaussian:
    /// - published: M(theta_h) = 2 x the Gaussian (it has unit area in theta_h, Xu Eq. 7), and S cos(theta_i)
    ///   d omega_i brings cos^2(theta_i) / cos^2(theta_d): the factor is 2 cos^2(theta_i) / cos^2(theta_d);
    /// - normalised: cos(theta_i) M^dEon(theta_i, theta_o) / Gaussian, smooth (about sqrt(cos theta_i / cos theta_o')
    ///   near the peak): I0(a) e^-a (at most 1) times the exponential of the rest of the ratio's log,
    ///   clamped as the light's ratio is (no logarithm of the Bessel term, no cos(theta_o') per call: they
    ///   cost `bench-fast` ~4 %).
    pub fn factor(&self, theta_i: f32) -> f32 {
        self.factor_at(theta_i, theta_i.sin_cos(), 0.0)
    }

    /// [`Self::factor`] times e^(ln_scale), at a node whose (sin, cos)(theta_i) are known (shared with
    /// its lambda'); ln_scale is the weight's ratio to its Gaussian, joined to the factor's own
    /// exponential. The shape's 2 sin^2((theta_i + theta_o')/2) is 1 - cos(theta_i + theta_o') from the
    /// two angles' sines and cosines, as sin^2 / (1 + cos) near the peak (1 - cos itself would lose
    /// ~1e-7 / v of the logarithm there: 1e-4 at beta = 1 degree; `tests/fast_model.rs` bounds it).
    pub fn factor_at(&self, theta_i: f32, (sin_i, cos_i): (f32, f32), ln_scale: f32) -> f32 {
        let ci = cos_i.max(0.0);
        if self.longitudinal == LONGITUDINAL_PUBLISHED {
            let cd = (0.5 * (self.theta_o - theta_i)).cos();
            return 2.0 * ci * ci / (cd * cd).max(1e-8) * ln_scale.exp();
        }
        let cos_sum = cos_i * self.cos_tilted - sin_i * self.sin_tilted;
        let sin_sum = sin_i * self.cos_tilted + cos_i * self.sin_tilted;
        let d = theta_i - self.mu;
        let ln_rest = -one_minus_cos(sin_sum, cos_sum) / self.v
            + self.ln_m_norm
            + d * d / (2.0 * self.v)
            + self.ln_gaussian_norm;
        ci * bessel_i0_scaled(self.bessel_argument(ci))
            * (ln_rest.clamp(-80.0, 20.0) + ln_scale).exp()
    }
}

/// ln M_p(theta_i, theta_o) of d'Eon et al. 2011 with variance v and the tilt 2 alpha on the outgoing inclination
/// (f32 twin of [`crate::scattering::marschner::ln_longitudinal_deon`]).
pub fn ln_longitudinal_deon(v: f32, theta_i: f32, theta_o: f32, alpha: f32) -> f32 {
    LongitudinalLobe::with_variance(0, theta_o, alpha, v).ln_m(theta_i)
}

/// The smooth factor of the outer integral at theta_i: the longitudinal factor ([`LongitudinalLobe::factor`])
/// times calN_t.
/// `cos_theta_j`: the light's cos(theta_j), found once for its nodes; (sin, cos)(theta_i) the node's,
/// shared with its weight; `ln_scale` the weight's ratio to the quadrature's Gaussian
/// ([`LongitudinalLobe::factor_at`]).
#[allow(clippy::too_many_arguments)]
pub fn outer_integrand(
    luts: &Luts,
    table: &AzimuthalTable,
    p: &FastHairParams,
    lobe: u32,
    light: SrbfInFrame,
    cos_theta_j: f32,
    phi_o: f32,
    longitudinal: &LongitudinalLobe,
    theta_i: f32,
    (sin_i, cos_i): (f32, f32),
    ln_scale: f32,
) -> Rgb32 {
    let theta_d = 0.5 * (longitudinal.theta_o - theta_i);
    let lp = azimuthal_bandwidth(light.lambda, cos_i, cos_theta_j);
    let w = longitudinal.factor_at(theta_i, (sin_i, cos_i), ln_scale);
    // An inner node clipped onto a pole (the quadrature skips the end nodes themselves).
    if w == 0.0 {
        return [0.0; 3];
    }
    let dphi = phi_o - light.phi;
    if lobe == 0 {
        let n = inner_integral_r(luts, p.eta, theta_d, lp, dphi);
        return [w * n; 3];
    }
    let sigma = p.sigma_a_rgb();
    // TT and TRT: the tabulated exact window integral at every lambda' (Xu's circular-Gaussian fits,
    // `tt_lobe` and `trt_lobes`, are kept as the published form and its tests).
    // TRT's eta*-bar (Xu Eq. 26); TT reads the table's own eta.
    let eta = if lobe == 1 {
        p.eta
    } else {
        eta_star_mean(luts, p.eta, p.eccentricity, lp, light.phi + phi_o)
    };
    table
        .window_gaussian(lobe, eta, sigma, theta_d, lp, dphi)
        .map(|n| w * n)
}

/// The longitudinal weight w(theta_i) = M_t(theta_h) g^c(theta_i; theta_j, lambda_j) of one lobe, in Laplace
/// form: its peak theta*, the bandwidth lambda* of the Gaussian with the same curvature there, and ln w(theta*).
/// M_t is taken as the Gaussian g(theta_i; mu_M, 2 sqrt(2) beta_t) around [`LongitudinalLobe::mu`] (published:
/// exactly M_t(theta_h) = g / (sqrt(2 pi) beta_t), Xu Eq. 7); [`LongitudinalLobe::factor`] carries the rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LongitudinalWeight {
    pub kappa_j: f32,
    /// sin(theta_j) and cos(theta_j) of the light: found once for the peak and every node.
    pub sin_j: f32,
    pub cos_j: f32,
    pub mu_m: f32,
    pub lambda_m: f32,
    pub peak: f32,
    pub lambda: f32,
    pub ln_w_peak: f32,
}

impl LongitudinalWeight {
    /// ln w(theta) without the 1 / (sqrt(2 pi) beta) factor:
    /// kappa_j (cos(theta - theta_j) - 1) - ((theta - mu_M) / lambda_M)^2.
    pub fn ln_w(&self, theta: f32) -> f32 {
        self.ln_w_at(theta, theta.sin_cos())
    }

    /// [`Self::ln_w`] at a quadrature node whose (sin, cos)(theta) are known: cos and sin of
    /// theta - theta_j by the difference formulas with the light's (no cosine per node; the peak's is
    /// found the same way, so the nodes' ratios to it share its rounding).
    pub fn ln_w_at(&self, theta: f32, (sin_t, cos_t): (f32, f32)) -> f32 {
        let c = cos_t * self.cos_j + sin_t * self.sin_j;
        let s = sin_t * self.cos_j - cos_t * self.sin_j;
        self.ln_w_from(theta, s, c)
    }

    /// Whether the weight's mass, e^(ln w(theta*)) lambda*, is under e^NEGLIGIBLE_LN_WEIGHT of lambda_M,
    /// the lobe's own (its weight under a light of 1 everywhere; WGSL twin:
    /// `longitudinal_weight_negligible`).
    pub fn negligible(&self) -> bool {
        self.ln_w_peak + (self.lambda / self.lambda_m).ln() < NEGLIGIBLE_LN_WEIGHT
    }

    fn ln_w_from(&self, theta: f32, sin_d: f32, cos_d: f32) -> f32 {
        let d = (theta - self.mu_m) / self.lambda_m;
        -self.kappa_j * one_minus_cos(sin_d, cos_d) - d * d
    }
}

/// A light's lobe is skipped when its longitudinal weight carries less than e^NEGLIGIBLE_LN_WEIGHT
/// (8.3e-7) of the lobe's own mass lambda_M, its weight under a light of 1 everywhere
/// ([`LongitudinalWeight::negligible`]: a narrow light far from the lobe in theta; relative to the
/// same light centred on the lobe, whose mass is about lambda_j for a narrow one, the cut is
/// e^-14 lambda_M / lambda_j: 6e-5 for beta_R = 7.5 degrees and lambda_j = 0.005). Measured over the
/// 200 views and tangents of `bench-fast`, the radiance a point loses is at most 1e-7 of its total under
/// the sunny sky, 1e-6 overcast and 4e-5 in the studio (whose 40 lights include many narrow ones), and
/// 9 %, 6 % and 21 % of the light-lobe pairs are skipped.
pub const NEGLIGIBLE_LN_WEIGHT: f32 = -14.0;

/// Newton's search for the weight's peak stops after a step below this (radians). It converges
/// quadratically: the peak left is within ~1e-6 lambda* of the converged one (the 24000 light-lobe pairs
/// of `bench-fast`, against a 1e-6 stop; 1.6 steps on average where that stop takes 2.2).
pub const PEAK_STEP_TOLERANCE: f32 = 1e-3;

/// Finds theta* by Newton's method on
/// d ln w / d theta = -kappa_j sin(theta - theta_j) - 2 (theta - mu_M) / lambda_M^2,
/// started from the product of Gaussians Xu uses (g^c replaced by g). When the curvature
/// kappa_j cos(theta* - theta_j) + 2 / lambda_M^2 is not clearly positive (a wide light centred more than
/// 90 degrees away), the light is smooth over the lobe and the weight is M_t alone (lambda* = lambda_M).
pub fn longitudinal_weight(
    theta_j: f32,
    lambda_j: f32,
    mu_m: f32,
    lambda_m: f32,
) -> LongitudinalWeight {
    let kappa_j = 2.0 / (lambda_j * lambda_j);
    let k_m = 2.0 / (lambda_m * lambda_m);
    let (_, t0, _) = gaussian_product(theta_j, lambda_j, mu_m, lambda_m);
    let mut t = t0;
    let mut curvature = 0.0;
    for _ in 0..10 {
        let (s, c) = (t - theta_j).sin_cos();
        let grad = -kappa_j * s - k_m * (t - mu_m);
        curvature = kappa_j * c + k_m;
        if curvature <= 0.25 * k_m {
            break;
        }
        let step = (grad / curvature).clamp(-0.3, 0.3);
        t += step;
        if step.abs() < PEAK_STEP_TOLERANCE {
            break;
        }
    }
    let (sin_j, cos_j) = theta_j.sin_cos();
    let mut w = LongitudinalWeight {
        kappa_j,
        sin_j,
        cos_j,
        mu_m,
        lambda_m,
        peak: t,
        lambda: 0.0,
        ln_w_peak: 0.0,
    };
    if curvature <= 0.25 * k_m || !t.is_finite() {
        w.peak = mu_m;
        w.lambda = lambda_m;
        w.ln_w_peak = 0.0; // the ratio w / g(theta; mu_M, lambda_M) is the light's g^c itself
        return w;
    }
    // ln w ~ ln w(theta*) - (curvature / 2) (theta - theta*)^2, i.e. a Gaussian of bandwidth sqrt(2 / curvature).
    w.lambda = (2.0 / curvature).sqrt();
    w.ln_w_peak = w.ln_w(t);
    w
}

/// M_t for lobe t (0 = R, 1 = TT, 2 = TRT), RGB (Xu Eq. 11 by Sec. 4.2.2).
///
/// Xu replaces the light's g^c(theta_i; theta_j, lambda_j) by the Gaussian g(theta_i; theta_j, lambda_j) and
/// integrates the smooth factor against the product Gaussian g M_t. That is exact for narrow lights but
/// off by large factors for wide ones far from the lobe (g^c / g = exp((2 (cos D - 1) + D^2) / lambda_j^2)
/// reaches 20 at D = 2.6, lambda_j = 1). Here the weight w = g^c M_t is kept exact: the quadrature runs
/// against the Gaussian with w's peak and curvature ([`longitudinal_weight`]) and the ratio of w to that
/// Gaussian (1 at the peak, smooth around it) joins the interpolated factor.
pub fn srbf_response_lobe(
    luts: &Luts,
    table: &AzimuthalTable,
    p: &FastHairParams,
    lobe: u32,
    light: SrbfInFrame,
    theta_o: f32,
    phi_o: f32,
) -> Rgb32 {
    let longitudinal = LongitudinalLobe::of_lobe(p, lobe, theta_o);
    srbf_response_lobe_in_view(luts, table, p, lobe, &longitudinal, light, phi_o)
}

/// The three lobes' longitudinal functions seen from theta_o: they depend on the hair's parameters and
/// the view only, so a shading point finds them once for all its lights (WGSL twin: `view_lobes`).
pub fn view_lobes(p: &FastHairParams, theta_o: f32) -> [LongitudinalLobe; 3] {
    std::array::from_fn(|t| LongitudinalLobe::of_lobe(p, t as u32, theta_o))
}

/// [`srbf_response_lobe`] with the lobe's longitudinal function of the view ([`view_lobes`]).
pub fn srbf_response_lobe_in_view(
    luts: &Luts,
    table: &AzimuthalTable,
    p: &FastHairParams,
    lobe: u32,
    longitudinal: &LongitudinalLobe,
    light: SrbfInFrame,
    phi_o: f32,
) -> Rgb32 {
    let beta = p.beta[lobe as usize];
    let lambda_m = 2.0 * std::f32::consts::SQRT_2 * beta;
    let w = longitudinal_weight(light.theta, light.lambda, longitudinal.mu, lambda_m);
    // The unit-area Gaussian of standard deviation 2 beta in theta_i; the longitudinal factor holds the rest.
    // A scale under 1e-30 is negligible too (ln w(theta*) < -67 for any beta below 10^22, and
    // lambda* < 2 lambda_M).
    if w.negligible() {
        return [0.0; 3];
    }
    let scale = w.ln_w_peak.exp() / ((2.0 * PI).sqrt() * 2.0 * beta);
    linear_quadrature(p.quadrature_segments, w.peak, w.lambda, |ti| {
        let (sin_i, cos_i) = ti.sin_cos();
        let d = (ti - w.peak) / w.lambda;
        let ln_w = w.ln_w_at(ti, (sin_i, cos_i));
        let ln_ratio = (ln_w - w.ln_w_peak + d * d).clamp(-80.0, 20.0);
        outer_integrand(
            luts,
            table,
            p,
            lobe,
            light,
            w.cos_j,
            phi_o,
            longitudinal,
            ti,
            (sin_i, cos_i),
            ln_ratio,
        )
    })
    // The parabolas may dip below zero where f vanishes; the response cannot.
    .map(|v| (scale * v).max(0.0))
}

/// M_R, M_TT, M_TRT (RGB each).
pub fn srbf_response(
    luts: &Luts,
    table: &AzimuthalTable,
    p: &FastHairParams,
    light: SrbfInFrame,
    theta_o: f32,
    phi_o: f32,
) -> [Rgb32; 3] {
    srbf_response_in_view(luts, table, p, &view_lobes(p, theta_o), light, phi_o)
}

/// [`srbf_response`] with the view's longitudinal functions ([`view_lobes`]).
pub fn srbf_response_in_view(
    luts: &Luts,
    table: &AzimuthalTable,
    p: &FastHairParams,
    lobes: &[LongitudinalLobe; 3],
    light: SrbfInFrame,
    phi_o: f32,
) -> [Rgb32; 3] {
    std::array::from_fn(|t| {
        srbf_response_lobe_in_view(luts, table, p, t as u32, &lobes[t], light, phi_o)
    })
}
