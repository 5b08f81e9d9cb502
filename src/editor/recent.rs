//! Sessions opened or saved lately, newest first, kept in the state folder as `recent.json`.

use std::path::{Path, PathBuf};

const RECENT_FILE: &str = "recent.json";
/// Entries kept in the menu.
const RECENT_KEPT: usize = 10;

pub struct RecentFiles {
    list: Vec<PathBuf>,
    dir: PathBuf,
}

impl RecentFiles {
    /// The list in `dir` (missing or unreadable: empty).
    pub fn read(dir: PathBuf) -> Self {
        let list = std::fs::read_to_string(dir.join(RECENT_FILE))
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default();
        Self { list, dir }
    }

    pub fn list(&self) -> &[PathBuf] {
        &self.list
    }

    /// The state folder the list lives in.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Puts `path` first (written atomically); an error names the file that could not be written.
    pub fn remember(&mut self, path: &Path) -> Result<(), String> {
        let p = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        self.list.retain(|r| r != &p);
        self.list.insert(0, p);
        self.list.truncate(RECENT_KEPT);
        let file = self.dir.join(RECENT_FILE);
        let text = serde_json::to_string_pretty(&self.list).unwrap_or_default();
        std::fs::create_dir_all(&self.dir)
            .and_then(|_| crate::files::write_atomic(&file, text.as_bytes()))
            .map_err(|e| format!("{}: {e}", file.display()))
    }
}
