//! `strandlight edit` (and `strandlight` alone): opens the editor on a session, a hair file and an
//! environment, or the default scene.

use clap::Args;
use std::path::PathBuf;
use strandlight::editor::{EditorOptions, run};
use strandlight::session::{EnvironmentSource, HairSource, Session};

#[derive(Args, Debug, Default)]
pub struct EditArgs {
    /// A session file (.slsession) to open.
    pub session: Option<PathBuf>,
    /// Hair file (.hair, .tfx, .gltf, .glb, .usd, .usda, .usdc, .usdz, .abc) instead of the generated default.
    #[arg(long, conflicts_with = "session")]
    pub hair: Option<PathBuf>,
    /// USD or Alembic: the prim or object path whose curves are the hair.
    #[arg(long, requires = "hair")]
    pub hair_prim: Option<String>,
    /// The time sampled curves are read at (USD: a time code; Alembic: seconds).
    #[arg(long, requires = "hair")]
    pub hair_time: Option<f64>,
    /// Environment (.hdr, .exr, .srbf.json) instead of the built-in sunny sky.
    #[arg(long, conflicts_with = "session")]
    pub env: Option<PathBuf>,
    /// SRBF lights fitted to an .hdr / .exr environment.
    #[arg(long, default_value_t = 40)]
    pub lights: usize,
    /// Reopen the work kept in a recovery file (`recovery-*.slsession` in the state folder): its
    /// session, and the session file it belongs to. The editor restarts itself this way after a
    /// lost GPU device.
    #[arg(long, conflicts_with_all = ["session", "hair", "env"])]
    pub recover: Option<PathBuf>,
    /// Print each change's times to stderr as the status bar shows them (first image, sharp image,
    /// converged, and the UI's frames meanwhile).
    #[arg(long)]
    pub log_times: bool,
}

pub fn run_editor(args: EditArgs, launched: std::time::Instant) -> anyhow::Result<()> {
    let mut session = Session::default();
    if let Some(path) = args.hair {
        let blake3 = strandlight::session::assemble::file_blake3(&path).ok();
        session.hair = HairSource::File {
            path,
            blake3,
            prim: args.hair_prim,
            time: args.hair_time,
        };
    }
    if let Some(path) = args.env {
        session.environment = EnvironmentSource::File {
            blake3: strandlight::session::assemble::file_blake3(&path).ok(),
            path,
            lights: args.lights.max(1),
            fitted: None,
        };
    }
    run(EditorOptions {
        session_path: args.session,
        session: Some(session),
        offer_recovery: args.recover.is_none(),
        state_dir: None,
        instance: None,
        recover: args.recover,
        relaunch_on_device_loss: true,
        launched: Some(launched),
        log_times: args.log_times,
    })
}
