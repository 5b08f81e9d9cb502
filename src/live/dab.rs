//! A brush dab on the live scene: the points under the dab found by the view's picker, the session's
//! paint layer changed there (made when the session had none), and only those points' absorption sent
//! to the renderer, which repaints what they change. The editor's brush and `bench` paint through it.

use super::driver::{LiveDriver, LiveError};
use crate::paint::brush::{Stroke, Touch, eumelanin_unit};
use crate::paint::{Brush, PaintLayer, SharedLayer};
use crate::session::Session;

/// What a call of [`LiveDriver::dab`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dab {
    /// The scene shown is not the session's yet (a hair change loading): nothing painted.
    SceneLoading,
    /// The view has no picker yet (its depth is not read back): nothing painted.
    Waiting,
    /// The dabs touched no hair.
    Missed,
    /// Painted: the points changed (none where the stroke has saturated), and whether the session had
    /// no paint layer before (this dab made it).
    Painted { points: usize, created_layer: bool },
}

#[derive(Debug, thiserror::Error)]
pub enum DabError {
    #[error("{0}: painting would replace it; Clear paint first to start anew")]
    UnreadablePaint(String),
    #[error(
        "the paint layer was painted on another hair: clear it (brush panel) to paint this one"
    )]
    OtherHair,
    #[error(transparent)]
    Live(#[from] LiveError),
}

impl LiveDriver {
    /// Dabs `brush` at `centres` (render pixels) with `radius` (render pixels) and `pressure`
    /// (0 to 1) into `session`'s paint layer as part of `stroke`.
    pub fn dab(
        &mut self,
        session: &mut Session,
        stroke: &mut Stroke,
        brush: &Brush,
        centres: &[[f32; 2]],
        radius: f32,
        pressure: f32,
    ) -> Result<Dab, DabError> {
        if self.needs_rebuild(session) {
            return Ok(Dab::SceneLoading);
        }
        let Some(picker) = self.picker() else {
            return Ok(Dab::Waiting);
        };
        let under: Vec<Vec<Touch>> = centres
            .iter()
            .map(|c| picker.dab(brush, *c, radius, pressure))
            .collect();
        if under.iter().all(Vec::is_empty) {
            return Ok(Dab::Missed);
        }
        let hair = self.hair.clone();
        let (points, strands) = (hair.point_count(), hair.strand_count());
        // A paint file the session names but that was not read (it failed to load): painting would
        // start an empty layer and the next save would replace the file.
        if session.paint_layer.is_none()
            && let Some(path) = &session.paint
        {
            let layer =
                PaintLayer::read(path).map_err(|e| DabError::UnreadablePaint(e.to_string()))?;
            session.paint_layer = Some(SharedLayer::new(layer));
        }
        let created_layer = session.paint_layer.is_none();
        let layer = session
            .paint_layer
            .get_or_insert_with(|| SharedLayer::new(PaintLayer::empty(points, strands)));
        if !layer.get().fits(points, strands) {
            return Err(DabError::OtherHair);
        }
        let mut changed: Vec<u32> = Vec::new();
        let layer_points = &mut layer.make_mut().points;
        for u in &under {
            changed.extend(stroke.dab(
                brush,
                u,
                layer_points,
                &self.base_sigma_a,
                |i| hair.strand_of_point(i),
                eumelanin_unit(),
            ));
        }
        changed.sort_unstable();
        changed.dedup();
        if changed.is_empty() {
            // A new revision with the same values: the renderer has them already.
            self.note_paint(session);
        } else {
            self.paint_points(session, &changed)?;
        }
        Ok(Dab::Painted {
            points: changed.len(),
            created_layer,
        })
    }
}
