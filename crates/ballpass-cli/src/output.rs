//! Where results go: output folders ([`ballpass::outdir::OutputDir`]: one
//! run at a time, outputs staged and committed together with
//! `ballpass-run.json` last; the files in them are written by the library,
//! atomically), and standard output with errors that say it was standard
//! output.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use ballpass::outdir::OutputDir;

/// Creates, locks and stages the output folder `dir` of `command`.
pub fn open_dir(dir: &Path, command: &str) -> Result<OutputDir> {
    Ok(OutputDir::create(dir, command)?)
}

/// Commits a staged output folder; returns the folder.
pub fn commit(out: OutputDir) -> Result<PathBuf> {
    let dir = out.dir().to_path_buf();
    out.commit()
        .with_context(|| format!("{}: outputs not complete", dir.display()))?;
    Ok(dir)
}

/// Standard output, locked, whose write errors say "standard output"
/// (a full disk behind `> file` is otherwise "No space left on device"
/// with no file named). The error kind is kept, so a closed pipe is still
/// recognised as one.
pub struct Stdout(std::io::StdoutLock<'static>);

/// Locks standard output (see [`Stdout`]).
pub fn stdout() -> Stdout {
    Stdout(std::io::stdout().lock())
}

fn named(e: std::io::Error) -> std::io::Error {
    std::io::Error::new(e.kind(), format!("writing to standard output: {e}"))
}

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.write(buf).map_err(named)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.0.write_all(buf).map_err(named)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush().map_err(named)
    }
}

impl Drop for Stdout {
    /// Text still buffered is flushed here; an error then cannot be
    /// returned, and every command flushes before it reports success.
    fn drop(&mut self) {
        let _ = self.0.flush();
    }
}

/// A spinner with the elapsed time and a message naming the current step,
/// on a terminal (long records take a while per step); `None` when stderr
/// is a file or a pipe. Steps are announced with `set_message`; the
/// spinner is cleared with `finish_and_clear` or when dropped.
pub fn steps(first: &str) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    std::io::stderr().is_terminal().then(|| {
        let b = indicatif::ProgressBar::new_spinner();
        b.set_style(
            indicatif::ProgressStyle::with_template("{spinner} {msg}  {elapsed}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        );
        b.set_message(first.to_string());
        b.enable_steady_tick(std::time::Duration::from_millis(200));
        b
    })
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
