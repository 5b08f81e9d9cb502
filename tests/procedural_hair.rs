//! Procedural hairstyles: outside the head, lengths as requested, deterministic.

use strandlight::hair::procedural::{Style, StyleParams, generate};

#[test]
fn no_point_inside_the_head_and_lengths_in_range() {
    for style in [
        Style::StraightLong,
        Style::Wavy,
        Style::Curly,
        Style::Bob,
        Style::Ponytail,
        Style::SidePart,
    ] {
        let mut p = StyleParams::new(style, 3000, 40, 11);
        p.frizz = 0.3;
        p.clumping = 0.7;
        let hair = generate(&p).unwrap();
        assert_eq!(hair.strand_count(), 3000);
        let inside = hair
            .positions
            .iter()
            .filter(|&&x| p.head.implicit(x) < 1.0)
            .count();
        let lengths = hair.strand_lengths();
        let (lo, hi) = lengths
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &l| (a.min(l), b.max(l)));
        println!(
            "{style:?}: lengths {lo:.2}..{hi:.2} cm (requested {:?}), {inside} points inside the head",
            p.length
        );
        assert_eq!(inside, 0, "{style:?}");
        // The side part's fringe and the strands that would fall over the face end above the
        // brows: shorter than requested, never longer.
        let shortest = if style == Style::SidePart {
            1.0
        } else {
            0.99 * p.length.0
        };
        assert!(
            lo >= shortest && hi <= 1.01 * p.length.1,
            "{style:?}: {lo}..{hi}"
        );
    }
}

#[test]
fn deterministic_per_seed() {
    let p = StyleParams::new(Style::Curly, 500, 20, 3);
    assert_eq!(generate(&p).unwrap(), generate(&p).unwrap());
    let q = StyleParams::new(Style::Curly, 500, 20, 4);
    assert_ne!(
        generate(&p).unwrap().positions,
        generate(&q).unwrap().positions
    );
}

#[test]
fn invalid_parameters_are_refused() {
    let mut p = StyleParams::new(Style::Bob, 10, 1, 0);
    assert!(generate(&p).is_err());
    p.points = 10;
    p.length = (5.0, 2.0);
    assert!(generate(&p).is_err());
}
