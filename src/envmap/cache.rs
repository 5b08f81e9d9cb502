//! Fits cached by content: a second load of the same environment with the same options is instant.
//! Cache folder: `$STRANDLIGHT_CACHE`, else `$XDG_CACHE_HOME/strandlight`, else `~/.cache/strandlight`.

use super::fit::{FitOptions, FitProgress, fit_srbf};
use super::image::{EnvError, Sanitised, decode_env};
use super::srbf::SrbfSet;
use std::path::{Path, PathBuf};

/// Bumped whenever the fit algorithm changes, so stale cache entries are ignored.
pub const FIT_ALGORITHM_VERSION: u32 = 1;

pub fn cache_dir() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("STRANDLIGHT_CACHE") {
        return Some(PathBuf::from(p));
    }
    if let Some(p) = std::env::var_os("XDG_CACHE_HOME") {
        return Some(PathBuf::from(p).join("strandlight"));
    }
    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/strandlight"))
}

#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error(transparent)]
    Env(#[from] EnvError),
    #[error("{path}: {message}")]
    Fit { path: PathBuf, message: String },
}

pub struct CachedFit {
    pub set: SrbfSet,
    pub from_cache: bool,
    pub sanitised: Sanitised,
}

/// Loads and fits `path`, or returns the cached fit of identical bytes and options.
pub fn fit_file(
    path: &Path,
    options: &FitOptions,
    use_cache: bool,
    progress: impl Fn(FitProgress) + Send + Sync + 'static,
) -> Result<CachedFit, FitError> {
    let bytes = std::fs::read(path).map_err(|source| EnvError::Io {
        path: path.into(),
        source,
    })?;
    let hash = blake3::hash(&bytes).to_hex().to_string();
    let key = format!(
        "{hash}-n{}-w{}-i{}-v{FIT_ALGORITHM_VERSION}.srbf.json",
        options.lights, options.fit_width, options.max_iters
    );
    let cached = cache_dir().map(|d| d.join(&key));
    if use_cache
        && let Some(c) = &cached
        && let Ok(set) = SrbfSet::read(c)
    {
        return Ok(CachedFit {
            set,
            from_cache: true,
            sanitised: Sanitised::default(),
        });
    }
    let (env, sanitised) = decode_env(&bytes, path)?;
    let mut set = fit_srbf(&env, options, progress).map_err(|message| FitError::Fit {
        path: path.into(),
        message,
    })?;
    set.source = path.file_name().map(|n| n.to_string_lossy().into_owned());
    set.source_hash = Some(hash);
    if use_cache && let Some(c) = &cached {
        // A cache that cannot be written is not an error: the fit is still returned.
        if c.parent()
            .is_some_and(|d| std::fs::create_dir_all(d).is_ok())
        {
            let _ = set.write(c);
        }
    }
    Ok(CachedFit {
        set,
        from_cache: false,
        sanitised,
    })
}
