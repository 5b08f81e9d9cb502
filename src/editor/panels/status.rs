//! The status bar: adapter, hair and light counts, refinement progress, UI frame time, jobs, messages.

use crate::editor::app::{EditorApp, Level};
use crate::render::progressive::UNIT_PASSES;

pub fn bar(app: &mut EditorApp, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        match &app.gpu {
            Some(g) => ui.label(format!("GPU: {} ({})", g.summary.name, g.summary.backend)),
            None => ui.colored_label(ui.visuals().error_fg_color, "no GPU"),
        };
        ui.separator();
        if let Some(live) = &app.live {
            ui.label(format!(
                "{} strands · {} points · {} lights",
                live.hair.strand_count(),
                live.hair.point_count(),
                live.renderer.light_count()
            ));
            ui.separator();
            let (w, h) = (live.display.width, live.display.height);
            match (live.progress, live.converged_in) {
                (Some(p), Some(t)) if p.converged && !live.tables_pending() => {
                    let passes: Vec<String> = UNIT_PASSES
                        .iter()
                        .zip(p.stats.pass_time)
                        .filter(|(_, d)| !d.is_zero())
                        .map(|(n, d)| format!("{n} {:.0}", d.as_secs_f64() * 1e3))
                        .collect();
                    ui.label(format!(
                        "{w}×{h} converged in {:.1} s · {} units, longest {:.0} ms",
                        t.as_secs_f64(),
                        p.stats.units,
                        p.stats.longest.as_secs_f64() * 1e3
                    ))
                    .on_hover_text(format!(
                        "Time per pass (ms, submission to completion of its units): {}",
                        passes.join(", ")
                    ));
                    ui.weak(format!("ms: {}", passes.join(" · ")));
                }
                (Some(p), _) => {
                    ui.add(
                        egui::ProgressBar::new(p.fraction)
                            .desired_width(120.0)
                            .text(format!("refining {w}×{h}")),
                    );
                    let times: Vec<String> =
                        [("preview", live.preview_in), ("full", live.full_image_in)]
                            .into_iter()
                            .filter_map(|(n, t)| t.map(|t| format!("{n} {:.2} s", t.as_secs_f64())))
                            .collect();
                    if !times.is_empty() {
                        ui.weak(times.join(" · ")).on_hover_text(
                            "Since the last change: the reduced-resolution preview, and the full \
                             image with every light at the front fragment of each pixel",
                        );
                    }
                }
                _ => {}
            }
        } else if app.loading.is_some() {
            ui.spinner();
        }
        if let Some(job) = &app.loading {
            ui.separator();
            ui.label(format!("{}…", job.label));
        }
        let mut cancel = false;
        if let Some(e) = &app.export {
            ui.separator();
            ui.add(
                egui::ProgressBar::new(e.fraction)
                    .desired_width(100.0)
                    .text("export"),
            );
            cancel = ui
                .add_enabled(!e.writing(), egui::Button::new("cancel").small())
                .on_hover_text("Stop the export (nothing is written)")
                .clicked();
        }
        if cancel {
            app.export = None;
            app.message(Level::Info, "export cancelled");
        }
        if app.frame_ms > 0.0 {
            ui.separator();
            ui.weak(format!("UI {:.1} ms", app.frame_ms))
                .on_hover_text("Time between UI frames while the viewport refines");
        }
        if let Some(m) = app.messages.last() {
            ui.separator();
            let colour = match m.level {
                Level::Error => ui.visuals().error_fg_color,
                Level::Warning => ui.visuals().warn_fg_color,
                Level::Info => ui.visuals().weak_text_color(),
            };
            ui.add(egui::Label::new(egui::RichText::new(&m.text).color(colour)).truncate());
        }
    });
}
