//! The live driver: a session shown as it is edited. [`LiveDriver`] tells the renderer what changed
//! in the session, hands over tables built on workers, plans and submits refinement units, reads the
//! view's depth back for the brush and repaints what a dab changed; [`LiveHandle`] runs it on its own
//! render thread so that refinement never waits for a UI frame. It knows no UI toolkit: the editor
//! wraps it (its texture in egui, repaint requests), and `bench` and the tests drive the same code.

pub mod dab;
pub mod driver;
pub mod jobs;
pub mod load;
pub mod picking;
pub mod prepare;
pub mod pump;
pub mod settings;
pub mod state;
pub mod tables;

pub use dab::{Dab, DabEdit, DabError};
pub use driver::{LiveDriver, LiveError};
pub use prepare::{Prepared, prepare};
pub use pump::LiveHandle;
pub use settings::{StepOutcome, ViewSettings};
