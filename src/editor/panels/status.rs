//! The status bar: adapter, hair and light counts, refinement progress, UI frame time, jobs, messages.

use crate::editor::command::AppCommand;
use crate::editor::context::PanelContext;
use crate::editor::messages::Level;
use crate::render::refine::UNIT_PASSES;

pub fn bar(ctx: &PanelContext, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        match ctx.gpu {
            Some(g) => ui.label(format!("GPU: {} ({})", g.summary.name, g.summary.backend)),
            None => ui.colored_label(ui.visuals().error_fg_color, "no GPU"),
        };
        ui.separator();
        if let Some(live) = ctx.live() {
            let s = {
                let d = live.lock();
                Snapshot {
                    strands: d.hair.strand_count(),
                    points: d.hair.point_count(),
                    lights: d.renderer.light_count(),
                    size: (d.display.width, d.display.height),
                    progress: d.clock.progress,
                    final_image: !d.tables_pending(),
                    first: d.first_image_in(),
                    sharp: d.clock.full_image_in,
                    converged: d.clock.converged_in,
                }
            };
            ui.label(format!(
                "{} strands · {} points · {} lights",
                s.strands, s.points, s.lights
            ));
            ui.separator();
            let (w, h) = s.size;
            ui.label(format!("{w}×{h} ({:.0} %)", 100.0 * ctx.viewport.view().scale))
                .on_hover_text(
                    "The render size and its share of the viewport's pixels (the resolution buttons by the view transform)",
                );
            let secs = |t: Option<std::time::Duration>| {
                t.map_or("–".to_string(), |t| format!("{:.1} s", t.as_secs_f64()))
            };
            let times = format!(
                "first {} · sharp {} · converged {}",
                secs(s.first),
                secs(s.sharp),
                secs(s.converged.filter(|_| s.final_image))
            );
            let hover = "Wall-clock time since the last change (since the launch for the first \
                         scene): the first image (a preview at reduced resolution), the sharp \
                         full-resolution image (every light at the front fragment of each pixel) \
                         and the converged image";
            match s.progress {
                Some(p) if p.converged && s.final_image => {
                    let passes: Vec<String> = UNIT_PASSES
                        .iter()
                        .zip(p.stats.pass_time)
                        .filter(|(_, d)| !d.is_zero())
                        .map(|(n, d)| format!("{n} {:.0}", d.as_secs_f64() * 1e3))
                        .collect();
                    ui.label(times).on_hover_text(format!(
                        "{hover}. {} units, the longest {:.0} ms; time per pass (ms, submission \
                         to completion of its units): {}",
                        p.stats.units,
                        p.stats.longest.as_secs_f64() * 1e3,
                        passes.join(", ")
                    ));
                }
                Some(p) => {
                    ui.add(
                        egui::ProgressBar::new(p.fraction)
                            .desired_width(120.0)
                            .text("refining"),
                    );
                    ui.weak(times).on_hover_text(hover);
                }
                None => {
                    ui.weak(times).on_hover_text(hover);
                }
            }
        }
        if let Some(label) = ctx.jobs.loading {
            ui.separator();
            ui.label(format!("{label}…"));
        }
        if let Some((fraction, writing)) = ctx.jobs.export {
            ui.separator();
            ui.add(
                egui::ProgressBar::new(fraction)
                    .desired_width(100.0)
                    .text("export"),
            );
            if ui
                .add_enabled(!writing, egui::Button::new("cancel").small())
                .on_hover_text("Stop the export (nothing is written)")
                .clicked()
            {
                ctx.send(AppCommand::CancelExport);
            }
        }
        if ctx.frame_ms > 0.0 {
            ui.separator();
            ui.weak(format!("UI {:.1} ms", ctx.frame_ms))
                .on_hover_text("The UI's own work per frame (the render thread refines apart)");
        }
        if let Some(m) = ctx.messages.last() {
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

/// What the status bar shows of the live driver, read under its lock at once.
struct Snapshot {
    strands: usize,
    points: usize,
    lights: u32,
    size: (u32, u32),
    progress: Option<crate::render::refine::Progress>,
    final_image: bool,
    first: Option<std::time::Duration>,
    sharp: Option<std::time::Duration>,
    converged: Option<std::time::Duration>,
}
