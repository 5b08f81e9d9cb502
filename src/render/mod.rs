//! The hair renderer (Xu et al. 2011 Sec. 5 on wgpu), shared by `strandlight render`, `bench` and the
//! editor. Its rooms follow the pipeline:
//! - [`renderer`]: the facade the front ends drive (resources for one hairstyle, updated in place);
//! - [`passes`]: the GPU passes of a frame, in order;
//! - [`refine`]: progressive refinement (which bounded unit next, its cost model, previews, repaints);
//! - [`reference`]: the CPU twins and reference modes (shading, A-buffer, path tracer);
//! - camera, frame read-back and output, display transform, scenes, tiled stills, pass timing.

pub mod camera;
pub mod display;
pub mod frame;
pub mod passes;
pub mod reference;
pub mod refine;
pub mod renderer;
pub mod scene;
pub mod tiled;
pub mod timing;

pub use camera::Camera;
pub use frame::Frame;
pub use renderer::{HairLook, RenderError, RenderSettings, Renderer};
