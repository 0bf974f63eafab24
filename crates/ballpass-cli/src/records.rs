//! Flags and glue for what happens to records between loading and
//! analysing: a time window, plateau segmentation, the pre-verdict checks
//! (dead channels, velocity against the encoder) and the memory estimate.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use ballpass::analysis::preflight::PreflightSettings;
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

/// Loads `paths` in parallel and applies the window; the first failure in
/// argument order is the one reported.
pub fn load_all(
    paths: &[PathBuf],
    opts: &LoadOptions,
    window: &WindowArgs,
) -> Result<Vec<Recording>> {
    window.parsed()?;
    paths
        .par_iter()
        .map(|p| {
            let rec = ballpass::recording::load(p, opts)
                .with_context(|| format!("loading {}", p.display()))?;
            window.apply(rec)
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect()
}

/// Each record's plateaus and the plateaus as records.
pub fn segment_all(recs: &[Recording]) -> Result<(Vec<Segmented>, Vec<Recording>)> {
    let settings = SegmentSettings::default();
    let mut found = Vec::new();
    let mut parts = Vec::new();
    for r in recs {
        let p = segment::plateaus(r, &settings)?;
        if p.is_empty() {
            bail!(
                "{}: no constant-velocity plateau of at least {} s found from the encoder",
                r.source_name(),
                settings.min_duration_s
            );
        }
        parts.extend(segment::split(r, &p)?);
        found.push(Segmented {
            source: r.source_name(),
            plateaus: p,
        });
    }
    Ok((found, parts))
}

/// Records grouped by speed: each group's speeds lie within `tolerance` of
/// its mean (the first record of a group sets it; groups in speed order).
pub fn group_by_speed(parts: Vec<Recording>, tolerance: f64) -> Vec<(f64, Vec<Recording>)> {
    let mut parts: Vec<(f64, Recording)> = parts
        .into_iter()
        .map(|r| (r.meta.velocity_mm_s.unwrap_or(0.0), r))
        .collect();
    parts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut groups: Vec<(f64, Vec<f64>, Vec<Recording>)> = Vec::new();
    for (v, r) in parts {
        match groups.last_mut() {
            Some((first, speeds, recs)) if (v - *first).abs() <= tolerance * *first => {
                speeds.push(v);
                recs.push(r);
            }
            _ => groups.push((v, vec![v], vec![r])),
        }
    }
    groups
        .into_iter()
        .map(|(_, speeds, recs)| (speeds.iter().sum::<f64>() / speeds.len() as f64, recs))
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
pub fn analysis_bytes(samples: usize, records: usize, report: bool) -> f64 {
    let first = if report { 1100.0 } else { 620.0 };
    let further = 250.0;
    samples as f64 * (first + further * records.saturating_sub(1) as f64)
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
pub fn check_memory(recs: &[Recording], report: bool, hint: &str) -> Result<()> {
    let samples = recs.iter().map(Recording::len).max().unwrap_or(0);
    let need = analysis_bytes(samples, recs.len(), report);
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
