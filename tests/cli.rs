//! The command-line interface as a user meets it.

use std::io::Write;
use std::process::{Command, Stdio};

fn strandlight() -> Command {
    Command::new(env!("CARGO_BIN_EXE_strandlight"))
}

/// Runs the binary with `args`, writing `stdin` to it; stdout and stderr captured.
fn run_with_stdin<A: AsRef<std::ffi::OsStr>>(
    args: impl IntoIterator<Item = A>,
    stdin: &[u8],
) -> std::process::Output {
    let mut child = strandlight()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child.stdin.take().unwrap().write_all(stdin).unwrap();
    child.wait_with_output().unwrap()
}

#[test]
fn help_lists_the_subcommands() {
    let out = strandlight().arg("--help").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("bsdf") && text.contains("gpu-info") && text.contains("edit"),
        "{text}"
    );
}

#[test]
fn without_a_display_the_editor_says_so_in_one_line() {
    for args in [&[][..], &["edit"][..]] {
        let out = strandlight()
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert!(!out.status.success());
        let text = String::from_utf8_lossy(&out.stderr);
        println!("{text}");
        assert_eq!(text.trim().lines().count(), 1, "{text}");
        assert!(text.contains("no display") && text.contains("strandlight render"));
    }
}

#[test]
fn bsdf_answers_json_that_matches_the_library() {
    let out = strandlight()
        .args([
            "bsdf",
            "--theta-i",
            "10",
            "--theta-o",
            "-5",
            "--phi-o",
            "160",
            "--preset",
            "blond",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let total: Vec<f64> = serde_json::from_value(v["S"]["total"].clone()).unwrap();
    use strandlight::scattering::*;
    let lib = scattering_s(
        &Preset::Blond.params(),
        ModelVariant::MARSCHNER,
        FiberAngles::new(10f64.to_radians(), 0.0),
        FiberAngles::new((-5f64).to_radians(), 160f64.to_radians()),
    )
    .total();
    for c in 0..3 {
        assert!(
            (total[c] - lib[c]).abs() <= 1e-12 * lib[c].abs(),
            "{total:?} vs {lib:?}"
        );
    }
    assert!((v["theta_h"].as_f64().unwrap() - 2.5).abs() < 1e-9);
}

#[test]
fn bsdf_batch_from_stdin_and_overrides() {
    let out = run_with_stdin(["bsdf", "--stdin", "--beta-r", "4"], br#"[{"theta_i": 20, "theta_o": -10, "phi_o": 30},
                 {"theta_i": 20, "theta_o": -10, "phi_o": 30, "params": {"beta_r": 8, "variant": "xu", "sigma_a": [0.1, 0.2, 0.3]}}]"#);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let arr = v.as_array().unwrap();
    assert_eq!(arr.len(), 2);
    assert!((arr[0]["params"]["beta_deg"][0].as_f64().unwrap() - 4.0).abs() < 1e-12);
    assert!((arr[1]["params"]["beta_deg"][0].as_f64().unwrap() - 8.0).abs() < 1e-12);
    assert_eq!(arr[1]["variant"], "xu");
    assert!((arr[1]["params"]["beta_deg"][2].as_f64().unwrap() - 16.0).abs() < 1e-12);
}

#[test]
fn bad_input_is_a_one_line_error_with_nonzero_exit() {
    for (args, stdin, needle) in [
        (
            vec!["bsdf", "--theta-i", "120", "--theta-o", "0"],
            "",
            "theta_i",
        ),
        (
            vec!["bsdf", "--theta-i", "0", "--theta-o", "0", "--eta", "-3"],
            "",
            "eta",
        ),
        (vec!["bsdf", "--stdin"], "not json", "JSON"),
        (
            vec!["bsdf", "--stdin"],
            r#"[{"theta_i": 0, "theta_o": 0, "colour": 1}]"#,
            "colour",
        ),
        (
            vec!["bsdf", "--stdin"],
            r#"[{"theta_i": 0, "theta_o": 0, "params": {"sigma_a": [1, 2]}}]"#,
            "sigma_a",
        ),
        // Limits in the units the user typed (degrees), and a missing file's error said once.
        (
            vec![
                "bsdf",
                "--theta-i",
                "0",
                "--theta-o",
                "0",
                "--beta-r",
                "1000",
            ],
            "",
            "got 1000 degrees",
        ),
        (
            vec![
                "render",
                "--hair",
                "/nonexistent/strandlight.hair",
                "-o",
                "/tmp/x.exr",
            ],
            "",
            "/nonexistent/strandlight.hair: No such file",
        ),
        // An output folder that does not exist fails before any rendering.
        (
            vec!["render", "-o", "/nonexistent/strandlight/x.exr"],
            "",
            "does not exist",
        ),
    ] {
        let out = run_with_stdin(&args, stdin.as_bytes());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.starts_with("error:") && err.trim_end().lines().count() == 1,
            "{err}"
        );
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(
            err.matches("os error").count() <= 1,
            "{args:?}: the cause repeated: {err}"
        );
    }
}

#[test]
fn stdin_presets_are_spelled_as_on_the_command_line() {
    let out = run_with_stdin(
        ["bsdf", "--stdin"],
        br#"[{"theta_i": 10, "theta_o": -5, "phi_o": 160, "params": {"preset": "dark-brown"}}]"#,
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn make_hair_then_info_and_a_corrupt_file() {
    let dir = std::env::temp_dir().join(format!("strandlight-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("bob.hair");
    let status = strandlight()
        .args([
            "make-hair",
            "--style",
            "bob",
            "--strands",
            "500",
            "--points",
            "12",
            "--seed",
            "9",
            "-o",
        ])
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let info = strandlight().arg("info").arg(&out).output().unwrap();
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    assert_eq!(v["strands"], 500);
    assert_eq!(v["points"], 6000);
    assert_eq!(v["normalization"]["up"], "+Y");
    assert_eq!(v["normalization"]["units"], "centimetres");
    assert!(v["length_cm"]["min"].as_f64().unwrap() >= 13.9);
    // A truncated copy: exit 1, one line, the file named.
    let bytes = std::fs::read(&out).unwrap();
    let bad = dir.join("cut.hair");
    std::fs::write(&bad, &bytes[..bytes.len() / 2]).unwrap();
    let e = strandlight().arg("info").arg(&bad).output().unwrap();
    let err = String::from_utf8_lossy(&e.stderr);
    assert_eq!(e.status.code(), Some(1));
    assert!(
        err.trim_end().lines().count() == 1 && err.contains("cut.hair"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn fit_env_caches_by_content_and_rotates() {
    let dir = std::env::temp_dir().join(format!("strandlight-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let env = dir.join("studio.exr");
    std::fs::copy(
        concat!(env!("CARGO_MANIFEST_DIR"), "/envmaps/studio.exr"),
        &env,
    )
    .unwrap();
    let run = |extra: &[&str]| {
        let out = strandlight()
            .env("STRANDLIGHT_CACHE", dir.join("cache"))
            .args(["fit-env", "--lights", "6"])
            .arg(&env)
            .arg("-o")
            .arg(dir.join("out.srbf.json"))
            .args(extra)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let first = run(&[]);
    assert!(!first.contains("(cached)"), "{first}");
    let plain = std::fs::read_to_string(dir.join("out.srbf.json")).unwrap();
    let second = run(&[
        "--yaw",
        "90",
        "--preview",
        dir.join("p.png").to_str().unwrap(),
    ]);
    assert!(second.contains("(cached)"), "{second}");
    let turned: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out.srbf.json")).unwrap()).unwrap();
    let plain: serde_json::Value = serde_json::from_str(&plain).unwrap();
    assert_eq!(turned["lights"][0]["lambda"], plain["lights"][0]["lambda"]);
    assert!((turned["yaw"].as_f64().unwrap() - 90f64.to_radians()).abs() < 1e-12);
    assert!(std::fs::metadata(dir.join("p.png")).unwrap().len() > 100);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn srbf_response_fast_against_reference_and_batch() {
    let out = strandlight()
        .args([
            "srbf-response",
            "--theta-j",
            "20",
            "--phi-j",
            "150",
            "--lambda",
            "0.3",
            "--theta-o",
            "-10",
            "--preset",
            "blond",
            "--reference",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for c in 0..3 {
        let e = v["relative_error"][c].as_f64().unwrap();
        assert!(e < 0.01, "channel {c}: {e}");
        let total = v["fast"]["total"][c].as_f64().unwrap();
        assert!(total > 0.0);
    }
    // Batch from stdin; an impossible query names itself.
    let out = run_with_stdin(["srbf-response", "--stdin"], br#"[{"theta_j": 20, "phi_j": 160, "lambda": 0.3, "theta_o": -10}, {"theta_j": 20, "phi_j": 160, "lambda": 0.3, "theta_o": -10, "params": {"sigma_a": [5]}}]"#);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let arr = v.as_array().unwrap();
    let tt = |k: usize| arr[k]["fast"]["TT"][0].as_f64().unwrap();
    assert!(
        tt(1) < 0.01 * tt(0),
        "dark hair transmits less: {} vs {}",
        tt(1),
        tt(0)
    );
    for (args, needle) in [
        (
            vec![
                "srbf-response",
                "--theta-j",
                "20",
                "--lambda",
                "0",
                "--theta-o",
                "0",
            ],
            "lambda",
        ),
        (
            vec![
                "srbf-response",
                "--theta-j",
                "20",
                "--lambda",
                "0.3",
                "--theta-o",
                "0",
                "--variant",
                "marschner",
            ],
            "variant",
        ),
    ] {
        let out = strandlight().args(&args).output().unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn render_reference_takes_an_optional_mode() {
    // A bad mode is refused before anything is rendered, naming the modes.
    let out = strandlight()
        .args([
            "render",
            "--reference=bogus",
            "--width",
            "8",
            "--height",
            "8",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("dual") && err.contains("path"), "{err}");
    // The help documents both forms and the path tracer's flags.
    let out = strandlight().args(["render", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    for want in ["--reference[=<REFERENCE>]", "--spp", "--max-depth"] {
        assert!(help.contains(want), "help lacks {want}");
    }
}

#[test]
fn a_closed_pipe_ends_a_command_quietly() {
    // `strandlight bsdf … | head -0`: the reader is gone before the first line is written.
    let mut child = strandlight()
        .args([
            "bsdf",
            "--theta-i",
            "10",
            "--theta-o",
            "-5",
            "--phi-o",
            "160",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("status {:?}, stderr {stderr:?}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_ne!(out.status.code(), Some(101), "a panic's exit code");
}
