//! The reference mode: the same visible points shaded with the exact Marschner model (Schlick Fresnel,
//! bare root sum: the variant Xu's fast form approximates) under directional lights, importance-sampled
//! from the full environment image (not its SRBF fit) or sampled from SRBF lobes. CPU, rayon. It
//! exists to measure the SRBF renderer's error honestly.
//!
//! Shadows, two ways:
//! - single scattering: each direction is attenuated by the exact-direction transmittance exp(-tau) of
//!   the same fiber-density volume the renderer builds;
//! - with multiple scattering: Zinke's ray shooting (Sec. 4.1.1, [`crate::shadow::ray_shooting`]):
//!   every direction's shadow ray is traced through the explicit fibers; a free ray carries single
//!   scattering plus d_b f_back, a blocked one carries (T_f d_f)(f_s^G + d_b f_back^G) with that ray's
//!   own T_f and per-channel sigma_f^2. The dual-scattering responses are those of
//!   [`crate::scattering::dual_response`] for a directional light (lambda = 0) with 16 quadrature
//!   segments; they are checked against direct quadrature of Xu's Eq. 27-31 in tests/dual_terms.rs.
//!   What this reference does not share with the renderer is what the renderer approximates: the
//!   fiber-density volume, the SRBF cone filtering and the shadow grid's interpolation.

pub mod abuffer;
pub mod lights;
pub mod path_trace;
pub mod ribbon;
pub mod shade;

use crate::envmap::EnvMap;
use crate::render::reference::shade::{LobeRadiance, ShadingPoint, fiber_angles, fiber_frame};
use crate::scattering::azimuthal_table::AzimuthalTable;
use crate::scattering::dual_response::{
    dual_scattering_components, global_response_lobe_in_view, local_response_behind,
};
use crate::scattering::dual_terms::DualTables;
use crate::scattering::dual_terms::HairBehind;
use crate::scattering::fast_params::FastHairParams;
use crate::scattering::fast_response::{LongitudinalLobe, SrbfInFrame};
use crate::scattering::frame::{FiberAngles, FiberFrame};
use crate::scattering::marschner::scattering_s;
use crate::scattering::params::{CausticModel, HairParams, ModelVariant};
use crate::shadow::fiber_density::FiberDensity;
use crate::shadow::fiber_grid::FiberGrid;
use crate::shadow::forward::{ForwardScattering, ForwardTable};
use crate::shadow::ray_shooting::{crossings_behind, shoot_forward};
use glam::Vec3;

pub use crate::render::reference::lights::{
    DirectionalLight, importance_sample_env, sample_srbf_lights,
};

/// The variant the fast model approximates (and the reference evaluates).
pub const REFERENCE_VARIANT: ModelVariant = ModelVariant {
    caustic: CausticModel::None,
    ..ModelVariant::XU
};

/// Quadrature segments of the reference's responses (the renderer uses Xu's m = 4); its dual terms
/// integrate with half of them ([`crate::scattering::dual_response::dual_quadrature_segments`]: 8).
pub const REFERENCE_QUADRATURE_SEGMENTS: u32 = 16;

/// What dual scattering needs besides the hair parameters.
pub struct DualReference<'a> {
    /// The explicit fibers (None: no shadows, every ray is free).
    pub fibers: Option<&'a FiberGrid>,
    pub forward: &'a ForwardTable,
    pub dual: &'a DualTables,
    /// d_f, d_b and the parameters in the fast model's form (its sigma_a is replaced per point).
    pub fast: FastHairParams,
    /// The azimuthal table of `fast`'s eta and eccentricity.
    pub azimuthal: &'a AzimuthalTable,
}

/// How the reference shadows each direction.
pub enum ReferenceShadows<'a> {
    None,
    /// exp(-tau) of the volume along the exact direction, past `skip` (single scattering only).
    Volume(&'a FiberDensity, f32),
    /// Ray shooting through the fibers, with single and dual scattering.
    Dual(&'a DualReference<'a>),
}

/// Radiance per lobe towards omega_o: sum over the lights of weight S(omega_i, omega_o) cos(theta_i) T
/// (R, TT, TRT) and, with [`ReferenceShadows::Dual`], MS.global and MS.local.
pub fn reference_shade(
    params: &HairParams,
    variant: ModelVariant,
    sp: &ShadingPoint,
    omega_o: Vec3,
    lights: &[DirectionalLight],
    shadows: &ReferenceShadows,
) -> LobeRadiance {
    let mut p = *params;
    p.sigma_a = sp.sigma_a.map(|s| s as f64);
    let (u, v, _) = fiber_frame(sp.tangent);
    let frame = FiberFrame::with_normal(u.as_dvec3(), v.as_dvec3());
    let wo: FiberAngles = frame.angles(omega_o.as_dvec3());
    let mut out = [[0.0f64; 3]; 5];
    for l in lights {
        let wi = frame.angles(l.direction);
        let dir = l.direction.as_vec3();
        let vis = match shadows {
            ReferenceShadows::None => 1.0,
            ReferenceShadows::Volume(vol, skip) => {
                vol.transmittance(sp.position, dir, *skip) as f64
            }
            ReferenceShadows::Dual(d) => {
                let (f, behind) =
                    d.fibers
                        .map_or((FREE_RAY, HairBehind::OpticalDepth(f32::INFINITY)), |g| {
                            (
                                shoot_forward(g, d.forward, sp.position, dir, sp.segment),
                                HairBehind::Fibers(crossings_behind(
                                    g,
                                    sp.position,
                                    dir,
                                    sp.segment,
                                )),
                            )
                        });
                let ms = dual_directional(d, sp, omega_o, dir, &f, behind);
                for c in 0..3 {
                    out[3][c] += l.weight[c] * ms.0[c] as f64;
                    out[4][c] += l.weight[c] * ms.1[c] as f64;
                }
                f.direct_fraction as f64
            }
        };
        if vis <= 0.0 {
            continue;
        }
        let s = scattering_s(&p, variant, wi, wo);
        let k = vis * wi.theta.cos();
        for (t, lobe) in [s.r, s.tt, s.trt].iter().enumerate() {
            for c in 0..3 {
                out[t][c] += k * l.weight[c] * lobe[c];
            }
        }
    }
    out.map(|lobe| lobe.map(|x| x as f32))
}

const FREE_RAY: ForwardScattering = ForwardScattering {
    direct_fraction: 1.0,
    transmittance_f: [1.0; 3],
    sigma_f2: [0.0; 3],
};

/// (MS.global, MS.local) per unit irradiance-weight from one direction whose shadow ray found `f`,
/// with `behind` the fibers behind the point along the light's travel (counted: A_b's sum stopped
/// there; the renderer's volume gives the Poisson mean of that count instead).
fn dual_directional(
    d: &DualReference,
    sp: &ShadingPoint,
    omega_o: Vec3,
    dir: Vec3,
    f: &ForwardScattering,
    behind: HairBehind,
) -> ([f32; 3], [f32; 3]) {
    let mut fp = d.fast;
    fp.sigma_a = [sp.sigma_a[0], sp.sigma_a[1], sp.sigma_a[2], 0.0];
    fp.quadrature_segments = REFERENCE_QUADRATURE_SEGMENTS;
    let frame = fiber_frame(sp.tangent);
    let (theta_o, phi_o) = fiber_angles(frame, omega_o);
    let (theta, phi) = fiber_angles(frame, dir);
    let light = SrbfInFrame {
        theta,
        phi,
        lambda: 0.0,
    };
    // The direct part's local term weighs with the direct fraction (0 or 1 per ray).
    let local_direct = if f.direct_fraction > 0.0 {
        local_response_behind(&fp, d.dual, light, theta_o, phi_o, [0.0; 3], behind)
    } else {
        [0.0; 3]
    };
    let (mut global, mut local) = ([0.0f32; 3], [0.0f32; 3]);
    if f.direct_fraction < 1.0 {
        // Each channel with its own sigma_f^2 (the renderer uses their mean).
        for t in 0..3 {
            let longitudinal = LongitudinalLobe::of_lobe(&fp, t, theta_o);
            for c in 0..3 {
                global[c] += global_response_lobe_in_view(
                    d.azimuthal,
                    &fp,
                    t,
                    &longitudinal,
                    light,
                    phi_o,
                    f.sigma_f2[c],
                )[c];
            }
        }
        local = local_response_behind(&fp, d.dual, light, theta_o, phi_o, f.sigma_f2, behind);
    }
    dual_scattering_components(
        &fp,
        f.direct_fraction,
        f.transmittance_f,
        local_direct,
        global,
        local,
    )
}

/// The reference's lights.
pub enum ReferenceLighting<'a> {
    /// `directions` importance-sampled from the image, turned by `yaw` about +Y as its SRBF lights are.
    Environment {
        env: &'a EnvMap,
        yaw: f64,
        directions: usize,
    },
    /// Given directional lights (for example [`sample_srbf_lights`]).
    Directional(Vec<DirectionalLight>),
}

impl ReferenceLighting<'_> {
    pub fn lights(&self) -> Vec<DirectionalLight> {
        match self {
            ReferenceLighting::Environment {
                env,
                yaw,
                directions,
            } => importance_sample_env(env, *directions, *yaw, 7),
            ReferenceLighting::Directional(l) => l.clone(),
        }
    }
}

/// What the reference needs besides the visibility of a frame.
pub struct ReferenceScene<'a> {
    pub hair: &'a crate::hair::Hair,
    pub sigma_a: &'a [[f32; 3]],
    pub look: &'a crate::render::HairLook,
    pub lighting: ReferenceLighting<'a>,
    pub settings: &'a crate::render::RenderSettings,
    pub camera: &'a crate::render::Camera,
}

/// The reference shading of the points the GPU frame sees (same coverage, depth and ids); its
/// components replace the frame's and the exposure is applied. With `settings.multiple_scattering`
/// it is dual scattering by ray shooting through the fibers (shadows by the same rays); without, single
/// scattering with the volume's exp(-tau) (or no) shadows.
pub fn reference_frame(
    frame: &crate::render::Frame,
    scene: &ReferenceScene,
) -> crate::render::Frame {
    let lights = scene.lighting.lights();
    let settings = scene.settings;
    let variant = REFERENCE_VARIANT.with_longitudinal(scene.look.longitudinal());
    let params = &scene.look.params;
    let hair = crate::render::reference::shade::ShadingHair::new(scene.hair, scene.sigma_a);
    let cam = scene
        .camera
        .uniform(frame.width, frame.height, settings.min_width_px);
    let pixels: Vec<usize> = frame.covered().collect();
    let shade = |shadows: &ReferenceShadows| {
        crate::render::reference::shade::shade_pixels(
            frame,
            &cam,
            &hair,
            &pixels,
            crate::render::reference::shade::EVERY_FRAGMENT,
            |sp, wo| reference_shade(params, variant, sp, wo, &lights, shadows),
        )
    };
    let radiance = if settings.multiple_scattering {
        let fibers = settings
            .shadows
            .then(|| FiberGrid::build(scene.hair, scene.sigma_a));
        // The tables the renderer reads (each point reads them at its own absorption): the same
        // build, taken from the process's cache when the renderer made them.
        let tables = crate::render::renderer::build_tables(params, None);
        let azimuthal = if tables.azimuthal.matches(&scene.look.fast) {
            tables.azimuthal.clone()
        } else {
            std::sync::Arc::new(AzimuthalTable::for_params(&scene.look.fast))
        };
        let d = DualReference {
            fibers: fibers.as_ref(),
            forward: &tables.forward,
            dual: &tables.dual,
            fast: scene.look.fast,
            azimuthal: &azimuthal,
        };
        shade(&ReferenceShadows::Dual(&d))
    } else {
        let volume = settings.shadows.then(|| {
            FiberDensity::build(scene.hair, scene.sigma_a, settings.voxel_size(scene.hair))
        });
        shade(&volume.as_ref().map_or(ReferenceShadows::None, |v| {
            ReferenceShadows::Volume(v, settings.shadow_skip(scene.hair))
        }))
    };
    frame.with_components(&pixels, &radiance, settings.exposure.exp2())
}
