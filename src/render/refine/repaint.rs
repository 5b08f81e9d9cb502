//! A brush dab's repaint: the segments at the points it changed (and the partners whose shared
//! multiple-scattering sample it joined or split) shaded again under every light batch, then their
//! rows gathered and resolved.

use super::Stage;
use crate::render::reference::shade::strand_partner;
use crate::render::renderer::Renderer;

/// A brush dab's repaint: the segments it shades again, and the dabs that came while it ran.
pub(in crate::render) struct RepaintState {
    /// The segments a planned repaint shades again (sorted), and the image rows they cover.
    pub(in crate::render) segments: Vec<u32>,
    pub(in crate::render) rows: std::ops::Range<u32>,
    /// Segments of dabs that came while a repaint was under way: repainted after it.
    pub(in crate::render) pending: Vec<u32>,
    /// Whether each pair of segments 2k, 2k + 1 shares its multiple-scattering sample (index k:
    /// [`crate::render::reference::shade::ms_paired`] at the absorption on the GPU), kept to notice a dab that changes it.
    pub(in crate::render) ms_pairs: Vec<bool>,
    /// The pairs (their even segments) whose sharing dabs changed since the last repaint started:
    /// their partners' multiple scattering moved ([`Renderer::repaint_points`]).
    pub(in crate::render) flips_pending: Vec<u32>,
    /// The pairs whose sharing changed for the repaint under way (sorted even segments).
    pub(in crate::render) flips: Vec<u32>,
}

impl Renderer {
    /// A brush dab on an image converged by segment: the segments that join the changed points
    /// `changed` are shaded again under every light, with the multiple scattering of their partners
    /// whose pair the dab joined or split ([`Renderer::repaint_partner`])
    /// ([`crate::render::refine::WorkUnit::Repaint`] units, light batch by light batch, each in parts sized to the budget),
    /// and the image is gathered from the segments ([`crate::render::refine::WorkUnit::RepaintGather`] bands), in place of
    /// a restart. The dab shows at full resolution after work on its segments alone; every other
    /// segment's radiance depends on its own points (and its pair's sharing, whose changes are
    /// shaded here) only and stays.
    /// (The volume and grid follow later: [`Renderer::rebuild_stale_volume`].) False, nothing
    /// planned, when the image is not converged by segment: the caller restarts.
    pub fn repaint_points(&mut self, changed: &[u32]) -> bool {
        let r = &self.refinement;
        let ready = self.by_segment
            && self.view.segment_targets.is_some()
            && self.stale.visibility_valid
            && !r.preview_state.owed
            && matches!(
                r.stage,
                Stage::Converged
                    | Stage::PreparePreview { .. }
                    | Stage::Repaint { .. }
                    | Stage::RepaintGather { .. }
            )
            && self.passes.shading_pass.frame_batches().next().is_some();
        if !ready {
            return false;
        }
        let mut segments: Vec<u32> = changed
            .iter()
            .flat_map(|&i| self.segments_at_point(i))
            .collect();
        if segments.is_empty() {
            return true;
        }
        // The repaint writes its segments' single scattering: nothing is kept across it.
        self.stale.single_kept = false;
        match self.refinement.stage {
            Stage::Repaint { batch, first } if batch > 0 || first > 0 => {
                // Under way: these follow once it ends (starting it again at every dab would never
                // let it finish while the pointer moves).
                self.repaint.pending.extend(segments);
            }
            Stage::RepaintGather { .. } => self.repaint.pending.extend(segments),
            stage => {
                // Converged, or planned and not started: one repaint of them all.
                if !stage.image_converged() {
                    segments.append(&mut self.repaint.segments);
                    self.repaint.flips_pending.append(&mut self.repaint.flips);
                }
                segments.append(&mut self.repaint.pending);
                self.start_repaint(segments);
            }
        }
        true
    }

    /// Plans the repaint of `segments` from the first light batch.
    pub(super) fn start_repaint(&mut self, mut segments: Vec<u32>) {
        segments.sort_unstable();
        segments.dedup();
        let mut flips = std::mem::take(&mut self.repaint.flips_pending);
        flips.sort_unstable();
        flips.dedup();
        self.repaint.flips = flips;
        // With multiple scattering the partners' is shaded again too where the paint moved their
        // pair's sample, so their rows are gathered.
        let with_partners: Vec<u32> = segments
            .iter()
            .flat_map(|&s| std::iter::once(s).chain(self.repaint_partner(s)))
            .collect();
        self.repaint.rows = self.rows_covered(&with_partners);
        self.repaint.segments = segments;
        self.refinement.stage = Stage::Repaint { batch: 0, first: 0 };
    }

    /// The segment whose multiple scattering a repaint of segment `s` shades too: its
    /// [`strand_partner`], with multiple scattering on, where the paint joined or split their pair
    /// ([`Renderer::repaint_flips`]: the partner's sample moved between its own midpoint and the
    /// pair's shared point). A pair that stays joined moves its sample only when its shared point's
    /// absorption changes, and both its segments are repainted then; one that stays split keeps
    /// each segment's own.
    pub(super) fn repaint_partner(&self, s: u32) -> Option<u32> {
        if !self.settings.multiple_scattering
            || self.repaint.flips.binary_search(&(s & !1)).is_err()
        {
            return None;
        }
        strand_partner(&self.scene.segment_first, s)
    }

    /// The image rows where `segments` may leave fragments: their ends' projections, widened by
    /// the ribbon's half width (at least `min_width_px`) and a pixel; every row when an end lies
    /// behind the eye or the frame is a tile.
    pub(super) fn rows_covered(&self, segments: &[u32]) -> std::ops::Range<u32> {
        let height = self.settings.height;
        let cam = self.view_camera();
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for &k in segments {
            let first = self.scene.segment_first[k as usize] as usize;
            for p in &self.scene.point_data[first..first + 2] {
                let at = glam::Vec3::new(p[0], p[1], p[2]);
                let Some(q) =
                    crate::render::camera::project(&cam, at).filter(|_| self.view.tile.is_none())
                else {
                    return 0..height;
                };
                let width = (p[3] / (q.depth * cam.pixel_angle)).max(cam.min_width_px);
                lo = lo.min(q.y - 0.5 * width - 1.0);
                hi = hi.max(q.y + 0.5 * width + 1.0);
            }
        }
        let clamp = |y: f32| (y.max(0.0) as u32).min(height);
        clamp(lo.floor())..clamp(hi.ceil())
    }

    /// Whether the refinement under way shades multiple scattering alone, keeping the segments'
    /// single scattering ([`Renderer::set_tables`] after the image converged).
    pub fn keeps_single_scattering(&self) -> bool {
        self.stale.single_kept && !self.refinement.stage.image_converged()
    }
}
