//! The editor driven as a user drives it (egui_kittest with its wgpu renderer on lavapipe): the
//! viewport against `strandlight render --session`, panel edits against image statistics, navigation,
//! undo/redo, save/reopen, autosave and recovery, bad files, export. Small scenes, a quarter-resolution
//! viewport and a coarse shadow grid keep each refinement to a few seconds on two cores.

mod common;

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};
use strandlight::editor::{AppCommand, EditorApp, EditorOptions};
use strandlight::hair::procedural::Style;
use strandlight::live::ViewSettings;
use strandlight::render::Frame;
use strandlight::render::refine::WorkUnit;
use strandlight::session::{HairSource, Session};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("strandlight-editor-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d.join(name)
}

/// A bob of 400 strands with a coarse volume and shadow grid.
fn small_session() -> Session {
    let mut s = Session::neutral(HairSource::generated(Style::Bob, 400, 8, 3));
    s.render.volume_resolution = 48;
    s.render.shadow_grid_resolution = 16;
    s
}

fn harness(session: Session, state_dir: &Path, recovery: bool) -> Harness<'static, EditorApp> {
    harness_as(session, state_dir, recovery, None)
}

/// An editor with its own recovery-file name (`instance`: a number no running process has).
fn harness_as(
    session: Session,
    state_dir: &Path,
    recovery: bool,
    instance: Option<u32>,
) -> Harness<'static, EditorApp> {
    std::fs::create_dir_all(state_dir).expect("state dir");
    harness_with(EditorOptions {
        session: Some(session),
        offer_recovery: recovery,
        state_dir: Some(state_dir.to_path_buf()),
        instance,
        ..Default::default()
    })
}

/// An editor started with `options` (the test window's size, a quarter-resolution viewport).
fn harness_with(options: EditorOptions) -> Harness<'static, EditorApp> {
    let mut h = Harness::builder()
        .with_size(egui::vec2(1100.0, 640.0))
        .wgpu_setup(strandlight::editor::wgpu_setup())
        .build_eframe(move |cc| EditorApp::new(cc, options));
    let view = ViewSettings {
        scale: 0.25,
        ..h.state().view()
    };
    h.state_mut().handle(AppCommand::SetView(view));
    h
}

/// Steps the UI until the export under way is written.
fn wait_for_export(h: &mut Harness<'static, EditorApp>) {
    let t = Instant::now();
    while h.state().exporting() {
        h.step();
        std::thread::sleep(Duration::from_millis(2));
        assert!(t.elapsed() < Duration::from_secs(300), "the export hangs");
    }
}

/// Runs the strandlight binary with `args`, which must succeed.
fn run_cli(args: &[&std::ffi::OsStr]) {
    let out = Command::new(env!("CARGO_BIN_EXE_strandlight"))
        .args(args)
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Steps the UI until the viewport has converged (the GPU works between steps).
fn converge(h: &mut Harness<'static, EditorApp>) {
    let t = Instant::now();
    loop {
        h.step();
        if h.state().converged().is_some() && !h.state().loading_scene() {
            // One more frame: the display pass of the last unit.
            h.step();
            // The editor shows GPU validation errors instead of panicking: none may have happened.
            assert!(
                !h.state()
                    .messages()
                    .iter()
                    .any(|m| m.text.starts_with("GPU error")),
                "a GPU error"
            );
            return;
        }
        assert!(
            t.elapsed() < Duration::from_secs(300),
            "the viewport did not converge in 300 s"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// When the viewport's current refinement started (the last change).
fn refine_started(h: &Harness<'static, EditorApp>) -> Instant {
    h.state()
        .live()
        .expect("a scene")
        .lock()
        .clock
        .refine_started
}

/// The viewport's converged image, read back from the renderer.
fn image(h: &Harness<'static, EditorApp>) -> Frame {
    let live = h.state().live().expect("a live scene").lock();
    live.renderer.read_frame(&live.ctx).expect("read back")
}

/// Mean luminance of the hair: the beauty less the head's radiance, over the hair's coverage.
fn mean_luminance(f: &Frame) -> f64 {
    let (mut sum, mut cover) = (0.0, 0.0);
    for (i, p) in f.beauty.iter().enumerate() {
        let head = f.occluder.get(i).copied().unwrap_or([0.0; 3]);
        let hair: [f64; 3] = std::array::from_fn(|c| (p[c] - head[c]) as f64);
        sum += 0.2126 * hair[0] + 0.7152 * hair[1] + 0.0722 * hair[2];
        cover += f.hair_alpha(i) as f64;
    }
    sum / cover.max(1e-9)
}

fn max_relative_difference(a: &Frame, b: &Frame) -> f32 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let peak = a
        .beauty
        .iter()
        .flat_map(|p| p[..3].iter().copied())
        .fold(1e-6f32, f32::max);
    a.beauty
        .iter()
        .zip(&b.beauty)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f32::max)
        / peak
}

/// The slider (not its number field) labelled `label`.
fn slider<'h>(h: &'h Harness<'static, EditorApp>, label: &'h str) -> egui_kittest::Node<'h> {
    h.get_by_role_and_label(egui::accesskit::Role::Slider, label)
}

fn mean_relative_difference(a: &Frame, b: &Frame) -> f32 {
    let peak = a
        .beauty
        .iter()
        .flat_map(|p| p[..3].iter().copied())
        .fold(1e-6f32, f32::max);
    let sum: f32 = a
        .beauty
        .iter()
        .zip(&b.beauty)
        .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs()))
        .sum();
    sum / (4.0 * a.beauty.len() as f32) / peak
}

fn click(h: &mut Harness<'static, EditorApp>, label: &str) {
    h.get_by_label(label).click();
    h.step();
}

#[test]
fn refinement_proceeds_without_ui_frames_and_converges() {
    let dir = tmp("no-frames");
    let mut h = harness(small_session(), &dir.join("state"), false);
    // UI frames until the loaded scene is installed (a frame takes the load job's result), and
    // one more that tells the driver the viewport's size and camera.
    let t = Instant::now();
    while h.state().live().is_none() {
        h.step();
        std::thread::sleep(Duration::from_millis(5));
        assert!(t.elapsed() < Duration::from_secs(300), "the scene loads");
    }
    h.step();
    // From here no UI frame runs: the render thread alone refines the image.
    let frames = h.state().frames_measured();
    let live = h.state().live().expect("a scene");
    assert!(
        live.handle().wait_idle(Duration::from_secs(300)),
        "the viewport converged without UI frames"
    );
    let (units, shown) = {
        let d = live.lock();
        let p = d.clock.progress.expect("progress");
        assert!(p.converged && d.clock.converged_in.is_some() && !d.tables_pending());
        (
            p.stats.units,
            d.first_image_in().is_some() && d.clock.full_image_in.is_some(),
        )
    };
    assert_eq!(h.state().frames_measured(), frames, "no UI frame ran");
    println!("converged in {units} units with no UI frame");
    assert!(shown && units > 1);
    // The next frame shows it converged.
    h.step();
    assert!(h.state().converged().is_some());
}

#[test]
fn the_viewport_equals_render_session_and_the_status_bar_names_the_adapter() {
    let dir = tmp("equal");
    let mut h = harness(small_session(), &dir, false);
    converge(&mut h);
    let adapter = h.state().gpu().expect("a GPU").summary.name.clone();
    assert!(
        h.query_by_label_contains(&adapter).is_some(),
        "the status bar names {adapter}"
    );
    // The window changes size (the render follows the viewport), then one orbit makes the camera
    // explicit; the session is saved at the viewport's render size.
    let before = image(&h);
    h.set_size(egui::vec2(1000.0, 600.0));
    h.step();
    converge(&mut h);
    assert_ne!(
        (before.width, before.height),
        (image(&h).width, image(&h).height)
    );
    let centre = h.state().viewport_rect().expect("a viewport").center();
    middle_drag(&mut h, centre, egui::vec2(30.0, 0.0), egui::Modifiers::NONE);
    converge(&mut h);
    let viewport = image(&h);
    let d = against_render_session(&h, &dir, "equal", &viewport);
    println!(
        "viewport {}x{} against render --session: max difference {d:.2e} of the peak",
        viewport.width, viewport.height
    );
    assert!(d < 1e-4, "{d}");
}

/// `strandlight render --session` of `session` (saved as `dir/name.slsession`) at its render size:
/// the EXR's beauty.
/// The largest difference (of the peak) between the viewport's image `got` and `render --session` of
/// the editor's session at that image's size.
fn against_render_session(
    h: &Harness<'static, EditorApp>,
    dir: &Path,
    name: &str,
    got: &Frame,
) -> f32 {
    let mut session = h.state().session().clone();
    session.render.width = got.width;
    session.render.height = got.height;
    max_relative_difference(got, &render_session(dir, name, &session))
}

fn render_session(dir: &Path, name: &str, session: &Session) -> Frame {
    let path = dir.join(format!("{name}.slsession"));
    session.write(&path).expect("saved");
    let exr = dir.join(format!("{name}.exr"));
    run_cli(&[
        "render".as_ref(),
        "--session".as_ref(),
        path.as_os_str(),
        "-o".as_ref(),
        exr.as_os_str(),
    ]);
    read_exr_beauty(&exr, session.render.width, session.render.height)
}

/// RGBA of an EXR as a frame's beauty.
fn read_exr_beauty(path: &Path, width: u32, height: u32) -> Frame {
    let c = common::read_exr_channels(path, &["R", "G", "B", "A"]);
    Frame {
        width,
        height,
        samples: 4,
        beauty: (0..c[0].len())
            .map(|i| [c[0][i], c[1][i], c[2][i], c[3][i]])
            .collect(),
        depth: Vec::new(),
        sample_ids: Vec::new(),
        fragments: Vec::new(),
        fragments_per_pixel: 0,
        pixel_fragments: Vec::new(),
        components: Vec::new(),
        background: Vec::new(),
        occluder: Vec::new(),
    }
}

fn middle_drag(
    h: &mut Harness<'static, EditorApp>,
    from: egui::Pos2,
    by: egui::Vec2,
    modifiers: egui::Modifiers,
) {
    h.event(egui::Event::ModifiersChanged(modifiers));
    h.hover_at(from);
    h.step();
    h.event(egui::Event::PointerButton {
        pos: from,
        button: egui::PointerButton::Middle,
        pressed: true,
        modifiers,
    });
    h.step();
    for k in 1..=4 {
        h.event(egui::Event::PointerMoved(from + by * (k as f32 / 4.0)));
        h.step();
    }
    h.event(egui::Event::PointerButton {
        pos: from + by,
        button: egui::PointerButton::Middle,
        pressed: false,
        modifiers,
    });
    h.step();
    h.event(egui::Event::ModifiersChanged(egui::Modifiers::NONE));
    h.step();
}

/// Steps until the full image's first pass of the refinement that started after `before`, counting
/// the volume and shadow-grid units submitted meanwhile; the preview, when there is one, comes first.
fn rebuilds_before_first_image(
    h: &mut Harness<'static, EditorApp>,
    before: Instant,
    what: &str,
) -> usize {
    let (mut rebuilds, t) = (0, Instant::now());
    loop {
        h.step();
        let live = h.state().live().expect("a scene").lock();
        // A rebuild submitted in the step that showed the full image came after it.
        if live.clock.refine_started > before
            && let Some(full) = live.clock.full_image_in
        {
            let first = live.first_image_in().unwrap_or(full);
            println!(
                "{what}: first image (preview) after {:.2} s, full image after {:.2} s",
                first.as_secs_f64(),
                full.as_secs_f64()
            );
            assert!(first <= full);
            return rebuilds;
        }
        if matches!(
            live.clock.progress.and_then(|p| p.submitted),
            Some(
                WorkUnit::ShadowGrid { .. }
                    | WorkUnit::GridSamples { .. }
                    | WorkUnit::Volume { .. }
                    | WorkUnit::VolumeResolve { .. }
                    | WorkUnit::DensityPyramid
            )
        ) {
            rebuilds += 1;
        }
        assert!(
            t.elapsed() < Duration::from_secs(120),
            "{what}: no first image"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn panel_edits_change_the_image_and_three_undos_restore_it() {
    let dir = tmp("edits");
    let mut h = harness(small_session(), &dir, false);
    converge(&mut h);
    let before_session = h.state().session().clone();
    let before = image(&h);
    let brown = mean_luminance(&before);

    // Raising sigma_a (the dark-brown preset) darkens the hair; blond lightens it. The new absorption
    // is shaded before the volume and shadow grid are rebuilt for it (single scattering reads only the
    // grid's transmittance, which absorption does not change).
    let started = refine_started(&h);
    click(&mut h, "dark brown");
    let rebuilt = rebuilds_before_first_image(&mut h, started, "dark brown");
    assert_eq!(rebuilt, 0, "the first image waited for the volume");
    converge(&mut h);
    let dark = mean_luminance(&image(&h));
    click(&mut h, "blond");
    converge(&mut h);
    let blond = mean_luminance(&image(&h));
    println!("mean luminance: dark brown {dark:.4}, brown {brown:.4}, blond {blond:.4}");
    assert!(dark < 0.8 * brown && blond > 1.5 * brown);

    // The environment's yaw changes the image without a refit (no job starts).
    slider(&h, "yaw").set_value_accesskit(90.0);
    h.step();
    assert!(!h.state().loading(), "yaw must not refit");
    converge(&mut h);
    let turned = image(&h);
    let yawed = mean_luminance(&turned);
    println!("yaw 90: {yawed:.4}");
    assert!((yawed - blond).abs() > 1e-3 * blond);
    assert_eq!(h.state().session().env_yaw, 90.0);

    // Three edits (dark brown, blond, yaw), three Ctrl+Z: the session and the image as before.
    for _ in 0..3 {
        h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
        h.step();
    }
    assert_eq!(*h.state().session(), before_session);
    converge(&mut h);
    let restored = image(&h);
    let d = max_relative_difference(&before, &restored);
    println!("after three undos: max difference {d:.2e} of the peak");
    assert!(d < 1e-5);
    // Redo reapplies them.
    for _ in 0..3 {
        h.key_press_modifiers(
            egui::Modifiers::COMMAND | egui::Modifiers::SHIFT,
            egui::Key::Z,
        );
        h.step();
    }
    assert_eq!(h.state().session().env_yaw, 90.0);
    assert_eq!(
        h.state().session().look.root,
        strandlight::session::Absorption::from_preset(strandlight::scattering::Preset::Blond)
    );
}

#[test]
fn a_narrower_highlight_is_sharper() {
    let dir = tmp("beta");
    let mut h = harness(small_session(), &dir, false);
    converge(&mut h);
    let r_peak = |f: &Frame| -> f32 {
        // The 99.9th percentile of the R lobe's luminance over covered pixels (a pixel mixes several
        // fibres: their highlights only line up in a few).
        let mut v: Vec<f32> = f.components[0]
            .iter()
            .zip(&f.beauty)
            .filter(|(_, b)| b[3] > 0.5)
            .map(|(c, _)| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2])
            .collect();
        v.sort_by(f32::total_cmp);
        v[(v.len() * 999) / 1000]
    };
    let wide = r_peak(&image(&h));
    let before = refine_started(&h);
    slider(&h, "β_R width").set_value_accesskit(3.0);
    // The new look shows before the shadow grid is rebuilt for the new tables (with dual scattering
    // their forward terms need it): the first image is shaded with the grid already built, and the
    // multiple scattering follows.
    let rebuilt = rebuilds_before_first_image(&mut h, before, "beta_R 7.5 -> 3 deg");
    assert_eq!(rebuilt, 0, "the first image waited for the shadow grid");
    converge(&mut h);
    let narrow = r_peak(&image(&h));
    println!("R lobe p99.9: beta_R 7.5 deg {wide:.4}, 3 deg {narrow:.4}");
    assert!((h.state().session().look.params.beta_r.to_degrees() - 3.0).abs() < 1e-9);
    assert!(narrow > 1.3 * wide);
}

/// The fibre thickness slider: thicker fibres shadow each other more (the hair darkens), the image
/// equals a headless render of the same session, and undo restores the thickness.
#[test]
fn thicker_fibres_darken_the_hair_as_a_headless_render_does() {
    let dir = tmp("thickness");
    let mut h = harness(small_session(), &dir, false);
    converge(&mut h);
    let thin = mean_luminance(&image(&h));
    slider(&h, "thickness").set_value_accesskit(3.0);
    h.step();
    converge(&mut h);
    let got = image(&h);
    let thick = mean_luminance(&got);
    println!("mean luminance: thickness x1 {thin:.4}, x3 {thick:.4}");
    assert_eq!(h.state().session().look.thickness_scale, 3.0);
    assert!(thick < thin, "thicker fibres shadow more");
    // The same session rendered headless (the scene assembly scales the hair itself; the editor
    // rewrote the renderer's points).
    let d = against_render_session(&h, &dir, "thick", &got);
    println!("editor against render --session: max difference {d:.2e} of the peak");
    assert!(d < 1e-4, "{d}");
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.step();
    assert_eq!(h.state().session().look.thickness_scale, 1.0);
    converge(&mut h);
    assert_eq!(
        mean_luminance(&image(&h)),
        thin,
        "undo restores the fibres' diameters"
    );
}

/// An eta change: the viewport keeps the old index until the new one's azimuthal table is ready (no
/// frame reads a table made for another index), shows it first with the table's draft (built at once,
/// about a twelfth of the build), then converges with the tables to what a headless render of the
/// session makes.
#[test]
fn a_new_eta_shows_with_a_draft_and_converges_to_the_render() {
    let dir = tmp("eta");
    let mut h = harness(small_session(), &dir, false);
    converge(&mut h);
    let before = mean_luminance(&image(&h));
    let t = Instant::now();
    slider(&h, "η").set_value_accesskit(1.62);
    let (mut draft_in, mut table_in) = (None, None);
    while table_in.is_none() {
        h.step();
        let live = h.state().live().expect("a scene").lock();
        let table = live.renderer.azimuthal_table();
        if table.eta == 1.62 {
            if table.draft {
                draft_in.get_or_insert(t.elapsed());
            } else {
                table_in = Some(t.elapsed());
            }
        }
        assert!(
            t.elapsed() < Duration::from_secs(60),
            "no table for the new eta"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    let draft_in = draft_in.expect("the new eta showed with a draft first");
    println!(
        "eta 1.55 -> 1.62: draft in the renderer after {:.2} s, the table after {:.2} s",
        draft_in.as_secs_f64(),
        table_in.map_or(0.0, |d| d.as_secs_f64())
    );
    converge(&mut h);
    let got = image(&h);
    assert_eq!(h.state().session().look.params.eta, 1.62);
    let d = against_render_session(&h, &dir, "eta", &got);
    println!(
        "editor against render --session: max difference {d:.2e} of the peak; mean luminance {before:.4} -> {:.4}",
        mean_luminance(&got)
    );
    assert!(d < 1e-4, "{d}");
}

/// Pixels of `f` showing the head (any of their samples).
fn head_pixels(f: &Frame) -> usize {
    f.sample_ids
        .iter()
        .filter(|ids| {
            ids.iter()
                .any(|&id| strandlight::render::passes::occluder::occluder_triangle(id).is_some())
        })
        .count()
}

#[test]
fn the_head_and_the_environment_show_and_the_panel_changes_them() {
    let dir = tmp("head");
    let mut h = harness(small_session(), &dir, false);
    converge(&mut h);
    // By default: the generated head under the bob, the environment behind both.
    let with_head = image(&h);
    let shown = head_pixels(&with_head);
    let behind = with_head
        .background
        .iter()
        .filter(|b| b.iter().any(|&v| v > 0.0))
        .count();
    println!(
        "{shown} of {} pixels show the head, {behind} have the environment behind",
        with_head.pixel_count()
    );
    assert!(shown > 50 && behind == with_head.pixel_count());
    // The head hidden: no head pixels, and the hair it hid shows.
    click(&mut h, "Head");
    assert!(!h.state().session().occluder.show);
    converge(&mut h);
    let without = image(&h);
    assert_eq!(head_pixels(&without), 0);
    let hair = |f: &Frame| {
        (0..f.pixel_count())
            .filter(|&i| f.hair_alpha(i) > 0.0)
            .count()
    };
    println!(
        "hair pixels: {} with the head, {} without",
        hair(&with_head),
        hair(&without)
    );
    assert!(
        hair(&without) > hair(&with_head),
        "the head hid hair behind it"
    );
    // Undo brings it back as it was.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.step();
    assert!(h.state().session().occluder.show);
    converge(&mut h);
    assert_eq!(
        image(&h).beauty,
        with_head.beauty,
        "undo restores the head exactly"
    );
    // A transparent background: the renderer looks nothing up behind the hair.
    // The render settings lie below the fold of the scene panel: clicked through accesskit.
    h.get_by_label("transparent").click_accesskit();
    h.step();
    assert_eq!(
        h.state().session().render.background,
        strandlight::render::passes::background::Background::Transparent
    );
    converge(&mut h);
    assert!(image(&h).background.is_empty());
}

#[test]
fn navigation_orbits_zooms_and_frames() {
    let dir = tmp("nav");
    let mut h = harness(small_session(), &dir, false);
    converge(&mut h);
    let start = h.state().camera().expect("a camera");
    let centre = h.state().viewport_rect().expect("a viewport").center();
    middle_drag(
        &mut h,
        centre,
        egui::vec2(50.0, 20.0),
        egui::Modifiers::NONE,
    );
    let orbited = h.state().camera().expect("a camera");
    println!(
        "orbit: yaw {} -> {}, pitch {} -> {}",
        start.yaw, orbited.yaw, start.pitch, orbited.pitch
    );
    assert!(orbited.yaw != start.yaw && orbited.pitch != start.pitch);
    assert!((orbited.distance - start.distance).abs() < 1e-4);
    assert_eq!(h.state().session().camera.yaw, orbited.yaw);
    // Shift+middle pans: the target moves, the distance stays.
    middle_drag(
        &mut h,
        centre,
        egui::vec2(40.0, 0.0),
        egui::Modifiers::SHIFT,
    );
    let panned = h.state().camera().expect("a camera");
    assert!(panned.target != orbited.target);
    // The wheel zooms in.
    h.hover_at(centre);
    for _ in 0..6 {
        h.event(egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: egui::vec2(0.0, 40.0),
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Wheel,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
    }
    let zoomed = h.state().camera().expect("a camera");
    println!("zoom: distance {} -> {}", panned.distance, zoomed.distance);
    assert!(zoomed.distance < 0.9 * panned.distance);
    // Home frames the hair again: the target is the hair's centre.
    h.hover_at(centre);
    h.key_press(egui::Key::Home);
    h.step();
    let framed = h.state().camera().expect("a camera");
    let hair = h.state().live().expect("live").lock().hair.clone();
    let (lo, hi) = hair.bounds();
    let mid = 0.5 * (lo + hi);
    assert!((glam::Vec3::from(framed.target) - mid).length() < 1e-4);
    assert!(h.state().session().camera.target.is_none());
    // Camera moves are not edits.
    assert!(!h.state().history().can_undo());

    // A slow orbit (a move per UI frame) shows previews while the button is held: each move waits
    // for the preview under way instead of restarting it.
    converge(&mut h);
    let shown = h.state().live().expect("live").lock().shown.previews_shown;
    h.hover_at(centre);
    h.step();
    h.event(egui::Event::PointerButton {
        pos: centre,
        button: egui::PointerButton::Middle,
        pressed: true,
        modifiers: egui::Modifiers::NONE,
    });
    h.step();
    for k in 1..=60 {
        h.event(egui::Event::PointerMoved(
            centre + egui::vec2(k as f32, 0.0),
        ));
        h.step();
        std::thread::sleep(Duration::from_millis(10));
    }
    let during = h.state().live().expect("live").lock().shown.previews_shown - shown;
    h.event(egui::Event::PointerButton {
        pos: centre + egui::vec2(60.0, 0.0),
        button: egui::PointerButton::Middle,
        pressed: false,
        modifiers: egui::Modifiers::NONE,
    });
    h.step();
    let live = h.state().live().expect("live").lock();
    println!(
        "previews shown during a 60-frame orbit: {during} ({}x{}, preview divisor {})",
        live.display.width,
        live.display.height,
        live.renderer.preview_factor()
    );
    assert!(during >= 2, "the viewport froze during the orbit");
    drop(live);
    converge(&mut h);
}

#[test]
fn sessions_save_reopen_autosave_and_recover() {
    let dir = tmp("sessions");
    // Process ids stop below 2^22 on Linux: these name editors that are not running.
    let mut h = harness_as(small_session(), &dir, false, Some(4_000_000_001));
    converge(&mut h);
    click(&mut h, "auburn");
    converge(&mut h);
    let first = image(&h);
    let path = dir.join("look.slsession");
    h.state_mut().save_session(&path);
    assert!(!h.state().modified());
    let saved = h.state().session().clone();

    // Reopen in a new editor: same model, equal image.
    let mut h2 = harness(Session::default(), &dir.join("other"), false);
    h2.state_mut().open_session(&path);
    converge(&mut h2);
    assert_eq!(*h2.state().session(), saved);
    // The same viewport size and camera: the same image.
    let d = max_relative_difference(&first, &image(&h2));
    println!("reopened: max difference {d:.2e} of the peak");
    assert!(d < 1e-4);
    drop(h2);

    // A change produces the autosave file (the interval shortened for the test).
    h.state_mut().autosave_mut().interval = Duration::from_millis(10);
    click(&mut h, "platinum");
    let recovery = h.state().autosave().path.clone();
    let t = Instant::now();
    while h.state().autosave().writes == 0 {
        h.step();
        std::thread::sleep(Duration::from_millis(5));
        assert!(t.elapsed() < Duration::from_secs(20), "no autosave");
    }
    assert!(recovery.is_file());
    let changed = h.state().session().clone();
    // "Kill" the editor: no on_exit.
    std::mem::forget(h);

    // The next start offers the recovery, which restores the model.
    let mut h3 = harness_as(Session::default(), &dir, true, Some(4_000_000_002));
    h3.step();
    assert!(h3.state().recovery_offered());
    click(&mut h3, "Recover");
    assert_eq!(h3.state().session().look, changed.look);
    assert_eq!(h3.state().session_path(), Some(path.as_path()));
    // The recovered work is now the new editor's own recovery file; the old one is gone.
    assert!(!recovery.exists() && h3.state().autosave().path.is_file());
    drop(h3);

    // A recovery file of an editor that is still running (this process) is not offered.
    let dir2 = dir.join("alive");
    std::fs::create_dir_all(&dir2).expect("dir");
    std::fs::copy(
        dir.join("recovery-4000000002.slsession"),
        dir2.join(format!("recovery-{}.slsession", std::process::id())),
    )
    .expect("copied");
    let h4 = harness_as(Session::default(), &dir2, true, Some(4_000_000_003));
    assert!(!h4.state().recovery_offered());
}

#[test]
fn corrupt_files_show_an_error_and_leave_the_scene() {
    let dir = tmp("corrupt");
    let mut h = harness(small_session(), &dir, false);
    converge(&mut h);
    let before = h.state().session().clone();
    let bad_hair = dir.join("broken.hair");
    std::fs::write(&bad_hair, b"HAIR\x01\x00\x00\x00garbage").expect("written");
    h.state_mut().open_hair(bad_hair.clone());
    wait_for_loading(&mut h);
    let msg = h.state().messages().last().expect("a message").text.clone();
    println!("{msg}");
    assert!(msg.contains("broken.hair"));
    assert_eq!(*h.state().session(), before);
    assert!(h.query_by_label_contains("broken.hair").is_some());

    let bad_env = dir.join("broken.exr");
    std::fs::write(&bad_env, b"not an exr at all").expect("written");
    h.state_mut().load_environment(bad_env, 8);
    wait_for_loading(&mut h);
    let msg = h.state().messages().last().expect("a message").text.clone();
    println!("{msg}");
    assert!(msg.contains("broken.exr"));
    assert_eq!(*h.state().session(), before);
    assert!(h.state().live().is_some());

    // A session whose hair file has gone opens the rest, says so, and keeps pointing at the file.
    let mut gone = before.clone();
    gone.hair = HairSource::File {
        path: dir.join("moved-away.hair"),
        blake3: None,
        prim: None,
        time: None,
    };
    gone.env_yaw = 45.0;
    let path = dir.join("gone.slsession");
    gone.write(&path).expect("saved");
    h.state_mut().open_session(&path);
    converge(&mut h);
    let warned = h
        .state()
        .messages()
        .iter()
        .any(|m| m.text.contains("moved-away.hair"));
    assert!(warned, "the missing file is reported");
    assert_eq!(*h.state().session(), gone);
}

fn wait_for_loading(h: &mut Harness<'static, EditorApp>) {
    let t = Instant::now();
    while h.state().loading() {
        h.step();
        std::thread::sleep(Duration::from_millis(5));
        assert!(t.elapsed() < Duration::from_secs(60), "loading hangs");
    }
}

#[test]
fn export_equals_render_session_and_the_screenshot_is_made() {
    let dir = tmp("export");
    let mut session = small_session();
    session.render.width = 96;
    session.render.height = 64;
    // A finer shadow grid than the other tests' (the screenshot shows the hair's shadow on the face).
    session.render.shadow_grid_resolution = 32;
    let mut h = harness(session, &dir, false);
    converge(&mut h);
    let exr = dir.join("export.exr");
    h.state_mut().handle(AppCommand::ExportStill {
        exr: exr.clone(),
        tile: None,
    });
    wait_for_export(&mut h);
    assert!(exr.is_file() && exr.with_extension("png").is_file());
    let path = dir.join("export.slsession");
    h.state().session().write(&path).expect("saved");
    let cli_exr = dir.join("cli.exr");
    run_cli(&[
        "render".as_ref(),
        "--session".as_ref(),
        path.as_os_str(),
        "-o".as_ref(),
        cli_exr.as_os_str(),
    ]);
    let (a, b) = (
        read_exr_beauty(&exr, 96, 64),
        read_exr_beauty(&cli_exr, 96, 64),
    );
    let d = max_relative_difference(&a, &b);
    println!("export against render --session: max difference {d:.2e} of the peak");
    assert!(d < 1e-4);

    // The same still exported in 40-pixel tiles (3 x 2, with partial tiles at the edges).
    let tiled = dir.join("tiled.exr");
    h.state_mut().handle(AppCommand::ExportStill {
        exr: tiled.clone(),
        tile: Some(40),
    });
    wait_for_export(&mut h);
    let c = read_exr_beauty(&tiled, 96, 64);
    let (d, mean) = (
        max_relative_difference(&a, &c),
        mean_relative_difference(&a, &c),
    );
    println!("tiled (40 px) against untiled export: max {d:.2e}, mean {mean:.2e} of the peak");
    assert!(mean < 1e-4, "{d} {mean}");
}

/// The default scene as a user first sees it, in the default window: it converges, the status bar
/// shows its times and scale, and the screenshot is the README's (docs/editor.png).
#[test]
fn the_default_scene_in_the_default_window() {
    let dir = tmp("default-scene");
    std::fs::create_dir_all(&dir).expect("state dir");
    let options = EditorOptions {
        session: Some(Session::default()),
        state_dir: Some(dir),
        ..Default::default()
    };
    let mut h = Harness::builder()
        .with_size(egui::vec2(1280.0, 800.0))
        .wgpu_setup(strandlight::editor::wgpu_setup())
        .build_eframe(move |cc| EditorApp::new(cc, options));
    let software = h.state().gpu().expect("a GPU").summary.device_type == "Cpu";
    assert_eq!(h.state().view().scale, if software { 0.5 } else { 1.0 });
    converge(&mut h);
    // The status bar's times of the launch (each query panics when no label matches).
    h.get_by_label_contains("first ");
    h.get_by_label_contains("sharp ");
    h.get_by_label_contains("converged ");
    h.get_by_label_contains(if software { "(50 %)" } else { "(100 %)" });
    let shot = h.render().expect("a screenshot");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("editor.png");
    shot.save(&out).expect("saved");
    println!("screenshot: {}", out.display());
    let lum: f64 = shot
        .pixels()
        .map(|p| p.0[0] as f64 + p.0[1] as f64 + p.0[2] as f64)
        .sum::<f64>()
        / (3.0 * shot.pixels().len() as f64);
    assert!(lum > 5.0, "the screenshot is black");
}

#[test]
fn a_lost_gpu_device_is_reported_and_the_session_kept() {
    let dir = tmp("lost");
    let mut h = harness(small_session(), &dir, false);
    converge(&mut h);
    click(&mut h, "auburn");
    let device = h.state().gpu().expect("a GPU").device.clone();
    device.destroy();
    let t = Instant::now();
    while h.state().gpu().is_some() {
        // wgpu reports the loss when the device is next polled (the renderer polls every frame).
        let _ = device.poll(wgpu::PollType::Poll);
        h.step();
        std::thread::sleep(Duration::from_millis(5));
        assert!(
            t.elapsed() < Duration::from_secs(20),
            "the loss was not reported"
        );
    }
    let msg = h.state().messages().last().expect("a message").text.clone();
    println!("{msg}");
    assert!(msg.contains("GPU device was lost"));
    assert!(h.state().live().is_none() && h.state().gpu().is_none());
    // The session with the edit is in the recovery file.
    let text = std::fs::read_to_string(&h.state().autosave().path).expect("a recovery file");
    assert!(
        text.contains("0.6") && text.contains("1.2"),
        "auburn's melanin"
    );
    // A new editor takes the session over on a new device (`edit --recover FILE`).
    let args = h.state().relaunch().map(<[_]>::to_vec).expect("a restart");
    assert_eq!(args[0], "edit");
    assert_eq!(args[1], "--recover");
    let file = std::path::PathBuf::from(&args[2]);
    assert_eq!(file, h.state().autosave().path);
    let session = h.state().session().clone();
    drop(h);
    let mut again = harness_with(EditorOptions {
        recover: Some(file.clone()),
        state_dir: Some(dir.clone()),
        instance: Some(4_000_000_002),
        ..Default::default()
    });
    assert!(*again.state().session() == session, "the recovered session");
    assert!(again.state().modified(), "recovered work is unsaved work");
    assert!(!file.exists(), "the old recovery file was taken over");
    assert!(again.state().autosave().path.exists(), "kept in its own");
    converge(&mut again);
    assert!(mean_luminance(&image(&again)) > 0.0, "it renders");
}

/// A left-drag with the brush from `from` to `to` (points) in `steps` moves.
fn brush_stroke(h: &mut Harness<'static, EditorApp>, from: egui::Pos2, to: egui::Pos2, steps: u32) {
    let m = egui::Modifiers::NONE;
    h.hover_at(from);
    h.step();
    h.event(egui::Event::PointerButton {
        pos: from,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: m,
    });
    h.step();
    for k in 1..=steps {
        h.event(egui::Event::PointerMoved(
            from + (to - from) * (k as f32 / steps as f32),
        ));
        h.step();
    }
    h.event(egui::Event::PointerButton {
        pos: to,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: m,
    });
    h.step();
    h.step();
}

/// The hair's mean colour over the pixels `which`: the beauty less the head's radiance, over the
/// hair's coverage.
fn mean_colour(f: &Frame, which: &[usize]) -> [f64; 3] {
    let a: f64 = which.iter().map(|&i| f.hair_alpha(i) as f64).sum();
    let head = |i: usize, c: usize| f.occluder.get(i).map_or(0.0, |o| o[c]);
    std::array::from_fn(|c| {
        which
            .iter()
            .map(|&i| (f.beauty[i][c] - head(i, c)) as f64)
            .sum::<f64>()
            / a.max(1e-12)
    })
}

#[test]
fn a_brush_stroke_dyes_the_hair_under_it_and_undo_redo_are_exact() {
    use strandlight::paint::brush::{Falloff, effective};
    use strandlight::paint::pick::{dabs_along, project};
    let dir = tmp("brush");
    let mut session = small_session();
    session.render.multiple_scattering = false;
    let mut h = harness(session, &dir, false);
    converge(&mut h);
    let before = image(&h);
    let sigma_before = h.state().live().unwrap().lock().sigma_a.clone();
    // B over the viewport takes the brush; the picker follows the view's depth.
    let rect = h.state().viewport_rect().expect("a viewport");
    h.hover_at(rect.center());
    h.step();
    h.key_press(egui::Key::B);
    h.step();
    assert_eq!(h.state().tool(), strandlight::editor::tools::Tool::Brush);
    let t = Instant::now();
    while h.state().live().unwrap().lock().picker().is_none() {
        h.step();
        std::thread::sleep(Duration::from_millis(5));
        assert!(t.elapsed() < Duration::from_secs(30), "no picker");
    }
    // A blue dye at full strength, constant falloff, across the hair's middle.
    let dye = strandlight::paint::sigma_a_from_colour([0.05, 0.25, 0.8], 0.3).map(|x| x as f32);
    h.state_mut().set_brush(strandlight::paint::Brush {
        radius_px: 40.0,
        strength: 1.0,
        falloff: Falloff::Constant,
        dye,
        ..Default::default()
    });
    let (w, hh) = (before.width as f32, before.height as f32);
    let covered: Vec<usize> = (0..before.beauty.len())
        .filter(|&i| before.beauty[i][3] > 0.0)
        .collect();
    let cx = covered
        .iter()
        .map(|&i| (i % before.width as usize) as f32 + 0.5)
        .sum::<f32>()
        / covered.len() as f32;
    let cy = covered
        .iter()
        .map(|&i| (i / before.width as usize) as f32 + 0.5)
        .sum::<f32>()
        / covered.len() as f32;
    let to_screen =
        |x: f32, y: f32| rect.min + egui::vec2(x / w * rect.width(), y / hh * rect.height());
    let (a, b) = (to_screen(cx - 10.0, cy), to_screen(cx + 10.0, cy));
    brush_stroke(&mut h, a, b, 8);
    let app = h.state();
    let layer = app.session().paint_layer.clone().expect("a paint layer");
    let painted: Vec<u32> = (0..layer.get().points.len() as u32)
        .filter(|&i| layer.get().points[i as usize][3] > 0.0)
        .collect();
    println!(
        "stroke: {} dabs, {} points painted",
        app.brush_stats().dabs,
        painted.len()
    );
    assert!(painted.len() > 10, "the stroke painted the hair");
    // The points painted are the picker's selection for the dabs along the path, at full strength.
    let live = app.live().unwrap().lock();
    let picker = live.picker().expect("picker");
    let radius = app.brush_radius_render_px();
    let to_render = |p: egui::Pos2| {
        [
            (p.x - rect.min.x) / rect.width() * w,
            (p.y - rect.min.y) / rect.height() * hh,
        ]
    };
    let (ra, rb) = (to_render(a), to_render(b));
    let (mut centres, _) = dabs_along(ra, rb, radius * app.brush().spacing, 0.0);
    centres.insert(0, ra);
    let mut want: Vec<u32> = centres
        .iter()
        .flat_map(|c| picker.dab(app.brush(), *c, radius, 1.0))
        .map(|t| t.0)
        .collect();
    want.sort_unstable();
    want.dedup();
    let extra: Vec<_> = painted
        .iter()
        .filter(|i| want.binary_search(i).is_err())
        .collect();
    let missing: Vec<_> = want
        .iter()
        .filter(|i| painted.binary_search(i).is_err())
        .collect();
    println!(
        "{} wanted; painted but not wanted {extra:?}, wanted but not painted {missing:?}",
        want.len()
    );
    assert_eq!(painted, want, "the points of the dabs along the path");
    for &i in &painted {
        let v = layer.get().points[i as usize];
        assert_eq!(v[3], 1.0);
        assert!((0..3).all(|c| (v[c] - dye[c]).abs() < 1e-6));
        let q = project(&picker.view.camera, live.hair.positions[i as usize]).unwrap();
        let (dx, dy) = (rb[0] - ra[0], rb[1] - ra[1]);
        let s = (((q.x - ra[0]) * dx + (q.y - ra[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        let d = ((q.x - ra[0] - s * dx).powi(2) + (q.y - ra[1] - s * dy).powi(2)).sqrt();
        assert!(
            d <= radius + 1e-3,
            "a painted point {d} px from the path (radius {radius})"
        );
    }
    // The renderer has the new absorption at the painted points only.
    let sigma = &live.sigma_a;
    for (i, (s0, s1)) in sigma_before.iter().zip(sigma).enumerate() {
        let p = painted.binary_search(&(i as u32)).is_ok();
        let want = if p {
            effective(live.paint.base_sigma_a[i], layer.get().points[i])
        } else {
            *s0
        };
        assert_eq!(*s1, want, "point {i}");
    }
    drop(live);
    let session_after = h.state().session().clone();
    converge(&mut h);
    let after = image(&h);
    // Pixels showing a painted segment move toward the dye (bluer); the others do not change
    // (single scattering: the shadows' transmittance does not read absorption).
    let hair = h.state().live().unwrap().lock().hair.clone();
    let painted_point = |p: u32| layer.get().points[p as usize][3] > 0.0;
    let segment_start: Vec<u32> = (0..hair.strand_count())
        .flat_map(|s| {
            let r = hair.strand_range(s);
            (r.start as u32..r.end as u32 - 1).collect::<Vec<_>>()
        })
        .collect();
    // Pixels whose colour comes mostly from painted fibres (the hair is translucent: a pixel mixes
    // the fibres of its K-buffer), and pixels with no painted fibre.
    let (mut hit, mut miss) = (Vec::new(), Vec::new());
    for i in 0..after.beauty.len() {
        if after.beauty[i][3] == 0.0 {
            continue;
        }
        let painted: f32 = after
            .kept_fragments(i)
            .iter()
            .filter(|f| {
                let p = segment_start[f.id as usize - 1];
                painted_point(p) || painted_point(p + 1)
            })
            .map(|f| f.weight)
            .sum();
        let share = painted / after.hair_alpha(i).max(1e-9);
        if share >= 0.5 {
            hit.push(i)
        } else if share == 0.0 {
            miss.push(i)
        }
    }
    let (c0, c1) = (mean_colour(&before, &hit), mean_colour(&after, &hit));
    println!("painted pixels {}: rgb {c0:.4?} -> {c1:.4?}", hit.len());
    assert!(
        c1[2] / c1[0] > 1.5 * c0[2] / c0[0],
        "the painted hair turns blue"
    );
    let (b0, b1) = (&before.beauty, &after.beauty);
    let worst = miss
        .iter()
        .flat_map(|&i| (0..4).map(move |c| (b0[i][c] - b1[i][c]).abs()))
        .fold(0.0f32, f32::max);
    let peak = before
        .beauty
        .iter()
        .flat_map(|p| p[..3].iter().copied())
        .fold(1e-6f32, f32::max);
    println!(
        "unpainted pixels {}: largest change {:.2e} of the peak",
        miss.len(),
        worst / peak
    );
    assert!(
        worst / peak < 1e-5,
        "unpainted hair unchanged under single scattering"
    );
    // Undo restores the absorption bit for bit and the image; redo reapplies the stroke.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.step();
    let sigma_now = h.state().live().unwrap().lock().sigma_a.clone();
    assert!(
        sigma_now == sigma_before,
        "undo restores the absorption bit for bit"
    );
    assert!(
        h.state().session().paint_layer.is_none(),
        "the stroke made the layer: its undo removes it"
    );
    converge(&mut h);
    assert!(
        max_relative_difference(&image(&h), &before) < 1e-6,
        "undo restores the image"
    );
    h.key_press_modifiers(
        egui::Modifiers::COMMAND | egui::Modifiers::SHIFT,
        egui::Key::Z,
    );
    h.step();
    assert!(
        *h.state().session() == session_after,
        "redo reapplies the stroke"
    );
    converge(&mut h);
    assert!(
        max_relative_difference(&image(&h), &after) < 1e-6,
        "redo restores the image"
    );
    // With multiple scattering, the unpainted hair changes only through the light the dyed hair
    // passes on: far less than the dyed hair itself.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.step();
    let mut render = h.state().session().render;
    render.multiple_scattering = true;
    h.state_mut()
        .perform(strandlight::session::Edit::Render(render), false);
    converge(&mut h);
    let plain_ms = image(&h);
    // The painted layer again, as an edit (replayed data, as autosave and tests replay them).
    h.state_mut().perform(
        strandlight::session::Edit::PaintLayer(Box::new((Some(layer.clone()), None))),
        false,
    );
    converge(&mut h);
    let painted_ms = image(&h);
    let change = |which: &[usize]| {
        let (a, b) = (
            mean_colour(&plain_ms, which),
            mean_colour(&painted_ms, which),
        );
        (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f64>() / (0..3).map(|c| a[c]).sum::<f64>()
    };
    let (near, far) = (change(&hit), change(&miss));
    println!("multiple scattering: dyed pixels change {near:.4}, the others {far:.5} (relative)");
    assert!(
        far > 0.0 && far < 0.1 * near,
        "the unpainted hair changes a little, through the dyed hair's light"
    );
}

/// The brush on, a stroke across the hair's middle with `brush`; returns the points painted.
fn paint_stroke(h: &mut Harness<'static, EditorApp>, brush: strandlight::paint::Brush) -> usize {
    let rect = h.state().viewport_rect().expect("a viewport");
    h.hover_at(rect.center());
    h.step();
    h.key_press(egui::Key::B);
    h.step();
    let t = Instant::now();
    while h.state().live().unwrap().lock().picker().is_none() {
        h.step();
        std::thread::sleep(Duration::from_millis(5));
        assert!(t.elapsed() < Duration::from_secs(30), "no picker");
    }
    h.state_mut().set_brush(brush);
    let f = image(h);
    let covered: Vec<usize> = (0..f.beauty.len())
        .filter(|&i| f.beauty[i][3] > 0.0)
        .collect();
    let n = covered.len() as f32;
    let cx = covered
        .iter()
        .map(|&i| (i % f.width as usize) as f32 + 0.5)
        .sum::<f32>()
        / n;
    let cy = covered
        .iter()
        .map(|&i| (i / f.width as usize) as f32 + 0.5)
        .sum::<f32>()
        / n;
    let at = |x: f32, y: f32| {
        rect.min
            + egui::vec2(
                x / f.width as f32 * rect.width(),
                y / f.height as f32 * rect.height(),
            )
    };
    brush_stroke(h, at(cx - 10.0, cy), at(cx + 10.0, cy), 8);
    let layer = h.state().session().paint_layer.clone().expect("a layer");
    layer.get().points.iter().filter(|v| v[3] > 0.0).count()
}

#[test]
fn a_painted_session_saves_reopens_renders_headless_and_exports_its_hair() {
    let dir = tmp("painted");
    let mut session = small_session();
    session.render.width = 96;
    session.render.height = 64;
    let mut h = harness(session, &dir, false);
    converge(&mut h);
    let dye = strandlight::paint::sigma_a_from_colour([0.6, 0.05, 0.3], 0.3).map(|x| x as f32);
    let painted = paint_stroke(
        &mut h,
        strandlight::paint::Brush {
            radius_px: 40.0,
            strength: 0.8,
            dye,
            ..Default::default()
        },
    );
    assert!(painted > 10);
    assert!(h.state().modified());
    // Save: the session and its layer beside it; then the saved state is unmodified.
    let path = dir.join("painted.slsession");
    h.state_mut().save_session(&path);
    let layer_file = path.with_extension("slpaint");
    assert!(
        path.is_file() && layer_file.is_file(),
        "session and layer written"
    );
    assert!(!h.state().modified());
    converge(&mut h);
    let edited = image(&h);
    let session = h.state().session().clone();
    // Reopened: the same model (layer included) and the same image.
    let mut again = harness_with(EditorOptions {
        session_path: Some(path.clone()),
        state_dir: Some(dir.clone()),
        instance: Some(4_000_000_003),
        ..Default::default()
    });
    converge(&mut again);
    assert!(
        *again.state().session() == session,
        "the same session, paint included"
    );
    assert!(!again.state().modified());
    let d = max_relative_difference(&image(&again), &edited);
    println!("reopened against edited: {d:.2e}");
    assert!(d < 1e-6);
    // The editor's export equals `render --session --paint` of the saved layer.
    let exr = dir.join("painted.exr");
    again.state_mut().handle(AppCommand::ExportStill {
        exr: exr.clone(),
        tile: None,
    });
    wait_for_export(&mut again);
    let cli = dir.join("painted-cli.exr");
    run_cli(&[
        "render".as_ref(),
        "--session".as_ref(),
        path.as_os_str(),
        "--paint".as_ref(),
        layer_file.as_os_str(),
        "-o".as_ref(),
        cli.as_os_str(),
    ]);
    let (a, b) = (read_exr_beauty(&exr, 96, 64), read_exr_beauty(&cli, 96, 64));
    let d = max_relative_difference(&a, &b);
    println!("export against render --paint: {d:.2e} of the peak");
    assert!(d < 1e-4);
    // The hair for other tools: cyHair with colours (read back), USD curves (parsed by usd-core
    // when it is installed).
    let hair_file = dir.join("painted.hair");
    let usda = dir.join("painted.usda");
    for out_file in [&hair_file, &usda] {
        run_cli(&[
            "export-hair".as_ref(),
            "--session".as_ref(),
            path.as_os_str(),
            "-o".as_ref(),
            out_file.as_os_str(),
        ]);
    }
    let live = again.state().live().unwrap().lock();
    let (points, strands) = (live.hair.point_count(), live.hair.strand_count());
    let bytes = std::fs::read(&hair_file).unwrap();
    let (back, _, _) =
        strandlight::hair::cyhair::read_cyhair(&bytes, &hair_file).expect("re-reads");
    let colours = back.colour.clone().expect("a colour array");
    assert_eq!(
        (back.point_count(), back.strand_count(), colours.len()),
        (points, strands, points)
    );
    // The look is uniform: the unpainted points share one colour, the painted ones differ.
    let base = colours[0];
    let tinted = colours
        .iter()
        .filter(|c| (0..3).any(|k| (c[k] - base[k]).abs() > 0.01 * base[k].max(1e-6)))
        .count();
    println!(".hair: {points} points, {tinted} with the dye's colour");
    assert!(tinted >= painted / 2, "the dye reaches the file's colours");
    let text = std::fs::read_to_string(&usda).unwrap();
    assert!(text.starts_with("#usda 1.0") && text.contains("def BasisCurves"));
    let script = format!(
        "from pxr import Usd, UsdGeom\n\
         s = Usd.Stage.Open({:?})\n\
         c = UsdGeom.BasisCurves(s.GetPrimAtPath('/Groom/hair'))\n\
         n = len(c.GetPointsAttr().Get())\n\
         k = c.GetCurveVertexCountsAttr().Get()\n\
         col = UsdGeom.PrimvarsAPI(c).GetPrimvar('displayColor')\n\
         w = c.GetWidthsAttr().Get()\n\
         print(n, len(k), len(col.Get()), col.GetInterpolation(), len(w))\n",
        usda.display().to_string()
    );
    let Some(mut python) = common::python_with("pxr") else {
        return;
    };
    let o = python.arg("-c").arg(&script).output().unwrap();
    assert!(
        o.status.success(),
        "usd-core rejects the .usda: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let got = String::from_utf8_lossy(&o.stdout).trim().to_string();
    println!("usd-core reads the .usda: {got}");
    assert_eq!(got, format!("{points} {strands} {points} vertex {points}"));
}
