//! Controls shared by the panels: a labelled slider with a tooltip (physical meaning and unit) and a
//! reset button, reporting whether the value changed and whether a drag is still going on.

/// What a control did this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Changed {
    pub changed: bool,
    /// The pointer is still on the control (a drag continues: one undo step).
    pub gesture: bool,
}

impl Changed {
    pub fn or(self, other: Changed) -> Changed {
        Changed {
            changed: self.changed || other.changed,
            gesture: self.gesture || other.gesture,
        }
    }
}

/// A slider over `range` in the unit `suffix`, with a reset to `default`.
#[allow(clippy::too_many_arguments)]
pub fn slider(
    ui: &mut egui::Ui,
    label: &str,
    value: &mut f64,
    range: std::ops::RangeInclusive<f64>,
    suffix: &str,
    decimals: usize,
    default: f64,
    tooltip: &str,
) -> Changed {
    let mut out = Changed::default();
    ui.horizontal(|ui| {
        let r = ui
            .add(
                egui::Slider::new(value, range)
                    .text(label)
                    .suffix(suffix)
                    .fixed_decimals(decimals)
                    // Only the user's edits: with Always, drawing a session's value outside the
                    // range (or with more decimals) rewrote it and recorded an edit.
                    .clamping(egui::SliderClamping::Edits),
            )
            .on_hover_text(tooltip);
        out.changed |= r.changed();
        out.gesture |= r.is_pointer_button_down_on() || r.dragged();
        if reset_button(ui, *value != default) {
            *value = default;
            out.changed = true;
        }
    });
    out
}

/// The same for an f32.
#[allow(clippy::too_many_arguments)]
pub fn slider32(
    ui: &mut egui::Ui,
    label: &str,
    value: &mut f32,
    range: std::ops::RangeInclusive<f32>,
    suffix: &str,
    decimals: usize,
    default: f32,
    tooltip: &str,
) -> Changed {
    let mut v = *value as f64;
    let c = slider(
        ui,
        label,
        &mut v,
        *range.start() as f64..=*range.end() as f64,
        suffix,
        decimals,
        default as f64,
        tooltip,
    );
    if c.changed {
        *value = v as f32;
    }
    c
}

/// A small reset button (enabled when the value differs from its default).
pub fn reset_button(ui: &mut egui::Ui, enabled: bool) -> bool {
    ui.add_enabled(enabled, egui::Button::new("↺").small())
        .on_hover_text("Reset to the default")
        .clicked()
}

/// Linear to sRGB-encoded byte, and back.
pub fn linear_to_srgb8(x: f64) -> u8 {
    (crate::colour::srgb_encode(x.clamp(0.0, 1.0) as f32) * 255.0 + 0.5) as u8
}

pub fn srgb8_to_linear(b: u8) -> f64 {
    crate::colour::srgb_decode(b as f64 / 255.0)
}
