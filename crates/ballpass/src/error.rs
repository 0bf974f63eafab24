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
    #[error("{}: {source}", shown_path(path))]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A text file has a bad cell or row.
    #[error("{}:{line}{}: {reason}", shown_path(path), column.as_ref().map(|c| format!(" column '{}'", excerpt(c))).unwrap_or_default())]
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
    #[error("{}: {reason}", shown_path(path))]
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

/// Longest excerpt of file or user text that a message quotes, in characters.
pub const EXCERPT_CHARS: usize = 60;

/// Text from a file or a user, made safe to quote in a one-line message:
/// control and direction-changing characters escaped (`\n`, `\r`, `\t`,
/// `\x1b`, `\u{202e}`, ...), and at most [`EXCERPT_CHARS`] characters kept,
/// the rest summarised as `… (N characters)`.
///
/// ```
/// use ballpass::error::excerpt;
/// assert_eq!(excerpt("1.5\r\n\x1b[31m"), "1.5\\r\\n\\x1b[31m");
/// let long = "x".repeat(1_000_000);
/// assert!(excerpt(&long).ends_with("… (1000000 characters)"));
/// ```
pub fn excerpt(s: &str) -> String {
    excerpt_within(s, EXCERPT_CHARS)
}

/// Longest path a message shows, in characters.
pub const PATH_CHARS: usize = 400;

/// A path as a message shows it: [`excerpt_within`] [`PATH_CHARS`].
pub fn shown_path(path: &std::path::Path) -> String {
    excerpt_within(&path.display().to_string(), PATH_CHARS)
}

/// Whether `c` must not reach a terminal or a log raw: C0 and C1
/// controls, DEL, and the Unicode marks that hide or reorder text
/// (zero-width characters, bidi overrides and isolates, line and paragraph
/// separators, the byte-order mark).
pub fn is_unsafe_char(c: char) -> bool {
    c.is_control()
        || matches!(c, '\u{200b}'..='\u{200f}' | '\u{2028}'..='\u{202e}' | '\u{2066}'..='\u{2069}' | '\u{feff}')
}

/// Appends `c` to `out`, escaped when [`is_unsafe_char`]: `\n`, `\r`, `\t`,
/// `\x1b` for the other ASCII controls, `\u{202e}` beyond ASCII.
pub fn push_escaped(out: &mut String, c: char) {
    match c {
        '\n' => out.push_str("\\n"),
        '\r' => out.push_str("\\r"),
        '\t' => out.push_str("\\t"),
        c if (c as u32) < 0x80 && c.is_control() => {
            out.push_str(&format!("\\x{:02x}", c as u32));
        }
        c if is_unsafe_char(c) => out.push_str(&format!("\\u{{{:x}}}", c as u32)),
        c => out.push(c),
    }
}

/// [`excerpt`] keeping at most `max_chars` characters.
pub fn excerpt_within(s: &str, max_chars: usize) -> String {
    let mut out = String::new();
    for (kept, c) in s.chars().enumerate() {
        if kept == max_chars {
            out.push_str(&format!("… ({} characters)", s.chars().count()));
            return out;
        }
        push_escaped(&mut out, c);
    }
    out
}

/// [`excerpt`] of bytes that may not be UTF-8 (invalid sequences shown as `\u{fffd}`).
pub fn excerpt_bytes(b: &[u8]) -> String {
    // Only the first characters are shown: decode a bounded prefix, then count.
    let head = &b[..b.len().min(4 * EXCERPT_CHARS + 4)];
    let text = String::from_utf8_lossy(head);
    let mut shown = excerpt(&text);
    if head.len() < b.len() && !shown.contains('…') {
        shown.push_str(&format!("… ({} bytes)", b.len()));
    } else if head.len() < b.len() {
        if let Some(p) = shown.find("… (") {
            shown.truncate(p);
            shown.push_str(&format!("… ({} bytes)", b.len()));
        }
    }
    shown
}
