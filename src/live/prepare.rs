//! What a session's scene needs before its renderer is made, computed off the UI thread: the
//! absorption per point with the session's paint over it, and the look's tables.

use crate::hair::Hair;
use crate::paint::SharedLayer;
use crate::paint::brush::effective;
use crate::render::HairLook;
use crate::render::renderer::{ParamTables, build_tables};
use crate::session::assemble::{base_absorption, mean_absorption, renderer_look};
use crate::session::{AssembleError, Session};

/// What a scene needs computed from the session and the hair before the renderer is built: the
/// per-point absorption, the look in the renderer's form and its tables (all CPU work, done on the
/// loading worker).
pub struct Prepared {
    pub sigma_a: Vec<[f32; 3]>,
    /// The look's absorption before the paint (the brush mixes toward and away from it).
    pub base_sigma_a: Vec<[f32; 3]>,
    pub look: HairLook,
    pub tables: ParamTables,
    /// The session's paint could not be shown (a layer made for another hair, an unreadable file).
    pub warning: Option<String>,
}

/// Computes [`Prepared`] (off the UI thread).
pub fn prepare(session: &Session, hair: &Hair) -> Result<Prepared, AssembleError> {
    let base_sigma_a = base_absorption(&session.look, hair)?;
    let (layer, warning) = paint_for(session, hair, &mut None);
    let sigma_a = painted(&base_sigma_a, layer.as_ref());
    let look = renderer_look(&session.look, mean_absorption(&sigma_a));
    let tables = build_tables(&look.params, None);
    Ok(Prepared {
        sigma_a,
        base_sigma_a,
        look,
        tables,
        warning,
    })
}

/// The session's paint for this hair: the layer in memory, else its file. A layer made for another
/// hair is left out with a warning (the session keeps it: undoing the hair change brings it back).
pub fn paint_for(
    session: &Session,
    hair: &Hair,
    file: &mut PaintFileCache,
) -> (Option<SharedLayer>, Option<String>) {
    let (points, strands) = (hair.point_count(), hair.strand_count());
    let layer = match (&session.paint_layer, &session.paint) {
        (Some(l), _) => l.clone(),
        (None, Some(path)) => {
            // Read once per file (a colour drag asks every frame).
            if file.as_ref().is_none_or(|(p, _)| p != path) {
                let read = crate::paint::PaintLayer::read(path)
                    .map(SharedLayer::new)
                    .map_err(|e| format!("{e}; the hair is shown unpainted"));
                *file = Some((path.clone(), read));
            }
            match file.as_ref().map(|(_, r)| r.clone()) {
                Some(Ok(l)) => l,
                Some(Err(e)) => return (None, Some(e)),
                None => return (None, None),
            }
        }
        (None, None) => return (None, None),
    };
    if layer.get().fits(points, strands) {
        (Some(layer), None)
    } else {
        let l = layer.get();
        let text = format!(
            "the paint layer was painted on {} points in {} strands, this hair has {points} points in {strands} strands: it is not shown",
            l.points.len(),
            l.strand_count
        );
        (None, Some(text))
    }
}

/// The paint file last read for a session without a layer in memory, and what it gave.
pub type PaintFileCache = Option<(std::path::PathBuf, Result<SharedLayer, String>)>;

/// Each point's absorption: the base with the layer over it.
pub fn painted(base: &[[f32; 3]], layer: Option<&SharedLayer>) -> Vec<[f32; 3]> {
    match layer {
        Some(l) => base
            .iter()
            .zip(&l.get().points)
            .map(|(b, v)| effective(*b, *v))
            .collect(),
        None => base.to_vec(),
    }
}

/// What identifies the session's paint: its file and the revision of the layer in memory.
pub(super) fn paint_key(session: &Session) -> (Option<std::path::PathBuf>, Option<u64>) {
    match &session.paint_layer {
        // The layer in memory is the paint, whatever file it was saved to.
        Some(l) => (None, Some(l.revision())),
        None => (session.paint.clone(), None),
    }
}
