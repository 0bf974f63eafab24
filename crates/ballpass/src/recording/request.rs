//! What a user asks a recording to be read with: a profile, then the values
//! given on top of it (the command line's input flags, the Python
//! keywords), then the bearing. Both front ends build one [`LoadRequest`]
//! and get their [`LoadOptions`] from it, so a file reads the same from
//! either.

use std::path::PathBuf;

use serde::Deserialize;

use super::profile::{parse_delimiter, GeometryOverride, Profile};
use super::{Format, LoadOptions, LoadOverrides, SourceOverride, TimeUnit};
use crate::bearing::{self, Geometry};
use crate::error::{Error, Result};

/// The catalog key used when neither the request nor a profile names a
/// bearing.
pub const DEFAULT_BEARING: &str = "sr25w";

/// Which bearing: a catalog key, geometry fields over it, or both (the
/// command line's `--bearing`, `--ball-diameter`, `--free-space`,
/// `--balls`; the Python keywords of the same names).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BearingRequest {
    /// Catalog key (`sr25w`).
    pub bearing: Option<String>,
    /// Ball diameter `d`, mm.
    pub ball_diameter_mm: Option<f64>,
    /// Total free space in the race `d_ext`, mm.
    pub free_space_mm: Option<f64>,
    /// Balls in the race `N_B` (a whole number from 1; signed so that a
    /// negative value is named in the error rather than refused unread).
    pub balls_in_race: Option<i64>,
}

impl BearingRequest {
    /// `(name, geometry)`: the catalog entry of `bearing`, else `fallback`,
    /// else [`DEFAULT_BEARING`]; with the fields given replacing its
    /// geometry (the name then says `(custom geometry)`).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for an unknown key or an out-of-range field.
    pub fn resolve(&self, fallback: Option<(String, Geometry)>) -> Result<(String, Geometry)> {
        let (name, base) = match (&self.bearing, fallback) {
            (Some(key), _) => catalog(key)?,
            (None, Some(f)) => f,
            (None, None) => catalog(DEFAULT_BEARING)?,
        };
        let balls = match self.balls_in_race {
            None => None,
            Some(n) => Some(u32::try_from(n).ok().filter(|&n| n > 0).ok_or_else(|| {
                Error::setting(
                    "balls in race",
                    format!("must be a whole number from 1, got {n}"),
                )
            })?),
        };
        let over = GeometryOverride {
            ball_diameter_mm: self.ball_diameter_mm,
            free_space_mm: self.free_space_mm,
            balls_in_race: balls,
        };
        let g = over.apply(base)?;
        let name = if over.is_empty() || name.ends_with("(custom geometry)") {
            name
        } else {
            format!("{name} (custom geometry)")
        };
        Ok((name, g))
    }
}

/// A catalog entry's name and geometry.
///
/// # Errors
/// [`Error::InvalidSetting`] naming the key and listing the catalog.
pub fn catalog(key: &str) -> Result<(String, Geometry)> {
    let e = bearing::find(key)?;
    Ok((e.name.to_string(), e.geometry))
}

/// Everything a recording may be read with; `None`/`false`: the profile's
/// value, else the default. Field names are the Python keywords; the
/// command line's flags are the same words (`fs_hz` is `--fs`, `time_col`
/// `--time-col`, `fill_gaps_s` `--fill-gaps`, `velocity_mm_s` `--velocity`).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoadRequest {
    /// A bench profile (TOML) read first.
    pub profile: Option<PathBuf>,
    /// File format (else from the file name).
    pub format: Option<Format>,
    /// CSV delimiter ([`parse_delimiter`]).
    pub delimiter: Option<String>,
    /// Sampling rate, Hz.
    pub fs_hz: Option<f64>,
    /// Time column / variable.
    pub time_col: Option<String>,
    /// Ignore the time column.
    pub ignore_time: bool,
    /// Friction column / variable / signal.
    pub friction_col: Option<String>,
    /// Position column / variable / signal.
    pub position_col: Option<String>,
    /// Optical column / variable / signal.
    pub optical_col: Option<String>,
    /// Friction multiplier.
    pub friction_scale: Option<f64>,
    /// Friction offset, N (after scaling).
    pub friction_offset: Option<f64>,
    /// Position multiplier.
    pub position_scale: Option<f64>,
    /// Position offset, mm.
    pub position_offset: Option<f64>,
    /// Optical multiplier.
    pub optical_scale: Option<f64>,
    /// Optical offset, V.
    pub optical_offset: Option<f64>,
    /// Tracking velocity, mm/s.
    pub velocity_mm_s: Option<f64>,
    /// Test identifier.
    pub test_id: Option<String>,
    /// Fewest ball-pass periods a recording must span.
    pub min_periods: Option<f64>,
    /// A MAT scalar (or struct field) holding the sampling rate.
    pub fs_from: Option<String>,
    /// Unit of the time column.
    pub time_unit: Option<TimeUnit>,
    /// Decimal commas in a CSV.
    pub decimal_comma: bool,
    /// Metadata lines before a CSV's header.
    pub skip_lines: Option<usize>,
    /// Fill gaps up to this long, s.
    pub fill_gaps_s: Option<f64>,
    /// Split the record at longer gaps.
    pub split_gaps: bool,
    /// Catalog key of the bearing.
    pub bearing: Option<String>,
    /// Ball diameter, mm.
    pub ball_diameter_mm: Option<f64>,
    /// Free space in the race, mm.
    pub free_space_mm: Option<f64>,
    /// Balls in the race.
    pub balls_in_race: Option<i64>,
}

impl LoadRequest {
    /// The bearing part of the request.
    pub fn bearing(&self) -> BearingRequest {
        BearingRequest {
            bearing: self.bearing.clone(),
            ball_diameter_mm: self.ball_diameter_mm,
            free_space_mm: self.free_space_mm,
            balls_in_race: self.balls_in_race,
        }
    }

    /// The values given on top of the profile.
    fn overrides(&self) -> LoadOverrides {
        let source = |name: &Option<String>, scale, offset| SourceOverride {
            name: name.clone(),
            scale,
            offset,
        };
        LoadOverrides {
            fs_hz: self.fs_hz,
            time: self.time_col.clone(),
            ignore_time: self.ignore_time,
            sources: [
                source(
                    &self.friction_col,
                    self.friction_scale,
                    self.friction_offset,
                ),
                source(
                    &self.position_col,
                    self.position_scale,
                    self.position_offset,
                ),
                source(&self.optical_col, self.optical_scale, self.optical_offset),
            ],
            velocity_mm_s: self.velocity_mm_s,
            test_id: self.test_id.clone(),
            min_periods: self.min_periods,
        }
    }

    /// Load options: defaults, then the profile, then the values given;
    /// the bearing resolved (the request's, the profile's, else
    /// [`DEFAULT_BEARING`]) and every setting validated.
    ///
    /// # Errors
    /// The profile's errors, and [`Error::InvalidSetting`] naming a bad
    /// value.
    pub fn options(&self) -> Result<LoadOptions> {
        let mut o = match &self.profile {
            Some(p) => Profile::read(p)?.load_options()?,
            None => LoadOptions::default(),
        };
        if self.format.is_some() {
            o.format = self.format;
        }
        if let Some(d) = &self.delimiter {
            o.delimiter = Some(parse_delimiter(d)?);
        }
        self.overrides().apply(&mut o);
        if self.fs_from.is_some() {
            o.fs_from.clone_from(&self.fs_from);
        }
        if self.time_unit.is_some() {
            o.time_unit = self.time_unit;
        }
        if self.decimal_comma {
            o.decimal_comma = Some(true);
        }
        if self.skip_lines.is_some() {
            o.skip_lines = self.skip_lines;
        }
        if self.fill_gaps_s.is_some() {
            o.gaps.fill_max_s = self.fill_gaps_s;
        }
        o.gaps.split |= self.split_gaps;
        let (name, g) = self.bearing().resolve(o.bearing_fallback())?;
        o.bearing = Some(name);
        o.geometry = Some(g);
        o.validate()?;
        Ok(o)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every value given lands in the options; nothing given leaves the
    /// defaults (with the default bearing).
    #[test]
    fn a_request_sets_what_it_gives_and_nothing_else() {
        let o = LoadRequest::default().options().unwrap();
        let mut want = LoadOptions::default();
        let (name, g) = catalog(DEFAULT_BEARING).unwrap();
        want.bearing = Some(name);
        want.geometry = Some(g);
        assert_eq!(o, want);

        let r: LoadRequest = serde_json::from_str(
            r#"{"format": "csv", "delimiter": "semicolon", "fs_hz": 1000, "optical_scale": 2,
                "decimal_comma": true, "time_unit": "ms", "skip_lines": 3, "fill_gaps_s": 0.01,
                "split_gaps": true, "balls_in_race": 12, "fs_from": "bearing.sr"}"#,
        )
        .unwrap();
        let o = r.options().unwrap();
        assert_eq!(o.format, Some(Format::Csv));
        assert_eq!(o.delimiter, Some(b';'));
        assert_eq!(o.fs_hz, Some(1000.0));
        assert_eq!(o.optical.scale, 2.0);
        assert_eq!(o.decimal_comma, Some(true));
        assert_eq!(o.time_unit, Some(TimeUnit::Ms));
        assert_eq!(o.skip_lines, Some(3));
        assert_eq!(o.gaps.fill_max_s, Some(0.01));
        assert!(o.gaps.split);
        assert_eq!(o.fs_from.as_deref(), Some("bearing.sr"));
        assert_eq!(o.geometry.unwrap().balls_in_race, 12);
        assert!(o.bearing.unwrap().ends_with("(custom geometry)"));
    }

    #[test]
    fn bad_bearings_are_named() {
        let bad = |b: BearingRequest| b.resolve(None).unwrap_err().to_string();
        let e = bad(BearingRequest {
            bearing: Some("xyz".into()),
            ..Default::default()
        });
        assert!(e.contains("unknown bearing 'xyz' (catalog: sr25w"), "{e}");
        let e = bad(BearingRequest {
            balls_in_race: Some(-3),
            ..Default::default()
        });
        assert!(e.contains("whole number from 1, got -3"), "{e}");
        let r: std::result::Result<LoadRequest, _> = serde_json::from_str(r#"{"fs": 1000}"#);
        assert!(r.is_err(), "unknown keys are refused");
    }
}
