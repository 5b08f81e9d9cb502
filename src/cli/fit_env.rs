//! `strandlight fit-env`: an environment to SRBF lights.

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use strandlight::envmap::cache::fit_file;
use strandlight::envmap::{FitOptions, load_env};

#[derive(Args, Debug)]
pub struct FitEnvArgs {
    /// Equirectangular .hdr or .exr.
    pub env: PathBuf,
    /// Number of SRBF lights (1-128).
    #[arg(long, default_value_t = 40)]
    pub lights: usize,
    /// Output light file (.srbf.json); default: next to the environment.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write the reconstruction, of the source's size: linear EXR, or a tone-mapped PNG if the
    /// name ends in .png.
    #[arg(long)]
    pub preview: Option<PathBuf>,
    /// Turn the lights about +Y by this many degrees (no refit).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub yaw: f64,
    /// Width of the map the optimiser works on.
    #[arg(long, default_value_t = 128)]
    pub fit_width: usize,
    /// Ignore and do not write the fit cache.
    #[arg(long)]
    pub no_cache: bool,
}

pub fn run(args: FitEnvArgs) -> anyhow::Result<()> {
    let options = FitOptions {
        lights: args.lights,
        fit_width: args.fit_width,
        ..Default::default()
    };
    let bar = ProgressBar::new(options.max_iters);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} evaluations")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let b2 = bar.clone();
    let fit = fit_file(&args.env, &options, !args.no_cache, move |p| {
        b2.set_message(p.stage);
        b2.set_position(p.done);
    })?;
    bar.finish_and_clear();
    let s = &fit.sanitised;
    if s.any() {
        eprintln!(
            "warning: {}: replaced {} NaN, {} infinite and {} negative values by 0",
            args.env.display(),
            s.nan,
            s.infinite,
            s.negative
        );
    }
    let set = if args.yaw != 0.0 {
        fit.set.rotated(args.yaw.to_radians())
    } else {
        fit.set
    };
    let out = args.output.clone().unwrap_or_else(|| {
        let mut p = args.env.clone();
        p.set_extension("srbf.json");
        p
    });
    set.write(&out)?;
    if let Some(preview) = &args.preview {
        let (w, h) = match set.source_size {
            Some([w, h]) => (w, h),
            None => {
                let (env, _) = load_env(&args.env)?;
                (env.width, env.height)
            }
        };
        let recon = set.render(w, h);
        if preview
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"))
        {
            recon.write_png_preview(preview, 1.0)?;
        } else {
            recon.write_exr(preview).context("writing the preview")?;
        }
    }
    let stats = set.fit.clone().unwrap_or_default();
    eprintln!(
        "{}: {} lights{} -> {}; relative L2 error {:.4}, power error R {:+.2}% G {:+.2}% B {:+.2}%, {:.2} s",
        args.env.display(),
        set.lights.len(),
        if fit.from_cache { " (cached)" } else { "" },
        out.display(),
        stats.relative_l2,
        100.0 * stats.power_error[0],
        100.0 * stats.power_error[1],
        100.0 * stats.power_error[2],
        stats.seconds
    );
    Ok(())
}
