//! Hair scattering maths: the exact Marschner model (reference) and the fast forms.

pub mod azimuthal_table;
pub mod circular_gaussian;
pub mod dual_response;
pub mod dual_terms;
pub mod fast_azimuthal;
pub mod fast_exact_azimuthal;
pub mod fast_params;
pub mod fast_response;
pub mod frame;
pub mod fresnel;
pub mod half_cells;
pub mod lut;
pub mod marschner;
pub mod numeric;
pub mod params;
pub mod reference;
pub mod srbf_reference;
pub mod tables;
pub mod tables_io;

pub use frame::{FiberAngles, FiberFrame, HalfAngles};
pub use marschner::{LobeValues, Rgb, scattering_s, scattering_s_p};
pub use params::{
    CausticModel, FresnelModel, HairParams, Lobe, LongitudinalModel, ModelVariant, Preset,
};
