//! The editor's scenarios inside `bench`: the session opened, edited and painted through the editor's
//! own live driver on its render thread ([`strandlight::live`]), exactly as the editor drives it (no
//! UI: a UI adds its own frames on top). Times are wall clock from the change, as the editor's status
//! bar shows them; `render --session` of the same session at the same size, run as a process, is the
//! yardstick.

use anyhow::{Context, bail};
use serde::Serialize;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};
use strandlight::gpu::GpuContext;
use strandlight::live::{Dab, LiveHandle, ViewSettings};
use strandlight::paint::Brush;
use strandlight::paint::brush::Stroke;
use strandlight::render::Camera;
use strandlight::scattering::Preset;
use strandlight::scattering::lut::Luts;
use strandlight::session::{Session, ViewCamera};

/// How long any one scenario may take before the bench gives up.
const TIMEOUT: Duration = Duration::from_secs(900);

/// The times of one change, milliseconds from it.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Times {
    /// The first image (a preview, or the full image when there is none).
    pub first_ms: Option<f64>,
    /// The full-resolution image with every light at each pixel's front fragment.
    pub sharp_ms: Option<f64>,
    /// Converged, with the tables and the volume the change needs.
    pub converged_ms: f64,
    pub units: u32,
}

#[derive(Serialize)]
pub struct Yardstick {
    /// `render --session` of the same session and size: the whole process, and its frame (the
    /// renderer made and the frame rendered, as it reports).
    pub process_ms: f64,
    pub frame_ms: f64,
}

#[derive(Serialize)]
pub struct DabReport {
    pub dabs: usize,
    pub radius_px: f32,
    /// From the session opened to the picker ready (the brush can paint).
    pub picker_ready_ms: f64,
    /// From a dab to its image (repaint or preview) finished, over the dabs that changed points.
    pub visible_dabs: usize,
    pub visible_ms_median: f64,
    pub visible_ms_max: f64,
    /// After the stroke: converged with the volume and shadow grid following the paint.
    pub stroke_converged_ms: f64,
}

#[derive(Serialize)]
pub struct EditorReport {
    pub size: [u32; 2],
    pub open: Times,
    pub yardstick: Option<Yardstick>,
    /// A look preset clicked (absorption only: no table is built).
    pub preset: Times,
    /// A new eta (its tables built on a worker).
    pub eta: Times,
    /// The side view (numpad 3).
    pub camera: Times,
    /// The gaps between a unit's completion and the next submission while work remained.
    pub idle_gap_ms_median: f64,
    pub idle_gap_ms_p95: f64,
    pub idle_gaps: usize,
    pub brush: Option<DabReport>,
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// The `q`-quantile (0 to 1) of `v` (NaN when empty).
fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Waits for the driver to finish and reads the change's times.
fn settle(handle: &LiveHandle) -> anyhow::Result<Times> {
    if !handle.wait_idle(TIMEOUT) {
        bail!("the live driver did not converge within {TIMEOUT:?}");
    }
    let mut d = handle.lock();
    if let Some(e) = d.take_errors().into_iter().next() {
        bail!("the live driver: {e}");
    }
    Ok(Times {
        first_ms: d.first_image_in().map(ms),
        sharp_ms: d.clock.full_image_in.map(ms),
        converged_ms: d.clock.converged_in.map_or(f64::NAN, ms),
        units: d.clock.progress.map_or(0, |p| p.stats.units),
    })
}

/// Applies `change` to the session and camera as an edit in the editor does, and waits for it.
fn edit(
    handle: &LiveHandle,
    session: &mut Session,
    camera: &mut Camera,
    change: impl FnOnce(&mut Session, &mut Camera),
) -> anyhow::Result<Times> {
    change(session, camera);
    handle.lock().sync(session, camera)?;
    handle.kick();
    settle(handle)
}

/// `render --session` of `session` at its render size, as a process (this binary).
fn yardstick(session: &Session, software: bool, dir: &Path) -> anyhow::Result<Yardstick> {
    let path = dir.join("bench-editor.slsession");
    session.write(&path)?;
    let exe = std::env::current_exe().context("the bench's own executable")?;
    let mut cmd = std::process::Command::new(exe);
    cmd.arg("render")
        .arg("--session")
        .arg(&path)
        .arg("-o")
        .arg(dir.join("bench-editor.exr"));
    if software {
        cmd.arg("--software");
    }
    let t = Instant::now();
    let out = cmd.output().context("running render --session")?;
    let process_ms = ms(t.elapsed());
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        bail!("render --session failed: {stderr}");
    }
    // "rendered WxH (...) in T s (frame F s)"
    let frame_s: f64 = stderr
        .lines()
        .find_map(|l| l.split("(frame ").nth(1))
        .and_then(|rest| rest.split(" s").next())
        .and_then(|v| v.trim().parse().ok())
        .with_context(|| format!("render printed no frame time: {stderr}"))?;
    Ok(Yardstick {
        process_ms,
        frame_ms: frame_s * 1e3,
    })
}

/// Options of the editor scenarios.
pub struct EditorBench {
    pub size: (u32, u32),
    pub dabs: usize,
    pub yardstick: bool,
    pub software: bool,
}

/// Opens `session` on the editor's live driver at `size` and runs the scenarios.
pub fn editor_run(
    ctx: &GpuContext,
    luts: &Luts,
    session: &Session,
    options: &EditorBench,
) -> anyhow::Result<EditorReport> {
    let (w, h) = options.size;
    let mut session = session.clone();
    session.render.width = w;
    session.render.height = h;
    let yardstick = if options.yardstick {
        let dir = std::env::temp_dir().join(format!("strandlight-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let y = yardstick(&session, options.software, &dir);
        let _ = std::fs::remove_dir_all(&dir);
        Some(y?)
    } else {
        None
    };
    let t = Instant::now();
    let (mut driver, warnings) =
        strandlight::live::load::open(ctx.clone(), luts, &session, (w, h), &AtomicBool::new(false))
            .map_err(anyhow::Error::msg)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    driver.count_from(t);
    driver.set_view(ViewSettings::default());
    let (lo, hi) = driver.bounds;
    let mut camera = session.camera.resolve(lo, hi, w as f32 / h.max(1) as f32);
    let handle = LiveHandle::start(driver, || {});
    let open = settle(&handle)?;
    let preset = edit(&handle, &mut session, &mut camera, |s, _| {
        s.look.apply_preset(Preset::Blond)
    })?;
    let eta = edit(&handle, &mut session, &mut camera, |s, _| {
        s.look.params.eta = 1.6
    })?;
    let camera_times = edit(&handle, &mut session, &mut camera, |s, c| {
        c.yaw = 90.0;
        c.pitch = 0.0;
        s.camera = ViewCamera::from_camera(c);
    })?;
    let gaps: Vec<f64> = handle
        .lock()
        .renderer
        .take_idle_gaps()
        .into_iter()
        .map(ms)
        .collect();
    let brush = if options.dabs > 0 {
        Some(stroke(&handle, &mut session, options.dabs)?)
    } else {
        None
    };
    Ok(EditorReport {
        size: [w, h],
        open,
        yardstick,
        preset,
        eta,
        camera: camera_times,
        idle_gap_ms_median: quantile(gaps.clone(), 0.5),
        idle_gap_ms_p95: quantile(gaps.clone(), 0.95),
        idle_gaps: gaps.len(),
        brush,
    })
}

/// One stroke of `dabs` dabs across the hair on screen, each waited for until it shows, as the
/// editor's brush paints it (through [`strandlight::live::LiveDriver::dab`]).
fn stroke(handle: &LiveHandle, session: &mut Session, dabs: usize) -> anyhow::Result<DabReport> {
    let t = Instant::now();
    handle.lock().set_picking(true);
    handle.kick();
    if !handle.wait_for(TIMEOUT, |d| d.picker().is_some()) {
        bail!("the brush's picker was not ready within {TIMEOUT:?}");
    }
    let picker_ready_ms = ms(t.elapsed());
    let picker = handle.lock().picker().context("the picker")?;
    // A horizontal stroke through the middle of the hair on screen, half the image wide.
    let view = &picker.view;
    let width = view.width as usize;
    let covered: Vec<usize> = (0..view.depth.len())
        .filter(|&i| view.depth[i] < 1e9)
        .collect();
    anyhow::ensure!(!covered.is_empty(), "no hair on screen to paint");
    let n = covered.len() as f32;
    let cx = covered
        .iter()
        .map(|&i| (i % width) as f32 + 0.5)
        .sum::<f32>()
        / n;
    let cy = covered
        .iter()
        .map(|&i| (i / width) as f32 + 0.5)
        .sum::<f32>()
        / n;
    let radius = 0.04 * width as f32;
    let brush = Brush {
        radius_px: radius,
        ..Default::default()
    };
    let length = 0.5 * width as f32;
    let mut stroke = Stroke::new();
    let mut visible = Vec::new();
    for k in 0..dabs {
        let x = cx - 0.5 * length + length * k as f32 / dabs.max(2).saturating_sub(1) as f32;
        let t = Instant::now();
        let dab = handle
            .lock()
            .dab(session, &mut stroke, &brush, &[[x, cy]], radius, 1.0)?;
        handle.kick();
        if let Dab::Painted { points, .. } = dab
            && points > 0
        {
            if !handle.wait_for(TIMEOUT, |d| d.first_image_in().is_some()) {
                bail!("a dab did not show within {TIMEOUT:?}");
            }
            visible.push(ms(t.elapsed()));
        }
    }
    let t = Instant::now();
    {
        let mut d = handle.lock();
        d.end_painting();
        d.paint_finished(session)?;
    }
    handle.kick();
    settle(handle)?;
    let stroke_converged_ms = ms(t.elapsed());
    Ok(DabReport {
        dabs,
        radius_px: radius,
        picker_ready_ms,
        visible_dabs: visible.len(),
        visible_ms_max: visible.iter().copied().fold(0.0, f64::max),
        visible_ms_median: quantile(visible, 0.5),
        stroke_converged_ms,
    })
}
