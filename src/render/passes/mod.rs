//! The GPU passes of a frame, in the order they run: the occluder (the head) drawn for depth, the
//! per-light shadow grid, visibility into the K-buffer, shading per light batch (per fragment or per
//! segment), the resolve into the frame's targets, and the background behind it.

pub mod background;
pub mod batch;
pub mod kbuffer;
pub mod occluder;
pub mod resolve;
pub mod row_segments;
pub mod segment_shading;
pub mod shading;
pub mod shadow_grid;
pub mod targets;
pub mod visibility;
