//! Recording operations that keep a part of a record: a time window
//! ([`Window`], [`window`]), a channel left out ([`Recording::without_channel`]),
//! and the constant-velocity plateaus of a multi-speed run found from the
//! encoder ([`plateaus`], [`split`]).
//!
//! A part keeps the time axis of its record (`meta.start_time_s` is the time
//! of its first sample) and says what it is in its name: its source becomes
//! `run.csv (t = 5.000–20.000 s)`, which every output that names a record
//! shows.
//!
//! # Plateaus
//!
//! The stage velocity is the least-squares slope of the position in blocks
//! of `block_s` (0.1 s). Blocks are grouped greedily into runs whose
//! velocities stay within `2 tolerance` of the run's median; each run's
//! velocity `V` is the median of its blocks, and blocks at either end that
//! differ from `V` by more than `tolerance |V|` are dropped: that removes
//! the ramps between speeds and the settling of the stage after them
//! (transients). A run is a plateau when what is left lasts at least
//! `min_duration_s` and `|V|` is at least `min_speed_mm_s` (a stage at rest
//! is no plateau). The plateau's velocity is then the least-squares slope of
//! the position over its samples; its sign is the direction.
//!
//! [`split`] makes each plateau a recording of its own, with the plateau's
//! speed as its velocity. A backward plateau (position decreasing) is
//! mirrored to look like forward motion: position and friction change sign
//! (the load cell reads the force against the motion, which turns with the
//! motion), the optical signal is kept. Every analysis then sees a stage
//! moving forward at a positive velocity, as it expects.

use serde::{Deserialize, Serialize};

use super::{Channel, Channels, Recording};
use crate::error::{Error, Result};

/// A time window `[start_s, end_s)` on a record's time axis (the time
/// column's, or `i / fs` without one); an open end runs to the record's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Window {
    /// First time kept, s (`None`: from the start).
    pub start_s: Option<f64>,
    /// Time where the window ends (excluded), s (`None`: to the end).
    pub end_s: Option<f64>,
}

impl Window {
    /// Parses `T0:T1`, `T0:` or `:T1` (seconds).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] (`window`) for anything else, a value that
    /// is not finite, or `T1 <= T0`.
    pub fn parse(s: &str) -> Result<Self> {
        let bad = |why: &str| Error::setting("window", format!("'{s}': {why}"));
        let (a, b) = s.split_once(':').ok_or_else(|| {
            bad(
                "expected T0:T1 in seconds (either may be left out); the Welch window of \
                 `analyze` is --welch-window",
            )
        })?;
        let num = |p: &str| -> Result<Option<f64>> {
            let p = p.trim();
            if p.is_empty() {
                return Ok(None);
            }
            match p.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(Some(v)),
                _ => Err(bad(&format!("'{p}' is not a finite number of seconds"))),
            }
        };
        let w = Window {
            start_s: num(a)?,
            end_s: num(b)?,
        };
        if w.start_s.is_none() && w.end_s.is_none() {
            return Err(bad("give T0, T1 or both"));
        }
        if let (Some(a), Some(b)) = (w.start_s, w.end_s) {
            if b <= a {
                return Err(bad("T1 must be after T0"));
            }
        }
        Ok(w)
    }

    /// `5–20 s`, `from 5 s`, `to 20 s`.
    pub fn describe(&self) -> String {
        match (self.start_s, self.end_s) {
            (Some(a), Some(b)) => format!("{a}–{b} s"),
            (Some(a), None) => format!("from {a} s"),
            (None, Some(b)) => format!("to {b} s"),
            (None, None) => "whole record".into(),
        }
    }
}

/// The samples of `rec` inside `w` (see [`Window`]).
///
/// # Errors
/// [`Error::InvalidRecording`] naming the record and both time ranges when
/// the window holds fewer than [`Recording::MIN_SAMPLES`] of its samples.
pub fn window(rec: &Recording, w: &Window) -> Result<Recording> {
    let fs = rec.fs_hz();
    let t0 = rec.meta.start_time_s;
    // Sample i is at t0 + i / fs; the first at or after a time t is
    // ceil((t - t0) fs), with a nanosample allowance for times typed from
    // the same grid.
    let index = |t: f64| ((t - t0) * fs - 1e-9).ceil().clamp(0.0, rec.len() as f64) as usize;
    let i0 = w.start_s.map_or(0, index);
    let i1 = w.end_s.map_or(rec.len(), index);
    if i1 <= i0 || i1 - i0 < Recording::MIN_SAMPLES {
        return Err(Error::InvalidRecording {
            source_name: rec.source_name(),
            reason: format!(
                "the window {} holds {} samples of this record ({:.3}–{:.3} s); at least {} needed",
                w.describe(),
                i1.saturating_sub(i0),
                t0,
                rec.time_s(rec.len()),
                Recording::MIN_SAMPLES
            ),
        });
    }
    slice(rec, i0, i1, false)
}

/// Samples `i0..i1` of `rec` as a recording named after its time range;
/// `mirror` changes the sign of position and friction (see the module docs).
fn slice(rec: &Recording, i0: usize, i1: usize, mirror: bool) -> Result<Recording> {
    let part = |c: Channel| {
        rec.channel(c).map(|x| {
            let x = &x[i0..i1];
            if mirror && c != Channel::Optical {
                x.iter().map(|v| -v).collect()
            } else {
                x.to_vec()
            }
        })
    };
    let mut meta = rec.meta.clone();
    meta.start_time_s = rec.time_s(i0);
    let name = rec.source_name();
    meta.source =
        Some(format!("{name} (t = {:.3}–{:.3} s)", rec.time_s(i0), rec.time_s(i1)).into());
    Recording::new(
        rec.fs_hz(),
        Channels {
            friction_n: part(Channel::Friction),
            position_mm: part(Channel::Position),
            optical_v: part(Channel::Optical),
        },
        meta,
    )
}

impl Recording {
    /// The recording without channel `c` (the others untouched, no copy).
    ///
    /// # Errors
    /// [`Error::InvalidChannel`] when `c` is the only channel.
    pub fn without_channel(mut self, c: Channel) -> Result<Recording> {
        let slot = match c {
            Channel::Friction => &mut self.friction_n,
            Channel::Position => &mut self.position_mm,
            Channel::Optical => &mut self.optical_v,
        };
        slot.take();
        if self.channels().is_empty() {
            return Err(Error::InvalidChannel {
                channel: c.column_name().into(),
                source_name: self.source_name(),
                reason: "is the only channel; nothing would be left".into(),
            });
        }
        Ok(self)
    }
}

/// Settings of [`plateaus`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SegmentSettings {
    /// Length of the blocks whose slope is the local velocity, s.
    pub block_s: f64,
    /// Largest relative deviation of a block's velocity from its plateau's.
    pub tolerance: f64,
    /// Shortest plateau kept, s.
    pub min_duration_s: f64,
    /// Slowest plateau kept, mm/s (slower: the stage is at rest).
    pub min_speed_mm_s: f64,
}

impl Default for SegmentSettings {
    fn default() -> Self {
        Self {
            block_s: 0.1,
            tolerance: 0.02,
            min_duration_s: 1.0,
            min_speed_mm_s: 0.05,
        }
    }
}

impl SegmentSettings {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the field.
    pub fn validate(&self) -> Result<()> {
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::setting(
                    name,
                    format!("must be a positive number, got {v}"),
                ))
            }
        };
        positive("segment block_s", self.block_s)?;
        positive("segment min_duration_s", self.min_duration_s)?;
        positive("segment min_speed_mm_s", self.min_speed_mm_s)?;
        if !(self.tolerance > 0.0 && self.tolerance < 0.5) {
            return Err(Error::setting(
                "segment tolerance",
                format!("must be between 0 and 0.5, got {}", self.tolerance),
            ));
        }
        if self.min_duration_s < 2.0 * self.block_s {
            return Err(Error::setting(
                "segment min_duration_s",
                format!(
                    "must be at least two blocks ({} s), got {}",
                    2.0 * self.block_s,
                    self.min_duration_s
                ),
            ));
        }
        Ok(())
    }
}

/// Direction of the stage on a plateau.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Position increasing.
    Forward,
    /// Position decreasing.
    Backward,
}

/// One constant-velocity part of a record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plateau {
    /// First sample (0-based).
    pub start: usize,
    /// One past the last sample.
    pub end: usize,
    /// Time of the first sample, s (the record's time axis).
    pub start_s: f64,
    /// Time one sample past the last, s.
    pub end_s: f64,
    /// Least-squares slope of the position over the plateau, mm/s (signed).
    pub velocity_mm_s: f64,
    /// Its magnitude, mm/s.
    pub speed_mm_s: f64,
    /// Its sign.
    pub direction: Direction,
    /// Largest relative deviation of a block's velocity from the plateau's.
    pub max_deviation: f64,
}

/// Least-squares slope of `x` against the sample index, per sample (0 for
/// fewer than two samples).
pub(crate) fn slope(x: &[f64]) -> f64 {
    let n = x.len() as f64;
    let tm = (n - 1.0) / 2.0;
    let mean = x.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, v) in x.iter().enumerate() {
        let d = i as f64 - tm;
        sxy += d * (v - mean);
        sxx += d * d;
    }
    if sxx > 0.0 {
        sxy / sxx
    } else {
        0.0
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The constant-velocity plateaus of `rec`, in time order (see the module
/// docs for how they are found).
///
/// # Errors
/// [`Error::MissingChannel`] without a position channel;
/// [`Error::InvalidSetting`] for bad settings.
pub fn plateaus(rec: &Recording, s: &SegmentSettings) -> Result<Vec<Plateau>> {
    s.validate()?;
    let x = rec.require(Channel::Position, "plateau segmentation")?;
    let fs = rec.fs_hz();
    let b = ((s.block_s * fs).round() as usize).max(2);
    let nb = x.len() / b;
    let v: Vec<f64> = (0..nb)
        .map(|j| slope(&x[j * b..(j + 1) * b]) * fs)
        .collect();
    let within = |a: f64, reference: f64, tol: f64| {
        (a - reference).abs() <= tol * reference.abs().max(s.min_speed_mm_s)
    };
    let min_blocks = ((s.min_duration_s * fs) / b as f64).ceil() as usize;
    let mut out = Vec::new();
    let mut j = 0;
    while j < nb {
        // Grow a run from block j while blocks stay near its running mean
        // (O(1) per block; the median below is taken once per run).
        let mut k = j + 1;
        let mut sum = v[j];
        while k < nb && within(v[k], sum / (k - j) as f64, 2.0 * s.tolerance) {
            sum += v[k];
            k += 1;
        }
        let vel = median(&mut v[j..k].to_vec());
        // Drop end blocks that are off the plateau's velocity.
        let (mut a, mut e) = (j, k);
        while a < e && !within(v[a], vel, s.tolerance) {
            a += 1;
        }
        while e > a && !within(v[e - 1], vel, s.tolerance) {
            e -= 1;
        }
        if e - a >= min_blocks && vel.abs() >= s.min_speed_mm_s {
            let (i0, i1) = (a * b, e * b);
            let velocity = slope(&x[i0..i1]) * fs;
            let max_deviation = v[a..e]
                .iter()
                .map(|w| (w - velocity).abs() / velocity.abs())
                .fold(0.0, f64::max);
            out.push(Plateau {
                start: i0,
                end: i1,
                start_s: rec.time_s(i0),
                end_s: rec.time_s(i1),
                velocity_mm_s: velocity,
                speed_mm_s: velocity.abs(),
                direction: if velocity >= 0.0 {
                    Direction::Forward
                } else {
                    Direction::Backward
                },
                max_deviation,
            });
        }
        j = k;
    }
    Ok(out)
}

/// Each plateau as a recording of its own: velocity its speed, backward
/// ones mirrored to forward motion (see the module docs), named after its
/// time range.
///
/// # Errors
/// [`Error::InvalidRecording`] for a plateau outside the record or shorter
/// than [`Recording::MIN_SAMPLES`].
pub fn split(rec: &Recording, plateaus: &[Plateau]) -> Result<Vec<Recording>> {
    plateaus
        .iter()
        .map(|p| {
            if p.end > rec.len() || p.end < p.start + Recording::MIN_SAMPLES {
                return Err(Error::InvalidRecording {
                    source_name: rec.source_name(),
                    reason: format!(
                        "plateau samples {}..{} do not fit a record of {} samples",
                        p.start,
                        p.end,
                        rec.len()
                    ),
                });
            }
            let mut r = slice(rec, p.start, p.end, p.direction == Direction::Backward)?;
            r.meta.velocity_mm_s = Some(p.speed_mm_s);
            Ok(r)
        })
        .collect()
}

/// [`plateaus`], refusing a record where none is found.
///
/// # Errors
/// As [`plateaus`]; [`Error::InvalidRecording`] naming the record when it
/// holds no plateau.
pub fn plateaus_found(rec: &Recording, s: &SegmentSettings) -> Result<Vec<Plateau>> {
    let p = plateaus(rec, s)?;
    if p.is_empty() {
        return Err(Error::InvalidRecording {
            source_name: rec.source_name(),
            reason: format!(
                "no constant-velocity plateau of at least {} s at {} mm/s or faster found from the \
                 encoder",
                s.min_duration_s, s.min_speed_mm_s
            ),
        });
    }
    Ok(p)
}

/// Plateaus (by speed) grouped into the speeds of a run: speeds sorted,
/// each group's speeds within `tolerance` (relative) of its slowest one.
/// Returns the group of each input speed and the mean speed of each group
/// (groups in ascending speed).
pub fn group_speeds(speeds: &[f64], tolerance: f64) -> (Vec<usize>, Vec<f64>) {
    let mut order: Vec<usize> = (0..speeds.len()).collect();
    order.sort_by(|&a, &b| speeds[a].total_cmp(&speeds[b]));
    let mut group = vec![0; speeds.len()];
    let mut members: Vec<Vec<f64>> = Vec::new();
    let mut first = f64::NAN;
    for i in order {
        let v = speeds[i];
        match members.last_mut() {
            Some(m) if (v - first).abs() <= tolerance * first => m.push(v),
            _ => {
                first = v;
                members.push(vec![v]);
            }
        }
        group[i] = members.len() - 1;
    }
    let means = members
        .iter()
        .map(|m| m.iter().sum::<f64>() / m.len() as f64)
        .collect();
    (group, means)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::Metadata;

    fn rec(position: Vec<f64>, start: f64) -> Recording {
        let n = position.len();
        Recording::new(
            1000.0,
            Channels {
                friction_n: Some((0..n).map(|i| 3.0 + (i as f64 * 0.1).sin()).collect()),
                position_mm: Some(position),
                optical_v: Some(vec![1.0; n]),
            },
            Metadata {
                source: Some("run.csv".into()),
                start_time_s: start,
                ..Default::default()
            },
        )
        .unwrap()
    }

    #[test]
    fn windows_parse_and_cut_on_the_time_axis() {
        assert_eq!(
            Window::parse("5:20").unwrap(),
            Window {
                start_s: Some(5.0),
                end_s: Some(20.0)
            }
        );
        assert_eq!(Window::parse(":2").unwrap().start_s, None);
        for bad in ["", "5", ":", "3:1", "a:2", "1:inf"] {
            assert!(Window::parse(bad).is_err(), "{bad}");
        }
        // 10 s at 1 kHz whose first sample is at t = 100 s.
        let r = rec((0..10_000).map(|i| i as f64 * 0.009).collect(), 100.0);
        let w = window(&r, &Window::parse("102:104.5").unwrap()).unwrap();
        assert_eq!(w.len(), 2500);
        assert_eq!(w.meta.start_time_s, 102.0);
        assert_eq!(
            w.channel(Channel::Position).unwrap()[0],
            r.channel(Channel::Position).unwrap()[2000]
        );
        assert_eq!(
            w.source_name(),
            "run.csv (t = 102.000–104.500 s)",
            "the part says what it is"
        );
        assert_eq!(
            window(&r, &Window::parse("109:").unwrap()).unwrap().len(),
            1000
        );
        let e = window(&r, &Window::parse("0:50").unwrap()).unwrap_err();
        assert!(
            e.to_string().contains("run.csv") && e.to_string().contains("100.000–110.000 s"),
            "{e}"
        );
    }

    #[test]
    fn a_channel_is_left_out_but_never_the_last() {
        let r = rec(vec![0.0; 100], 0.0);
        let r = r.without_channel(Channel::Friction).unwrap();
        assert_eq!(r.channels(), [Channel::Position, Channel::Optical]);
        let r = r.without_channel(Channel::Optical).unwrap();
        assert!(r.without_channel(Channel::Position).is_err());
    }

    /// Piecewise motion with exact ramps: plateaus at the right speeds and
    /// directions, ramps dropped.
    #[test]
    fn plateaus_of_a_clean_profile() {
        // 2 s at +20, ramp 0.5 s to -20, 2 s at -20, ramp to +5, 3 s at +5.
        let mut v = Vec::new();
        v.extend(std::iter::repeat_n(20.0, 2000));
        v.extend((0..500).map(|i| 20.0 - 40.0 * i as f64 / 500.0));
        v.extend(std::iter::repeat_n(-20.0, 2000));
        v.extend((0..500).map(|i| -20.0 + 25.0 * i as f64 / 500.0));
        v.extend(std::iter::repeat_n(5.0, 3000));
        let mut x = 0.0;
        let pos: Vec<f64> = v
            .iter()
            .map(|dv| {
                x += dv / 1000.0;
                x
            })
            .collect();
        let r = rec(pos, 0.0);
        let p = plateaus(&r, &SegmentSettings::default()).unwrap();
        let got: Vec<(f64, Direction)> = p.iter().map(|p| (p.velocity_mm_s, p.direction)).collect();
        assert_eq!(got.len(), 3, "{p:?}");
        for ((v, d), (want, wd)) in got.iter().zip([
            (20.0, Direction::Forward),
            (-20.0, Direction::Backward),
            (5.0, Direction::Forward),
        ]) {
            // Exact ramps: the slope is exact to rounding.
            assert!((v - want).abs() < 1e-9, "{v} vs {want}");
            assert_eq!(*d, wd);
        }
        // Boundaries within one block (0.1 s) of the true ones.
        let truth = [(0.0, 2.0), (2.5, 4.5), (5.0, 8.0)];
        for (p, (a, b)) in p.iter().zip(truth) {
            assert!(p.start_s >= a - 1e-9 && p.start_s <= a + 0.1, "{p:?}");
            assert!(p.end_s <= b + 1e-9 && p.end_s >= b - 0.1, "{p:?}");
        }
        let parts = split(&r, &p).unwrap();
        assert!((parts[1].meta.velocity_mm_s.unwrap() - 20.0).abs() < 1e-9);
        // The backward plateau is mirrored: position increases.
        let x1 = parts[1].channel(Channel::Position).unwrap();
        assert!(x1[x1.len() - 1] > x1[0]);
        assert!(parts[1].channel(Channel::Friction).unwrap()[0] < 0.0);
    }

    /// Speeds forward and back, in any order, pooled within the tolerance
    /// of their group's slowest; a speed just outside starts a group.
    #[test]
    fn speeds_group_within_the_tolerance() {
        let speeds = [83.1, 42.0, 41.9, 125.2, 83.0, 125.0, 44.1];
        let (g, means) = group_speeds(&speeds, 0.05);
        // 41.9 opens the first group; 44.1 > 41.9 * 1.05 = 43.995 opens
        // the second.
        assert_eq!(g, [2, 0, 0, 3, 2, 3, 1]);
        assert_eq!(means.len(), 4);
        assert!((means[0] - 41.95).abs() < 1e-12);
        assert_eq!(means[1], 44.1);
        assert!((means[2] - 83.05).abs() < 1e-12);
        let (g, m) = group_speeds(&[], 0.05);
        assert!(g.is_empty() && m.is_empty());
    }

    #[test]
    fn a_record_at_rest_has_no_plateau_and_says_so() {
        let r = rec(vec![1.0; 3000], 0.0);
        let e = plateaus_found(&r, &SegmentSettings::default()).unwrap_err();
        assert!(
            e.to_string().contains("no constant-velocity plateau"),
            "{e}"
        );
    }
}
