//! strandlight: physically based hair appearance editing under environment lighting
//! (Marschner et al. 2003 scattering in the circular-Gaussian form of Xu et al. 2011).

pub mod gpu;
pub mod hair;
pub mod scattering;
