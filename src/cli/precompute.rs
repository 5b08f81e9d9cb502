//! `strandlight precompute`: rebuild the Xu 2011 tables in `luts/`.

use anyhow::anyhow;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;
use strandlight::scattering::tables::build_all;
use strandlight::scattering::tables_io::write_tables;

#[derive(Args, Debug)]
pub struct PrecomputeArgs {
    /// Output folder.
    #[arg(short, long, default_value = "luts")]
    pub output: PathBuf,
}

pub fn run(args: PrecomputeArgs) -> anyhow::Result<()> {
    let t = Instant::now();
    let tables = build_all();
    let build = t.elapsed().as_secs_f64();
    write_tables(&tables, &args.output).map_err(|e| anyhow!(e))?;
    eprintln!(
        "{}: {} tables built in {build:.3} s ({} threads), written in {:.3} s",
        args.output.display(),
        tables.len(),
        rayon::current_num_threads(),
        t.elapsed().as_secs_f64() - build
    );
    Ok(())
}
