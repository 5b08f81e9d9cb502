//! GPU access through wgpu: headless device creation shared by the CLI, tests and (later) the editor.

pub mod context;

pub use context::{GpuContext, GpuError, GpuOptions};
