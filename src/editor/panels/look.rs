//! The look panel: presets, absorption (melanin, dye colour or sigma_a; root-to-tip gradient; per-strand
//! variation), Marschner's lobe shifts and widths (locked to his couplings unless opened), the fibre's
//! index and eccentricity, Zinke's density factors and the longitudinal function. The TRT caustic's
//! width and fade are shown disabled (only Xu's fits read them; the renderer integrates the exact
//! caustic); the caustic limit and glint scale, which the fast form never reads, are not shown.
//! Returns the edited look and whether a drag is still going on.

use super::widgets::{Changed, linear_to_srgb8, reset_button, slider, slider32, srgb8_to_linear};
use crate::paint::dye::DEFAULT_BETA_N;
use crate::scattering::{HairParams, Lobe, LongitudinalModel, Preset};
use crate::session::{Absorption, Look};

pub fn panel(ui: &mut egui::Ui, current: &Look) -> Option<(Look, bool)> {
    let mut look = *current;
    let mut c = Changed::default();
    let defaults = Look::default();
    ui.heading("Look");
    c = c.or(preset_row(ui, &mut look));
    ui.separator();

    ui.strong("Absorption");
    c = c.or(absorption(ui, "root", &mut look.root));
    let mut gradient = look.tip.is_some();
    if ui
        .checkbox(&mut gradient, "Root-to-tip gradient")
        .on_hover_text("A different absorption at the tips, interpolated along each strand")
        .changed()
    {
        look.tip = gradient.then_some(look.root);
        c.changed = true;
    }
    if let Some(tip) = &mut look.tip {
        c = c.or(absorption(ui, "tip", tip));
    }
    c = c.or(slider32(
        ui,
        "strand variation",
        &mut look.strand_variation,
        0.0..=1.0,
        "",
        2,
        0.0,
        "Per-strand log-normal variation of sigma_a: the standard deviation of ln sigma_a across strands",
    ));
    ui.separator();

    ui.strong("Highlights (Marschner)");
    c = c.or(lobes(ui, &mut look.params));
    ui.separator();

    ui.strong("Fibre");
    c = c.or(slider32(
        ui,
        "thickness",
        &mut look.thickness_scale,
        0.25..=4.0,
        "×",
        2,
        defaults.thickness_scale,
        "Multiplies every fibre's diameter (the file's, or 70 µm): thicker fibres shadow each other \
         more (the fibre-density volume's optical depth grows with the diameter) and their ribbons in \
         the view widen (at least a pixel)",
    ));
    let p = &mut look.params;
    let d = &defaults.params;
    c = c.or(slider(
        ui,
        "η",
        &mut p.eta,
        1.3..=2.0,
        "",
        3,
        d.eta,
        "Index of refraction of the fibre (1.55 for keratin)",
    ));
    c = c.or(slider(
        ui,
        "eccentricity",
        &mut p.eccentricity,
        0.8..=1.2,
        "",
        3,
        d.eccentricity,
        "Ratio of the cross-section's axes (1 = circular); moves the TRT glints with the azimuth",
    ));
    // The renderer integrates the exact TRT caustic (the azimuthal table, the reference's unsmoothed
    // root sum): Marschner's width and fade shape only Xu's published circular-Gaussian fits and the
    // exact model's smoothed variant (CPU), so they are shown and kept in the session, not edited here.
    ui.add_enabled_ui(false, |ui| {
        let mut wc = p.caustic_width.to_degrees();
        slider(
            ui,
            "caustic width w_c",
            &mut wc,
            5.0..=40.0,
            "°",
            1,
            d.caustic_width.to_degrees(),
            "Azimuthal width of the TRT caustic (glint) lobes, degrees",
        );
        let mut fade = p.caustic_fade;
        slider(
            ui,
            "caustic fade Δη'",
            &mut fade,
            0.05..=0.6,
            "",
            2,
            d.caustic_fade,
            "Range of the Bravais index over which the caustics fade out as η' approaches 2",
        );
    });
    ui.weak("The renderer integrates the exact caustic: w_c and Δη' shape only Xu's fitted lobes.");
    ui.separator();

    ui.strong("Multiple scattering (Zinke)");
    c = c.or(slider32(
        ui,
        "d_f",
        &mut look.d_f,
        0.0..=1.0,
        "",
        2,
        defaults.d_f,
        "Forward-scattering density factor of dual scattering (0.7 in Zinke et al. 2008)",
    ));
    c = c.or(slider32(
        ui,
        "d_b",
        &mut look.d_b,
        0.0..=1.0,
        "",
        2,
        defaults.d_b,
        "Backward-scattering density factor of dual scattering (0.7 in Zinke et al. 2008)",
    ));
    ui.horizontal(|ui| {
        ui.label("Longitudinal");
        for (m, name, tip) in [
            (
                LongitudinalModel::Normalized,
                "normalised",
                "d'Eon et al. 2011: energy-conserving (a lossless fibre in a white furnace renders at 1)",
            ),
            (
                LongitudinalModel::Published,
                "published",
                "Marschner 2003 / Xu 2011 Eq. 7 as printed: about twice too bright",
            ),
        ] {
            if ui
                .selectable_label(look.longitudinal == m, name)
                .on_hover_text(tip)
                .clicked()
                && look.longitudinal != m
            {
                look.longitudinal = m;
                c.changed = true;
            }
        }
    });
    (c.changed && look != *current && look.validate().is_ok()).then_some((look, c.gesture))
}

fn preset_row(ui: &mut egui::Ui, look: &mut Look) -> Changed {
    let mut c = Changed::default();
    ui.horizontal_wrapped(|ui| {
        ui.label("Preset");
        for p in Preset::ALL {
            let name = format!("{p:?}")
                .replace("DarkBrown", "dark brown")
                .to_lowercase();
            if ui
                .button(name)
                .on_hover_text("Melanin concentrations and Marschner's mid-range lobe parameters")
                .clicked()
            {
                look.apply_preset(p);
                c.changed = true;
            }
        }
    });
    c
}

/// The absorption of one end of the strands: melanin, a dye colour or sigma_a itself.
fn absorption(ui: &mut egui::Ui, end: &str, a: &mut Absorption) -> Changed {
    let mut c = Changed::default();
    ui.horizontal(|ui| {
        ui.label(end);
        let sigma = a.sigma_a();
        let modes = [
            (
                "melanin",
                "Eumelanin and pheomelanin concentrations (d'Eon et al. 2011)",
            ),
            (
                "dye",
                "A colour, inverted to sigma_a by Chiang et al. 2016 Eq. 9",
            ),
            ("σ_a", "Absorption per unit fibre radius, RGB"),
        ];
        let current = match a {
            Absorption::Melanin { .. } => 0,
            Absorption::Dye { .. } => 1,
            Absorption::SigmaA { .. } => 2,
        };
        for (i, (name, tip)) in modes.iter().enumerate() {
            if ui
                .selectable_label(current == i, *name)
                .on_hover_text(*tip)
                .clicked()
                && current != i
            {
                *a = match i {
                    0 => Absorption::from_preset(Preset::Brown),
                    // The dye whose inversion gives today's sigma_a would need the forward model;
                    // start from a mid brown the user then picks from.
                    1 => Absorption::Dye {
                        colour: [0.25, 0.12, 0.06],
                        beta_n: DEFAULT_BETA_N,
                    },
                    _ => Absorption::SigmaA { sigma_a: sigma },
                };
                c.changed = true;
            }
        }
    });
    match a {
        Absorption::Melanin {
            eumelanin,
            pheomelanin,
        } => {
            c = c.or(slider(
                ui,
                "eumelanin",
                eumelanin,
                0.0..=8.0,
                "",
                2,
                1.3,
                "Eumelanin concentration (brown-black pigment): about 0.3 blond, 1.3 brown, 8 black",
            ));
            c = c.or(slider(
                ui,
                "pheomelanin",
                pheomelanin,
                0.0..=4.0,
                "",
                2,
                0.2,
                "Pheomelanin concentration (red-yellow pigment)",
            ));
        }
        Absorption::Dye { colour, beta_n } => {
            ui.horizontal(|ui| {
                let mut srgb = colour.map(linear_to_srgb8);
                let r = egui::color_picker::color_edit_button_srgb(ui, &mut srgb).on_hover_text(
                    "The dye's colour (sRGB): the hair's multiple-scattering albedo",
                );
                if r.changed() {
                    *colour = srgb.map(srgb8_to_linear);
                    c.changed = true;
                    c.gesture = true;
                }
                ui.label("dye colour");
                if reset_button(ui, *beta_n != DEFAULT_BETA_N) {
                    *beta_n = DEFAULT_BETA_N;
                    c.changed = true;
                }
            });
            c = c.or(slider(
                ui,
                "β_N of the inversion",
                beta_n,
                0.1..=0.9,
                "",
                2,
                DEFAULT_BETA_N,
                "Azimuthal roughness assumed by Chiang's colour inversion (their default 0.3)",
            ));
        }
        Absorption::SigmaA { sigma_a } => {
            for (i, ch) in ["σ_a R", "σ_a G", "σ_a B"].iter().enumerate() {
                c = c.or(slider(
                    ui,
                    ch,
                    &mut sigma_a[i],
                    0.0..=10.0,
                    " /r",
                    3,
                    Preset::Brown.params().sigma_a[i],
                    "Absorption coefficient per unit fibre radius in this channel",
                ));
            }
        }
    }
    let s = a.sigma_a();
    ui.weak(format!("σ_a = ({:.3}, {:.3}, {:.3})", s[0], s[1], s[2]));
    c
}

/// alpha_R and beta_R, and the TT / TRT shifts and widths behind Marschner's couplings.
fn lobes(ui: &mut egui::Ui, p: &mut HairParams) -> Changed {
    let mut c = Changed::default();
    let d = HairParams::default();
    let mut deg = |ui: &mut egui::Ui,
                   label: &str,
                   v: f64,
                   range: std::ops::RangeInclusive<f64>,
                   default: f64,
                   tip: &str|
     -> Option<f64> {
        let mut x = v.to_degrees();
        let r = slider(ui, label, &mut x, range, "°", 1, default.to_degrees(), tip);
        c = c.or(r);
        r.changed.then(|| x.to_radians())
    };
    if let Some(x) = deg(
        ui,
        "α_R shift",
        p.alpha_r,
        -15.0..=15.0,
        d.alpha_r,
        "Longitudinal shift of the primary highlight R (cuticle tilt; negative: towards the root), degrees",
    ) {
        p.alpha_r = x;
    }
    if let Some(x) = deg(
        ui,
        "β_R width",
        p.beta_r,
        1.0..=25.0,
        d.beta_r,
        "Longitudinal width (standard deviation) of R, degrees; smaller is a sharper highlight",
    ) {
        p.beta_r = x;
    }
    let coupled = p.alpha_tt.is_none()
        && p.alpha_trt.is_none()
        && p.beta_tt.is_none()
        && p.beta_trt.is_none();
    let mut lock = coupled;
    let mut lock_changed = false;
    if ui
        .checkbox(&mut lock, "Marschner's couplings")
        .on_hover_text(
            "α_TT = -α_R/2, α_TRT = -3α_R/2, β_TT = β_R/2, β_TRT = 2β_R; untick to set TT and TRT apart",
        )
        .changed()
    {
        if lock {
            p.alpha_tt = None;
            p.alpha_trt = None;
            p.beta_tt = None;
            p.beta_trt = None;
        } else {
            p.alpha_tt = Some(p.alpha(Lobe::TT));
            p.alpha_trt = Some(p.alpha(Lobe::TRT));
            p.beta_tt = Some(p.beta(Lobe::TT));
            p.beta_trt = Some(p.beta(Lobe::TRT));
        }
        lock_changed = true;
    }
    if !lock {
        let (a_tt, a_trt, b_tt, b_trt) = (
            p.alpha(Lobe::TT),
            p.alpha(Lobe::TRT),
            p.beta(Lobe::TT),
            p.beta(Lobe::TRT),
        );
        if let Some(x) = deg(
            ui,
            "α_TT",
            a_tt,
            -15.0..=15.0,
            -0.5 * p.alpha_r,
            "Shift of the transmitted lobe TT, degrees",
        ) {
            p.alpha_tt = Some(x);
        }
        if let Some(x) = deg(
            ui,
            "α_TRT",
            a_trt,
            -25.0..=25.0,
            -1.5 * p.alpha_r,
            "Shift of the secondary highlight TRT, degrees",
        ) {
            p.alpha_trt = Some(x);
        }
        if let Some(x) = deg(
            ui,
            "β_TT",
            b_tt,
            0.5..=20.0,
            0.5 * p.beta_r,
            "Width of TT, degrees",
        ) {
            p.beta_tt = Some(x);
        }
        if let Some(x) = deg(
            ui,
            "β_TRT",
            b_trt,
            1.0..=40.0,
            2.0 * p.beta_r,
            "Width of TRT, degrees",
        ) {
            p.beta_trt = Some(x);
        }
    }
    c.changed |= lock_changed;
    c
}
