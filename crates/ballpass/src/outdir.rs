//! One run's output folder: one writer at a time, outputs staged and
//! committed together, and a run manifest written last.
//!
//! A command that writes a folder of results ([`OutputDir::create`]):
//!
//! 1. creates the folder and takes its lock, `DIR/.ballpass.lock`: an
//!    advisory lock of the operating system (`flock`), so a lock whose
//!    process died (even by SIGKILL) is free again at once, with nothing to
//!    recover by hand. A second run into the same folder meanwhile fails at
//!    once with a message naming the folder and the process that holds it
//!    (on a file system without advisory locks the run goes on unlocked);
//! 2. removes what a killed run left there: staging folders
//!    (`DIR/.ballpass-staging.<pid>`: no other run can be writing them, the
//!    lock says so) and temporary files of dead processes
//!    ([`crate::fsutil::remove_stale_temps`], in `DIR` and its direct
//!    sub-folders);
//! 3. writes everything into its own staging folder ([`OutputDir::path`]);
//! 4. on success, [`OutputDir::commit`]: removes the previous run manifest
//!    `DIR/ballpass-run.json`, renames every staged file into place, removes
//!    the files the previous manifest listed that this run did not write
//!    (so figures of an earlier run never mix with this run's), and writes
//!    the new manifest **last**.
//!
//! **A folder holds one complete run exactly when `ballpass-run.json` is
//! there**, and the files it lists (with their sizes) are that run's. A run
//! that fails or is interrupted leaves the previous outputs as they were
//! (nothing is renamed before the commit), and a run killed in the
//! milliseconds of its commit leaves no manifest: readers, and the next
//! run, can tell. Without `ballpass-run.json` a folder's files are not a
//! result.
//!
//! On an interrupt ([`crate::fsutil::interrupt`]) the staging folder and the
//! lock file are removed; a commit in progress is let finish first.

use std::fs::File;
use std::io::{Read, Seek, Write};
use std::path::{Component, Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::fsutil;

/// The lock file inside an output folder.
pub const LOCK_FILE: &str = ".ballpass.lock";
/// The run manifest, written last: the folder holds a complete run exactly
/// when it is there.
pub const RUN_FILE: &str = "ballpass-run.json";
/// Schema tag of [`RUN_FILE`].
pub const RUN_SCHEMA: &str = "ballpass.run/1";
/// Staging folders are `.ballpass-staging.<pid>`.
const STAGING_PREFIX: &str = ".ballpass-staging.";

/// One file of a run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunFile {
    /// Path relative to the output folder, `/`-separated.
    pub path: String,
    /// Size, bytes.
    pub bytes: u64,
}

/// The run manifest `ballpass-run.json` (schema `ballpass.run/1`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunManifest {
    /// [`RUN_SCHEMA`].
    pub schema: String,
    /// ballpass version.
    pub version: String,
    /// The command that wrote the folder (`analyze`, `sweep`, ...).
    pub command: String,
    /// Every file of the run, sorted by path (the manifest itself excluded).
    pub files: Vec<RunFile>,
}

impl RunManifest {
    /// Reads `dir/ballpass-run.json`; `None` when it is missing or not a
    /// run manifest.
    pub fn read(dir: &Path) -> Option<Self> {
        let text = std::fs::read_to_string(dir.join(RUN_FILE)).ok()?;
        let m: RunManifest = serde_json::from_str(&text).ok()?;
        (m.schema == RUN_SCHEMA).then_some(m)
    }
}

/// An output folder being written by this process (see the module docs).
#[derive(Debug)]
pub struct OutputDir {
    dir: PathBuf,
    staging: PathBuf,
    command: String,
    lock_path: PathBuf,
    lock: Option<File>,
    /// The folder did not exist before: a run that does not commit removes
    /// it again if it is empty.
    created: bool,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl OutputDir {
    /// Creates `dir` if needed, takes its lock, cleans what killed runs
    /// left, and makes a fresh staging folder (see the module docs).
    ///
    /// # Errors
    /// [`Error::Io`] naming the folder when it cannot be created or written
    /// (a file in the way, no permission, read-only); [`Error::OutputInUse`]
    /// when another process holds its lock.
    pub fn create(dir: &Path, command: &str) -> Result<Self> {
        let created = std::fs::symlink_metadata(dir).is_err();
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let lock_path = dir.join(LOCK_FILE);
        let lock = take_lock(dir, &lock_path)?;
        let out = Self {
            dir: dir.to_path_buf(),
            staging: dir.join(format!("{STAGING_PREFIX}{}", std::process::id())),
            command: command.to_string(),
            lock_path,
            lock: Some(lock),
            created,
        };
        fsutil::register(&out.lock_path).map_err(io(dir))?;
        out.clean_stale()?;
        fsutil::register(&out.staging).map_err(io(&out.staging))?;
        std::fs::create_dir(&out.staging).map_err(io(&out.staging))?;
        Ok(out)
    }

    /// The folder to write this run's files into (the staging folder).
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The output folder as given.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Where a file written under [`OutputDir::path`] will be after the
    /// commit (other paths are returned unchanged).
    pub fn final_path(&self, staged: &Path) -> PathBuf {
        match staged.strip_prefix(&self.staging) {
            Ok(rel) => self.dir.join(rel),
            Err(_) => staged.to_path_buf(),
        }
    }

    /// Staging folders of earlier runs and temporary files of dead
    /// processes, in the folder and its direct sub-folders.
    fn clean_stale(&self) -> Result<()> {
        let entries = std::fs::read_dir(&self.dir).map_err(io(&self.dir))?;
        let mut subdirs = Vec::new();
        for e in entries.flatten() {
            let name = e.file_name();
            let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
            if !is_dir {
                continue;
            }
            if name.to_string_lossy().starts_with(STAGING_PREFIX) {
                // We hold the lock: no run is writing it.
                let _ = std::fs::remove_dir_all(e.path());
            } else {
                subdirs.push(e.path());
            }
        }
        fsutil::remove_stale_temps(&self.dir, None)?;
        for d in subdirs {
            // A sub-folder that cannot be listed is not ours to clean.
            let _ = fsutil::remove_stale_temps(&d, None);
        }
        Ok(())
    }

    /// Moves every staged file into the folder and writes the run manifest
    /// last (see the module docs); releases the lock.
    ///
    /// # Errors
    /// [`Error::Io`] naming the file that could not be moved or written;
    /// the folder then has no run manifest.
    pub fn commit(mut self) -> Result<RunManifest> {
        let _guard = fsutil::commit_lock();
        if fsutil::is_interrupted() {
            return Err(io(&self.dir)(fsutil::interrupted_error()));
        }
        let mut files = Vec::new();
        list_files(&self.staging, Path::new(""), &mut files)?;
        files.sort();
        let previous = RunManifest::read(&self.dir);
        let run_file = self.dir.join(RUN_FILE);
        match std::fs::remove_file(&run_file) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(io(&run_file)(e)),
        }
        let mut listed = Vec::with_capacity(files.len());
        for (rel, bytes) in &files {
            let to = self.dir.join(rel);
            if let Some(parent) = to.parent() {
                std::fs::create_dir_all(parent).map_err(io(parent))?;
            }
            fsutil::replace(&self.staging.join(rel), &to).map_err(io(&to))?;
            listed.push(RunFile {
                path: slash_path(rel),
                bytes: *bytes,
            });
        }
        if let Some(prev) = previous {
            for f in prev.files {
                if listed.iter().any(|n| n.path == f.path) {
                    continue;
                }
                if let Some(rel) = safe_relative(&f.path) {
                    let p = self.dir.join(&rel);
                    if std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_file()) {
                        let _ = std::fs::remove_file(&p);
                        remove_empty_parents(&self.dir, &rel);
                    }
                }
            }
        }
        let manifest = RunManifest {
            schema: RUN_SCHEMA.into(),
            version: crate::VERSION.into(),
            command: self.command.clone(),
            files: listed,
        };
        let text = serde_json::to_string_pretty(&manifest).map_err(|e| Error::Format {
            path: run_file.clone(),
            reason: format!("cannot serialise: {e}"),
        })? + "\n";
        fsutil::write_atomic(&run_file, text.as_bytes())?;
        let _ = std::fs::remove_dir_all(&self.staging);
        fsutil::unregister(&self.staging);
        self.release();
        Ok(manifest)
    }

    /// Removes the lock file and releases the lock.
    fn release(&mut self) {
        if let Some(f) = self.lock.take() {
            // Removed while still held: a run that opened the old file
            // meanwhile sees that it is no longer at the path and retries.
            let _ = std::fs::remove_file(&self.lock_path);
            fsutil::unregister(&self.lock_path);
            drop(f);
        }
    }
}

impl Drop for OutputDir {
    /// A run that did not commit leaves nothing: its staging folder goes,
    /// the previous outputs stay.
    fn drop(&mut self) {
        if self.lock.is_some() {
            let _ = std::fs::remove_dir_all(&self.staging);
            fsutil::unregister(&self.staging);
            self.release();
            if self.created {
                let _ = std::fs::remove_dir(&self.dir);
            }
        }
    }
}

/// Opens and locks `lock_path`, retrying when the file was replaced between
/// opening and locking (its holder removed it on the way out).
fn take_lock(dir: &Path, lock_path: &Path) -> Result<File> {
    for _ in 0..100 {
        let mut f = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(lock_path)
            .map_err(io(dir))?;
        match f.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                let mut holder = String::new();
                let _ = f.read_to_string(&mut holder);
                let holder = holder.trim();
                return Err(Error::OutputInUse {
                    path: dir.to_path_buf(),
                    holder: if holder.is_empty() {
                        "another ballpass run".into()
                    } else {
                        format!("another ballpass run (pid {holder})")
                    },
                });
            }
            // A file system without advisory locks (some network mounts):
            // the run goes on unlocked rather than not at all.
            Err(std::fs::TryLockError::Error(e)) if e.kind() == std::io::ErrorKind::Unsupported => {
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(io(lock_path)(e)),
        }
        if !same_file(&f, lock_path) {
            continue;
        }
        f.set_len(0).map_err(io(lock_path))?;
        f.rewind().map_err(io(lock_path))?;
        write!(f, "{}", std::process::id()).map_err(io(lock_path))?;
        return Ok(f);
    }
    Err(io(lock_path)(std::io::Error::other(
        "the lock file keeps being replaced",
    )))
}

/// Whether the open file is still the one at `path`.
fn same_file(f: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (f.metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (f, path);
        true
    }
}

/// Every file under `root/rel`, relative to `root`, with its size.
fn list_files(root: &Path, rel: &Path, out: &mut Vec<(PathBuf, u64)>) -> Result<()> {
    let dir = root.join(rel);
    for e in std::fs::read_dir(&dir).map_err(io(&dir))? {
        let e = e.map_err(io(&dir))?;
        let r = rel.join(e.file_name());
        let m = e.metadata().map_err(io(&e.path()))?;
        if m.is_dir() {
            list_files(root, &r, out)?;
        } else {
            out.push((r, m.len()));
        }
    }
    Ok(())
}

fn slash_path(rel: &Path) -> String {
    rel.components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("/")
}

/// A manifest path as a relative path inside the folder; `None` for
/// anything that could leave it (absolute, `..`).
fn safe_relative(p: &str) -> Option<PathBuf> {
    let path = PathBuf::from(p);
    let ok = !p.is_empty() && path.components().all(|c| matches!(c, Component::Normal(_)));
    ok.then_some(path)
}

/// Removes the now empty folders between `dir/rel`'s parent and `dir`.
fn remove_empty_parents(dir: &Path, rel: &Path) {
    let mut p = rel.parent();
    while let Some(d) = p.filter(|d| !d.as_os_str().is_empty()) {
        if std::fs::remove_dir(dir.join(d)).is_err() {
            break;
        }
        p = d.parent();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("ballpass-outdir-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn write(p: &Path, text: &str) {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        fsutil::write_atomic(p, text.as_bytes()).unwrap();
    }

    /// Issue 18 item 8: a second writer is refused while the first holds
    /// the folder, with the holder named; after the first is done the
    /// folder is free again.
    #[test]
    fn item8_one_writer_per_output_folder() {
        let d = dir("lock");
        let first = OutputDir::create(&d, "analyze").unwrap();
        let e = OutputDir::create(&d, "analyze").unwrap_err();
        let msg = e.to_string();
        assert!(
            msg.contains(&d.display().to_string())
                && msg.contains(&format!("pid {}", std::process::id())),
            "{msg}"
        );
        drop(first);
        // It created the folder and committed nothing: the folder is gone.
        assert!(!d.exists());
        let again = OutputDir::create(&d, "analyze").unwrap();
        again.commit().unwrap();
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Issue 18 item 8: outputs appear together with the manifest, replace
    /// the previous run's, and files only the previous run wrote go.
    #[test]
    fn item8_commit_replaces_the_previous_run_and_writes_the_manifest_last() {
        let d = dir("commit");
        let out = OutputDir::create(&d, "analyze").unwrap();
        write(&out.path().join("a.csv"), "1");
        write(&out.path().join("figures/old.svg"), "<svg/>");
        // Nothing is visible before the commit.
        assert_eq!(names(&d).len(), 2, "{:?}", names(&d)); // lock + staging
        assert_eq!(
            out.final_path(&out.path().join("figures/old.svg")),
            d.join("figures/old.svg")
        );
        let m = out.commit().unwrap();
        assert_eq!(
            m.files,
            vec![
                RunFile {
                    path: "a.csv".into(),
                    bytes: 1
                },
                RunFile {
                    path: "figures/old.svg".into(),
                    bytes: 6
                }
            ]
        );
        assert_eq!(names(&d), ["a.csv", "ballpass-run.json", "figures"]);
        std::fs::write(d.join("user.txt"), "mine").unwrap();
        let out = OutputDir::create(&d, "analyze").unwrap();
        write(&out.path().join("a.csv"), "22");
        out.commit().unwrap();
        assert_eq!(names(&d), ["a.csv", "ballpass-run.json", "user.txt"]);
        assert_eq!(std::fs::read_to_string(d.join("a.csv")).unwrap(), "22");
        assert_eq!(RunManifest::read(&d).unwrap().files.len(), 1);
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Issue 18 item 8: a run that fails (dropped before its commit) leaves
    /// the previous run's outputs and manifest as they were.
    #[test]
    fn item8_a_failed_run_leaves_the_previous_outputs() {
        let d = dir("fail");
        let out = OutputDir::create(&d, "sweep").unwrap();
        write(&out.path().join("sweep.csv"), "old");
        out.commit().unwrap();
        let out = OutputDir::create(&d, "sweep").unwrap();
        write(&out.path().join("sweep.csv"), "new, half");
        drop(out);
        assert_eq!(names(&d), ["ballpass-run.json", "sweep.csv"]);
        assert_eq!(std::fs::read_to_string(d.join("sweep.csv")).unwrap(), "old");
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Issue 18 item 8: what a killed run left (a staging folder, a lock
    /// file with a dead pid, temporary files of a dead process) is cleaned
    /// by the next run.
    #[test]
    fn item8_leftovers_of_a_killed_run_are_cleaned() {
        let d = dir("stale");
        std::fs::create_dir_all(d.join(".ballpass-staging.4194999/figures")).unwrap();
        std::fs::write(d.join(".ballpass-staging.4194999/figures/x.svg"), "").unwrap();
        std::fs::write(d.join(LOCK_FILE), "4194999").unwrap();
        std::fs::create_dir_all(d.join("figures")).unwrap();
        std::fs::write(d.join("figures/.x.svg.4194999-3.tmp"), "half").unwrap();
        std::fs::write(d.join(".report.html.4194999-1.tmp"), "half").unwrap();
        let out = OutputDir::create(&d, "analyze").unwrap();
        out.commit().unwrap();
        assert_eq!(names(&d), ["ballpass-run.json", "figures"]);
        if cfg!(target_os = "linux") {
            assert!(names(&d.join("figures")).is_empty());
        }
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_file_in_the_way_is_an_error_naming_it() {
        let d = dir("file");
        std::fs::write(&d, "x").unwrap();
        let e = OutputDir::create(&d, "analyze").unwrap_err();
        assert!(matches!(&e, Error::Io { path, .. } if path == &d), "{e}");
        std::fs::remove_file(&d).unwrap();
    }

    #[test]
    fn manifest_paths_cannot_leave_the_folder() {
        assert!(safe_relative("figures/a.svg").is_some());
        for p in ["", "/etc/passwd", "../x", "a/../../x", "./a"] {
            assert!(safe_relative(p).is_none(), "{p}");
        }
    }
}
