//! The paint brush's settings and what a stroke does to the paint layer.
//!
//! A point's absorption is mix(base, painted, weight) ([`super::PaintLayer`]). A stroke keeps, for
//! every point it touched, the layer's value before the stroke and the largest dab strength it
//! received; the point's value is recomputed from those two, so dabs that overlap do not add up past
//! the brush's strength (Blender's stroke behaviour) and the stroke's effect does not depend on how
//! densely the dabs were spaced.
//!
//! A dab reads the layer and writes its changes to a [`DabLayer`] over it, which becomes a
//! [`PaintDelta`]: the editor applies that as an edit like any other, so undo, autosave and the tests
//! see strokes as data.

use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};

/// How strength falls off from the brush centre (r: distance over radius, in [0, 1]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Falloff {
    /// 3(1 - r)^2 - 2(1 - r)^3 (smoothstep).
    #[default]
    Smooth,
    /// 1 - r.
    Linear,
    /// 1.
    Constant,
    /// (1 - r)^2.
    Sharp,
}

impl Falloff {
    pub const ALL: [Falloff; 4] = [
        Falloff::Smooth,
        Falloff::Linear,
        Falloff::Constant,
        Falloff::Sharp,
    ];

    /// The weight at r = distance / radius (0 outside the brush).
    pub fn weight(self, r: f32) -> f32 {
        if !(0.0..=1.0).contains(&r) {
            return 0.0;
        }
        let s = 1.0 - r;
        match self {
            Falloff::Smooth => s * s * (3.0 - 2.0 * s),
            Falloff::Linear => s,
            Falloff::Constant => 1.0,
            Falloff::Sharp => s * s,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Falloff::Smooth => "smooth",
            Falloff::Linear => "linear",
            Falloff::Constant => "constant",
            Falloff::Sharp => "sharp",
        }
    }
}

/// What a dab does to the points under it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PaintMode {
    /// Mix toward the dye's absorption.
    #[default]
    Dye,
    /// Add eumelanin ([`MELANIN_STEP`] concentration at full strength).
    Darken,
    /// Remove melanin: absorption scaled by [`LIGHTEN_FACTOR`] at full strength (bleach).
    Lighten,
    /// Average with the neighbours along the strand and the other strands under the dab.
    Blur,
    /// Back to the base look.
    Erase,
}

impl PaintMode {
    pub const ALL: [PaintMode; 5] = [
        PaintMode::Dye,
        PaintMode::Darken,
        PaintMode::Lighten,
        PaintMode::Blur,
        PaintMode::Erase,
    ];

    pub fn name(self) -> &'static str {
        match self {
            PaintMode::Dye => "dye",
            PaintMode::Darken => "darken",
            PaintMode::Lighten => "lighten",
            PaintMode::Blur => "blur",
            PaintMode::Erase => "erase",
        }
    }
}

/// The absorption of a unit eumelanin concentration (what darken adds, [`MELANIN_STEP`] of it).
pub fn eumelanin_unit() -> [f32; 3] {
    crate::scattering::params::sigma_a_from_melanin(1.0, 0.0).map(|x| x as f32)
}

/// Eumelanin concentration a full-strength darken dab adds.
pub const MELANIN_STEP: f64 = 1.0;
/// What a full-strength lighten dab scales the absorption by (both melanins alike).
pub const LIGHTEN_FACTOR: f32 = 0.4;

/// Which hair under the brush a dab reaches.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reach {
    /// Points at most this far (cm, along the view axis) behind the front-most hair under them.
    pub depth: f32,
}

/// The front-most hair: points within this depth (cm) of the visible surface under them (about the
/// hair's top few layers of fibres).
pub const FRONT_DEPTH: f32 = 0.5;

/// The brush's settings (the editor's brush panel; not part of the session's undo history).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Brush {
    /// Radius in screen pixels (the viewport's points, as the cursor ring shows it).
    pub radius_px: f32,
    /// Strength in [0, 1]: what a stroke saturates at, at the centre.
    pub strength: f32,
    pub falloff: Falloff,
    pub mode: PaintMode,
    /// The dye's absorption (per unit fibre radius, as the look's sigma_a).
    pub dye: [f32; 3],
    /// Reach behind the front-most hair, cm ([`FRONT_DEPTH`]: the front only).
    pub depth: f32,
    /// Root-to-tip mask: only where the strand parameter t lies in [t0, t1], feathered over
    /// `feather` on each side (None: everywhere).
    pub mask: Option<[f32; 3]>,
    /// Also paint the mirror image of the footprint across the hair's symmetry plane (x = centre).
    pub mirror: bool,
    /// Dab spacing along the pointer path, as a fraction of the radius.
    pub spacing: f32,
}

impl Default for Brush {
    fn default() -> Self {
        Self {
            radius_px: 30.0,
            strength: 0.6,
            falloff: Falloff::Smooth,
            mode: PaintMode::Dye,
            dye: [0.08, 0.55, 0.9],
            depth: FRONT_DEPTH,
            mask: None,
            mirror: false,
            spacing: 0.15,
        }
    }
}

impl Brush {
    /// The mask's weight at strand parameter t.
    pub fn mask_weight(&self, t: f32) -> f32 {
        let Some([t0, t1, feather]) = self.mask else {
            return 1.0;
        };
        let f = feather.max(1e-4);
        let ramp = |x: f32| x.clamp(0.0, 1.0);
        let (t0, t1) = (t0.min(t1), t0.max(t1));
        let rise = if t0 <= 0.0 {
            1.0
        } else {
            ramp((t - t0) / f + 1.0)
        };
        let fall = if t1 >= 1.0 {
            1.0
        } else {
            ramp((t1 - t) / f + 1.0)
        };
        rise * fall
    }
}

/// A painted point's layer value: painted sigma_a RGB and weight.
pub type LayerValue = [f32; 4];

/// A point's absorption from its base and its layer value.
pub fn effective(base: [f32; 3], v: LayerValue) -> [f32; 3] {
    std::array::from_fn(|c| base[c] + v[3] * (v[c] - base[c]))
}

/// The layer value after mixing absorption `before` (a layer value over `base`) toward `target` by
/// `a` in [0, 1], keeping the weight form: w' = 1 - (1 - w)(1 - a),
/// c' = (c w (1 - a) + a target) / w', so that mix(base, c', w') = mix(mix(base, c, w), target, a)
/// and the painted part still follows the base where it was not fully painted.
pub fn mix_toward(before: LayerValue, target: [f32; 3], a: f32) -> LayerValue {
    let w = before[3];
    let w1 = 1.0 - (1.0 - w) * (1.0 - a);
    if w1 <= 0.0 {
        return before;
    }
    let c: [f32; 3] = std::array::from_fn(|k| (before[k] * w * (1.0 - a) + a * target[k]) / w1);
    [c[0], c[1], c[2], w1]
}

/// Where a dab reads and writes layer values: a layer itself, or a [`DabLayer`] over one.
pub trait LayerValues {
    fn value(&self, i: u32) -> LayerValue;
    fn set_value(&mut self, i: u32, v: LayerValue);
}

impl LayerValues for [LayerValue] {
    fn value(&self, i: u32) -> LayerValue {
        self[i as usize]
    }

    fn set_value(&mut self, i: u32, v: LayerValue) {
        self[i as usize] = v;
    }
}

/// A dab's changes over a layer that it leaves as it is: the dab reads through them (blur's
/// neighbours see the values the dab wrote before, as on the layer itself), and they become the
/// delta that the session applies.
pub struct DabLayer<'a> {
    layer: &'a [LayerValue],
    changed: BTreeMap<u32, LayerValue>,
}

impl<'a> DabLayer<'a> {
    pub fn new(layer: &'a [LayerValue]) -> Self {
        Self {
            layer,
            changed: BTreeMap::new(),
        }
    }

    /// The points written and their new values (sorted by index; None when nothing was written):
    /// applied to the layer, it makes the dab's change.
    pub fn into_delta(self) -> Option<PaintDelta> {
        if self.changed.is_empty() {
            return None;
        }
        let (indices, values) = self.changed.into_iter().unzip();
        Some(PaintDelta { indices, values })
    }
}

impl LayerValues for DabLayer<'_> {
    fn value(&self, i: u32) -> LayerValue {
        self.changed
            .get(&i)
            .copied()
            .unwrap_or(self.layer[i as usize])
    }

    fn set_value(&mut self, i: u32, v: LayerValue) {
        self.changed.insert(i, v);
    }
}

/// One stroke under way: the layer values before it and the strongest dab each point received.
#[derive(Default)]
pub struct Stroke {
    touched: HashMap<u32, (LayerValue, f32)>,
    /// Dabs applied.
    pub dabs: u32,
}

/// A point under a dab: its index and the dab's strength there (strength x falloff x mask x
/// pressure), in [0, 1].
pub type Touch = (u32, f32);

impl Stroke {
    pub fn new() -> Self {
        Self::default()
    }

    /// Applies a dab of `brush` to the points `under` it; writes the new layer values into `layer` and
    /// returns the indices whose value changed. `base`: each point's absorption without paint;
    /// `strand_of`: the strand range of a point (blur's neighbours along it); `eumelanin`: the
    /// absorption of a unit eumelanin concentration (darken).
    pub fn dab<L: LayerValues + ?Sized>(
        &mut self,
        brush: &Brush,
        under: &[Touch],
        layer: &mut L,
        base: &[[f32; 3]],
        strand_of: impl Fn(u32) -> std::ops::Range<u32>,
        eumelanin: [f32; 3],
    ) -> Vec<u32> {
        self.dabs += 1;
        // Blur's across-strand target: the mean absorption under the dab, as it was before the dab.
        let mean_under = if brush.mode == PaintMode::Blur && !under.is_empty() {
            let mut acc = [0.0f64; 3];
            for &(i, _) in under {
                let e = effective(base[i as usize], layer.value(i));
                for c in 0..3 {
                    acc[c] += e[c] as f64;
                }
            }
            acc.map(|x| (x / under.len() as f64) as f32)
        } else {
            [0.0; 3]
        };
        let mut changed = Vec::with_capacity(under.len());
        for &(i, a) in under {
            let iu = i as usize;
            let entry = self.touched.entry(i).or_insert((layer.value(i), 0.0));
            // The stroke's effect saturates at the strongest dab (blur keeps smoothing).
            let a = if brush.mode == PaintMode::Blur {
                a
            } else {
                if a <= entry.1 {
                    continue;
                }
                entry.1 = a;
                a
            };
            let before = if brush.mode == PaintMode::Blur {
                layer.value(i)
            } else {
                entry.0
            };
            let b = base[iu];
            let now = effective(b, before);
            let value = match brush.mode {
                PaintMode::Dye => mix_toward(before, brush.dye, a),
                PaintMode::Erase => [before[0], before[1], before[2], before[3] * (1.0 - a)],
                PaintMode::Darken => {
                    let t = std::array::from_fn(|c| now[c] + MELANIN_STEP as f32 * eumelanin[c]);
                    mix_toward(before, t, a)
                }
                PaintMode::Lighten => {
                    let t = now.map(|x| x * LIGHTEN_FACTOR);
                    mix_toward(before, t, a)
                }
                PaintMode::Blur => {
                    let r = strand_of(i);
                    let (lo, hi) = (i.saturating_sub(1).max(r.start), (i + 1).min(r.end - 1));
                    let along: [f32; 3] = std::array::from_fn(|c| {
                        let e = |k: u32| effective(base[k as usize], layer.value(k))[c];
                        (e(lo) + e(i) + e(hi)) / 3.0
                    });
                    let t = std::array::from_fn(|c| 0.5 * (along[c] + mean_under[c]));
                    mix_toward(before, t, a)
                }
            };
            if value != layer.value(i) {
                layer.set_value(i, value);
                changed.push(i);
            }
        }
        changed
    }

    /// The stroke as an undo step: the touched points' values before it (a [`PaintDelta`] whose
    /// application restores them), None when it changed nothing.
    pub fn finish(self, layer: &[LayerValue]) -> Option<PaintDelta> {
        let mut v: Vec<(u32, LayerValue)> = self
            .touched
            .into_iter()
            .filter(|(i, (before, _))| layer[*i as usize] != *before)
            .map(|(i, (before, _))| (i, before))
            .collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by_key(|(i, _)| *i);
        Some(PaintDelta {
            indices: v.iter().map(|(i, _)| *i).collect(),
            values: v.iter().map(|(_, x)| *x).collect(),
        })
    }

    /// Points touched so far.
    pub fn touched(&self) -> usize {
        self.touched.len()
    }
}

/// A sparse change of the paint layer: applying it swaps the listed points' values with the layer's,
/// so the same record undoes and then redoes (20 bytes per touched point).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PaintDelta {
    pub indices: Vec<u32>,
    pub values: Vec<LayerValue>,
}

impl PaintDelta {
    /// Swaps the values with `layer`'s; the delta then holds what the layer had (its inverse).
    pub fn swap(&mut self, layer: &mut [LayerValue]) {
        for (i, v) in self.indices.iter().zip(self.values.iter_mut()) {
            if let Some(slot) = layer.get_mut(*i as usize) {
                std::mem::swap(slot, v);
            }
        }
    }

    /// Adds the points of `later` that this delta does not hold yet, with their values in `later`:
    /// for undo deltas, the earliest value of each point wins (a stroke's undo holds each point as
    /// it was before the stroke). Both are sorted by index, and so is the result.
    pub fn keep_earliest(&mut self, later: PaintDelta) {
        let mut merged = Vec::with_capacity(self.indices.len() + later.indices.len());
        let mut mine = self
            .indices
            .iter()
            .copied()
            .zip(self.values.iter().copied());
        let mut theirs = later.indices.into_iter().zip(later.values).peekable();
        for (i, v) in mine.by_ref() {
            while let Some(&(j, w)) = theirs.peek()
                && j < i
            {
                merged.push((j, w));
                theirs.next();
            }
            if theirs.peek().is_some_and(|&(j, _)| j == i) {
                theirs.next();
            }
            merged.push((i, v));
        }
        merged.extend(theirs);
        (self.indices, self.values) = merged.into_iter().unzip();
    }

    /// Drops the points whose value here equals the layer's (a stroke that put a point back as it
    /// was has no undo for it).
    pub fn retain_differing(&mut self, layer: &[LayerValue]) {
        let keep: Vec<(u32, LayerValue)> = self
            .indices
            .iter()
            .zip(&self.values)
            .filter(|(i, v)| layer.get(**i as usize) != Some(*v))
            .map(|(i, v)| (*i, *v))
            .collect();
        (self.indices, self.values) = keep.into_iter().unzip();
    }

    /// Memory the delta holds, bytes.
    pub fn bytes(&self) -> usize {
        self.indices.len() * std::mem::size_of::<u32>()
            + self.values.len() * std::mem::size_of::<LayerValue>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(
        brush: &Brush,
        dabs: &[&[Touch]],
        layer: &mut [LayerValue],
        base: &[[f32; 3]],
    ) -> Stroke {
        let mut s = Stroke::new();
        let n = layer.len() as u32;
        for d in dabs {
            s.dab(brush, d, layer, base, |_| 0..n, [0.4, 0.8, 1.6]);
        }
        s
    }

    #[test]
    fn mixing_in_weight_form_equals_mixing_the_absorption() {
        let base = [0.3, 0.5, 1.1];
        for before in [
            [0.0, 0.0, 0.0, 0.0],
            [2.0, 1.0, 0.2, 0.4],
            [0.1, 0.2, 0.3, 1.0],
        ] {
            for a in [0.0, 0.25, 1.0] {
                let target = [1.5, 0.05, 0.7];
                let got = effective(base, mix_toward(before, target, a));
                let e = effective(base, before);
                for c in 0..3 {
                    let want = e[c] + a * (target[c] - e[c]);
                    assert!((got[c] - want).abs() < 1e-6, "{got:?} {want}");
                }
            }
        }
    }

    #[test]
    fn a_stroke_saturates_at_its_strength_and_undoes_exactly() {
        let base = vec![[0.4, 0.6, 1.0]; 4];
        let mut layer = vec![[0.0; 4]; 4];
        let brush = Brush {
            strength: 0.5,
            ..Default::default()
        };
        // Ten overlapping dabs at 0.5 leave the point half way, not at the dye.
        let dab: &[Touch] = &[(1, 0.5), (2, 0.25)];
        let s = run(&brush, &[dab; 10], &mut layer, &base);
        let e = effective(base[1], layer[1]);
        for c in 0..3 {
            let want = base[1][c] + 0.5 * (brush.dye[c] - base[1][c]);
            assert!((e[c] - want).abs() < 1e-6);
        }
        assert_eq!(layer[0], [0.0; 4], "outside the dab");
        assert_eq!(layer[3], [0.0; 4]);
        let mut delta = s.finish(&layer).expect("a change");
        assert_eq!(delta.indices, vec![1, 2]);
        let painted = layer.clone();
        delta.swap(&mut layer);
        assert_eq!(layer, vec![[0.0; 4]; 4], "undo is exact");
        delta.swap(&mut layer);
        assert_eq!(layer, painted, "redo is exact");
        assert_eq!(delta.bytes(), 2 * 20);
    }

    #[test]
    fn erase_darken_lighten_and_blur_move_the_right_way() {
        let base = vec![[0.4, 0.6, 1.0]; 3];
        let lum = |x: [f32; 3]| x[0] + x[1] + x[2];
        let full = |mode| Brush {
            strength: 1.0,
            mode,
            ..Default::default()
        };
        let mut layer = vec![[0.0; 4]; 3];
        run(&full(PaintMode::Dye), &[&[(1, 1.0)]], &mut layer, &base);
        run(&full(PaintMode::Erase), &[&[(1, 1.0)]], &mut layer, &base);
        assert_eq!(effective(base[1], layer[1]), base[1]);
        run(&full(PaintMode::Darken), &[&[(1, 1.0)]], &mut layer, &base);
        assert!(lum(effective(base[1], layer[1])) > lum(base[1]) + 2.0);
        let mut layer = vec![[0.0; 4]; 3];
        run(&full(PaintMode::Lighten), &[&[(1, 1.0)]], &mut layer, &base);
        let e = effective(base[1], layer[1]);
        assert!((e[2] - LIGHTEN_FACTOR * base[1][2]).abs() < 1e-6);
        // Blur pulls a dyed point toward its undyed neighbours.
        let mut layer = vec![[0.0; 4]; 3];
        run(&full(PaintMode::Dye), &[&[(1, 1.0)]], &mut layer, &base);
        let dyed = effective(base[1], layer[1]);
        run(
            &full(PaintMode::Blur),
            &[&[(0, 1.0), (1, 1.0), (2, 1.0)]],
            &mut layer,
            &base,
        );
        let blurred = effective(base[1], layer[1]);
        assert!((blurred[0] - base[1][0]).abs() < (dyed[0] - base[1][0]).abs());
    }

    #[test]
    fn a_dab_over_a_layer_gives_the_delta_the_layer_itself_gets() {
        let base = vec![[0.4, 0.6, 1.0]; 5];
        let mut direct = vec![[0.0; 4]; 5];
        direct[2] = [1.0, 0.2, 0.1, 0.5];
        let brush = Brush {
            strength: 0.7,
            mode: PaintMode::Blur,
            ..Default::default()
        };
        let under: &[Touch] = &[(1, 0.6), (2, 1.0), (3, 0.3)];
        let before = direct.clone();
        let mut over = DabLayer::new(&before);
        let changed = Stroke::new().dab(&brush, under, &mut over, &base, |_| 0..5, [0.4, 0.8, 1.6]);
        let mut delta = over.into_delta().expect("a change");
        assert_eq!(delta.indices, changed);
        let changed_direct = Stroke::new().dab(
            &brush,
            under,
            &mut direct[..],
            &base,
            |_| 0..5,
            [0.4, 0.8, 1.6],
        );
        assert_eq!(changed, changed_direct);
        let mut layer = before.clone();
        delta.swap(&mut layer);
        assert_eq!(layer, direct, "the delta is the dab, bit for bit");
        // Undo deltas merge keeping each point's earliest value.
        let mut first = PaintDelta {
            indices: vec![1, 4],
            values: vec![[1.0; 4], [4.0; 4]],
        };
        first.keep_earliest(PaintDelta {
            indices: vec![0, 1, 2, 5],
            values: vec![[0.5; 4], [9.0; 4], [2.0; 4], [5.0; 4]],
        });
        assert_eq!(first.indices, vec![0, 1, 2, 4, 5]);
        assert_eq!(
            first.values,
            vec![[0.5; 4], [1.0; 4], [2.0; 4], [4.0; 4], [5.0; 4]]
        );
        first.retain_differing(&[[0.5; 4], [0.0; 4], [2.0; 4], [0.0; 4], [0.0; 4], [5.0; 4]]);
        assert_eq!(first.indices, vec![1, 4]);
    }

    #[test]
    fn falloffs_and_the_mask() {
        for f in Falloff::ALL {
            assert_eq!(f.weight(0.0), 1.0);
            assert!(f.weight(1.0).abs() < 1e-6 || f == Falloff::Constant);
            assert_eq!(f.weight(1.01), 0.0);
        }
        let b = Brush {
            mask: Some([0.0, 0.3, 0.1]),
            ..Default::default()
        };
        assert_eq!(b.mask_weight(0.0), 1.0);
        assert_eq!(b.mask_weight(0.3), 1.0);
        assert!((b.mask_weight(0.35) - 0.5).abs() < 1e-6);
        assert_eq!(b.mask_weight(0.5), 0.0);
    }
}
