// Xu 2011 Sec. 4.2: the single-scattering response of one SRBF light per lobe.
// Twin of src/scattering/fast_response.rs (and the FastHairParams layout of fast_params.rs).

struct FastHairParams {
    sigma_a: vec4<f32>,
    alpha: vec4<f32>,
    beta: vec4<f32>,
    eta: f32,
    eccentricity: f32,
    caustic_width: f32,
    caustic_fade: f32,
    quadrature_segments: u32,
    d_f: f32,
    d_b: f32,
    // 0: d'Eon et al. 2011's normalised M (LONGITUDINAL_NORMALIZED); 1: published (LONGITUDINAL_PUBLISHED).
    longitudinal: u32,
}

const LONGITUDINAL_PUBLISHED: u32 = 1u;

struct SrbfInFrame {
    theta: f32,
    phi: f32,
    lambda: f32,
}

const LAMBDA_PRIME_MAX: f32 = 10.0;

// g(x; mu1, l1) g(x; mu2, l2) = scale g(x; mu, l): returns (scale, mu, l).
fn gaussian_product(mu1: f32, l1: f32, mu2: f32, l2: f32) -> vec3<f32> {
    let a = l1 * l1;
    let b = l2 * l2;
    let s = a + b;
    let d = mu1 - mu2;
    return vec3<f32>(exp(-d * d / s), (mu1 * b + mu2 * a) / s, sqrt(a * b / s));
}

// Sample s (0..=m) of the quadrature over [-pi/2, pi/2] for a Gaussian (mu, lambda).
fn quadrature_sample(s: u32, m: u32, mu: f32, lambda: f32) -> f32 {
    if (s == 0u) {
        return -FRAC_PI_2;
    }
    if (s >= m) {
        return FRAC_PI_2;
    }
    let half = 0.5 * (f32(m) - 2.0) * lambda;
    let lo_raw = mu - half;
    let hi_raw = mu + half;
    let lo_clipped = lo_raw <= -FRAC_PI_2;
    let hi_clipped = hi_raw >= FRAC_PI_2;
    let lo = clamp(lo_raw, -FRAC_PI_2, FRAC_PI_2);
    let hi = clamp(hi_raw, -FRAC_PI_2, FRAC_PI_2);
    let inner = m - 1u;
    let denom = (inner - 1u) + select(0u, 1u, lo_clipped) + select(0u, 1u, hi_clipped);
    if (denom == 0u) {
        return clamp(mu, -FRAC_PI_2, FRAC_PI_2);
    }
    let k = (s - 1u) + select(0u, 1u, lo_clipped);
    return lo + (hi - lo) * f32(k) / f32(denom);
}

// lambda' = lambda_j / sqrt(cos theta_i cos theta_j) from cos theta_i (the node's, shared with its
// longitudinal factor) and cos theta_j (the light's, once for its nodes).
fn azimuthal_bandwidth(lambda_j: f32, cos_theta_i: f32, cos_theta_j: f32) -> f32 {
    let c = max(cos_theta_i * cos_theta_j, 1e-8);
    return min(lambda_j / sqrt(c), LAMBDA_PRIME_MAX);
}

// theta_o' = theta_o - 2 alpha, reflected back into [-pi/2, pi/2] past a pole.
fn tilted_outgoing(theta_o: f32, alpha: f32) -> f32 {
    let t = theta_o - 2.0 * alpha;
    if (t > FRAC_PI_2) {
        return PI - t;
    }
    if (t < -FRAC_PI_2) {
        return -PI - t;
    }
    return t;
}

// x beyond which 1 - e^(-x) rounds to 1 in f32 (ONE_MINUS_EXP_IS_ONE in fast_response.rs).
const ONE_MINUS_EXP_IS_ONE: f32 = 17.5;

// One lobe's longitudinal function for one view (twin of LongitudinalLobe in fast_response.rs): what does
// not depend on theta_i, computed once per view (view_lobes) instead of at every quadrature sample.
struct LongitudinalLobe {
    longitudinal: u32,
    theta_o: f32,
    tilted: f32,
    v: f32,
    // Centre of the quadrature's Gaussian: published 2 alpha - theta_o, normalised -theta_o'.
    mu: f32,
    // -ln v - ln(1 - e^(-2/v)), and ln sqrt(2 pi v).
    ln_m_norm: f32,
    ln_gaussian_norm: f32,
    cos_tilted: f32,
    sin_tilted: f32,
}

fn longitudinal_lobe_with_variance(longitudinal: u32, theta_o: f32, alpha: f32, v: f32) -> LongitudinalLobe {
    let tilted = tilted_outgoing(theta_o, alpha);
    var mu = -tilted;
    if (longitudinal == LONGITUDINAL_PUBLISHED) {
        mu = 2.0 * alpha - theta_o;
    }
    let ln_v = log(v);
    // ln(1 - e^(-2/v)) is 0 in f32 past ONE_MINUS_EXP_IS_ONE.
    var ln_csch_part = 0.0;
    if (2.0 / v <= ONE_MINUS_EXP_IS_ONE) {
        ln_csch_part = log(1.0 - exp(-2.0 / v));
    }
    return LongitudinalLobe(longitudinal, theta_o, tilted, v, mu, -ln_v - ln_csch_part, 0.5 * (log(2.0 * PI) + ln_v), cos(tilted), sin(tilted));
}

fn longitudinal_lobe(longitudinal: u32, theta_o: f32, alpha: f32, beta: f32) -> LongitudinalLobe {
    return longitudinal_lobe_with_variance(longitudinal, theta_o, alpha, max(4.0 * beta * beta, 1e-8));
}

// d'Eon's Bessel argument cos theta_i cos theta_o' / v from cos theta_i clamped at 0 (bessel_argument).
fn longitudinal_bessel_argument(l: LongitudinalLobe, cos_theta_i: f32) -> f32 {
    return cos_theta_i * l.cos_tilted / l.v;
}


// The longitudinal factor relative to the Gaussian: published 2 cos^2(theta_i) / cos^2(theta_d); normalised
// cos(theta_i) M^dEon / Gaussian.
fn longitudinal_factor(l: LongitudinalLobe, theta_i: f32) -> f32 {
    return longitudinal_factor_at(l, theta_i, sin(theta_i), cos(theta_i), 0.0);
}

// 1 - cos x as sin^2 x / (1 + cos x) where cos x > 0: no cancellation near x = 0 (one_minus_cos in
// fast_response.rs).
fn one_minus_cos(sin_x: f32, cos_x: f32) -> f32 {
    return select(1.0 - cos_x, sin_x * sin_x / (1.0 + cos_x), cos_x > 0.0);
}

// longitudinal_factor times e^(ln_scale) at a node whose sin and cos are known (factor_at): the shape's
// 2 sin^2((theta_i + theta_o')/2) as 1 - cos(theta_i + theta_o') from the angles' sines and cosines.
fn longitudinal_factor_at(l: LongitudinalLobe, theta_i: f32, sin_i: f32, cos_i: f32, ln_scale: f32) -> f32 {
    let ci = max(cos_i, 0.0);
    if (l.longitudinal == LONGITUDINAL_PUBLISHED) {
        let cd = cos(0.5 * (l.theta_o - theta_i));
        return 2.0 * ci * ci / max(cd * cd, 1e-8) * exp(ln_scale);
    }
    let cos_sum = cos_i * l.cos_tilted - sin_i * l.sin_tilted;
    let sin_sum = sin_i * l.cos_tilted + cos_i * l.sin_tilted;
    let d = theta_i - l.mu;
    let ln_rest = -one_minus_cos(sin_sum, cos_sum) / l.v + l.ln_m_norm + d * d / (2.0 * l.v) + l.ln_gaussian_norm;
    return ci * bessel_i0_scaled(longitudinal_bessel_argument(l, ci)) * exp(clamp(ln_rest, -80.0, 20.0) + ln_scale);
}

// longitudinal_factor x e^(ln_scale) x calN_t at theta_i; cos_theta_j the light's.
// sin_i, cos_i: the node's, shared with its weight.
fn outer_integrand(params: FastHairParams, lobe: u32, light: SrbfInFrame, cos_theta_j: f32, phi_o: f32, longitudinal: LongitudinalLobe, theta_i: f32, sin_i: f32, cos_i: f32, ln_scale: f32) -> vec3<f32> {
    let theta_d = 0.5 * (longitudinal.theta_o - theta_i);
    let lp = azimuthal_bandwidth(light.lambda, cos_i, cos_theta_j);
    let w = longitudinal_factor_at(longitudinal, theta_i, sin_i, cos_i, ln_scale);
    // An inner node clipped onto a pole (the quadrature skips the end nodes themselves).
    if (w == 0.0) {
        return vec3<f32>(0.0);
    }
    let dphi = phi_o - light.phi;
    let sigma = params.sigma_a.xyz;
    if (lobe == 0u) {
        return vec3<f32>(w * inner_integral_r(params.eta, theta_d, lp, dphi));
    }
    // TT and TRT: the tabulated exact window integral at every lambda' (TRT at eta*-bar, Xu Eq. 26).
    if (lobe == 1u) {
        return w * azimuthal_table_gaussian(1u, params.eta, sigma, theta_d, lp, dphi);
    }
    let eta = eta_star_mean(params.eta, params.eccentricity, lp, light.phi + phi_o);
    return w * azimuthal_table_gaussian(2u, eta, sigma, theta_d, lp, dphi);
}

// The weight M_t g^c(theta_i; theta_j, lambda_j) in Laplace form.
struct LongitudinalWeight {
    kappa_j: f32,
    // sin(theta_j) and cos(theta_j) of the light: found once for the peak and every node.
    sin_j: f32,
    cos_j: f32,
    mu_m: f32,
    lambda_m: f32,
    peak: f32,
    lambda: f32,
    ln_w_peak: f32,
}

// ln w from sin and cos of theta - theta_j (LongitudinalWeight::ln_w_from).
fn longitudinal_ln_w_from(w: LongitudinalWeight, theta: f32, sin_d: f32, cos_d: f32) -> f32 {
    let d = (theta - w.mu_m) / w.lambda_m;
    return -w.kappa_j * one_minus_cos(sin_d, cos_d) - d * d;
}

// At a node whose sin and cos are known, with the light's (LongitudinalWeight::ln_w_at): no cosine
// per node.
fn longitudinal_ln_w_at(w: LongitudinalWeight, theta: f32, sin_t: f32, cos_t: f32) -> f32 {
    return longitudinal_ln_w_from(w, theta, sin_t * w.cos_j - cos_t * w.sin_j, cos_t * w.cos_j + sin_t * w.sin_j);
}

// A light's lobe is skipped below this (NEGLIGIBLE_LN_WEIGHT in fast_response.rs).
const NEGLIGIBLE_LN_WEIGHT: f32 = -14.0;

// Whether the weight's mass is under e^NEGLIGIBLE_LN_WEIGHT of lambda_M, the lobe's under a light of
// 1 everywhere (LongitudinalWeight::negligible).
fn longitudinal_weight_negligible(w: LongitudinalWeight) -> bool {
    return w.ln_w_peak + log(w.lambda / w.lambda_m) < NEGLIGIBLE_LN_WEIGHT;
}

// Newton's stop for the weight's peak (radians; PEAK_STEP_TOLERANCE in fast_response.rs).
const PEAK_STEP_TOLERANCE: f32 = 1e-3;

fn longitudinal_weight(theta_j: f32, lambda_j: f32, mu_m: f32, lambda_m: f32) -> LongitudinalWeight {
    let kappa_j = 2.0 / (lambda_j * lambda_j);
    let k_m = 2.0 / (lambda_m * lambda_m);
    var t = gaussian_product(theta_j, lambda_j, mu_m, lambda_m).y;
    var curvature = 0.0;
    for (var it = 0; it < 10; it++) {
        let s = sin(t - theta_j);
        let c = cos(t - theta_j);
        let grad = -kappa_j * s - k_m * (t - mu_m);
        curvature = kappa_j * c + k_m;
        if (curvature <= 0.25 * k_m) {
            break;
        }
        let step = clamp(grad / curvature, -0.3, 0.3);
        t = t + step;
        if (abs(step) < PEAK_STEP_TOLERANCE) {
            break;
        }
    }
    var w = LongitudinalWeight(kappa_j, sin(theta_j), cos(theta_j), mu_m, lambda_m, t, 0.0, 0.0);
    // A peak that is not finite takes the same fallback (the twin's is_finite; a compiler allowed
    // finite maths may drop a NaN test, so this guards infinities for sure; the lights file's
    // lambda bound, SRBF_LAMBDA_MIN, is what keeps the peak finite).
    if (curvature <= 0.25 * k_m || !(abs(t) < 1e30)) {
        w.peak = mu_m;
        w.lambda = lambda_m;
        w.ln_w_peak = 0.0;
        return w;
    }
    w.lambda = sqrt(2.0 / curvature);
    // As at the quadrature's nodes (from sines and cosines), so that their ratios to it share its
    // rounding.
    w.ln_w_peak = longitudinal_ln_w_at(w, t, sin(t), cos(t));
    return w;
}

fn weighted_integrand(params: FastHairParams, lobe: u32, light: SrbfInFrame, phi_o: f32, longitudinal: LongitudinalLobe, w: LongitudinalWeight, ti: f32) -> vec3<f32> {
    let sin_i = sin(ti);
    let cos_i = cos(ti);
    let d = (ti - w.peak) / w.lambda;
    let ln_ratio = clamp(longitudinal_ln_w_at(w, ti, sin_i, cos_i) - w.ln_w_peak + d * d, -80.0, 20.0);
    return outer_integrand(params, lobe, light, w.cos_j, phi_o, longitudinal, ti, sin_i, cos_i, ln_ratio);
}

// The quadrature of Sec. 4.2.2 node by node (twin: Quadrature in fast_response.rs): nodes s = 0..=m are
// fed in order; each even node closes the pair of segments before it with their parabola, a last odd
// node (m odd) its linear segment. One call site of the integrand per quadrature keeps the shading
// shaders small: every call is inlined, and with three call sites per quadrature the segment kernel
// takes lavapipe about 7 s to compile.
struct Quadrature {
    mu: f32,
    l: f32,
    x0: f32,
    // gaussian_end at x0: each node's is found once.
    e0: vec3<f32>,
    f0: vec3<f32>,
    x1: f32,
    f1: vec3<f32>,
    out: vec3<f32>,
}

// Node 0, the pole -pi/2. Every integrand of the quadratures carries the longitudinal factor's
// cos(theta_i) clamped at 0 (longitudinal_factor), so the integrand vanishes at both ends (exactly in
// the Rust twin, where cos(FRAC_PI_2) < 0 in f32; a GPU's cos, accurate to 2^-11, could only have added
// a spurious value there): the ends are not evaluated (an early return there does not save the
// integrands' table reads on lavapipe), only the m - 1 inner nodes, and quadrature_end closes the rule
// at +pi/2.
fn quadrature_start(mu: f32, l: f32) -> Quadrature {
    return Quadrature(mu, l, -FRAC_PI_2, gaussian_end((-FRAC_PI_2 - mu) / l), vec3<f32>(0.0), 0.0, vec3<f32>(0.0), vec3<f32>(0.0));
}

fn quadrature_end(q: ptr<function, Quadrature>, m: u32) {
    quadrature_node(q, m, m, FRAC_PI_2, vec3<f32>(0.0));
}

fn quadrature_node(q: ptr<function, Quadrature>, s: u32, m: u32, x: f32, f: vec3<f32>) {
    let odd = (s & 1u) == 1u;
    if (s > 0u && odd && s < m) {
        // The middle of a pair: kept until its end.
        (*q).x1 = x;
        (*q).f1 = f;
        return;
    }
    let x0 = (*q).x0;
    let f0 = (*q).f0;
    if (s > 0u && x > x0) {
        // The pair's parabola through (x0, x1, x) when its middle lies strictly inside, else the line
        // from x0 (the last node of an odd m, or a pair whose middle was clipped onto an end): one set
        // of moments either way, the line being the parabola with q2 = 0 (Newton form in y = x - mu).
        let x1 = (*q).x1;
        let pair = !odd && x1 > x0 && x > x1;
        let end = gaussian_end((x - (*q).mu) / (*q).l);
        let mo = gaussian_quadratic_moments_between((*q).e0, end, (*q).l);
        (*q).e0 = end;
        let y0 = x0 - (*q).mu;
        var q1 = (f - f0) / (x - x0);
        var q2 = vec3<f32>(0.0);
        var y1 = 0.0;
        if (pair) {
            q1 = ((*q).f1 - f0) / (x1 - x0);
            q2 = ((f - (*q).f1) / (x - x1) - q1) / (x - x0);
            y1 = x1 - (*q).mu;
        }
        (*q).out = (*q).out + (f0 - q1 * y0 + q2 * (y0 * y1)) * mo.x + (q1 - q2 * (y0 + y1)) * mo.y + q2 * mo.z;
    }
    (*q).x0 = x;
    (*q).f0 = f;
}

// M_t for lobe t (0 = R, 1 = TT, 2 = TRT), RGB (Xu Eq. 11 by Sec. 4.2.2, parabolas on paired segments).
fn srbf_response_lobe(params: FastHairParams, lobe: u32, light: SrbfInFrame, theta_o: f32, phi_o: f32) -> vec3<f32> {
    return srbf_response_lobe_in_view(params, lobe, longitudinal_lobe(params.longitudinal, theta_o, params.alpha[lobe], params.beta[lobe]), light, phi_o);
}

// The three lobes' longitudinal functions seen from theta_o (view_lobes): once per shading point.
fn view_lobes(params: FastHairParams, theta_o: f32) -> array<LongitudinalLobe, 3> {
    return array<LongitudinalLobe, 3>(
        longitudinal_lobe(params.longitudinal, theta_o, params.alpha[0], params.beta[0]),
        longitudinal_lobe(params.longitudinal, theta_o, params.alpha[1], params.beta[1]),
        longitudinal_lobe(params.longitudinal, theta_o, params.alpha[2], params.beta[2]),
    );
}

// srbf_response_lobe with the lobe's longitudinal function of the view.
fn srbf_response_lobe_in_view(params: FastHairParams, lobe: u32, longitudinal: LongitudinalLobe, light: SrbfInFrame, phi_o: f32) -> vec3<f32> {
    let beta = params.beta[lobe];
    let lambda_m = 2.0 * SQRT_2 * beta;
    let w = longitudinal_weight(light.theta, light.lambda, longitudinal.mu, lambda_m);
    let scale = exp(w.ln_w_peak) / (sqrt(2.0 * PI) * 2.0 * beta);
    // A negligible light's lobe runs no node (its quadrature stays 0): a loop that no lane of a SIMD
    // group enters is skipped, where lavapipe runs both sides of a branch. (A scale under 1e-30 is
    // negligible too: srbf_response_lobe_in_view in fast_response.rs.)
    let m = select(params.quadrature_segments, 0u, longitudinal_weight_negligible(w));
    var q = quadrature_start(w.peak, w.lambda);
    for (var s = 1u; s < m; s++) {
        let x = quadrature_sample(s, m, q.mu, q.l);
        quadrature_node(&q, s, m, x, weighted_integrand(params, lobe, light, phi_o, longitudinal, w, x));
    }
    quadrature_end(&q, m);
    return max(scale * q.out, vec3<f32>(0.0));
}
