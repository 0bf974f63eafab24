//! Scratch folders for tests that remove themselves when the test ends,
//! also when it fails (the guard drops while the panic unwinds), so test
//! runs leave nothing behind in the temp folder. Shared by the library's
//! unit tests, its integration tests and the CLI's end-to-end tests.

#![allow(dead_code)] // each user takes its own subset

use std::ffi::OsStr;
use std::ops::Deref;
use std::path::{Path, PathBuf};

/// A folder under the temp dir, removed on drop.
pub struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

impl Deref for Scratch {
    type Target = PathBuf;
    fn deref(&self) -> &PathBuf {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<OsStr> for Scratch {
    fn as_ref(&self) -> &OsStr {
        self.0.as_os_str()
    }
}

/// `<temp>/ballpass-<tag>-<name>-<pid>`, removed if it exists but not
/// created (for commands that must create their output folder).
pub fn scratch_path_in(tag: &str, name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("ballpass-{tag}-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    Scratch(d)
}

/// An empty scratch folder [`scratch_path_in`]`(tag, name)`, created.
pub fn scratch_in(tag: &str, name: &str) -> Scratch {
    let d = scratch_path_in(tag, name);
    std::fs::create_dir_all(&*d).expect("create a scratch folder under the temp dir");
    d
}
