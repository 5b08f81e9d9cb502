//! The live driver on its render thread, driven as the editor drives it (session edits through
//! `sync`, a brush stroke through `dab`): after each change its converged image is, bit for bit, the
//! image `render_frame` makes of the edited session from scratch. And the thread refines by itself:
//! nothing but the change and a kick is needed.

mod common;

use std::sync::atomic::AtomicBool;
use std::time::Duration;
use strandlight::gpu::{GpuContext, GpuOptions};
use strandlight::hair::procedural::Style;
use strandlight::live::{Dab, LiveDriver, LiveHandle, ViewSettings};
use strandlight::paint::Brush;
use strandlight::paint::brush::Stroke;
use strandlight::render::{Camera, Frame};
use strandlight::scattering::Preset;
use strandlight::scattering::lut::Luts;
use strandlight::session::{HairSource, Session, ViewCamera};

const SIZE: (u32, u32) = (64, 48);
const TIMEOUT: Duration = Duration::from_secs(300);

fn context() -> GpuContext {
    let ctx = GpuContext::new_headless(&GpuOptions::from_env()).expect("a GPU adapter (lavapipe)");
    println!("adapter: {} ({})", ctx.summary.name, ctx.summary.backend);
    ctx
}

/// A 400-strand bob on the generated head with a coarse volume and shadow grid.
fn small_session() -> Session {
    let mut s = Session::neutral(HairSource::generated(Style::Bob, 400, 10, 3));
    s.render.volume_resolution = 48;
    s.render.shadow_grid_resolution = 16;
    s
}

fn open(ctx: &GpuContext, luts: &Luts, session: &Session) -> LiveDriver {
    let (driver, warnings) =
        strandlight::live::load::open(ctx.clone(), luts, session, SIZE, &AtomicBool::new(false))
            .expect("the session opens");
    assert!(warnings.is_empty(), "{warnings:?}");
    driver
}

/// `render_frame` of `session` by a driver made for it from scratch (no refinement, no edits).
fn fresh_frame(ctx: &GpuContext, luts: &Luts, session: &Session, camera: &Camera) -> Frame {
    let mut d = open(ctx, luts, session);
    d.sync(session, camera).expect("sync");
    d.renderer.render_frame(ctx);
    d.renderer.read_frame(ctx).expect("read back")
}

/// Waits until the driver has converged with everything the change needs, and reads its image.
fn converged(ctx: &GpuContext, handle: &LiveHandle) -> Frame {
    assert!(handle.wait_idle(TIMEOUT), "the driver did not converge");
    let mut d = handle.lock();
    assert_eq!(d.take_errors(), Vec::<String>::new());
    assert!(d.clock.converged_in.is_some() && !d.tables_pending());
    d.renderer.read_frame(ctx).expect("read back")
}

/// The largest difference between two frames' pixels, beauty and components.
fn difference(a: &Frame, b: &Frame) -> f32 {
    let pairs = a
        .beauty
        .iter()
        .zip(&b.beauty)
        .flat_map(|(x, y)| x.iter().zip(y));
    let comps = a
        .components
        .iter()
        .chain([&a.occluder])
        .zip(b.components.iter().chain([&b.occluder]))
        .flat_map(|(ca, cb)| ca.iter().zip(cb).flat_map(|(x, y)| x.iter().zip(y)));
    pairs
        .chain(comps)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

fn lit(f: &Frame) -> bool {
    f.beauty.iter().any(|p| p[3] > 0.0 && p[0] > 0.0)
}

#[test]
fn the_driver_converges_to_render_frame_after_a_look_an_eta_a_camera_and_a_stroke() {
    let ctx = context();
    let luts = Luts::default_tables();
    let mut session = small_session();
    let mut driver = open(&ctx, &luts, &session);
    driver.set_view(ViewSettings::default());
    let (lo, hi) = driver.bounds;
    let mut camera = session
        .camera
        .resolve(lo, hi, SIZE.0 as f32 / SIZE.1 as f32);
    let handle = LiveHandle::start(driver, || {});
    let check = |what: &str, session: &Session, camera: &Camera| {
        let live = converged(&ctx, &handle);
        let want = fresh_frame(&ctx, &luts, session, camera);
        assert!(lit(&want), "{what}: the frame shows hair");
        let d = difference(&live, &want);
        let units = handle.lock().clock.progress.map_or(0, |p| p.stats.units);
        println!("{what}: converged in {units} units, difference to render_frame {d:.1e}");
        assert_eq!(d, 0.0, "{what}: the live image is render_frame's");
    };
    check("opened", &session, &camera);

    let mut change = |f: &dyn Fn(&mut Session, &mut Camera)| {
        f(&mut session, &mut camera);
        handle.lock().sync(&session, &camera).expect("sync");
        handle.kick();
        (session.clone(), camera)
    };
    let (s, c) = change(&|s, _| s.look.apply_preset(Preset::Blond));
    check("a preset (absorption only)", &s, &c);
    let (s, c) = change(&|s, _| s.look.params.eta = 1.6);
    check("a new eta (its tables built on a worker)", &s, &c);
    let (s, c) = change(&|s, c| {
        c.yaw = 90.0;
        c.pitch = 0.0;
        s.camera = ViewCamera::from_camera(c);
    });
    check("the side view", &s, &c);

    // A stroke across the middle of the hair, as the brush paints it.
    handle.lock().set_picking(true);
    handle.kick();
    assert!(
        handle.wait_for(TIMEOUT, |d| d.picker().is_some()),
        "the picker is built"
    );
    let brush = Brush {
        radius_px: 6.0,
        ..Default::default()
    };
    let mut stroke = Stroke::new();
    let mut painted = 0;
    for k in 0..8 {
        let x = SIZE.0 as f32 * (0.3 + 0.05 * k as f32);
        let dab = handle
            .lock()
            .dab(
                &mut session,
                &mut stroke,
                &brush,
                &[[x, 0.5 * SIZE.1 as f32]],
                6.0,
                1.0,
            )
            .expect("the dab paints");
        handle.kick();
        if let Dab::Painted { points, .. } = dab {
            painted += points;
        }
    }
    assert!(painted > 0, "the stroke painted points");
    {
        let mut d = handle.lock();
        d.end_painting();
        d.paint_finished(&session).expect("the stroke ends");
    }
    handle.kick();
    check("a stroke", &session, &camera);
}

#[test]
fn the_render_thread_refines_with_nothing_but_a_kick() {
    let ctx = context();
    let luts = Luts::default_tables();
    let session = small_session();
    let mut driver = open(&ctx, &luts, &session);
    driver.set_view(ViewSettings::default());
    let handle = LiveHandle::start(driver, || {});
    // Nobody steps the driver: the thread alone refines it to convergence.
    assert!(handle.wait_idle(TIMEOUT), "the driver converged by itself");
    let mut d = handle.lock();
    let stats = d.clock.progress.expect("progress").stats;
    let gaps: Vec<f64> = d
        .renderer
        .take_idle_gaps()
        .into_iter()
        .map(|g| g.as_secs_f64() * 1e3)
        .collect();
    let mut sorted = gaps.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN);
    println!(
        "{} units; idle gap between a unit's completion and the next submission: median {median:.2} ms over {} gaps",
        stats.units,
        gaps.len()
    );
    assert!(stats.units > 1 && !gaps.is_empty());
    assert!(d.first_image_in().is_some() && d.clock.full_image_in.is_some());
}
