//! Spatially varying absorption (the dye): colour-to-absorption inversion, root-to-tip gradients,
//! per-strand variation, the paint-layer file the editor saves and the CLI reads, and the brush
//! (what a dab touches and what a stroke does to the layer).

pub mod brush;
pub mod dye;
pub mod layer;
pub mod pick;

pub use brush::{Brush, DabLayer, PaintDelta, PaintMode, Stroke};
pub use dye::{AbsorptionSpec, sigma_a_from_colour};
pub use layer::{PaintLayer, PaintLayerError, SharedLayer};
