//! Edits as data (Blender's operators): the editor's panels emit [`Edit`] values; one [`apply`] changes the
//! session and returns the edit that undoes it. Undo/redo, autosave and the tests replay the same values.
//! Camera moves are not edits (they are saved with the session but not undone).

use super::model::{EnvironmentSource, HairSource, Look, OccluderOptions, RenderOptions, Session};
use crate::paint::{PaintDelta, SharedLayer};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// One change of the session. Each carries the new value of what it changes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Edit {
    /// The whole hair look (a slider changes one field of it).
    Look(Box<Look>),
    /// The environment's turn about +Y, degrees (no refit).
    EnvYaw(f64),
    Render(RenderOptions),
    Hair(HairSource),
    Environment(Box<EnvironmentSource>),
    /// A paint stroke's points and the layer values they take (applying swaps them with the
    /// layer's: the inverse holds the values they had).
    Paint(Box<PaintDelta>),
    /// The whole paint layer and the file it is saved to (clearing it; undoing a stroke that made
    /// the layer).
    PaintLayer(Box<(Option<SharedLayer>, Option<PathBuf>)>),
    /// The head (the occluder): shown or not, its mesh file, its albedo.
    Occluder(Box<OccluderOptions>),
}

/// What an edit touches: consecutive edits of the same kind during one gesture (a slider drag) merge
/// into one undo step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EditKind {
    Look,
    EnvYaw,
    Render,
    Hair,
    Environment,
    Paint,
    PaintLayer,
    Occluder,
}

impl EditKind {
    /// Whether an edit of this kind, during a gesture whose step is of kind `step`, belongs to that
    /// step: one of the same kind, or a paint stroke's dabs after the dab that made the layer (the
    /// step's undo removes the whole layer).
    pub fn extends(self, step: EditKind) -> bool {
        self == step || (self == EditKind::Paint && step == EditKind::PaintLayer)
    }
}

impl Edit {
    pub fn kind(&self) -> EditKind {
        match self {
            Edit::Look(_) => EditKind::Look,
            Edit::EnvYaw(_) => EditKind::EnvYaw,
            Edit::Render(_) => EditKind::Render,
            Edit::Hair(_) => EditKind::Hair,
            Edit::Environment(_) => EditKind::Environment,
            Edit::Paint(_) => EditKind::Paint,
            Edit::PaintLayer(_) => EditKind::PaintLayer,
            Edit::Occluder(_) => EditKind::Occluder,
        }
    }

    /// A short name for menus and the status bar.
    pub fn label(&self) -> &'static str {
        match self {
            Edit::Look(_) => "look",
            Edit::EnvYaw(_) => "environment yaw",
            Edit::Render(_) => "render settings",
            Edit::Hair(_) => "hair",
            Edit::Environment(_) => "environment",
            Edit::Paint(_) => "paint stroke",
            Edit::PaintLayer(_) => "paint layer",
            Edit::Occluder(_) => "head",
        }
    }

    /// Memory the edit holds, bytes (the undo history's budget).
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Edit>()
            + match self {
                Edit::Paint(d) => d.bytes(),
                Edit::PaintLayer(l) => l.0.as_ref().map_or(0, |l| 16 * l.get().points.len()),
                Edit::Look(_) => std::mem::size_of::<Look>(),
                Edit::Environment(e) => match e.as_ref() {
                    EnvironmentSource::File {
                        fitted: Some(f), ..
                    } => std::mem::size_of_val(f.lights.as_slice()) + 256,
                    _ => 256,
                },
                _ => 0,
            }
    }
}

/// Applies `edit` to `session`; returns the edit that restores the previous state.
pub fn apply(session: &mut Session, edit: Edit) -> Edit {
    match edit {
        Edit::Look(look) => Edit::Look(Box::new(std::mem::replace(&mut session.look, *look))),
        Edit::EnvYaw(yaw) => Edit::EnvYaw(std::mem::replace(&mut session.env_yaw, yaw)),
        Edit::Render(r) => Edit::Render(std::mem::replace(&mut session.render, r)),
        Edit::Hair(h) => Edit::Hair(std::mem::replace(&mut session.hair, h)),
        Edit::Environment(e) => {
            Edit::Environment(Box::new(std::mem::replace(&mut session.environment, *e)))
        }
        Edit::Paint(mut d) => {
            if let Some(layer) = &mut session.paint_layer
                && d.indices
                    .iter()
                    .all(|&i| (i as usize) < layer.get().points.len())
            {
                d.swap(&mut layer.make_mut().points);
            }
            Edit::Paint(d)
        }
        Edit::Occluder(o) => Edit::Occluder(Box::new(std::mem::replace(&mut session.occluder, *o))),
        Edit::PaintLayer(l) => {
            let (layer, path) = *l;
            Edit::PaintLayer(Box::new((
                std::mem::replace(&mut session.paint_layer, layer),
                std::mem::replace(&mut session.paint, path),
            )))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scattering::Preset;

    #[test]
    fn an_edit_and_its_inverse_restore_the_session() {
        let start = Session::default();
        let mut s = start.clone();
        let inverse = apply(
            &mut s,
            Edit::Look(Box::new(Look::from_preset(Preset::Blond))),
        );
        assert_ne!(s, start);
        let redo = apply(&mut s, inverse);
        assert_eq!(s, start);
        apply(&mut s, redo);
        assert_eq!(s.look, Look::from_preset(Preset::Blond));
    }

    #[test]
    fn edits_serialise() {
        let e = Edit::EnvYaw(30.0);
        let text = serde_json::to_string(&e).unwrap();
        assert_eq!(serde_json::from_str::<Edit>(&text).unwrap(), e);
    }
}
