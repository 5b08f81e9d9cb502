//! The exact azimuthal window integrals as a table: calN_TT, calN_TRT under every light (Xu Eq. 12) and
//! calN_t^G of the forward-scattered light (Eq. 28), looked up instead of integrated per shading point.
//!
//! What is tabulated: for lobe p the window integral is
//!   calN_p = integral k(dphi - Phi(t)) cos t G_p(t) exp(-s x(t)) dt,
//! G_p = A_p / 2 without absorption ((1 - F)^2 F^(p-1) / 2; F / 2 for R), x = cos gamma_t = sqrt(1 - h^2 / eta'^2)
//! the chord length per unit diameter, s = 2 p sigma_a' (T = exp(-2 sigma_a' x), T^2 for TRT). Everything but
//! exp(-s x) depends only on (eta, theta_d, lambda', dphi), so each cell stores the measure
//! mu(x) = k cos t G_p dt as a two-node Gauss rule (weights w_1, w_2 and nodes x_1 <= x_2 that integrate
//! 1, x, x^2, x^3 exactly against mu), and the runtime sum w_1 e^(-s x_1) + w_2 e^(-s x_2) gives calN_p for
//! any absorption, per channel and per point (painted dye needs no rebuild). The error is that of a
//! two-point rule for e^(-s x) over the spread of x inside one window (small: x lies in
//! [sqrt(1 - 1/eta'^2), 1] and narrow windows see a narrow part of it; wide ones, like the box windows,
//! all of it) plus the interpolation between cells;
//! `tests/azimuthal_table.rs` measures both against the integral.
//!
//! Axes (the integrals are even in theta_d and in dphi): |theta_d| in [0, THETA_D_MAX] uniform,
//! lambda' in [LAMBDA_MIN, LAMBDA_MAX] uniform in ln lambda', |dphi| in [0, pi] uniform (TT, box windows)
//! or aligned with the TRT caustic and support edge ([`trt_dphi`]: they move with eta', and cells
//! interpolated across theta_d or eta*-bar at the same dphi put two half caustics where there is one), and for
//! TRT under eccentricity the averaged index eta*-bar (Xu Eq. 26) uniform over [eta_2*, eta_1*]. Gaussian windows are
//! stored divided by the window's own integral 2 pi e^-kappa I0(kappa) so cells vary slowly in lambda'.
//! Cells hold (w_1, w_1 x_1, w_2, w_2 x_2): interpolated linearly, a corner with no weight does not pull
//! the nodes. Built on the CPU in f64 moments of the f32 quadrature of [`for_each_window_node`], with rayon;
//! rebuilt when eta or the eccentricity change (nothing else reaches it).
//!
//! Cells are kept in half precision ([`super::half_cells`]: 11 significant bits from 6e-8 to 64;
//! the cells stay under 2.1: 0.83 for eta 1.55 round, 1.55-2.07 for eta 1.3-2 and eccentricities
//! 0.5-2, and `tests/azimuthal_table.rs` bounds them by 8). The GPU's buffer
//! ([`AzimuthalTable::gpu`]) holds each cell as two half pairs in a vec2<u32>: a lookup loads half
//! the words it would in f32 (a software GPU's loads cost per word). The CPU's cells are the
//! same rounded values, so the WGSL twin (`shaders/azimuthal_table.wgsl`) and the lookups here
//! read the same numbers;
//! `tests/azimuthal_table.rs` measures the rounding with the rest (it moves TT's median error
//! against the exact integrals from 2.6e-4 in f32 to 3.0e-4, its p95 from 6.5e-3 to 6.6e-3, and
//! leaves TRT's p95 at 4.2e-3). A rule's node x = (w x) / w carries two roundings (~1e-3
//! relative), so e^(-s x) errs by ~1e-3 s relative: a few percent of a dark TRT's tiny value (s of
//! 30 and more). See docs/fast-form.md.

use super::circular_gaussian::{asin_precise, bessel_i0_scaled};
use super::fast_azimuthal::LAMBDA_PRIME_MAX;
use super::fast_azimuthal::{Rgb32, bravais_eta_prime, fresnel_schlick, sigma_a_prime};
use super::fast_exact_azimuthal::for_each_window_node;
use super::fast_params::FastHairParams;
use super::half_cells::{half_pair, round_to_half_bits};
use super::params::HairParams;
use rayon::prelude::*;
use std::f32::consts::{FRAC_PI_2, PI, TAU};

/// Samples of |theta_d| over [0, THETA_D_MAX].
pub const TABLE_THETA_D: usize = 32;
pub const THETA_D_MAX: f32 = 1.5;
/// Samples of lambda', log-spaced over [LAMBDA_MIN, LAMBDA_MAX]: every lambda' the renderer meets (it
/// clamps lambda' to [`LAMBDA_PRIME_MAX`]), so that no light needs Xu's circular-Gaussian fits
/// (on a software GPU every SIMD group holding one wide light would run them, ~30 % of the shading
/// pass).
/// 54 samples space the axis by about 0.14 in ln lambda'.
pub const TABLE_LAMBDA: usize = 54;
pub const LAMBDA_MIN: f32 = 0.005;
pub const LAMBDA_MAX: f32 = LAMBDA_PRIME_MAX;
/// Samples of |dphi| over [0, pi], both ends included.
pub const TABLE_DPHI: usize = 256;
/// Samples of eta*-bar for TRT when the fiber is elliptical (1 when it is round).
pub const TABLE_ETA_ECCENTRIC: usize = 6;
/// Half-width of the Gaussian window in units of lambda' (as the exact integral).
const WINDOW: f32 = 3.5;

/// Rounds cells to what the GPU holds and returns that as the GPU's entries: (w_1, w_1 x_1) and
/// (w_2, w_2 x_2) as half pairs, the first of each in the low half (WGSL's unpack2x16float).
fn to_gpu_cells(cells: &mut [[f32; 4]]) -> Vec<[u32; 2]> {
    let bits = round_to_half_bits(cells.as_flattened_mut());
    bits.chunks_exact(4)
        .map(|b| [half_pair(b[0], b[1]), half_pair(b[2], b[3])])
        .collect()
}

/// The GPU buffer's entries before the cells: the header's four f32 bits.
pub const GPU_HEADER_ENTRIES: usize = 2;

/// One table for one (eta, eccentricity). Layout of `cells` (vec4 each): [0] header (eta_lo, eta_hi,
/// eta samples, eta); then TT windows [theta_d][lambda][dphi]; TRT windows [eta][theta_d][lambda][dphi];
/// box windows of R, TT, TRT [lobe][theta_d][dphi].
#[derive(Clone, Debug, PartialEq)]
pub struct AzimuthalTable {
    pub eta: f32,
    pub eccentricity: f32,
    /// A draft ([`AzimuthalTable::build_draft`]): most cells interpolated, for a preview.
    pub draft: bool,
    pub cells: Vec<[f32; 4]>,
    /// The GPU's buffer (`azimuthal_table.wgsl`): the header's f32 bits in [`GPU_HEADER_ENTRIES`]
    /// entries, then cell k >= 1 at entry k + 1 (`to_gpu_cell`), made with the table on its thread.
    pub gpu: Vec<[u32; 2]>,
}

/// A draft's strides along theta_d, lambda' and dphi ([`AzimuthalTable::build_draft`]).
pub const DRAFT_STRIDE: [usize; 3] = [2, 2, 4];

// TRT's knots (u = 1/3 and 2/3) fall on dphi cells.
const _: () = assert!((TABLE_DPHI - 1).is_multiple_of(3));

/// Whether a draft computes sample i of axis `axis` (0 theta_d, 1 lambda', 2 dphi) of n samples: every
/// [`DRAFT_STRIDE`]-th, the last, and along dphi the cells of TRT's knots, the caustic and the
/// support's edge at u = 1/3 and 2/3 ([`trt_dphi`]: interpolated, the feature the axis keeps sharp
/// would be smoothed).
/// (The knot cells are computed in the TT and box slabs too, where they are ordinary cells.)
fn draft_sample(axis: usize, i: usize, n: usize) -> bool {
    let knot = axis == 2 && n == TABLE_DPHI && (3 * i == n - 1 || 3 * i == 2 * (n - 1));
    i.is_multiple_of(DRAFT_STRIDE[axis]) || i + 1 == n || knot
}

/// The computed samples around sample i of an axis and the weight of the upper one.
fn draft_neighbours(axis: usize, i: usize, n: usize) -> (usize, usize, f32) {
    let lo = (0..i)
        .rev()
        .find(|&k| draft_sample(axis, k, n))
        .unwrap_or(0);
    let hi = (i + 1..n)
        .find(|&k| draft_sample(axis, k, n))
        .unwrap_or(n - 1);
    (lo, hi, (i - lo) as f32 / (hi - lo).max(1) as f32)
}

/// What cell i of a table with `eta_samples` TRT indices holds (the layout of
/// [`AzimuthalTable::cells`]).
#[derive(Clone, Copy, Debug, PartialEq)]
enum CellAt {
    Header,
    /// A Gaussian window of lobe p (1 TT, 2 TRT), TRT's eta*-bar sample `ie`, at theta_d sample `it`,
    /// lambda' sample `il` and dphi sample `ip`.
    Gaussian {
        p: u32,
        ie: usize,
        it: usize,
        il: usize,
        ip: usize,
    },
    /// The box window of lobe `lobe` at theta_d sample `it` and dphi sample `ip`.
    Box {
        lobe: usize,
        it: usize,
        ip: usize,
    },
}

fn cell_at(i: usize, eta_samples: usize) -> CellAt {
    if i == 0 {
        return CellAt::Header;
    }
    if i < box_base(eta_samples) {
        let (p, j) = if i < trt_base() {
            (1, i - 1)
        } else {
            (2, i - trt_base())
        };
        let per_lobe = TABLE_THETA_D * TABLE_LAMBDA * TABLE_DPHI;
        let (ie, k) = (j / per_lobe, j % per_lobe);
        let rest = k % (TABLE_LAMBDA * TABLE_DPHI);
        return CellAt::Gaussian {
            p,
            ie,
            it: k / (TABLE_LAMBDA * TABLE_DPHI),
            il: rest / TABLE_DPHI,
            ip: rest % TABLE_DPHI,
        };
    }
    let j = i - box_base(eta_samples);
    let rest = j % (TABLE_THETA_D * TABLE_DPHI);
    CellAt::Box {
        lobe: j / (TABLE_THETA_D * TABLE_DPHI),
        it: rest / TABLE_DPHI,
        ip: rest % TABLE_DPHI,
    }
}

/// Whether a draft computes cell i of a table with `eta_samples` TRT indices.
fn draft_computes(i: usize, eta_samples: usize) -> bool {
    match cell_at(i, eta_samples) {
        CellAt::Header => true,
        CellAt::Gaussian { it, il, ip, .. } => {
            draft_sample(0, it, TABLE_THETA_D)
                && draft_sample(1, il, TABLE_LAMBDA)
                && draft_sample(2, ip, TABLE_DPHI)
        }
        CellAt::Box { it, ip, .. } => {
            draft_sample(0, it, TABLE_THETA_D) && draft_sample(2, ip, TABLE_DPHI)
        }
    }
}

/// Fills a draft's slab of cells [theta_d][lambda'][dphi] (`dims`) from its computed ones: along dphi
/// in the computed rows, then along lambda', then along theta_d.
fn fill_draft_slab(cells: &mut [[f32; 4]], dims: [usize; 3]) {
    let [n0, n1, n2] = dims;
    let at = |a: usize, b: usize, c: usize| (a * n1 + b) * n2 + c;
    for a in (0..n0).filter(|&a| draft_sample(0, a, n0)) {
        for b in (0..n1).filter(|&b| draft_sample(1, b, n1)) {
            for c in (0..n2).filter(|&c| !draft_sample(2, c, n2)) {
                let (lo, hi, w) = draft_neighbours(2, c, n2);
                cells[at(a, b, c)] = lerp4(cells[at(a, b, lo)], cells[at(a, b, hi)], w);
            }
        }
        for b in (0..n1).filter(|&b| !draft_sample(1, b, n1)) {
            let (lo, hi, w) = draft_neighbours(1, b, n1);
            for c in 0..n2 {
                cells[at(a, b, c)] = lerp4(cells[at(a, lo, c)], cells[at(a, hi, c)], w);
            }
        }
    }
    for a in (0..n0).filter(|&a| !draft_sample(0, a, n0)) {
        let (lo, hi, w) = draft_neighbours(0, a, n0);
        for b in 0..n1 {
            for c in 0..n2 {
                cells[at(a, b, c)] = lerp4(cells[at(lo, b, c)], cells[at(hi, b, c)], w);
            }
        }
    }
}

/// Where the TRT windows start (in cells).
pub fn trt_base() -> usize {
    1 + TABLE_THETA_D * TABLE_LAMBDA * TABLE_DPHI
}

/// Where the box windows start for `eta_samples` TRT index samples.
pub fn box_base(eta_samples: usize) -> usize {
    trt_base() + eta_samples * TABLE_THETA_D * TABLE_LAMBDA * TABLE_DPHI
}

/// The range of eta*-bar (Xu Eq. 24-26) for index eta and eccentricity a: (eta_2*, eta_1*) ordered.
pub fn eta_star_range(eta: f32, a: f32) -> (f32, f32) {
    if a == 1.0 {
        return (eta, eta);
    }
    let eta1 = 2.0 * (eta - 1.0) * a * a - eta + 2.0;
    let eta2 = 2.0 * (eta - 1.0) / (a * a) - eta + 2.0;
    (eta1.min(eta2), eta1.max(eta2))
}

fn axis_theta_d(i: usize) -> f32 {
    THETA_D_MAX * i as f32 / (TABLE_THETA_D - 1) as f32
}

fn axis_lambda(i: usize) -> f32 {
    let (a, b) = (LAMBDA_MIN.ln(), LAMBDA_MAX.ln());
    (a + (b - a) * i as f32 / (TABLE_LAMBDA - 1) as f32).exp()
}

fn axis_dphi(i: usize) -> f32 {
    PI * i as f32 / (TABLE_DPHI - 1) as f32
}

/// The two azimuths where N_TRT changes abruptly for index eta', ordered: the caustic |phi_c| =
/// |Phi(2, h_c)| (h_c = sqrt((4 - eta'^2) / 3); 0 when eta' >= 2, no caustic) and the edge of the support
/// |Phi(2, 1)| = |4 asin(1 / eta') - pi| (both wrapped into [0, pi]).
pub fn trt_knots(eta_p: f32) -> [f32; 2] {
    let mut caustic = 0.0;
    if eta_p < 2.0 {
        let hc = ((4.0 - eta_p * eta_p) / 3.0).max(0.0).sqrt().min(1.0);
        caustic = (4.0 * asin_precise(hc / eta_p) - 2.0 * asin_precise(hc)).abs();
    }
    let edge = (4.0 * asin_precise((1.0 / eta_p).min(1.0)) - PI).abs();
    [caustic.min(edge), caustic.max(edge)]
}

/// The TRT cells' azimuth axis, aligned with the caustic and the support's edge so that cells at
/// different theta_d and eta*-bar interpolate caustic with caustic: u in [0, 1/3] spans [0, k_1] and
/// [1/3, 2/3] spans [k_1, k_2] linearly, [2/3, 1] spans [k_2, pi] quadratically (fine just past the
/// edge, where narrow lights' smoothed features end).
pub fn trt_dphi(u: f32, knots: [f32; 2]) -> f32 {
    let [k1, k2] = knots;
    if u <= 1.0 / 3.0 {
        return 3.0 * u * k1;
    }
    if u <= 2.0 / 3.0 {
        return k1 + (k2 - k1) * (3.0 * u - 1.0);
    }
    let v = 3.0 * u - 2.0;
    k2 + (PI - k2) * v * v
}

/// The inverse of [`trt_dphi`] for |dphi| in [0, pi].
pub fn trt_u(dphi: f32, knots: [f32; 2]) -> f32 {
    let [k1, k2] = knots;
    if dphi <= k1 {
        return if k1 > 0.0 {
            dphi / (3.0 * k1)
        } else {
            1.0 / 3.0
        };
    }
    if dphi <= k2 {
        return if k2 > k1 {
            (1.0 + (dphi - k1) / (k2 - k1)) / 3.0
        } else {
            2.0 / 3.0
        };
    }
    (2.0 + ((dphi - k2) / (PI - k2)).max(0.0).sqrt()) / 3.0
}

fn axis_eta(lo: f32, hi: f32, samples: usize, i: usize) -> f32 {
    if samples <= 1 {
        return lo;
    }
    lo + (hi - lo) * i as f32 / (samples - 1) as f32
}

/// The integral of the Gaussian window over a period, 2 pi e^-kappa I0(kappa), kappa = 2 / lambda'^2.
pub fn window_energy(lambda_prime: f32) -> f32 {
    TAU * bessel_i0_scaled(2.0 / (lambda_prime * lambda_prime))
}

/// The two-node Gauss rule of the window's measure in x (a cell): (w_1, w_1 x_1, w_2, w_2 x_2).
/// `kappa` = 0 is the box window of half-width `half_width`.
pub fn window_rule(
    p: u32,
    eta: f32,
    theta_d: f32,
    dphi: f32,
    kappa: f32,
    half_width: f32,
) -> [f32; 4] {
    let eta_p = bravais_eta_prime(eta, theta_d);
    let cos_d = theta_d.cos();
    let inv_eta_p2 = 1.0 / (eta_p as f64 * eta_p as f64);
    // Moments of y = 1 - x about the first node's y (shifted: narrow windows see y within 1e-4).
    let mut shift: Option<f64> = None;
    let mut m = [0.0f64; 4];
    for_each_window_node(p, eta_p, dphi, kappa, half_width, |h, weight| {
        let f = fresnel_schlick(eta, cos_d, h);
        let g = match p {
            0 => 0.5 * f,
            1 => 0.5 * (1.0 - f) * (1.0 - f),
            _ => 0.5 * (1.0 - f) * (1.0 - f) * f,
        };
        let h = h as f64;
        let y = 1.0 - (1.0 - h * h * inv_eta_p2).max(0.0).sqrt();
        let y0 = *shift.get_or_insert(y);
        let z = y - y0;
        let wgt = weight as f64 * g as f64;
        m[0] += wgt;
        m[1] += wgt * z;
        m[2] += wgt * z * z;
        m[3] += wgt * z * z * z;
    });
    gauss_rule_2(m, shift.unwrap_or(0.0))
}

/// The two-point Gauss rule of a positive measure from its moments m_k = integral z^k (k = 0..3) about
/// y0 (y = y0 + z, x = 1 - y), as (w_1, w_1 x_1, w_2, w_2 x_2) with x_1 <= x_2. One node when the
/// measure is (numerically) a point.
pub fn gauss_rule_2(m: [f64; 4], y0: f64) -> [f32; 4] {
    if m[0] <= 0.0 {
        return [0.0; 4];
    }
    let mean = m[1] / m[0];
    let c2 = (m[2] / m[0] - mean * mean).max(0.0);
    let c3 = m[3] / m[0] - 3.0 * mean * m[2] / m[0] + 2.0 * mean * mean * mean;
    let x_mean = 1.0 - (y0 + mean);
    if c2 < 1e-14 {
        return [m[0] as f32, (m[0] * x_mean) as f32, 0.0, 0.0];
    }
    // Orthogonal polynomial z^2 - r z - c2 (z about the mean), r = c3 / c2; its roots are the nodes.
    let r = c3 / c2;
    let root = (r * r + 4.0 * c2).sqrt();
    let (z_hi, z_lo) = (0.5 * (r + root), 0.5 * (r - root));
    let w_hi = -z_lo / (z_hi - z_lo);
    let w_lo = z_hi / (z_hi - z_lo);
    // z_hi is the larger y, the smaller x: node 1.
    let (x1, x2) = (x_mean - z_hi, x_mean - z_lo);
    let (w1, w2) = (m[0] * w_hi, m[0] * w_lo);
    [w1 as f32, (w1 * x1) as f32, w2 as f32, (w2 * x2) as f32]
}

impl AzimuthalTable {
    /// Cells of the largest table (an elliptical fiber's); GPU buffers are made this size once.
    pub const MAX_CELLS: usize = 1
        + (1 + TABLE_ETA_ECCENTRIC) * TABLE_THETA_D * TABLE_LAMBDA * TABLE_DPHI
        + 3 * TABLE_THETA_D * TABLE_DPHI;
    pub const MAX_BYTES: u64 = ((Self::MAX_CELLS + GPU_HEADER_ENTRIES - 1) * 8) as u64;

    /// Builds the table for the fiber's eta and eccentricity (on two cores of a CI-sized machine
    /// about 0.8 s for a round fiber, 3 s for an elliptical one with its six TRT indices).
    pub fn build(eta: f32, eccentricity: f32) -> Self {
        Self::build_cells(eta, eccentricity, false)
    }

    /// A draft of [`Self::build`]'s table for a preview while the table is built: the cells at every
    /// [`DRAFT_STRIDE`]-th sample of theta_d, lambda' and dphi (and each axis's last) computed (and the
    /// cells of TRT's knots), 1/14 of them, the others interpolated between those as the lookups interpolate
    /// (`tests/azimuthal_table.rs` measures what that costs). Never kept, never reused as the table
    /// ([`Self::fits_hair`], [`Self::matches`]); [`Self::for_index`] tells that it reads the right index.
    pub fn build_draft(eta: f32, eccentricity: f32) -> Self {
        Self::build_cells(eta, eccentricity, true)
    }

    fn build_cells(eta: f32, eccentricity: f32, draft: bool) -> Self {
        let (eta_lo, eta_hi) = eta_star_range(eta, eccentricity);
        let eta_samples = if eta_lo == eta_hi {
            1
        } else {
            TABLE_ETA_ECCENTRIC
        };
        let per_lobe = TABLE_THETA_D * TABLE_LAMBDA * TABLE_DPHI;
        let box_cells = 3 * TABLE_THETA_D * TABLE_DPHI;
        let total = box_base(eta_samples) + box_cells;
        // Cell index -> its rule; the header is cell 0.
        let cell = |i: usize| -> [f32; 4] {
            match cell_at(i, eta_samples) {
                CellAt::Header => [eta_lo, eta_hi, eta_samples as f32, eta],
                CellAt::Gaussian { p, ie, it, il, ip } => {
                    let eta = if p == 2 {
                        axis_eta(eta_lo, eta_hi, eta_samples, ie)
                    } else {
                        eta
                    };
                    let lp = axis_lambda(il);
                    let kappa = 2.0 / (lp * lp);
                    let theta_d = axis_theta_d(it);
                    let dphi = if p == 2 {
                        let u = ip as f32 / (TABLE_DPHI - 1) as f32;
                        trt_dphi(u, trt_knots(bravais_eta_prime(eta, theta_d)))
                    } else {
                        axis_dphi(ip)
                    };
                    let rule = window_rule(p, eta, theta_d, dphi, kappa, (WINDOW * lp).min(PI));
                    let e = window_energy(lp);
                    rule.map(|v| v / e)
                }
                CellAt::Box { lobe, it, ip } => window_rule(
                    lobe as u32,
                    eta,
                    axis_theta_d(it),
                    axis_dphi(ip),
                    0.0,
                    FRAC_PI_2,
                )
                .map(|v| v / PI),
            }
        };
        let computed = |i: usize| !draft || draft_computes(i, eta_samples);
        let mut cells: Vec<[f32; 4]> = (0..total)
            .into_par_iter()
            .map(|i| if computed(i) { cell(i) } else { [0.0; 4] })
            .collect();
        if draft {
            let gaussian = [TABLE_THETA_D, TABLE_LAMBDA, TABLE_DPHI];
            let slabs = (0..1 + eta_samples).map(|k| (1 + k * per_lobe, gaussian));
            let boxes = (0..3).map(|lobe| {
                (
                    box_base(eta_samples) + lobe * TABLE_THETA_D * TABLE_DPHI,
                    [TABLE_THETA_D, 1, TABLE_DPHI],
                )
            });
            for (base, dims) in slabs.chain(boxes) {
                let n = dims.iter().product::<usize>();
                fill_draft_slab(&mut cells[base..base + n], dims);
            }
        }
        // What the GPU holds (the header stays in f32).
        let header = cells[0].map(f32::to_bits);
        let mut gpu = vec![[header[0], header[1]], [header[2], header[3]]];
        gpu.par_extend(
            cells[1..]
                .par_chunks_mut(1 << 14)
                .flat_map_iter(to_gpu_cells),
        );
        debug_assert_eq!(gpu.len(), cells.len() + GPU_HEADER_ENTRIES - 1);
        Self {
            eta,
            eccentricity,
            draft,
            cells,
            gpu,
        }
    }

    /// The table for fast parameters `p` (its eta and eccentricity).
    pub fn for_params(p: &FastHairParams) -> Self {
        Self::build(p.eta, p.eccentricity)
    }

    /// Whether this table was built for `p` (and needs no rebuild: not a draft).
    pub fn matches(&self, p: &FastHairParams) -> bool {
        !self.draft && self.for_index(p)
    }

    /// Whether this table, or this draft, was made for `p`'s eta and eccentricity (a frame may read it).
    pub fn for_index(&self, p: &FastHairParams) -> bool {
        self.eta == p.eta && self.eccentricity == p.eccentricity
    }

    /// The table of exact hair parameters (the fast form's f32 eta and eccentricity).
    pub fn for_hair(p: &HairParams) -> Self {
        Self::build(p.eta as f32, p.eccentricity as f32)
    }

    /// [`AzimuthalTable::matches`] for exact hair parameters.
    pub fn fits_hair(&self, p: &HairParams) -> bool {
        !self.draft && self.made_for_hair(p)
    }

    /// [`AzimuthalTable::for_index`] for exact hair parameters (a draft too).
    pub fn made_for_hair(&self, p: &HairParams) -> bool {
        self.eta == p.eta as f32 && self.eccentricity == p.eccentricity as f32
    }

    /// The GPU's buffer as bytes ([`Self::gpu`]).
    pub fn gpu_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.gpu)
    }
}

/// Linear position on a uniform axis of `n` samples: (index, weight of the next).
fn axis_position(x: f32, n: usize) -> (usize, f32) {
    let x = x.clamp(0.0, (n - 1) as f32);
    let i = (x as usize).min(n - 2);
    (i, x - i as f32)
}

/// |dphi| wrapped into [0, pi].
fn folded_dphi(dphi: f32) -> f32 {
    let d = dphi + PI;
    let wrapped = d - TAU * (d / TAU).floor() - PI;
    wrapped.abs().min(PI)
}

/// calN(s) of an interpolated cell: w_1 e^(-s x_1) + w_2 e^(-s x_2), per channel.
fn rule_value(c: [f32; 4], s: Rgb32) -> Rgb32 {
    let x1 = if c[0] > 0.0 { c[1] / c[0] } else { 1.0 };
    let x2 = if c[2] > 0.0 { c[3] / c[2] } else { 1.0 };
    s.map(|s| c[0].max(0.0) * (-s * x1).exp() + c[2].max(0.0) * (-s * x2).exp())
}

/// Two cells along dphi, mixed.
#[inline(always)]
fn dphi_pair(cells: &[[f32; 4]], w: f32) -> [f32; 4] {
    lerp4(cells[0], cells[1], w)
}

/// WGSL's mix.
#[inline(always)]
fn lerp4(a: [f32; 4], b: [f32; 4], w: f32) -> [f32; 4] {
    std::array::from_fn(|k| a[k] * (1.0 - w) + b[k] * w)
}

/// s = 2 p sigma_a' per channel.
fn absorption_exponent(p: u32, eta: f32, sigma_a: Rgb32, theta_d: f32) -> Rgb32 {
    sigma_a.map(|s| 2.0 * p as f32 * sigma_a_prime(s, eta, theta_d))
}

impl AzimuthalTable {
    /// calN_TT (p = 1) or calN_TRT (p = 2) under the Gaussian window of bandwidth lambda' (Xu Eq. 12), for
    /// absorption sigma_a (per unit radius, RGB) and, for TRT, the averaged index eta*-bar (the WGSL
    /// twin: `azimuthal_table_gaussian`).
    pub fn window_gaussian(
        &self,
        p: u32,
        eta_star: f32,
        sigma_a: Rgb32,
        theta_d: f32,
        lambda_prime: f32,
        dphi: f32,
    ) -> Rgb32 {
        let cells = &self.cells;
        let header = cells[0];
        let eta_samples = header[2] as usize;
        let (t, wt) = axis_position(
            theta_d.abs() / THETA_D_MAX * (TABLE_THETA_D - 1) as f32,
            TABLE_THETA_D,
        );
        let lp = lambda_prime.clamp(LAMBDA_MIN, LAMBDA_MAX);
        let (a, b) = (LAMBDA_MIN.ln(), LAMBDA_MAX.ln());
        let (l, wl) = axis_position(
            (lp.ln() - a) / (b - a) * (TABLE_LAMBDA - 1) as f32,
            TABLE_LAMBDA,
        );
        let mut u = folded_dphi(dphi) / PI;
        let (mut base, mut e, mut we, mut eta) = (1usize, 0usize, 0.0f32, header[3]);
        if p == 2 {
            base = trt_base();
            eta = eta_star;
            // The knots of the cells read: theta_d beyond the axis reads the last cells.
            let cells_theta_d = theta_d.abs().min(THETA_D_MAX);
            u = trt_u(
                folded_dphi(dphi),
                trt_knots(bravais_eta_prime(eta_star, cells_theta_d)),
            );
            if eta_samples > 1 {
                let x = (eta_star - header[0]) / (header[1] - header[0]) * (eta_samples - 1) as f32;
                (e, we) = axis_position(x, eta_samples);
            }
        }
        let (f, wf) = axis_position(u * (TABLE_DPHI - 1) as f32, TABLE_DPHI);
        let per_lobe = TABLE_THETA_D * TABLE_LAMBDA * TABLE_DPHI;
        // The (theta_d, lambda') corners of index sample ie, each with its two dphi neighbours
        // side by side.
        let slab = |ie: usize| {
            let at = |it: usize, il: usize| {
                let i = base + ie * per_lobe + (it * TABLE_LAMBDA + il) * TABLE_DPHI + f;
                dphi_pair(&cells[i..i + 2], wf)
            };
            let near = lerp4(at(t, l), at(t, l + 1), wl);
            let far = lerp4(at(t + 1, l), at(t + 1, l + 1), wl);
            lerp4(near, far, wt)
        };
        let mut c = slab(e);
        if we > 0.0 {
            c = lerp4(c, slab(e + 1), we);
        }
        let energy = window_energy(lambda_prime);
        rule_value(c, absorption_exponent(p, eta, sigma_a, theta_d)).map(|v| energy * v)
    }

    /// calN_t^G (Xu Eq. 28): the box window of half-width pi/2 over pi, lobe p = 0, 1, 2 (the WGSL twin:
    /// `azimuthal_table_box`).
    pub fn window_box(&self, p: u32, sigma_a: Rgb32, theta_d: f32, dphi: f32) -> Rgb32 {
        let cells = &self.cells;
        let header = cells[0];
        let base = box_base(header[2] as usize) + p as usize * TABLE_THETA_D * TABLE_DPHI;
        let (t, wt) = axis_position(
            theta_d.abs() / THETA_D_MAX * (TABLE_THETA_D - 1) as f32,
            TABLE_THETA_D,
        );
        let (f, wf) = axis_position(folded_dphi(dphi) / PI * (TABLE_DPHI - 1) as f32, TABLE_DPHI);
        let at = |it: usize, ip: usize| cells[base + it * TABLE_DPHI + ip];
        let lo = lerp4(at(t, f), at(t, f + 1), wf);
        let hi = lerp4(at(t + 1, f), at(t + 1, f + 1), wf);
        let c = lerp4(lo, hi, wt);
        rule_value(c, absorption_exponent(p, header[3], sigma_a, theta_d))
    }
}
