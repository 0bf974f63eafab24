//! From the numbers a loader read to recordings: the time base, units,
//! scales, the value range, and gaps (refused, filled or split at).
//!
//! Samples live on a uniform grid: raw row `r` is grid sample `g(r) = r +`
//! (samples missing from the time column before it). A gap is a run of grid
//! samples that are missing or hold a non-finite value in some channel.
//! Missing samples are never materialised unless they are filled, so a time
//! column that jumps by an hour costs nothing.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::timebase::{self, TimeGap};
use super::units::channel_factor;
use super::{LoadOptions, Locator, RawTable, TimeUnit};
use crate::error::{excerpt, shown_path, Error, Result};
use crate::recording::{Channel, Channels, Metadata, Recording};

/// Why samples are missing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GapCause {
    /// Time stamps missing from the uniform grid (the time column jumps).
    MissingSamples,
    /// Samples without a finite value (`NaN`, `inf`, an empty cell).
    NoValue,
    /// Both, side by side.
    Both,
}

/// A run of missing samples.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Gap {
    /// First missing sample on the uniform grid (0-based).
    pub start: usize,
    /// Missing samples.
    pub len: usize,
    /// Time of the first missing sample, s.
    pub start_time_s: f64,
    /// `len / fs`, s.
    pub duration_s: f64,
    /// Why.
    pub cause: GapCause,
    /// Channels without a value there (all, for missing samples).
    pub channels: Vec<String>,
    /// Where in the file (`line 57`, `sample 57`).
    pub place: String,
}

/// A file's numbers on their time base, gaps found but not repaired: what
/// `inspect` reports on.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Time of grid sample 0, s.
    pub start_time_s: f64,
    /// Channels as read (scaled, units converted), one value per raw row;
    /// gaps hold their non-finite values.
    pub channels: Vec<(Channel, Vec<f64>)>,
    /// Grid sample of each raw row, when samples are missing (else row = sample).
    pub grid: Option<Vec<usize>>,
    /// Samples on the grid, missing ones included.
    pub grid_len: usize,
    /// Gaps, in time order.
    pub gaps: Vec<Gap>,
    /// Values beyond ±[`Recording::MAX_ABS`]: how many, and the first
    /// (channel, grid sample, value).
    pub out_of_range: (usize, Option<(Channel, usize, f64)>),
    /// How the file was read, when that changed numbers.
    pub notes: Vec<String>,
    locator: Locator,
    names: Vec<String>,
}

impl Prepared {
    fn g(&self, row: usize) -> usize {
        self.grid.as_ref().map_or(row, |g| g[row])
    }
}

/// Reads a file for inspection: its numbers on their time base with the gaps
/// listed and values out of range counted, nothing refused but what cannot
/// be placed (a bad time column, a bad cell).
///
/// # Errors
/// As [`super::load`], except for gaps and values out of range.
pub fn prepare_for_inspection(path: &Path, bytes: &[u8], opts: &LoadOptions) -> Result<Prepared> {
    opts.validate()?;
    let table = super::parse(path, bytes, opts)?;
    prepare(path, table, opts, false)
}

/// The rate given by the options or stated by the file (they must agree).
fn given_rate(path: &Path, table: &RawTable, opts: &LoadOptions) -> Result<Option<f64>> {
    match (opts.fs_hz, &table.stated_rate) {
        (Some(a), Some((b, from))) => {
            if (a - b).abs() > 1e-9 * a.abs().max(b.abs()) {
                return Err(Error::setting(
                    "fs",
                    format!(
                        "{}: {a} Hz given, but {from} states {b} Hz",
                        shown_path(path)
                    ),
                ));
            }
            Ok(Some(a))
        }
        (Some(a), None) => Ok(Some(a)),
        (None, Some((b, from))) => {
            if !(b.is_finite() && *b > 0.0) {
                return Err(Error::Format {
                    path: path.to_path_buf(),
                    reason: format!(
                        "{from} states a sampling rate of {b} Hz; expected a positive number"
                    ),
                });
            }
            Ok(Some(*b))
        }
        (None, None) => Ok(None),
    }
}

fn prepare(path: &Path, table: RawTable, opts: &LoadOptions, strict: bool) -> Result<Prepared> {
    let n = table
        .channels
        .first()
        .map(|(_, c)| c.values.len())
        .unwrap_or(0);
    for (c, col) in &table.channels {
        if col.values.len() != n {
            return Err(Error::Format {
                path: path.to_path_buf(),
                reason: format!(
                    "'{}' ({}) has {} samples but '{}' has {n}",
                    col.name,
                    c.column_name(),
                    col.values.len(),
                    table.channels[0].1.name
                ),
            });
        }
    }
    let mut notes = table.notes.clone();
    let given = given_rate(path, &table, opts)?;
    let time = if opts.ignore_time {
        None
    } else {
        table.time.as_ref()
    };
    let (fs_hz, start_time_s, time_gaps) = match time {
        Some(t) => {
            if t.values.len() != n {
                return Err(Error::Format {
                    path: path.to_path_buf(),
                    reason: format!(
                        "time '{}' has {} samples but the channels have {n}",
                        t.name,
                        t.values.len()
                    ),
                });
            }
            let unit = time_unit(path, &table, opts)?;
            let (times, resolution);
            let scaled: Vec<f64>;
            if unit == TimeUnit::S {
                times = &t.values[..];
                resolution = t.resolution;
            } else {
                let k = unit.seconds();
                scaled = t.values.iter().map(|x| x * k).collect();
                times = &scaled[..];
                resolution = t.resolution * k;
                notes.push(format!("time '{}' read in {}", t.name, unit.symbol()));
            }
            let base = timebase::derive(times, resolution, opts.time_step_tolerance, true)
                .map_err(|e| table.locator.error(path, e.index, &t.name, e.reason))?;
            let steps = base.grid_steps(n);
            let fs = match given {
                Some(fs) => {
                    timebase::check_given_rate(times, resolution, fs, steps).map_err(|e| {
                        Error::setting(
                            "fs",
                            format!("{}: {} (time '{}')", shown_path(path), e.reason, t.name),
                        )
                    })?;
                    fs
                }
                None => base.fs_hz,
            };
            (fs, base.start_time_s, base.gaps)
        }
        None => match given {
            Some(fs) => (fs, table.start_time_s.unwrap_or(0.0), Vec::new()),
            None => {
                return Err(Error::Format {
                    path: path.to_path_buf(),
                    reason: format!(
                        "no time column ('{}') and no sampling rate given (fs): one is needed",
                        excerpt(opts.time.as_deref().unwrap_or("time_s"))
                    ),
                })
            }
        },
    };

    let mut channels = Vec::with_capacity(table.channels.len());
    let mut names = Vec::with_capacity(table.channels.len());
    let mut out_of_range = (0usize, None);
    let mut all_in_range = true;
    for (c, col) in table.channels {
        let src = opts.source(c);
        let mut factor = 1.0;
        if let Some((unit, from)) = &col.unit {
            match channel_factor(c, unit) {
                Some(1.0) => {}
                Some(f) if src.is_identity() => {
                    factor = f;
                    notes.push(format!(
                        "{}: '{}' is in {} ({from}), converted to {} (x{f})",
                        c.column_name(),
                        col.name,
                        excerpt(unit),
                        c.unit()
                    ));
                }
                Some(_) => notes.push(format!(
                    "{}: '{}' is in {} ({from}); the given scale is used instead",
                    c.column_name(),
                    col.name,
                    excerpt(unit)
                )),
                None if src.is_identity() => {
                    return Err(Error::Format {
                        path: path.to_path_buf(),
                        reason: format!(
                            "'{}' for {} is in '{}' ({from}), which ballpass cannot convert to \
                             {}: give the {} scale (and offset) that does",
                            col.name,
                            c.column_name(),
                            excerpt(unit),
                            c.unit(),
                            c.short_name()
                        ),
                    })
                }
                None => {}
            }
        }
        let scale = src.scale * factor;
        let mut v = col.values;
        if scale != 1.0 || src.offset != 0.0 {
            for x in &mut v {
                *x = *x * scale + src.offset;
            }
        }
        // One pass in the common case (every value finite and in range).
        let in_range = v
            .iter()
            .fold(true, |ok, x| ok & (x.abs() <= Recording::MAX_ABS));
        all_in_range &= in_range;
        for (i, &x) in v.iter().enumerate() {
            if !in_range && x.is_finite() && x.abs() > Recording::MAX_ABS {
                if strict {
                    let scaled = if scale != 1.0 || src.offset != 0.0 {
                        " after scaling"
                    } else {
                        ""
                    };
                    return Err(table.locator.error(
                        path,
                        i,
                        &col.name,
                        format!(
                            "{}: value {x:e}{scaled} is beyond ±{:e}, far outside any \
                             measurement (check the file and the scale)",
                            c.column_name(),
                            Recording::MAX_ABS
                        ),
                    ));
                }
                out_of_range.0 += 1;
                out_of_range.1.get_or_insert((c, i, x));
            }
        }
        names.push(col.name);
        channels.push((c, v));
    }
    let missing = time_gaps
        .iter()
        .fold(0usize, |a, g| a.saturating_add(g.missing));
    let grid = (!time_gaps.is_empty()).then(|| {
        let mut g = Vec::with_capacity(n);
        let mut shift = 0usize;
        let mut next = time_gaps.iter().peekable();
        for r in 0..n {
            while let Some(tg) = next.next_if(|tg| tg.index == r) {
                shift = shift.saturating_add(tg.missing);
            }
            g.push(r.saturating_add(shift));
        }
        g
    });
    if let Some((c, i, x)) = out_of_range.1 {
        out_of_range.1 = Some((c, grid.as_ref().map_or(i, |g| g[i]), x));
    }
    let mut p = Prepared {
        fs_hz,
        start_time_s,
        channels,
        grid,
        grid_len: n.saturating_add(missing),
        gaps: Vec::new(),
        out_of_range,
        notes,
        locator: table.locator,
        names,
    };
    if !(all_in_range && time_gaps.is_empty()) {
        p.gaps = find_gaps(&p, &time_gaps);
    }
    Ok(p)
}

/// The unit of the time column: the option, else what the file states, else s.
pub(crate) fn time_unit(path: &Path, table: &RawTable, opts: &LoadOptions) -> Result<TimeUnit> {
    match (opts.time_unit, &table.time_unit) {
        (Some(a), Some((b, from))) if a != *b => Err(Error::setting(
            "time unit",
            format!(
                "{}: {} given, but {from} says {}",
                shown_path(path),
                a.symbol(),
                b.symbol()
            ),
        )),
        (Some(a), _) => Ok(a),
        (None, Some((b, _))) => Ok(*b),
        (None, None) => Ok(TimeUnit::S),
    }
}

/// Gaps: runs of missing samples and of rows where some channel has no
/// finite value, merged where they touch on the grid.
fn find_gaps(p: &Prepared, time_gaps: &[TimeGap]) -> Vec<Gap> {
    // (grid start, grid end, row at or after the start, has missing, has no-value)
    let mut runs: Vec<(usize, usize, usize, bool, bool)> = Vec::new();
    for tg in time_gaps {
        let end = p.g(tg.index);
        runs.push((end.saturating_sub(tg.missing), end, tg.index, true, false));
    }
    let n = p.channels.first().map_or(0, |(_, v)| v.len());
    let bad = |r: usize| p.channels.iter().any(|(_, v)| !v[r].is_finite());
    let all_finite = p
        .channels
        .iter()
        .all(|(_, v)| v.iter().fold(true, |ok, x| ok & x.is_finite()));
    let mut r = if all_finite { n } else { 0 };
    while r < n {
        if bad(r) {
            let r0 = r;
            while r < n && bad(r) && (r == r0 || p.g(r) == p.g(r - 1) + 1) {
                r += 1;
            }
            runs.push((p.g(r0), p.g(r - 1) + 1, r0, false, true));
        } else {
            r += 1;
        }
    }
    runs.sort_by_key(|x| x.0);
    let mut merged: Vec<(usize, usize, usize, bool, bool)> = Vec::new();
    for run in runs {
        match merged.last_mut() {
            Some(last) if run.0 <= last.1 => {
                last.1 = last.1.max(run.1);
                last.3 |= run.3;
                last.4 |= run.4;
                if run.4 && !last.4 {
                    last.2 = run.2;
                }
            }
            _ => merged.push(run),
        }
    }
    merged
        .into_iter()
        .map(|(start, end, row, missing, nan)| {
            let cause = match (missing, nan) {
                (true, true) => GapCause::Both,
                (true, false) => GapCause::MissingSamples,
                _ => GapCause::NoValue,
            };
            let channels = p
                .channels
                .iter()
                .filter(|(_, v)| {
                    missing
                        || (row..n)
                            .take_while(|&r| p.g(r) < end)
                            .any(|r| !v[r].is_finite())
                })
                .map(|(c, _)| c.column_name().to_string())
                .collect();
            Gap {
                start,
                len: end - start,
                start_time_s: p.start_time_s + start as f64 / p.fs_hz,
                duration_s: (end - start) as f64 / p.fs_hz,
                cause,
                channels,
                place: p.locator.place(row.min(n.saturating_sub(1))),
            }
        })
        .collect()
}

/// Validates a raw table and builds the recordings (several when the gap
/// policy splits it).
pub(crate) fn finish(path: &Path, table: RawTable, opts: &LoadOptions) -> Result<Vec<Recording>> {
    let mut p = prepare(path, table, opts, true)?;
    let policy = opts.gaps;
    // What happens to each gap.
    let mut fill = Vec::new();
    let mut cut = Vec::new();
    for (k, gap) in p.gaps.iter().enumerate() {
        let edge = gap.start == 0 || gap.start + gap.len == p.grid_len;
        let short = policy
            .fill_max_s
            .is_some_and(|m| gap.duration_s <= m * (1.0 + 1e-9));
        if policy.refuses() {
            return Err(refusal(path, &p, k));
        } else if short && !edge {
            fill.push(k);
        } else if policy.split || edge {
            cut.push(k);
        } else {
            return Err(refusal(path, &p, k));
        }
    }
    let invented = fill
        .iter()
        .fold(0usize, |a, &k| a.saturating_add(p.gaps[k].len));
    let real = p.channels.first().map_or(0, |(_, v)| v.len());
    if invented > real {
        return Err(Error::InvalidRecording {
            source_name: shown_path(path),
            reason: format!(
                "filling its gaps would invent {invented} samples, more than the {real} it holds"
            ),
        });
    }
    // Pieces: grid ranges between cut gaps.
    let mut bounds = Vec::new();
    let mut from = 0;
    for &k in &cut {
        let g = &p.gaps[k];
        bounds.push((from, g.start));
        from = g.start + g.len;
    }
    bounds.push((from, p.grid_len));
    let mut notes = p.notes.clone();
    if !fill.is_empty() {
        let longest = fill.iter().map(|&k| p.gaps[k].len).max().unwrap_or(0);
        let first = &p.gaps[fill[0]];
        notes.push(format!(
            "filled {} gap(s) by linear interpolation: {invented} sample(s), the longest {longest} \
             ({:.6} s), the first at t = {:.6} s ({})",
            fill.len(),
            longest as f64 / p.fs_hz,
            first.start_time_s,
            first.place
        ));
    }
    let cut_notes: Vec<String> = cut
        .iter()
        .map(|&k| {
            let g = &p.gaps[k];
            format!(
                "cut at a gap of {} sample(s) ({:.6} s) at t = {:.6} s ({})",
                g.len, g.duration_s, g.start_time_s, g.place
            )
        })
        .collect();
    notes.extend(cut_notes);
    let stem = opts
        .test_id
        .clone()
        .or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned()));
    let pieces: Vec<(usize, usize)> = bounds.into_iter().filter(|(a, b)| b > a).collect();
    let several = pieces.len() > 1;
    let mut out = Vec::new();
    let mut dropped = Vec::new();
    // The common file (no gap): its columns become the recording as they are.
    let whole = pieces.len() == 1 && fill.is_empty() && p.grid.is_none() && p.gaps.is_empty();
    let mut columns = if whole {
        std::mem::take(&mut p.channels)
    } else {
        Vec::new()
    };
    for (k, &(a, b)) in pieces.iter().enumerate() {
        let channels = if whole {
            let mut out = Channels::default();
            for (c, v) in columns.drain(..) {
                match c {
                    Channel::Friction => out.friction_n = Some(v),
                    Channel::Position => out.position_mm = Some(v),
                    Channel::Optical => out.optical_v = Some(v),
                }
            }
            out
        } else {
            materialise(&p, a, b, &fill)
        };
        let mut meta = Metadata {
            velocity_mm_s: opts.velocity_mm_s,
            bearing: opts.bearing.clone(),
            test_id: match (&stem, several) {
                (Some(s), true) => Some(format!("{s}_part{}", k + 1)),
                (s, _) => s.clone(),
            },
            source: Some(path.to_path_buf()),
            start_time_s: p.start_time_s + a as f64 / p.fs_hz,
            notes: notes.clone(),
        };
        if several {
            meta.notes.push(format!(
                "piece {} of {}: t = {:.6} to {:.6} s",
                k + 1,
                pieces.len(),
                meta.start_time_s,
                p.start_time_s + b as f64 / p.fs_hz
            ));
        }
        let piece = Recording::new(p.fs_hz, channels, meta);
        let piece = match piece {
            Ok(r) => check_periods(r, opts),
            Err(e) => Err(e),
        };
        match piece {
            Ok(r) => out.push(r),
            Err(e) if several => dropped.push(format!("piece {} dropped: {e}", k + 1)),
            Err(e) => return Err(e),
        }
    }
    if out.is_empty() {
        return Err(Error::InvalidRecording {
            source_name: shown_path(path),
            reason: format!(
                "nothing usable is left between its gaps ({} piece(s), all too short)",
                pieces.len()
            ),
        });
    }
    for r in &mut out {
        r.meta.notes.extend(dropped.iter().cloned());
    }
    Ok(out)
}

/// The error for gap `k` when it may not be repaired.
fn refusal(path: &Path, p: &Prepared, k: usize) -> Error {
    let g = &p.gaps[k];
    let what = match g.cause {
        GapCause::MissingSamples => format!("{} sample(s) missing from the time column", g.len),
        _ => format!(
            "no finite value in {} for {} sample(s)",
            g.channels.join(", "),
            g.len
        ),
    };
    let how = if p.gaps.len() > 1 {
        format!("; {} gaps in the record", p.gaps.len())
    } else {
        String::new()
    };
    let reason = format!(
        "{what} at t = {:.6} s ({:.6} s long){how}: fill short gaps (fill-gaps SECONDS) or \
         split the record at them (split-gaps); `ballpass inspect` lists them",
        g.start_time_s, g.duration_s
    );
    // Name the column where the first bad value is.
    let row = p
        .grid
        .as_ref()
        .map_or(g.start, |grid| grid.partition_point(|&x| x < g.start));
    let column = p
        .channels
        .iter()
        .zip(&p.names)
        .find(|((_, v), _)| v.get(row).is_some_and(|x| !x.is_finite()))
        .map(|(_, name)| name.as_str())
        .unwrap_or("time");
    p.locator.error(
        path,
        row.min(p.channels[0].1.len().saturating_sub(1)),
        column,
        reason,
    )
}

/// Grid samples `a..b` of every channel, the gaps in `fill` interpolated.
fn materialise(p: &Prepared, a: usize, b: usize, fill: &[usize]) -> Channels {
    let mut out = Channels::default();
    for (c, v) in &p.channels {
        let mut x = vec![f64::NAN; b - a];
        for (r, &val) in v.iter().enumerate() {
            let g = p.g(r);
            if g >= a && g < b {
                x[g - a] = val;
            }
        }
        for &k in fill {
            let gap = &p.gaps[k];
            if gap.start < a || gap.start + gap.len > b {
                continue;
            }
            let (s, e) = (gap.start - a, gap.start + gap.len - a);
            // Each channel's own runs inside the gap, between its finite neighbours.
            let mut i = s;
            while i < e {
                if x[i].is_finite() {
                    i += 1;
                    continue;
                }
                let j = (i..e).find(|&j| x[j].is_finite()).unwrap_or(e);
                let (l, r) = (x[i - 1], x[j]);
                let span = (j - i + 1) as f64;
                for (m, slot) in x[i..j].iter_mut().enumerate() {
                    *slot = l + (r - l) * (m + 1) as f64 / span;
                }
                i = j;
            }
        }
        match c {
            Channel::Friction => out.friction_n = Some(x),
            Channel::Position => out.position_mm = Some(x),
            Channel::Optical => out.optical_v = Some(x),
        }
    }
    out
}

/// With velocity and geometry known, the recording must span `min_periods` periods.
fn check_periods(rec: Recording, opts: &LoadOptions) -> Result<Recording> {
    let (Some(v), Some(g)) = (opts.velocity_mm_s, opts.geometry) else {
        return Ok(rec);
    };
    let tau_c_s = 1.0 / (v / (2.0 * g.d_avg_mm()));
    let periods = rec.duration_s() / tau_c_s;
    if periods < opts.min_periods {
        return Err(Error::InvalidRecording {
            source_name: rec.source_name(),
            reason: format!(
                "{:.4} s of data spans {periods:.2} ball-pass periods at {v} mm/s \
                 (tau_c = {tau_c_s:.4} s); at least {} needed (min_periods)",
                rec.duration_s(),
                opts.min_periods
            ),
        });
    }
    Ok(rec)
}
