//! A brush dab on the live scene: the points under the dab found by the view's picker, the change of
//! the session's paint layer there as an edit (a new layer when the session had none), and only those
//! points' absorption sent to the renderer, which repaints what they change. The editor's brush (which
//! applies the edit through its history) and `bench` paint through it.

use super::driver::{LiveDriver, LiveError};
use crate::paint::brush::{DabLayer, Stroke, Touch, eumelanin_unit};
use crate::paint::{Brush, PaintLayer, SharedLayer};
use crate::session::{Edit, Session, apply};

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

/// A dab as an edit of the session: what it did, and the edit that makes its change (None when it
/// changed nothing) with the points that edit changes.
pub struct DabEdit {
    pub dab: Dab,
    pub edit: Option<Edit>,
    pub changed: Vec<u32>,
}

impl LiveDriver {
    /// Dabs `brush` at `centres` (render pixels) with `radius` (render pixels) and `pressure`
    /// (0 to 1) into `session`'s paint layer as part of `stroke`: the edit applied through
    /// [`crate::session::apply`], and the changed points sent to the renderer.
    pub fn dab(
        &mut self,
        session: &mut Session,
        stroke: &mut Stroke,
        brush: &Brush,
        centres: &[[f32; 2]],
        radius: f32,
        pressure: f32,
    ) -> Result<Dab, DabError> {
        let d = self.dab_edit(session, stroke, brush, centres, radius, pressure)?;
        if let Some(edit) = d.edit {
            apply(session, edit);
            self.paint_points(session, &d.changed)?;
        }
        Ok(d.dab)
    }

    /// The dab of [`LiveDriver::dab`] as an edit, the session left as it is: a [`Edit::Paint`] of
    /// the changed points, or, when the session has no paint layer in memory, a
    /// [`Edit::PaintLayer`] with the new layer (undoing it removes the layer again). Once the
    /// caller has applied the edit, [`LiveDriver::paint_points`] sends the changed points.
    pub fn dab_edit(
        &mut self,
        session: &Session,
        stroke: &mut Stroke,
        brush: &Brush,
        centres: &[[f32; 2]],
        radius: f32,
        pressure: f32,
    ) -> Result<DabEdit, DabError> {
        let nothing = |dab| DabEdit {
            dab,
            edit: None,
            changed: Vec::new(),
        };
        if self.needs_rebuild(session) {
            return Ok(nothing(Dab::SceneLoading));
        }
        let Some(picker) = self.picker() else {
            return Ok(nothing(Dab::Waiting));
        };
        let under: Vec<Vec<Touch>> = centres
            .iter()
            .map(|c| picker.dab(brush, *c, radius, pressure))
            .collect();
        if under.iter().all(Vec::is_empty) {
            return Ok(nothing(Dab::Missed));
        }
        let hair = self.hair.clone();
        let (points, strands) = (hair.point_count(), hair.strand_count());
        // No layer in memory: the session's paint file (one that was not read when the session
        // opened: painting over nothing would replace it at the next save), else an empty layer.
        let mut made = None;
        let layer: &PaintLayer = match &session.paint_layer {
            Some(l) => l.get(),
            None => made.insert(match &session.paint {
                Some(path) => {
                    PaintLayer::read(path).map_err(|e| DabError::UnreadablePaint(e.to_string()))?
                }
                None => PaintLayer::empty(points, strands),
            }),
        };
        if !layer.fits(points, strands) {
            return Err(DabError::OtherHair);
        }
        let mut over = DabLayer::new(&layer.points);
        for u in &under {
            stroke.dab(
                brush,
                u,
                &mut over,
                &self.paint.base_sigma_a,
                |i| hair.strand_of_point(i),
                eumelanin_unit(),
            );
        }
        let Some(mut delta) = over.into_delta() else {
            return Ok(nothing(Dab::Painted {
                points: 0,
                created_layer: false,
            }));
        };
        let changed = delta.indices.clone();
        let created_layer = made.is_some();
        let edit = match made {
            Some(mut layer) => {
                delta.swap(&mut layer.points);
                Edit::PaintLayer(Box::new((
                    Some(SharedLayer::new(layer)),
                    session.paint.clone(),
                )))
            }
            None => Edit::Paint(Box::new(delta)),
        };
        Ok(DabEdit {
            dab: Dab::Painted {
                points: changed.len(),
                created_layer,
            },
            edit: Some(edit),
            changed,
        })
    }
}
