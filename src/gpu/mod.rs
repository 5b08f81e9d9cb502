//! GPU access through wgpu: device creation shared by the CLI, the tests and the editor.

pub mod context;
pub mod density_pyramid;
pub mod dual_eval;
pub mod fast_eval;
pub mod fiber_density;
pub mod forward;
pub mod shaders;

pub use context::{GpuContext, GpuError, GpuOptions};
