//! USD: curves in from any stage (`read`), the painted groom out in Unreal's and Blender's
//! conventions (`write`).

pub mod isolate;
pub mod read;
pub mod write;

pub use read::{CurveSelection, read_usd};
pub use write::write_usda;
