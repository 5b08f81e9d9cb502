//! The session parser fed mutated session files and the recovery file's reader mutated JSON values:
//! errors are fine (and name the file), panics are not; whatever parses also validates.

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::path::Path;
use strandlight::session::Session;

const CASES: u32 = 20_000;

/// Feeds `cases` mutations of the JSON text `seed` to `check` (true: it parsed); no panic may occur.
/// The edits are mostly digits and JSON punctuation: they reach the values, not just the syntax.
fn fuzz_json(
    seed: &str,
    cases: u32,
    check: impl Fn(&str) -> Result<bool, proptest::test_runner::TestCaseError>,
) -> u32 {
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    });
    let parsed = std::cell::Cell::new(0u32);
    runner
        .run(
            &(
                prop::collection::vec((any::<usize>(), any::<u8>()), 0..6),
                prop::option::of(any::<usize>()),
            ),
            |(edits, cut)| {
                let mut b = seed.as_bytes().to_vec();
                for (pos, v) in edits {
                    let n = b.len();
                    b[pos % n] = b"0123456789-.e,:{}[]\"tfn "[v as usize % 24];
                }
                if let Some(c) = cut {
                    b.truncate(c % (b.len() + 1));
                }
                if check(&String::from_utf8_lossy(&b))? {
                    parsed.set(parsed.get() + 1);
                }
                Ok(())
            },
        )
        .expect("no panic, errors name the file");
    parsed.get()
}

#[test]
fn mutated_sessions_never_panic() {
    let mut valid = Session {
        env_yaw: 30.0,
        ..Default::default()
    };
    valid.look.tip = Some(strandlight::session::Absorption::Dye {
        colour: [0.4, 0.2, 0.1],
        beta_n: 0.3,
    });
    let text = valid.to_json();
    // The seed itself must parse: a parser that rejected everything would otherwise pass.
    let back = Session::from_json(&text, Path::new("seed.slsession")).expect("the seed parses");
    assert_eq!(back, valid);
    let parsed = fuzz_json(&text, CASES, |text| {
        match Session::from_json(text, Path::new("fuzzed.slsession")) {
            Ok(s) => {
                prop_assert!(s.validate().is_ok());
                Ok(true)
            }
            Err(e) => {
                prop_assert!(e.to_string().contains("fuzzed.slsession"));
                Ok(false)
            }
        }
    });
    println!("{CASES} mutated sessions: {parsed} still parsed and validated");
}

#[test]
fn mutated_recovery_files_never_panic() {
    let session: serde_json::Value =
        serde_json::from_str(&Session::default().to_json()).expect("a session's JSON");
    let seed = serde_json::json!({
        "session_path": "/nowhere/look.slsession",
        "session": session,
    })
    .to_string();
    let dir =
        std::env::temp_dir().join(format!("strandlight-recovery-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("recovery-1.slsession");
    let read = |bytes: &[u8]| {
        std::fs::write(&file, bytes).expect("written");
        strandlight::session::autosave::read_recovery(&file)
    };
    // The seed itself must read back: a reader that rejected everything would otherwise pass.
    let (path, s, warning) = read(seed.as_bytes()).expect("the unmutated recovery file reads");
    assert_eq!(path, Path::new("/nowhere/look.slsession"));
    assert_eq!(s, Session::default());
    assert!(warning.is_none());
    let cases = CASES / 4;
    let parsed = fuzz_json(&seed, cases, |text| match read(text.as_bytes()) {
        Ok((_, s, _)) => {
            prop_assert!(s.validate().is_ok());
            Ok(true)
        }
        Err(e) => {
            let e = e.to_string();
            prop_assert!(e.contains("recovery-1.slsession"), "{e}");
            Ok(false)
        }
    });
    let _ = std::fs::remove_dir_all(&dir);
    println!("{cases} mutated recovery files: {parsed} still read and validated");
}
