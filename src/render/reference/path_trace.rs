//! A brute-force path-traced reference (CPU, rayon): the same visible points as the GPU frame, lit by
//! the reference mode's lighting ([`crate::render::reference::ReferenceLighting`]), with every order of
//! scattering traced through the explicit fibers ([`FiberGrid`]). It is the ground truth for the
//! renderer's dual scattering and for the reference mode's ray shooting: nothing in it is fitted or
//! approximated but the environment image's texels (constant radiance per texel).
//!
//! Estimator, per visible point and path (unbiased up to the depth cut-off):
//! - the kernel is the exact model, K(omega_i, omega_o) = S(omega_i, omega_o) cos(theta_i) per lobe
//!   ([`scattering_s`] with [`REFERENCE_VARIANT`] and the look's longitudinal function); radiance
//!   L_o = integral K L_i d omega_i;
//! - next-event estimation with a shadow ray through the fibers (any crossing blocks). The
//!   environment image is sampled afresh for every point and vertex (texels by luminance x solid
//!   angle): no light set is shared between pixels, so its discretisation averages out instead of
//!   biasing every pixel alike. At the visible point, `directions` stratified samples are drawn, their
//!   unshadowed contributions computed once, and each path draws one of them proportionally to its
//!   contribution, so only visibility is sampled; past it, one sample per vertex;
//! - a continuation ray sampled from the kernel (one-sample MIS over the lobes: [`Scatterer::sample`],
//!   weight K / pdf with the full mixture pdf) to the nearest fiber crossing. Past the visible point, a
//!   continuation that escapes sees the environment, and it and next-event estimation are weighed by
//!   the balance heuristic; at the visible point (whose direct light is next-event estimation's alone)
//!   and with fixed directional lights (delta lights, SRBF lobe samples) an escaping ray adds nothing;
//! - Russian roulette on the throughput from the third bounce (paths whose throughput has not fallen,
//!   such as lossless ones, are never cut); at most `max_depth` bounces.
//!
//! Components: the direct light at the visible point (order 0) goes into R, TT and TRT per lobe,
//! everything of higher order into MS.global (MS.local is 0), so the multiple-scattering share can be
//! read off the AOVs.
//!
//! Toggles: a path tracer always has occlusion, so `settings.shadows` is ignored (every light is
//! shadowed by the fibers); `settings.multiple_scattering == false` stops at order 0, which gives
//! single scattering with exact shadows.
//!
//! Sampling the kernel ([`Scatterer`]): lobe p is picked with probabilities proportional to a cheap
//! estimate of its energy at the point (floored, so no lobe is starved), plus a uniform-sphere
//! component of probability [`UNIFORM_SHARE`] so the pdf is positive wherever the kernel is. Per lobe,
//! theta_i follows d'Eon et al. 2011's longitudinal function (variance v_p = (2 beta_p)^2, tilt on the
//! outgoing inclination theta'_o = theta_o - 2 alpha_p, sampled as pbrt-v4's `SampleMp`) and the
//! azimuth follows the offset h, uniform in (-1, 1), through phi = phi(p, h). Whatever form the model's
//! own longitudinal function takes, this is only a density: the weight is the true kernel over it.

use crate::envmap::EnvMap;
use crate::envmap::direction::{direction_from_uv, rotate_yaw, uv_from_direction};
use crate::render::reference::shade::{
    LobeRadiance, ShadingHair, ShadingPoint, fold_visible_points,
};
use crate::render::reference::{
    DirectionalLight, REFERENCE_VARIANT, ReferenceLighting, ReferenceScene,
};
use crate::scattering::frame::{FiberAngles, FiberFrame, wrap_angle};
use crate::scattering::marschner::{
    AzimuthalLobe, deon_variance, dphi_dh, ln_longitudinal_deon, phi_p, scattering_s,
    tilted_outgoing,
};
use crate::scattering::params::{HairParams, Lobe, ModelVariant};
use crate::shadow::fiber_grid::{Crossing, FiberGrid};
use glam::{DVec3, Vec3};
use rand_core::{Rng, SeedableRng};
use std::f64::consts::{PI, TAU};

/// Default bounce limit. Measured on the white furnace of tests/path_trace.rs with lossless hair
/// (sigma_a = 0, where nothing but escape ends a path; 64 paths per point), mean radiance with the
/// cut-off at D against D = 64: a 1500-strand bob is within 0.2 % at D = 3; a dense 3000-fiber clump
/// (4 x 2 cm, 80 um, 20 % of the environment seen directly, MS share 77 %) is 1.0 % low at D = 16,
/// 0.5 % at 18, 0.1 % at 22, 0.04 % at 24 and < 0.01 % at 32. So 32 keeps the truncation far below
/// 1 % for any hair; Russian roulette and escapes end most paths long before.
pub const DEFAULT_MAX_DEPTH: u32 = 32;

/// Probability of the uniform-sphere component of the sampling mixture.
pub const UNIFORM_SHARE: f64 = 0.05;

/// Bounces before Russian roulette starts.
const ROULETTE_AFTER: u32 = 3;

/// How the path tracer samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathTraceSettings {
    /// Paths per visible point (each point of a pixel gets this many).
    pub samples_per_pixel: u32,
    /// Most bounces after the primary point (0: single scattering with shadows).
    pub max_depth: u32,
    /// Seed of the per-pixel random streams (deterministic for a given seed).
    pub seed: u64,
}

impl Default for PathTraceSettings {
    fn default() -> Self {
        Self {
            samples_per_pixel: 64,
            max_depth: DEFAULT_MAX_DEPTH,
            seed: 1,
        }
    }
}

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
    fn lobe(&self, k: usize, theta_d: f64) -> AzimuthalLobe {
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
struct Sampler(rand_pcg::Pcg64Mcg);

impl Sampler {
    fn new(seed: u64, a: u64, b: u64) -> Self {
        let mut z =
            seed ^ a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        // splitmix64 finaliser
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        Self(rand_pcg::Pcg64Mcg::seed_from_u64(z))
    }

    fn next(&mut self) -> f64 {
        ((self.0.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
}

/// A cumulative distribution over a list (index drawn proportionally to the weights).
struct Cdf {
    cdf: Vec<f64>,
}

impl Cdf {
    fn new(weights: impl Iterator<Item = f64>) -> Self {
        let mut cdf = Vec::new();
        let mut total = 0.0;
        for w in weights {
            total += w.max(0.0);
            cdf.push(total);
        }
        Self { cdf }
    }

    fn total(&self) -> f64 {
        self.cdf.last().copied().unwrap_or(0.0)
    }

    /// Probability of drawing index i.
    fn probability(&self, i: usize) -> f64 {
        let total = self.total();
        if total <= 0.0 {
            return 0.0;
        }
        (self.cdf[i] - if i > 0 { self.cdf[i - 1] } else { 0.0 }) / total
    }

    /// (index, probability) or None when every weight is 0.
    fn draw(&self, u: f64) -> Option<(usize, f64)> {
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
struct EnvSampler<'a> {
    env: &'a EnvMap,
    yaw: f64,
    cdf: Cdf,
}

impl<'a> EnvSampler<'a> {
    fn new(env: &'a EnvMap, yaw: f64) -> Self {
        let cdf = Cdf::new((0..env.width * env.height).map(|i| {
            let p = env.pixels[i];
            let lum = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            lum.max(0.0) * env.solid_angle(i / env.width)
        }));
        Self { env, yaw, cdf }
    }

    /// A direction and its L(omega) / pdf(omega) from three uniform numbers (uniform in solid angle
    /// within the texel: cos(theta) uniform over the row's band).
    fn sample(&self, u: f64, ju: f64, jv: f64) -> Option<DirectionalLight> {
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
    fn texel(&self, dir: DVec3) -> usize {
        let (u, v) = uv_from_direction(rotate_yaw(dir, -self.yaw));
        let (w, h) = (self.env.width, self.env.height);
        let x = ((u * w as f64) as usize).min(w - 1);
        let y = ((v * h as f64) as usize).min(h - 1);
        y * w + x
    }

    /// Density of [`EnvSampler::sample`] per unit solid angle at a world direction, and the
    /// radiance there.
    fn pdf_and_radiance(&self, dir: DVec3) -> (f64, [f64; 3]) {
        let i = self.texel(dir);
        let y = i / self.env.width;
        let pdf = self.cdf.probability(i) / self.env.solid_angle(y);
        (pdf, self.env.pixels[i].map(|c| c as f64))
    }
}

/// Where next-event estimation gets its light.
enum LightSource<'a> {
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
    fn new(lighting: &'a ReferenceLighting<'a>) -> Self {
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
    fn point_lights(&self, rng: &mut Sampler) -> Vec<DirectionalLight> {
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
    fn sample_one(&self, rng: &mut Sampler) -> Option<(DirectionalLight, Option<f64>)> {
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

/// What the tracer shares between pixels.
struct Tracer<'a> {
    params: &'a HairParams,
    variant: ModelVariant,
    lights: LightSource<'a>,
    grid: &'a FiberGrid,
    settings: PathTraceSettings,
}

/// A point's estimate: the five components, the radiance per scattering order (order 0 = direct) and
/// the furnace deficit (see [`PathTraceStats::furnace_deficit`]).
#[derive(Clone, Debug)]
struct PointEstimate {
    components: [[f64; 3]; 5],
    orders: Vec<[f64; 3]>,
    deficit: [f64; 3],
}

impl PointEstimate {
    fn zero(orders: usize) -> Self {
        Self {
            components: [[0.0; 3]; 5],
            orders: vec![[0.0; 3]; orders],
            deficit: [0.0; 3],
        }
    }

    fn add_scaled(&mut self, o: &PointEstimate, w: f64) {
        for t in 0..5 {
            for c in 0..3 {
                self.components[t][c] += w * o.components[t][c];
            }
        }
        for (a, b) in self.orders.iter_mut().zip(&o.orders) {
            for c in 0..3 {
                a[c] += w * b[c];
            }
        }
        for c in 0..3 {
            self.deficit[c] += w * o.deficit[c];
        }
    }
}

/// The own segment and its neighbours on the same strand (the fiber a ray starts on).
fn is_own(grid: &FiberGrid, own: u32, x: &Crossing) -> bool {
    let Some(o) = grid.segments.get(own as usize) else {
        return false;
    };
    grid.segments[x.segment as usize].strand == o.strand && x.segment.abs_diff(own) <= 1
}

/// Whether a ray from p along d crosses any fiber other than its own.
fn blocked(grid: &FiberGrid, p: Vec3, d: Vec3, own: u32) -> bool {
    let mut hit = false;
    grid.crossings(p, d, 0.0, |x| {
        if !hit && !is_own(grid, own, &x) {
            hit = true;
        }
    });
    hit
}

/// The nearest crossing of a ray from p along d, its own fiber excluded.
fn nearest(grid: &FiberGrid, p: Vec3, d: Vec3, own: u32) -> Option<Crossing> {
    let mut best: Option<Crossing> = None;
    grid.crossings(p, d, 0.0, |x| {
        if !is_own(grid, own, &x) && best.is_none_or(|b| x.t < b.t) {
            best = Some(x);
        }
    });
    best
}

/// The shading point where a ray crosses a segment: on its axis at u.
fn crossing_point(grid: &FiberGrid, x: &Crossing) -> ShadingPoint {
    let s = &grid.segments[x.segment as usize];
    ShadingPoint {
        position: s.a + (s.b - s.a) * x.u,
        tangent: s.b - s.a,
        sigma_a: std::array::from_fn(|c| {
            s.sigma_a[0][c] + x.u * (s.sigma_a[1][c] - s.sigma_a[0][c])
        }),
        segment: x.segment,
    }
}

fn luminance_max(t: [f64; 3]) -> f64 {
    t[0].max(t[1]).max(t[2])
}

impl Tracer<'_> {
    /// `samples_per_pixel` paths from the visible point sp seen along -omega_o, averaged.
    fn trace_point(&self, sp: &ShadingPoint, omega_o: Vec3, rng: &mut Sampler) -> PointEstimate {
        let max_depth = self.settings.max_depth as usize;
        let mut out = PointEstimate::zero(max_depth + 1);
        let spp = self.settings.samples_per_pixel.max(1);
        let primary = Scatterer::new(self.params, self.variant, sp.sigma_a, sp.tangent, omega_o);
        // Unshadowed contribution of every light at the primary point, per lobe.
        let lights = self.lights.point_lights(rng);
        let direct: Vec<[[f64; 3]; 3]> = lights
            .iter()
            .map(|l| {
                let k = primary.kernel(primary.frame.angles(l.direction));
                k.map(|lobe| std::array::from_fn(|c| lobe[c] * l.weight[c]))
            })
            .collect();
        let direct_cdf = Cdf::new(
            direct
                .iter()
                .map(|k| k.iter().map(|l| l[0] + l[1] + l[2]).sum::<f64>()),
        );
        let w = 1.0 / spp as f64;
        for _ in 0..spp {
            // Order 0: one light by its unshadowed contribution, visibility by a shadow ray.
            if let Some((j, prob)) = direct_cdf.draw(rng.next()) {
                let dir = lights[j].direction.as_vec3();
                if !blocked(self.grid, sp.position, dir, sp.segment) {
                    for t in 0..3 {
                        for c in 0..3 {
                            let v = w * direct[j][t][c] / prob;
                            out.components[t][c] += v;
                            out.orders[0][c] += v;
                        }
                    }
                }
            }
            if max_depth == 0 {
                continue;
            }
            self.trace_continuation(sp, &primary, rng, w, &mut out);
        }
        out
    }

    /// The orders >= 1 of one path leaving `start` (whose scatterer is `first`), added with weight w.
    fn trace_continuation(
        &self,
        start: &ShadingPoint,
        first: &Scatterer,
        rng: &mut Sampler,
        w: f64,
        out: &mut PointEstimate,
    ) {
        let max_depth = self.settings.max_depth;
        let mut throughput = [w; 3];
        let mut point = *start;
        let mut owned;
        let mut scatterer = first;
        for depth in 1..=max_depth {
            // Continue: sample the kernel at the current point, go to the nearest fiber.
            let wi = scatterer.sample([rng.next(), rng.next(), rng.next(), rng.next()]);
            let pdf = scatterer.pdf(wi);
            if pdf <= 0.0 || !pdf.is_finite() {
                return;
            }
            let k = scatterer.kernel(wi);
            for c in 0..3 {
                let before = throughput[c];
                throughput[c] *= (k[0][c] + k[1][c] + k[2][c]) / pdf;
                // The furnace deficit's term at this vertex: (1 - K / pdf) estimates 1 - albedo.
                out.deficit[c] += before - throughput[c];
            }
            if luminance_max(throughput) <= 0.0 || !throughput.iter().all(|x| x.is_finite()) {
                return;
            }
            let d = scatterer.frame.direction(wi);
            let Some(x) = nearest(self.grid, point.position, d.as_vec3(), point.segment) else {
                // Escaped: past the primary point, the environment seen by kernel sampling, weighed
                // against next-event estimation by the balance heuristic (the primary point's
                // direct light is next-event estimation's alone).
                if depth >= 2
                    && let LightSource::Image { sampler, .. } = &self.lights
                {
                    let (pdf_env, radiance) = sampler.pdf_and_radiance(d);
                    let mis = pdf / (pdf + pdf_env);
                    for c in 0..3 {
                        let v = throughput[c] * radiance[c] * mis;
                        out.components[3][c] += v;
                        out.orders[depth as usize - 1][c] += v;
                    }
                }
                return;
            };
            point = crossing_point(self.grid, &x);
            owned = Scatterer::new(
                self.params,
                self.variant,
                point.sigma_a,
                point.tangent,
                -d.as_vec3(),
            );
            scatterer = &owned;
            // Next-event estimation: one light (balance heuristic against kernel sampling for
            // the environment image).
            if let Some((l, pdf_light)) = self.lights.sample_one(rng) {
                let dir = l.direction.as_vec3();
                let wl = scatterer.frame.angles(l.direction);
                let k = scatterer.kernel(wl);
                let sum: [f64; 3] = std::array::from_fn(|c| k[0][c] + k[1][c] + k[2][c]);
                if sum.iter().any(|&s| s > 0.0)
                    && !blocked(self.grid, point.position, dir, point.segment)
                {
                    let mis = pdf_light.map_or(1.0, |pl| pl / (pl + scatterer.pdf(wl)));
                    for c in 0..3 {
                        let v = throughput[c] * sum[c] * l.weight[c] * mis;
                        out.components[3][c] += v;
                        out.orders[depth as usize][c] += v;
                    }
                }
            }
            if depth >= ROULETTE_AFTER {
                // Relative to the sample's weight w: lossless paths (throughput ~w) are not cut.
                let survive = (luminance_max(throughput) / w).min(1.0);
                if survive < 1.0 {
                    if rng.next() >= survive {
                        return;
                    }
                    throughput = throughput.map(|t| t / survive);
                }
            }
        }
    }
}

/// The per-pixel loop of [`crate::render::reference::shade::shade_pixels`] (same rays, same points, same coverage
/// weights), with a seeded random stream per pixel and point, over the given pixels in parallel.
fn trace_pixels(
    frame: &crate::render::Frame,
    scene: &ReferenceScene,
    settings: &PathTraceSettings,
    pixels: &[usize],
) -> Vec<PointEstimate> {
    let grid = FiberGrid::build(scene.hair, scene.sigma_a);
    let hair = ShadingHair::new(scene.hair, scene.sigma_a);
    let cam = scene
        .camera
        .uniform(frame.width, frame.height, scene.settings.min_width_px);
    let mut settings = *settings;
    if !scene.settings.multiple_scattering {
        settings.max_depth = 0;
    }
    let tracer = Tracer {
        variant: REFERENCE_VARIANT.with_longitudinal(scene.look.longitudinal()),
        params: &scene.look.params,
        lights: LightSource::new(&scene.lighting),
        grid: &grid,
        settings,
    };
    let orders = settings.max_depth as usize + 1;
    fold_visible_points(
        frame,
        &cam,
        &hair,
        pixels,
        || PointEstimate::zero(orders),
        |acc, pixel, sp, omega_o, weight| {
            let mut rng = Sampler::new(settings.seed, pixel as u64, sp.segment as u64 + 1);
            let e = tracer.trace_point(sp, omega_o, &mut rng);
            acc.add_scaled(&e, weight);
        },
    )
}

/// The path-traced shading of the points the GPU frame sees (same coverage, depth and ids); its
/// components replace the frame's and the exposure is applied. Order 0 goes into R, TT, TRT, higher
/// orders into MS.global.
pub fn path_trace_frame(
    frame: &crate::render::Frame,
    scene: &ReferenceScene,
    settings: &PathTraceSettings,
) -> crate::render::Frame {
    path_trace_frame_with_stats(frame, scene, settings).0
}

/// What [`path_trace_frame_with_stats`] measures besides the frame: sums over the covered pixels
/// divided by their summed coverage, so means over the hair as the beauty over alpha is, before
/// exposure.
#[derive(Clone, Debug, PartialEq)]
pub struct PathTraceStats {
    /// Radiance per scattering order (index 0: direct; k: k bounces after the primary point). The
    /// mean with the depth cut-off at D is the sum of orders 0..=D (Russian roulette keeps each
    /// unbiased).
    pub orders: Vec<[f64; 3]>,
    /// In a uniform white environment of radiance 1, the energy the hair loses on the way to the
    /// eye: 1 - L = (1 - A) + integral K (1 - V) (1 - L(y)) d omega (A the kernel's albedo, V the
    /// visibility), estimated along the continuation paths alone, (1 - K / pdf) per vertex times the
    /// throughput, with no light and no shadow ray. So mean radiance + deficit = 1 in expectation
    /// whatever the kernel's albedo: a check of the estimator's bookkeeping (next-event estimation,
    /// shadow rays and the lights against the continuation sampling). Only meaningful with multiple
    /// scattering and a white furnace.
    pub furnace_deficit: [f64; 3],
}

/// As [`path_trace_frame`], plus [`PathTraceStats`].
pub fn path_trace_frame_with_stats(
    frame: &crate::render::Frame,
    scene: &ReferenceScene,
    settings: &PathTraceSettings,
) -> (crate::render::Frame, PathTraceStats) {
    let pixels: Vec<usize> = frame.covered().collect();
    let estimates = trace_pixels(frame, scene, settings, &pixels);
    let coverage: f64 = pixels.iter().map(|&i| frame.beauty[i][3] as f64).sum();
    let norm = 1.0 / coverage.max(1e-30);
    let mut stats = PathTraceStats {
        orders: vec![[0.0f64; 3]; estimates.first().map_or(1, |e| e.orders.len())],
        furnace_deficit: [0.0; 3],
    };
    for e in &estimates {
        for (a, b) in stats.orders.iter_mut().zip(&e.orders) {
            for c in 0..3 {
                a[c] += b[c] * norm;
            }
        }
        for c in 0..3 {
            stats.furnace_deficit[c] += e.deficit[c] * norm;
        }
    }
    let radiance: Vec<LobeRadiance> = estimates
        .iter()
        .map(|e| e.components.map(|l| l.map(|x| x as f32)))
        .collect();
    let out = frame.with_components(&pixels, &radiance, scene.settings.exposure.exp2());
    (out, stats)
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
