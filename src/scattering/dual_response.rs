//! Multiple scattering per SRBF light by dual scattering (Xu et al. 2011 Sec. 4.3; Zinke et al. 2008),
//! given what the renderer supplies per shaded point and light: the forward-scattering transmittance
//! T_f, the spread sigma_f^2 and the direct fraction. f32, as the WGSL twin.
//!
//! The forward-scattered light of SRBF j arrives spread over the front half of the azimuths around phi_j
//! (s_f = 1/pi) and over theta_i as a unit-area Gaussian around theta_j of variance
//! sigma^2 = sigma_f^2 + lambda_j^2 / 2 (Xu's Eq. 27 uses sigma_f alone; the light's own longitudinal
//! spread, a standard deviation of lambda_j / sqrt(2), is added here so wide SRBFs are not treated as
//! directional). Responses are per unit light power; the renderer multiplies by the SRBF's power
//! pi lambda_j^2 (1 - e^(-4 / lambda_j^2)) and radiance.

use super::azimuthal_table::AzimuthalTable;
use super::dual_terms::{DualTables, HairBehind, sigma_cell};
use super::fast_azimuthal::Rgb32;
use super::fast_params::FastHairParams;
use super::fast_response::{LongitudinalLobe, SrbfInFrame, gaussian_product, linear_quadrature};
use super::lut::wrap_angle_f32;
use std::f32::consts::{PI, SQRT_2};

/// `dual_quadrature_segments` of the WGSL: the dual terms' quadrature segments, half the
/// single-scattering quadrature's and at least 2 (the renderer's 4 give 2: one inner node; the
/// poles are not evaluated, [`crate::scattering::fast_response::Quadrature`]). The dual terms are
/// broad (the forward spread widens the light, the back lobe is wide): against direct quadrature
/// the global term's worst error is 1.0 % (0.16 % with the full m), the local one's 8.8 % (7.2 %;
/// most of it Xu's means over the light's width) (`tests/dual_terms.rs`).
pub fn dual_quadrature_segments(m: u32) -> u32 {
    (m / 2).max(2)
}

/// Standard deviation of the forward-scattered light's longitudinal spread.
pub fn forward_spread(sigma_f2: f32, lambda_j: f32) -> f32 {
    (sigma_f2 + 0.5 * lambda_j * lambda_j).max(1e-6).sqrt()
}

/// calN_t^G(phi_o - phi_j, theta_d) = (1/pi) integral_{-pi/2}^{pi/2} N_t(theta_d, phi_o - phi_j - x) dx (Xu Eq. 28),
/// from the exact N_t, tabulated ([`AzimuthalTable::window_box`]).
pub fn inner_integral_global(
    table: &AzimuthalTable,
    p: &FastHairParams,
    lobe: u32,
    theta_d: f32,
    dphi: f32,
) -> Rgb32 {
    table.window_box(lobe, p.sigma_a_rgb(), theta_d, dphi)
}

/// M_t^G per unit light power (Xu Eq. 27): (1/cos theta_j) integral g^u(theta_i; theta_j, sigma) M_t(theta_h)
/// cos^2(theta_i) / cos^2(theta_d) calN_t^G d theta_i as published, or with d'Eon's M_t(theta_i, theta_o) cos(theta_i)
/// normalised ([`LongitudinalLobe::factor`]), by the quadrature of Sec. 4.2.2 against the product of the two
/// Gaussians.
pub fn global_response_lobe(
    table: &AzimuthalTable,
    p: &FastHairParams,
    lobe: u32,
    light: SrbfInFrame,
    theta_o: f32,
    phi_o: f32,
    sigma_f2: f32,
) -> Rgb32 {
    let longitudinal = LongitudinalLobe::of_lobe(p, lobe, theta_o);
    global_response_lobe_in_view(table, p, lobe, &longitudinal, light, phi_o, sigma_f2)
}

/// [`global_response_lobe`] with the lobe's longitudinal function of the view
/// ([`crate::scattering::fast_response::view_lobes`], shared with single scattering).
pub fn global_response_lobe_in_view(
    table: &AzimuthalTable,
    p: &FastHairParams,
    lobe: u32,
    longitudinal: &LongitudinalLobe,
    light: SrbfInFrame,
    phi_o: f32,
    sigma_f2: f32,
) -> Rgb32 {
    let theta_o = longitudinal.theta_o;
    let sigma = forward_spread(sigma_f2, light.lambda);
    let beta = p.beta[lobe as usize];
    // g^u with std sigma is Xu's g with bandwidth sqrt(2) sigma, over sqrt(2 pi) sigma.
    let (scale, mu, l) = gaussian_product(
        light.theta,
        SQRT_2 * sigma,
        longitudinal.mu,
        2.0 * SQRT_2 * beta,
    );
    // The two unit-area Gaussians (std sigma and 2 beta); the longitudinal factor holds the rest of M_t.
    let c = scale / (2.0 * PI * sigma * 2.0 * beta * light.theta.cos().max(1e-3));
    if c < 1e-30 {
        return [0.0; 3];
    }
    let dphi = phi_o - light.phi;
    linear_quadrature(
        dual_quadrature_segments(p.quadrature_segments),
        mu,
        l,
        |ti| {
            let theta_d = 0.5 * (theta_o - ti);
            let w = longitudinal.factor(ti);
            inner_integral_global(table, p, lobe, theta_d, dphi).map(|n| w * n)
        },
    )
    .map(|v| (c * v).max(0.0))
}

/// M^L per unit light power (Xu Eq. 29-31): (2 / cos theta_j) (pi - |phi_j - phi_o|) / pi^2 times
/// integral g^u(theta_i; theta_j, sigma) g^u(theta_i; Delta_b~ - theta_o, sigma_b~) A_b(theta_d) cos^2(theta_i) / cos^2(theta_d) d theta_i
/// as published (the 2 is Zinke's Eq. 10, the same factor as M_t's), or normalised
/// (1 / cos theta_j) (pi - |phi_j - phi_o|) / pi^2 integral g^u(theta_i; theta_j, sigma) M^dEon(theta_i, theta_o - Delta_b~; sigma_b~^2)
/// A_b cos(theta_i) d theta_i, so that A_b is the energy the back-scattered light carries,
/// with Delta_b~, sigma_b~ the means of Delta_b, sigma_b over theta_i in theta_j +- sigma (from the SATs).
/// `depth_behind` is the optical depth of the hair behind the point along the light's direction of
/// travel: A_b is scaled by [`crate::scattering::dual_terms::backscatter_depth_fraction`] at each node
/// (`f32::INFINITY`: Zinke's unbounded hair). The WGSL twin's form; [`local_response_behind`] also
/// takes an exact fiber count.
pub fn local_response(
    p: &FastHairParams,
    tables: &DualTables,
    light: SrbfInFrame,
    theta_o: f32,
    phi_o: f32,
    sigma_f2: f32,
    depth_behind: f32,
) -> Rgb32 {
    local_response_behind(
        p,
        tables,
        light,
        theta_o,
        phi_o,
        [sigma_f2; 3],
        HairBehind::OpticalDepth(depth_behind),
    )
}

/// [`local_response`] with the hair behind the point given either way, and each channel's own
/// forward spread sigma_f^2 (the reference's shadow rays carry one per channel; the renderer their
/// mean).
pub fn local_response_behind(
    p: &FastHairParams,
    tables: &DualTables,
    light: SrbfInFrame,
    theta_o: f32,
    phi_o: f32,
    sigma_f2: Rgb32,
    behind: HairBehind,
) -> Rgb32 {
    let azimuthal = (PI - wrap_angle_f32(light.phi - phi_o).abs()) / (PI * PI);
    // Each channel at the point's own absorption (a painted strand's, not the hair's mean), its axis
    // cell found once.
    let cells = p.sigma_a_rgb().map(sigma_cell);
    let mut out = [0.0; 3];
    for c in 0..3 {
        let sigma = forward_spread(sigma_f2[c], light.lambda);
        let lo = 0.5 * (theta_o - (light.theta + sigma));
        let hi = 0.5 * (theta_o - (light.theta - sigma));
        let (delta_c, sig_b_c) = tables.mean_delta_sigma_in_cell(lo, hi, cells[c]);
        let sb = sig_b_c.max(1e-3);
        // Zinke's back lobe g(theta_i + theta_o - Delta_b; sigma_b) is M with tilt Delta_b / 2 and width sigma_b / 2:
        // published, its explicit factor 2 (Eq. 10) and cos^2/cos^2(theta_d); normalised, d'Eon's M of variance
        // sigma_b^2.
        let back = LongitudinalLobe::new(p.longitudinal, theta_o, 0.5 * delta_c, 0.5 * sb);
        let (scale, mu, l) = gaussian_product(light.theta, SQRT_2 * sigma, back.mu, SQRT_2 * sb);
        let k = azimuthal * scale / (2.0 * PI * sigma * sb * light.theta.cos().max(1e-3));
        if k < 1e-30 {
            continue;
        }
        let v = linear_quadrature(
            dual_quadrature_segments(p.quadrature_segments),
            mu,
            l,
            |ti| {
                let theta_d = 0.5 * (theta_o - ti);
                let (big_a_b, a_f) = tables.backscatter_in_cell(theta_d, cells[c]);
                let a = big_a_b * behind.fraction(a_f);
                [a * back.factor(ti); 3]
            },
        );
        out[c] = (k * v[0]).max(0.0);
    }
    out
}

/// Zinke's shader (Fig. 5) per SRBF light, split into the renderer's components. The direct part
/// (direct fraction D) carries single scattering (not here: the R, TT, TRT components) plus d_b f_back;
/// the forward-scattered part (T_f - D) d_f carries global + d_b local. `local_direct` is the local term
/// with sigma_f = 0, `global` (summed over lobes) and `local` with the path's sigma_f^2. Returns
/// (MS.global, MS.local) per unit light power. Zinke's pseudo code multiplies f_back by pi in the
/// scattered part because its f_back still holds s_b = 1/pi for one azimuth; Xu's M^L has already
/// integrated the azimuthal spread (Eq. 30), so no pi appears here.
pub fn dual_scattering_components(
    p: &FastHairParams,
    direct_fraction: f32,
    transmittance_f: Rgb32,
    local_direct: Rgb32,
    global: Rgb32,
    local: Rgb32,
) -> (Rgb32, Rgb32) {
    let scattered = transmittance_f.map(|t| (t - direct_fraction).max(0.0) * p.d_f);
    let ms_global = std::array::from_fn(|c| scattered[c] * global[c]);
    let ms_local = std::array::from_fn(|c| {
        direct_fraction * p.d_b * local_direct[c] + scattered[c] * p.d_b * local[c]
    });
    (ms_global, ms_local)
}
