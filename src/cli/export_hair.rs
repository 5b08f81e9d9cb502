//! `strandlight export-hair --session S -o OUT.usda|OUT.hair`: the session's hair with its look and
//! paint layer as USD curves or cyHair with colours, for other tools.

use anyhow::Context;
use clap::Args;
use std::path::PathBuf;
use strandlight::session::Session;
use strandlight::session::export_hair::export_session_hair;

#[derive(Args, Debug)]
pub struct ExportHairArgs {
    /// The session (.slsession) whose hair, look and paint layer are exported.
    #[arg(long)]
    pub session: PathBuf,
    /// A paint layer (.slpaint) instead of the session's.
    #[arg(long)]
    pub paint: Option<PathBuf>,
    /// Output: .usda (a USD groom in Unreal's convention, which Blender reads too: widths, groom_color,
    /// displayColor, groom_roughness, and the look and absorption to come back exactly) or .hair
    /// (cyHair with colours).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: ExportHairArgs) -> anyhow::Result<()> {
    let mut session = Session::read(&args.session)
        .with_context(|| format!("reading {}", args.session.display()))?;
    if let Some(p) = args.paint {
        session.paint = Some(p);
    }
    strandlight::render::frame::check_output_folders(std::iter::once(args.output.as_path()))?;
    export_session_hair(&session, &args.output).map_err(anyhow::Error::msg)?;
    println!("wrote {}", args.output.display());
    Ok(())
}
