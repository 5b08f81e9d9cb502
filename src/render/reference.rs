//! The reference mode: the same visible points shaded with the exact Marschner model (Schlick Fresnel,
//! bare root sum: the variant Xu's fast form approximates) under directional lights importance-sampled
//! from the full environment image (not its SRBF fit), each shadowed by the exact-direction
//! transmittance exp(-tau) of the same fiber-density volume. CPU, rayon. It exists to measure the
//! SRBF renderer's error honestly.

use super::shade::{LobeRadiance, ShadingPoint, fiber_frame};
use crate::envmap::EnvMap;
use crate::envmap::direction::{direction_from_uv, rotate_yaw};
use crate::scattering::frame::{FiberAngles, FiberFrame};
use crate::scattering::marschner::scattering_s;
use crate::scattering::params::{CausticModel, FresnelModel, HairParams, ModelVariant};
use crate::shadow::fiber_density::FiberDensity;
use glam::{DVec3, Vec3};
use rand_core::{Rng, SeedableRng};

/// The variant the fast model approximates (and the reference evaluates).
pub const REFERENCE_VARIANT: ModelVariant = ModelVariant {
    fresnel: FresnelModel::XuSchlick,
    caustic: CausticModel::None,
};

/// A directional light carrying its share of the environment's integral: L(omega) / (pdf N), summed
/// over the samples that fell in the same texel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    pub direction: DVec3,
    pub weight: [f64; 3],
}

/// `n` stratified samples of the environment proportional to luminance x solid angle (texel CDF
/// inversion, uniform within the texel), merged per texel. Their weights sum to the texels' integral of
/// L d omega up to sampling error; `yaw` turns them as `SrbfSet::rotated` turns lights.
pub fn importance_sample_env(env: &EnvMap, n: usize, yaw: f64, seed: u64) -> Vec<DirectionalLight> {
    let (w, h) = (env.width, env.height);
    let mut cdf = Vec::with_capacity(w * h + 1);
    cdf.push(0.0f64);
    let mut total = 0.0;
    for y in 0..h {
        let omega = env.solid_angle(y);
        for x in 0..w {
            let p = env.pixels[y * w + x];
            let lum = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            total += lum.max(0.0) * omega;
            cdf.push(total);
        }
    }
    if total <= 0.0 || n == 0 {
        return Vec::new();
    }
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(seed);
    let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let mut merged: std::collections::BTreeMap<usize, DirectionalLight> = Default::default();
    for k in 0..n {
        let target = (k as f64 + unit()) / n as f64 * total;
        let i = cdf.partition_point(|&c| c <= target).clamp(1, w * h) - 1;
        let (x, y) = (i % w, i / w);
        let pdf_texel = (cdf[i + 1] - cdf[i]) / total;
        if pdf_texel <= 0.0 {
            continue;
        }
        let omega = env.solid_angle(y);
        let (ju, jv) = (unit(), unit());
        let d = direction_from_uv((x as f64 + ju) / w as f64, (y as f64 + jv) / h as f64);
        let d = rotate_yaw(d, yaw);
        let p = env.pixels[i];
        let scale = omega / (pdf_texel * n as f64);
        let e = merged.entry(i).or_insert(DirectionalLight {
            direction: DVec3::ZERO,
            weight: [0.0; 3],
        });
        // Several samples in one texel: one light along their mean direction.
        e.direction += d;
        for c in 0..3 {
            e.weight[c] += p[c] as f64 * scale;
        }
    }
    merged
        .into_values()
        .map(|mut l| {
            l.direction = l.direction.normalize();
            l
        })
        .collect()
}

/// Radiance per lobe towards omega_o: sum over the lights of weight S(omega_i, omega_o) cos(theta_i) T.
pub fn reference_shade(
    params: &HairParams,
    sp: &ShadingPoint,
    omega_o: Vec3,
    lights: &[DirectionalLight],
    shadows: Option<(&FiberDensity, f32)>,
) -> LobeRadiance {
    let mut p = *params;
    p.sigma_a = sp.sigma_a.map(|s| s as f64);
    let (u, v, _) = fiber_frame(sp.tangent);
    let frame = FiberFrame::with_normal(u.as_dvec3(), v.as_dvec3());
    let wo: FiberAngles = frame.angles(omega_o.as_dvec3());
    let mut out = [[0.0f64; 3]; 3];
    for l in lights {
        let wi = frame.angles(l.direction);
        let vis = shadows.map_or(1.0, |(vol, skip)| {
            vol.transmittance(sp.position, l.direction.as_vec3(), skip) as f64
        });
        if vis <= 0.0 {
            continue;
        }
        let s = scattering_s(&p, REFERENCE_VARIANT, wi, wo);
        let k = vis * wi.theta.cos();
        for (t, lobe) in [s.r, s.tt, s.trt].iter().enumerate() {
            for c in 0..3 {
                out[t][c] += k * l.weight[c] * lobe[c];
            }
        }
    }
    let mut radiance = [[0.0; 3]; 5];
    for t in 0..3 {
        radiance[t] = out[t].map(|x| x as f32);
    }
    radiance
}

/// What the reference needs besides the visibility of a frame.
pub struct ReferenceScene<'a> {
    pub hair: &'a crate::hair::Hair,
    pub sigma_a: &'a [[f32; 3]],
    pub params: &'a HairParams,
    pub env: &'a EnvMap,
    /// Rotation of the environment about +Y (radians), as applied to its SRBF lights.
    pub yaw: f64,
    /// Directions sampled from the environment (at least 1024 for the fidelity figures).
    pub directions: usize,
    pub settings: &'a super::RenderSettings,
    pub camera: &'a super::Camera,
}

/// The reference shading of the points the GPU frame sees (same coverage, depth and ids); its
/// components R, TT, TRT replace the frame's, multiple scattering is zero (single scattering only: the
/// multiple-scattering reference is still to come), the exposure is applied.
pub fn reference_frame(frame: &super::Frame, scene: &ReferenceScene) -> super::Frame {
    let lights = importance_sample_env(scene.env, scene.directions, scene.yaw, 7);
    let settings = scene.settings;
    let volume = settings
        .shadows
        .then(|| FiberDensity::build(scene.hair, scene.sigma_a, settings.voxel_size(scene.hair)));
    let skip = settings.shadow_skip(scene.hair);
    let hair = super::shade::ShadingHair::new(scene.hair, scene.sigma_a);
    let cam = scene
        .camera
        .uniform(frame.width, frame.height, settings.min_width_px);
    let pixels: Vec<usize> = frame.covered().collect();
    let shadows = volume.as_ref().map(|v| (v, skip));
    let radiance = super::shade::shade_pixels(frame, &cam, &hair, &pixels, |sp, wo| {
        reference_shade(scene.params, sp, wo, &lights, shadows)
    });
    frame.with_components(&pixels, &radiance, settings.exposure.exp2())
}
