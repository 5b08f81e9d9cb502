//! Background jobs: the crate's [`crate::jobs::Job`], named here too because the driver's workers
//! (table builds, picking) are such jobs.

pub use crate::jobs::{Job, Wake};
