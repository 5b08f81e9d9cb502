//! The exact Marschner et al. 2003 hair scattering model on the CPU, in f64.
//!
//! S(omega_i, omega_o) = sum_p M_p(theta_h) N_p(eta'(theta_d), phi) / cos^2(theta_d)   (Marschner Eq. 2)
//! as published ([`LongitudinalModel::Published`]), or by default with d'Eon et al. 2011's normalised
//! longitudinal function ([`LongitudinalModel::Normalized`]):
//!   S(omega_i, omega_o) cos(theta_i) = sum_p M_p(theta_i, theta_o) N_p(eta'(theta_d), phi),
//! integral M_p cos(theta_i) d theta_i = 1, so that integral S cos(theta_i) d omega_i = sum_p integral N_p d phi
//! = (1/2) sum_p integral A_p dh, the energy the three lobes carry (~0.95-1 for sigma_a = 0).
//!
//! This is the reference every fast path is tested against. Angles follow
//! [`crate::scattering::frame`]. Symbols are the paper's; docs/hair-model.md restates them.

use super::frame::{FiberAngles, HalfAngles, wrap_angle};
use super::fresnel::{
    bravais_parallel, bravais_perpendicular, fresnel_bravais, fresnel_schlick_xu,
};
use super::params::{
    CausticModel, FresnelModel, HairParams, Lobe, LongitudinalModel, ModelVariant,
};
use serde::Serialize;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// RGB triple.
pub type Rgb = [f64; 3];

/// Unit-area Gaussian with standard deviation `beta`: g(beta; x) (Marschner's notation).
/// Evaluated as exp of the exponent so very narrow lobes underflow to 0 instead of producing NaN.
pub fn gaussian(beta: f64, x: f64) -> f64 {
    let e = -x * x / (2.0 * beta * beta);
    e.exp() / ((2.0 * PI).sqrt() * beta)
}

/// Longitudinal scattering M_p(theta_h) = g(beta_p; theta_h - alpha_p) (Marschner Sec. 4.1).
pub fn longitudinal_m_p(params: &HairParams, lobe: Lobe, theta_h: f64) -> f64 {
    gaussian(params.beta(lobe), theta_h - params.alpha(lobe))
}

/// I0(x) e^-x for x >= 0 in f64: the power series up to x = 30 (positive terms, no cancellation),
/// the asymptotic series beyond (relative error < 1e-12 on both sides).
pub fn bessel_i0_scaled_f64(x: f64) -> f64 {
    let x = x.abs();
    if x <= 30.0 {
        let q = 0.25 * x * x;
        let (mut term, mut sum) = (1.0f64, 1.0f64);
        for k in 1..200 {
            term *= q / (k * k) as f64;
            sum += term;
            if term < 1e-17 * sum {
                break;
            }
        }
        return sum * (-x).exp();
    }
    // e^x / sqrt(2 pi x) sum_k ((2k - 1)!!)^2 / (k! 8^k x^k)
    let (mut term, mut sum) = (1.0f64, 1.0f64);
    for k in 1..12 {
        let m = (2 * k - 1) as f64;
        term *= m * m / (8.0 * k as f64 * x);
        sum += term;
    }
    sum / (2.0 * PI * x).sqrt()
}

/// The variance v_p = (2 beta_p)^2 of d'Eon's longitudinal function: Marschner's M_p(theta_h) has standard
/// deviation beta_p in theta_h = (theta_i + theta_o)/2, so 2 beta_p in theta_i; both forms have that width.
pub fn deon_variance(beta: f64) -> f64 {
    (4.0 * beta * beta).max(1e-12)
}

/// The centre in theta_i of lobe p's longitudinal function for the outgoing theta_o (where quadratures split):
/// published, 2 alpha_p - theta_o (possibly past a pole, where the lobe is cut); normalised, -theta_o' (d'Eon's
/// peak, reflected back inside).
pub fn lobe_centre(params: &HairParams, variant: ModelVariant, lobe: Lobe, theta_o: f64) -> f64 {
    match variant.longitudinal {
        LongitudinalModel::Published => 2.0 * params.alpha(lobe) - theta_o,
        LongitudinalModel::Normalized => -tilted_outgoing(theta_o, params.alpha(lobe)),
    }
}

/// The outgoing inclination tilted by the scales, theta_o' = theta_o - 2 alpha (pbrt-v4 applies the tilt to
/// theta_o alone), reflected back into [-pi/2, pi/2] past a pole as pbrt's absolute value of cos(theta_o')
/// does, so M stays normalised over theta_i.
pub fn tilted_outgoing(theta_o: f64, alpha: f64) -> f64 {
    let t = theta_o - 2.0 * alpha;
    if t > FRAC_PI_2 {
        PI - t
    } else if t < -FRAC_PI_2 {
        -PI - t
    } else {
        t
    }
}

/// ln M_p(theta_i, theta_o') of d'Eon et al. 2011 (Eq. 6 of their paper; pbrt-v4's `Mp`), with variance v and
/// theta_o' from [`tilted_outgoing`]:
/// M = csch(1/v) / (2v) exp(-sin theta_i sin theta_o' / v) I0(cos theta_i cos theta_o' / v),
/// in log space so narrow lobes (v -> 0, 1/v in the hundreds) neither overflow nor lose precision:
/// ln M = ln(I0(a) e^-a) + (cos(theta_i + theta_o') - 1)/v - ln v - ln(1 - e^(-2/v)), a = cos theta_i cos theta_o' / v,
/// with cos(x) - 1 = -2 sin^2(x/2).
pub fn ln_longitudinal_deon(v: f64, theta_i: f64, theta_o_tilted: f64) -> f64 {
    let a = theta_i.cos().max(0.0) * theta_o_tilted.cos() / v;
    let half = (0.5 * (theta_i + theta_o_tilted)).sin();
    bessel_i0_scaled_f64(a).ln() - 2.0 * half * half / v - v.ln() - (-(-2.0 / v).exp()).ln_1p()
}

/// d'Eon's normalised M_p(theta_i, theta_o) for lobe p: variance (2 beta_p)^2, tilt 2 alpha_p on theta_o.
/// integral_{-pi/2}^{pi/2} M_p cos(theta_i) d theta_i = 1.
pub fn longitudinal_m_p_normalized(
    params: &HairParams,
    lobe: Lobe,
    theta_i: f64,
    theta_o: f64,
) -> f64 {
    let t = tilted_outgoing(theta_o, params.alpha(lobe));
    ln_longitudinal_deon(deon_variance(params.beta(lobe)), theta_i, t).exp()
}

/// Marschner's eccentric index eta*(phi_h) (Marschner Sec. 4.4; Xu Eq. 24).
pub fn eccentric_eta(eta: f64, a: f64, phi_h: f64) -> f64 {
    let eta1 = 2.0 * (eta - 1.0) * a * a - eta + 2.0;
    let eta2 = 2.0 * (eta - 1.0) / (a * a) - eta + 2.0;
    0.5 * ((eta1 + eta2) + (2.0 * phi_h).cos() * (eta1 - eta2))
}

/// Exit azimuth of path p for offset h: phi(p, h) = 2 p gamma_t - 2 gamma_i + p pi (Marschner Eq. 6),
/// not wrapped (continuous in h).
pub fn phi_p(p: u32, h: f64, eta_perp: f64) -> f64 {
    let gamma_i = h.clamp(-1.0, 1.0).asin();
    let gamma_t = (h / eta_perp).clamp(-1.0, 1.0).asin();
    let pf = p as f64;
    2.0 * pf * gamma_t - 2.0 * gamma_i + pf * PI
}

/// d phi(p, h) / dh = 2p / sqrt(eta'^2 - h^2) - 2 / sqrt(1 - h^2).
pub fn dphi_dh(p: u32, h: f64, eta_perp: f64) -> f64 {
    let pf = p as f64;
    2.0 * pf / (eta_perp * eta_perp - h * h).sqrt() - 2.0 / (1.0 - h * h).max(0.0).sqrt()
}

/// d^2 phi(p, h) / dh^2.
pub fn d2phi_dh2(p: u32, h: f64, eta_perp: f64) -> f64 {
    let pf = p as f64;
    2.0 * pf * h / (eta_perp * eta_perp - h * h).powf(1.5)
        - 2.0 * h / (1.0 - h * h).max(0.0).powf(1.5)
}

/// Offsets |h| where d phi / dh = 0 for p >= 2 (the TRT caustic, eta' < 2): h_c = sqrt((p^2 - eta'^2)/(p^2 - 1)).
pub fn caustic_offset(p: u32, eta_perp: f64) -> Option<f64> {
    if p < 2 {
        return None;
    }
    let p2 = (p * p) as f64;
    let h2 = (p2 - eta_perp * eta_perp) / (p2 - 1.0);
    (h2 > 0.0 && h2 < 1.0).then(|| h2.sqrt())
}

/// The absorption-free factors of A_p(h) ([`AzimuthalLobe::attenuation_geometry`]).
#[derive(Clone, Copy, Debug)]
pub struct AttenuationGeometry {
    pub f_ext: f64,
    pub f_int: f64,
    pub chord: f64,
}

/// Everything about one lobe that depends on theta_d (and phi_h through eccentricity) but not on phi.
#[derive(Clone, Copy, Debug)]
pub struct AzimuthalLobe {
    pub lobe: Lobe,
    /// The lobe's index: eta, or eta*(phi_h) for TRT with eccentricity.
    pub eta: f64,
    pub theta_d: f64,
    /// eta'(theta_d)
    pub eta_perp: f64,
    /// eta''(theta_d)
    pub eta_par: f64,
    /// sigma_a' = sigma_a / cos(theta_t), per unit radius.
    pub sigma_a_prime: Rgb,
    pub fresnel: FresnelModel,
}

/// Up to this many roots of phi(p, h) = phi are returned (p <= 2 has at most 3).
const MAX_ROOTS: usize = 8;

/// Roots h in [-1, 1] of phi(p, h) = phi (mod 2 pi).
#[derive(Clone, Copy, Debug, Default)]
pub struct Roots {
    pub h: [f64; MAX_ROOTS],
    pub count: usize,
}

impl Roots {
    pub fn as_slice(&self) -> &[f64] {
        &self.h[..self.count]
    }
}

impl AzimuthalLobe {
    pub fn new(
        params: &HairParams,
        variant: ModelVariant,
        lobe: Lobe,
        theta_d: f64,
        phi_h: f64,
    ) -> Self {
        let eta = if lobe == Lobe::TRT && params.eccentricity != 1.0 {
            eccentric_eta(params.eta, params.eccentricity, phi_h)
        } else {
            params.eta
        };
        let s = theta_d.sin();
        // cos(theta_t) of the refracted ray's inclination: sin(theta_t) = sin(theta_d) / eta.
        let cos_theta_t = (1.0 - s * s / (eta * eta)).max(0.0).sqrt();
        let sigma_a_prime = params.sigma_a.map(|x| x / cos_theta_t);
        Self {
            lobe,
            eta,
            theta_d,
            eta_perp: bravais_perpendicular(eta, theta_d),
            eta_par: bravais_parallel(eta, theta_d),
            sigma_a_prime,
            fresnel: variant.fresnel,
        }
    }

    pub fn p(&self) -> u32 {
        self.lobe.p()
    }

    /// Attenuation A_p(h) (Marschner Eq. 8-9; Xu Eq. 10), RGB.
    /// Absorption over the chord: T = exp(-2 sigma_a' cos(gamma_t)) (unit radius).
    pub fn attenuation_a_p(&self, h: f64) -> Rgb {
        let h = h.clamp(-1.0, 1.0);
        let gamma_i = h.asin();
        let gamma_t = (h / self.eta_perp).clamp(-1.0, 1.0).asin();
        self.attenuation_a_p_at(h, gamma_i, gamma_t)
    }

    /// [`AzimuthalLobe::attenuation_a_p`] at h in [-1, 1] with its angles gamma_i = asin h and
    /// gamma_t = asin(h / eta') already known (an integral over gamma_i has them).
    pub fn attenuation_a_p_at(&self, h: f64, gamma_i: f64, gamma_t: f64) -> Rgb {
        let g = self.attenuation_geometry(h, gamma_i, gamma_t);
        self.sigma_a_prime.map(|s| self.attenuation_of(&g, s))
    }

    /// What A_p(h) owes to the fiber's surface and shape, not its absorption: the Fresnel factors
    /// and the chord 2 cos(gamma_t) (the same for every sigma_a; the dual-scattering tables share it
    /// across their absorption axis).
    pub fn attenuation_geometry(&self, h: f64, gamma_i: f64, gamma_t: f64) -> AttenuationGeometry {
        let (f_ext, f_int) = match self.fresnel {
            FresnelModel::Exact => (
                fresnel_bravais(self.eta_perp, self.eta_par, gamma_i),
                fresnel_bravais(1.0 / self.eta_perp, 1.0 / self.eta_par, gamma_t),
            ),
            FresnelModel::XuSchlick => {
                let f = fresnel_schlick_xu(self.eta, self.theta_d, h);
                (f, f)
            }
        };
        AttenuationGeometry {
            f_ext,
            f_int,
            chord: 2.0 * gamma_t.cos(),
        }
    }

    /// A_p of one channel from its geometry and the channel's sigma_a' (`sigma_a_prime`).
    pub fn attenuation_of(&self, g: &AttenuationGeometry, sigma_a_prime: f64) -> f64 {
        match self.lobe {
            Lobe::R => g.f_ext,
            Lobe::TT => (1.0 - g.f_ext).powi(2) * (-sigma_a_prime * g.chord).exp(),
            Lobe::TRT => (1.0 - g.f_ext).powi(2) * g.f_int * (-2.0 * sigma_a_prime * g.chord).exp(),
        }
    }

    /// The pieces of [-1, 1] on which phi(p, h) is monotone.
    fn monotone_pieces(&self) -> ([f64; 4], usize) {
        match caustic_offset(self.p(), self.eta_perp) {
            Some(hc) => ([-1.0, -hc, hc, 1.0], 4),
            None => ([-1.0, 1.0, 0.0, 0.0], 2),
        }
    }

    /// Every h in [-1, 1] with phi(p, h) = phi (mod 2 pi), by bracketing on monotone pieces and a
    /// safeguarded Newton iteration in gamma_i = asin h (converged to ~1e-15).
    pub fn roots(&self, phi: f64) -> Roots {
        let p = self.p();
        let mut out = Roots::default();
        let (ends, n) = self.monotone_pieces();
        for k in 0..n - 1 {
            let (a, b) = (ends[k], ends[k + 1]);
            let (fa, fb) = (phi_p(p, a, self.eta_perp), phi_p(p, b, self.eta_perp));
            let (lo, hi) = (fa.min(fb), fa.max(fb));
            // Every branch phi + 2 pi m inside [lo, hi].
            let m0 = ((lo - phi) / TAU).ceil() as i64;
            let m1 = ((hi - phi) / TAU).floor() as i64;
            for m in m0..=m1 {
                let target = phi + TAU * m as f64;
                let h = self.solve_monotone(a, b, fa, fb, target);
                // A root shared by two pieces (exactly at an interior end) is counted once.
                if out.count > 0 && (out.h[out.count - 1] - h).abs() < 1e-13 {
                    continue;
                }
                if out.count < MAX_ROOTS {
                    out.h[out.count] = h;
                    out.count += 1;
                }
            }
        }
        out
    }

    fn solve_monotone(&self, a: f64, b: f64, fa: f64, fb: f64, target: f64) -> f64 {
        let p = self.p();
        let pf = p as f64;
        // In gamma_i = asin h, where phi(p, h) = 2p asin(sin(gamma_i) / eta') - 2 gamma_i + p pi has a
        // finite slope at h = +-1 (d phi / dh is infinite there, and Newton in h fell back to
        // bisection: 12 steps per root on average).
        let g = |x: f64| {
            let s = x.sin();
            2.0 * pf * (s / self.eta_perp).clamp(-1.0, 1.0).asin() - 2.0 * x + pf * PI - target
        };
        let slope = |x: f64| {
            let (s, c) = x.sin_cos();
            2.0 * pf * c / (self.eta_perp * self.eta_perp - s * s).max(0.0).sqrt() - 2.0
        };
        let (ga, gb) = (a.clamp(-1.0, 1.0).asin(), b.clamp(-1.0, 1.0).asin());
        // Orient the bracket so that g(lo) <= 0 <= g(hi).
        let (mut lo, mut hi) = if fa - target <= 0.0 {
            (ga, gb)
        } else {
            (gb, ga)
        };
        // Started where the chord through the piece's ends meets the target.
        let mut x = if fb != fa {
            ga + (gb - ga) * ((target - fa) / (fb - fa)).clamp(0.0, 1.0)
        } else {
            0.5 * (ga + gb)
        };
        for _ in 0..200 {
            let gx = g(x);
            if gx == 0.0 {
                return x.sin();
            }
            if gx < 0.0 {
                lo = x;
            } else {
                hi = x;
            }
            let mut next = x - gx / slope(x);
            let (l, u) = (lo.min(hi), lo.max(hi));
            if !(next.is_finite() && next > l && next < u) {
                next = 0.5 * (lo + hi);
            }
            if (next - x).abs() <= 1e-15 || (u - l) <= 1e-15 {
                return next.sin();
            }
            x = next;
        }
        x.sin()
    }

    /// N_p(phi) as the bare sum over roots: sum_h A_p(h) / |2 dphi/dh| (Marschner Eq. 7).
    pub fn azimuthal_n_p_roots(&self, phi: f64) -> Rgb {
        let mut n = [0.0; 3];
        for &h in self.roots(phi).as_slice() {
            let d = dphi_dh(self.p(), h, self.eta_perp).abs();
            if d == 0.0 || !d.is_finite() {
                continue;
            }
            let a = self.attenuation_a_p(h);
            for c in 0..3 {
                n[c] += a[c] / (2.0 * d);
            }
        }
        n
    }

    /// Azimuths (wrapped to (-pi, pi]) where the number of roots changes: the images of h = +-1 and,
    /// for TRT with eta' < 2, the caustics. Sorted, with -pi and pi included. Used by integrators.
    pub fn breakpoints(&self) -> Vec<f64> {
        let p = self.p();
        let mut v = vec![-PI, PI];
        let mut hs = vec![-1.0, 1.0];
        if let Some(hc) = caustic_offset(p, self.eta_perp) {
            hs.extend([-hc, hc]);
        }
        for h in hs {
            v.push(wrap_angle(phi_p(p, h, self.eta_perp)));
        }
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-14);
        v
    }
}

/// Marschner's TRT caustic treatment (Sec. 4.3), prepared for one theta_d.
#[derive(Clone, Copy, Debug)]
pub struct CausticFix {
    /// Caustic azimuth phi_c >= 0; the caustics sit at +-phi_c.
    pub phi_c: f64,
    /// Blend t: 1 below 2 - Delta eta', smoothly to 0 at eta' = 2.
    pub t: f64,
    /// Delta h = min(caustic limit, 2 sqrt(2 w_c / |d^2 phi / dh^2 (h_c)|)).
    pub delta_h: f64,
    /// A_TRT(h_c), RGB.
    pub a_c: Rgb,
    pub w_c: f64,
    pub glint_scale: f64,
}

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl CausticFix {
    pub fn new(params: &HairParams, lobe: &AzimuthalLobe) -> Option<Self> {
        let hc = caustic_offset(2, lobe.eta_perp)?;
        let t = 1.0 - smoothstep(2.0 - params.caustic_fade, 2.0, lobe.eta_perp);
        if t <= 0.0 {
            return None;
        }
        let curvature = d2phi_dh2(2, hc, lobe.eta_perp).abs();
        let delta_h = params
            .caustic_limit
            .min(2.0 * (2.0 * params.caustic_width / curvature).sqrt());
        Some(Self {
            phi_c: wrap_angle(phi_p(2, hc, lobe.eta_perp)).abs(),
            t,
            delta_h,
            a_c: lobe.attenuation_a_p(hc),
            w_c: params.caustic_width,
            glint_scale: params.glint_scale,
        })
    }

    /// N_TRT(phi) = N_roots(phi) (1 - t g(w_c; phi - phi_c)/g(w_c; 0)) (1 - t g(w_c; phi + phi_c)/g(w_c; 0))
    ///            + t g_c Delta h A(2, h_c) (g(w_c; phi - phi_c) + g(w_c; phi + phi_c))
    pub fn apply(&self, phi: f64, n_roots: Rgb) -> Rgb {
        let g0 = gaussian(self.w_c, 0.0);
        let g1 = gaussian(self.w_c, wrap_angle(phi - self.phi_c));
        let g2 = gaussian(self.w_c, wrap_angle(phi + self.phi_c));
        let damp = (1.0 - self.t * g1 / g0) * (1.0 - self.t * g2 / g0);
        let peak = self.t * self.glint_scale * self.delta_h * (g1 + g2);
        std::array::from_fn(|c| {
            let base = if damp > 0.0 && n_roots[c].is_finite() {
                n_roots[c] * damp
            } else {
                0.0
            };
            base + peak * self.a_c[c]
        })
    }
}

/// N_p(phi) for the chosen variant (bare root sum, or with Marschner's caustic fix for TRT).
pub fn azimuthal_n_p(
    params: &HairParams,
    variant: ModelVariant,
    lobe: &AzimuthalLobe,
    phi: f64,
) -> Rgb {
    let n = lobe.azimuthal_n_p_roots(phi);
    if lobe.lobe != Lobe::TRT || variant.caustic == CausticModel::None {
        return n;
    }
    match CausticFix::new(params, lobe) {
        Some(fix) => fix.apply(phi, n),
        None => n,
    }
}

/// S_p for each lobe and their sum, RGB.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct LobeValues {
    #[serde(rename = "R")]
    pub r: Rgb,
    #[serde(rename = "TT")]
    pub tt: Rgb,
    #[serde(rename = "TRT")]
    pub trt: Rgb,
}

impl LobeValues {
    pub fn get(&self, lobe: Lobe) -> Rgb {
        match lobe {
            Lobe::R => self.r,
            Lobe::TT => self.tt,
            Lobe::TRT => self.trt,
        }
    }

    pub fn total(&self) -> Rgb {
        std::array::from_fn(|c| self.r[c] + self.tt[c] + self.trt[c])
    }
}

/// One lobe of the scattering function: published, S_p = M_p(theta_h) N_p(phi) / cos^2(theta_d);
/// normalised, S_p = M_p(theta_i, theta_o) N_p(phi) / cos(theta_i) (so that S_p cos(theta_i), what every
/// caller integrates over the incident directions, is d'Eon's M_p N_p).
pub fn scattering_s_p(
    params: &HairParams,
    variant: ModelVariant,
    lobe: Lobe,
    wi: FiberAngles,
    wo: FiberAngles,
) -> Rgb {
    let ha = HalfAngles::new(wi, wo);
    let (m, divisor) = match variant.longitudinal {
        LongitudinalModel::Published => (
            longitudinal_m_p(params, lobe, ha.theta_h),
            ha.theta_d.cos().powi(2),
        ),
        LongitudinalModel::Normalized => (
            longitudinal_m_p_normalized(params, lobe, wi.theta, wo.theta),
            wi.theta.cos(),
        ),
    };
    if m == 0.0 || !m.is_finite() {
        return [0.0; 3];
    }
    let az = AzimuthalLobe::new(params, variant, lobe, ha.theta_d, ha.phi_h);
    let n = azimuthal_n_p(params, variant, &az, ha.phi);
    let d = divisor.max(1e-12);
    n.map(|x| m * x / d)
}

/// The full scattering function S(omega_i, omega_o), per lobe (Marschner Eq. 2).
pub fn scattering_s(
    params: &HairParams,
    variant: ModelVariant,
    wi: FiberAngles,
    wo: FiberAngles,
) -> LobeValues {
    LobeValues {
        r: scattering_s_p(params, variant, Lobe::R, wi, wo),
        tt: scattering_s_p(params, variant, Lobe::TT, wi, wo),
        trt: scattering_s_p(params, variant, Lobe::TRT, wi, wo),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn r_root_is_closed_form() {
        let params = HairParams::default();
        let az = AzimuthalLobe::new(&params, ModelVariant::MARSCHNER, Lobe::R, 0.2, 0.0);
        for phi in [-2.5, -0.3, 0.0, 1.0, 3.0] {
            let r = az.roots(phi);
            assert_eq!(r.count, 1, "phi {phi}");
            assert!((r.h[0] + (phi / 2.0f64).sin()).abs() < 1e-12);
        }
    }

    #[test]
    fn roots_satisfy_the_equation() {
        let params = HairParams::default();
        for lobe in Lobe::ALL {
            for theta_d in [0.0, 0.4, 0.8, 1.2] {
                let az = AzimuthalLobe::new(&params, ModelVariant::MARSCHNER, lobe, theta_d, 0.0);
                for k in 0..50 {
                    let phi = -PI + TAU * (k as f64 + 0.37) / 50.0;
                    for &h in az.roots(phi).as_slice() {
                        let r = wrap_angle(phi_p(lobe.p(), h, az.eta_perp) - phi);
                        assert!(
                            r.abs() < 1e-9,
                            "{lobe:?} theta_d {theta_d} phi {phi}: residual {r}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn large_absorption_leaves_only_r() {
        let params = HairParams::with_sigma_a([60.0; 3]);
        let v = scattering_s(
            &params,
            ModelVariant::MARSCHNER,
            FiberAngles::new(0.2, 0.1),
            FiberAngles::new(-0.1, 2.9),
        );
        assert!(v.tt[0] < 1e-30 && v.trt[0] < 1e-30 && v.r[0] > 0.0);
    }
}
