//! A brute-force path-traced reference (CPU, rayon): the same visible points as the GPU frame, lit by
//! the reference mode's lighting ([`crate::render::reference::ReferenceLighting`]), with every order of
//! scattering traced through the explicit fibers ([`FiberGrid`]). It is the ground truth for the
//! renderer's dual scattering and for the reference mode's ray shooting: nothing in it is fitted or
//! approximated but the environment image's texels (constant radiance per texel).
//!
//! Estimator, per visible point and path (unbiased up to the depth cut-off):
//! - the kernel is the exact model, K(omega_i, omega_o) = S(omega_i, omega_o) cos(theta_i) per lobe
//!   ([`crate::scattering::marschner::scattering_s`] with [`REFERENCE_VARIANT`] and the look's longitudinal function); radiance
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

pub mod sampling;

use crate::render::reference::shade::{
    LobeRadiance, ShadingHair, ShadingPoint, fold_visible_points,
};
use crate::render::reference::{REFERENCE_VARIANT, ReferenceScene};
use crate::scattering::params::{HairParams, ModelVariant};
use crate::shadow::fiber_grid::{Crossing, FiberGrid};
use glam::Vec3;
use sampling::{Cdf, LightSource, Sampler, Scatterer};

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
