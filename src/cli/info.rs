//! `strandlight info FILE`: what a hair file holds.

use anyhow::Context;
use clap::Args;
use serde::Serialize;
use std::path::PathBuf;
use strandlight::hair::load::{ArraysPresent, LoadOptions, load_hair};
use strandlight::hair::normalize::{Normalization, Units, UpAxis};

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A .hair (cyHair), .tfx (TressFX 3/4), .gltf or .glb file.
    pub file: PathBuf,
    #[command(flatten)]
    pub space: SpaceArgs,
}

/// Overrides of the detected orientation and units.
#[derive(Args, Debug, Clone, Copy)]
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
}

impl SpaceArgs {
    pub fn options(&self) -> LoadOptions {
        LoadOptions {
            up: self.up,
            units: self.units,
            scale: self.scale,
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
}

pub fn run(args: InfoArgs) -> anyhow::Result<()> {
    let loaded =
        load_hair(&args.file, &args.space.options()).context("could not read hair file")?;
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
    };
    println!("{}", serde_json::to_string_pretty(&info)?);
    eprintln!(
        "{}: {} strands, {} points; up {} ({}), units {:?} ({})",
        info.file,
        info.strands,
        info.points,
        serde_json::to_string(&info.normalization.up)?.trim_matches('"'),
        info.normalization.up_source,
        info.normalization.units,
        if info.normalization.units_detected {
            "detected"
        } else {
            "given"
        },
    );
    Ok(())
}
