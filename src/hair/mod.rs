//! Hair geometry: file formats in and out, the in-memory representation, normalisation to world
//! space (centimetres, +Y up), and procedural hairstyles.

pub mod alembic;
pub mod bytes;
pub mod curve_file;
pub mod curves;
pub mod cyhair;
pub mod error;
pub mod gltf_io;
pub mod load;
pub mod mesh;
pub mod model;
pub mod normalize;
pub mod procedural;
pub mod tressfx;
pub mod usd;

pub use error::{HairError, MAX_POINTS};
pub use load::{LoadOptions, LoadedHair, load_hair, load_mesh};
pub use mesh::TriangleMesh;
pub use model::{Hair, RawStrand, Thickness};
