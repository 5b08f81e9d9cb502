//! The tool row (navigate, brush) and the brush panel: mode, dye (colour picker, melanin, palette),
//! radius, strength, falloff, reach, root-to-tip mask, mirror, spacing.

use super::widgets::{linear_to_srgb8, srgb8_to_linear};
use crate::editor::command::AppCommand;
use crate::editor::context::PanelContext;
use crate::editor::tools::brush::BrushTool;
use crate::editor::tools::{Tool, Tools};
use crate::paint::brush::{FRONT_DEPTH, Falloff, PaintMode};
use crate::paint::dye::{DEFAULT_BETA_N, colour_from_sigma_a};
use crate::paint::sigma_a_from_colour;
use crate::scattering::params::sigma_a_from_melanin;

/// A dye of the palette: its name and how its absorption is made.
enum DyeSpec {
    Melanin(f64, f64),
    /// Linear RGB multiple-scattering albedo (inverted as in the look panel).
    Colour([f64; 3]),
}

/// Natural shades (eumelanin, pheomelanin; d'Eon 2011) and fashion dyes (sRGB colours).
const PALETTE: [(&str, DyeSpec); 12] = [
    ("black", DyeSpec::Melanin(8.0, 0.0)),
    ("dark brown", DyeSpec::Melanin(2.5, 0.3)),
    ("chestnut", DyeSpec::Melanin(1.1, 0.9)),
    ("ginger", DyeSpec::Melanin(0.25, 2.0)),
    ("golden blond", DyeSpec::Melanin(0.25, 0.35)),
    ("platinum", DyeSpec::Melanin(0.02, 0.02)),
    ("cherry red", DyeSpec::Colour([0.50, 0.03, 0.04])),
    ("copper", DyeSpec::Colour([0.62, 0.20, 0.05])),
    ("pastel pink", DyeSpec::Colour([0.80, 0.32, 0.45])),
    ("violet", DyeSpec::Colour([0.20, 0.06, 0.45])),
    ("electric blue", DyeSpec::Colour([0.03, 0.15, 0.65])),
    ("teal", DyeSpec::Colour([0.03, 0.35, 0.30])),
];

impl DyeSpec {
    fn sigma_a(&self) -> [f32; 3] {
        match *self {
            DyeSpec::Melanin(e, p) => sigma_a_from_melanin(e, p),
            DyeSpec::Colour(c) => sigma_a_from_colour(c, DEFAULT_BETA_N),
        }
        .map(|x| x as f32)
    }
}

/// The colour a sigma_a looks (the inversion run forward), for swatches.
fn swatch(sigma_a: [f32; 3]) -> egui::Color32 {
    let c = colour_from_sigma_a(sigma_a.map(f64::from), DEFAULT_BETA_N);
    let [r, g, b] = c.map(linear_to_srgb8);
    egui::Color32::from_rgb(r, g, b)
}

/// The tool row, and the brush's settings when it is the tool.
pub fn tools(ctx: &PanelContext, tools: &mut Tools, ui: &mut egui::Ui) {
    let mut tool = tools.active();
    ui.horizontal(|ui| {
        ui.label("Tool");
        ui.selectable_value(&mut tool, Tool::Navigate, "navigate")
            .on_hover_text("Orbit, pan and zoom (V or Esc)");
        ui.selectable_value(&mut tool, Tool::Brush, "brush")
            .on_hover_text(
                "Paint absorption onto the strands under the cursor (B): left-drag paints, the middle \
                 button and the wheel still navigate",
            );
    });
    tools.select(tool);
    if tool == Tool::Brush {
        panel(ctx, tools.brush_mut(), ui);
    }
}

fn panel(ctx: &PanelContext, brush: &mut BrushTool, ui: &mut egui::Ui) {
    let st = brush.stats();
    let b = brush.settings_mut();
    ui.horizontal_wrapped(|ui| {
        for m in PaintMode::ALL {
            ui.selectable_value(&mut b.mode, m, m.name())
                .on_hover_text(match m {
                    PaintMode::Dye => "Mix toward the dye's absorption",
                    PaintMode::Darken => {
                        "Add eumelanin (one unit of concentration at full strength)"
                    }
                    PaintMode::Lighten => {
                        "Remove melanin (bleach: 60 % less absorption at full strength)"
                    }
                    PaintMode::Blur => {
                        "Average with the neighbours along the strand and under the brush"
                    }
                    PaintMode::Erase => "Back to the look's absorption",
                });
        }
    });
    if b.mode == PaintMode::Dye {
        ui.horizontal(|ui| {
            // The dye's colour: the albedo its absorption gives, editable through the inversion.
            let mut srgb = swatch(b.dye).to_array();
            let mut rgb = [srgb[0], srgb[1], srgb[2]];
            let r = egui::color_picker::color_edit_button_srgb(ui, &mut rgb).on_hover_text(
                "The dye's colour (sRGB): the hair's multiple-scattering albedo, turned into \
                 absorption by Chiang 2016's inversion",
            );
            if r.changed() {
                srgb[..3].copy_from_slice(&rgb);
                b.dye =
                    sigma_a_from_colour(rgb.map(srgb8_to_linear), DEFAULT_BETA_N).map(|x| x as f32);
            }
            ui.weak(format!(
                "σ_a = ({:.2}, {:.2}, {:.2})",
                b.dye[0], b.dye[1], b.dye[2]
            ))
            .on_hover_text("The dye's absorption per unit fibre radius (R, G, B)");
        });
        ui.horizontal_wrapped(|ui| {
            for (name, spec) in &PALETTE {
                let s = spec.sigma_a();
                let swatch_button =
                    egui::Button::new(egui::RichText::new("■").color(swatch(s)).size(18.0)).small();
                if ui
                    .add(swatch_button)
                    .on_hover_text(format!(
                        "{name}: σ_a = ({:.2}, {:.2}, {:.2})",
                        s[0], s[1], s[2]
                    ))
                    .clicked()
                {
                    b.dye = s;
                }
            }
        });
        // The dye as melanin concentrations (d'Eon 2011), as the look panel makes hair from them.
        let id = ui.scope_id().with("dye melanin");
        let mut m: (f64, f64) = ui.data(|d| d.get_temp(id)).unwrap_or((1.0, 0.3));
        let changed = ui
            .horizontal(|ui| {
                let e = ui
                    .add(
                        egui::DragValue::new(&mut m.0)
                            .range(0.0..=20.0)
                            .speed(0.02)
                            .prefix("eu "),
                    )
                    .on_hover_text("Eumelanin concentration of the dye (brown-black)");
                let p = ui
                    .add(
                        egui::DragValue::new(&mut m.1)
                            .range(0.0..=20.0)
                            .speed(0.02)
                            .prefix("pheo "),
                    )
                    .on_hover_text("Pheomelanin concentration of the dye (red-yellow)");
                ui.weak("melanin");
                e.changed() || p.changed()
            })
            .inner;
        if changed {
            b.dye = sigma_a_from_melanin(m.0, m.1).map(|x| x as f32);
        }
        ui.data_mut(|d| d.insert_temp(id, m));
    }
    ui.add(
        egui::Slider::new(&mut b.radius_px, 2.0..=500.0)
            .text("radius")
            .suffix(" px")
            .fixed_decimals(0),
    )
    .on_hover_text("Brush radius in screen pixels ([ and ], or F then move)");
    ui.add(egui::Slider::new(&mut b.strength, 0.0..=1.0).text("strength"))
        .on_hover_text(
            "What a stroke reaches at the brush centre: 1 paints the dye fully (Shift+F)",
        );
    egui::ComboBox::from_label("falloff")
        .selected_text(b.falloff.name())
        .show_ui(ui, |ui| {
            for f in Falloff::ALL {
                ui.selectable_value(&mut b.falloff, f, f.name());
            }
        });
    let mut through = b.depth > FRONT_DEPTH;
    ui.horizontal(|ui| {
        if ui
            .checkbox(&mut through, "paint through")
            .on_hover_text(format!(
                "Reach strands hidden behind the front ones, up to the depth set (cm behind the \
                 front-most hair under the brush). Off: the front {FRONT_DEPTH} cm only"
            ))
            .changed()
        {
            b.depth = if through { 3.0 } else { FRONT_DEPTH };
        }
        if through {
            ui.add(
                egui::DragValue::new(&mut b.depth)
                    .range(FRONT_DEPTH..=100.0)
                    .speed(0.1)
                    .suffix(" cm"),
            );
        }
    });
    let mut masked = b.mask.is_some();
    if ui
        .checkbox(&mut masked, "root-to-tip mask")
        .on_hover_text("Paint only where the strand parameter (0 root, 1 tip) lies in a range: roots, ombré, tips")
        .changed()
    {
        b.mask = masked.then_some([0.6, 1.0, 0.1]);
    }
    if let Some([t0, t1, f]) = &mut b.mask {
        ui.add(egui::Slider::new(t0, 0.0..=1.0).text("from t"));
        ui.add(egui::Slider::new(t1, 0.0..=1.0).text("to t"));
        ui.add(egui::Slider::new(f, 0.0..=0.5).text("feather"))
            .on_hover_text("The mask fades over this much of the strand on each side");
    }
    ui.checkbox(&mut b.mirror, "X mirror")
        .on_hover_text("Also paint the footprint mirrored across the hair's symmetry plane (even where that side is hidden)");
    ui.add(egui::Slider::new(&mut b.spacing, 0.05..=1.0).text("spacing"))
        .on_hover_text("Dab spacing along the stroke, as a fraction of the radius");
    let painted = ctx.session.paint_layer.is_some() || ctx.session.paint.is_some();
    if ui
        .add_enabled(painted, egui::Button::new("Clear paint"))
        .on_hover_text("Remove the paint layer: the hair shows the look alone (one undo step)")
        .clicked()
    {
        ctx.send(AppCommand::ClearPaint);
    }
    if st.dabs > 0 {
        ui.weak(format!(
            "{} dabs · last {:.2} ms, {} points · mean {:.2} ms",
            st.dabs, st.last_dab_ms, st.last_points, st.mean_dab_ms
        ))
        .on_hover_text("CPU time per dab: finding the points, the layer, the upload");
    }
}
