//! Opening a session for the live driver: its hair and environment loaded (a missing or broken
//! source replaced by the default, with a warning: the rest of the session opens and keeps pointing at
//! the file), the renderer's CPU work prepared and the driver built. The editor runs this on a worker;
//! `bench` runs it as it is.

use super::driver::LiveDriver;
use super::prepare::prepare;
use crate::gpu::GpuContext;
use crate::render::passes::background::BackgroundMap;
use crate::scattering::lut::Luts;
use crate::session::Session;
use crate::session::assemble::{load_environment_source, load_hair_source};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A driver for `session` at `width` x `height`, and the warnings of what was replaced on the way.
/// Stops before the renderer is built when `cancelled` is set (a newer load superseded this one).
pub fn open(
    ctx: GpuContext,
    luts: &Luts,
    session: &Session,
    (width, height): (u32, u32),
    cancelled: &AtomicBool,
) -> Result<(LiveDriver, Vec<String>), String> {
    let mut warnings = Vec::new();
    let hair = match load_hair_source(&session.hair) {
        Ok(h) => h,
        Err(e) => {
            warnings.push(format!("{e}; showing the default hairstyle instead"));
            load_hair_source(&Session::default().hair).map_err(|e| e.to_string())?
        }
    };
    let environment = match load_environment_source(&session.environment) {
        Ok((environment, w)) => {
            warnings.extend(w);
            environment
        }
        Err(e) => {
            warnings.push(format!("{e}; lighting with the built-in sky instead"));
            crate::render::scene::default_environment()
        }
    };
    warnings.extend(hair.warning.clone());
    // A failure later still reports what was replaced on the way.
    let failed = |e: String| match warnings.is_empty() {
        true => e,
        false => format!("{e} (also: {})", warnings.join("; ")),
    };
    let prepared = prepare(session, &hair.hair).map_err(|e| failed(e.to_string()))?;
    if cancelled.load(Ordering::Relaxed) {
        return Err("superseded".into());
    }
    let (lo, hi) = hair.hair.bounds();
    let camera = session
        .camera
        .resolve(lo, hi, width as f32 / height.max(1) as f32);
    let background = Arc::new(BackgroundMap::from_environment(&environment));
    let driver = LiveDriver::new(
        ctx,
        luts,
        session,
        hair,
        environment,
        background,
        prepared,
        &camera,
        width,
        height,
    )
    .map_err(|e| failed(e.to_string()))?;
    Ok((driver, warnings))
}
