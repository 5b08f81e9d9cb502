//! `strandlight bench-fast`: CPU cost of the Xu 2011 preprocessing (LUT build, dual-scattering tables)
//! and of the fast single-scattering response, alone and with dual scattering, for one shading point under
//! a 40-light SRBF set, as JSON.

use clap::Args;
use glam::DVec3;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;
use strandlight::envmap::SrbfSet;
use strandlight::scattering::azimuthal_table::AzimuthalTable;
use strandlight::scattering::dual_response::{
    dual_scattering_components, global_response_lobe_in_view, local_response,
};
use strandlight::scattering::dual_terms::DualTables;
use strandlight::scattering::fast_params::{DEFAULT_QUADRATURE_SEGMENTS, FastHairParams};
use strandlight::scattering::fast_response::{SrbfInFrame, srbf_response_in_view, view_lobes};
use strandlight::scattering::lut::Luts;
use strandlight::scattering::tables::build_all;
use strandlight::scattering::{
    CausticModel, FiberFrame, HairParams, LongitudinalModel, ModelVariant,
};

#[derive(Args, Debug)]
pub struct BenchFastArgs {
    /// SRBF lights (.srbf.json); default: the project's sunny sky.
    #[arg(long)]
    pub lights: Option<PathBuf>,
    /// Repeats of each measurement; medians are reported.
    #[arg(long, default_value_t = 9)]
    pub repeats: usize,
    /// Shading points (random fiber tangents and views) per repeat of the response timing.
    #[arg(long, default_value_t = 200)]
    pub points: usize,
    /// Longitudinal function of the fast form.
    #[arg(long, value_enum, default_value_t = LongitudinalModel::Normalized)]
    pub longitudinal: LongitudinalModel,
}

#[derive(Serialize)]
struct Report {
    machine_threads: usize,
    lut_build_seconds_median: f64,
    lut_build_seconds_all: Vec<f64>,
    dual_tables_build_seconds_median: f64,
    /// The azimuthal table of the exact window integrals (all threads; rebuilt when eta or the
    /// eccentricity change).
    azimuthal_table_build_seconds_median: f64,
    lights_file: String,
    lights: usize,
    quadrature_segments: u32,
    /// One thread: all lights' R, TT and TRT responses (RGB) at one shading point.
    response_microseconds_per_point_median: f64,
    response_microseconds_per_light: f64,
    /// One thread: per light, single scattering plus dual scattering as the shading pass evaluates it
    /// (M^G of the three lobes, M^L with the path's spread and without, Zinke's combination).
    single_multiple_microseconds_per_point_median: f64,
    single_multiple_microseconds_per_light: f64,
    /// The longitudinal function measured ("normalized": d'Eon et al. 2011).
    longitudinal: LongitudinalModel,
    /// Sum over lights and points of the response's total (a checksum that the work was done).
    checksum: f64,
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

pub fn run(args: BenchFastArgs) -> anyhow::Result<()> {
    let repeats = args.repeats.max(1);
    let mut lut_times: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            let tables = build_all();
            std::hint::black_box(&tables);
            t.elapsed().as_secs_f64()
        })
        .collect();
    let all = lut_times.clone();
    let lut_median = median(&mut lut_times);
    let params = HairParams::default();
    let variant = ModelVariant {
        caustic: CausticModel::None,
        ..ModelVariant::XU
    };
    let mut dual_times: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(DualTables::build(&params, variant));
            t.elapsed().as_secs_f64()
        })
        .collect();
    let path = args.lights.clone().unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("envmaps/sunny.srbf.json")
    });
    let set = SrbfSet::read(&path)?;
    let luts = Luts::default_tables();
    let fp = FastHairParams::new(&params, DEFAULT_QUADRATURE_SEGMENTS)
        .with_longitudinal(args.longitudinal);
    let mut table_times: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(AzimuthalTable::for_params(&fp));
            t.elapsed().as_secs_f64()
        })
        .collect();
    let table = AzimuthalTable::for_params(&fp);
    // Deterministic shading points: tangents and views spread over the sphere (golden spiral).
    let dir = |k: usize, n: usize, twist: f64| {
        let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let a = k as f64 * 2.399_963 + twist;
        DVec3::new(r * a.cos(), z, r * a.sin())
    };
    let points: Vec<(Vec<SrbfInFrame>, f32, f32)> = (0..args.points.max(1))
        .map(|k| {
            let frame = FiberFrame::from_tangent(dir(k, args.points, 0.0));
            let view = frame.angles(dir(k, args.points, 1.3));
            let lights = set
                .lights
                .iter()
                .map(|l| {
                    let a = frame.angles(l.dir());
                    SrbfInFrame {
                        theta: a.theta as f32,
                        phi: a.phi as f32,
                        lambda: l.lambda as f32,
                    }
                })
                .collect();
            (lights, view.theta as f32, view.phi as f32)
        })
        .collect();
    let mut checksum = 0.0;
    let mut per_point: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            for (lights, theta_o, phi_o) in &points {
                // What the view fixes, once per point (as the shading pass).
                let lobes = view_lobes(&fp, *theta_o);
                for l in lights {
                    let r = srbf_response_in_view(&luts, &table, &fp, &lobes, *l, *phi_o);
                    checksum += r.iter().flatten().map(|v| *v as f64).sum::<f64>();
                }
            }
            t.elapsed().as_secs_f64() * 1e6 / points.len() as f64
        })
        .collect();
    let per_point_median = median(&mut per_point);
    let tables = DualTables::build(&params, variant.with_longitudinal(args.longitudinal));
    let mut per_point_ms: Vec<f64> = (0..repeats)
        .map(|_| {
            let t = Instant::now();
            for (lights, theta_o, phi_o) in &points {
                let lobes = view_lobes(&fp, *theta_o);
                for l in lights {
                    let (to, po) = (*theta_o, *phi_o);
                    let r = srbf_response_in_view(&luts, &table, &fp, &lobes, *l, po);
                    // A shadow-grid value: half the light forward-scattered, spread 0.05 rad^2,
                    // two fibers behind the point.
                    let (direct, t_f, s2, behind) = (0.5, [0.7f32; 3], 0.05, 2.0);
                    let mut global = [0.0f32; 3];
                    for lobe in 0..3 {
                        let g = global_response_lobe_in_view(
                            &table,
                            &fp,
                            lobe,
                            &lobes[lobe as usize],
                            *l,
                            po,
                            s2,
                        );
                        for c in 0..3 {
                            global[c] += g[c];
                        }
                    }
                    let local = local_response(&fp, &tables, *l, to, po, s2, behind);
                    let local_direct = local_response(&fp, &tables, *l, to, po, 0.0, behind);
                    let ms =
                        dual_scattering_components(&fp, direct, t_f, local_direct, global, local);
                    checksum += r.iter().flatten().map(|v| *v as f64).sum::<f64>()
                        + ms.0
                            .iter()
                            .chain(ms.1.iter())
                            .map(|v| *v as f64)
                            .sum::<f64>();
                }
            }
            t.elapsed().as_secs_f64() * 1e6 / points.len() as f64
        })
        .collect();
    let per_point_ms_median = median(&mut per_point_ms);
    let report = Report {
        machine_threads: rayon::current_num_threads(),
        lut_build_seconds_median: lut_median,
        lut_build_seconds_all: all,
        dual_tables_build_seconds_median: median(&mut dual_times),
        azimuthal_table_build_seconds_median: median(&mut table_times),
        lights_file: path.display().to_string(),
        lights: set.lights.len(),
        quadrature_segments: fp.quadrature_segments,
        response_microseconds_per_point_median: per_point_median,
        response_microseconds_per_light: per_point_median / set.lights.len().max(1) as f64,
        single_multiple_microseconds_per_point_median: per_point_ms_median,
        single_multiple_microseconds_per_light: per_point_ms_median
            / set.lights.len().max(1) as f64,
        longitudinal: args.longitudinal,
        checksum: checksum / (2 * repeats) as f64,
    };
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
