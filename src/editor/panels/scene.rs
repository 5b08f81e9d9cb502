//! The scene panel: the hair (file or procedural generator, and its statistics), the environment
//! (file, yaw), the still's render settings and the viewport's view transform.

use super::widgets::{Changed, slider, slider32};
use crate::colour::{srgb_decode, srgb_encode};
use crate::editor::command::{AppCommand, Dialog};
use crate::editor::context::PanelContext;
use crate::editor::env_preview::EnvPreview;
use crate::hair::procedural::{Style, StyleParams};
use crate::render::display::{Solo, ViewTransform};
use crate::render::passes::background::Background;
use crate::render::passes::targets::COMPONENTS;
use crate::session::{Edit, EnvironmentSource, HairSource, RenderOptions};

const STYLES: [(Style, &str); 6] = [
    (Style::StraightLong, "straight long"),
    (Style::Wavy, "wavy"),
    (Style::Curly, "curly"),
    (Style::Bob, "bob"),
    (Style::Ponytail, "ponytail"),
    (Style::SidePart, "side part"),
];

pub fn panel(ctx: &PanelContext, ui: &mut egui::Ui) {
    ui.heading("Hair");
    hair(ctx, ui);
    ui.separator();
    ui.heading("Environment");
    environment(ctx, ui);
    ui.separator();
    ui.heading("Render");
    render(ctx, ui);
    ui.separator();
    ui.heading("Viewport");
    view(ctx, ui);
}

fn hair(ctx: &PanelContext, ui: &mut egui::Ui) {
    match &ctx.session.hair {
        HairSource::File { path, .. } => {
            ui.label(format!("file {}", path.display()));
        }
        HairSource::Generated { .. } => {
            ui.label("procedural, on the generated head");
        }
    }
    if ui.button("Open hair file…").clicked() {
        ctx.send(AppCommand::Dialog(Dialog::OpenHair));
    }
    generator(ctx, ui);
    head(ctx, ui);
    let mut dye = None;
    if let Some(live) = ctx.live() {
        // The driver's bounds, found once per hair (not every frame over every point).
        let (strands, points, (lo, hi), coloured) = {
            let d = live.lock();
            let coloured = d.hair.colour.is_some();
            (
                d.hair.strand_count(),
                d.hair.point_count(),
                d.bounds,
                coloured,
            )
        };
        let size = hi - lo;
        ui.weak(format!(
            "{strands} strands, {points} points, {:.1} × {:.1} × {:.1} cm",
            size.x, size.y, size.z
        ));
        if coloured
            && ui
                .button("Dye from the file's colours")
                .on_hover_text(
                    "The file carries a colour per point (groom_color, displayColor, the cyHair \
                     colour array): paint every point with the absorption that colour gives \
                     (Chiang's inversion), as a paint layer you can undo or paint over",
                )
                .clicked()
        {
            let hair = live.lock().hair.clone();
            dye = crate::paint::PaintLayer::from_colours(&hair, crate::paint::dye::DEFAULT_BETA_N);
        }
    }
    if let Some(layer) = dye {
        let layer = crate::paint::SharedLayer::new(layer);
        ctx.send(AppCommand::Edit {
            edit: Edit::PaintLayer(Box::new((Some(layer), None))),
            gesture: false,
        });
    }
}

/// The head the hair sits on: shown or not, its skin colour, and its mesh (the hair's own: the
/// generated head, or the mesh a glTF hair carries; or a mesh file).
fn head(ctx: &PanelContext, ui: &mut egui::Ui) {
    let mut o = ctx.session.occluder.clone();
    let mut gesture = false;
    ui.horizontal(|ui| {
        ui.checkbox(&mut o.show, "Head").on_hover_text(
            "Draw the head: it hides the hair behind it, shadows the hair and takes the hair's shadows",
        );
        let encode = |v: f32| (255.0 * srgb_encode(v.clamp(0.0, 1.0)) + 0.5) as u8;
        let mut rgb = o.albedo.map(encode);
        if ui
            .color_edit_button_srgb(&mut rgb)
            .on_hover_text("Skin colour (its diffuse albedo)")
            .changed()
        {
            o.albedo = rgb.map(|v| srgb_decode(v as f64 / 255.0) as f32);
            gesture |= ui.input(|i| i.pointer.any_down());
        }
    });
    ui.horizontal(|ui| {
        let own = match (
            &ctx.session.hair,
            ctx.live().map(|l| l.lock().sources.hair_mesh.is_some()),
        ) {
            (HairSource::Generated { .. }, _) => "the generated head",
            (_, Some(true)) => "the hair file's mesh",
            _ => "none (the hair file has no mesh)",
        };
        let what = o
            .mesh
            .as_ref()
            .and_then(|p| p.file_name())
            .map_or(own.to_string(), |n| n.to_string_lossy().into_owned());
        ui.weak(what);
        if ui
            .button("Mesh…")
            .on_hover_text("An OBJ or glTF mesh, in the hair file's units and axes")
            .clicked()
        {
            ctx.send(AppCommand::Dialog(Dialog::OpenOccluder));
        }
        if o.mesh.is_some()
            && ui
                .button("Own")
                .on_hover_text(format!("Back to {own}"))
                .clicked()
        {
            o.mesh = None;
        }
    });
    if o != ctx.session.occluder {
        ctx.send(AppCommand::Edit {
            edit: Edit::Occluder(Box::new(o)),
            gesture,
        });
    }
}

/// The generator's settings being edited (applied by Generate, one undo step).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Generator {
    style: usize,
    strands: usize,
    points: usize,
    seed: u64,
    length: [f32; 2],
    clumping: f32,
    frizz: f32,
}

impl Generator {
    fn of(source: &HairSource) -> Self {
        let p = source
            .style_params()
            .unwrap_or_else(|| StyleParams::new(Style::Wavy, 3000, 16, 1));
        Self {
            style: STYLES.iter().position(|s| s.0 == p.style).unwrap_or(1),
            strands: p.strands,
            points: p.points,
            seed: p.seed,
            length: [p.length.0, p.length.1],
            clumping: p.clumping,
            frizz: p.frizz,
        }
    }

    /// The session's hair source; the shape is left at the generator's defaults where it equals them.
    fn source(&self) -> HairSource {
        let style = STYLES[self.style].0;
        let d = StyleParams::new(style, self.strands, self.points, self.seed);
        let [a, b] = self.length;
        HairSource::Generated {
            style,
            strands: self.strands,
            points: self.points,
            seed: self.seed,
            length: ((a, b) != d.length).then_some([a.min(b), a.max(b)]),
            clumping: (self.clumping != d.clumping).then_some(self.clumping),
            frizz: (self.frizz != d.frizz).then_some(self.frizz),
        }
    }
}

/// The procedural generator (style, counts, seed, length, clumping, frizz): Generate makes the
/// settings the session's hair.
fn generator(ctx: &PanelContext, ui: &mut egui::Ui) {
    let id = ui.scope_id().with("generator");
    let mut g = ui
        .data_mut(|d| d.get_temp::<Generator>(id))
        .unwrap_or_else(|| Generator::of(&ctx.session.hair));
    egui::CollapsingHeader::new("Generator")
        .default_open(false)
        .show(ui, |ui| {
            let before = g.style;
            egui::ComboBox::from_label("style")
                .selected_text(STYLES[g.style].1)
                .show_ui(ui, |ui| {
                    for (i, (_, name)) in STYLES.iter().enumerate() {
                        ui.selectable_value(&mut g.style, i, *name);
                    }
                });
            if g.style != before {
                let (a, b) = STYLES[g.style].0.default_length();
                g.length = [a, b];
            }
            ui.add(
                egui::DragValue::new(&mut g.strands)
                    .range(1..=200_000)
                    .prefix("strands "),
            )
            .on_hover_text("Number of strands");
            ui.add(egui::DragValue::new(&mut g.points).range(2..=64).prefix("points "))
                .on_hover_text("Points per strand");
            ui.add(egui::DragValue::new(&mut g.seed).prefix("seed "))
                .on_hover_text("Random seed: the same settings and seed give the same hair");
            ui.horizontal(|ui| {
                ui.add(
                    egui::DragValue::new(&mut g.length[0])
                        .range(1.0..=200.0)
                        .speed(0.2)
                        .prefix("length ")
                        .suffix(" cm"),
                )
                .on_hover_text("Shortest strand, cm (strand lengths are uniform in the range)");
                ui.add(
                    egui::DragValue::new(&mut g.length[1])
                        .range(1.0..=200.0)
                        .speed(0.2)
                        .prefix("to ")
                        .suffix(" cm"),
                )
                .on_hover_text("Longest strand, cm");
            });
            ui.add(egui::Slider::new(&mut g.clumping, 0.0..=1.0).text("clumping"))
                .on_hover_text("How far strands are pulled towards their clump's guide: 0 none, 1 the tips meet it");
            ui.add(egui::Slider::new(&mut g.frizz, 0.0..=1.0).text("frizz"))
                .on_hover_text("Random tilts of the strands growing towards the tips: 0 none, 1 strong");
            ui.horizontal(|ui| {
                let source = g.source();
                if ui
                    .add_enabled(source != ctx.session.hair, egui::Button::new("Generate"))
                    .clicked()
                {
                    ctx.send(AppCommand::Edit {
                        edit: Edit::Hair(source),
                        gesture: false,
                    });
                }
                if ui.button("Defaults").on_hover_text("The style's default shape").clicked() {
                    let style = STYLES[g.style].0;
                    let d = Generator::of(&HairSource::generated(style, g.strands, g.points, g.seed));
                    g = Generator { style: g.style, ..d };
                }
            });
        });
    ui.data_mut(|d| d.insert_temp(id, g));
}

fn environment(ctx: &PanelContext, ui: &mut egui::Ui) {
    match &ctx.session.environment {
        EnvironmentSource::Builtin => ui.label("built-in sunny sky"),
        EnvironmentSource::File { path, .. } => ui.label(path.display().to_string()),
    };
    ui.horizontal(|ui| {
        if ui.button("Open…").clicked() {
            ctx.send(AppCommand::Dialog(Dialog::OpenEnvironment));
        }
        if ui
            .add_enabled(
                ctx.session.environment != EnvironmentSource::Builtin,
                egui::Button::new("Built-in"),
            )
            .clicked()
        {
            ctx.send(AppCommand::Edit {
                edit: Edit::Environment(Box::new(EnvironmentSource::Builtin)),
                gesture: false,
            });
            ctx.send(AppCommand::ReloadScene);
        }
    });
    let mut yaw = ctx.session.env_yaw;
    let c = slider(
        ui,
        "yaw",
        &mut yaw,
        -180.0..=180.0,
        "°",
        0,
        0.0,
        "Turns the environment about the vertical axis (no refit), degrees",
    );
    if c.changed {
        ctx.send(AppCommand::Edit {
            edit: Edit::EnvYaw(yaw),
            gesture: c.gesture,
        });
    }
    // The pictures' textures, uploaded once per environment and kept with the panel's other state
    // in egui's memory.
    let id = ui.scope_id().with("environment pictures");
    let mut preview: Option<EnvPreview> = ui.data(|d| d.get_temp(id));
    if let Some(live) = ctx.live() {
        let (count, name) = {
            let d = live.lock();
            (
                d.environment.lights.lights.len(),
                d.environment.name.clone(),
            )
        };
        let pictures = live.environment_pictures.clone();
        if preview.as_ref().map(|p| &p.key) != Some(&pictures.key) {
            let uploaded = crate::editor::env_preview::upload(ui.ctx(), &pictures);
            ui.data_mut(|d| d.insert_temp(id, uploaded.clone()));
            preview = Some(uploaded);
        }
        ui.weak(format!("{count} SRBF lights · {name}"));
    }
    if let Some(p) = &preview {
        let w = ui.available_width().min(250.0);
        let size = egui::vec2(w, 0.5 * w);
        if let Some(image) = &p.image {
            ui.add(egui::Image::new((image.id(), size)))
                .on_hover_text("The environment image (median luminance exposed to 0.18)");
        }
        ui.add(egui::Image::new((p.fit.id(), size)))
            .on_hover_text("Its SRBF reconstruction: what the renderer lights with");
        match p.relative_l2 {
            Some(e) => ui.weak(format!("fit error {:.1} % (relative L2)", 100.0 * e)),
            None => ui.weak("the fit recorded no error"),
        };
    }
}

fn render(ctx: &PanelContext, ui: &mut egui::Ui) {
    let mut r: RenderOptions = ctx.session.render;
    let mut c = Changed::default();
    c.changed |= ui
        .checkbox(&mut r.shadows, "Self-shadowing")
        .on_hover_text("Transmittance through the fibre-density volume (Bertails 2005)")
        .changed();
    c.changed |= ui
        .checkbox(&mut r.multiple_scattering, "Multiple scattering")
        .on_hover_text(
            "Dual scattering (Zinke 2008): global forward scattering and local back scattering",
        )
        .changed();
    c = c.or(slider32(
        ui,
        "exposure",
        &mut r.exposure,
        -6.0..=6.0,
        " EV",
        1,
        0.0,
        "Exposure of the render and the exported EXR, stops",
    ));
    ui.horizontal(|ui| {
        ui.label("still");
        let mut size = [r.width, r.height];
        for (k, v) in size.iter_mut().enumerate() {
            if k == 1 {
                ui.label("×");
            }
            let resp = ui
                .add(egui::DragValue::new(v).range(16..=8192).suffix(" px"))
                .on_hover_text("Size of the exported still, pixels");
            c.changed |= resp.changed();
            c.gesture |= resp.is_pointer_button_down_on() || resp.dragged();
        }
        [r.width, r.height] = size;
    });
    // Wrapped: on a narrow panel the choices go on to the next line rather than out of reach.
    ui.horizontal_wrapped(|ui| {
        ui.label("background");
        let now = r.background;
        let colour = match now {
            Background::Colour(c) => c,
            _ => [51, 51, 56],
        };
        for (b, name, tip) in [
            (
                Background::Environment,
                "environment",
                "The environment seen through the camera (the PNG too)",
            ),
            (
                Background::Transparent,
                "transparent",
                "Nothing: the PNG keeps the hair's coverage as alpha",
            ),
            (
                Background::Colour(colour),
                "colour",
                "A flat colour (exactly this colour in the PNG)",
            ),
        ] {
            let same = std::mem::discriminant(&now) == std::mem::discriminant(&b);
            if ui.selectable_label(same, name).on_hover_text(tip).clicked() && !same {
                r.background = b;
                c.changed = true;
            }
        }
        if let Background::Colour(mut rgb) = now
            && ui
                .color_edit_button_srgb(&mut rgb)
                .on_hover_text("The background colour")
                .changed()
        {
            r.background = Background::Colour(rgb);
            c.changed = true;
            // Dragging in the picker is one undo step.
            c.gesture |= ui.input(|i| i.pointer.any_down());
        }
    });
    ui.horizontal(|ui| {
        ui.label("samples");
        for s in [2u32, 4] {
            if ui
                .selectable_label(r.samples == s, s.to_string())
                .on_hover_text("The head's samples per pixel")
                .clicked()
                && r.samples != s
            {
                r.samples = s;
                c.changed = true;
            }
        }
    });
    ui.horizontal_wrapped(|ui| {
        ui.label("fragments");
        for k in [4u32, 8, 12, 20, 32] {
            if ui
                .selectable_label(r.fragments == k, k.to_string())
                .on_hover_text(
                    "Hair fragments kept and shaded per pixel (translucency and anti-aliasing): \
                     more is closer to all of them and slower",
                )
                .clicked()
                && r.fragments != k
            {
                r.fragments = k;
                c.changed = true;
            }
        }
    });
    if c.changed && r != ctx.session.render {
        ctx.send(AppCommand::Edit {
            edit: Edit::Render(r),
            gesture: c.gesture,
        });
    }
}

fn view(ctx: &PanelContext, ui: &mut egui::Ui) {
    let mut view = ctx.viewport.view();
    ui.horizontal(|ui| {
        ui.label("view");
        for (t, name, tip) in [
            (
                ViewTransform::Filmic,
                "filmic",
                "ACES filmic (Narkowicz's fit), as the PNG previews",
            ),
            (ViewTransform::Standard, "standard", "Clamped sRGB"),
        ] {
            if ui
                .selectable_label(view.transform == t, name)
                .on_hover_text(tip)
                .clicked()
            {
                view.transform = t;
            }
        }
    });
    slider32(
        ui,
        "view exposure",
        &mut view.exposure,
        -6.0..=6.0,
        " EV",
        1,
        0.0,
        "Viewport only: never changes the EXR",
    );
    ui.horizontal_wrapped(|ui| {
        ui.label("show");
        if ui
            .selectable_label(view.solo == Solo::Beauty, "beauty")
            .on_hover_text("All scattering components")
            .clicked()
        {
            view.solo = Solo::Beauty;
        }
        for (k, name) in COMPONENTS.iter().enumerate() {
            if ui
                .selectable_label(view.solo == Solo::Component(k), *name)
                .on_hover_text("This component alone (the EXR's AOV layer of the same name)")
                .clicked()
            {
                view.solo = Solo::Component(k);
            }
        }
    });
    ui.horizontal(|ui| {
        ui.label("resolution");
        for s in [0.25f32, 0.5, 1.0] {
            if ui
                .selectable_label(view.scale == s, format!("{:.0}%", s * 100.0))
                .on_hover_text("Render resolution as a fraction of the viewport's pixels")
                .clicked()
            {
                view.scale = s;
            }
        }
    });
    if view != ctx.viewport.view() {
        ctx.send(AppCommand::SetView(view));
    }
}
