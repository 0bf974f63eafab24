//! Bench profiles: what a lab writes once about its test bench (TOML).
//!
//! ```toml
//! name = "UNH air-bearing stage, dSPACE DS1103"
//! format = "mat"                 # csv | tsv | mat | tdms | mf4; default: from the file name
//! fs_hz = 1000.0                 # needed when files have no time column
//! # fs_from = "bearing.sr"       # or: a MAT variable / struct field holding it
//! time = "Zeit"                  # time column / variable, default time_s
//! # time_unit = "ms"             # s | ms | us; default: what the file states, else s
//! # decimal_comma = true         # default: detected
//! # skip_lines = 4               # lines before the header; default: found
//! # fill_gaps = 0.005            # fill gaps up to 5 ms by linear interpolation
//! # split_gaps = true            # split the record at longer gaps
//! bearing = "sr25w"              # catalog key
//! min_periods = 3.0
//!
//! [friction]                     # value = raw * scale + offset
//! name = "Model Root/Load cell/Force"
//! scale = 1.0
//!
//! [position]
//! name = "Counts"
//! scale = 1e-4                   # encoder counts of 0.1 um -> mm
//!
//! [optical]
//! name = "Voltage"
//!
//! [geometry]                     # custom geometry, overrides the catalog's fields
//! balls_in_race = 35
//!
//! [analysis]                     # defaults for the analysis stages, kept as given
//! lowpass_hz = 20.0
//! ```
//!
//! Unknown keys are errors (a misspelt `fs` is reported, not ignored), except
//! inside `[analysis]`, which later stages read with their own settings types.
//! Every error names the profile file and the line of the key at fault.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::io::{ChannelSource, Format, GapPolicy, LoadOptions, TimeUnit};
use crate::bearing::{self, Geometry};
use crate::error::{Error, Result};

/// One test bench's file layout, scales, rate, bearing and analysis defaults.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Profile {
    /// Name of the bench, for reports.
    pub name: Option<String>,
    /// File format; `None`: from the file name.
    pub format: Option<Format>,
    /// Field delimiter of text files: `","`, `";"`, `"tab"`; `None`: detected.
    pub delimiter: Option<String>,
    /// Sampling rate, Hz.
    pub fs_hz: Option<f64>,
    /// MAT variable or struct field holding the sampling rate, Hz.
    pub fs_from: Option<String>,
    /// Time column / variable name.
    pub time: Option<String>,
    /// Unit of the time column.
    pub time_unit: Option<TimeUnit>,
    /// Text files write numbers with a decimal comma; `None`: detected.
    pub decimal_comma: Option<bool>,
    /// Lines before the header of text files; `None`: found.
    pub skip_lines: Option<usize>,
    /// Fill gaps up to this long, s, by linear interpolation.
    pub fill_gaps: Option<f64>,
    /// Split records at the gaps that are not filled.
    pub split_gaps: bool,
    /// Ignore the time column and use `fs_hz`.
    pub ignore_time: bool,
    /// Largest relative deviation of one time step from the median step.
    pub time_step_tolerance: Option<f64>,
    /// Friction channel source.
    pub friction: ChannelSource,
    /// Position channel source.
    pub position: ChannelSource,
    /// Optical channel source.
    pub optical: ChannelSource,
    /// Bearing catalog key.
    pub bearing: Option<String>,
    /// Custom geometry fields, overriding the catalog entry's.
    pub geometry: Option<GeometryOverride>,
    /// Fewest ball-pass periods a recording must span.
    pub min_periods: Option<f64>,
    /// Default settings of the analysis stages, as written.
    pub analysis: Option<serde_json::Value>,
    /// File the profile was read from (not read from TOML).
    #[serde(skip)]
    pub source: Option<PathBuf>,
}

/// Geometry fields a profile or flags may set on top of a catalog entry.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GeometryOverride {
    /// Ball diameter `d`, mm.
    pub ball_diameter_mm: Option<f64>,
    /// Total free space in the race `d_ext`, mm.
    pub free_space_mm: Option<f64>,
    /// Balls in the race `N_B`.
    pub balls_in_race: Option<u32>,
}

impl GeometryOverride {
    /// True when no field is set.
    pub fn is_empty(&self) -> bool {
        self.ball_diameter_mm.is_none()
            && self.free_space_mm.is_none()
            && self.balls_in_race.is_none()
    }

    /// `base` with the set fields replaced, validated.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for an out-of-range field.
    pub fn apply(&self, mut base: Geometry) -> Result<Geometry> {
        if let Some(d) = self.ball_diameter_mm {
            base.ball_diameter_mm = d;
        }
        if let Some(d) = self.free_space_mm {
            base.free_space_mm = d;
        }
        if let Some(n) = self.balls_in_race {
            base.balls_in_race = n;
        }
        base.validate()?;
        Ok(base)
    }
}

impl Profile {
    /// Reads and checks a profile file.
    ///
    /// # Errors
    /// [`Error::Io`] when unreadable; [`Error::Parse`] naming the line for bad
    /// TOML, an unknown key, a value of the wrong type or out of range.
    pub fn read(path: &Path) -> Result<Self> {
        let text = crate::fsutil::read_text(path, "a profile is TOML text")?;
        let mut p = Self::parse(path, &text)?;
        p.source = Some(path.to_path_buf());
        p.load_options().map_err(|e| locate(path, &text, e))?;
        Ok(p)
    }

    /// Parses profile text; `path` is only used in messages.
    ///
    /// # Errors
    /// [`Error::Parse`] with the line of the problem.
    pub fn parse(path: &Path, text: &str) -> Result<Self> {
        toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1)
                .unwrap_or(0);
            Error::Parse {
                path: path.to_path_buf(),
                line,
                column: None,
                reason: crate::error::excerpt_within(e.message().trim(), 300),
            }
        })
    }

    /// The bearing the profile names, with its geometry overrides applied:
    /// `(name, geometry)`, or `None` when it names none.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for an unknown catalog key or a bad field.
    pub fn bearing(&self) -> Result<Option<(String, Geometry)>> {
        let geometry = self.geometry.unwrap_or_default();
        let entry = match &self.bearing {
            Some(key) => Some(bearing::find(key)?),
            None if geometry.is_empty() => return Ok(None),
            None => None,
        };
        let (name, base) = match entry {
            Some(e) => (e.name.to_string(), e.geometry),
            None => {
                let (Some(d), Some(e), Some(n)) = (
                    geometry.ball_diameter_mm,
                    geometry.free_space_mm,
                    geometry.balls_in_race,
                ) else {
                    return Err(Error::setting(
                        "geometry",
                        "without a catalog bearing, give ball_diameter_mm, free_space_mm \
                         and balls_in_race",
                    ));
                };
                ("custom".to_string(), Geometry::new(d, e, n)?)
            }
        };
        let custom = entry.is_some() && !geometry.is_empty();
        let g = geometry.apply(base)?;
        Ok(Some((
            if custom {
                format!("{name} (custom geometry)")
            } else {
                name
            },
            g,
        )))
    }

    /// The load options this profile sets (everything else at its default).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming a bad value (delimiter, bearing,
    /// scale, rate, tolerance).
    pub fn load_options(&self) -> Result<LoadOptions> {
        let mut o = LoadOptions {
            format: self.format,
            delimiter: self.delimiter.as_deref().map(parse_delimiter).transpose()?,
            decimal_comma: self.decimal_comma,
            skip_lines: self.skip_lines,
            fs_hz: self.fs_hz,
            fs_from: self.fs_from.clone(),
            time: self.time.clone(),
            time_unit: self.time_unit,
            gaps: GapPolicy {
                fill_max_s: self.fill_gaps,
                split: self.split_gaps,
            },
            ignore_time: self.ignore_time,
            friction: self.friction.clone(),
            position: self.position.clone(),
            optical: self.optical.clone(),
            ..Default::default()
        };
        if let Some(t) = self.time_step_tolerance {
            o.time_step_tolerance = t;
        }
        if let Some(m) = self.min_periods {
            o.min_periods = m;
        }
        if let Some((name, g)) = self.bearing()? {
            o.bearing = Some(name);
            o.geometry = Some(g);
        }
        o.validate()?;
        Ok(o)
    }
}

/// A setting's error as an error at the line of its key in the profile text.
fn locate(path: &Path, text: &str, e: Error) -> Error {
    let Error::InvalidSetting { name, reason } = &e else {
        return e;
    };
    let (table, key) = match name.as_str() {
        "fs" => (None, "fs_hz"),
        "delimiter" => (None, "delimiter"),
        "bearing" => (None, "bearing"),
        "time step tolerance" => (None, "time_step_tolerance"),
        "min_periods" => (None, "min_periods"),
        "fill-gaps" => (None, "fill_gaps"),
        "skip-lines" => (None, "skip_lines"),
        "decimal-comma" => (None, "decimal_comma"),
        "geometry" => (Some("geometry"), ""),
        "ball diameter" => (Some("geometry"), "ball_diameter_mm"),
        "free space" => (Some("geometry"), "free_space_mm"),
        "balls in race" => (Some("geometry"), "balls_in_race"),
        other => match other.split_once(' ') {
            Some((ch @ ("friction" | "position" | "optical"), k @ ("scale" | "offset"))) => {
                (Some(ch), k)
            }
            _ => return e,
        },
    };
    match line_of(text, table, key) {
        Some(line) => Error::Parse {
            path: path.to_path_buf(),
            line,
            column: None,
            reason: format!("invalid {name}: {reason}"),
        },
        None => e,
    }
}

/// 1-based line where `key` is set in `[table]` (top level for `None`); an
/// empty key names the table's header line.
fn line_of(text: &str, table: Option<&str>, key: &str) -> Option<usize> {
    let mut current: Option<String> = None;
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if let Some(name) = l.strip_prefix('[').and_then(|r| r.split(']').next()) {
            current = Some(name.trim().to_string());
            if key.is_empty() && table == current.as_deref() {
                return Some(i + 1);
            }
            continue;
        }
        if current.as_deref() != table || key.is_empty() {
            continue;
        }
        if let Some((k, _)) = l.split_once('=') {
            if k.trim().trim_matches('"') == key {
                return Some(i + 1);
            }
        }
    }
    None
}

/// Parses a delimiter name: a single ASCII character, or `tab`, `comma`,
/// `semicolon`, `space`.
///
/// # Errors
/// [`Error::InvalidSetting`] naming `delimiter`.
pub fn parse_delimiter(s: &str) -> Result<u8> {
    match s.to_ascii_lowercase().as_str() {
        "tab" | "\\t" | "\t" => Ok(b'\t'),
        "comma" => Ok(b','),
        "semicolon" => Ok(b';'),
        "space" => Ok(b' '),
        one if one.len() == 1 && one.is_ascii() && one != "#" && one != "\"" => {
            Ok(one.as_bytes()[0])
        }
        _ => Err(Error::setting(
            "delimiter",
            format!(
                "expected one character or tab, comma, semicolon, space; got '{}' \
                 ('#' and '\"' are reserved)",
                crate::error::excerpt(s)
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: &str = r#"
name = "UNH air-bearing stage"
format = "mat"
fs_hz = 1000.0
time = "Zeit"
bearing = "SR25W"
min_periods = 2.5

[friction]
name = "Model Root/Load cell/Force"

[position]
name = "Counts"
scale = 1e-4

[optical]
name = "Voltage"
offset = -0.1

[geometry]
balls_in_race = 35

[analysis]
lowpass_hz = 20.0
detrend = "linear"
"#;

    #[test]
    fn full_profile_sets_load_options() {
        let p = Profile::parse(Path::new("bench.toml"), FULL).unwrap();
        let o = p.load_options().unwrap();
        assert_eq!(o.format, Some(Format::Mat));
        assert_eq!(o.fs_hz, Some(1000.0));
        assert_eq!(o.time.as_deref(), Some("Zeit"));
        assert_eq!(o.position.scale, 1e-4);
        assert_eq!(o.position.name.as_deref(), Some("Counts"));
        assert_eq!(o.optical.offset, -0.1);
        assert_eq!(o.friction.scale, 1.0);
        assert_eq!(o.min_periods, 2.5);
        assert_eq!(o.bearing.as_deref(), Some("THK SR25W (custom geometry)"));
        assert_eq!(o.geometry.unwrap().balls_in_race, 35);
        assert_eq!(o.geometry.unwrap().ball_diameter_mm, 4.0);
        assert_eq!(p.analysis.unwrap()["lowpass_hz"], 20.0);
    }

    #[test]
    fn typos_bad_values_and_bad_toml_name_the_line() {
        let e = Profile::parse(Path::new("b.toml"), "fs_hz = 1000\nfs = 2\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("b.toml:2") && e.contains("fs"), "{e}");
        let e = Profile::parse(Path::new("b.toml"), "\n\nfs_hz = \"fast\"\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("b.toml:3"), "{e}");
        let e = Profile::parse(Path::new("b.toml"), "[position]\nscale = 0\n")
            .unwrap()
            .load_options()
            .unwrap_err()
            .to_string();
        assert!(e.contains("position scale"), "{e}");
        let e = Profile::parse(Path::new("b.toml"), "bearing = \"nope\"\n")
            .unwrap()
            .load_options()
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown bearing 'nope'"), "{e}");
        // Found by the fuzz run (seed 7): the name is escaped, not echoed raw.
        let e = Profile::parse(Path::new("b.toml"), "bearing = \"sr25\\tw\"\n")
            .unwrap()
            .load_options()
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown bearing 'sr25\\tw'"), "{e}");
        assert!(!e.chars().any(char::is_control), "{e}");
        let e = Profile::parse(Path::new("b.toml"), "[geometry]\nball_diameter_mm = -4\n")
            .unwrap()
            .load_options()
            .unwrap_err()
            .to_string();
        assert!(e.contains("ball_diameter_mm, free_space_mm"), "{e}");
        let e = Profile::parse(
            Path::new("b.toml"),
            "bearing = \"sr25w\"\n[geometry]\nball_diameter_mm = -4\n",
        )
        .unwrap()
        .load_options()
        .unwrap_err()
        .to_string();
        assert!(e.contains("ball diameter") && e.contains("-4"), "{e}");
    }

    /// Issue 18, item 11: a value out of range is an error naming the
    /// profile file and the line of its key.
    #[test]
    fn profile_value_errors_name_file_and_line() {
        let dir = std::env::temp_dir().join(format!("ballpass-profile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (text, line, what) in [
            (
                "name = \"x\"\n\n[position]\nname = \"p\"\nscale = 0\n",
                5,
                "position scale",
            ),
            ("fs_hz = -5\n", 1, "fs"),
            ("# c\nbearing = \"nope\"\n", 2, "unknown bearing"),
            (
                "bearing = \"sr25w\"\n[geometry]\nballs_in_race = 0\n",
                3,
                "balls in race",
            ),
            (
                "[geometry]\nball_diameter_mm = 1\n",
                1,
                "without a catalog bearing",
            ),
            ("fill_gaps = 0\n", 1, "fill-gaps"),
        ] {
            let p = dir.join("bench.toml");
            std::fs::write(&p, text).unwrap();
            let e = Profile::read(&p).unwrap_err().to_string();
            let want = format!("{}:{line}", p.display());
            assert!(e.starts_with(&want) && e.contains(what), "{text:?}: {e}");
        }
        std::fs::write(dir.join("bad.toml"), b"name = \"\xff\"\n").unwrap();
        let e = Profile::read(&dir.join("bad.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.toml:1") && e.contains("not UTF-8"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn new_keys_set_dialects_and_gap_policy() {
        let p = Profile::parse(
            Path::new("b.toml"),
            "format = \"tdms\"\nfs_from = \"bearing.sr\"\ntime_unit = \"ms\"\n\
             decimal_comma = true\nskip_lines = 3\nfill_gaps = 0.01\nsplit_gaps = true\n",
        )
        .unwrap();
        let o = p.load_options().unwrap();
        assert_eq!(o.format, Some(Format::Tdms));
        assert_eq!(o.fs_from.as_deref(), Some("bearing.sr"));
        assert_eq!(o.time_unit, Some(TimeUnit::Ms));
        assert_eq!(o.decimal_comma, Some(true));
        assert_eq!(o.skip_lines, Some(3));
        assert_eq!(o.gaps.fill_max_s, Some(0.01));
        assert!(o.gaps.split);
    }

    #[test]
    fn delimiters() {
        assert_eq!(parse_delimiter("tab").unwrap(), b'\t');
        assert_eq!(parse_delimiter(";").unwrap(), b';');
        assert!(parse_delimiter("#").is_err());
        assert!(parse_delimiter("ab").is_err());
    }
}
