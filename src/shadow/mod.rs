//! Self-shadowing of hair by hair: the fiber-density volume and the transmittance it gives each light.

pub mod cone;
pub mod fiber_density;
pub mod fiber_grid;
pub mod forward;
pub mod grid;
pub mod ray_shooting;
pub mod sample_packing;
pub mod solid;
pub mod sweep;
pub mod voxels;

pub use cone::DensityPyramid;
pub use fiber_density::FiberDensity;
