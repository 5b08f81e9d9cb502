// Circular-Gaussian primitives of Xu et al. 2011's fast model.
// Twin of src/scattering/circular_gaussian.rs and the Bessel helper of fast_azimuthal.rs:
// same names, same formulas, f32.

const PI: f32 = 3.14159265358979;
const TAU: f32 = 6.28318530717959;
const FRAC_PI_2: f32 = 1.57079632679490;
const SQRT_2: f32 = 1.41421356237310;
const SQRT_PI: f32 = 1.77245385090552;

// Wraps an angle to [-pi, pi].
fn wrap_angle(x: f32) -> f32 {
    return x - TAU * floor((x + PI) / TAU);
}

// asin to f32 precision (Cephes asinf). Vulkan lets the built-in asin be off by thousands of ULP, and
// exp(kappa (cos(Phi) - 1)) with kappa = 2 / lambda'^2 up to ~1000 amplifies that into percent errors.
fn asin_precise(x: f32) -> f32 {
    let a = abs(x);
    var r: f32;
    if (a < 0.5) {
        let z = a * a;
        r = a + a * z * ((((4.2163199048e-2 * z + 2.4181311049e-2) * z + 4.5470025998e-2) * z + 7.4953002686e-2) * z + 1.6666752422e-1);
    } else {
        let z = 0.5 * (1.0 - min(a, 1.0));
        let s = sqrt(z);
        r = FRAC_PI_2 - 2.0 * (s + s * z * ((((4.2163199048e-2 * z + 2.4181311049e-2) * z + 4.5470025998e-2) * z + 7.4953002686e-2) * z + 1.6666752422e-1));
    }
    return sign(x) * r;
}

// I0(x) e^-x (Abramowitz & Stegun 9.8.1, 9.8.2).
fn bessel_i0_scaled(x: f32) -> f32 {
    let ax = abs(x);
    if (ax <= 3.75) {
        let t = (ax / 3.75) * (ax / 3.75);
        let i0 = 1.0 + t * (3.5156229 + t * (3.0899424 + t * (1.2067492 + t * (0.2659732 + t * (0.0360768 + t * 0.0045813)))));
        return i0 * exp(-ax);
    }
    let t = 3.75 / ax;
    let p = 0.39894228 + t * (0.01328592 + t * (0.00225319 + t * (-0.00157565 + t * (0.00916281
        + t * (-0.02057706 + t * (0.02635537 + t * (-0.01647633 + t * 0.00392377)))))));
    return p / sqrt(ax);
}

// One end u of a Gaussian's segment (GaussianEnd in circular_gaussian.rs): (u, erf(u), e^(-u^2)), the two
// sharing one exponential; erf by A&S 7.1.26 (WGSL has no erf).
fn gaussian_end(u: f32) -> vec3<f32> {
    let a = abs(u);
    let t = 1.0 / (1.0 + 0.3275911 * a);
    let poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    let gauss = exp(-a * a);
    return vec3<f32>(u, sign(u) * (1.0 - poly * gauss), gauss);
}


// integral_a^b y^k g(x; mu, lambda) dx (k = 0, 1, 2; y = x - mu) between two ends found already
// (gaussian_end; gaussian_quadratic_moments_between in circular_gaussian.rs), once per segment pair.
fn gaussian_quadratic_moments_between(a: vec3<f32>, b: vec3<f32>, lambda: f32) -> vec3<f32> {
    let m0 = 0.5 * SQRT_PI * (b.y - a.y);
    let m1 = 0.5 * (a.z - b.z);
    let m2 = 0.5 * m0 - 0.5 * (b.x * b.z - a.x * a.z);
    return vec3<f32>(lambda * m0, lambda * lambda * m1, lambda * lambda * lambda * m2);
}

