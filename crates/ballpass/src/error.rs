//! The one error type of the `ballpass` domain library.

use std::path::PathBuf;

/// Result alias used across the domain library.
pub type Result<T> = std::result::Result<T, Error>;

/// Everything that can go wrong between a file on disk and a result.
///
/// Messages are one line and name where the problem is (file, line, column,
/// channel) and what was expected.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A text file has a bad cell or row.
    #[error("{}:{line}{}: {reason}", path.display(), column.as_ref().map(|c| format!(" column '{c}'")).unwrap_or_default())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// Column name, when the problem is in one cell.
        column: Option<String>,
        /// What was found and what was expected.
        reason: String,
    },
    /// A file is not of the format its name or contents claim.
    #[error("{}: {reason}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// An analysis needs a channel that the recording does not have.
    #[error("{source_name}: channel {channel} is missing ({needed_for} needs it)")]
    MissingChannel {
        /// Canonical channel name (`friction_N`, `position_mm`, `optical_V`).
        channel: &'static str,
        /// File or test the recording came from.
        source_name: String,
        /// What needed it.
        needed_for: &'static str,
    },
    /// A channel's samples are unusable.
    #[error("{source_name}: channel {channel}: {reason}")]
    InvalidChannel {
        /// Canonical channel name.
        channel: String,
        /// File or test the recording came from.
        source_name: String,
        /// What is wrong.
        reason: String,
    },
    /// A recording is readable but unusable as a whole (e.g. too short).
    #[error("{source_name}: {reason}")]
    InvalidRecording {
        /// File or test the recording came from.
        source_name: String,
        /// What is wrong, with the numbers.
        reason: String,
    },
    /// A setting or parameter given by the user is out of range.
    #[error("invalid {name}: {reason}")]
    InvalidSetting {
        /// The setting's name as the user knows it (flag or field).
        name: String,
        /// What is wrong, with the value.
        reason: String,
    },
    /// The optical channel holds no ball passages that can be measured.
    #[error("{source_name}: no ball passages found in optical_V: {reason}")]
    NoPassages {
        /// File or test the recording came from.
        source_name: String,
        /// What was found instead, with the threshold.
        reason: String,
    },
    /// Another process is writing the output folder (it holds its lock).
    #[error("{}: in use by {holder}; wait for it to finish or choose another output folder", path.display())]
    OutputInUse {
        /// The output folder.
        path: PathBuf,
        /// Who holds it (`another ballpass run (pid 1234)`).
        holder: String,
    },
    /// A kernel of `ballpass-dsp` rejected its input.
    #[error("{context}: {source}")]
    Dsp {
        /// What was being computed, on what.
        context: String,
        /// The kernel's error.
        source: ballpass_dsp::DspError,
    },
    /// A figure or report cannot be built: malformed figure data (length
    /// mismatch, bad range, nothing drawable), a bad id, or drawing failed.
    #[error("report: {what}: {reason}")]
    Report {
        /// Which figure, panel or series (`figure 'corr_ff' panel 2 series 'R'`).
        what: String,
        /// What is wrong, with the values.
        reason: String,
    },
}

impl Error {
    /// Shorthand for [`Error::InvalidSetting`].
    pub fn setting(name: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidSetting {
            name: name.into(),
            reason: reason.into(),
        }
    }

    /// Shorthand for [`Error::Dsp`] with a context.
    pub fn dsp(context: impl Into<String>, source: ballpass_dsp::DspError) -> Self {
        Error::Dsp {
            context: context.into(),
            source,
        }
    }
}
