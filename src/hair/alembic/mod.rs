//! Alembic: the Ogawa container (`ogawa`) and the curves in it (`read`).

pub mod ogawa;
pub mod read;

pub use read::read_alembic;
