//! The shading kernel on the CPU: the twin of `shaders/shading.wgsl` (same shading points, same fast
//! response, same swept transmittance) used to test the GPU end to end, and the pixel loop the
//! reference mode shares with it.

use crate::envmap::SrbfLight;
use crate::envmap::srbf::srbf_integral;
use crate::hair::Hair;
use crate::render::camera::{CameraUniform, closest_on_segment, pixel_ray};
use crate::render::frame::Frame;
use crate::render::passes::kbuffer::{Fragment, PixelFragments};
use crate::scattering::azimuthal_table::AzimuthalTable;
use crate::scattering::dual_response::{
    dual_scattering_components, global_response_lobe_in_view, local_response,
};
use crate::scattering::dual_terms::DualTables;
use crate::scattering::fast_params::FastHairParams;
use crate::scattering::fast_response::{SrbfInFrame, srbf_response_in_view, view_lobes};
use crate::scattering::lut::Luts;
use crate::shadow::grid::{GridShadow, GridValues};
use glam::Vec3;
use rayon::prelude::*;

pub type Rgb = [f32; 3];

/// Radiance per component (R, TT, TRT, MS.global, MS.local).
pub type LobeRadiance = [Rgb; 5];

/// A visible point on a fiber.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    pub position: Vec3,
    pub tangent: Vec3,
    pub sigma_a: Rgb,
    /// The segment the point lies on.
    pub segment: u32,
}

/// The first point of every segment, in the order the GPU numbers segments.
pub fn segment_starts(hair: &Hair) -> Vec<u32> {
    (0..hair.strand_count())
        .flat_map(|s| {
            let r = hair.strand_range(s);
            (r.start as u32)..(r.end as u32).saturating_sub(1).max(r.start as u32)
        })
        .collect()
}

/// The hair as the shading kernel reads it.
pub struct ShadingHair<'a> {
    pub hair: &'a Hair,
    pub segments: Vec<u32>,
    pub sigma_a: &'a [[f32; 3]],
}

impl<'a> ShadingHair<'a> {
    pub fn new(hair: &'a Hair, sigma_a: &'a [[f32; 3]]) -> Self {
        Self {
            hair,
            segments: segment_starts(hair),
            sigma_a,
        }
    }

    /// `shading_point` of the WGSL: the point of segment `seg` closest to the ray.
    pub fn shading_point(&self, seg: u32, origin: Vec3, dir: Vec3) -> ShadingPoint {
        let i0 = self.segments[seg as usize] as usize;
        let (a, b) = (self.hair.positions[i0], self.hair.positions[i0 + 1]);
        let t = closest_on_segment(origin, dir, a, b);
        let (s0, s1) = (self.sigma_a[i0], self.sigma_a[i0 + 1]);
        ShadingPoint {
            position: a + (b - a) * t,
            tangent: b - a,
            sigma_a: std::array::from_fn(|c| s0[c] + (s1[c] - s0[c]) * t),
            segment: seg,
        }
    }
}

impl ShadingHair<'_> {
    /// `segment_point` of the WGSL: the point of segment `seg` at t (0: its first point, 1: its
    /// second), its absorption linear along it.
    pub fn segment_point(&self, seg: u32, t: f32) -> ShadingPoint {
        let i0 = self.segments[seg as usize] as usize;
        let (a, b) = (self.hair.positions[i0], self.hair.positions[i0 + 1]);
        let (s0, s1) = (self.sigma_a[i0], self.sigma_a[i0 + 1]);
        ShadingPoint {
            position: a * (1.0 - t) + b * t,
            tangent: b - a,
            sigma_a: std::array::from_fn(|c| s0[c] * (1.0 - t) + s1[c] * t),
            segment: seg,
        }
    }

    /// `ms_key` of the WGSL: multiple scattering varies slowly along a strand (spread over sigma_f,
    /// read from the coarse shadow grid), so it is evaluated once per pair of consecutive segments of
    /// a strand (2k and 2k + 1, when 2k + 1 continues 2k and the pair's three points have the same
    /// absorption) at the point they share ([`ShadingHair::ms_point`]), and read by both: the key of
    /// segment `seg`'s pair is its even segment; a segment without a pair (a strand's first or last
    /// segment where the pairs, counted over the whole hair, straddle its ends; paint that varies
    /// along the pair) is its own key, sampled at its midpoint.
    pub fn ms_key(&self, seg: u32) -> u32 {
        let even = seg & !1;
        if ms_paired(&self.segments, self.sigma_a, even) {
            even
        } else {
            seg
        }
    }

    /// `ms_point` of the WGSL: where multiple scattering is evaluated for key `key`
    /// ([`ShadingHair::ms_key`]): a pair's shared point, its tangent the pair's chord (the first
    /// segment's where the pair folds back onto its first point), or an unpaired segment's midpoint.
    pub fn ms_point(&self, key: u32) -> ShadingPoint {
        if key & 1 == 1 || !ms_paired(&self.segments, self.sigma_a, key) {
            return self.segment_point(key, 0.5);
        }
        let i0 = self.segments[key as usize] as usize;
        let p = &self.hair.positions;
        let chord = p[i0 + 2] - p[i0];
        ShadingPoint {
            position: p[i0 + 1],
            tangent: if chord.dot(chord) > 0.0 {
                chord
            } else {
                p[i0 + 1] - p[i0]
            },
            sigma_a: self.sigma_a[i0 + 1],
            segment: key,
        }
    }
}

/// `ms_paired` of the WGSL over a hair's segments (`segments`: each one's first point) and absorption
/// per point: whether segments `even` and `even` + 1 share a multiple-scattering sample (the second
/// continues the first and their three points' absorption is the same).
pub fn ms_paired(segments: &[u32], sigma_a: &[[f32; 3]], even: u32) -> bool {
    if strand_partner(segments, even).is_none() {
        return false;
    }
    let i0 = segments[even as usize] as usize;
    let s = sigma_a[i0 + 1];
    sigma_a[i0] == s && sigma_a[i0 + 2] == s
}

/// The segment that makes a multiple-scattering pair with segment `seg` where their absorption allows
/// ([`ShadingHair::ms_key`]): 2k + 1 for 2k and 2k for 2k + 1, when 2k + 1 continues 2k in its
/// strand (`segments`: each segment's first point).
pub fn strand_partner(segments: &[u32], seg: u32) -> Option<u32> {
    let even = (seg & !1) as usize;
    (even + 1 < segments.len() && segments[even + 1] == segments[even] + 1).then_some(seg ^ 1)
}

/// FiberFrame::from_tangent in f32 (twin of `fiber_frame` in `shaders/camera.wgsl`): (u, v, w).
pub fn fiber_frame(tangent: Vec3) -> (Vec3, Vec3, Vec3) {
    let u = tangent.normalize();
    let helper = if u.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let v = (helper - u * helper.dot(u)).normalize();
    (u, v, u.cross(v))
}

/// (theta, phi) of a unit direction in the frame (twin of `fiber_angles`).
pub fn fiber_angles(frame: (Vec3, Vec3, Vec3), omega: Vec3) -> (f32, f32) {
    let (u, v, w) = frame;
    (
        crate::scattering::circular_gaussian::asin_precise(omega.dot(u).clamp(-1.0, 1.0)),
        omega.dot(w).atan2(omega.dot(v)),
    )
}

/// Where the shading pass reads shadows from: the grid's values for the same lights, in order
/// (`shade_point`'s light k reads the grid's light k).
pub type GridShadows<'a> = &'a GridValues;

/// `shade_point` of the WGSL: lights' R, TT, TRT radiance towards omega_o, each light scaled by its
/// transmittance read from the shadow grid when shadows are given; with `dual` (the dual-scattering
/// tables), also MS.global and MS.local.
#[allow(clippy::too_many_arguments)]
pub fn shade_point(
    luts: &Luts,
    table: &AzimuthalTable,
    params: &FastHairParams,
    sp: &ShadingPoint,
    omega_o: Vec3,
    lights: &[SrbfLight],
    shadows: Option<GridShadows>,
    dual: Option<&DualTables>,
) -> LobeRadiance {
    let mut p = *params;
    p.sigma_a = [sp.sigma_a[0], sp.sigma_a[1], sp.sigma_a[2], 0.0];
    let frame = fiber_frame(sp.tangent);
    let (theta_o, phi_o) = fiber_angles(frame, omega_o);
    let lobes = view_lobes(&p, theta_o);
    let mut out = [[0.0; 3]; 5];
    for (li, l) in lights.iter().enumerate() {
        let dir = l.dir().normalize().as_vec3();
        let lambda = l.lambda as f32;
        let (theta, phi) = fiber_angles(frame, dir);
        let sh = shadows.map_or(
            GridShadow {
                transmittance: 1.0,
                transmittance_f: [1.0; 3],
                sigma_f2: [0.0; 3],
                depth_behind: f32::INFINITY,
            },
            |g| g.shadow(sp.position, li),
        );
        let light = SrbfInFrame { theta, phi, lambda };
        let m = srbf_response_in_view(luts, table, &p, &lobes, light, phi_o);
        for t in 0..3 {
            for c in 0..3 {
                out[t][c] += sh.transmittance * l.rgb[c] as f32 * m[t][c];
            }
        }
        let Some(tables) = dual else {
            continue;
        };
        let s2 = (sh.sigma_f2[0] + sh.sigma_f2[1] + sh.sigma_f2[2]) / 3.0;
        // Only what Zinke's combination does not multiply by zero (as the WGSL): the forward-scattered
        // part where T_f exceeds the direct fraction, the direct part where light arrives directly.
        let (mut global, mut local, mut local_direct) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        if sh.transmittance > 0.0 {
            local_direct = local_response(&p, tables, light, theta_o, phi_o, 0.0, sh.depth_behind);
        }
        if sh.transmittance_f.iter().any(|&t| t > sh.transmittance) {
            for t in 0..3 {
                let g = global_response_lobe_in_view(
                    table,
                    &p,
                    t,
                    &lobes[t as usize],
                    light,
                    phi_o,
                    s2,
                );
                for c in 0..3 {
                    global[c] += g[c];
                }
            }
            local = if s2 == 0.0 && sh.transmittance > 0.0 {
                local_direct
            } else {
                local_response(&p, tables, light, theta_o, phi_o, s2, sh.depth_behind)
            };
        }
        let (ms_global, ms_local) = dual_scattering_components(
            &p,
            sh.transmittance,
            sh.transmittance_f,
            local_direct,
            global,
            local,
        );
        let power = srbf_integral(l.lambda) as f32;
        for c in 0..3 {
            out[3][c] += power * l.rgb[c] as f32 * ms_global[c];
            out[4][c] += power * l.rgb[c] as f32 * ms_local[c];
        }
    }
    out
}

/// Single scattering of a segment at its samples t = 0, 1/2, 1, per sample per lobe (R, TT, TRT).
pub type SegmentSingle = [[Rgb; 3]; 3];

/// `shade_segment_single` of the WGSL: a segment's single scattering at t = 0, 1/2, 1 towards omega_o,
/// each light's response at the midpoint `mid` (its tangent and view), scaled by the light's
/// transmittance at each sample (`ends`: the segment's ends, their positions and absorption). One
/// response per light where the ends' absorption is the same (the midpoint's that response too);
/// where it differs one at each end's, the midpoint's between them ([`between_ends`]).
#[allow(clippy::too_many_arguments)]
pub fn shade_segment_single(
    luts: &Luts,
    table: &AzimuthalTable,
    params: &FastHairParams,
    mid: &ShadingPoint,
    ends: [ShadingPoint; 2],
    omega_o: Vec3,
    lights: &[SrbfLight],
    shadows: Option<GridShadows>,
) -> SegmentSingle {
    let with_sigma = |sp: &ShadingPoint| {
        let mut p = *params;
        p.sigma_a = [sp.sigma_a[0], sp.sigma_a[1], sp.sigma_a[2], 0.0];
        p
    };
    let (pa, pb) = (with_sigma(&ends[0]), with_sigma(&ends[1]));
    let painted = ends[0].sigma_a != ends[1].sigma_a;
    let frame = fiber_frame(mid.tangent);
    let (theta_o, phi_o) = fiber_angles(frame, omega_o);
    let lobes = view_lobes(params, theta_o);
    let at = [ends[0].position, mid.position, ends[1].position];
    let mut out = [[[0.0; 3]; 3]; 3];
    for (li, l) in lights.iter().enumerate() {
        let (theta, phi) = fiber_angles(frame, l.dir().normalize().as_vec3());
        let light = SrbfInFrame {
            theta,
            phi,
            lambda: l.lambda as f32,
        };
        let ma = srbf_response_in_view(luts, table, &pa, &lobes, light, phi_o);
        let mb = if painted {
            srbf_response_in_view(luts, table, &pb, &lobes, light, phi_o)
        } else {
            ma
        };
        for (s, x) in at.iter().enumerate() {
            let t = shadows.map_or(1.0, |g| g.shadow(*x, li).transmittance);
            for lobe in 0..3 {
                for c in 0..3 {
                    let k = l.rgb[c] as f32;
                    let (a, b) = (k * ma[lobe][c], k * mb[lobe][c]);
                    out[s][lobe][c] += t * match s {
                        0 => a,
                        1 if painted => between_ends(a, b, 0.5),
                        1 => a,
                        _ => b,
                    };
                }
            }
        }
    }
    out
}

/// Whether a resolved sample id names a hair segment (segment + 1; not 0, not the occluder's).
pub fn is_hair(id: u32) -> bool {
    id != 0 && id & crate::render::passes::occluder::OCCLUDER_ID_BIT == 0
}

/// Which of a pixel's K-buffer fragments are shaded, as (segment + 1, weight).
pub type FragmentChoice = fn(&[Fragment], &PixelFragments) -> Vec<(u32, f64)>;

/// The frame's choice: every kept fragment with its composite weight (twin of a slot's dispatch).
pub const EVERY_FRAGMENT: FragmentChoice = |slots, _| {
    slots
        .iter()
        .filter(|f| f.id != 0 && f.weight > 0.0)
        .map(|f| (f.id, f.weight as f64))
        .collect()
};

/// The pixel loop of the CPU shading passes (rayon over the given pixels): for each pixel, `fold` is
/// called on a fresh `init()` for every kept fragment of its K-buffer, with the pixel index, the
/// shading point, omega_o and the fragment's composite weight.
pub fn fold_visible_points<T: Send>(
    frame: &Frame,
    camera: &CameraUniform,
    hair: &ShadingHair,
    pixels: &[usize],
    init: impl Fn() -> T + Sync,
    fold: impl Fn(&mut T, usize, &ShadingPoint, Vec3, f64) + Sync,
) -> Vec<T> {
    fold_chosen_points(frame, camera, hair, pixels, EVERY_FRAGMENT, init, fold)
}

/// [`fold_visible_points`] over the fragments `choose` picks.
pub fn fold_chosen_points<T: Send>(
    frame: &Frame,
    camera: &CameraUniform,
    hair: &ShadingHair,
    pixels: &[usize],
    choose: FragmentChoice,
    init: impl Fn() -> T + Sync,
    fold: impl Fn(&mut T, usize, &ShadingPoint, Vec3, f64) + Sync,
) -> Vec<T> {
    let k = frame.fragments_per_pixel as usize;
    pixels
        .par_iter()
        .map(|&i| {
            let mut acc = init();
            let (Some(slots), Some(info)) = (
                frame.fragments.get(i * k..(i + 1) * k),
                frame.pixel_fragments.get(i),
            ) else {
                return acc;
            };
            let (x, y) = (
                (i % frame.width as usize) as f32,
                (i / frame.width as usize) as f32,
            );
            let (origin, dir) = pixel_ray(camera, x + 0.5, y + 0.5);
            for (id, weight) in choose(slots, info) {
                let sp = hair.shading_point(id - 1, origin, dir);
                fold(&mut acc, i, &sp, -dir, weight);
            }
            acc
        })
        .collect()
}

/// The pixel loop of the shading pass on the CPU: for each pixel of `pixels`, the weighted sum of
/// `shade` over the fragments `choose` picks ([`EVERY_FRAGMENT`] for the frame and the preview), the
/// radiance per lobe (before exposure).
pub fn shade_pixels(
    frame: &Frame,
    camera: &CameraUniform,
    hair: &ShadingHair,
    pixels: &[usize],
    choose: FragmentChoice,
    shade: impl Fn(&ShadingPoint, Vec3) -> LobeRadiance + Sync,
) -> Vec<LobeRadiance> {
    fold_chosen_points(
        frame,
        camera,
        hair,
        pixels,
        choose,
        || [[0.0; 3]; 5],
        |acc: &mut LobeRadiance, _, sp, omega_o, weight| {
            let l = shade(sp, omega_o);
            let w = weight as f32;
            for t in 0..5 {
                for c in 0..3 {
                    acc[t][c] += w * l[t][c];
                }
            }
        },
    )
}

/// Single scattering at t between two samples (twin of `between_ends`): log-linear where both are
/// positive (a light's transmittance falls off exponentially into the hair), else linear.
pub fn between_ends(a: f32, b: f32, t: f32) -> f32 {
    if a > 0.0 && b > 0.0 {
        (a.max(1e-30).ln() * (1.0 - t) + b.max(1e-30).ln() * t).exp()
    } else {
        a * (1.0 - t) + b * t
    }
}

/// Single scattering at t along a segment from its samples a, m, b at t = 0, 1/2, 1 (twin of
/// `between_samples`): [`between_ends`] on each half. A sum of lights each exponential along the
/// segment is log-convex, so one log-linear piece over the whole segment overstates it.
pub fn between_samples(a: f32, m: f32, b: f32, t: f32) -> f32 {
    if t < 0.5 {
        between_ends(a, m, 2.0 * t)
    } else {
        between_ends(m, b, 2.0 * t - 1.0)
    }
}

/// The frame's segment shading on the CPU (twin of `shade_segments` and `gather_segments`): for each
/// pixel of `pixels`, every kept fragment's weight times its segment's radiance: single scattering
/// (R, TT, TRT) from `single` (`shade_segment_single` with the segment's midpoint, its ends and the
/// direction to the eye from the midpoint) between its samples at the fragment's point
/// ([`between_samples`]), multiple scattering that of its pair's point ([`ShadingHair::ms_key`],
/// [`ShadingHair::ms_point`]) by `multiple` towards the eye.
pub fn shade_pixels_by_segment(
    frame: &Frame,
    camera: &CameraUniform,
    hair: &ShadingHair,
    pixels: &[usize],
    single: impl Fn(&ShadingPoint, [ShadingPoint; 2], Vec3) -> SegmentSingle + Sync,
    multiple: impl Fn(&ShadingPoint, Vec3) -> LobeRadiance + Sync,
) -> Vec<LobeRadiance> {
    let eye = Vec3::from(camera.eye);
    let k = frame.fragments_per_pixel as usize;
    pixels
        .par_iter()
        .map(|&i| {
            let mut acc = [[0.0f32; 3]; 5];
            let slots = frame.fragments.get(i * k..(i + 1) * k).unwrap_or(&[]);
            let (x, y) = (
                (i % frame.width as usize) as f32,
                (i / frame.width as usize) as f32,
            );
            let (origin, dir) = pixel_ray(camera, x + 0.5, y + 0.5);
            for (id, weight) in EVERY_FRAGMENT(slots, &PixelFragments::default()) {
                let seg = id - 1;
                let i0 = hair.segments[seg as usize] as usize;
                let (a, b) = (hair.hair.positions[i0], hair.hair.positions[i0 + 1]);
                let t = closest_on_segment(origin, dir, a, b);
                let mid = hair.segment_point(seg, 0.5);
                let omega_o = (eye - mid.position).normalize();
                let ends = [hair.segment_point(seg, 0.0), hair.segment_point(seg, 1.0)];
                let ss = single(&mid, ends, omega_o);
                let at = hair.ms_point(hair.ms_key(seg));
                let ms = multiple(&at, (eye - at.position).normalize());
                let w = weight as f32;
                for c in 0..5 {
                    for ch in 0..3 {
                        acc[c][ch] += w * match c {
                            0..=2 => between_samples(ss[0][c][ch], ss[1][c][ch], ss[2][c][ch], t),
                            _ => ms[c][ch],
                        };
                    }
                }
            }
            acc
        })
        .collect()
}
