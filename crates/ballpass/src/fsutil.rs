//! Writing files atomically: the content goes to a temporary file in the
//! same folder, which is then renamed over the target. A reader never sees
//! half a file, and an interrupted or failed write leaves the previous file
//! intact; the temporary file is removed on error.
//!
//! The temporary file is `.<name>.<pid>-<k>.tmp` beside the target, `k` a
//! process-wide counter, so concurrent writers (threads or processes) never
//! share one.
//!
//! **No `fsync`.** Every file ballpass writes (recordings it simulates or
//! converts, analysis tables, reports, campaign outputs) can be made again
//! from its inputs, and an `fsync` per file costs more wall time than a whole
//! analysis. The rename still gives readers all-or-nothing; what is given up
//! is only durability of the newest content across a power loss or OS crash.
//!
//! **An existing target is moved aside first.** Renaming a fresh file over an
//! existing one makes ext4 (`auto_da_alloc`) start writing the new file out
//! to disk inside the `rename` call: 6-7 ms for the 8 MB `correlations.csv`
//! of one analysis, more than the analysis itself. So the old file is first
//! renamed to `.<name>.<pid>-<k>.old`, the temporary file renamed to the
//! target, and the old file removed. A reader still sees the old file or the
//! new one, whole, except in the microseconds between the two renames when
//! the path is briefly absent; a process killed exactly there leaves the old
//! content under the `.old` name instead of the target's.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};

/// Capacity of the buffer [`write_atomic_with`] hands to its body.
const BUFFER_BYTES: usize = 1 << 16;

/// Writes `bytes` to `path` atomically (see the module docs).
///
/// # Errors
///
/// [`Error::Io`] naming `path` when it has no file name or the temporary file
/// cannot be created, written or renamed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Runs `body` on a buffered temporary file beside `path`, then renames it to
/// `path` (see the module docs); on any error the temporary file is removed.
///
/// # Errors
///
/// [`Error::Io`] naming `path` when it has no file name, when `body` fails,
/// or when the temporary file cannot be created, flushed or renamed.
pub fn write_atomic_with(
    path: &Path,
    body: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<()> {
    let io_err = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let tmp = temp_path(path).ok_or_else(|| {
        io_err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a file path",
        ))
    })?;
    let result = (|| {
        let file = File::options().write(true).create_new(true).open(&tmp)?;
        let mut w = BufWriter::with_capacity(BUFFER_BYTES, file);
        body(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?;
        replace(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io_err)
}

/// Writes serializable rows atomically as a CSV table with a header row
/// (the `csv` crate's formatting: shortest round-trip numbers, empty cells
/// for `None`).
///
/// # Errors
/// [`Error::Format`] when a row cannot be formatted, [`Error::Io`] naming
/// `path` when it cannot be written.
pub fn write_csv_rows<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let format_err = |reason: String| Error::Format {
        path: path.to_path_buf(),
        reason: format!("cannot format the table: {reason}"),
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(|e| format_err(e.to_string()))?;
    }
    let bytes = w.into_inner().map_err(|e| format_err(e.to_string()))?;
    write_atomic(path, &bytes)
}

/// Writes a value atomically as pretty JSON with a trailing newline.
///
/// # Errors
/// [`Error::Format`] when it cannot be serialised, [`Error::Io`] naming
/// `path` when it cannot be written.
pub fn write_json_pretty<T: serde::Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(|e| Error::Format {
        path: path.to_path_buf(),
        reason: format!("cannot serialise: {e}"),
    })?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}

/// Renames `tmp` to `path`, moving an existing `path` aside first and
/// removing it afterwards (see the module docs).
fn replace(tmp: &Path, path: &Path) -> std::io::Result<()> {
    // Only a file is moved aside; a folder in the way is left for the plain
    // rename to refuse.
    let is_file = std::fs::symlink_metadata(path).is_ok_and(|m| !m.is_dir());
    let old = match side_path(path, "old") {
        Some(old) if is_file => old,
        _ => return std::fs::rename(tmp, path),
    };
    let moved = match std::fs::rename(path, &old) {
        Ok(()) => true,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => false,
        Err(_) => return std::fs::rename(tmp, path),
    };
    if let Err(e) = std::fs::rename(tmp, path) {
        if moved {
            // Put the old file back; the error names the failed rename.
            let _ = std::fs::rename(&old, path);
        }
        return Err(e);
    }
    if moved {
        // The new content is in place; an old copy that cannot be removed
        // is only litter, not a failed write.
        let _ = std::fs::remove_file(&old);
    }
    Ok(())
}

/// `.<name>.<pid>-<k>.tmp` beside `path`; `None` when `path` has no file name.
fn temp_path(path: &Path) -> Option<PathBuf> {
    side_path(path, "tmp")
}

/// `.<name>.<pid>-<k>.<ext>` beside `path`, `k` from a process-wide
/// counter; `None` when `path` has no file name.
fn side_path(path: &Path, ext: &str) -> Option<PathBuf> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name()?.to_string_lossy().into_owned();
    let k = COUNTER.fetch_add(1, Ordering::Relaxed);
    Some(path.with_file_name(format!(".{name}.{}-{k}.{ext}", std::process::id())))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("ballpass-fsutil-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn leftovers(d: &Path) -> Vec<String> {
        std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp") || n.ends_with(".old"))
            .collect()
    }

    #[test]
    fn writes_and_replaces_without_leftovers() {
        let d = dir("replace");
        let p = d.join("a.txt");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        write_atomic_with(&p, |w| writeln!(w, "third")).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "third\n");
        assert!(leftovers(&d).is_empty(), "{:?}", leftovers(&d));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_failing_body_keeps_the_old_file_and_removes_the_temporary() {
        let d = dir("fail");
        let p = d.join("a.txt");
        write_atomic(&p, b"old").unwrap();
        let e = write_atomic_with(&p, |w| {
            w.write_all(b"half")?;
            Err(std::io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(
            e.to_string().contains("a.txt") && e.to_string().contains("boom"),
            "{e}"
        );
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        assert!(leftovers(&d).is_empty(), "{:?}", leftovers(&d));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_folder_in_the_way_is_an_error_and_stays() {
        let d = dir("folder");
        let p = d.join("a.csv");
        std::fs::create_dir(&p).unwrap();
        std::fs::write(p.join("inner"), b"keep").unwrap();
        let e = write_atomic(&p, b"x").unwrap_err();
        assert!(matches!(&e, Error::Io { path, .. } if path == &p), "{e}");
        assert_eq!(std::fs::read(p.join("inner")).unwrap(), b"keep");
        assert!(leftovers(&d).is_empty(), "{:?}", leftovers(&d));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn errors_name_the_file() {
        let d = dir("missing");
        let p = d.join("no-such-folder").join("a.txt");
        let e = write_atomic(&p, b"x").unwrap_err();
        assert!(matches!(&e, Error::Io { path, .. } if path == &p), "{e}");
        let e = write_atomic(Path::new("/"), b"x").unwrap_err();
        assert!(e.to_string().contains("not a file path"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn temporary_names_are_unique_and_hidden() {
        let p = Path::new("out/x.csv");
        let (a, b) = (temp_path(p).unwrap(), temp_path(p).unwrap());
        assert_ne!(a, b);
        let name = a.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            name.starts_with(".x.csv.") && name.ends_with(".tmp"),
            "{name}"
        );
        assert_eq!(a.parent(), p.parent());
    }
}
