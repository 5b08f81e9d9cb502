//! The A-buffer reference: every fragment of every pixel built on the CPU by brute force, sorted front
//! to back, and the K-buffer the GPU pass should keep from it ([`composite`]).

use super::ribbon::{fragment_depth, optical_depth, pixel_coverage, ribbon_quad};
use crate::render::camera::CameraUniform;
use crate::render::passes::kbuffer::{
    EXPAND_PX, Fragment, OPTICAL_DEPTH_SCALE, PixelFragments, Tail,
};
use glam::{Vec2, Vec4};
use rayon::prelude::*;

/// One fragment of the A-buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawFragment {
    pub segment: u32,
    pub depth: f32,
    pub opacity: f32,
}

impl RawFragment {
    /// The K-buffer's order: depth, then segment (the key's bits).
    fn key(&self) -> u64 {
        ((self.depth.to_bits() as u64) << 32) | self.segment as u64
    }
}

/// Every fragment of every pixel, sorted front to back (no occluder): the A-buffer.
pub struct ABuffer {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec<RawFragment>>,
}

/// The A-buffer of the segments (first points `segments` into `points`: xyz, diameter) seen by the
/// camera, by brute force on the CPU: every pixel of each ribbon's grown bounding box whose coverage
/// is positive.
pub fn abuffer(c: &CameraUniform, points: &[[f32; 4]], segments: &[u32]) -> ABuffer {
    let (w, h) = (c.size[0], c.size[1]);
    let per_segment: Vec<Vec<(u32, RawFragment)>> = segments
        .par_iter()
        .enumerate()
        .map(|(seg, &i0)| {
            let (a, b) = (
                Vec4::from(points[i0 as usize]),
                Vec4::from(points[i0 as usize + 1]),
            );
            let q = ribbon_quad(c, a, b);
            let mut out = Vec::new();
            if !q.valid {
                return out;
            }
            let grow = q.half_width.max_element() + EXPAND_PX;
            let lo = q.p0.min(q.p1) - Vec2::splat(grow);
            let hi = q.p0.max(q.p1) + Vec2::splat(grow);
            let x0 = lo.x.floor().max(0.0) as u32;
            let y0 = lo.y.floor().max(0.0) as u32;
            let x1 = (hi.x.ceil().max(0.0) as u32).min(w);
            let y1 = (hi.y.ceil().max(0.0) as u32).min(h);
            for y in y0..y1 {
                for x in x0..x1 {
                    let cover = pixel_coverage(&q, x, y);
                    if cover > 0.0 {
                        let depth = fragment_depth(c, a.truncate(), b.truncate(), x, y);
                        let f = RawFragment {
                            segment: seg as u32,
                            depth,
                            opacity: cover,
                        };
                        out.push((y * w + x, f));
                    }
                }
            }
            out
        })
        .collect();
    let mut pixels = vec![Vec::new(); w as usize * h as usize];
    for (p, f) in per_segment.into_iter().flatten() {
        pixels[p as usize].push(f);
    }
    pixels
        .par_iter_mut()
        .for_each(|l| l.sort_by_key(RawFragment::key));
    ABuffer {
        width: w,
        height: h,
        pixels,
    }
}

/// The composite of one pixel's fragments (sorted front to back) keeping `k` (twin of `composite`,
/// without an occluder): the k slots and the pixel's summary.
pub fn composite(list: &[RawFragment], k: usize, tail: Tail) -> (Vec<Fragment>, PixelFragments) {
    let mut slots = vec![Fragment::default(); k];
    let mut t = 1.0f32;
    let mut kept_alpha = 0.0f32;
    let mut kept = 0u32;
    let n = list.len().min(k);
    for (slot, f) in slots.iter_mut().zip(&list[..n]) {
        let a = f.opacity.min(1.0);
        kept += optical_depth(a);
        *slot = Fragment {
            id: f.segment + 1,
            weight: t * a,
        };
        kept_alpha += t * a;
        t *= 1.0 - a;
    }
    let all: u32 = list.iter().map(|f| optical_depth(f.opacity)).sum();
    if tail != Tail::Drop && n == k && k > 0 {
        let behind = (-(all.saturating_sub(kept) as f32) / OPTICAL_DEPTH_SCALE).exp();
        if tail == Tail::Fold || kept_alpha <= 0.0 {
            slots[n - 1].weight += t * (1.0 - behind);
        } else {
            let scale = 1.0 + t * (1.0 - behind) / kept_alpha;
            for f in &mut slots[..n] {
                f.weight *= scale;
            }
        }
        t *= behind;
    }
    let info = PixelFragments {
        alpha: 1.0 - t,
        occluder_transmittance: 1.0,
        depth: list.first().map_or(1e10, |f| f.depth),
        count: list.len() as f32,
    };
    (slots, info)
}

impl ABuffer {
    /// The K-buffer of every pixel from the A-buffer ([`composite`]): `k` slots per pixel, and the
    /// pixels' summaries.
    pub fn kbuffer(&self, k: usize, tail: Tail) -> (Vec<Fragment>, Vec<PixelFragments>) {
        let per: Vec<(Vec<Fragment>, PixelFragments)> = self
            .pixels
            .par_iter()
            .map(|l| composite(l, k, tail))
            .collect();
        let mut slots = Vec::with_capacity(per.len() * k);
        let mut info = Vec::with_capacity(per.len());
        for (s, i) in per {
            slots.extend(s);
            info.push(i);
        }
        (slots, info)
    }

    /// The most fragments any pixel holds.
    pub fn depth_complexity(&self) -> usize {
        self.pixels.iter().map(Vec::len).max().unwrap_or(0)
    }
}
