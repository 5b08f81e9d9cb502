//! strandlight: physically based hair appearance editing under environment lighting
//! (Marschner et al. 2003 scattering in the circular-Gaussian form of Xu et al. 2011).

// RGB loops index several per-channel arrays in lockstep (`for c in 0..3`); indices read better there.
#![allow(clippy::needless_range_loop)]

pub mod colour;
pub mod editor;
pub mod envmap;
pub mod files;
pub mod gpu;
pub mod hair;
pub mod jobs;
pub mod live;
pub mod paint;
pub mod render;
pub mod scattering;
pub mod session;
pub mod shadow;
