//! The hair renderer (Xu et al. 2011 Sec. 5 on wgpu): visibility, per-SRBF shading batches with
//! self-shadowing, resolve; shared by `strandlight render`, `bench` and the editor.

pub mod background;
pub mod camera;
pub mod display;
pub mod frame;
pub mod kbuffer;
pub mod occluder;
pub mod path_trace;
pub mod preview;
pub mod progressive;
pub mod reference;
pub mod reference_lights;
pub mod renderer;
pub mod resolve;
pub mod row_segments;
pub mod scene;
pub mod segment_shading;
pub mod shade;
pub mod shading;
pub mod shadow_grid;
pub mod table_cache;
pub mod targets;
pub mod tiled;
pub mod timing;
pub mod visibility;

pub use camera::Camera;
pub use frame::Frame;
pub use renderer::{HairLook, RenderError, RenderSettings, Renderer};
