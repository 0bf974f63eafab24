//! Bench profiles: what a lab writes once about its test bench (TOML).
//!
//! ```toml
//! name = "UNH air-bearing stage, dSPACE DS1103"
//! format = "mat"                 # csv | tsv | mat; default: from the file name
//! fs_hz = 1000.0                 # needed when files have no time column
//! time = "Zeit"                  # time column / variable, default time_s
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

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::io::{ChannelSource, Format, LoadOptions};
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
    /// Time column / variable name.
    pub time: Option<String>,
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
    /// TOML, an unknown key or a value of the wrong type; the errors of
    /// [`Profile::load_options`] for values out of range.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut p = Self::parse(path, &text)?;
        p.source = Some(path.to_path_buf());
        p.load_options()?;
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
                reason: e.message().replace('\n', " ").trim().to_string(),
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
            Some(key) => Some(lookup(key)?),
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
            fs_hz: self.fs_hz,
            time: self.time.clone(),
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

fn lookup(key: &str) -> Result<&'static bearing::CatalogEntry> {
    bearing::lookup(key).ok_or_else(|| {
        let keys: Vec<_> = bearing::CATALOG.iter().map(|e| e.key).collect();
        Error::setting(
            "bearing",
            format!("unknown bearing '{key}' (catalog: {})", keys.join(", ")),
        )
    })
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
                "expected one character or tab, comma, semicolon, space; got '{s}' \
                 ('#' and '\"' are reserved)"
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

    #[test]
    fn delimiters() {
        assert_eq!(parse_delimiter("tab").unwrap(), b'\t');
        assert_eq!(parse_delimiter(";").unwrap(), b';');
        assert!(parse_delimiter("#").is_err());
        assert!(parse_delimiter("ab").is_err());
    }
}
