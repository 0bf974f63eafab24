//! Writing files atomically: the content goes to a temporary file in the
//! same folder, which is then renamed over the target. A reader never sees
//! half a file, and an interrupted or failed write leaves the previous file
//! intact; the temporary file is removed on error.
//!
//! The temporary file is `.<name>.<pid>-<k>.tmp` beside the target, `k` a
//! process-wide counter, so concurrent writers (threads or processes) never
//! share one. When the target's name is long, `<name>` is cut so that the
//! temporary name is never longer than [`NAME_MAX`] bytes: a name the file
//! system takes as a target always has a temporary file it takes too.
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
//! content under the `.old` name instead of the target's, and the next
//! [`remove_stale_temps`] in that folder puts it back.
//!
//! # Interruption
//!
//! Every temporary file (and every staging folder of
//! [`crate::outdir::OutputDir`]) is registered while it exists. A program
//! that catches SIGINT/SIGTERM calls [`interrupt`]: from then on no new
//! temporary file is created (writers fail with
//! [`std::io::ErrorKind::Interrupted`]), a commit of an output folder in
//! progress is let finish, and everything registered is removed (a `.old`
//! copy whose target is gone is put back instead). The library never
//! installs a signal handler itself; the `ballpass` binary does.
//!
//! Files left by a process that was killed outright (SIGKILL, power loss)
//! are found by their names on the next run into the same folder
//! ([`remove_stale_temps`]; [`crate::outdir::OutputDir::create`] calls it).

use std::collections::BTreeMap;
use std::ffi::{OsStr, OsString};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

use crate::error::{Error, Result};

/// Capacity of the buffer [`write_atomic_with`] hands to its body.
const BUFFER_BYTES: usize = 1 << 16;

/// Longest file name, in bytes, that the common file systems take (Linux
/// `NAME_MAX`; ext4, XFS, btrfs, tmpfs, NTFS and APFS all allow 255).
pub const NAME_MAX: usize = 255;

/// Set once by [`interrupt`]; no temporary file is created afterwards.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Temporary files and staging folders that exist now, each with the
/// target a `.old` copy belongs to (`None`: remove it on interrupt).
static LIVE: Mutex<BTreeMap<PathBuf, Option<PathBuf>>> = Mutex::new(BTreeMap::new());

/// Held while an output folder is committed; [`interrupt`] waits for it.
static COMMIT: Mutex<()> = Mutex::new(());

fn live() -> MutexGuard<'static, BTreeMap<PathBuf, Option<PathBuf>>> {
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// The lock an output folder's commit holds (see [`interrupt`]).
pub(crate) fn commit_lock() -> MutexGuard<'static, ()> {
    COMMIT.lock().unwrap_or_else(|e| e.into_inner())
}

/// The error every write started after [`interrupt`] fails with.
pub(crate) fn interrupted_error() -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::Interrupted, "interrupted")
}

/// Whether [`interrupt`] was called.
pub fn is_interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// Registers `path` (a staging folder or lock file) to be removed by
/// [`interrupt`]; fails once interrupted.
pub(crate) fn register(path: &Path) -> std::io::Result<()> {
    let mut l = live();
    if is_interrupted() {
        return Err(interrupted_error());
    }
    l.insert(path.to_path_buf(), None);
    Ok(())
}

/// Forgets `path` (removed or put in place by its owner).
pub(crate) fn unregister(path: &Path) {
    live().remove(path);
}

/// Stops all writing and removes every temporary file and staging folder
/// of this process (see the module docs). Returns how many were removed or
/// put back. Meant for a signal handler: it blocks only while an output
/// folder's commit (a few renames) finishes.
pub fn interrupt() -> usize {
    INTERRUPTED.store(true, Ordering::SeqCst);
    let _commit = commit_lock();
    let entries = std::mem::take(&mut *live());
    let mut n = 0;
    for (path, restore) in entries {
        let done = match restore {
            Some(target) if std::fs::symlink_metadata(&target).is_err() => {
                std::fs::rename(&path, &target).is_ok()
            }
            _ => match std::fs::symlink_metadata(&path) {
                Ok(m) if m.is_dir() => std::fs::remove_dir_all(&path).is_ok(),
                Ok(_) => std::fs::remove_file(&path).is_ok(),
                Err(_) => false,
            },
        };
        n += usize::from(done);
    }
    n
}

/// Largest small text file [`read_text`] reads: 64 MiB (a manifest of
/// about 800 000 records; profiles and `compensation.json` are kilobytes).
pub(crate) const MAX_TEXT_BYTES: u64 = 64 << 20;

/// A small text file read whole (a manifest, a profile, a
/// `compensation.json`): its bytes as UTF-8 text. `what` says what the
/// file should be ("a manifest is CSV text"): the errors for a file too
/// large or not UTF-8 end with it.
///
/// # Errors
/// [`Error::Io`] when unreadable; [`Error::Format`] for more than
/// [`MAX_TEXT_BYTES`] (also what never ends, like `/dev/zero`);
/// [`Error::Parse`] naming the line of the first byte that is not UTF-8.
pub(crate) fn read_text(path: &Path, what: &str) -> Result<String> {
    read_text_max(path, what, MAX_TEXT_BYTES)
}

/// [`read_text`] with the limit `max` bytes.
fn read_text_max(path: &Path, what: &str, max: u64) -> Result<String> {
    use std::io::Read;
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut bytes = Vec::new();
    File::open(path)
        .map_err(io)?
        .take(max + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > max {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: format!("more than {max} bytes; {what}"),
        });
    }
    String::from_utf8(bytes).map_err(|e| Error::Parse {
        path: path.to_path_buf(),
        line: 1 + e.as_bytes()[..e.utf8_error().valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count(),
        column: None,
        reason: format!("text that is not UTF-8; {what}"),
    })
}

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
/// or when the temporary file cannot be created, flushed or renamed;
/// [`std::io::ErrorKind::Interrupted`] after [`interrupt`].
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
        let file = create_registered(&tmp)?;
        let mut w = BufWriter::with_capacity(BUFFER_BYTES, file);
        body(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?;
        replace(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    unregister(&tmp);
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

/// Creates `tmp` (which must not exist) and registers it, both under the
/// registry's lock, so that [`interrupt`] either sees it or stops it.
fn create_registered(tmp: &Path) -> std::io::Result<File> {
    let mut l = live();
    if is_interrupted() {
        return Err(interrupted_error());
    }
    let f = File::options().write(true).create_new(true).open(tmp)?;
    l.insert(tmp.to_path_buf(), None);
    Ok(f)
}

/// Renames `tmp` to `path`, moving an existing `path` aside first and
/// removing it afterwards (see the module docs).
pub(crate) fn replace(tmp: &Path, path: &Path) -> std::io::Result<()> {
    // Only a file is moved aside; a folder in the way is left for the plain
    // rename to refuse.
    let is_file = std::fs::symlink_metadata(path).is_ok_and(|m| !m.is_dir());
    let old = match side_path(path, "old") {
        Some(old) if is_file => old,
        _ => return std::fs::rename(tmp, path),
    };
    let moved = {
        let mut l = live();
        match std::fs::rename(path, &old) {
            Ok(()) => {
                l.insert(old.clone(), Some(path.to_path_buf()));
                true
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => false,
            Err(_) => {
                drop(l);
                return std::fs::rename(tmp, path);
            }
        }
    };
    let result = std::fs::rename(tmp, path);
    if moved {
        if result.is_err() {
            // Put the old file back; the error names the failed rename.
            let _ = std::fs::rename(&old, path);
        } else {
            // The new content is in place; an old copy that cannot be
            // removed is only litter, not a failed write.
            let _ = std::fs::remove_file(&old);
        }
        unregister(&old);
    }
    result
}

/// `.<name>.<pid>-<k>.tmp` beside `path`; `None` when `path` has no file name.
fn temp_path(path: &Path) -> Option<PathBuf> {
    side_path(path, "tmp")
}

/// `.<name>.<pid>-<k>.<ext>` beside `path`, `k` from a process-wide
/// counter, `<name>` cut so that the whole is at most [`NAME_MAX`] bytes;
/// `None` when `path` has no file name.
fn side_path(path: &Path, ext: &str) -> Option<PathBuf> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name()?;
    let k = COUNTER.fetch_add(1, Ordering::Relaxed);
    let suffix = format!(".{}-{k}.{ext}", std::process::id());
    let room = NAME_MAX - 1 - suffix.len();
    let mut side = OsString::from(".");
    side.push(cut_name(name, room));
    side.push(&suffix);
    Some(path.with_file_name(side))
}

/// The first at most `max_bytes` bytes of `name`, cut at a character
/// boundary when the name is text.
fn cut_name(name: &OsStr, max_bytes: usize) -> OsString {
    if name.len() <= max_bytes {
        return name.to_os_string();
    }
    if let Some(s) = name.to_str() {
        let mut end = max_bytes;
        while !s.is_char_boundary(end) {
            end -= 1;
        }
        return OsString::from(&s[..end]);
    }
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        OsStr::from_bytes(&name.as_bytes()[..max_bytes]).to_os_string()
    }
    #[cfg(not(unix))]
    {
        let s = name.to_string_lossy();
        let mut end = max_bytes.min(s.len());
        while !s.is_char_boundary(end) {
            end -= 1;
        }
        OsString::from(&s[..end])
    }
}

/// A file to be put in place together with others by [`commit_all`]: it is
/// written under a registered temporary name beside its target first
/// ([`Pending::path`]), so that an interrupt before the commit removes it
/// and leaves the target as it was. Dropped without a commit, it removes
/// its temporary file.
#[derive(Debug)]
pub struct Pending {
    tmp: PathBuf,
    target: PathBuf,
}

impl Pending {
    /// Reserves a temporary name beside `target` (nothing is created).
    ///
    /// # Errors
    /// [`Error::Io`] naming `target` when it has no file name, or after
    /// [`interrupt`].
    pub fn new(target: &Path) -> Result<Self> {
        let io_err = |source| Error::Io {
            path: target.to_path_buf(),
            source,
        };
        let tmp = temp_path(target).ok_or_else(|| {
            io_err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "not a file path",
            ))
        })?;
        register(&tmp).map_err(io_err)?;
        Ok(Self {
            tmp,
            target: target.to_path_buf(),
        })
    }

    /// Where to write the content (a hidden name beside the target).
    pub fn path(&self) -> &Path {
        &self.tmp
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.tmp);
        unregister(&self.tmp);
    }
}

/// Puts every pending file in place (renamed as in the module docs), holding the
/// commit lock so that an interrupt waits for all of them. On an error the
/// files not yet in place are removed and the error names the target.
///
/// # Errors
/// [`Error::Io`] naming the target that could not be put in place;
/// [`std::io::ErrorKind::Interrupted`] after [`interrupt`] (nothing moved).
pub fn commit_all(files: Vec<Pending>) -> Result<()> {
    let _guard = commit_lock();
    if is_interrupted() {
        let path = files.first().map(|f| f.target.clone()).unwrap_or_default();
        return Err(Error::Io {
            path,
            source: interrupted_error(),
        });
    }
    for f in &files {
        replace(&f.tmp, &f.target).map_err(|source| Error::Io {
            path: f.target.clone(),
            source,
        })?;
    }
    Ok(())
}

/// A side file's name taken apart: `.<name>.<pid>-<k>.<tmp|old>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SideName {
    /// The target's name, possibly cut.
    pub base: OsString,
    /// The writing process.
    pub pid: u32,
    /// `.old` (a previous version moved aside) rather than `.tmp`.
    pub old: bool,
}

/// Parses a side file's name; `None` for any other name.
pub(crate) fn parse_side_name(name: &OsStr) -> Option<SideName> {
    let lossy = name.to_string_lossy();
    let rest = lossy.strip_prefix('.')?;
    let (rest, old) = match (rest.strip_suffix(".tmp"), rest.strip_suffix(".old")) {
        (Some(r), _) => (r, false),
        (_, Some(r)) => (r, true),
        _ => return None,
    };
    let (base, tag) = rest.rsplit_once('.')?;
    let (pid, k) = tag.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if base.is_empty() || !digits(pid) || !digits(k) {
        return None;
    }
    // The base as bytes of the original name (lossy decoding only replaced
    // bytes inside it; its length in the original is the name's minus the
    // tag's, which is ASCII).
    let tail = 1 + tag.len() + 4;
    let base = slice_os(name, 1, name.len() - tail)?;
    Some(SideName {
        base,
        pid: pid.parse().ok()?,
        old,
    })
}

/// Bytes `from..to` of `name` (ASCII cut points only).
fn slice_os(name: &OsStr, from: usize, to: usize) -> Option<OsString> {
    if let Some(s) = name.to_str() {
        return s.get(from..to).map(OsString::from);
    }
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        name.as_bytes()
            .get(from..to)
            .map(|b| OsStr::from_bytes(b).to_os_string())
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// Whether process `pid` may still be running. Exact on Linux (`/proc`);
/// elsewhere every other process is taken as running, so nothing of it is
/// touched.
pub(crate) fn pid_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

/// What [`remove_stale_temps`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StaleCleanup {
    /// Temporary files removed.
    pub removed: Vec<PathBuf>,
    /// `.old` copies put back under their target's name (the target was
    /// missing: the writer died between its two renames).
    pub restored: Vec<PathBuf>,
}

/// Removes, in `dir` (not below it), the temporary files of ballpass
/// processes that no longer run, and puts back a `.old` copy whose target is
/// missing. Only names of the form `.<name>.<pid>-<k>.tmp|old` are touched,
/// only of other processes, and only of dead ones (Linux: no `/proc/<pid>`); with
/// `names`, only side files of those targets.
///
/// # Errors
///
/// [`Error::Io`] naming `dir` when it cannot be listed (a missing folder is
/// not an error: nothing to clean).
pub fn remove_stale_temps(dir: &Path, names: Option<&[&OsStr]>) -> Result<StaleCleanup> {
    let mut done = StaleCleanup::default();
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(done),
        Err(source) => {
            return Err(Error::Io {
                path: dir.to_path_buf(),
                source,
            })
        }
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(side) = parse_side_name(&name) else {
            continue;
        };
        if pid_alive(side.pid) {
            continue;
        }
        if let Some(names) = names {
            let wanted = names.iter().any(|n| {
                let full = n.to_string_lossy();
                full.starts_with(&*side.base.to_string_lossy())
            });
            if !wanted {
                continue;
            }
        }
        if !e.file_type().is_ok_and(|t| t.is_file()) {
            continue;
        }
        let path = e.path();
        let target = dir.join(&side.base);
        if side.old && std::fs::symlink_metadata(&target).is_err() {
            if std::fs::rename(&path, &target).is_ok() {
                done.restored.push(target);
            }
        } else if std::fs::remove_file(&path).is_ok() {
            done.removed.push(path);
        }
    }
    Ok(done)
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

    /// A small text file is read up to its limit: one byte more, or a file
    /// that never ends, is an error naming it, read no further.
    #[test]
    fn a_text_file_over_its_limit_is_refused() {
        let d = dir("read-text");
        let p = d.join("m.csv");
        std::fs::write(&p, "path,bearing\nr.csv,b\n").unwrap();
        assert_eq!(
            read_text_max(&p, "CSV", 21).unwrap(),
            "path,bearing\nr.csv,b\n"
        );
        let e = read_text_max(&p, "CSV", 20).unwrap_err().to_string();
        assert!(
            e.contains("m.csv") && e.contains("more than 20 bytes; CSV"),
            "{e}"
        );
        #[cfg(unix)]
        {
            let e = read_text(Path::new("/dev/zero"), "CSV")
                .unwrap_err()
                .to_string();
            assert!(e.contains("/dev/zero") && e.contains("more than"), "{e}");
        }
        let _ = std::fs::remove_dir_all(&d);
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

    /// Issue 18 item 8: a legal long target name gets a temporary name the
    /// file system takes (`simulate -o` with a 250-byte name used to write
    /// the CSV and fail on its truth file).
    #[test]
    fn item8_temporary_names_never_exceed_name_max() {
        let d = dir("long");
        for len in [1, 200, 230, 250, NAME_MAX] {
            let name = "é".repeat(len / 2) + &"x".repeat(len % 2);
            let p = d.join(&name);
            let t = temp_path(&p).unwrap();
            let n = t.file_name().unwrap().len();
            assert!(n <= NAME_MAX, "{len}: {n}");
            write_atomic(&p, b"x").unwrap();
            assert_eq!(std::fs::read(&p).unwrap(), b"x");
            // The parse finds the (cut) base again.
            let side = parse_side_name(t.file_name().unwrap()).unwrap();
            assert!(name.starts_with(&*side.base.to_string_lossy()), "{len}");
            assert_eq!(side.pid, std::process::id());
        }
        assert!(leftovers(&d).is_empty(), "{:?}", leftovers(&d));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn side_names_parse_and_other_names_do_not() {
        let s = parse_side_name(OsStr::new(".a.b.csv.123-7.tmp")).unwrap();
        assert_eq!(
            (s.base.to_str().unwrap(), s.pid, s.old),
            ("a.b.csv", 123, false)
        );
        let s = parse_side_name(OsStr::new(".x.9-0.old")).unwrap();
        assert!(s.old && s.pid == 9);
        for n in [
            ".x.tmp",
            "x.1-2.tmp",
            ".x.1-.tmp",
            ".x.a-1.tmp",
            "..1-2.tmp",
            ".x.1-2.txt",
        ] {
            assert!(parse_side_name(OsStr::new(n)).is_none(), "{n}");
        }
    }

    /// Issue 18 item 8: temporary files of a dead process are removed on
    /// the next run, a `.old` copy whose target is gone is put back, and a
    /// live process's files are left alone.
    #[test]
    fn item8_stale_temporaries_of_dead_processes_are_cleaned() {
        let d = dir("stale");
        // Far above any Linux pid_max (4194304): never a running process.
        let dead = 4_194_999u32;
        let me = std::process::id();
        std::fs::write(d.join(format!(".a.csv.{dead}-0.tmp")), b"half").unwrap();
        std::fs::write(d.join(format!(".b.csv.{dead}-3.old")), b"previous").unwrap();
        std::fs::write(d.join(format!(".c.csv.{me}-1.tmp")), b"mine").unwrap();
        std::fs::write(d.join("notes.tmp"), b"user").unwrap();
        let done = remove_stale_temps(&d, None).unwrap();
        if cfg!(target_os = "linux") {
            assert_eq!(done.removed.len(), 1, "{done:?}");
            assert_eq!(std::fs::read(d.join("b.csv")).unwrap(), b"previous");
            assert!(!d.join(format!(".a.csv.{dead}-0.tmp")).exists());
        }
        assert!(d.join(format!(".c.csv.{me}-1.tmp")).exists());
        assert!(d.join("notes.tmp").exists());
        // Restricted to named targets: another target's temporaries stay.
        std::fs::write(d.join(format!(".z.csv.{dead}-0.tmp")), b"half").unwrap();
        remove_stale_temps(&d, Some(&[OsStr::new("y.csv")])).unwrap();
        assert!(d.join(format!(".z.csv.{dead}-0.tmp")).exists());
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// A pair is put in place together or not at all.
    #[test]
    fn pending_files_appear_together_or_not_at_all() {
        let d = dir("pending");
        let (a, b) = (d.join("r.csv"), d.join("r.truth.json"));
        {
            let pa = Pending::new(&a).unwrap();
            let _pb = Pending::new(&b).unwrap();
            write_atomic(pa.path(), b"rec").unwrap();
            // Dropped before the commit (a failure in between).
        }
        assert!(std::fs::read_dir(&d).unwrap().next().is_none());
        let pa = Pending::new(&a).unwrap();
        let pb = Pending::new(&b).unwrap();
        write_atomic(pa.path(), b"rec").unwrap();
        write_atomic(pb.path(), b"truth").unwrap();
        commit_all(vec![pa, pb]).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), b"rec");
        assert_eq!(std::fs::read(&b).unwrap(), b"truth");
        assert!(leftovers(&d).is_empty(), "{:?}", leftovers(&d));
        std::fs::remove_dir_all(&d).unwrap();
    }
}
