//! Procedural hairstyles (`strandlight make-hair`): deterministic per seed, parallel over strands.
//!
//! Each strand grows from a root on the generated head's scalp in `points - 1` steps of equal
//! length. A base direction starts along the scalp normal and bends under gravity (or, for the
//! ponytail, towards the tie point first); the step direction is the base tilted by the style's
//! curl, wave and frizz angles, so the arc length is exactly the requested length. Steps that
//! enter the head slide over it. Clumping then pulls strands towards guide strands, and a final
//! follow-the-leader pass restores every segment length while keeping points outside the head.

pub mod head;

pub use head::Head;

use glam::Vec3;
use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::model::{Hair, RawStrand};

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Style {
    StraightLong,
    Wavy,
    Curly,
    Bob,
    Ponytail,
    /// Chin to shoulder length, parted on the right (+X): combed from the parting down over the
    /// scalp, with a fringe over the forehead that ends just above the brows (no strand falls in
    /// front of the face: each is cut where it would), so the scalp is hidden from the front and
    /// the sides.
    SidePart,
}

impl Style {
    /// Default strand length range, cm.
    pub fn default_length(self) -> (f32, f32) {
        match self {
            Style::StraightLong => (35.0, 45.0),
            Style::Wavy => (30.0, 40.0),
            Style::Curly => (25.0, 35.0),
            Style::Bob => (14.0, 20.0),
            Style::Ponytail => (40.0, 50.0),
            Style::SidePart => (18.0, 25.0),
        }
    }
}

#[derive(Clone, Debug)]
pub struct StyleParams {
    pub style: Style,
    pub strands: usize,
    pub points: usize,
    pub seed: u64,
    /// Strand length range (min, max), cm.
    pub length: (f32, f32),
    /// 0 (none) to 1 (tips meet their clump's guide).
    pub clumping: f32,
    /// Strands per clump.
    pub clump_size: usize,
    /// 0 (none) to 1 (strong random tilts towards the tip).
    pub frizz: f32,
    /// Fiber diameter, cm.
    pub thickness: f32,
    pub head: Head,
}

impl StyleParams {
    pub fn new(style: Style, strands: usize, points: usize, seed: u64) -> Self {
        Self {
            style,
            strands,
            points,
            seed,
            length: style.default_length(),
            clumping: 0.4,
            clump_size: 40,
            frizz: 0.1,
            thickness: 0.007,
            head: Head::default(),
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        if self.strands == 0 || self.strands > 2_000_000 {
            return Err(format!(
                "strands must be in 1..=2000000, got {}",
                self.strands
            ));
        }
        if self.points < 2 || self.points > 1000 {
            return Err(format!(
                "points per strand must be in 2..=1000, got {}",
                self.points
            ));
        }
        let (a, b) = self.length;
        if !(a.is_finite() && b.is_finite() && a > 0.0 && b >= a && b <= 500.0) {
            return Err(format!(
                "length range must satisfy 0 < min <= max <= 500 cm, got {a}..{b}"
            ));
        }
        for (name, x) in [("clumping", self.clumping), ("frizz", self.frizz)] {
            if !(0.0..=1.0).contains(&x) {
                return Err(format!("{name} must be in [0, 1], got {x}"));
            }
        }
        if !(self.thickness.is_finite() && self.thickness > 0.0) {
            return Err(format!("thickness must be > 0, got {}", self.thickness));
        }
        Ok(())
    }
}

/// Relative margin kept between hair and skull (0.5 % of the radii, ~0.5 mm).
const MARGIN: f32 = 0.005;

fn rng_for(seed: u64, strand: usize, stream: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(
        seed ^ (strand as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ stream.rotate_left(32),
    )
}

fn uniform(r: &mut Pcg64Mcg) -> f32 {
    (r.next_u64() >> 40) as f32 / (1u64 << 24) as f32
}

/// A root on the scalp: (position, normal).
fn sample_root(head: &Head, r: &mut Pcg64Mcg) -> (Vec3, Vec3) {
    for _ in 0..1000 {
        let z = 2.0 * uniform(r) - 1.0;
        let a = std::f32::consts::TAU * uniform(r);
        let s = (1.0 - z * z).max(0.0).sqrt();
        let dir = Vec3::new(s * a.cos(), z, s * a.sin());
        if head.on_scalp(dir) {
            let (p, n) = head.surface(dir);
            return (head.push_out(p, MARGIN), n);
        }
    }
    let (p, n) = head.surface(Vec3::Y);
    (head.push_out(p, MARGIN), n)
}

/// Any unit vector orthogonal to `d`.
fn orthogonal(d: Vec3) -> Vec3 {
    d.any_orthonormal_vector()
}

/// Grows one strand (before clumping).
fn grow(params: &StyleParams, strand: usize) -> Vec<Vec3> {
    let head = &params.head;
    let mut r = rng_for(params.seed, strand, 1);
    let (root, normal) = sample_root(head, &mut r);
    let (lmin, lmax) = params.length;
    let length = lmin + (lmax - lmin) * uniform(&mut r);
    let n = params.points;
    let ds = length / (n - 1) as f32;
    let down = -Vec3::Y;
    // Ponytail: a tie point at the back of the head, tails fall from there.
    let tie = head.centre
        + Vec3::new(
            0.0,
            0.25 * head.radii.y,
            -(1.0 + 2.0 * MARGIN) * head.radii.z,
        );
    let tail_offset = Vec3::new(
        2.0 * uniform(&mut r) - 1.0,
        0.0,
        2.0 * uniform(&mut r) - 1.0,
    ) * 1.2;
    let mut reached_tie = false;
    // Curl and wave phases and frames.
    let phase = std::f32::consts::TAU * uniform(&mut r);
    let curl_pitch = 2.0 + 1.5 * uniform(&mut r); // cm per turn
    let wave_length = 5.0 + 2.0 * uniform(&mut r); // cm
    // Start outwards and down (no loops above the crown); roots over the forehead are combed up,
    // back and aside, away from a parting, so the face stays clear (combed only back, they slid down
    // over the forehead and fell over the face).
    let outward = (root - head.centre).with_y(0.0).normalize_or(normal);
    let front = ((root.z - head.centre.z) / head.radii.z).max(0.0);
    let aside = Vec3::X * (root.x - head.centre.x).signum();
    let mut base = match params.style {
        Style::SidePart => parted_start(head, root, normal),
        _ => {
            (0.5 * normal + outward + 0.5 * down + (Vec3::Y * 1.5 - Vec3::Z * 2.5 + aside) * front)
                .normalize_or(down)
        }
    };
    let mut side = orthogonal(base);
    let mut frizz_tilt = Vec3::ZERO;
    let mut pts = Vec::with_capacity(n);
    pts.push(root);
    let mut p = root;
    for k in 1..n {
        let t = k as f32 / (n - 1) as f32;
        let s = k as f32 * ds;
        // Base direction: gravity bends it down; the ponytail first heads for the tie point.
        base = match params.style {
            Style::Ponytail if !reached_tie => {
                if p.distance(tie) < 1.5 * ds.max(0.5) {
                    reached_tie = true;
                }
                (tie - p).normalize_or(down)
            }
            Style::Ponytail => {
                let column = tie + tail_offset - Vec3::Y * (tie.y - p.y);
                (down + 0.3 * (column - p)).normalize_or(down)
            }
            _ => {
                // Combed back while in front of the ears, above the chin: the face stays clear
                // (the side part's fringe only below the brow, so it sweeps across the forehead).
                let brow = head.centre.y + 0.15 * head.radii.y;
                let clear = match params.style {
                    Style::SidePart => p.y < brow,
                    _ => p.y > head.centre.y - 0.6 * head.radii.y,
                };
                let ahead = ((p.z - head.centre.z) / head.radii.z).max(0.0) * clear as u8 as f32;
                (base + 0.35 * ds * down - Vec3::Z * (0.6 * ds * ahead)).normalize_or(down)
            }
        };
        // Parallel transport of the side vector keeps curls from twisting.
        side = (side - base * side.dot(base)).normalize_or(orthogonal(base));
        let binormal = base.cross(side);
        // Style tilts (radians) grow in from the root.
        let ramp = (t * 4.0).min(1.0);
        let mut dir = base;
        match params.style {
            Style::Curly => {
                let a = std::f32::consts::TAU * s / curl_pitch + phase;
                let tilt = 0.9 * ramp;
                dir = base * tilt.cos() + (side * a.cos() + binormal * a.sin()) * tilt.sin();
            }
            Style::Wavy => {
                let tilt = 0.45 * ramp * (std::f32::consts::TAU * s / wave_length + phase).sin();
                dir = base * tilt.cos() + side * tilt.sin();
            }
            Style::Bob => {
                // Tips curl under, towards the neck.
                let inward = (head.centre - p).with_y(0.0).normalize_or_zero();
                let curl = ((t - 0.7) / 0.3).clamp(0.0, 1.0);
                dir = (base + 1.2 * curl * inward).normalize_or(base);
            }
            Style::SidePart => {
                // A loose wave for body, only towards the tips (the crown stays sleek).
                let tilt = 0.3
                    * ((t - 0.4) / 0.3).clamp(0.0, 1.0)
                    * (std::f32::consts::TAU * s / (1.5 * wave_length) + phase).sin();
                dir = base * tilt.cos() + side * tilt.sin();
            }
            Style::StraightLong | Style::Ponytail => {}
        }
        if params.frizz > 0.0 {
            let jitter = Vec3::new(uniform(&mut r), uniform(&mut r), uniform(&mut r)) - 0.5;
            frizz_tilt = 0.8 * frizz_tilt + jitter * params.frizz * t * t;
            dir = (dir + frizz_tilt).normalize_or(dir);
        }
        p = step_outside(head, p, dir, ds);
        pts.push(p);
    }
    pts
}

/// The parting of [`Style::SidePart`]: x over the head's half width (right of centre, as seen facing
/// the head).
const PARTING_X: f32 = 0.3;

/// The first direction of a [`Style::SidePart`] strand rooted at `root` (scalp normal `normal`):
/// along the scalp, away from the parting, turning to straight back behind the crown; the front of
/// the longer side sweeps across the forehead (the fringe). A slight lift off the scalp gives the
/// crown some volume.
fn parted_start(head: &Head, root: Vec3, normal: Vec3) -> Vec3 {
    let q = (root - head.centre) / head.radii;
    // Away from the parting, the strands along it combed back over it (no line of bare scalp).
    let away = Vec3::X * ((q.x - PARTING_X) / 0.2).clamp(-1.0, 1.0);
    // Behind the crown the parting ends: hair there falls back and down.
    let behind = ((-q.z + 0.1) / 0.5).clamp(0.0, 1.0);
    let front = (q.z / 0.8).clamp(0.0, 1.0);
    let fringe = fringe_weight(q);
    let comb =
        (away * (1.0 - behind) + Vec3::NEG_Z * (0.25 * (1.0 - front) + behind) + Vec3::NEG_Y * 0.4)
            * (1.0 - fringe)
            + (Vec3::Z + Vec3::NEG_Y * 0.6 + Vec3::X * (0.35 * q.x)) * fringe;
    let along = (comb - normal * comb.dot(normal)).normalize_or(Vec3::NEG_Y);
    (along + 0.15 * normal).normalize_or(Vec3::NEG_Y)
}

/// How much a root (at `q`, scaled by the head's radii) belongs to the fringe (the bangs): 1 over
/// the front of the scalp between the temples, 0 from half way up to the crown and at the sides.
fn fringe_weight(q: Vec3) -> f32 {
    let ahead = ((q.z - 0.35) / 0.25).clamp(0.0, 1.0);
    let between = ((0.9 - q.x.abs()) / 0.3).clamp(0.0, 1.0);
    ahead * between
}

/// The height (over the head's centre, in half heights) above which [`Style::SidePart`]'s strands
/// end where they would fall in front of the face: just above the brows.
const FRINGE_CUT: f32 = 0.18;

/// Whether `p` lies in front of the face below the fringe's cut: no strand of
/// [`Style::SidePart`] enters it.
fn before_face(head: &Head, p: Vec3, cut: f32) -> bool {
    let q = (p - head.centre) / head.radii;
    q.y < cut && q.z > 0.4 && q.x.abs() < 0.8
}

/// Cuts a strand where it first enters the space in front of the face (the fringe ends above the
/// brows, no strand crosses the eyes), resampled to the same number of points of equal spacing.
/// The cut height varies a little per strand (a soft, uneven fringe line).
fn trim_fringe(head: &Head, pts: Vec<Vec3>, jitter: f32) -> Vec<Vec3> {
    let cut = FRINGE_CUT + 0.03 * jitter;
    let Some(k) = pts.iter().position(|&p| before_face(head, p, cut)) else {
        return pts;
    };
    if k == 0 {
        return pts;
    }
    let arc: Vec<f32> = std::iter::once(0.0)
        .chain(pts.windows(2).scan(0.0, |a, w| {
            *a += w[0].distance(w[1]);
            Some(*a)
        }))
        .collect();
    let length = arc[k - 1].max(0.5 * arc[k]).max(1e-3);
    let n = pts.len();
    let mut j = 0;
    (0..n)
        .map(|i| {
            let s = length * i as f32 / (n - 1) as f32;
            while j + 2 < n && arc[j + 1] < s {
                j += 1;
            }
            let span = (arc[j + 1] - arc[j]).max(1e-6);
            let p = pts[j].lerp(pts[j + 1], ((s - arc[j]) / span).clamp(0.0, 1.0));
            head.push_out(p, MARGIN)
        })
        .collect()
}

/// One step of length `ds` from `p` along `dir`, sliding over the head if it would enter it.
fn step_outside(head: &Head, p: Vec3, dir: Vec3, ds: f32) -> Vec3 {
    let mut q = p + dir * ds;
    for _ in 0..4 {
        if head.implicit(q) >= (1.0 + MARGIN).powi(2) {
            break;
        }
        let pushed = head.push_out(q, 2.0 * MARGIN);
        q = p + (pushed - p).normalize_or(Vec3::Y) * ds;
    }
    if head.implicit(q) < (1.0 + MARGIN).powi(2) {
        q = head.push_out(q, 2.0 * MARGIN);
    }
    q
}

/// Generates the hairstyle.
pub fn generate(params: &StyleParams) -> Result<Hair, String> {
    params.validate()?;
    let grown: Vec<Vec<Vec3>> = (0..params.strands)
        .into_par_iter()
        .map(|s| grow(params, s))
        .collect();
    // Clumps: every clump_size-th strand is a guide; others follow the guide with the nearest root.
    let stride = params.clump_size.max(1);
    let guides: Vec<usize> = (0..params.strands).step_by(stride).collect();
    let seg: Vec<f32> = grown.iter().map(|s| s[0].distance(s[1])).collect();
    let strands: Vec<RawStrand> = (0..params.strands)
        .into_par_iter()
        .map(|s| {
            let own = &grown[s];
            let mut pts = own.clone();
            if params.clumping > 0.0 && guides.len() > 1 {
                let g = guides
                    .iter()
                    .copied()
                    .min_by(|&a, &b| {
                        own[0]
                            .distance_squared(grown[a][0])
                            .total_cmp(&own[0].distance_squared(grown[b][0]))
                    })
                    .unwrap_or(s);
                if g != s {
                    let guide = &grown[g];
                    let n = pts.len();
                    let root_offset = own[0] - guide[0];
                    for k in 1..n {
                        let t = k as f32 / (n - 1) as f32;
                        let w = params.clumping * t * t * (3.0 - 2.0 * t);
                        let target = guide[k] + root_offset * (1.0 - t);
                        pts[k] = pts[k].lerp(target, w);
                    }
                }
            }
            // Follow the leader: restore each segment length, keep outside the head.
            let ds = seg[s];
            let mut out = Vec::with_capacity(pts.len());
            out.push(pts[0]);
            for k in 1..pts.len() {
                let prev = out[k - 1];
                let dir = (pts[k] - prev).normalize_or(Vec3::NEG_Y);
                out.push(step_outside(&params.head, prev, dir, ds));
            }
            if params.style == Style::SidePart {
                let jitter = 2.0 * uniform(&mut rng_for(params.seed, s, 2)) - 1.0;
                out = trim_fringe(&params.head, out, jitter);
            }
            RawStrand {
                points: out,
                ..Default::default()
            }
        })
        .collect();
    let (hair, _) = Hair::from_strands(strands, params.thickness);
    Ok(hair)
}
