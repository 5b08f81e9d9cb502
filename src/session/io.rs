//! Session files (`.slsession`, versioned JSON) and atomic writes: a temporary file beside the target,
//! written, flushed to disk, then renamed over it, so a crash leaves the old file or the new one,
//! never half of either.

use super::model::{SESSION_VERSION, Session};
use crate::files::write_atomic;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    #[error("{path}: {message}")]
    Io { path: PathBuf, message: String },
    #[error("{path} is not a strandlight session: {message}")]
    Format { path: PathBuf, message: String },
    #[error(
        "{path} is a session of version {found}; this strandlight reads version {SESSION_VERSION}"
    )]
    Version { path: PathBuf, found: u32 },
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

impl Session {
    /// The session as pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self)
            .unwrap_or_else(|e| unreachable!("a session holds only serialisable plain data: {e}"))
    }

    /// Parses and validates a session; errors name `path`.
    pub fn from_json(text: &str, path: &Path) -> Result<Self, SessionError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| SessionError::Format {
                path: path.into(),
                message: e.to_string(),
            })?;
        let found = value.get("version").and_then(|v| v.as_u64());
        match found {
            Some(v) if v == SESSION_VERSION as u64 => {}
            Some(v) => {
                return Err(SessionError::Version {
                    path: path.into(),
                    found: v.min(u32::MAX as u64) as u32,
                });
            }
            None => {
                return Err(SessionError::Format {
                    path: path.into(),
                    message: "no \"version\" field".into(),
                });
            }
        }
        let session: Session = serde_json::from_value(value).map_err(|e| SessionError::Format {
            path: path.into(),
            message: e.to_string(),
        })?;
        session
            .validate()
            .map_err(|message| SessionError::Invalid {
                path: path.into(),
                message,
            })?;
        Ok(session)
    }

    pub fn read(path: &Path) -> Result<Self, SessionError> {
        let text = std::fs::read_to_string(path).map_err(|e| SessionError::Io {
            path: path.into(),
            message: format!("cannot read the session: {e}"),
        })?;
        Self::from_json(&text, path)
    }

    /// Saves atomically.
    pub fn write(&self, path: &Path) -> Result<(), SessionError> {
        write_atomic(path, self.to_json().as_bytes()).map_err(|e| SessionError::Io {
            path: path.into(),
            message: format!("cannot write the session: {e}"),
        })
    }

    /// Saves the session to `path` with its paint layer in memory beside it (`path` with the
    /// extension `.slpaint`, which `paint` then names; both written atomically, the layer first).
    pub fn save(&mut self, path: &Path) -> Result<(), SessionError> {
        let Some(layer) = &self.paint_layer else {
            return self.write(path);
        };
        let file = path.with_extension("slpaint");
        if file == path {
            return Err(SessionError::Invalid {
                path: path.into(),
                message: "a session cannot be saved as .slpaint (the paint layer's name)".into(),
            });
        }
        layer.get().write(&file).map_err(|e| SessionError::Io {
            path: file.clone(),
            message: format!("cannot write the paint layer: {e}"),
        })?;
        let before = self
            .paint
            .replace(std::path::absolute(&file).unwrap_or(file));
        let written = self.write(path);
        if written.is_err() {
            self.paint = before;
        }
        written
    }

    /// Reads the paint file the session names into memory (the editor paints on it); the session is
    /// unchanged when the file cannot be read.
    pub fn load_paint(&mut self) -> Result<(), crate::paint::PaintLayerError> {
        if self.paint_layer.is_none()
            && let Some(path) = &self.paint
        {
            self.paint_layer = Some(crate::paint::SharedLayer::new(
                crate::paint::PaintLayer::read(path)?,
            ));
        }
        Ok(())
    }

    /// Checks the values a file could get wrong.
    pub fn validate(&self) -> Result<(), String> {
        self.look.validate()?;
        self.occluder.validate()?;
        let r = &self.render;
        if !matches!(r.samples, 2 | 4) {
            return Err(format!("render samples must be 2 or 4, got {}", r.samples));
        }
        let most = crate::render::kbuffer::MAX_FRAGMENTS;
        if !(1..=most).contains(&r.fragments) {
            return Err(format!(
                "render fragments must be 1 to {most}, got {}",
                r.fragments
            ));
        }
        if r.width == 0 || r.height == 0 || r.width > 16384 || r.height > 16384 {
            return Err(format!(
                "render size {}x{} is out of range",
                r.width, r.height
            ));
        }
        if !r.exposure.is_finite() || !self.env_yaw.is_finite() {
            return Err("exposure and environment yaw must be finite".into());
        }
        if !(4..=512).contains(&r.volume_resolution)
            || !(2..=128).contains(&r.shadow_grid_resolution)
        {
            return Err(format!(
                "volume resolution lies in [4, 512] and shadow grid resolution in [2, 128], got {} and {}",
                r.volume_resolution, r.shadow_grid_resolution
            ));
        }
        if let super::model::EnvironmentSource::File { lights, .. } = &self.environment
            && !(1..=1024).contains(lights)
        {
            return Err(format!(
                "an environment is fitted with 1 to 1024 lights, got {lights}"
            ));
        }
        let c = &self.camera;
        if c.target.is_some_and(|t| t.iter().any(|v| !v.is_finite())) {
            return Err("the camera target must be finite".into());
        }
        if !(c.fov_y > 1.0 && c.fov_y < 170.0 && c.yaw.is_finite() && c.pitch.is_finite()) {
            return Err("the camera's field of view lies in (1, 170) degrees".into());
        }
        if let Some(d) = c.distance
            && !(d > 0.0 && d.is_finite())
        {
            return Err(format!("camera distance must be positive, got {d}"));
        }
        if let super::model::HairSource::Generated {
            strands, points, ..
        } = self.hair
            && (strands == 0 || strands > 2_000_000 || !(2..=256).contains(&points))
        {
            return Err(format!(
                "generated hair of {strands} strands x {points} points is out of range"
            ));
        }
        if let Some(p) = self.hair.style_params() {
            p.validate().map_err(|e| format!("generated hair: {e}"))?;
        }
        Ok(())
    }
}

/// Where the editor keeps recovery files and its recent-files list: `$STRANDLIGHT_STATE_DIR`, else
/// `$XDG_STATE_HOME/strandlight`, else `~/.local/state/strandlight`.
pub fn state_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("STRANDLIGHT_STATE_DIR") {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("XDG_STATE_HOME") {
        return PathBuf::from(d).join("strandlight");
    }
    match std::env::var_os("HOME") {
        Some(h) => PathBuf::from(h).join(".local/state/strandlight"),
        None => std::env::temp_dir().join("strandlight"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sessions_round_trip_and_bad_files_name_themselves() {
        let dir = std::env::temp_dir().join(format!("sl-session-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.slsession");
        let s = Session {
            env_yaw: 12.5,
            ..Default::default()
        };
        s.write(&path).unwrap();
        assert_eq!(Session::read(&path).unwrap(), s);
        std::fs::write(&path, "{ not json").unwrap();
        let e = Session::read(&path).unwrap_err().to_string();
        assert!(
            e.contains("a.slsession") && e.contains("not a strandlight session"),
            "{e}"
        );
        let newer = s.to_json().replace("\"version\": 1", "\"version\": 9");
        let e = Session::from_json(&newer, &path).unwrap_err().to_string();
        assert!(e.contains("version 9"), "{e}");
        let bad = s.to_json().replace("\"d_f\": 0.7", "\"d_f\": 3.0");
        let e = Session::from_json(&bad, &path).unwrap_err().to_string();
        assert!(e.contains("d_f"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_generators_shape_is_optional_checked_and_reaches_the_hair() {
        use crate::hair::procedural::Style;
        use crate::session::HairSource;
        // Files without the shape read as the generator's defaults.
        let old = Session::default().to_json();
        assert!(!old.contains("clumping"));
        let s = Session::from_json(&old, Path::new("x")).unwrap();
        assert_eq!(s, Session::default());
        let shaped = Session {
            hair: HairSource::Generated {
                style: Style::Bob,
                strands: 50,
                points: 8,
                seed: 2,
                length: Some([10.0, 12.0]),
                clumping: Some(0.9),
                frizz: Some(0.0),
            },
            ..Default::default()
        };
        let back = Session::from_json(&shaped.to_json(), Path::new("x")).unwrap();
        assert_eq!(back, shaped);
        let p = back.hair.style_params().unwrap();
        assert_eq!((p.length, p.clumping, p.frizz), ((10.0, 12.0), 0.9, 0.0));
        let bad = shaped.to_json().replace("0.9", "1.5");
        let e = Session::from_json(&bad, Path::new("x"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("clumping"), "{e}");
        // The shape changes the hair: longer strands reach further down.
        let lowest = |source: &HairSource| {
            crate::session::assemble::load_hair_source(source)
                .unwrap()
                .hair
                .bounds()
                .0
                .y
        };
        let long = HairSource::Generated {
            style: Style::Bob,
            strands: 50,
            points: 8,
            seed: 2,
            length: Some([20.0, 24.0]),
            clumping: Some(0.9),
            frizz: Some(0.0),
        };
        assert!(lowest(&long) < lowest(&shaped.hair) - 3.0);
    }

    #[test]
    fn presets_are_spelled_as_on_the_command_line() {
        let text = Session::default()
            .to_json()
            .replace("\"style\": \"side-part\"", "\"style\": \"bob\"");
        let s = Session::from_json(&text, Path::new("x")).unwrap();
        assert!(matches!(
            s.hair,
            crate::session::HairSource::Generated {
                style: crate::hair::procedural::Style::Bob,
                ..
            }
        ));
    }
}
