//! Errors from reading and writing hair and mesh files. Every message names the file.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum HairError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file's contents are not what its format requires.
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    #[error(
        "{path}: unsupported file type (expected .hair, .tfx, .gltf, .glb, .usd, .usda, .usdc, .usdz, .abc or .obj)"
    )]
    UnknownType { path: PathBuf },
}

impl HairError {
    pub fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::Format {
            path: path.into(),
            message: message.into(),
        }
    }
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}

/// Upper bound on points in one hairstyle (Yu 2012's largest scene has 6.8M segments): anything
/// beyond is refused before allocating.
pub const MAX_POINTS: u64 = 50_000_000;
