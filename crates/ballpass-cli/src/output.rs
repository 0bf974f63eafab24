//! Output folders. The files themselves are written by the library
//! (atomically, [`ballpass::fsutil::write_atomic`]: temp file + rename), so
//! that a reader never sees half a table and an interrupted run leaves the
//! old file intact.

use std::fs;
use std::path::Path;

use anyhow::{Context, Result};

/// Creates `dir` (and its parents) if needed.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir).with_context(|| format!("creating output directory {}", dir.display()))
}
