//! `strandlight info FILE`: what a hair file holds.

use anyhow::Context;
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use strandlight::hair::curve_file::CurveFile;
use strandlight::hair::load::{ArraysPresent, LoadOptions, load_hair};
use strandlight::hair::normalize::{Normalization, Units, UpAxis};
use strandlight::hair::usd::CurveSelection;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A .hair (cyHair), .tfx (TressFX 3/4), .gltf, .glb, USD (.usd, .usda, .usdc, .usdz) or Alembic
    /// (.abc) file.
    pub file: PathBuf,
    #[command(flatten)]
    pub space: SpaceArgs,
}

/// Overrides of the detected or declared orientation and units, and which curves to read.
#[derive(Args, Debug, Clone)]
pub struct SpaceArgs {
    /// Up axis of the file (detected when absent).
    #[arg(long, value_enum)]
    pub up: Option<UpAxis>,
    /// Units of the file (detected when absent).
    #[arg(long, value_enum)]
    pub units: Option<Units>,
    /// Extra scale after unit conversion.
    #[arg(long, default_value_t = 1.0)]
    pub scale: f32,
    /// USD or Alembic: the prim or object path whose curves are read (USD default: the stage's
    /// default prim; Alembic: the whole archive).
    #[arg(long)]
    pub prim: Option<String>,
    /// The time sampled curves are read at (USD: a time code; Alembic: seconds; default: the
    /// first sample).
    #[arg(long)]
    pub time: Option<f64>,
}

impl SpaceArgs {
    pub fn options(&self) -> LoadOptions {
        LoadOptions {
            up: self.up,
            units: self.units,
            scale: self.scale,
            curves: CurveSelection {
                prim: self.prim.clone(),
                time: self.time,
            },
        }
    }
}

#[derive(Serialize)]
struct Stats {
    min: f32,
    mean: f32,
    max: f32,
}

impl Stats {
    fn of(v: impl Iterator<Item = f32>) -> Stats {
        let (mut min, mut max, mut sum, mut n) = (f32::INFINITY, f32::NEG_INFINITY, 0.0f64, 0usize);
        for x in v {
            min = min.min(x);
            max = max.max(x);
            sum += x as f64;
            n += 1;
        }
        Stats {
            min,
            mean: (sum / n.max(1) as f64) as f32,
            max,
        }
    }
}

#[derive(Serialize)]
struct Info {
    file: String,
    format: &'static str,
    declared_strands: u64,
    declared_points: u64,
    strands: usize,
    points: usize,
    points_per_strand: Stats,
    zero_length_segments_removed: usize,
    short_strands_dropped: usize,
    source_bounds: [[f32; 3]; 2],
    normalization: Normalization,
    world_bounds_cm: [[f32; 3]; 2],
    length_cm: Stats,
    thickness_cm: Stats,
    arrays: ArraysPresent,
    occluder_triangles: usize,
    /// What a USD or Alembic file declared: the curve batches read and skipped, the colour
    /// primvar, the time read.
    #[serde(skip_serializing_if = "Option::is_none")]
    curves: Option<CurveFile>,
    load_seconds: f64,
}

pub fn run(args: InfoArgs) -> anyhow::Result<()> {
    let start = std::time::Instant::now();
    let mut loaded =
        load_hair(&args.file, &args.space.options()).context("could not read hair file")?;
    let load_seconds = start.elapsed().as_secs_f64();
    let h = &loaded.file.hair;
    let (lo, hi) = h.bounds();
    let info = Info {
        file: args.file.display().to_string(),
        format: loaded.file.format,
        declared_strands: loaded.file.declared.0,
        declared_points: loaded.file.declared.1,
        strands: h.strand_count(),
        points: h.point_count(),
        points_per_strand: Stats::of((0..h.strand_count()).map(|s| h.strand_range(s).len() as f32)),
        zero_length_segments_removed: loaded.file.clean.zero_length_segments_removed,
        short_strands_dropped: loaded.file.clean.short_strands_dropped,
        source_bounds: [
            loaded.source_bounds.0.to_array(),
            loaded.source_bounds.1.to_array(),
        ],
        normalization: loaded.normalization,
        world_bounds_cm: [lo.to_array(), hi.to_array()],
        length_cm: Stats::of(h.strand_lengths().into_iter()),
        thickness_cm: Stats::of(
            (0..h.strand_count())
                .flat_map(|s| h.strand_range(s).map(move |p| (s, p)))
                .map(|(s, p)| h.thickness_at(s, p)),
        ),
        arrays: loaded.file.arrays,
        occluder_triangles: loaded.file.mesh.as_ref().map_or(0, |m| m.triangles.len()),
        curves: loaded.file.curves.take(),
        load_seconds,
    };
    println!("{}", serde_json::to_string_pretty(&info)?);
    let n = &info.normalization;
    let units = match n.declared_cm_per_unit {
        Some(cm) => format!("{cm} cm per unit (declared by the file)"),
        None if n.units_detected => format!("{:?} (detected)", n.units),
        None => format!("{:?} (given)", n.units),
    };
    eprintln!(
        "{}: {} strands, {} points in {:.2} s; up {} ({}), units {units}",
        info.file,
        info.strands,
        info.points,
        info.load_seconds,
        serde_json::to_string(&n.up)?.trim_matches('"'),
        n.up_source,
    );
    for skipped in info.curves.iter().flat_map(|c| &c.skipped) {
        eprintln!("skipped {skipped}");
    }
    Ok(())
}
