//! The command-line front end. Every subcommand calls into the library; nothing here does maths.

pub mod bench;
pub mod bench_editor;
pub mod bench_fast;
pub mod bench_fit;
pub mod bsdf;
pub mod edit;
pub mod export_hair;
pub mod fit_env;
pub mod gpu_info;
pub mod info;
pub mod make_env;
pub mod make_hair;
pub mod params_args;
pub mod precompute;
pub mod render;
pub mod srbf_response;

use clap::{Parser, Subcommand};

/// strandlight: physically based hair appearance under HDR environments.
#[derive(Parser, Debug)]
#[command(name = "strandlight", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Open the editor (the default without a subcommand): a window where hair looks are designed live.
    Edit(edit::EditArgs),
    /// Evaluate the exact Marschner scattering function S_R, S_TT, S_TRT for given angles (JSON).
    Bsdf(Box<bsdf::BsdfArgs>),
    /// Describe a hair file: counts, bounds, detected up axis and units, lengths, optional arrays (JSON).
    Info(info::InfoArgs),
    /// Generate a procedural hairstyle around a generated head and write it as cyHair.
    MakeHair(make_hair::MakeHairArgs),
    /// Fit an HDR environment (.hdr, .exr) with SRBF lights and write them as .srbf.json.
    FitEnv(fit_env::FitEnvArgs),
    /// Generate the project's own environments (sunny sky, overcast, studio) as EXR, with their fits.
    MakeEnv(make_env::MakeEnvArgs),
    /// Benchmark the SRBF fit on environments (CPU seconds, JSON).
    BenchFit(bench_fit::BenchFitArgs),
    /// Rebuild the Xu 2011 tables (C_k, H_k^TT, H_k^TRT) in luts/ as float32 EXR plus a manifest.
    Precompute(precompute::PrecomputeArgs),
    /// The fast per-SRBF single-scattering response (Xu 2011), optionally against brute force (JSON).
    SrbfResponse(Box<srbf_response::SrbfResponseArgs>),
    /// Benchmark the LUT build, the dual-scattering tables and the 40-light fast response (CPU, JSON).
    BenchFast(bench_fast::BenchFastArgs),
    /// Render a still (linear EXR, PNG preview) of a hairstyle under an environment on the GPU.
    Render(Box<render::RenderArgs>),
    /// Benchmark the renderer on the standard scenes S0-S3: GPU time per pass (JSON).
    Bench(bench::BenchArgs),
    /// Export a session's hair with its look and paint for other tools (.usda USD curves, .hair).
    ExportHair(export_hair::ExportHairArgs),
    /// Print the GPU adapter strandlight would render with (JSON).
    GpuInfo {
        /// Ask for a software adapter (lavapipe) even if a GPU exists.
        #[arg(long)]
        software: bool,
    },
}

pub fn run(cli: Cli) -> anyhow::Result<()> {
    // The editor's first times count from here (its window and device come after).
    let launched = std::time::Instant::now();
    match cli.command {
        Some(Command::Edit(args)) => edit::run_editor(args, launched),
        Some(Command::Bsdf(args)) => bsdf::run(*args),
        Some(Command::Info(args)) => info::run(args),
        Some(Command::MakeHair(args)) => make_hair::run(args),
        Some(Command::FitEnv(args)) => fit_env::run(args),
        Some(Command::MakeEnv(args)) => make_env::run(args),
        Some(Command::BenchFit(args)) => bench_fit::run(args),
        Some(Command::Precompute(args)) => precompute::run(args),
        Some(Command::SrbfResponse(args)) => srbf_response::run(*args),
        Some(Command::BenchFast(args)) => bench_fast::run(args),
        Some(Command::Render(args)) => render::run(*args),
        Some(Command::Bench(args)) => bench::run(args),
        Some(Command::ExportHair(args)) => export_hair::run(args),
        Some(Command::GpuInfo { software }) => gpu_info::run(software),
        None => edit::run_editor(
            edit::EditArgs {
                lights: 40,
                ..Default::default()
            },
            launched,
        ),
    }
}
