//! The friction against the travel since the last optical passage: the
//! table the controller's key reads, and the disturbance that would act
//! at the commanded (constant) velocity.
//!
//! # Why travel, not time
//!
//! The friction of a bearing is a function of where the balls are, that is
//! of position; the stage's own motion only decides *when* it is met. The
//! synchronous average ([`crate::analysis::sync`]) resamples each period
//! uniformly in time: where the stage slows down at a friction peak, the
//! peak lasts longer in time and fills more of the period, and the average
//! over-weights it and moves it. At a nearly constant velocity the two are
//! the same; near stall (velocity-error std a large part of the velocity)
//! they are not. The controller keys the table on the travel since the last
//! passage ([`crate::sim::feedforward`]), so the table is averaged in that
//! key:
//!
//! ```text
//! period    passages k → k+1 (encoder positions x_k, x_k+1), travel D_k,
//!           kept when 0.5 D_med ≤ D_k ≤ 1.5 D_med
//! bin j     travel L_j = j·P/B after x_k (P = 2·d_avg, the controller's
//!           pitch), sampled where L_j < D_k: the friction at the first
//!           time the encoder reaches x_k + L_j (linear interpolation)
//! table     u[j] = mean over the periods that reach bin j, minus the mean
//!           over the bins
//! ```
//!
//! The friction is the analysis' (load-cell discharge undone as the
//! analysis does, its low-pass, zero phase).

use crate::analysis::Analysis;
use crate::recording::{Channel, Recording};

/// One record's inputs to the travel-keyed table, the rail grid and the
/// replay ([`super::replay`]).
#[derive(Debug, Clone)]
pub(crate) struct RecordKeys {
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Friction, N (discharge undone, low-passed, linear trend removed;
    /// its level is set by [`super::replay::fit_levels`]).
    pub friction_n: Vec<f64>,
    /// Std of the record's low-passed velocity error, µm/s (what the
    /// replay without a table is held to when its level is fitted).
    pub velocity_error_std_um_s: f64,
    /// Encoder position, mm.
    pub position_mm: Vec<f64>,
    /// Optical passages, fractional sample index, increasing.
    pub passages: Vec<f64>,
    /// Encoder position at each passage, mm.
    pub passage_mm: Vec<f64>,
}

impl RecordKeys {
    /// Direction of travel (+1 forward, −1 backward).
    pub fn direction(&self) -> f64 {
        match (self.position_mm.first(), self.position_mm.last()) {
            (Some(a), Some(b)) if b < a => -1.0,
            _ => 1.0,
        }
    }
}

/// Linear interpolation of `x` at fractional index `u` (clamped).
pub(crate) fn at_index(x: &[f64], u: f64) -> f64 {
    let u = u.clamp(0.0, (x.len() - 1) as f64);
    let i = (u.floor() as usize).min(x.len().saturating_sub(2));
    x[i] + (u - i as f64) * (x[i + 1] - x[i])
}

/// Each record's friction, position and optical passages, or why not.
///
/// With `refined` (below [`super::SEVERE_STALL_FRACTION`]), the friction's
/// linear trend is removed and each passage is put at its optical pulse's
/// centre in travel; without, the friction is as restored and the passage
/// at the encoder position of its time (measured better above it,
/// docs/methods.md §14).
pub(crate) fn record_keys(
    recs: &[Recording],
    a: &Analysis,
    refined: bool,
) -> Result<Vec<RecordKeys>, String> {
    let settings = crate::analysis::PassageSettings {
        velocity_mm_s: Some(a.prediction.velocity_mm_s),
        fit_pulses: 0,
        ..Default::default()
    };
    let mut out = Vec::with_capacity(recs.len());
    for r in recs {
        let name = r.source_name();
        let Some(x) = r.channel(Channel::Position) else {
            return Err(format!("no encoder position in {name}"));
        };
        if r.channel(Channel::Friction).is_none() {
            return Err(format!("no friction in {name}"));
        }
        if x.len() < 2 {
            return Err(format!("{name}: fewer than 2 samples"));
        }
        let fs = r.fs_hz();
        let friction_n = friction_of(r, a, a.settings.load_cell, refined)?;
        let lowpass = crate::analysis::preprocess::lowpass_filter(&a.settings, fs)
            .map_err(|e| e.to_string())?;
        // The velocity error as the analysis takes it (numpy.gradient of the
        // encoder, low-passed), along the motion.
        let speed = ballpass_dsp::gradient(x, ballpass_dsp::Spacing::Uniform(1.0 / fs))
            .map_err(|e| format!("{name}: velocity from the encoder: {e}"))?;
        let speed = match &lowpass {
            Some(lp) if speed.len() > 64 => lp
                .apply(&speed)
                .map_err(|e| format!("{name}: low-pass of the velocity: {e}"))?,
            _ => speed,
        };
        let velocity_error_std_um_s =
            1e3 * crate::stats::MeanStd::of(&speed).map_or(0.0, |m| m.std);
        let p = crate::analysis::detect_passages(r, &settings)
            .map_err(|_| format!("passages not found in {name}"))?;
        let passages: Vec<f64> = p
            .passages
            .iter()
            .map(|q| ((q.time_s - r.meta.start_time_s) * fs).clamp(0.0, (x.len() - 1) as f64))
            .collect();
        let at_time: Vec<f64> = passages.iter().map(|&u| at_index(x, u)).collect();
        // The passage's position is the pulse's centre in travel: its time
        // centre, read on the encoder, moves with the stage's speed within
        // the pulse (near stall by tenths of a millimetre).
        let dir = match (x.first(), x.last()) {
            (Some(a), Some(b)) if b < a => -1.0,
            _ => 1.0,
        };
        let passage_mm = match r.channel(Channel::Optical).filter(|_| refined) {
            Some(o) => pulse_centres_in_travel(
                x,
                o,
                &passages,
                &at_time,
                PULSE_WINDOW * 2.0 * a.prediction.d_avg_mm,
                dir,
            ),
            None => at_time,
        };
        let passages = first_reach(x, &passages, &passage_mm, dir);
        out.push(RecordKeys {
            fs_hz: fs,
            friction_n,
            velocity_error_std_um_s,
            position_mm: x.to_vec(),
            passages,
            passage_mm,
        });
    }
    Ok(out)
}

/// The friction of record `r` as the replay takes it: the load cell's
/// discharge undone as `correction` says, low-passed as the analysis `a`
/// does and, when `refined`, its linear trend removed (its level kept).
pub(crate) fn friction_of(
    r: &Recording,
    a: &Analysis,
    correction: crate::analysis::load_cell::LoadCellCorrection,
    refined: bool,
) -> Result<Vec<f64>, String> {
    let name = r.source_name();
    let f = r
        .channel(Channel::Friction)
        .ok_or_else(|| format!("no friction in {name}"))?;
    let fs = r.fs_hz();
    let (restored, _) =
        crate::analysis::load_cell::restore_friction(f, fs, a.prediction.tau_c_s, correction)
            .map_err(|e| format!("{name}: {e}"))?;
    let lowpass =
        crate::analysis::preprocess::lowpass_filter(&a.settings, fs).map_err(|e| e.to_string())?;
    let friction = match &lowpass {
        Some(lp) => lp
            .apply(&restored)
            .map_err(|e| format!("{name}: low-pass of the friction: {e}"))?,
        None => restored.into_owned(),
    };
    if !refined {
        return Ok(friction);
    }
    // A periodic friction has no trend; a trend is the discharge undone
    // with the wrong time constant or start (its level is fitted later).
    let level = friction.iter().sum::<f64>() / friction.len() as f64;
    Ok(
        ballpass_dsp::detrend(&friction, ballpass_dsp::DetrendType::Linear)
            .map_err(|e| format!("{name}: detrend of the friction: {e}"))?
            .iter()
            .map(|f| f + level)
            .collect(),
    )
}

/// Half-width of the window around a passage in which its pulse's centre
/// in travel is taken, ball pitches (the pulse's FWHM is about 0.155).
const PULSE_WINDOW: f64 = 0.15;

/// The fractional sample index at which the encoder first reaches each
/// position `p` (searched from the index `u` the position came from, back
/// and forth), travel along `dir`.
fn first_reach(x: &[f64], passages: &[f64], passage_mm: &[f64], dir: f64) -> Vec<f64> {
    let n = x.len();
    passages
        .iter()
        .zip(passage_mm)
        .map(|(&u, &p)| {
            let mut i = (u.floor() as usize).min(n.saturating_sub(2));
            while i > 0 && dir * (x[i] - p) >= 0.0 {
                i -= 1;
            }
            while i + 2 < n && dir * (x[i + 1] - p) < 0.0 {
                i += 1;
            }
            let (a, b) = (dir * (x[i] - p), dir * (x[i + 1] - p));
            if a < 0.0 && b >= 0.0 && b > a {
                i as f64 + (-a / (b - a))
            } else {
                u
            }
        })
        .collect()
}

/// The centre of each optical pulse in position: around each passage
/// position `p_k` (travel along the motion), the part of the optical
/// signal above half its height within `±half` of travel, integrated over
/// travel (not time: where the stage stops, a sample adds no travel), its
/// centroid. Returns `p_k` unchanged where the window holds no pulse.
/// `dir` is the direction of travel.
pub(crate) fn pulse_centres_in_travel(
    position_mm: &[f64],
    optical: &[f64],
    passages: &[f64],
    passage_mm: &[f64],
    half: f64,
    dir: f64,
) -> Vec<f64> {
    let n = position_mm.len().min(optical.len());
    passages
        .iter()
        .zip(passage_mm)
        .map(|(&u, &p)| {
            let i0 = (u.round() as usize).min(n.saturating_sub(1));
            // Samples within ±half of travel around the passage.
            let mut lo = i0;
            while lo > 0 && dir * (p - position_mm[lo - 1]) <= half {
                lo -= 1;
            }
            let mut hi = i0;
            while hi + 1 < n && dir * (position_mm[hi + 1] - p) <= half {
                hi += 1;
            }
            if hi <= lo + 2 {
                return p;
            }
            let w = &optical[lo..=hi];
            let (mn, mx) = w
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            let mut sorted = w.to_vec();
            sorted.sort_by(f64::total_cmp);
            let median = sorted[sorted.len() / 2];
            // The pulse stands out from the window's median: up or down.
            let up = optical[i0] >= median;
            let mid = 0.5 * (mn + mx);
            let (mut sw, mut swx) = (0.0, 0.0);
            for i in lo..hi {
                let dx = dir * (position_mm[i + 1] - position_mm[i]);
                if dx <= 0.0 {
                    continue;
                }
                let a = 0.5 * (optical[i] + optical[i + 1]);
                let h = if up { a - mid } else { mid - a };
                if h > 0.0 {
                    let xm = 0.5 * (position_mm[i] + position_mm[i + 1]);
                    sw += h * dx;
                    swx += h * dx * xm;
                }
            }
            if sw > 0.0 {
                swx / sw
            } else {
                p
            }
        })
        .collect()
}

/// Sum and count per bin of `y` against the travel since each passage
/// (module docs), over every record's kept periods.
pub(crate) fn travel_bins(
    keys: &[RecordKeys],
    y: impl Fn(&RecordKeys) -> &[f64],
    pitch_mm: f64,
    bins: usize,
) -> (Vec<f64>, Vec<usize>) {
    let mut sum = vec![0.0; bins];
    let mut count = vec![0usize; bins];
    let travels: Vec<f64> = keys
        .iter()
        .flat_map(|k| {
            let dir = k.direction();
            k.passage_mm.windows(2).map(move |w| dir * (w[1] - w[0]))
        })
        .collect();
    let Some(med) = crate::stats::median(&travels) else {
        return (sum, count);
    };
    let step = pitch_mm / bins as f64;
    for k in keys {
        let (x, v, dir) = (&k.position_mm, y(k), k.direction());
        for (w, xw) in k.passages.windows(2).zip(k.passage_mm.windows(2)) {
            let d = dir * (xw[1] - xw[0]);
            if !(d >= 0.5 * med && d <= 1.5 * med) {
                continue;
            }
            // First crossing of each level x_k + L_j along the samples.
            let mut j = 0;
            let (mut u, end) = (w[0], w[1]);
            let mut prev = 0.0;
            while j < bins && u < end {
                let level = j as f64 * step;
                if level >= d {
                    break;
                }
                let next = (u.floor() + 1.0).min(end);
                let t = dir * (at_index(x, next) - xw[0]);
                if t >= level {
                    let frac = if t > prev {
                        ((level - prev) / (t - prev)).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    sum[j] += at_index(v, u + frac * (next - u));
                    count[j] += 1;
                    j += 1;
                } else {
                    prev = t;
                    u = next;
                }
            }
        }
    }
    (sum, count)
}

/// The mean per bin of [`travel_bins`], minus its mean; bins no period
/// reached take the linear interpolation of their neighbours (periodic).
/// `None` when no bin has a value.
pub(crate) fn travel_table(sum: &[f64], count: &[usize]) -> Option<Vec<f64>> {
    let b = sum.len();
    let have: Vec<usize> = (0..b).filter(|&j| count[j] > 0).collect();
    if have.is_empty() {
        return None;
    }
    let mean_at = |j: usize| sum[j] / count[j] as f64;
    let mut m = vec![0.0; b];
    for j in 0..b {
        if count[j] > 0 {
            m[j] = mean_at(j);
            continue;
        }
        // Nearest bins with a value before and after (wrapping).
        let after = have.iter().find(|&&h| h > j).copied();
        let before = have.iter().rev().find(|&&h| h < j).copied();
        let (lo, hi) = (
            before.unwrap_or(*have.last().unwrap_or(&0)),
            after.unwrap_or(have[0]),
        );
        let span = (hi + b - lo) % b;
        let pos = (j + b - lo) % b;
        m[j] = if span == 0 {
            mean_at(lo)
        } else {
            mean_at(lo) + (mean_at(hi) - mean_at(lo)) * pos as f64 / span as f64
        };
    }
    let mean = m.iter().sum::<f64>() / b as f64;
    Some(m.iter().map(|v| v - mean).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A friction that is a known function of position, met by a stage
    /// whose speed varies (slow where the friction is high): keyed on travel
    /// the table is that function; keyed on time it is not.
    #[test]
    fn the_travel_table_is_the_friction_against_position_whatever_the_speed() {
        let fs = 1000.0;
        let pitch = 8.0;
        let shape = |x: f64| (std::f64::consts::TAU * x / pitch).cos();
        // Speed 1 − 0.6·shape: the stage crawls through the peaks.
        let (mut x, mut xs) = (0.0, Vec::new());
        while x < 40.0 * pitch {
            xs.push(x);
            x += (4.0 - 2.4 * shape(x)) / fs;
        }
        let f: Vec<f64> = xs.iter().map(|&x| 3.0 + shape(x)).collect();
        // Passages where the position crosses k·pitch.
        let mut passages = Vec::new();
        for (i, w) in xs.windows(2).enumerate() {
            let k = (w[1] / pitch).floor();
            if (w[0] / pitch).floor() < k {
                passages.push(i as f64 + (k * pitch - w[0]) / (w[1] - w[0]));
            }
        }
        let passage_mm = passages.iter().map(|&u| at_index(&xs, u)).collect();
        let keys = vec![RecordKeys {
            fs_hz: fs,
            friction_n: f,
            velocity_error_std_um_s: 0.0,
            position_mm: xs,
            passages,
            passage_mm,
        }];
        let (s, c) = travel_bins(&keys, |k| &k.friction_n, pitch, 32);
        let t = travel_table(&s, &c).unwrap();
        // Linear interpolation of a unit cosine sampled every 1/4 mm or
        // finer (speed ≤ 6.4 mm/s at 1 kHz: ≤ 0.0064 mm): error ≤ 1e-3.
        for (j, v) in t.iter().enumerate() {
            let want = shape(j as f64 * pitch / 32.0);
            assert!((v - want).abs() < 1e-3, "bin {j}: {v} vs {want}");
        }
    }

    /// The stage stops for a second just before the pulse's centre: the
    /// pulse's centre in time, read on the encoder, moves towards the stop;
    /// its centre in travel does not.
    #[test]
    fn the_pulse_centre_in_travel_ignores_where_the_stage_dwells() {
        let fs = 1000.0;
        let (mut x, mut xs) = (0.0, Vec::new());
        let mut stopped = 0;
        while x < 10.0 {
            xs.push(x);
            if x >= 4.7 && stopped < 1000 {
                stopped += 1;
            } else {
                x += 1.0 / fs;
            }
        }
        // Gaussian pulse in position at 5 mm, σ 0.5 mm, on a 1 V level.
        let o: Vec<f64> = xs
            .iter()
            .map(|&x| 1.0 + 0.5 * (-0.5 * ((x - 5.0) / 0.5f64).powi(2)).exp())
            .collect();
        // Its centre in time (weights above the level).
        let (sw, swt) = o.iter().enumerate().fold((0.0, 0.0), |(a, b), (i, &v)| {
            (a + (v - 1.0), b + (v - 1.0) * i as f64)
        });
        let u = swt / sw;
        let p = at_index(&xs, u);
        assert!((p - 5.0).abs() > 0.1, "time centre at {p}");
        let c = pulse_centres_in_travel(&xs, &o, &[u], &[p], 1.5, 1.0);
        // Trapezoid integration at 1 µm steps over a symmetric window
        // clipped at half height: within 2 µm.
        assert!((c[0] - 5.0).abs() < 2e-3, "travel centre at {}", c[0]);
        let back = first_reach(&xs, &[u], &c, 1.0);
        assert!((at_index(&xs, back[0]) - c[0]).abs() < 1e-9);
    }

    #[test]
    fn empty_bins_are_filled_between_their_neighbours() {
        let sum = [1.0, 0.0, 3.0, 0.0];
        let count = [1, 0, 1, 0];
        let t = travel_table(&sum, &count).unwrap();
        // Means 1, 2, 3, 2 (the last wraps from 3 to 1): mean 2.
        assert_eq!(t, vec![-1.0, 0.0, 1.0, 0.0]);
        assert!(travel_table(&[0.0; 3], &[0; 3]).is_none());
    }
}
