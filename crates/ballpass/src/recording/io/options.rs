//! How to read a recording file: [`LoadOptions`] and the types it is made of.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::timebase;
use crate::bearing::Geometry;
use crate::error::{Error, Result};
use crate::recording::Channel;

/// File formats a recording can be read from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum Format {
    /// Delimited text with a header row; the delimiter is detected
    /// (`,` `;` or tab) unless [`LoadOptions::delimiter`] is set.
    Csv,
    /// Tab-separated text with a header row.
    Tsv,
    /// MATLAB MAT-file: level 5 (`-v6`/`-v7`) or v7.3 (HDF5), told apart by
    /// their contents.
    Mat,
    /// NI TDMS (LabVIEW, DAQmx).
    Tdms,
    /// ASAM MDF 4 (`.mf4`: Vector, dSPACE, ETAS loggers).
    Mf4,
}

impl Format {
    /// The format a file name implies: `.mat`, `.h5`, `.hdf5` → MAT, `.tdms`
    /// → TDMS, `.mf4`, `.mdf` → MF4, `.tsv`/`.tab` → TSV, anything else →
    /// CSV (the delimiter is then detected from the header).
    pub fn from_path(path: &Path) -> Format {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("mat" | "h5" | "hdf5") => Format::Mat,
            Some("tdms") => Format::Tdms,
            Some("mf4" | "mdf") => Format::Mf4,
            Some("tsv" | "tab") => Format::Tsv,
            _ => Format::Csv,
        }
    }

    /// The format whose signature starts `bytes`, for binary formats.
    pub(crate) fn sniff(bytes: &[u8]) -> Option<Format> {
        if bytes.starts_with(b"TDSm") {
            Some(Format::Tdms)
        } else if bytes.starts_with(b"MDF     ") {
            Some(Format::Mf4)
        } else if bytes.starts_with(b"MATLAB") || bytes.starts_with(b"\x89HDF\r\n\x1a\n") {
            Some(Format::Mat)
        } else {
            None
        }
    }

    /// Lower-case name (`csv`, `mat`, ...), as `--format` takes it.
    pub fn name(self) -> &'static str {
        match self {
            Format::Csv => "csv",
            Format::Tsv => "tsv",
            Format::Mat => "mat",
            Format::Tdms => "tdms",
            Format::Mf4 => "mf4",
        }
    }
}

/// Where one channel comes from in a file, and how to convert it to its unit.
///
/// ```text
/// value [unit] = raw * scale + offset
/// ```
///
/// e.g. encoder counts at 0.1 µm per count: `scale = 1e-4` → mm.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChannelSource {
    /// Column (CSV), variable, struct field path or signal (MAT), channel
    /// (`Group/Channel` or `Channel`, TDMS and MF4), matched ignoring case.
    /// `None`: the canonical name (`friction_N`, `position_mm`, `optical_V`).
    pub name: Option<String>,
    /// Multiplier applied to the raw numbers.
    pub scale: f64,
    /// Added after scaling, in the channel's unit.
    pub offset: f64,
}

impl Default for ChannelSource {
    fn default() -> Self {
        Self {
            name: None,
            scale: 1.0,
            offset: 0.0,
        }
    }
}

impl ChannelSource {
    /// True when values are used as read.
    pub fn is_identity(&self) -> bool {
        self.scale == 1.0 && self.offset == 0.0
    }

    fn check(&self, channel: Channel) -> Result<()> {
        if !(self.scale.is_finite() && self.scale != 0.0) {
            return Err(Error::setting(
                format!("{} scale", channel.short_name()),
                format!("must be a finite non-zero number, got {}", self.scale),
            ));
        }
        if !self.offset.is_finite() {
            return Err(Error::setting(
                format!("{} offset", channel.short_name()),
                format!("must be a finite number, got {}", self.offset),
            ));
        }
        Ok(())
    }
}

/// Unit of a time column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TimeUnit {
    /// Seconds.
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
}

impl TimeUnit {
    /// Seconds per unit.
    pub fn seconds(self) -> f64 {
        match self {
            TimeUnit::S => 1.0,
            TimeUnit::Ms => 1e-3,
            TimeUnit::Us => 1e-6,
        }
    }

    /// Symbol (`s`, `ms`, `us`).
    pub fn symbol(self) -> &'static str {
        match self {
            TimeUnit::S => "s",
            TimeUnit::Ms => "ms",
            TimeUnit::Us => "us",
        }
    }

    /// The unit a symbol names: `s`, `sec`, `ms`, `us`, `µs`, `μs` (any case).
    pub fn parse(symbol: &str) -> Option<TimeUnit> {
        let s = symbol.trim();
        Some(match s.to_ascii_lowercase().as_str() {
            "s" | "sec" | "secs" | "second" | "seconds" => TimeUnit::S,
            "ms" | "msec" | "millisecond" | "milliseconds" => TimeUnit::Ms,
            "us" | "usec" | "microsecond" | "microseconds" => TimeUnit::Us,
            _ if s == "µs" || s == "μs" || s == "µsec" || s == "μsec" => TimeUnit::Us,
            _ => return None,
        })
    }

    /// The unit a column or variable name states: `time_ms`, `t [ms]`,
    /// `Zeit (µs)`, `time/s`, `time in ms`; `None` when it states none.
    pub fn of_name(name: &str) -> Option<TimeUnit> {
        super::units::unit_of_name(name).and_then(TimeUnit::parse)
    }
}

/// What to do with gaps: time stamps missing from a uniform grid, and
/// samples without a finite value (`NaN`, an empty cell).
///
/// By default a record with a gap is refused, naming where the first one
/// is (`inspect` lists them all). Gaps up to `fill_max_s` long may be
/// filled by linear interpolation between the samples on either side;
/// longer ones may split the record into pieces, each a recording of its
/// own. Gaps at either end, which have a neighbour on one side only, are
/// cut off when filling or splitting is asked for. Every repair is stated
/// in [`crate::recording::Metadata::notes`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GapPolicy {
    /// Fill gaps up to this long, s, by linear interpolation.
    pub fill_max_s: Option<f64>,
    /// Split the record at the gaps that are not filled.
    pub split: bool,
}

impl GapPolicy {
    /// True when gaps are refused (the default).
    pub fn refuses(&self) -> bool {
        self.fill_max_s.is_none() && !self.split
    }
}

/// How to read a recording file: which columns hold what, scales, sampling
/// rate, and the metadata the file itself does not carry.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadOptions {
    /// File format; `None`: from the file name (see [`Format::from_path`]),
    /// and a file whose contents say otherwise is an error that says so.
    pub format: Option<Format>,
    /// Field delimiter of a text file; `None`: detected from the header line.
    pub delimiter: Option<u8>,
    /// Decimal comma in a text file (`1,5`); `None`: detected (a `,` inside
    /// numbers of a `;`- or tab-separated file).
    pub decimal_comma: Option<bool>,
    /// Lines before the header of a text file (metadata a logger writes);
    /// `None`: the header is the first line, among the first
    /// [`super::csv::MAX_PREAMBLE_LINES`], that names a wanted column.
    pub skip_lines: Option<usize>,
    /// Sampling rate, Hz. Required when the file has no time column and
    /// states no rate; checked against the time column when it has one.
    pub fs_hz: Option<f64>,
    /// A variable or struct field holding the sampling rate, Hz (MAT-files:
    /// `bearing.sr`).
    pub fs_from: Option<String>,
    /// Name of the time column / variable. `None`: `time_s` if present
    /// (ControlDesk's `X.Data` in a ControlDesk MAT-file, the master channel
    /// in MF4).
    pub time: Option<String>,
    /// Unit of the time column; `None`: from the file (a units row, or the
    /// column name: `time_ms`, `t [ms]`), else seconds. Given, it must agree
    /// with what the file states.
    pub time_unit: Option<TimeUnit>,
    /// Ignore any time column and use [`LoadOptions::fs_hz`] alone.
    pub ignore_time: bool,
    /// Friction force channel, N.
    pub friction: ChannelSource,
    /// Stage position channel, mm.
    pub position: ChannelSource,
    /// Optical sensor channel, V.
    pub optical: ChannelSource,
    /// Largest deviation of one time step from the median step, relative to
    /// the step (the printed time's rounding is allowed on top, see [`timebase`]).
    pub time_step_tolerance: f64,
    /// What to do with missing samples and values.
    pub gaps: GapPolicy,
    /// Tracking velocity, mm/s, recorded in the metadata.
    pub velocity_mm_s: Option<f64>,
    /// Bearing name, recorded in the metadata.
    pub bearing: Option<String>,
    /// Bearing geometry used to check that the recording spans enough
    /// ball-pass periods (only when the velocity is known too).
    pub geometry: Option<Geometry>,
    /// Fewest ball-pass periods `tau_c` a recording must span.
    pub min_periods: f64,
    /// Test identifier; `None`: the file stem.
    pub test_id: Option<String>,
    /// The record to read from a file that holds several: a TDMS group
    /// (one run per group, as LabVIEW writes them). Set from a path
    /// `FILE#NAME` by [`super::load`]; `None`: the file is one record.
    pub record: Option<String>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            format: None,
            delimiter: None,
            decimal_comma: None,
            skip_lines: None,
            fs_hz: None,
            fs_from: None,
            time: None,
            time_unit: None,
            ignore_time: false,
            friction: ChannelSource::default(),
            position: ChannelSource::default(),
            optical: ChannelSource::default(),
            time_step_tolerance: timebase::DEFAULT_STEP_TOLERANCE,
            gaps: GapPolicy::default(),
            velocity_mm_s: None,
            bearing: None,
            geometry: None,
            min_periods: 3.0,
            test_id: None,
            record: None,
        }
    }
}

/// One channel's values given on top of a profile (a command-line flag, a
/// Python keyword): each one given replaces the profile's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SourceOverride {
    /// Column / variable / signal name.
    pub name: Option<String>,
    /// Multiplier.
    pub scale: Option<f64>,
    /// Offset added after scaling.
    pub offset: Option<f64>,
}

/// The loading values given on top of a profile's [`LoadOptions`] (the
/// command line's flags, the Python keywords): each one given replaces the
/// profile's; `ignore_time` can only switch the time column off.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadOverrides {
    /// Sampling rate, Hz.
    pub fs_hz: Option<f64>,
    /// Time column / variable.
    pub time: Option<String>,
    /// Ignore the time column.
    pub ignore_time: bool,
    /// Friction, position and optical, in [`Channel::ALL`] order.
    pub sources: [SourceOverride; 3],
    /// Tracking velocity, mm/s.
    pub velocity_mm_s: Option<f64>,
    /// Test identifier.
    pub test_id: Option<String>,
    /// Fewest ball-pass periods a recording must span.
    pub min_periods: Option<f64>,
}

impl LoadOverrides {
    /// Writes the values given into `o`.
    pub fn apply(&self, o: &mut LoadOptions) {
        if self.fs_hz.is_some() {
            o.fs_hz = self.fs_hz;
        }
        if self.time.is_some() {
            o.time.clone_from(&self.time);
        }
        o.ignore_time |= self.ignore_time;
        for (c, given) in Channel::ALL.into_iter().zip(&self.sources) {
            let src = o.source_mut(c);
            if given.name.is_some() {
                src.name.clone_from(&given.name);
            }
            if let Some(s) = given.scale {
                src.scale = s;
            }
            if let Some(x) = given.offset {
                src.offset = x;
            }
        }
        if self.velocity_mm_s.is_some() {
            o.velocity_mm_s = self.velocity_mm_s;
        }
        if self.test_id.is_some() {
            o.test_id.clone_from(&self.test_id);
        }
        if let Some(m) = self.min_periods {
            o.min_periods = m;
        }
    }
}

impl LoadOptions {
    /// The source of one channel.
    pub fn source(&self, c: Channel) -> &ChannelSource {
        match c {
            Channel::Friction => &self.friction,
            Channel::Position => &self.position,
            Channel::Optical => &self.optical,
        }
    }

    /// Mutable access to the source of one channel.
    pub fn source_mut(&mut self, c: Channel) -> &mut ChannelSource {
        match c {
            Channel::Friction => &mut self.friction,
            Channel::Position => &mut self.position,
            Channel::Optical => &mut self.optical,
        }
    }

    /// The profile's bearing and geometry when it names both (the base a
    /// caller's bearing choice falls back to).
    pub fn bearing_fallback(&self) -> Option<(String, crate::bearing::Geometry)> {
        match (&self.bearing, self.geometry) {
            (Some(name), Some(g)) => Some((name.clone(), g)),
            _ => None,
        }
    }

    /// Checks the ranges of the settings (scales, rate, velocity, tolerances).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the setting.
    pub fn validate(&self) -> Result<()> {
        for c in Channel::ALL {
            self.source(c).check(c)?;
        }
        if let Some(fs) = self.fs_hz {
            if !(fs.is_finite() && fs > 0.0) {
                return Err(Error::setting(
                    "fs",
                    format!("must be a positive number of Hz, got {fs}"),
                ));
            }
        }
        if self.ignore_time && self.fs_hz.is_none() && self.fs_from.is_none() {
            return Err(Error::setting(
                "fs",
                "the time column is ignored, so the sampling rate must be given",
            ));
        }
        if let Some(v) = self.velocity_mm_s {
            crate::bearing::check_velocity(v)?;
        }
        if let Some(g) = &self.geometry {
            g.validate()?;
        }
        if !(self.time_step_tolerance.is_finite()
            && self.time_step_tolerance > 0.0
            && self.time_step_tolerance < 0.5)
        {
            return Err(Error::setting(
                "time step tolerance",
                format!(
                    "must be between 0 and 0.5 (relative to the step), got {}",
                    self.time_step_tolerance
                ),
            ));
        }
        if !(self.min_periods.is_finite() && self.min_periods >= 0.0) {
            return Err(Error::setting(
                "min_periods",
                format!("must be zero or positive, got {}", self.min_periods),
            ));
        }
        if let Some(m) = self.gaps.fill_max_s {
            if !(m.is_finite() && m > 0.0) {
                return Err(Error::setting(
                    "fill-gaps",
                    format!("must be a positive number of seconds, got {m}"),
                ));
            }
        }
        if let Some(n) = self.skip_lines {
            if n > super::csv::MAX_PREAMBLE_LINES {
                return Err(Error::setting(
                    "skip-lines",
                    format!(
                        "at most {} lines before the header, got {n}",
                        super::csv::MAX_PREAMBLE_LINES
                    ),
                ));
            }
        }
        if self.decimal_comma == Some(true) && self.delimiter == Some(b',') {
            return Err(Error::setting(
                "decimal-comma",
                "a decimal comma needs another delimiter than ',' (';' or tab)",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What is given replaces the profile's value; what is not keeps it;
    /// `ignore_time` only switches the time column off.
    #[test]
    fn overrides_replace_only_what_is_given() {
        let mut profile = LoadOptions {
            fs_hz: Some(500.0),
            time: Some("t".into()),
            ignore_time: true,
            velocity_mm_s: Some(3.0),
            ..LoadOptions::default()
        };
        profile.position.name = Some("enc".into());
        profile.position.scale = 1e-4;
        profile.optical.offset = 0.5;
        let mut o = profile.clone();
        LoadOverrides::default().apply(&mut o);
        assert_eq!(o, profile);
        let mut given = LoadOverrides {
            fs_hz: Some(1000.0),
            min_periods: Some(5.0),
            ..LoadOverrides::default()
        };
        given.sources[1].scale = Some(2.0);
        given.sources[2].name = Some("light".into());
        given.apply(&mut o);
        assert_eq!(o.fs_hz, Some(1000.0));
        assert_eq!(o.time.as_deref(), Some("t"));
        assert!(o.ignore_time);
        assert_eq!(o.velocity_mm_s, Some(3.0));
        assert_eq!(o.min_periods, 5.0);
        assert_eq!(
            (o.position.name.as_deref(), o.position.scale),
            (Some("enc"), 2.0)
        );
        assert_eq!(
            (o.optical.name.as_deref(), o.optical.offset),
            (Some("light"), 0.5)
        );
    }
}
