//! Helpers shared by the end-to-end tests: the real `ballpass` binary, its
//! runs captured as text, scratch folders and the library's test files.
#![allow(dead_code)] // each test binary uses its own subset

use std::path::{Path, PathBuf};
use std::process::Command;

/// The binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ballpass"))
}

/// A finished run: exit code (-1 when killed by a signal), stdout and stderr.
pub struct Run {
    /// Exit code.
    pub code: i32,
    /// Standard output, lossily decoded.
    pub stdout: String,
    /// Standard error, lossily decoded.
    pub stderr: String,
}

impl Run {
    /// Whether the run exited with 0.
    pub fn ok(&self) -> bool {
        self.code == 0
    }
}

/// Runs `cmd` to the end, capturing its output.
pub fn output(cmd: &mut Command) -> Run {
    let o = cmd.output().expect("run ballpass");
    Run {
        code: o.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
    }
}

/// Runs `ballpass args…`: whether it succeeded, stdout, stderr.
pub fn run(args: &[&str]) -> (bool, String, String) {
    let r = output(bin().args(args));
    (r.ok(), r.stdout, r.stderr)
}

/// Runs `ballpass args…` in the folder `dir`.
pub fn run_in(dir: &Path, args: &[&str]) -> Run {
    output(bin().current_dir(dir).args(args))
}

/// Runs `cmd`, fails the test with its stderr unless it succeeds, and
/// returns its stdout.
pub fn run_ok(cmd: &mut Command) -> String {
    let r = output(cmd);
    assert!(r.ok(), "failed: {}", r.stderr);
    r.stdout
}

#[path = "../../../ballpass/tests/common/scratch.rs"]
mod scratch_dir;
pub use scratch_dir::Scratch;

/// `<temp>/ballpass-<test binary>-<name>-<pid>`, removed if it exists but
/// not created (for commands that must create their output folder);
/// removed again when the returned guard drops.
pub fn scratch_path(name: &str) -> Scratch {
    scratch_dir::scratch_path_in(env!("CARGO_CRATE_NAME"), name)
}

/// An empty scratch folder [`scratch_path`]`(name)`, created.
pub fn scratch(name: &str) -> Scratch {
    scratch_dir::scratch_in(env!("CARGO_CRATE_NAME"), name)
}

/// A file under the library's `crates/ballpass/tests/` (fixtures, data).
pub fn library_test_file(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../ballpass/tests")
        .join(rel)
}
