//! `strandlight gpu-info`: which adapter the renderer would use.

use strandlight::gpu::{GpuContext, GpuOptions};

pub fn run(software: bool) -> anyhow::Result<()> {
    let mut options = GpuOptions::from_env();
    options.force_software |= software;
    let ctx = GpuContext::new_headless(&options)?;
    println!("{}", serde_json::to_string_pretty(&ctx.summary)?);
    Ok(())
}
