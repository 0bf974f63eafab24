//! Shared argument groups and parsers.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use ballpass::bearing::Geometry;
use ballpass::recording::{BearingRequest, Format, LoadOptions, LoadRequest, Profile, TimeUnit};
use ballpass::report::{write_report, Report, ReportFiles, ReportOptions};
use clap::{Args, ValueEnum};

/// Which bearing: a catalog key or a custom geometry.
#[derive(Debug, Clone, Args)]
pub struct BearingArgs {
    /// Bearing from the catalog (see `ballpass predict --list-bearings`)
    /// [default: the profile's, else sr25w].
    #[arg(long)]
    pub bearing: Option<String>,
    /// Custom geometry: ball diameter d, mm (overrides the catalog entry's).
    #[arg(long, value_name = "MM", allow_hyphen_values = true)]
    pub ball_diameter: Option<f64>,
    /// Custom geometry: total free space in the race d_ext, mm.
    #[arg(long, value_name = "MM", allow_hyphen_values = true)]
    pub free_space: Option<f64>,
    /// Custom geometry: number of balls in the race N_B.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub balls: Option<i64>,
}

impl BearingArgs {
    /// The geometry selected, catalog entry (default sr25w) with any flag
    /// overriding its field.
    pub fn geometry(&self) -> Result<(String, Geometry)> {
        self.resolve(None)
    }

    /// As [`BearingArgs::geometry`], but without `--bearing` the `fallback`
    /// (a profile's bearing) is the base before the sr25w default.
    pub fn resolve(&self, fallback: Option<(String, Geometry)>) -> Result<(String, Geometry)> {
        Ok(self.request().resolve(fallback)?)
    }

    /// The library's form of these flags.
    pub fn request(&self) -> BearingRequest {
        BearingRequest {
            bearing: self.bearing.clone(),
            ball_diameter_mm: self.ball_diameter,
            free_space_mm: self.free_space,
            balls_in_race: self.balls,
        }
    }
}

/// File format on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    /// Delimited text, delimiter detected.
    Csv,
    /// Tab-separated text.
    Tsv,
    /// MATLAB MAT-file (v5/v7, or v7.3 HDF5: told apart by the contents).
    Mat,
    /// NI TDMS (LabVIEW, DAQmx).
    Tdms,
    /// ASAM MDF 4 (.mf4).
    Mf4,
}

impl From<FormatArg> for Format {
    fn from(f: FormatArg) -> Self {
        match f {
            FormatArg::Csv => Format::Csv,
            FormatArg::Tsv => Format::Tsv,
            FormatArg::Mat => Format::Mat,
            FormatArg::Tdms => Format::Tdms,
            FormatArg::Mf4 => Format::Mf4,
        }
    }
}

/// How to read recording files: the flags every command that loads
/// recordings flattens in. Flags override the `--profile`'s values, which
/// override the defaults.
#[derive(Debug, Clone, Args)]
pub struct LoadArgs {
    /// Bench profile (TOML): column names, scales, rate, bearing of one bench.
    #[arg(long, value_name = "FILE", help_heading = "Input")]
    pub profile: Option<PathBuf>,
    /// File format [default: from the file name].
    #[arg(long, value_enum, help_heading = "Input")]
    pub format: Option<FormatArg>,
    /// Delimiter of text files: one character, or tab, comma, semicolon, space
    /// [default: detected from the header].
    #[arg(long, value_name = "CHAR", help_heading = "Input")]
    pub delimiter: Option<String>,
    /// Sampling rate, Hz: needed without a time column, checked against one.
    #[arg(
        long,
        value_name = "HZ",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub fs: Option<f64>,
    /// Time column / variable, s [default: time_s].
    #[arg(long, value_name = "NAME", help_heading = "Input")]
    pub time_col: Option<String>,
    /// Ignore the time column and use --fs.
    #[arg(long, help_heading = "Input")]
    pub ignore_time: bool,
    /// Friction column / variable / ControlDesk signal [default: friction_N].
    #[arg(long, value_name = "NAME", help_heading = "Input")]
    pub friction_col: Option<String>,
    /// Position column / variable / signal [default: position_mm].
    #[arg(long, value_name = "NAME", help_heading = "Input")]
    pub position_col: Option<String>,
    /// Optical sensor column / variable / signal [default: optical_V].
    #[arg(long, value_name = "NAME", help_heading = "Input")]
    pub optical_col: Option<String>,
    /// Friction = raw * scale + offset, N.
    #[arg(
        long,
        value_name = "X",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub friction_scale: Option<f64>,
    /// Added to the scaled friction, N.
    #[arg(
        long,
        value_name = "N",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub friction_offset: Option<f64>,
    /// Position = raw * scale + offset, mm (encoder counts of 0.1 um: 1e-4).
    #[arg(
        long,
        value_name = "X",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub position_scale: Option<f64>,
    /// Added to the scaled position, mm.
    #[arg(
        long,
        value_name = "MM",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub position_offset: Option<f64>,
    /// Optical = raw * scale + offset, V.
    #[arg(
        long,
        value_name = "X",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub optical_scale: Option<f64>,
    /// Added to the scaled optical signal, V.
    #[arg(
        long,
        value_name = "V",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub optical_offset: Option<f64>,
    /// Tracking velocity of the test, mm/s.
    #[arg(
        long,
        short = 'v',
        value_name = "MM/S",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub velocity: Option<f64>,
    /// Test identifier [default: the file name without extension].
    #[arg(long, value_name = "ID", help_heading = "Input")]
    pub test_id: Option<String>,
    /// Fewest ball-pass periods a recording must span [default: 3].
    #[arg(
        long,
        value_name = "N",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub min_periods: Option<f64>,
    #[command(flatten)]
    pub bearing: BearingArgs,
    #[command(flatten)]
    pub dialect: Box<DialectArgs>,
    /// `--window` (records.rs).
    #[command(flatten)]
    pub window: crate::records::WindowArgs,
}

/// File dialects and gaps: the flags of `LoadArgs` for recordings as labs
/// write them (text dialects, a rate stored in a MAT struct, gaps).
#[derive(Debug, Clone, Args)]
pub struct DialectArgs {
    /// MAT variable or struct field holding the sampling rate, Hz (e.g. bearing.sr).
    #[arg(long, value_name = "PATH", help_heading = "Input")]
    pub fs_from: Option<String>,
    /// Unit of the time column [default: what the file states (units row,
    /// `time_ms`, `t [ms]`), else s].
    #[arg(long, value_enum, value_name = "UNIT", help_heading = "Input")]
    pub time_unit: Option<TimeUnitArg>,
    /// Text files write numbers with a decimal comma (1,5) [default: detected].
    #[arg(long, help_heading = "Input")]
    pub decimal_comma: bool,
    /// Lines before the header of text files [default: found, at most 200].
    #[arg(long, value_name = "N", help_heading = "Input")]
    pub skip_lines: Option<usize>,
    /// Fill gaps (missing samples, NaN, empty cells) up to this long by
    /// linear interpolation, s [default: a gap is an error].
    #[arg(
        long,
        value_name = "SECONDS",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub fill_gaps: Option<f64>,
    /// Split records at gaps that are not filled; each piece is a recording
    /// of its own (a repeat, for analyze).
    #[arg(long, help_heading = "Input")]
    pub split_gaps: bool,
}

/// Unit of a time column on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TimeUnitArg {
    /// Seconds.
    S,
    /// Milliseconds.
    Ms,
    /// Microseconds.
    Us,
}

impl From<TimeUnitArg> for TimeUnit {
    fn from(u: TimeUnitArg) -> Self {
        match u {
            TimeUnitArg::S => TimeUnit::S,
            TimeUnitArg::Ms => TimeUnit::Ms,
            TimeUnitArg::Us => TimeUnit::Us,
        }
    }
}

impl LoadArgs {
    /// The profile named by `--profile`, if any.
    pub fn profile(&self) -> Result<Option<Profile>> {
        self.profile
            .as_deref()
            .map(Profile::read)
            .transpose()
            .map_err(Into::into)
    }

    /// Load options: defaults, then the profile, then the flags; with the
    /// bearing resolved (flag, profile, sr25w) and the settings validated.
    pub fn options(&self) -> Result<LoadOptions> {
        Ok(self.request().options()?)
    }

    /// The library's form of these flags.
    pub fn request(&self) -> LoadRequest {
        let d = &self.dialect;
        let b = self.bearing.request();
        LoadRequest {
            profile: self.profile.clone(),
            format: self.format.map(Into::into),
            delimiter: self.delimiter.clone(),
            fs_hz: self.fs,
            time_col: self.time_col.clone(),
            ignore_time: self.ignore_time,
            friction_col: self.friction_col.clone(),
            position_col: self.position_col.clone(),
            optical_col: self.optical_col.clone(),
            friction_scale: self.friction_scale,
            friction_offset: self.friction_offset,
            position_scale: self.position_scale,
            position_offset: self.position_offset,
            optical_scale: self.optical_scale,
            optical_offset: self.optical_offset,
            velocity_mm_s: self.velocity,
            test_id: self.test_id.clone(),
            min_periods: self.min_periods,
            fs_from: d.fs_from.clone(),
            time_unit: d.time_unit.map(Into::into),
            decimal_comma: d.decimal_comma,
            skip_lines: d.skip_lines,
            fill_gaps_s: d.fill_gaps,
            split_gaps: d.split_gaps,
            bearing: b.bearing,
            ball_diameter_mm: b.ball_diameter_mm,
            free_space_mm: b.free_space_mm,
            balls_in_race: b.balls_in_race,
        }
    }
}

/// The HTML report every command with an output directory writes: the
/// flags it flattens in.
#[derive(Debug, Clone, Args)]
pub struct ReportArgs {
    /// Write the HTML report (the default; the last of --report/--no-report wins).
    #[arg(long, overrides_with = "no_report", help_heading = "Report")]
    pub report: bool,
    /// Do not write the HTML report (DIR/report.html and DIR/figures/*.svg).
    #[arg(long, overrides_with = "report", help_heading = "Report")]
    pub no_report: bool,
    /// Also write every figure as PNG (DIR/figures/*.png).
    #[arg(long, conflicts_with = "no_report", help_heading = "Report")]
    pub png: bool,
}

impl ReportArgs {
    /// Writes `report` into `dir` unless `--no-report`, printing its drawing
    /// notes to stderr; `None` when no report was asked for.
    pub fn write(&self, report: &Report, dir: &Path) -> Result<Option<ReportFiles>> {
        if self.no_report {
            return Ok(None);
        }
        let files = write_report(
            report,
            dir,
            ReportOptions {
                png: self.png,
                ..ReportOptions::default()
            },
        )
        .with_context(|| format!("writing the report in {}", dir.display()))?;
        for w in &files.warnings {
            eprintln!("note: {}", crate::text::line(w));
        }
        Ok(Some(files))
    }
}

/// The command line as typed, for a report's header: any argument bytes,
/// escaped losslessly ([`crate::text::command_line`]).
pub fn command_line() -> String {
    crate::text::command_line()
}

/// Parses `V` or `START:STOP:STEP` (inclusive) into a list of velocities, mm/s.
pub fn parse_velocities(s: &str) -> Result<Vec<f64>> {
    let parts: Vec<&str> = s.split(':').collect();
    let num = |p: &str| -> Result<f64> {
        p.trim()
            .parse::<f64>()
            .with_context(|| format!("velocity '{s}': '{p}' is not a number"))
    };
    match parts.as_slice() {
        [v] => Ok(vec![num(v)?]),
        [a, b, step] => {
            let (a, b, step) = (num(a)?, num(b)?, num(step)?);
            if !(step.is_finite() && step > 0.0 && a.is_finite() && b.is_finite()) || b < a {
                bail!("velocity range '{s}': expected START:STOP:STEP with STOP >= START and STEP > 0");
            }
            let n = ((b - a) / step + 1e-9).floor() as usize + 1;
            if n > 100_000 {
                bail!("velocity range '{s}' has {n} values; at most 100000");
            }
            Ok((0..n).map(|i| a + i as f64 * step).collect())
        }
        _ => bail!("velocity '{s}': expected a number or START:STOP:STEP"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, clap::Parser)]
    struct WithReport {
        #[command(flatten)]
        report: ReportArgs,
    }

    /// The report is on by default; `--report` and `--no-report` may both be
    /// given (the last wins); `--png` needs the report.
    #[test]
    fn report_flags() {
        use clap::Parser;
        let p = |args: &[&str]| {
            WithReport::try_parse_from(std::iter::once("x").chain(args.iter().copied()))
        };
        assert!(!p(&[]).unwrap().report.no_report);
        assert!(p(&["--no-report"]).unwrap().report.no_report);
        assert!(!p(&["--no-report", "--report"]).unwrap().report.no_report);
        assert!(p(&["--report", "--no-report"]).unwrap().report.no_report);
        assert!(p(&["--report", "--png"]).unwrap().report.png);
        assert!(p(&["--no-report", "--png"]).is_err());
    }

    #[test]
    fn velocity_ranges_are_inclusive() {
        assert_eq!(parse_velocities("9").unwrap(), vec![9.0]);
        assert_eq!(parse_velocities("1:3:1").unwrap(), vec![1.0, 2.0, 3.0]);
        assert_eq!(parse_velocities("1:2:0.5").unwrap(), vec![1.0, 1.5, 2.0]);
        assert!(parse_velocities("3:1:1").is_err());
        assert!(parse_velocities("1:2:0").is_err());
        assert!(parse_velocities("fast").is_err());
    }
}
