// calN_TT and calN_TRT under narrow lights from the exact N_p (and calN_t^G over a box window).
// Twin of src/scattering/fast_exact_azimuthal.rs.

const EXACT_BLEND_LO: f32 = 0.7;
const EXACT_BLEND_HI: f32 = 1.4;
const EXACT_WINDOW: f32 = 3.5;
const EXACT_PANELS: u32 = 2u;

const GL8_X = array<f32, 8>(-0.9602899, -0.7966665, -0.5255324, -0.18343464, 0.18343464, 0.5255324, 0.7966665, 0.9602899);
const GL8_W = array<f32, 8>(0.10122854, 0.22238103, 0.31370665, 0.36268378, 0.36268378, 0.31370665, 0.22238103, 0.10122854);

// Phi(p, t) = 2 p asin(sin t / eta') - 2 t + p pi.
fn exit_azimuth(p: u32, t: f32, eta_p: f32) -> f32 {
    let pf = f32(p);
    return 2.0 * pf * asin_precise(sin(t) / eta_p) - 2.0 * t + pf * PI;
}

fn exit_azimuth_dt(p: u32, t: f32, eta_p: f32) -> f32 {
    let s = sin(t);
    return 2.0 * f32(p) * cos(t) / sqrt(eta_p * eta_p - s * s) - 2.0;
}

// t in [a, b] with Phi(t) = goal (Phi monotone on [a, b]).
fn invert_exit_azimuth(p: u32, eta_p: f32, a: f32, b: f32, goal: f32) -> f32 {
    let increasing = exit_azimuth(p, b, eta_p) >= exit_azimuth(p, a, eta_p);
    var lo = select(b, a, increasing);
    var hi = select(a, b, increasing);
    var t = 0.5 * (a + b);
    for (var it = 0; it < 24; it++) {
        let g = exit_azimuth(p, t, eta_p) - goal;
        if (g <= 0.0) {
            lo = t;
        } else {
            hi = t;
        }
        let d = exit_azimuth_dt(p, t, eta_p);
        var next = t - g / d;
        let l = min(lo, hi);
        let u = max(lo, hi);
        if (!(next > l && next < u) || abs(d) < 1e-6) {
            next = 0.5 * (lo + hi);
        }
        if (abs(next - t) < 1e-7) {
            return next;
        }
        t = next;
    }
    return t;
}

// A_p(h) / 2: R F, TT (1-F)^2 T, TRT (1-F)^2 F T^2.
fn half_attenuation(p: u32, eta: f32, cos_d: f32, eta_p: f32, sigma_p: vec3<f32>, h: f32) -> vec3<f32> {
    let f = fresnel_schlick(eta, cos_d, h);
    let t = attenuation_exact(sigma_p, eta_p, h);
    if (p == 0u) {
        return vec3<f32>(0.5 * f);
    }
    if (p == 1u) {
        return 0.5 * (1.0 - f) * (1.0 - f) * t;
    }
    return 0.5 * (1.0 - f) * (1.0 - f) * f * t * t;
}

// integral over |x| <= half_width of k(x) N_p(theta_d, dphi - x) dx, k = g^c(x; 0, lambda') (kappa = 2/lambda'^2) or 1 (kappa = 0).
fn azimuthal_window_integral(p: u32, eta: f32, sigma_a: vec3<f32>, theta_d: f32, dphi: f32, kappa: f32, half_width: f32) -> vec3<f32> {
    let eta_p = bravais_eta_prime(eta, theta_d);
    let cos_d = cos(theta_d);
    let sigma_p = sigma_a_prime(sigma_a, eta, theta_d);
    let w = min(half_width, PI);
    var ends = array<f32, 4>(-FRAC_PI_2, FRAC_PI_2, FRAC_PI_2, FRAC_PI_2);
    var pieces = 1u;
    if (p == 2u && eta_p < 2.0) {
        let tc = asin_precise(sqrt((4.0 - eta_p * eta_p) / 3.0));
        ends = array<f32, 4>(-FRAC_PI_2, -tc, tc, FRAC_PI_2);
        pieces = 3u;
    }
    var out = vec3<f32>(0.0);
    for (var k = 0u; k < pieces; k++) {
        let a = ends[k];
        let b = ends[k + 1u];
        let pa = exit_azimuth(p, a, eta_p);
        let pb = exit_azimuth(p, b, eta_p);
        let lo = min(pa, pb);
        let hi = max(pa, pb);
        let m0 = i32(ceil((lo - (dphi + w)) / TAU));
        let m1 = i32(floor((hi - (dphi - w)) / TAU));
        for (var m = m0; m <= m1; m++) {
            let c = dphi + TAU * f32(m);
            let wl = max(c - w, lo);
            let wh = min(c + w, hi);
            if (wh <= wl) {
                continue;
            }
            let ta = invert_exit_azimuth(p, eta_p, a, b, wl);
            let tb = invert_exit_azimuth(p, eta_p, a, b, wh);
            let t0 = min(ta, tb);
            let t1 = max(ta, tb);
            let half = 0.5 * (t1 - t0) / f32(EXACT_PANELS);
            for (var panel = 0u; panel < EXACT_PANELS; panel++) {
                let mid = t0 + half * f32(2u * panel + 1u);
                for (var i = 0u; i < 8u; i++) {
                    let t = mid + half * GL8_X[i];
                    var g = 1.0;
                    if (kappa > 0.0) {
                        // cos x - 1 = -2 sin^2(x/2), without the cancellation that kappa ~ 1e3 amplifies.
                        let s = sin(0.5 * (exit_azimuth(p, t, eta_p) - c));
                        g = exp(-2.0 * kappa * s * s);
                    }
                    let a_half = half_attenuation(p, eta, cos_d, eta_p, sigma_p, sin(t));
                    out = out + half * GL8_W[i] * g * cos(t) * a_half;
                }
            }
        }
    }
    return out;
}

fn inner_integral_exact(p: u32, eta: f32, sigma_a: vec3<f32>, theta_d: f32, lambda_prime: f32, dphi: f32) -> vec3<f32> {
    let kappa = 2.0 / (lambda_prime * lambda_prime);
    return azimuthal_window_integral(p, eta, sigma_a, theta_d, dphi, kappa, min(EXACT_WINDOW * lambda_prime, PI));
}

// calN_TT (p = 1) or calN_TRT (p = 2): exact under narrow lights, the fit under wide ones.
fn inner_integral_blended(p: u32, eta: f32, sigma_a: vec3<f32>, theta_d: f32, lambda_prime: f32, dphi: f32, caustic_width: f32, caustic_fade: f32) -> vec3<f32> {
    let t = smoothstep_f(EXACT_BLEND_LO, EXACT_BLEND_HI, lambda_prime);
    var out = vec3<f32>(0.0);
    if (t > 0.0) {
        var fit: LobeFit;
        if (p == 1u) {
            fit.lobes[0] = tt_lobe(eta, sigma_a, theta_d);
            fit.count = 1u;
        } else {
            fit = trt_lobes(eta, sigma_a, theta_d, caustic_width, caustic_fade);
        }
        out = out + t * inner_integral_lobes(fit, lambda_prime, dphi);
    }
    if (t < 1.0) {
        out = out + (1.0 - t) * inner_integral_exact(p, eta, sigma_a, theta_d, lambda_prime, dphi);
    }
    return out;
}
