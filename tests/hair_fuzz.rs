//! Every parser fed 10^5 mutated versions of a valid file (which must itself parse): errors are
//! fine, panics are not.

mod common;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::path::Path;
use strandlight::hair::cyhair::{read_cyhair, write_cyhair};
use strandlight::hair::gltf_io::read_gltf;
use strandlight::hair::mesh::read_obj;
use strandlight::hair::procedural::{Style, StyleParams, generate};
use strandlight::hair::tressfx::read_tressfx;
use strandlight::hair::usd::{CurveSelection, read_usd, write_usda};

const CASES: u32 = 100_000;

/// Byte edits (position, value), an optional truncation and an optional 32-bit field overwrite
/// (aimed at counts and offsets in headers).
type Mutation = (Vec<(usize, u8)>, Option<usize>, Option<(usize, u32)>);

fn mutations() -> impl Strategy<Value = Mutation> {
    (
        prop::collection::vec((any::<usize>(), any::<u8>()), 0..8),
        prop::option::of(any::<usize>()),
        prop::option::of((0usize..64, any::<u32>())),
    )
}

fn mutate(valid: &[u8], m: &Mutation) -> Vec<u8> {
    let mut b = valid.to_vec();
    for &(pos, v) in &m.0 {
        let n = b.len();
        b[pos % n] = v;
    }
    if let Some((word, v)) = m.2 {
        let at = 4 * word;
        if at + 4 <= b.len() {
            b[at..at + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    if let Some(t) = m.1 {
        let n = b.len();
        b.truncate(t % (n + 1));
    }
    b
}

fn fuzz(name: &str, valid: Vec<u8>, parse: impl Fn(&[u8]) -> bool) {
    fuzz_n(name, valid, CASES, parse)
}

fn fuzz_n(name: &str, valid: Vec<u8>, cases: u32, parse: impl Fn(&[u8]) -> bool) {
    // The seed itself must parse: a parser that rejected everything would otherwise pass.
    assert!(
        parse(&valid),
        "{name}: the unmutated seed file does not parse"
    );
    // A fixed seed keeps CI reproducible; set PROPTEST_RNG_SEED to explore other mutations.
    let seed = std::env::var("PROPTEST_RNG_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0x5EED_u64);
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(seed),
        ..Config::default()
    });
    let accepted = std::cell::Cell::new(0u32);
    runner
        .run(&mutations(), |m| {
            let bytes = mutate(&valid, &m);
            if parse(&bytes) {
                accepted.set(accepted.get() + 1);
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    println!(
        "{name}: {cases} mutated inputs, {} still parsed, none panicked",
        accepted.get()
    );
}

#[test]
fn cyhair_parser_survives_mutations() {
    let hair = generate(&StyleParams::new(Style::Wavy, 6, 5, 1)).unwrap();
    fuzz("cyHair", write_cyhair(&hair, "fuzz"), |b| {
        read_cyhair(b, Path::new("f.hair")).is_ok()
    });
}

#[test]
fn tressfx_parsers_survive_mutations() {
    fuzz("TressFX 3", common::tressfx3(4, 5), |b| {
        read_tressfx(b, Path::new("f.tfx")).is_ok()
    });
    fuzz("TressFX 4", common::tressfx4(3, 4), |b| {
        read_tressfx(b, Path::new("f.tfx")).is_ok()
    });
}

#[test]
fn gltf_parser_survives_mutations() {
    fuzz("glTF (GLB)", common::glb(), |b| {
        read_gltf(b, Path::new("f.glb"), None).is_ok()
    });
}

#[test]
fn obj_parser_survives_mutations() {
    fuzz("OBJ", common::OBJ.as_bytes().to_vec(), |b| {
        read_obj(b, Path::new("f.obj")).is_ok()
    });
}

/// The USD reader opens files by path (references resolve beside them): each mutation is written
/// to a temporary file, so fewer cases run than for the in-memory parsers.
fn fuzz_usd(name: &str, ext: &str, valid: Vec<u8>, cases: u32) {
    let path = common::temp_file("usd-fuzz", &format!("f.{ext}"));
    let failed_inside = std::cell::Cell::new(0u32);
    fuzz_n(name, valid, cases, |b| {
        std::fs::write(&path, b).unwrap();
        let r = read_usd(&path, &CurveSelection::default());
        if let Err(e) = &r
            && (e.contains("USD reader failed") || e.contains("USD reader crashed"))
        {
            failed_inside.set(failed_inside.get() + 1);
        }
        r.is_ok()
    });
    println!(
        "{name}: the USD crate panicked or aborted on {} inputs (isolated, reported as errors)",
        failed_inside.get()
    );
}

#[test]
fn usd_reader_survives_mutations() {
    let hair = generate(&StyleParams::new(Style::Wavy, 3, 5, 1)).unwrap();
    let text = write_usda(&hair, None, "fuzz");
    // The same layer as a binary crate file, written by the USD crate.
    let data = openusd::usda::parse(&text).unwrap();
    let crate_path = common::temp_file("usd-fuzz", "seed.usdc");
    openusd::usdc::CrateWriter::write_to_file(&data, crate_path.to_str().unwrap()).unwrap();
    let crate_bytes = std::fs::read(&crate_path).unwrap();
    fuzz_usd("USD text", "usda", text.into_bytes(), 1_500);
    fuzz_usd("USD crate", "usdc", crate_bytes, 1_500);
}

#[test]
fn alembic_reader_survives_mutations_and_names_what_it_refuses() {
    use strandlight::hair::alembic::read_alembic;
    let read = |b: &[u8]| read_alembic(b, &CurveSelection::default());
    let hdf5 = [b"\x89HDF\r\n\x1a\n".as_slice(), &[0u8; 64]].concat();
    let e = read(&hdf5).unwrap_err();
    assert!(e.contains("HDF5"), "{e}");
    assert!(read(b"Ogawa").unwrap_err().contains("not an Alembic"));
    let mut unfinished = b"Ogawa\x00\x00\x01".to_vec();
    unfinished.extend([0u8; 8]);
    assert!(read(&unfinished).unwrap_err().contains("not finished"));
    let Some(data) = common::shared_data() else {
        return;
    };
    // Blender's archive (2 MB): truncations through its structure, then mutations.
    let seed = std::fs::read(data.join("hair/alembic/ponytail_blender.abc")).unwrap();
    let n = seed.len();
    let mut refused = 0;
    for k in 0..400 {
        let cut = if k < 200 {
            k * 16
        } else {
            n - (k - 199) * 97 % n
        };
        refused += usize::from(read(&seed[..cut.min(n)]).is_err());
    }
    println!("Alembic: 400 truncations, {refused} refused, none panicked");
    fuzz_n("Alembic (Blender's ponytail)", seed, 3_000, |b| {
        read(b).is_ok()
    });
}
