//! Spatially varying absorption (the dye): colour-to-absorption inversion, root-to-tip gradients,
//! per-strand variation, and the paint-layer file the editor will save and the CLI reads.

pub mod dye;
pub mod layer;

pub use dye::{AbsorptionSpec, sigma_a_from_colour};
pub use layer::{PaintLayer, PaintLayerError};
