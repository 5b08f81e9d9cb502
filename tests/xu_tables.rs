//! The Xu 2011 tables in luts/: regenerated identically, and every sampled entry equal to a slow
//! adaptive quadrature of its definition.

use std::path::Path;
use strandlight::scattering::tables::{build_all, cos_gaussian_integral, fresnel_moment};
use strandlight::scattering::tables_io::{read_manifest, read_table};

fn luts() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/luts"))
}

#[test]
fn committed_tables_are_what_precompute_builds() {
    let t = std::time::Instant::now();
    let fresh = build_all();
    println!("tables built in {:.3} s", t.elapsed().as_secs_f64());
    let manifest = read_manifest(luts()).unwrap();
    assert_eq!(manifest.tables.len(), fresh.len());
    for (entry, table) in manifest.tables.iter().zip(&fresh) {
        let committed = read_table(luts(), entry).unwrap();
        assert_eq!(committed.x_axis, table.x_axis);
        assert_eq!(committed.y_axis, table.y_axis);
        assert_eq!(committed.channels, table.channels);
        let mut worst = 0f32;
        for (a, b) in committed.data.iter().zip(&table.data) {
            for (x, y) in a.iter().zip(b) {
                worst = worst.max((x - y).abs() / y.abs().max(1e-30));
            }
        }
        println!(
            "{}: regenerated, worst relative difference {worst:e}",
            entry.file
        );
        assert!(
            worst <= 1e-6,
            "{}: committed table differs from a fresh build",
            entry.file
        );
    }
}

#[test]
fn table_entries_match_brute_force_quadrature() {
    let manifest = read_manifest(luts()).unwrap();
    for entry in &manifest.tables {
        let table = read_table(luts(), entry).unwrap();
        let (w, h) = (table.x_axis.samples, table.y_axis.samples);
        let mut worst = (0f64, String::new());
        let mut n = 0;
        // Every 7th column and 5th row, plus the corners.
        for y in (0..h).step_by(5).chain([h - 1]) {
            for x in (0..w).step_by(7).chain([w - 1]) {
                let (xv, yv) = (table.x_axis.value(x), table.y_axis.value(y));
                for (c, name) in table.channels.iter().enumerate() {
                    let k: u32 = name[1..].parse().unwrap();
                    let exact = match entry.name.as_str() {
                        "C_k" => cos_gaussian_integral(k, xv, yv),
                        "H_TT" => fresnel_moment(false, k, xv, yv),
                        _ => fresnel_moment(true, k, xv, yv),
                    };
                    let got = table.data[c][y * w + x] as f64;
                    let rel = if exact.abs() > 1e-12 {
                        ((got - exact) / exact).abs()
                    } else {
                        (got - exact).abs()
                    };
                    if rel > worst.0 {
                        worst = (rel, format!("{name} at ({xv:.4}, {yv:.4})"));
                    }
                    n += 1;
                }
            }
        }
        println!(
            "{}: {n} entries against adaptive quadrature, worst relative error {:.2e} at {}",
            entry.file, worst.0, worst.1
        );
        assert!(worst.0 < 2e-6, "{}: {:?}", entry.file, worst);
    }
}
