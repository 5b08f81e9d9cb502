//! Absorption from dye colours (Chiang 2016's inversion), gradients, per-strand variation, and the
//! paint-layer file (round trip, hostile bytes, mismatched hair).

use std::path::Path;
use strandlight::hair::procedural::Style;
use strandlight::paint::dye::{DEFAULT_BETA_N, parse_colour};
use strandlight::paint::{AbsorptionSpec, PaintLayer, sigma_a_from_colour};
use strandlight::render::scene::generated_hair;

#[test]
fn colour_inversion_matches_chiang_2016() {
    // Eq. (9) at beta_N = 0.3 by hand: d = 5.969 - 0.215 b + 2.532 b^2 - 10.73 b^3 + 5.574 b^4 + 0.245 b^5.
    let b: f64 = 0.3;
    let d = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3)
        + 5.574 * b.powi(4)
        + 0.245 * b.powi(5);
    let s = sigma_a_from_colour([0.5, 0.25, 0.1], DEFAULT_BETA_N);
    for (c, want) in [0.5f64, 0.25, 0.1].iter().enumerate() {
        let expect = (want.ln() / d).powi(2);
        println!("albedo {want}: sigma_a {:.5} (by hand {expect:.5})", s[c]);
        assert!((s[c] - expect).abs() < 1e-12);
    }
    // Darker dye absorbs more; white absorbs (almost) nothing.
    assert!(s[0] < s[1] && s[1] < s[2]);
    assert!(sigma_a_from_colour([1.0; 3], 0.3)[0] < 1e-9);
    // Colours: sRGB hex decodes to linear; r,g,b is linear.
    let red = parse_colour("#ff0000").expect("hex");
    assert_eq!(red, [1.0, 0.0, 0.0]);
    let mid = parse_colour("#808080").expect("hex")[0];
    assert!((mid - 0.2158605).abs() < 1e-6, "sRGB 128 is linear {mid}");
    assert_eq!(
        parse_colour("0.2, 0.3,0.4").expect("linear"),
        [0.2, 0.3, 0.4]
    );
    for bad in ["#12345", "#gg0000", "1,2", "0.1,0.2,1.5", "red"] {
        let e = parse_colour(bad).expect_err("rejected");
        println!("{bad:?}: {e}");
    }
}

#[test]
fn gradients_and_per_strand_variation() {
    let hair = generated_hair(Style::StraightLong, 50, 12, 2);
    let spec = AbsorptionSpec {
        root: [2.0, 2.0, 2.0],
        tip: [0.2, 0.4, 0.8],
        variation: 0.0,
        seed: 1,
    };
    let s = spec.per_point(&hair);
    let r = hair.strand_range(3);
    assert_eq!(s[r.start], [2.0; 3]);
    assert!((s[r.end - 1][0] - 0.2).abs() < 1e-6 && (s[r.end - 1][2] - 0.8).abs() < 1e-6);
    for w in s[r.clone()].windows(2) {
        assert!(
            w[1][0] <= w[0][0],
            "sigma_a falls monotonically root to tip"
        );
    }
    let varied = AbsorptionSpec {
        variation: 0.3,
        ..AbsorptionSpec::uniform([1.0, 1.0, 1.0])
    };
    let (a, b) = (varied.per_point(&hair), varied.per_point(&hair));
    assert_eq!(a, b, "deterministic per seed");
    let scales: Vec<f32> = (0..hair.strand_count())
        .map(|k| a[hair.strand_range(k).start][0])
        .collect();
    for k in 0..hair.strand_count() {
        assert!(
            a[hair.strand_range(k)].iter().all(|p| p[0] == scales[k]),
            "constant along a strand"
        );
    }
    let ln: Vec<f64> = scales.iter().map(|s| (*s as f64).ln()).collect();
    let mean = ln.iter().sum::<f64>() / ln.len() as f64;
    let sd = (ln.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / ln.len() as f64).sqrt();
    println!("per-strand log scale: mean {mean:.3}, sd {sd:.3} (asked 0.3)");
    assert!(mean.abs() < 0.15 && (sd - 0.3).abs() < 0.1);
}

#[test]
fn paint_layers_round_trip_and_reject_bad_files() {
    let hair = generated_hair(Style::Bob, 20, 6, 2);
    let n = hair.point_count();
    let layer = PaintLayer {
        strand_count: hair.strand_count() as u64,
        points: (0..n)
            .map(|k| [0.1 * k as f32, 1.0, 2.0, if k % 2 == 0 { 1.0 } else { 0.0 }])
            .collect(),
    };
    let path =
        std::env::temp_dir().join(format!("strandlight-paint-{}.slpaint", std::process::id()));
    layer.write(&path).expect("write");
    let back = PaintLayer::read(&path).expect("read");
    assert_eq!(back, layer);
    let mut base = vec![[0.5f32; 3]; n];
    back.apply(&mut base, hair.strand_count(), &path)
        .expect("apply");
    assert_eq!(base[0], [0.0, 1.0, 2.0]);
    assert_eq!(base[1], [0.5, 0.5, 0.5]);
    // Mismatched hair, truncation, bad magic, version, NaN, negative, weight out of range.
    let mut other = vec![[0.5f32; 3]; n + 1];
    let e = back
        .apply(&mut other, hair.strand_count(), &path)
        .expect_err("mismatch");
    println!("{e}");
    assert!(e.to_string().contains("strandlight-paint"));
    let bytes = layer.encode();
    let p = Path::new("bad.slpaint");
    let mut cases: Vec<Vec<u8>> = vec![
        bytes[..bytes.len() - 3].to_vec(),
        b"NOTPAINT".iter().chain(&bytes[8..]).copied().collect(),
        Vec::new(),
    ];
    let mut v = bytes.clone();
    v[8] = 9;
    cases.push(v);
    for (offset, value) in [(32usize, f32::NAN), (36, -1.0), (44, 1.5)] {
        let mut v = bytes.clone();
        v[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
        cases.push(v);
    }
    let mut v = bytes.clone();
    v[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
    cases.push(v);
    for c in &cases {
        let e = PaintLayer::decode(c, p).expect_err("rejected");
        println!("{e}");
        assert!(e.to_string().starts_with("bad.slpaint: "));
    }
    // Fuzz: random mutations never panic.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for _ in 0..20_000 {
        let mut v = bytes.clone();
        for _ in 0..1 + next() % 4 {
            let i = (next() as usize) % v.len();
            v[i] = next() as u8;
        }
        if next() % 5 == 0 {
            v.truncate((next() as usize) % v.len());
        }
        let _ = PaintLayer::decode(&v, p);
    }
    let _ = std::fs::remove_file(&path);
}
