//! Flags and glue for what happens to records between loading and
//! analysing: a time window, plateau segmentation, the pre-verdict checks
//! (dead channels, velocity against the encoder) and the memory estimate.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use ballpass::analysis::preflight::PreflightSettings;
use ballpass::analysis::MaxLag;
use ballpass::recording::segment::{self, Plateau, SegmentSettings, Window};
use ballpass::recording::{LoadOptions, Recording};
use clap::Args;
use rayon::prelude::*;

/// `--window`, flattened into every command that reads records.
#[derive(Debug, Clone, Args)]
pub struct WindowArgs {
    /// Use only the part T0:T1 of each record, in seconds on its time axis
    /// (the time column's, else from 0); `T0:` or `:T1` leave an end open.
    /// The outputs name each record with the window used.
    #[arg(
        long,
        value_name = "T0:T1",
        allow_hyphen_values = true,
        help_heading = "Input"
    )]
    pub window: Option<String>,
}

impl WindowArgs {
    /// The window, parsed.
    pub fn parsed(&self) -> Result<Option<Window>> {
        Ok(self.window.as_deref().map(Window::parse).transpose()?)
    }

    /// `rec` cut to the window (unchanged without one).
    pub fn apply(&self, rec: Recording) -> Result<Recording> {
        match self.parsed()? {
            Some(w) => Ok(segment::window(&rec, &w)?),
            None => Ok(rec),
        }
    }

    /// The pieces of one file (split at its gaps) cut to the window: pieces
    /// wholly outside it are left out; an error when none reaches into it,
    /// or when one that does holds too few samples.
    pub fn apply_pieces(&self, pieces: Vec<Recording>) -> Result<Vec<Recording>> {
        let Some(w) = self.parsed()? else {
            return Ok(pieces);
        };
        if pieces.len() == 1 {
            return Ok(vec![segment::window(&pieces[0], &w)?]);
        }
        let inside = |r: &Recording| {
            let (t0, t1) = (r.meta.start_time_s, r.time_s(r.len()));
            w.start_s.is_none_or(|s| s < t1) && w.end_s.is_none_or(|e| e > t0)
        };
        let Some(first) = pieces.first() else {
            return Ok(pieces);
        };
        if !pieces.iter().any(inside) {
            // The window's own message, for the first piece.
            return Ok(vec![segment::window(first, &w)?]);
        }
        pieces
            .iter()
            .filter(|r| inside(r))
            .map(|r| Ok(segment::window(r, &w)?))
            .collect()
    }
}

/// `--force-velocity`, for the commands that analyse at a velocity.
#[derive(Debug, Clone, Args)]
pub struct CheckArgs {
    /// Analyse at the stated velocity even when the encoder's differs from
    /// it by more than 5 % (a warning instead of an error). A ball-pass
    /// frequency above Nyquist is refused all the same.
    #[arg(long, help_heading = "Checks")]
    pub force_velocity: bool,
}

impl CheckArgs {
    /// The pre-verdict checks' settings.
    pub fn preflight(&self) -> PreflightSettings {
        PreflightSettings {
            force_velocity: self.force_velocity,
            ..PreflightSettings::default()
        }
    }
}

/// `--segment`, for the commands that can take a multi-speed run apart.
#[derive(Debug, Clone, Args)]
pub struct SegmentArgs {
    /// Split each record into its constant-velocity plateaus found from the
    /// encoder (ramps and settling dropped); each plateau is a record at its
    /// own measured speed (backward ones mirrored to forward motion).
    #[arg(long, help_heading = "Input")]
    pub segment: bool,
}

/// One record's plateaus.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Segmented {
    /// The record (with the window, if any).
    pub source: String,
    /// Its plateaus, in time order.
    pub plateaus: Vec<Plateau>,
}

/// Loads `paths` in parallel (each file one record, or its pieces with
/// `--split-gaps`) and applies the window; the first failure in argument
/// order is the one reported.
pub fn load_all(
    paths: &[PathBuf],
    opts: &LoadOptions,
    window: &WindowArgs,
) -> Result<Vec<Recording>> {
    window.parsed()?;
    let per_file = paths
        .par_iter()
        .map(|p| {
            let pieces = ballpass::recording::load_all(p, opts)
                .with_context(|| format!("loading {}", p.display()))?;
            window.apply_pieces(pieces)
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect::<Result<Vec<_>>>()?;
    Ok(per_file.into_iter().flatten().collect())
}

/// Each record's plateaus and the plateaus as records.
pub fn segment_all(recs: &[Recording]) -> Result<(Vec<Segmented>, Vec<Recording>)> {
    let settings = SegmentSettings::default();
    let mut found = Vec::new();
    let mut parts = Vec::new();
    for r in recs {
        let p = segment::plateaus_found(r, &settings)?;
        parts.extend(segment::split(r, &p)?);
        found.push(Segmented {
            source: r.source_name(),
            plateaus: p,
        });
    }
    Ok((found, parts))
}

/// Records grouped by speed ([`segment::group_speeds`]): each group's
/// speeds lie within `tolerance` of its slowest; groups in speed order,
/// with their mean speed.
pub fn group_by_speed(parts: Vec<Recording>, tolerance: f64) -> Vec<(f64, Vec<Recording>)> {
    let speeds: Vec<f64> = parts
        .iter()
        .map(|r| r.meta.velocity_mm_s.unwrap_or(0.0))
        .collect();
    let (group, means) = segment::group_speeds(&speeds, tolerance);
    let mut groups: Vec<(f64, Vec<(f64, Recording)>)> =
        means.into_iter().map(|m| (m, Vec::new())).collect();
    for ((g, v), r) in group.into_iter().zip(speeds).zip(parts) {
        groups[g].1.push((v, r));
    }
    groups
        .into_iter()
        .map(|(m, mut recs)| {
            // In speed order within a group, as before.
            recs.sort_by(|a, b| a.0.total_cmp(&b.0));
            (m, recs.into_iter().map(|(_, r)| r).collect())
        })
        .collect()
}

/// Bytes of memory the analysis of `records` records of `samples` samples
/// each is expected to take at its peak.
///
/// Measured with `/usr/bin/time -f %M` (maximum resident set size) on the
/// release `ballpass analyze` of simulated 3-channel records at 1 kHz
/// (0.2 to 1.6 million samples): 1.00 kB per sample with the report,
/// 0.48–0.56 kB without; each further repeat 0.1–0.23 kB per sample. The
/// constants below round these up by about 10 %, so a refusal means the
/// run would not have fitted.
///
/// With the correlations over a lag window shorter than the record
/// (`windowed`), measured the same way on the staged analysis of a 2-hour
/// record (7.2 million samples, 2026-11-24): 66 bytes per sample with or
/// without the report (456 MiB), 58 on a 24-hour record; the constant
/// rounds these up by 14–30 %, and a further repeat is taken at 100
/// bytes per sample (its recording, signals and spectra; not measured).
/// Records up to 2^20 samples run their stages side by side, which holds
/// more per sample (the earlier 120–160 bytes): that is the floor.
pub fn analysis_bytes(samples: usize, records: usize, report: bool, windowed: bool) -> f64 {
    let (first, further) = match (windowed, report) {
        (false, true) => (1100.0, 250.0),
        (false, false) => (620.0, 250.0),
        (true, _) => (75.0, 100.0),
    };
    let need = samples as f64 * (first + further * records.saturating_sub(1) as f64);
    if windowed {
        need.max(160.0 * samples.min(1 << 20) as f64)
    } else {
        need
    }
}

/// Environment variable: the memory ballpass may use, GB (default: what
/// the system has available).
pub const MEMORY_ENV: &str = "BALLPASS_MEMORY_GB";

/// Memory this process may use now, bytes: `BALLPASS_MEMORY_GB` when set,
/// else the smaller of `MemAvailable` and the cgroup's limit less its use;
/// `None` where none can be read.
pub fn available_bytes() -> Result<Option<f64>> {
    if let Some(v) = std::env::var_os(MEMORY_ENV) {
        let gb = v
            .to_str()
            .and_then(|s| s.trim().parse::<f64>().ok())
            .filter(|g| g.is_finite() && *g > 0.0)
            .with_context(|| {
                format!(
                    "{MEMORY_ENV}={}: expected a positive number of GB",
                    v.to_string_lossy()
                )
            })?;
        return Ok(Some(gb * 1e9));
    }
    Ok(system_available_bytes())
}

fn system_available_bytes() -> Option<f64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines()
            .find(|l| l.starts_with("MemAvailable:"))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|kb| kb.parse::<f64>().ok())
            .map(|kb| kb * 1024.0)
    });
    let read = |p: &str| {
        std::fs::read_to_string(p)
            .ok()
            .and_then(|t| t.trim().parse::<f64>().ok())
    };
    let cgroup = match (
        read("/sys/fs/cgroup/memory.max"),
        read("/sys/fs/cgroup/memory.current"),
    ) {
        (Some(max), Some(cur)) => Some((max - cur).max(0.0)),
        _ => None,
    };
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// Refuses, before any work, an analysis that would not fit in memory.
///
/// `max_lag` is the correlations' lag window: a window shorter than the
/// record needs far less (see [`analysis_bytes`]); [`MaxLag::Auto`] is
/// taken at its shortest, [`MaxLag::AUTO_MIN_S`].
pub fn check_memory(recs: &[Recording], report: bool, max_lag: MaxLag, hint: &str) -> Result<()> {
    let samples = recs.iter().map(Recording::len).max().unwrap_or(0);
    let fs = recs.first().map_or(1.0, Recording::fs_hz);
    let windowed = match max_lag {
        MaxLag::Full => false,
        MaxLag::Auto => (MaxLag::AUTO_MIN_S * fs) < samples.saturating_sub(1) as f64,
        MaxLag::Seconds(s) => (s * fs) < samples.saturating_sub(1) as f64,
    };
    let need = analysis_bytes(samples, recs.len(), report, windowed);
    if let Some(have) = available_bytes()? {
        if need > have {
            let gb = |b: f64| b / 1e9;
            bail!(
                "the analysis of {} record(s) of {samples} samples needs about {:.2} GB of memory \
                 but {:.2} GB are available ({MEMORY_ENV} or the system); {hint}; nothing written",
                recs.len(),
                gb(need),
                gb(have)
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use ballpass::recording::{Channels, Metadata};

    /// A piece of `n` samples at 100 Hz starting at `t0` s.
    fn piece(t0: f64, n: usize) -> Recording {
        Recording::new(
            100.0,
            Channels {
                friction_n: Some((0..n).map(|i| i as f64).collect()),
                ..Channels::default()
            },
            Metadata {
                start_time_s: t0,
                ..Metadata::default()
            },
        )
        .unwrap()
    }

    fn window(w: &str) -> WindowArgs {
        WindowArgs {
            window: Some(w.into()),
        }
    }

    #[test]
    fn pieces_outside_the_window_are_left_out() {
        // Pieces 0–1 s, 2–3 s, 4–5 s; the window 2.5:4.5 reaches into the
        // last two.
        let pieces = vec![piece(0.0, 100), piece(2.0, 100), piece(4.0, 100)];
        let kept = window("2.5:4.5").apply_pieces(pieces).unwrap();
        assert_eq!(kept.len(), 2);
        assert_eq!(kept[0].len(), 50);
        assert!((kept[0].meta.start_time_s - 2.5).abs() < 1e-9);
        assert_eq!(kept[1].len(), 50);
        assert!((kept[1].meta.start_time_s - 4.0).abs() < 1e-9);
    }

    #[test]
    fn a_window_past_every_piece_is_an_error() {
        let pieces = vec![piece(0.0, 100), piece(2.0, 100)];
        let e = window("7:8").apply_pieces(pieces).unwrap_err().to_string();
        assert!(e.contains("the window"), "{e}");
    }

    #[test]
    fn a_piece_cut_too_short_by_the_window_is_an_error() {
        // 5 samples of the second piece are inside 2.95:3.5: fewer than
        // Recording::MIN_SAMPLES.
        let pieces = vec![piece(0.0, 100), piece(2.0, 100)];
        assert!(window("2.95:3.5").apply_pieces(pieces).is_err());
    }

    #[test]
    fn without_a_window_the_pieces_are_kept() {
        let pieces = vec![piece(0.0, 100), piece(2.0, 100)];
        let none = WindowArgs { window: None };
        assert_eq!(none.apply_pieces(pieces).unwrap().len(), 2);
    }
}
