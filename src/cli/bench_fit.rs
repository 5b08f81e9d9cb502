//! `strandlight bench-fit ENV...`: CPU time of the SRBF fit per environment, as JSON.

use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;
use strandlight::envmap::{FitOptions, fit_srbf, load_env};

#[derive(Args, Debug)]
pub struct BenchFitArgs {
    /// Environments (.hdr, .exr).
    #[arg(required = true)]
    pub envs: Vec<PathBuf>,
    #[arg(long, default_value_t = 40)]
    pub lights: usize,
    /// Fits per environment; the median is reported.
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
}

#[derive(Serialize)]
struct Row {
    env: String,
    size: [usize; 2],
    lights: usize,
    load_seconds: f64,
    fit_seconds_median: f64,
    fit_seconds_all: Vec<f64>,
    relative_l2: f64,
    power_error: [f64; 3],
}

#[derive(Serialize)]
struct Report {
    machine_threads: usize,
    rows: Vec<Row>,
}

pub fn run(args: BenchFitArgs) -> anyhow::Result<()> {
    let mut rows = Vec::new();
    for path in &args.envs {
        let t = Instant::now();
        let (env, _) = load_env(path)?;
        let load_seconds = t.elapsed().as_secs_f64();
        let options = FitOptions {
            lights: args.lights,
            ..Default::default()
        };
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..args.repeats.max(1) {
            let t = Instant::now();
            let set = fit_srbf(&env, &options, |_| {}).map_err(anyhow::Error::msg)?;
            times.push(t.elapsed().as_secs_f64());
            last = Some(set);
        }
        let mut sorted = times.clone();
        sorted.sort_by(f64::total_cmp);
        let stats = last.and_then(|s| s.fit).unwrap_or_default();
        rows.push(Row {
            env: path.display().to_string(),
            size: [env.width, env.height],
            lights: args.lights,
            load_seconds,
            fit_seconds_median: sorted[sorted.len() / 2],
            fit_seconds_all: times,
            relative_l2: stats.relative_l2,
            power_error: stats.power_error,
        });
    }
    let report = Report {
        machine_threads: rayon::current_num_threads(),
        rows,
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
