//! What the path tracer samples: the kernel's lobes ([`Scatterer`]: d'Eon's longitudinal function
//! and the azimuth through the offset h), the environment image by luminance and solid angle, and
//! the lights of next-event estimation.

use super::UNIFORM_SHARE;
use crate::envmap::EnvMap;
use crate::envmap::direction::{direction_from_uv, rotate_yaw, uv_from_direction};
use crate::render::reference::{DirectionalLight, REFERENCE_VARIANT, ReferenceLighting};
use crate::scattering::frame::{FiberAngles, FiberFrame, wrap_angle};
use crate::scattering::marschner::{
    AzimuthalLobe, deon_variance, dphi_dh, ln_longitudinal_deon, phi_p, scattering_s,
    tilted_outgoing,
};
use crate::scattering::params::{HairParams, Lobe, ModelVariant};
use glam::{DVec3, Vec3};
use rand_core::{Rng, SeedableRng};
use std::f64::consts::{PI, TAU};

/// The sampling density's longitudinal part for one lobe: variance v and the tilted outgoing
/// inclination theta'_o ([`tilted_outgoing`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Longitudinal {
    pub v: f64,
    pub theta_o: f64,
}

impl Longitudinal {
    /// v_p = (2 beta_p)^2, theta'_o = theta_o - 2 alpha_p (reflected back past the pole).
    pub fn new(params: &HairParams, lobe: Lobe, theta_o: f64) -> Self {
        Self {
            v: deon_variance(params.beta(lobe)),
            theta_o: tilted_outgoing(theta_o, params.alpha(lobe)),
        }
    }

    /// d'Eon's M(theta_i; theta'_o, v) = csch(1/v)/(2v) exp(-sin theta_i sin theta'_o / v)
    /// I0(cos theta_i cos theta'_o / v), with integral M cos(theta_i) d theta_i = 1 over [-pi/2, pi/2];
    /// the exact model's own log-space form ([`ln_longitudinal_deon`]), so sampler and kernel agree.
    pub fn density(&self, theta_i: f64) -> f64 {
        ln_longitudinal_deon(self.v, theta_i, self.theta_o).exp()
    }

    /// theta_i with density M(theta_i) cos(theta_i) (pbrt-v4's `SampleMp`): the cosine to the cone's
    /// axis from the von Mises-Fisher inversion, its azimuth uniform, then the inclination.
    pub fn sample(&self, u1: f64, u2: f64) -> f64 {
        // 1 - cos = -v ln(u1 + (1 - u1) e^{-2/v}), kept apart so narrow lobes keep their precision.
        let one_minus_cos =
            (-self.v * (u1 + (1.0 - u1) * (-2.0 / self.v).exp()).ln()).clamp(0.0, 2.0);
        let cos_t = 1.0 - one_minus_cos;
        let sin_t = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
        let (sin_o, cos_o) = self.theta_o.sin_cos();
        let sin_i = -cos_t * sin_o + sin_t * (TAU * u2).cos() * cos_o;
        sin_i.clamp(-1.0, 1.0).asin()
    }
}

/// Density of phi = phi(p, h) for h uniform in (-1, 1): sum over the roots h of phi(p, h) = phi of
/// 1 / (2 |d phi / dh|). Integrates to 1 over (-pi, pi].
pub fn azimuthal_density(lobe: &AzimuthalLobe, phi: f64) -> f64 {
    let p = lobe.p();
    lobe.roots(phi)
        .as_slice()
        .iter()
        .map(|&h| {
            let d = dphi_dh(p, h, lobe.eta_perp).abs();
            if d > 0.0 && d.is_finite() {
                0.5 / d
            } else {
                0.0
            }
        })
        .sum()
}

/// The kernel and its sampling at one point on a fiber, for one outgoing direction.
pub struct Scatterer {
    /// The hair parameters with the point's absorption.
    pub params: HairParams,
    /// The same without eccentricity: the sampler's azimuthal lobes (its own density, so it need
    /// not follow the model's eccentric index).
    sampler_params: HairParams,
    pub frame: FiberFrame,
    pub wo: FiberAngles,
    /// Probabilities of R, TT, TRT and the uniform sphere.
    pub q: [f64; 4],
    long: [Longitudinal; 3],
    /// The exact model's variant (its longitudinal function is the look's).
    variant: ModelVariant,
}

impl Scatterer {
    pub fn new(
        base: &HairParams,
        variant: ModelVariant,
        sigma_a: [f32; 3],
        tangent: Vec3,
        omega_o: Vec3,
    ) -> Self {
        let mut params = *base;
        params.sigma_a = sigma_a.map(|s| s as f64);
        let mut sampler_params = params;
        sampler_params.eccentricity = 1.0;
        let frame = FiberFrame::from_tangent(tangent.as_dvec3());
        let wo = frame.angles(omega_o.as_dvec3());
        // Each lobe's energy, roughly: the mean of A_p over 8 offsets at theta_d = theta_o (the
        // specular cone, theta_i = -theta_o), floored at 5 % of the total.
        let mut e = [0.0f64; 3];
        for (k, lobe) in Lobe::ALL.into_iter().enumerate() {
            let az = AzimuthalLobe::new(&sampler_params, REFERENCE_VARIANT, lobe, wo.theta, 0.0);
            e[k] = (0..8)
                .map(|j| {
                    let a = az.attenuation_a_p(-1.0 + (j as f64 + 0.5) / 4.0);
                    (a[0] + a[1] + a[2]) / 3.0
                })
                .sum::<f64>()
                / 8.0;
        }
        let total: f64 = e.iter().sum();
        let floored = e.map(|x| x.max(0.05 * total).max(1e-12));
        let sum: f64 = floored.iter().sum();
        let q = [
            (1.0 - UNIFORM_SHARE) * floored[0] / sum,
            (1.0 - UNIFORM_SHARE) * floored[1] / sum,
            (1.0 - UNIFORM_SHARE) * floored[2] / sum,
            UNIFORM_SHARE,
        ];
        let long = Lobe::ALL.map(|lobe| Longitudinal::new(&sampler_params, lobe, wo.theta));
        Self {
            params,
            sampler_params,
            frame,
            wo,
            q,
            long,
            variant,
        }
    }

    /// K = S cos(theta_i) per lobe (R, TT, TRT), RGB.
    pub fn kernel(&self, wi: FiberAngles) -> [[f64; 3]; 3] {
        let s = scattering_s(&self.params, self.variant, wi, self.wo);
        let c = wi.theta.cos().max(0.0);
        [s.r, s.tt, s.trt].map(|l| l.map(|x| x * c))
    }

    /// The sampler's azimuthal lobe p at theta_d.
    pub(super) fn lobe(&self, k: usize, theta_d: f64) -> AzimuthalLobe {
        AzimuthalLobe::new(
            &self.sampler_params,
            REFERENCE_VARIANT,
            Lobe::ALL[k],
            theta_d,
            0.0,
        )
    }

    /// Density of [`Scatterer::sample`] per unit solid angle:
    /// sum_p q_p M_p(theta_i) pdf_p(phi) + q_u / (4 pi) (the theta density M cos(theta_i) over the
    /// cos(theta_i) of the solid angle).
    pub fn pdf(&self, wi: FiberAngles) -> f64 {
        let theta_d = 0.5 * (self.wo.theta - wi.theta);
        let phi = wrap_angle(self.wo.phi - wi.phi);
        let mut pdf = self.q[3] / (4.0 * PI);
        for k in 0..3 {
            if self.q[k] <= 0.0 {
                continue;
            }
            let m = self.long[k].density(wi.theta);
            if m <= 0.0 || !m.is_finite() {
                continue;
            }
            pdf += self.q[k] * m * azimuthal_density(&self.lobe(k, theta_d), phi);
        }
        pdf
    }

    /// A direction from the mixture, from four uniform numbers.
    pub fn sample(&self, u: [f64; 4]) -> FiberAngles {
        let mut k = 0;
        let mut acc = self.q[0];
        while k < 3 && u[0] >= acc {
            k += 1;
            acc += self.q[k];
        }
        if k == 3 {
            let z = 2.0 * u[1] - 1.0;
            return FiberAngles::new(z.clamp(-1.0, 1.0).asin(), wrap_angle(TAU * u[2] - PI));
        }
        let theta_i = self.long[k].sample(u[1], u[2]);
        let theta_d = 0.5 * (self.wo.theta - theta_i);
        let lobe = self.lobe(k, theta_d);
        let h = (2.0 * u[3] - 1.0).clamp(-1.0 + 1e-12, 1.0 - 1e-12);
        let phi = phi_p(lobe.p(), h, lobe.eta_perp);
        FiberAngles::new(theta_i, wrap_angle(self.wo.phi - phi))
    }
}

/// Uniform numbers in (0, 1) from a PCG stream.
pub(super) struct Sampler(rand_pcg::Pcg64Mcg);

impl Sampler {
    pub(super) fn new(seed: u64, a: u64, b: u64) -> Self {
        let mut z =
            seed ^ a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        // splitmix64 finaliser
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Self(rand_pcg::Pcg64Mcg::seed_from_u64(z))
    }

    pub(super) fn next(&mut self) -> f64 {
        ((self.0.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
}

/// A cumulative distribution over a list (index drawn proportionally to the weights).
pub(super) struct Cdf {
    cdf: Vec<f64>,
}

impl Cdf {
    pub(super) fn new(weights: impl Iterator<Item = f64>) -> Self {
        let mut cdf = Vec::new();
        let mut total = 0.0;
        for w in weights {
            total += w.max(0.0);
            cdf.push(total);
        }
        Self { cdf }
    }

    pub(super) fn total(&self) -> f64 {
        self.cdf.last().copied().unwrap_or(0.0)
    }

    /// Probability of drawing index i.
    pub(super) fn probability(&self, i: usize) -> f64 {
        let total = self.total();
        if total <= 0.0 {
            return 0.0;
        }
        (self.cdf[i] - if i > 0 { self.cdf[i - 1] } else { 0.0 }) / total
    }

    /// (index, probability) or None when every weight is 0.
    pub(super) fn draw(&self, u: f64) -> Option<(usize, f64)> {
        let total = self.total();
        if total <= 0.0 {
            return None;
        }
        let target = u * total;
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.cdf.len() - 1);
        let w = self.cdf[i] - if i > 0 { self.cdf[i - 1] } else { 0.0 };
        (w > 0.0).then_some((i, w / total))
    }
}

/// The environment image as a light: texels drawn by luminance x solid angle (the CDF of
/// [`crate::render::reference::importance_sample_env`]), the direction uniform in the texel (in u, v), turned by
/// `yaw`; each sample carries L / pdf.
pub(super) struct EnvSampler<'a> {
    env: &'a EnvMap,
    yaw: f64,
    cdf: Cdf,
}

impl<'a> EnvSampler<'a> {
    pub(super) fn new(env: &'a EnvMap, yaw: f64) -> Self {
        let cdf = Cdf::new((0..env.width * env.height).map(|i| {
            let p = env.pixels[i];
            let lum = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            lum.max(0.0) * env.solid_angle(i / env.width)
        }));
        Self { env, yaw, cdf }
    }

    /// A direction and its L(omega) / pdf(omega) from three uniform numbers (uniform in solid angle
    /// within the texel: cos(theta) uniform over the row's band).
    pub(super) fn sample(&self, u: f64, ju: f64, jv: f64) -> Option<DirectionalLight> {
        let (i, prob) = self.cdf.draw(u)?;
        let (w, h) = (self.env.width, self.env.height);
        let (x, y) = (i % w, i / w);
        let (c0, c1) = (
            (PI * y as f64 / h as f64).cos(),
            (PI * (y + 1) as f64 / h as f64).cos(),
        );
        let v = (c0 + jv * (c1 - c0)).clamp(-1.0, 1.0).acos() / PI;
        let d = direction_from_uv((x as f64 + ju) / w as f64, v);
        let scale = self.env.solid_angle(y) / prob;
        let p = self.env.pixels[i];
        Some(DirectionalLight {
            direction: rotate_yaw(d, self.yaw),
            weight: p.map(|c| c as f64 * scale),
        })
    }

    /// The texel a world direction falls in.
    pub(super) fn texel(&self, dir: DVec3) -> usize {
        let (u, v) = uv_from_direction(rotate_yaw(dir, -self.yaw));
        let (w, h) = (self.env.width, self.env.height);
        let x = ((u * w as f64) as usize).min(w - 1);
        let y = ((v * h as f64) as usize).min(h - 1);
        y * w + x
    }

    /// Density of [`EnvSampler::sample`] per unit solid angle at a world direction, and the
    /// radiance there.
    pub(super) fn pdf_and_radiance(&self, dir: DVec3) -> (f64, [f64; 3]) {
        let i = self.texel(dir);
        let y = i / self.env.width;
        let pdf = self.cdf.probability(i) / self.env.solid_angle(y);
        (pdf, self.env.pixels[i].map(|c| c as f64))
    }
}

/// Where next-event estimation gets its light.
pub(super) enum LightSource<'a> {
    /// The environment image, sampled afresh for every point and vertex: no light set is shared
    /// between pixels, so the discretisation of the environment averages out over the image instead
    /// of biasing every pixel alike (with one shared set of 1024-16384 directions the mean of a
    /// furnace moved by 2-4 %).
    Image {
        sampler: EnvSampler<'a>,
        per_point: usize,
    },
    /// A fixed list of directional lights (sampled from SRBF lobes), drawn by power.
    Fixed {
        lights: Vec<DirectionalLight>,
        cdf: Cdf,
    },
}

impl<'a> LightSource<'a> {
    pub(super) fn new(lighting: &'a ReferenceLighting<'a>) -> Self {
        match lighting {
            ReferenceLighting::Environment {
                env,
                yaw,
                directions,
            } => LightSource::Image {
                sampler: EnvSampler::new(env, *yaw),
                per_point: (*directions).max(1),
            },
            ReferenceLighting::Directional(lights) => LightSource::Fixed {
                cdf: Cdf::new(lights.iter().map(|l| l.weight.iter().sum::<f64>())),
                lights: lights.clone(),
            },
        }
    }

    /// The lights of one primary point: `per_point` stratified samples of the image, each weighing
    /// 1 / per_point of its L / pdf, or the fixed list.
    pub(super) fn point_lights(&self, rng: &mut Sampler) -> Vec<DirectionalLight> {
        match self {
            LightSource::Image { sampler, per_point } => {
                let n = *per_point;
                (0..n)
                    .filter_map(|k| {
                        let u = (k as f64 + rng.next()) / n as f64;
                        sampler.sample(u, rng.next(), rng.next()).map(|mut l| {
                            l.weight = l.weight.map(|x| x / n as f64);
                            l
                        })
                    })
                    .collect()
            }
            LightSource::Fixed { lights, .. } => lights.clone(),
        }
    }

    /// One light for a vertex, its weight divided by the probability of drawing it, and its density
    /// per unit solid angle (None for a fixed list: delta lights, which kernel sampling never hits).
    pub(super) fn sample_one(&self, rng: &mut Sampler) -> Option<(DirectionalLight, Option<f64>)> {
        match self {
            LightSource::Image { sampler, .. } => {
                let l = sampler.sample(rng.next(), rng.next(), rng.next())?;
                Some((l, Some(sampler.pdf_and_radiance(l.direction).0)))
            }
            LightSource::Fixed { lights, cdf } => {
                let (j, prob) = cdf.draw(rng.next())?;
                let l = lights[j];
                let l = DirectionalLight {
                    direction: l.direction,
                    weight: l.weight.map(|x| x / prob),
                };
                Some((l, None))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scattering::params::Preset;

    /// Midpoint rule, fine enough for the narrowest lobe here (v = 0.003: width ~0.05 rad).
    fn integrate(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        let h = (b - a) / n as f64;
        (0..n).map(|k| f(a + (k as f64 + 0.5) * h)).sum::<f64>() * h
    }

    /// The environment sampler's weights L / pdf average to the map's power, and its density at a
    /// sampled direction is the one the weight was made with (what the balance heuristic needs).
    #[test]
    fn environment_samples_integrate_the_map_and_agree_with_their_density() {
        let (w, h) = (32usize, 16usize);
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                [
                    1.0 + x,
                    0.5 + y * y,
                    if x == 3.0 && y == 4.0 { 500.0 } else { 0.1 },
                ]
            })
            .collect();
        let (env, _) = EnvMap::new(w, h, pixels, std::path::Path::new("test")).expect("env");
        let sampler = EnvSampler::new(&env, 0.7);
        let power = env.power();
        let mut rng = Sampler::new(1, 2, 3);
        let n = 400_000;
        let mut mean = [0.0f64; 3];
        for _ in 0..n {
            let l = sampler
                .sample(rng.next(), rng.next(), rng.next())
                .expect("a sample");
            let (pdf, radiance) = sampler.pdf_and_radiance(l.direction);
            for c in 0..3 {
                mean[c] += l.weight[c] / n as f64;
                assert!(
                    (radiance[c] / pdf - l.weight[c]).abs() <= 1e-6 * l.weight[c].max(1.0),
                    "weight {:?} vs L / pdf {}",
                    l.weight,
                    radiance[c] / pdf
                );
            }
        }
        for c in 0..3 {
            assert!(
                (mean[c] / power[c] - 1.0).abs() < 0.01,
                "channel {c}: {} vs {}",
                mean[c],
                power[c]
            );
        }
    }

    #[test]
    fn bessel_matches_its_integral_definition() {
        for x in [0.0, 0.3, 2.0, 12.0, 29.9, 30.1, 80.0, 400.0] {
            // I0(x) e^-x = (1/pi) integral_0^pi e^{x (cos t - 1)} dt
            let want = integrate(|t: f64| (x * (t.cos() - 1.0)).exp(), 0.0, PI, 200_000) / PI;
            let got = crate::scattering::marschner::bessel_i0_scaled_f64(x);
            assert!((got / want - 1.0).abs() < 1e-9, "x {x}: {got} vs {want}");
        }
    }

    #[test]
    fn longitudinal_density_integrates_to_one_and_matches_its_samples() {
        let params = Preset::Blond.params();
        let mut rng = Sampler::new(3, 1, 2);
        for lobe in Lobe::ALL {
            for theta_o in [-1.3, -0.4, 0.0, 0.7, 1.45] {
                let l = Longitudinal::new(&params, lobe, theta_o);
                let total = integrate(|t| l.density(t) * t.cos(), -PI / 2.0, PI / 2.0, 40_000);
                assert!(
                    (total - 1.0).abs() < 1e-4,
                    "{lobe:?} theta_o {theta_o}: integral {total}"
                );
                // Histogram of 100k samples in 60 bins against the density integrated per bin.
                let (bins, n) = (60usize, 100_000usize);
                let mut counts = vec![0usize; bins];
                for _ in 0..n {
                    let t = l.sample(rng.next(), rng.next());
                    let b = (((t + PI / 2.0) / PI) * bins as f64) as usize;
                    counts[b.min(bins - 1)] += 1;
                }
                let (mut chi2, mut dof) = (0.0, 0usize);
                for (b, &count) in counts.iter().enumerate() {
                    let lo = -PI / 2.0 + PI * b as f64 / bins as f64;
                    let expected = n as f64
                        * integrate(|t| l.density(t) * t.cos(), lo, lo + PI / bins as f64, 400);
                    if expected > 20.0 {
                        chi2 += (count as f64 - expected).powi(2) / expected;
                        dof += 1;
                    }
                }
                let limit = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt() + 10.0;
                assert!(
                    chi2 < limit,
                    "{lobe:?} theta_o {theta_o}: chi^2 {chi2:.1} over {dof} bins (limit {limit:.1})"
                );
            }
        }
    }

    #[test]
    fn azimuthal_density_integrates_to_one() {
        let params = Preset::Blond.params();
        for lobe in Lobe::ALL {
            for theta_d in [0.0, 0.3, 0.7, 1.1] {
                let az = AzimuthalLobe::new(&params, REFERENCE_VARIANT, lobe, theta_d, 0.0);
                let total = crate::scattering::numeric::integrate_piecewise_relative(
                    &|phi| azimuthal_density(&az, phi),
                    &az.breakpoints(),
                    1e-7,
                );
                assert!(
                    (total - 1.0).abs() < 1e-4,
                    "{lobe:?} theta_d {theta_d}: integral {total}"
                );
            }
        }
    }

    /// The mixture pdf integrates to 1 over the sphere and E[K / pdf] over its samples is the
    /// kernel's integral (the directional albedo), computed by quadrature.
    #[test]
    fn mixture_pdf_is_normalised_and_weights_are_unbiased() {
        let params = Preset::Blond.params();
        let tangent = Vec3::Y;
        let omega_o = Vec3::new(0.6, 0.3, 0.74).normalize();
        let s = Scatterer::new(
            &params,
            REFERENCE_VARIANT,
            [0.3, 0.5, 0.9],
            tangent,
            omega_o,
        );
        // Quadrature over (theta, phi): cos(theta) d theta d phi.
        let (nt, np) = (600usize, 720usize);
        let (mut pdf_total, mut albedo) = (0.0, [0.0f64; 3]);
        for a in 0..nt {
            let theta = -PI / 2.0 + PI * (a as f64 + 0.5) / nt as f64;
            for b in 0..np {
                let phi = -PI + TAU * (b as f64 + 0.5) / np as f64;
                let wi = FiberAngles::new(theta, phi);
                let dw = theta.cos() * (PI / nt as f64) * (TAU / np as f64);
                pdf_total += s.pdf(wi) * dw;
                let k = s.kernel(wi);
                for c in 0..3 {
                    albedo[c] += (k[0][c] + k[1][c] + k[2][c]) * dw;
                }
            }
        }
        let mut rng = Sampler::new(5, 1, 1);
        let n = 200_000;
        let mut est = [0.0f64; 3];
        for _ in 0..n {
            let wi = s.sample([rng.next(), rng.next(), rng.next(), rng.next()]);
            let k = s.kernel(wi);
            let p = s.pdf(wi);
            for c in 0..3 {
                est[c] += (k[0][c] + k[1][c] + k[2][c]) / p / n as f64;
            }
        }
        println!("pdf integral {pdf_total:.4}; albedo quadrature {albedo:.4?}, sampled {est:.4?}");
        assert!((pdf_total - 1.0).abs() < 0.01, "pdf integral {pdf_total}");
        for c in 0..3 {
            assert!(
                (est[c] / albedo[c] - 1.0).abs() < 0.02,
                "channel {c}: {} vs {}",
                est[c],
                albedo[c]
            );
        }
    }
}
