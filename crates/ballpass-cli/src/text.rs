//! Text the CLI prints that came from a user or a file: escaped and bounded,
//! so that a file name or a cell can neither forge lines (CR/LF), drive the
//! terminal (escape sequences) nor flood it (a 1 MB cell in an error).

use std::borrow::Cow;
use std::ffi::OsStr;
use std::path::Path;

use ballpass::error::{is_unsafe_char, push_escaped};

/// Longest line the CLI prints for an error, warning or note, in
/// characters: long enough for any real message with two full paths.
pub const MAX_LINE_CHARS: usize = 2000;

/// `s` with every character that must not reach a terminal raw escaped
/// ([`ballpass::error::push_escaped`]: `\n`, `\r`, `\t`, `\x1b`,
/// `\u{202e}`); `s` itself when it has none.
pub fn escape(s: &str) -> Cow<'_, str> {
    if !s.chars().any(is_unsafe_char) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        push_escaped(&mut out, c);
    }
    Cow::Owned(out)
}

/// [`escape`]d and cut to at most `max` characters: the start and the end
/// are kept and the middle is replaced by `… [N characters left out] …`.
pub fn bounded(s: &str, max: usize) -> String {
    let e = escape(s);
    let n = e.chars().count();
    if n <= max {
        return e.into_owned();
    }
    let head = max * 3 / 4;
    let tail = max / 5;
    let start: String = e.chars().take(head).collect();
    let end: String = e.chars().skip(n - tail).collect();
    format!(
        "{start} … [{} characters left out] … {end}",
        n - head - tail
    )
}

/// A line for the terminal: [`bounded`] to [`MAX_LINE_CHARS`].
pub fn line(s: &str) -> String {
    bounded(s, MAX_LINE_CHARS)
}

/// A path for the terminal: lossy, escaped.
pub fn path(p: &Path) -> String {
    escape(&p.to_string_lossy()).into_owned()
}

/// One argument as a shell word that gives back exactly the same bytes:
/// plain when it is safe, single-quoted when it has spaces or shell
/// characters, `$'…'` with `\xNN` escapes when it has bytes that are not
/// UTF-8 or control characters.
pub fn shell_word(arg: &OsStr) -> String {
    let bytes = arg.as_encoded_bytes();
    let plain = |b: u8| b.is_ascii_alphanumeric() || b"-_./:=,+@%^".contains(&b);
    if !bytes.is_empty() && bytes.iter().all(|&b| plain(b)) {
        return String::from_utf8_lossy(bytes).into_owned();
    }
    let needs_ansi = match arg.to_str() {
        Some(s) => s.chars().any(is_unsafe_char),
        None => true,
    };
    if !needs_ansi {
        let s = arg.to_string_lossy();
        return format!("'{}'", s.replace('\'', r"'\''"));
    }
    let mut out = String::from("$'");
    for chunk in bytes.utf8_chunks() {
        for c in chunk.valid().chars() {
            match c {
                '\\' => out.push_str("\\\\"),
                '\'' => out.push_str("\\'"),
                '\n' => out.push_str("\\n"),
                '\r' => out.push_str("\\r"),
                '\t' => out.push_str("\\t"),
                c if is_unsafe_char(c) => {
                    let mut buf = [0u8; 4];
                    for b in c.encode_utf8(&mut buf).bytes() {
                        out.push_str(&format!("\\x{b:02x}"));
                    }
                }
                c => out.push(c),
            }
        }
        for b in chunk.invalid() {
            out.push_str(&format!("\\x{b:02x}"));
        }
    }
    out.push('\'');
    out
}

/// The command line as typed, for a report's header: every argument as a
/// [`shell_word`] (never fails, whatever bytes the arguments hold).
pub fn command_line() -> String {
    std::env::args_os()
        .map(|a| shell_word(&a))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controls_are_escaped_and_plain_text_is_kept() {
        assert!(matches!(escape("plain é text"), Cow::Borrowed(_)));
        assert_eq!(escape("a\nb\r\x1b[2Jc\t"), "a\\nb\\r\\x1b[2Jc\\t");
        assert_eq!(escape("x\u{202e}y"), "x\\u{202e}y");
    }

    /// Issue 18 item 11: a 1 MB cell no longer makes a 1 MB error line.
    #[test]
    fn item11_lines_are_bounded_keeping_both_ends() {
        let s = format!("file.csv:3: '{}' is not a number", "9".repeat(1_000_000));
        let l = line(&s);
        assert!(l.chars().count() <= MAX_LINE_CHARS + 60, "{}", l.len());
        assert!(l.starts_with("file.csv:3: '999"));
        assert!(l.ends_with("' is not a number"));
        assert!(l.contains("characters left out"));
        assert_eq!(line("short"), "short");
    }

    /// Issue 18 item 6: any argument bytes give a command line that a shell
    /// reads back to the same bytes.
    #[test]
    fn item6_shell_words_are_lossless() {
        assert_eq!(shell_word(OsStr::new("--out")), "--out");
        assert_eq!(shell_word(OsStr::new("a b")), "'a b'");
        assert_eq!(shell_word(OsStr::new("it's")), r"'it'\''s'");
        assert_eq!(shell_word(OsStr::new("")), "''");
        assert_eq!(shell_word(OsStr::new("a\nb")), r"$'a\nb'");
        #[cfg(unix)]
        {
            use std::os::unix::ffi::OsStrExt;
            let w = shell_word(OsStr::from_bytes(b"caf\xe9 'x'.csv"));
            assert_eq!(w, r"$'caf\xe9 \'x\'.csv'");
        }
    }
}
