//! `strandlight make-env`: the project's own environments and their fits.

use anyhow::{Context, anyhow};
use clap::Args;
use std::path::PathBuf;
use strandlight::envmap::procedural::{EnvKind, make_env};
use strandlight::envmap::{FitOptions, fit_srbf};

#[derive(Args, Debug)]
pub struct MakeEnvArgs {
    /// Which environments (default: all).
    #[arg(long, value_enum)]
    pub kind: Vec<EnvKind>,
    /// Width in pixels (height is half).
    #[arg(long, default_value_t = 512)]
    pub width: usize,
    /// Output folder.
    #[arg(short, long, default_value = "envmaps")]
    pub output: PathBuf,
    /// Also write tone-mapped PNG previews.
    #[arg(long)]
    pub png: bool,
    /// SRBF lights in each fit.
    #[arg(long, default_value_t = 40)]
    pub lights: usize,
}

pub fn run(args: MakeEnvArgs) -> anyhow::Result<()> {
    if args.width < 16 || !args.width.is_multiple_of(2) || args.width > 8192 {
        return Err(anyhow!(
            "width must be even and in 16..=8192, got {}",
            args.width
        ));
    }
    std::fs::create_dir_all(&args.output)
        .with_context(|| format!("creating {}", args.output.display()))?;
    let kinds = if args.kind.is_empty() {
        EnvKind::ALL.to_vec()
    } else {
        args.kind.clone()
    };
    for kind in kinds {
        let env = make_env(kind, args.width);
        let exr = args.output.join(format!("{}.exr", kind.name()));
        env.write_exr(&exr)?;
        if args.png {
            env.write_png_preview(&args.output.join(format!("{}.png", kind.name())), 1.0)?;
        }
        let mut set = fit_srbf(
            &env,
            &FitOptions {
                lights: args.lights,
                ..Default::default()
            },
            |_| {},
        )
        .map_err(|e| anyhow!(e))?;
        set.source = Some(format!("{}.exr", kind.name()));
        set.source_hash = Some(blake3::hash(&std::fs::read(&exr)?).to_hex().to_string());
        let json = args.output.join(format!("{}.srbf.json", kind.name()));
        set.write(&json)?;
        let s = set.fit.clone().unwrap_or_default();
        eprintln!(
            "{}: {}x{}, {} lights, relative L2 {:.3}, power error {:+.2}%",
            exr.display(),
            env.width,
            env.height,
            set.lights.len(),
            s.relative_l2,
            100.0 * s.power_error[1]
        );
    }
    Ok(())
}
