//! Circular-Gaussian primitives of Xu et al. 2011's fast model, in f32 exactly as the WGSL twins
//! compute them (same names; docs/hair-model.md, "Three Gaussian widths").
//!
//! - Circular Gaussian g^c(x; mu, lambda) = exp(2 (cos(x - mu) - 1) / lambda^2) = exp(kappa (cos(x - mu) - 1)),
//!   kappa = 2 / lambda^2.
//! - Xu's 1D Gaussian g(x; mu, lambda) = exp(-(x - mu)^2 / lambda^2) (lambda = sqrt(2) x standard deviation).

use std::f32::consts::PI;

/// g^c(x; mu, lambda).
pub fn circular_gaussian(x: f32, mu: f32, lambda: f32) -> f32 {
    (2.0 * ((x - mu).cos() - 1.0) / (lambda * lambda)).exp()
}

/// asin to f32 precision by the same rational form as the WGSL twin (Cephes asinf), so CPU and GPU round
/// alike: Vulkan lets a built-in asin be off by thousands of ULP, which narrow lights amplify.
#[allow(clippy::excessive_precision)] // the published coefficients, verbatim
pub fn asin_precise(x: f32) -> f32 {
    let a = x.abs();
    let p = |z: f32| {
        (((4.2163199048e-2 * z + 2.4181311049e-2) * z + 4.5470025998e-2) * z + 7.4953002686e-2) * z
            + 1.6666752422e-1
    };
    let r = if a < 0.5 {
        let z = a * a;
        a + a * z * p(z)
    } else {
        let z = 0.5 * (1.0 - a.min(1.0));
        let s = z.sqrt();
        std::f32::consts::FRAC_PI_2 - 2.0 * (s + s * z * p(z))
    };
    r.copysign(x)
}

/// I0(x) e^-x, the exponentially scaled modified Bessel function of the first kind, order 0
/// (Abramowitz & Stegun 9.8.1 for x <= 3.75, 9.8.2 for x > 3.75; relative error < 2e-7).
/// Scaled so large kappa does not overflow.
#[allow(clippy::excessive_precision)] // the published coefficients, verbatim
pub fn bessel_i0_scaled(x: f32) -> f32 {
    let ax = x.abs();
    if ax <= 3.75 {
        let t = (ax / 3.75) * (ax / 3.75);
        let i0 = 1.0
            + t * (3.5156229
                + t * (3.0899424
                    + t * (1.2067492 + t * (0.2659732 + t * (0.0360768 + t * 0.0045813)))));
        i0 * (-ax).exp()
    } else {
        let t = 3.75 / ax;
        let p = 0.39894228
            + t * (0.01328592
                + t * (0.00225319
                    + t * (-0.00157565
                        + t * (0.00916281
                            + t * (-0.02057706
                                + t * (0.02635537 + t * (-0.01647633 + t * 0.00392377)))))));
        p / ax.sqrt()
    }
}

/// integral over a full period of g^c(x; mu, lambda) = 2 pi e^-kappa I0(kappa) (exact; tends to
/// sqrt(pi) lambda for small lambda, Xu's approximation).
pub fn circular_gaussian_integral(lambda: f32) -> f32 {
    2.0 * PI * bessel_i0_scaled(2.0 / (lambda * lambda))
}

/// The product g^c(x; mu1, lambda1) g^c(x; mu2, lambda2) = scale g^c(x; mu, lambda):
/// kappa e^(i mu) = kappa1 e^(i mu1) + kappa2 e^(i mu2), scale = exp(kappa - kappa1 - kappa2).
/// Returns (scale, mu, lambda); lambda is infinite (a constant) when the two cancel exactly.
pub fn circular_gaussian_product(
    mu1: f32,
    lambda1: f32,
    mu2: f32,
    lambda2: f32,
) -> (f32, f32, f32) {
    let (k1, k2) = (2.0 / (lambda1 * lambda1), 2.0 / (lambda2 * lambda2));
    let re = k1 * mu1.cos() + k2 * mu2.cos();
    let im = k1 * mu1.sin() + k2 * mu2.sin();
    let k = (re * re + im * im).sqrt();
    let mu = im.atan2(re);
    let lambda = if k > 0.0 {
        (2.0 / k).sqrt()
    } else {
        f32::INFINITY
    };
    ((k - k1 - k2).exp(), mu, lambda)
}

/// Abramowitz & Stegun 7.1.26: erf(x) = 1 - (a1 t + ... + a5 t^5) e^(-x^2), t = 1 / (1 + p x), x >= 0,
/// |error| <= 1.5e-7 in exact arithmetic.
const ERF_P: f64 = 0.3275911;
const ERF_A: [f64; 5] = [
    0.254829592,
    -0.284496736,
    1.421413741,
    -1.453152027,
    1.061405429,
];

/// erf(x) by A&S 7.1.26 in f32, as WGSL (which has no erf) computes it: the published 1.5e-7 plus
/// f32 rounding near erf = 1, about 2.5e-7 in all (tested).
pub fn erf_approx(x: f32) -> f32 {
    GaussianEnd::at(x).erf
}

/// One end u of a Gaussian's segment: erf(u) ([`erf_approx`]) and e^(-u^2), which share the one
/// exponential. A quadrature's segments share their ends, so it finds each end once (WGSL twin:
/// `gaussian_end`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussianEnd {
    pub u: f32,
    pub erf: f32,
    /// e^(-u^2).
    pub gauss: f32,
}

impl GaussianEnd {
    pub fn at(u: f32) -> Self {
        let a = u.abs();
        let t = 1.0 / (1.0 + ERF_P as f32 * a);
        let [a1, a2, a3, a4, a5] = ERF_A.map(|c| c as f32);
        let poly = t * (a1 + t * (a2 + t * (a3 + t * (a4 + t * a5))));
        let gauss = (-a * a).exp();
        Self {
            u,
            erf: u.signum() * (1.0 - poly * gauss),
            gauss,
        }
    }
}

/// The same formula in f64, to check the published bound itself.
pub fn erf_approx_f64(x: f64) -> f64 {
    let a = x.abs();
    let t = 1.0 / (1.0 + ERF_P * a);
    let [a1, a2, a3, a4, a5] = ERF_A;
    let poly = t * (a1 + t * (a2 + t * (a3 + t * (a4 + t * a5))));
    x.signum() * (1.0 - poly * (-a * a).exp())
}

/// integral_a^b (c0 + c1 x) g(x; mu, lambda) dx in closed form, g(x; mu, lambda) = exp(-(x - mu)^2 / lambda^2):
/// the piece of Xu's linear quadrature (Sec. 4.2.2) on one segment.
pub fn gaussian_linear_integral(a: f32, b: f32, mu: f32, lambda: f32, c0: f32, c1: f32) -> f32 {
    let [i0, i1] = gaussian_linear_moments(a, b, mu, lambda);
    (c0 + c1 * mu) * i0 + c1 * i1
}

/// The moments (integral g, integral (x - mu) g) over [a, b] of [`gaussian_linear_integral`], computed once
/// for the three channels of a segment.
pub fn gaussian_linear_moments(a: f32, b: f32, mu: f32, lambda: f32) -> [f32; 2] {
    let (ua, ub) = ((a - mu) / lambda, (b - mu) / lambda);
    let sqrt_pi = PI.sqrt();
    // integral g = (sqrt(pi) lambda / 2) (erf(ub) - erf(ua));
    // integral (x - mu) g = (lambda^2 / 2) (e^-ua^2 - e^-ub^2).
    [
        0.5 * sqrt_pi * lambda * (erf_approx(ub) - erf_approx(ua)),
        0.5 * lambda * lambda * ((-ua * ua).exp() - (-ub * ub).exp()),
    ]
}

/// integral_a^b (d0 + d1 y + d2 y^2) g(x; mu, lambda) dx with y = x - mu, in closed form (the quadratic
/// pieces of the quadrature). With u = y / lambda: integral e^(-u^2) = (sqrt(pi)/2)(erf ub - erf ua),
/// integral u e^(-u^2) = (e^(-ua^2) - e^(-ub^2))/2, integral u^2 e^(-u^2) = (1/2) integral e^(-u^2) - [u e^(-u^2)/2].
pub fn gaussian_quadratic_integral(a: f32, b: f32, mu: f32, lambda: f32, d: [f32; 3]) -> f32 {
    let m = gaussian_quadratic_moments(a, b, mu, lambda);
    d[0] * m[0] + d[1] * m[1] + d[2] * m[2]
}

/// The moments integral y^k g dx (k = 0, 1, 2; y = x - mu) over [a, b] of [`gaussian_quadratic_integral`],
/// computed once for the three channels of a segment pair.
pub fn gaussian_quadratic_moments(a: f32, b: f32, mu: f32, lambda: f32) -> [f32; 3] {
    gaussian_quadratic_moments_between(
        GaussianEnd::at((a - mu) / lambda),
        GaussianEnd::at((b - mu) / lambda),
        lambda,
    )
}

/// [`gaussian_quadratic_moments`] between two ends u = (x - mu) / lambda found already.
pub fn gaussian_quadratic_moments_between(a: GaussianEnd, b: GaussianEnd, lambda: f32) -> [f32; 3] {
    let m0 = 0.5 * PI.sqrt() * (b.erf - a.erf);
    let m1 = 0.5 * (a.gauss - b.gauss);
    let m2 = 0.5 * m0 - 0.5 * (b.u * b.gauss - a.u * a.gauss);
    [
        lambda * m0,
        lambda * lambda * m1,
        lambda * lambda * lambda * m2,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scattering::numeric::integrate_piecewise_relative;

    #[test]
    fn bessel_against_its_integral_definition() {
        // I0(x) e^-x = (1/pi) integral_0^pi exp(x (cos t - 1)) dt.
        let mut worst = 0f64;
        for k in 0..200 {
            let x = 0.01 * 1.06f64.powi(k);
            let exact = integrate_piecewise_relative(
                &|t: f64| (x * (t.cos() - 1.0)).exp(),
                &[0.0, 0.5, std::f64::consts::PI],
                1e-12,
            ) / std::f64::consts::PI;
            let got = bessel_i0_scaled(x as f32) as f64;
            worst = worst.max(((got - exact) / exact).abs());
        }
        assert!(worst < 1e-6, "worst relative error {worst:e}");
    }

    #[test]
    fn period_integral_and_small_lambda_limit() {
        for lambda in [0.05f32, 0.3, 1.0, 3.0] {
            let exact = integrate_piecewise_relative(
                &|x: f64| (2.0 * (x.cos() - 1.0) / (lambda as f64 * lambda as f64)).exp(),
                &[-std::f64::consts::PI, 0.0, std::f64::consts::PI],
                1e-12,
            );
            let got = circular_gaussian_integral(lambda) as f64;
            assert!(
                ((got - exact) / exact).abs() < 1e-6,
                "lambda {lambda}: {got} vs {exact}"
            );
        }
        let l = 0.02f32;
        assert!((circular_gaussian_integral(l) / (PI.sqrt() * l) - 1.0).abs() < 1e-3);
    }

    #[test]
    fn product_of_circular_gaussians_is_one() {
        let (s, mu, l) = circular_gaussian_product(0.3, 0.5, -1.1, 0.8);
        for k in 0..50 {
            let x = -PI + 2.0 * PI * k as f32 / 50.0;
            let direct = circular_gaussian(x, 0.3, 0.5) * circular_gaussian(x, -1.1, 0.8);
            let fused = s * circular_gaussian(x, mu, l);
            assert!(
                (direct - fused).abs() <= 1e-6 + 1e-5 * direct,
                "{x}: {direct} vs {fused}"
            );
        }
    }

    #[test]
    fn erf_and_segment_integral_against_quadrature() {
        let (mut worst, mut worst64) = (0f64, 0f64);
        for k in 0..400 {
            let x = -4.0 + 8.0 * k as f64 / 399.0;
            // erf(x) = sign(x) (2 / sqrt(pi)) integral_0^|x| e^(-t^2) dt.
            let exact = if x == 0.0 {
                0.0
            } else {
                x.signum() * 2.0 / std::f64::consts::PI.sqrt()
                    * integrate_piecewise_relative(&|t: f64| (-t * t).exp(), &[0.0, x.abs()], 1e-13)
            };
            worst = worst.max((erf_approx(x as f32) as f64 - exact).abs());
            worst64 = worst64.max((erf_approx_f64(x) - exact).abs());
        }
        println!(
            "erf A&S 7.1.26: worst absolute error {worst64:.2e} in f64, {worst:.2e} in f32, over [-4, 4]"
        );
        assert!(worst64 <= 1.5e-7, "the published bound: {worst64:e}");
        assert!(worst <= 3e-7, "f32 evaluation: {worst:e}");
        for &(a, b, mu, l, c0, c1) in &[
            (-1.0f32, 0.5f32, 0.1f32, 0.3f32, 0.7f32, -0.4f32),
            (0.2, 1.4, 1.0, 0.05, 1.0, 2.0),
            (-1.5, 1.5, 0.0, 2.0, 0.0, 1.0),
        ] {
            let exact = integrate_piecewise_relative(
                &|x: f64| {
                    (c0 as f64 + c1 as f64 * x)
                        * (-(x - mu as f64).powi(2) / (l as f64).powi(2)).exp()
                },
                &[a as f64, mu.clamp(a, b) as f64, b as f64],
                1e-12,
            );
            let got = gaussian_linear_integral(a, b, mu, l, c0, c1) as f64;
            assert!(
                (got - exact).abs() < 2e-6 * (1.0 + exact.abs()),
                "{a} {b}: {got} vs {exact}"
            );
        }
    }
}
