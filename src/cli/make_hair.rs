//! `strandlight make-hair`: a procedural hairstyle written as cyHair.

use anyhow::{Context, anyhow};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;
use strandlight::hair::cyhair::write_cyhair;
use strandlight::hair::procedural::{Style, StyleParams, generate};

#[derive(Args, Debug)]
pub struct MakeHairArgs {
    #[arg(long, value_enum, default_value_t = Style::StraightLong)]
    pub style: Style,
    #[arg(long, default_value_t = 10_000)]
    pub strands: usize,
    /// Points per strand.
    #[arg(long, default_value_t = 32)]
    pub points: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Strand length range MIN,MAX in cm (default depends on the style).
    #[arg(long, value_delimiter = ',', num_args = 2)]
    pub length: Option<Vec<f32>>,
    /// Clumping, 0..1.
    #[arg(long, default_value_t = 0.4)]
    pub clumping: f32,
    /// Strands per clump.
    #[arg(long, default_value_t = 40)]
    pub clump_size: usize,
    /// Frizz, 0..1.
    #[arg(long, default_value_t = 0.1)]
    pub frizz: f32,
    /// Fiber diameter in cm.
    #[arg(long, default_value_t = 0.007)]
    pub thickness: f32,
    /// Output .hair file.
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: MakeHairArgs) -> anyhow::Result<()> {
    let mut p = StyleParams::new(args.style, args.strands, args.points, args.seed);
    if let Some(l) = &args.length {
        p.length = (l[0], l[1]);
    }
    p.clumping = args.clumping;
    p.clump_size = args.clump_size;
    p.frizz = args.frizz;
    p.thickness = args.thickness;
    let t = Instant::now();
    let hair = generate(&p)
        .map_err(|e| anyhow!(e))
        .context("invalid hairstyle parameters")?;
    let elapsed = t.elapsed();
    let info = format!("strandlight make-hair {:?} seed {}", args.style, args.seed);
    std::fs::write(&args.output, write_cyhair(&hair, &info))
        .with_context(|| format!("writing {}", args.output.display()))?;
    eprintln!(
        "{}: {} strands x {} points ({:?}) generated in {:.2} s",
        args.output.display(),
        hair.strand_count(),
        args.points,
        args.style,
        elapsed.as_secs_f64()
    );
    Ok(())
}
