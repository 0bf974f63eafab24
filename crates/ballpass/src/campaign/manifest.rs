//! Campaign manifests: which recordings make up a campaign, with the bearing,
//! velocity and repeat of each.
//!
//! A manifest is a CSV file with a header and the columns
//! `path, bearing, velocity_mm_s, repeat` and, optionally, `condition` and
//! `notes` (any order, names matched ignoring case; other columns are kept
//! out). Relative paths are relative to the manifest's folder. Lines starting
//! with `#` are comments. The velocity may be left empty for a multi-speed
//! run that is segmented into its plateaus ([`super::segments`]), whose
//! speeds are measured from the encoder.
//!
//! Labs without a manifest name a folder and a file-name pattern instead
//! ([`from_directory`]): `*` matches any run of characters, and the fields
//! `{velocity}`, `{repeat}`, `{bearing}` match a run of characters that is
//! read as that field, e.g. `v{velocity}_r{repeat}.csv`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::pattern::{Field, Pattern};
use crate::error::{excerpt, Error, Result};

/// One recording of a campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ManifestEntry {
    /// The recording file, resolved against the manifest's folder.
    pub path: PathBuf,
    /// Bearing name.
    pub bearing: String,
    /// Commanded tracking velocity, mm/s; NaN where the manifest leaves it
    /// empty (a multi-speed run whose plateaus' measured speeds are used,
    /// see [`super::segments`]).
    pub velocity_mm_s: f64,
    /// Repeat number.
    pub repeat: u32,
    /// Known condition (e.g. `good`, `sticking`), when the manifest says.
    pub condition: Option<String>,
    /// Free notes.
    pub notes: Option<String>,
    /// The plateau of a multi-speed run this entry stands for (see
    /// [`super::segments`]); `None`: the whole file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plateau: Option<super::segments::PlateauSource>,
}

/// A whole campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Where it came from (manifest file or folder).
    pub source: PathBuf,
    /// Its recordings, in file order.
    pub entries: Vec<ManifestEntry>,
    /// Folder mode: what in the folder was left out, and why (see
    /// [`from_directory`]); empty for a manifest file.
    #[serde(default)]
    pub skipped: Vec<Skipped>,
}

/// Something in a folder that folder mode left out.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Skipped {
    /// The name in the folder (lossily decoded for display).
    pub name: String,
    /// Why (`a folder`, `a broken link`, `does not match the pattern`, ...).
    pub reason: String,
}

impl ManifestEntry {
    /// The file, and for a plateau which one: `run.tdms (plateau 2 of 6,
    /// t = 4.100–6.900 s, -42.03 mm/s)`.
    pub fn label(&self) -> String {
        match &self.plateau {
            None => self.path.display().to_string(),
            Some(p) => format!(
                "{} (plateau {} of {}, t = {:.3}–{:.3} s, {:.2} mm/s)",
                self.path.display(),
                p.index,
                p.of,
                p.plateau.start_s,
                p.plateau.end_s,
                p.plateau.velocity_mm_s
            ),
        }
    }
}

impl Manifest {
    /// Distinct bearings, sorted.
    pub fn bearings(&self) -> Vec<String> {
        let mut b: Vec<String> = self.entries.iter().map(|e| e.bearing.clone()).collect();
        b.sort();
        b.dedup();
        b
    }

    /// Entries grouped by velocity (ordered by velocity).
    pub fn by_velocity(&self) -> BTreeMap<OrderedVelocity, Vec<&ManifestEntry>> {
        let mut m: BTreeMap<OrderedVelocity, Vec<&ManifestEntry>> = BTreeMap::new();
        for e in &self.entries {
            m.entry(OrderedVelocity(e.velocity_mm_s))
                .or_default()
                .push(e);
        }
        m
    }
}

/// A velocity usable as an ordered map key (total order of f64).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrderedVelocity(pub f64);

impl Eq for OrderedVelocity {}

impl PartialOrd for OrderedVelocity {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for OrderedVelocity {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

const REQUIRED: [&str; 4] = ["path", "bearing", "velocity_mm_s", "repeat"];

/// Reads a manifest CSV.
///
/// # Errors
/// [`Error::Io`] when it cannot be read; [`Error::Parse`] naming the line and
/// column for a missing column, an empty path or bearing, a velocity that is
/// not a positive number, a repeat that is not a whole number, a ragged row or
/// a duplicate (bearing, velocity, repeat); [`Error::Format`] for a manifest
/// without entries.
pub fn read_manifest(path: &Path) -> Result<Manifest> {
    let text = crate::fsutil::read_text(path, "a manifest is CSV text")?;
    parse_manifest(path, &text)
}

/// Parses manifest text; `path` names it in messages and relative paths in
/// it are relative to its folder.
///
/// # Errors
/// As [`read_manifest`].
pub fn parse_manifest(path: &Path, text: &str) -> Result<Manifest> {
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let parse_err = |line: usize, column: Option<&str>, reason: String| Error::Parse {
        path: path.to_path_buf(),
        line,
        column: column.map(str::to_string),
        reason,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((hline, header)) = lines.next() else {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: "empty manifest; expected a header `path,bearing,velocity_mm_s,repeat`".into(),
        });
    };
    let names: Vec<String> = split_row(header)
        .iter()
        .map(|s| s.to_ascii_lowercase())
        .collect();
    let col = |want: &str| names.iter().position(|n| n == want);
    for want in REQUIRED {
        if col(want).is_none() {
            return Err(parse_err(
                hline,
                None,
                format!("header has no column '{want}' (expected path, bearing, velocity_mm_s, repeat[, condition, notes])"),
            ));
        }
    }
    let (ip, ib, iv, ir) = (
        col("path").unwrap_or(0),
        col("bearing").unwrap_or(0),
        col("velocity_mm_s").unwrap_or(0),
        col("repeat").unwrap_or(0),
    );
    let (ic, inotes) = (col("condition"), col("notes"));
    let mut entries = Vec::new();
    let mut seen = BTreeMap::new();
    for (line, row) in lines {
        let cells = split_row(row);
        if cells.len() != names.len() {
            return Err(parse_err(
                line,
                None,
                format!("{} fields, but the header has {}", cells.len(), names.len()),
            ));
        }
        let p = cells[ip].trim();
        if p.is_empty() {
            return Err(parse_err(line, Some("path"), "empty path".into()));
        }
        let bearing = cells[ib].trim().to_string();
        if bearing.is_empty() {
            return Err(parse_err(
                line,
                Some("bearing"),
                "empty bearing name".into(),
            ));
        }
        // Empty: a multi-speed run, its plateaus' speeds measured.
        let velocity_mm_s: f64 = if cells[iv].trim().is_empty() {
            Ok(f64::NAN)
        } else {
            cells[iv]
                .trim()
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite() && *v > 0.0)
                .ok_or(())
        }
        .map_err(|()| {
            parse_err(
                line,
                Some("velocity_mm_s"),
                format!(
                    "'{}' is not a positive number of mm/s",
                    excerpt(cells[iv].trim())
                ),
            )
        })?;
        let repeat: u32 = cells[ir].trim().parse().map_err(|_| {
            parse_err(
                line,
                Some("repeat"),
                format!("'{}' is not a whole number", excerpt(cells[ir].trim())),
            )
        })?;
        let opt = |i: Option<usize>| {
            i.map(|i| cells[i].trim().to_string())
                .filter(|s| !s.is_empty())
        };
        let key = (bearing.clone(), velocity_mm_s.to_bits(), repeat);
        if let Some(prev) = seen.insert(key, line) {
            return Err(parse_err(
                line,
                None,
                format!(
                    "bearing {}, {velocity_mm_s} mm/s, repeat {repeat} already listed on line {prev}",
                    excerpt(&bearing)
                ),
            ));
        }
        let rel = PathBuf::from(p);
        entries.push(ManifestEntry {
            path: if rel.is_absolute() {
                rel
            } else {
                base.join(rel)
            },
            bearing,
            velocity_mm_s,
            repeat,
            condition: opt(ic),
            notes: opt(inotes),
            plateau: None,
        });
    }
    if entries.is_empty() {
        return Err(Error::Format {
            path: path.to_path_buf(),
            reason: "manifest lists no recordings".into(),
        });
    }
    Ok(Manifest {
        source: path.to_path_buf(),
        entries,
        skipped: Vec::new(),
    })
}

/// Splits one CSV row on commas, honouring double quotes around a cell.
fn split_row(row: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = row.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(std::mem::take(&mut cur).trim().to_string()),
            c => cur.push(c),
        }
    }
    out.push(cur.trim().to_string());
    out
}

/// Writes a manifest CSV (`path,bearing,velocity_mm_s,repeat,condition,notes`)
/// to a string, with paths as given.
pub fn manifest_csv(entries: &[ManifestEntry]) -> String {
    let quote = |s: &str| {
        if s.contains([',', '"', '\n']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    };
    let mut s = String::from("path,bearing,velocity_mm_s,repeat,condition,notes\n");
    for e in entries {
        s.push_str(&format!(
            "{},{},{},{},{},{}\n",
            quote(&e.path.to_string_lossy()),
            quote(&e.bearing),
            e.velocity_mm_s,
            e.repeat,
            quote(e.condition.as_deref().unwrap_or("")),
            quote(e.notes.as_deref().unwrap_or(""))
        ));
    }
    s
}

/// Builds a manifest from the files of a folder whose names match `pattern`
/// (see [`Pattern`] for the syntax and how matching works).
///
/// `{velocity}` (mm/s), `{repeat}` and `{bearing}` in the pattern capture those
/// fields from the name; `*` matches anything. A field the pattern does not
/// capture comes from the defaults: `bearing` (required then) and
/// `velocity_mm_s` (required then); repeats are numbered 1, 2, … in name
/// order per (bearing, velocity) when not captured.
///
/// Links are followed: a link to a file is a recording like the file. A name
/// that is not valid UTF-8 is matched in its lossy form (each bad byte reads
/// as `�`, which `*` and fields match) and its file is opened by its real
/// name. Everything left out is listed in [`Manifest::skipped`] with the
/// reason: entries whose name matches but that are not readable files
/// (folders, broken links, sockets), and each name that does not match.
///
/// # Errors
/// [`Error::Io`] for an unreadable folder; [`Error::InvalidSetting`] for a
/// pattern with an unknown field, a missing default, a captured velocity or
/// repeat that is not a number, or no matching file.
pub fn from_directory(
    dir: &Path,
    pattern: &str,
    bearing: Option<&str>,
    velocity_mm_s: Option<f64>,
) -> Result<Manifest> {
    let pat = Pattern::parse(pattern)?;
    if !pat.has(Field::Bearing) && bearing.is_none() {
        return Err(Error::setting(
            "bearing",
            "the pattern has no {bearing}: give --bearing",
        ));
    }
    if !pat.has(Field::Velocity) && velocity_mm_s.is_none() {
        return Err(Error::setting(
            "velocity",
            "the pattern has no {velocity}: give --velocity",
        ));
    }
    let io_err = |source| Error::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut found: Vec<(String, std::ffi::OsString)> = Vec::new();
    for e in std::fs::read_dir(dir).map_err(io_err)? {
        let e = e.map_err(io_err)?;
        let os = e.file_name();
        found.push((os.to_string_lossy().into_owned(), os));
    }
    found.sort();
    let mut entries = Vec::new();
    let mut skipped = Vec::new();
    let mut counters: BTreeMap<(String, u64), u32> = BTreeMap::new();
    for (name, os) in found {
        let path = dir.join(&os);
        let Some(caps) = pat.captures(&name) else {
            skipped.push(Skipped {
                name,
                reason: format!("does not match '{pattern}'"),
            });
            continue;
        };
        // `metadata` follows links: a link to a file is a file.
        let kind = match std::fs::metadata(&path) {
            Ok(m) if m.is_file() => None,
            Ok(m) if m.is_dir() => Some("a folder".to_string()),
            Ok(_) => Some("not a regular file".to_string()),
            Err(e) if std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_symlink()) => {
                Some(format!("a broken link ({e})"))
            }
            Err(e) => Some(format!("cannot be read ({e})")),
        };
        if let Some(reason) = kind {
            skipped.push(Skipped { name, reason });
            continue;
        }
        let get = |f: Field| caps.iter().find(|(g, _)| *g == f).map(|(_, s)| s.clone());
        let bearing = get(Field::Bearing)
            .or_else(|| bearing.map(str::to_string))
            .unwrap_or_default();
        let velocity = match get(Field::Velocity) {
            Some(s) => s
                .replace('p', ".")
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| {
                    Error::setting(
                        "pattern",
                        format!(
                            "{}: '{s}' captured as {{velocity}} is not a positive number",
                            name
                        ),
                    )
                })?,
            None => velocity_mm_s.unwrap_or(f64::NAN),
        };
        let repeat = match get(Field::Repeat) {
            Some(s) => s.parse::<u32>().map_err(|_| {
                Error::setting(
                    "pattern",
                    format!("{name}: '{s}' captured as {{repeat}} is not a whole number"),
                )
            })?,
            None => {
                let c = counters
                    .entry((bearing.clone(), velocity.to_bits()))
                    .or_insert(0);
                *c += 1;
                *c
            }
        };
        entries.push(ManifestEntry {
            path,
            bearing,
            velocity_mm_s: velocity,
            repeat,
            condition: None,
            notes: None,
            plateau: None,
        });
    }
    if entries.is_empty() {
        let why: Vec<String> = skipped
            .iter()
            .filter(|s| !s.reason.starts_with("does not match"))
            .map(|s| format!("{} is {}", s.name, s.reason))
            .collect();
        return Err(Error::setting(
            "pattern",
            if why.is_empty() {
                format!("no file in {} matches '{pattern}'", dir.display())
            } else {
                format!(
                    "no file in {} matches '{pattern}' ({})",
                    dir.display(),
                    why.join("; ")
                )
            },
        ));
    }
    Ok(Manifest {
        source: dir.to_path_buf(),
        entries,
        skipped,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmpdir(tag: &str) -> crate::test_scratch::Scratch {
        crate::test_scratch::scratch_in("manifest", tag)
    }

    #[test]
    fn reads_a_manifest_with_relative_paths_and_optional_columns() {
        let d = tmpdir("ok");
        let m = d.join("manifest.csv");
        std::fs::write(
            &m,
            "# campaign\nPath,bearing,velocity_mm_s,repeat,condition\nv9/r1.csv,b1,9,1,good\n\"v 9/r2.csv\",b1,9.0,2,\n",
        )
        .unwrap();
        let man = read_manifest(&m).unwrap();
        assert_eq!(man.entries.len(), 2);
        assert_eq!(man.entries[0].path, d.join("v9/r1.csv"));
        assert_eq!(man.entries[0].condition.as_deref(), Some("good"));
        assert_eq!(man.entries[1].path, d.join("v 9/r2.csv"));
        assert_eq!(man.entries[1].condition, None);
        // Round trip through the writer.
        std::fs::write(&m, manifest_csv(&man.entries)).unwrap();
        assert_eq!(read_manifest(&m).unwrap().entries, man.entries);
    }

    /// A manifest that is not UTF-8 text, or cannot be read, is an error
    /// naming the file (and the line of the first bad byte).
    #[test]
    fn a_manifest_that_is_not_text_names_its_line() {
        let d = tmpdir("not-utf8");
        let m = d.join("m.csv");
        std::fs::write(&m, b"path,bearing,velocity_mm_s,repeat\nr\xff.csv,b1,9,1\n").unwrap();
        let e = read_manifest(&m).unwrap_err().to_string();
        let want = format!("{}:2", m.display());
        assert!(e.starts_with(&want), "{e}");
        assert!(e.contains("not UTF-8; a manifest is CSV text"), "{e}");
        let e = read_manifest(&d.join("absent.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("absent.csv"), "{e}");
    }

    /// An empty velocity is "measured" (NaN) for a segmented run; the
    /// entry says which plateau it is once segmented.
    #[test]
    fn an_empty_velocity_is_left_to_the_plateaus() {
        let d = tmpdir("empty-v");
        let m = d.join("m.csv");
        std::fs::write(
            &m,
            "path,bearing,velocity_mm_s,repeat
run.tdms,b1,,1
",
        )
        .unwrap();
        let man = read_manifest(&m).unwrap();
        assert!(man.entries[0].velocity_mm_s.is_nan());
        assert_eq!(
            man.entries[0].label(),
            d.join("run.tdms").display().to_string()
        );
    }

    #[test]
    fn bad_manifests_name_line_and_column() {
        let d = tmpdir("bad");
        let m = d.join("m.csv");
        for (text, want) in [
            ("path,bearing,repeat\na,b,1\n", "no column 'velocity_mm_s'"),
            (
                "path,bearing,velocity_mm_s,repeat\na,b,fast,1\n",
                ":2 column 'velocity_mm_s'",
            ),
            (
                "path,bearing,velocity_mm_s,repeat\na,b,0,1\n",
                "not a positive number",
            ),
            (
                "path,bearing,velocity_mm_s,repeat\na,b,9,x\n",
                ":2 column 'repeat'",
            ),
            ("path,bearing,velocity_mm_s,repeat\na,b,9\n", ":2: 3 fields"),
            (
                "path,bearing,velocity_mm_s,repeat\na,b,9,1\nc,b,9,1\n",
                "already listed on line 2",
            ),
            ("path,bearing,velocity_mm_s,repeat\n", "no recordings"),
            ("", "empty manifest"),
        ] {
            std::fs::write(&m, text).unwrap();
            let err = read_manifest(&m).unwrap_err().to_string();
            assert!(
                err.contains(want) && err.contains("m.csv"),
                "{text:?}: {err}"
            );
        }
    }

    #[test]
    fn directory_pattern_captures_fields() {
        let d = tmpdir("dir");
        for n in ["v9_r1.csv", "v9_r2.csv", "v12p5_r1.csv", "notes.txt"] {
            std::fs::write(d.join(n), "").unwrap();
        }
        let m = from_directory(&d, "v{velocity}_r{repeat}.csv", Some("sr25w"), None).unwrap();
        let mut got: Vec<(f64, u32)> = m
            .entries
            .iter()
            .map(|e| (e.velocity_mm_s, e.repeat))
            .collect();
        got.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        assert_eq!(got, vec![(9.0, 1), (9.0, 2), (12.5, 1)]);
        let m = from_directory(&d, "*.csv", Some("b"), Some(3.0)).unwrap();
        assert_eq!(
            m.entries.iter().map(|e| e.repeat).collect::<Vec<_>>(),
            vec![1, 2, 3]
        );
        assert!(from_directory(&d, "{speed}.csv", Some("b"), None).is_err());
        assert!(from_directory(&d, "*.csv", None, Some(3.0)).is_err());
        assert!(from_directory(&d, "*.dat", Some("b"), Some(3.0)).is_err());
    }

    /// Issue 18 item 9: a linked recording and a file whose name is not
    /// UTF-8 are recordings like the others; what is left out is listed
    /// with the reason.
    #[cfg(unix)]
    #[test]
    fn item9_links_and_non_utf8_names_are_read_and_skips_are_listed() {
        use std::os::unix::ffi::OsStrExt;
        let d = tmpdir("item9");
        let real = tmpdir("item9-real");
        std::fs::write(real.join("elsewhere.csv"), "").unwrap();
        std::fs::write(d.join("v9_r1.csv"), "").unwrap();
        std::os::unix::fs::symlink(real.join("elsewhere.csv"), d.join("v9_r2.csv")).unwrap();
        std::os::unix::fs::symlink(d.join("gone.csv"), d.join("v9_r4.csv")).unwrap();
        let odd = std::ffi::OsStr::from_bytes(b"v9_r3_caf\xe9.csv");
        std::fs::write(d.join(odd), "").unwrap();
        std::fs::create_dir(d.join("v9_r5.csv")).unwrap();
        std::fs::write(d.join("notes.txt"), "").unwrap();
        let m = from_directory(&d, "v{velocity}_r{repeat}*.csv", Some("b"), None).unwrap();
        let repeats: Vec<u32> = m.entries.iter().map(|e| e.repeat).collect();
        assert_eq!(repeats, [1, 2, 3]);
        assert_eq!(m.entries[2].path, d.join(odd));
        let why = |n: &str| {
            m.skipped
                .iter()
                .find(|s| s.name == n)
                .map(|s| s.reason.clone())
                .unwrap_or_default()
        };
        assert!(
            why("v9_r4.csv").starts_with("a broken link"),
            "{:?}",
            m.skipped
        );
        assert_eq!(why("v9_r5.csv"), "a folder");
        assert!(why("notes.txt").starts_with("does not match"));
        assert_eq!(m.skipped.len(), 3);
        // Nothing readable: the error says what was there.
        let e = from_directory(&d, "v9_r5.csv", Some("b"), Some(9.0)).unwrap_err();
        assert!(e.to_string().contains("v9_r5.csv is a folder"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
        std::fs::remove_dir_all(&real).unwrap();
    }
}
