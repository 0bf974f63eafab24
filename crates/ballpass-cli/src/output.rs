//! Writing result files: atomically ([`ballpass::fsutil::write_atomic`]:
//! temp file + rename), so that a reader never sees half a table and an
//! interrupted run leaves the old file intact.

use std::fs;
use std::path::Path;

use anyhow::{Context, Result};
use ballpass::fsutil::write_atomic;
use serde::Serialize;

/// Creates `dir` (and its parents) if needed.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir).with_context(|| format!("creating output directory {}", dir.display()))
}

/// Writes serializable rows as a CSV table with a header row.
pub fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)
            .with_context(|| format!("formatting {}", path.display()))?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| anyhow::anyhow!("formatting {}: {e}", path.display()))?;
    Ok(write_atomic(path, &bytes)?)
}

/// Writes a value as pretty JSON with a trailing newline.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value)
        .with_context(|| format!("formatting {}", path.display()))?;
    bytes.push(b'\n');
    Ok(write_atomic(path, &bytes)?)
}

/// A progress bar over `len` items named `what` on a terminal; `None` when
/// stderr is a file or a pipe (logs stay clean).
pub fn progress(len: usize, what: &str) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    std::io::stderr().is_terminal().then(|| {
        let b = indicatif::ProgressBar::new(len as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(&format!(
                "{{bar:40}} {{pos}}/{{len}} {what}  {{elapsed}}  eta {{eta}}"
            ))
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    })
}
