//! `strandlight gpu-info`: which adapter the renderer would use, and the optional features it has.

use strandlight::gpu::{GpuContext, GpuOptions};

pub fn run(software: bool) -> anyhow::Result<()> {
    let mut options = GpuOptions::from_env();
    options.force_software |= software;
    let ctx = GpuContext::new_headless(&options)?;
    let mut summary = serde_json::to_value(&ctx.summary)?;
    summary["features"] = format!("{:?}", ctx.adapter.features()).into();
    println!("{}", serde_json::to_string_pretty(&summary)?);
    Ok(())
}
