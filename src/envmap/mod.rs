//! HDR environments: loading, the SRBF light fit, and the project's own generated environments.

pub mod cache;
pub mod direction;
pub mod fit;
pub mod image;
pub mod procedural;
pub mod srbf;

pub use fit::{FitOptions, FitProgress, fit_srbf};
pub use image::{EnvError, EnvMap, load_env};
pub use srbf::{SrbfLight, SrbfSet};
