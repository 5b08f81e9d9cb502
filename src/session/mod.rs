//! The session model the editor and the CLI share: what defines a picture ([`Session`]), edits as data
//! with undo/redo ([`Edit`], [`History`]), session files with atomic writes, autosave and recovery
//! ([`autosave`]), and scene assembly.

pub mod assemble;
pub mod autosave;
pub mod edit;
pub mod export_hair;
pub mod history;
pub mod io;
pub mod model;

pub use assemble::{AssembleError, Scene};
pub use autosave::{Autosave, AutosaveError};
pub use edit::{Edit, EditKind, apply};
pub use history::History;
pub use io::SessionError;
pub use model::{
    Absorption, EnvironmentSource, HairSource, Look, OccluderOptions, RenderOptions,
    SESSION_VERSION, Session, ViewCamera,
};
