//! The session parser fed mutated session files and the recovery file's reader mutated JSON values:
//! errors are fine (and name the file), panics are not; whatever parses also validates.

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::path::Path;
use strandlight::session::Session;

const CASES: u32 = 20_000;

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
    let bytes = text.as_bytes().to_vec();
    let mut runner = TestRunner::new(Config {
        cases: CASES,
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
                let mut b = bytes.clone();
                for (pos, v) in edits {
                    let n = b.len();
                    // Mostly digits and JSON punctuation: they reach the values, not just the syntax.
                    b[pos % n] = b"0123456789-.e,:{}[]\"tfn "[v as usize % 24];
                }
                if let Some(c) = cut {
                    b.truncate(c % (b.len() + 1));
                }
                let text = String::from_utf8_lossy(&b);
                match Session::from_json(&text, Path::new("fuzzed.slsession")) {
                    Ok(s) => {
                        parsed.set(parsed.get() + 1);
                        prop_assert!(s.validate().is_ok());
                    }
                    Err(e) => prop_assert!(e.to_string().contains("fuzzed.slsession")),
                }
                Ok(())
            },
        )
        .expect("no panic, errors name the file");
    println!(
        "{CASES} mutated sessions: {} still parsed and validated",
        parsed.get()
    );
}
