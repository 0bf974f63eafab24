//! Ball-passage detection scored against the simulator's truth, one record
//! at a time ([`score`], [`score_simulation`]) and over many randomized
//! benches ([`summarize`], in `summary.rs`).
//!
//! # What a record is scored on
//!
//! Every true passage (the ball centre crossing the sensor,
//! [`Truth::optical_passage_times_s`], plus the one just before the record
//! and the one just after it, whose pulses may reach into the record) is
//! either *required* or *optional*:
//!
//! - optional when its centre lies within half a pulse FWHM of the record's
//!   start or end (inside or outside: the pulse is cut, and whether a
//!   detector counts it is a matter of convention), or, under
//!   coherent-light interference, when the fringe leaves the pulse less than
//!   half its height (`|sin θ| < 0.5` at the centre) or changes sign within
//!   half a FWHM of it (the pulse is not one pulse any more);
//! - required otherwise.
//!
//! A detection *matches* the nearest true passage within ±0.25 `τ_c` not
//! already matched; a detection that matches none is *spurious* (and
//! *inverted-spurious* when it points down). The record's count is
//! *exact* when no required passage is missed and nothing is spurious.
//! A record with fewer than two required passages cannot give a period
//! (the analysis then reports an error): it is *too short*, counted apart
//! and left out of the count rates.
//!
//! The timing error of a matched required passage is the detection's time
//! less the midpoint of the pulse's two half-maximum points (found from the
//! recorded stage position as below), in `τ_c`: the analysis times a pulse
//! there. For a symmetric pulse at constant speed that is the ball's centre;
//! the skewed pulse's midpoint lies FWHM/6 after it, a constant that every
//! `τ_c` cancels.
//!
//! The width error is `mean τ_p / truth − 1`, with `mean τ_p` the analysis'
//! [`PassageAnalysis::tau_p_s`] mean (the passages it uses for widths). The
//! headline truth ([`WidthTruth::HalfProminence`]) is what ballpass promises
//! `τ_p` to be: the width at half prominence of the pulses **as recorded**
//! (SciPy's `peak_widths(rel_height = 0.5)`), read by
//! [`recorded_half_prominence_width_s`] on the same bench simulated again
//! without noise, drift, AC coupling or interference (same seed, same
//! pulses). Where the tails of neighbouring pulses overlap, the light never
//! falls back to the dark level between them, and that width is narrower
//! than one pulse's FWHM (4.6 % for a Gaussian of 0.45 τ_c). It is applied
//! as a ratio: the FWHM truth below times (half-prominence width / FWHM) of
//! the noise-free record. Where the noise-free record holds fewer than three
//! pulses (`peak_widths` needs a pulse with a neighbour on each side), the
//! truth is the FWHM of one pulse ([`WidthTruth::OnePulseFwhm`]), and the
//! score says so.
//!
//! The second truth, kept beside (`width_error_fwhm`), is the FWHM of one
//! pulse: the mean, over the required passages, of the time each pulse
//! takes to pass between its two half-maximum points: the simulated shape's
//! half-maximum points in ball travel (`±FWHM/2`, or `−FWHM/3, +2 FWHM/3`
//! for the skewed shape, with FWHM = `width_ratio × d_avg`), turned into
//! times by the recorded stage position (the balls travel half as far as
//! the stage). At constant speed this is the truth's
//! [`Truth::optical_pulse_fwhm_s`]; a stage that oscillates at the
//! ball-pass frequency (a soft stage, `f_n` near `f_c`) passes the pulses
//! faster or slower than its mean speed, and the pulses in the record are
//! that much narrower or wider. The error against the stated
//! `optical_pulse_fwhm_s` is kept too (`width_error_stated`).
//!
//! A record whose analysis succeeded but reported no width (every pulse
//! cut by an end, or the widths withheld by the analysis) is *withheld*: it counts in the width rates' denominators as not within
//! 3 %, and the summary counts it on a line of its own.
//!
//! Conditions are scored as verdicts: each condition the analysis reports
//! is held against what the bench simulated ([`ConditionTruth`]).

use serde::{Deserialize, Serialize};

use crate::analysis::passage::{detect_passages, ConditionKind, PassageAnalysis, PassageSettings};
use crate::error::Result;
use crate::recording::Channel;
use crate::sim::{simulate, PulseShape, Simulation, Truth};
use crate::validate::bench::Bench;

mod summary;

pub use summary::{summarize, ConditionRow, GroupRow, Headline, PassageSummary, Spread};

/// Matching tolerance of a detection to a true passage, in `τ_c`.
pub const MATCH_TAU_C: f64 = 0.25;

/// Centres closer than this many FWHM to a record end are optional.
pub const EDGE_FWHM: f64 = 0.5;

/// Overlap width-shortfall estimate above which a record is counted as
/// flagged ([`crate::analysis::passage::PulseOverlap::width_shortfall`];
/// the threshold of the withdrawn `overlapping_pulses` caution).
pub const FLAGGED_SHORTFALL: f64 = 0.01;

/// Under interference, pulses scaled below this fraction are optional.
pub const FADED_FRACTION: f64 = 0.5;

/// Which truth a record's headline width error is against (module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WidthTruth {
    /// The width at half prominence of the pulses as recorded (SciPy's
    /// `peak_widths` on the noise-free record): what `τ_p` promises.
    HalfProminence,
    /// The FWHM of one pulse: the noise-free record held fewer than three
    /// pulses to read the half-prominence width on (and the truth of
    /// scores written before session 15).
    #[default]
    OnePulseFwhm,
}

/// What the bench simulated that the detector should say.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConditionTruth {
    /// The photodetector was AC coupled.
    pub ac_coupling: bool,
    /// AC-coupling time constant, s (when coupled).
    pub ac_time_constant_s: Option<f64>,
    /// Size of the AC coupling's effect: the dip each pulse leaves,
    /// `pulse area / T` in pulse heights (`1.064 FWHM / T` for a Gaussian);
    /// 0 when DC coupled.
    pub ac_dip: f64,
    /// The DC level wandered (baseline drift), peak in pulse heights (0: none).
    pub drift_fraction: f64,
    /// Period of the drift's slower component, in `τ_c` (when it drifts):
    /// the faster one is 0.37 of it.
    #[serde(default)]
    pub drift_period_tau_c: Option<f64>,
    /// Coherent-light interference (pulses fade and invert).
    pub interference: bool,
    /// Required passages with the fringe inverting them (`sin θ > 0.5`).
    pub inverted_required: usize,
}

/// Which conditions the analysis reported.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ConditionsReported {
    /// [`ConditionKind::AcCoupling`].
    pub ac_coupling: bool,
    /// [`ConditionKind::BaselineDrift`].
    pub baseline_drift: bool,
    /// [`ConditionKind::InvertedPulses`].
    pub inverted_pulses: bool,
    /// [`ConditionKind::MissedPassages`].
    pub missed_passages: bool,
    /// [`ConditionKind::PeriodMismatch`].
    pub period_mismatch: bool,
    /// [`ConditionKind::WidthsWithheld`].
    #[serde(default)]
    pub widths_withheld: bool,
    /// The analysis' median bend of the baseline under a pulse, in pulse
    /// heights ([`PassageAnalysis::baseline_bend`]).
    #[serde(default)]
    pub baseline_bend: Option<f64>,
    /// [`PassageAnalysis::width_scatter_se`].
    #[serde(default)]
    pub width_scatter_se: Option<f64>,
    /// The baseline drift's measure (its range over the median pulse) when reported.
    pub baseline_drift_measure: Option<f64>,
    /// The AC coupling's time constant found (and undone), s.
    pub ac_time_constant_s: Option<f64>,
}

impl ConditionsReported {
    fn of(a: &PassageAnalysis) -> Self {
        let has = |k| a.conditions.iter().any(|c| c.kind == k);
        Self {
            ac_coupling: has(ConditionKind::AcCoupling),
            baseline_drift: has(ConditionKind::BaselineDrift),
            inverted_pulses: has(ConditionKind::InvertedPulses),
            missed_passages: has(ConditionKind::MissedPassages),
            period_mismatch: has(ConditionKind::PeriodMismatch),
            widths_withheld: has(ConditionKind::WidthsWithheld),
            baseline_bend: a.baseline_bend,
            width_scatter_se: a.width_scatter_se,
            baseline_drift_measure: a
                .conditions
                .iter()
                .find(|c| c.kind == ConditionKind::BaselineDrift)
                .map(|c| c.measure),
            ac_time_constant_s: a.ac_time_constant_s,
        }
    }
}

/// The bench a record came from, as the summary bands it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RecordBench {
    /// Bench seed (0 for a record not drawn from a domain).
    pub bench_seed: u64,
    /// Simulation seed.
    pub seed: u64,
    /// Tracking velocity, mm/s.
    pub velocity_mm_s: f64,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// True ball-pass period, s.
    pub tau_c_s: f64,
    /// Pulse FWHM over `τ_c`.
    pub fwhm_tau_c: f64,
    /// Pulse FWHM in samples.
    pub fwhm_samples: f64,
    /// Pulse height over the per-sample noise std.
    pub snr: f64,
    /// Pulse shape.
    pub shape: PulseShape,
}

/// One record scored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassageScore {
    /// The bench.
    pub bench: RecordBench,
    /// What was simulated.
    pub truth: ConditionTruth,
    /// True passages with their centre inside the record.
    pub true_passages: usize,
    /// Of the true passages (inside or just outside), those that must be found.
    pub required: usize,
    /// Passages the analysis reported.
    pub detected: usize,
    /// Detections that matched a true passage.
    pub matched: usize,
    /// Required passages no detection matched.
    pub missed: usize,
    /// Detections that matched no true passage.
    pub spurious: usize,
    /// Of the spurious, those pointing down.
    pub spurious_inverted: usize,
    /// Matched detections whose polarity is not the pulse's (required ones).
    pub polarity_errors: usize,
    /// No required passage missed and nothing spurious.
    pub count_exact: bool,
    /// Fewer than two required passages (module docs).
    pub too_short: bool,
    /// Analysis' mean `τ_p`, s.
    pub width_s: Option<f64>,
    /// The analysis succeeded but reported no width (module docs).
    #[serde(default)]
    pub width_withheld: bool,
    /// The headline width truth (module docs), s: the width at half
    /// prominence of the pulses as recorded, or one pulse's FWHM when
    /// `width_truth` says so.
    pub true_width_s: f64,
    /// Which truth `true_width_s` is.
    #[serde(default)]
    pub width_truth: WidthTruth,
    /// True FWHM of one recorded pulse (module docs), s.
    #[serde(default)]
    pub fwhm_width_s: f64,
    /// The truth's stated FWHM, `width_ratio × τ_c`, s.
    pub stated_width_s: f64,
    /// `width_s / true_width_s − 1` (the headline).
    pub width_error: Option<f64>,
    /// `width_s / fwhm_width_s − 1`.
    #[serde(default)]
    pub width_error_fwhm: Option<f64>,
    /// `width_s / stated_width_s − 1`.
    pub width_error_stated: Option<f64>,
    /// Passages whose width entered the mean.
    pub widths_used: Option<usize>,
    /// The analysis' overlap estimate is above [`FLAGGED_SHORTFALL`]
    /// (where session 11 raised a caution; kept to score the estimate).
    #[serde(default)]
    pub width_lower_bound: bool,
    /// The analysis' possible width shortfall from the overlap (a fraction).
    #[serde(default)]
    pub width_shortfall: Option<f64>,
    /// Largest `|t_detected − t_true|` of the matched required passages, in `τ_c`.
    pub worst_timing_tau_c: Option<f64>,
    /// Mean `t_detected − t_true` of the matched required passages, in `τ_c`.
    pub mean_timing_tau_c: Option<f64>,
    /// `t_detected − t_true` of every matched required passage, in `τ_c`.
    #[serde(default)]
    pub timing_tau_c: Vec<f64>,
    /// Conditions reported.
    pub reported: ConditionsReported,
    /// The analysis' error, when it gave none.
    pub error: Option<String>,
}

/// Scores the passage detection on record `seed` of `bench`'s first good
/// bearing, with the default [`PassageSettings`] and the bench's geometry.
///
/// # Errors
/// The simulator's, for settings it rejects (the default domain draws none).
pub fn score(bench: &Bench, seed: u64) -> Result<PassageScore> {
    let sim = simulate(&bench.settings(&bench.bearing(0, false), seed))?;
    let settings = PassageSettings {
        geometry: Some(bench.geometry),
        ..PassageSettings::default()
    };
    let mut s = score_simulation(&sim, &settings);
    s.bench.bench_seed = bench.seed;
    Ok(s)
}

/// [`score`], and beside it the width at half prominence of the same
/// bench's pulses over their FWHM ([`half_prominence_ratio`]); `None` with
/// fewer than three clean pulses. Kept for the bench's `--recorded-width`
/// lines: the score's `true_width_s` is that width already.
///
/// # Errors
/// As [`score`].
pub fn score_and_recorded_width(bench: &Bench, seed: u64) -> Result<(PassageScore, Option<f64>)> {
    let s = score(bench, seed)?;
    let ratio = (s.width_truth == WidthTruth::HalfProminence && s.fwhm_width_s > 0.0)
        .then(|| s.true_width_s / s.fwhm_width_s);
    Ok((s, ratio))
}

/// The width at half prominence of `sim`'s pulses as recorded over their
/// FWHM: [`recorded_half_prominence_width_s`] on `sim`'s settings simulated
/// again without noise, drift, AC coupling or interference (same seed, same
/// pulses), over that record's mean one-pulse FWHM (its required passages).
/// Below 1 where the tails of neighbouring pulses overlap (the signal never
/// falls back to the dark level between them); `None` with fewer than three
/// clean pulses, or when the settings cannot be simulated again.
pub fn half_prominence_ratio(sim: &Simulation) -> Option<f64> {
    let mut settings = sim.truth.settings.clone();
    let o = &mut settings.optical;
    o.noise_v = 1e-5 * o.pulse_amplitude_v;
    o.ac_coupling = false;
    o.baseline_drift_v = 0.0;
    o.interference_drift = false;
    let clean = simulate(&settings).ok()?;
    let truths = true_passages(&clean.truth);
    let widths: Vec<f64> = truths
        .iter()
        .zip(&half_maximum_times(&clean, &truths))
        .filter(|(p, _)| p.required)
        .filter_map(|(_, h)| h.map(|(l, r)| r - l))
        .collect();
    (!widths.is_empty())
        .then(|| widths.iter().sum::<f64>() / widths.len() as f64)
        .and_then(|fwhm| Some(recorded_half_prominence_width_s(&clean)? / fwhm))
}

/// One true passage and how it is scored.
#[derive(Debug, Clone, Copy)]
struct TruePassage {
    time_s: f64,
    inside: bool,
    required: bool,
    /// +1 up, −1 inverted by the fringe, 0 faded or not one pulse.
    polarity: i8,
}

/// The true passages of `t`, with one extrapolated before the first and
/// one after the last (their pulses may reach into the record).
fn true_passages(t: &Truth) -> Vec<TruePassage> {
    let s = &t.settings;
    let end_s = (t.n_samples.saturating_sub(1)) as f64 / t.fs_hz;
    let fwhm = t.optical_pulse_fwhm_s;
    let half_speed = t.mean_velocity_mm_s / 2.0;
    let n_b = t.ball_spacings_mm.len();
    let mut times: Vec<f64> = Vec::with_capacity(t.optical_passage_times_s.len() + 2);
    if let (Some(&t0), Some(&b0)) = (
        t.optical_passage_times_s.first(),
        t.optical_passage_balls.first(),
    ) {
        let prev = (b0 + n_b - 1) % n_b;
        times.push(t0 - t.ball_spacings_mm[prev] / half_speed);
    }
    times.extend_from_slice(&t.optical_passage_times_s);
    if let (Some(&t1), Some(&b1)) = (
        t.optical_passage_times_s.last(),
        t.optical_passage_balls.last(),
    ) {
        times.push(t1 + t.ball_spacings_mm[b1] / half_speed);
    }
    // The fringe's factor on the pulses: −sin θ(t), θ(t) = θ_0 + 2π t / P.
    let fringe = |time: f64| -> f64 {
        match t.interference_phase_rad {
            Some(th0) => {
                -(th0 + std::f64::consts::TAU * time / s.optical.interference_period_s).sin()
            }
            None => 1.0,
        }
    };
    times
        .into_iter()
        .map(|time| {
            let inside = (0.0..=end_s).contains(&time);
            let edge = time.min(end_s - time) < EDGE_FWHM * fwhm;
            let m = fringe(time);
            let steady = [-0.5, -0.25, 0.25, 0.5]
                .iter()
                .all(|f| fringe(time + f * fwhm) * m > 0.0);
            let polarity = if m.abs() >= FADED_FRACTION && steady {
                if m > 0.0 {
                    1
                } else {
                    -1
                }
            } else {
                0
            };
            TruePassage {
                time_s: time,
                inside,
                required: inside && !edge && polarity != 0,
                polarity,
            }
        })
        .collect()
}

/// Scores an analysis of `sim` run with `settings`.
pub fn score_simulation(sim: &Simulation, settings: &PassageSettings) -> PassageScore {
    score_with(sim, |r| detect_passages(r, settings))
}

/// Scores the passages `detect` finds in `sim`'s record (another detection
/// method, such as the windowed one of streamed records).
pub fn score_with(
    sim: &Simulation,
    detect: impl FnOnce(&crate::recording::Recording) -> Result<crate::analysis::PassageAnalysis>,
) -> PassageScore {
    let t = &sim.truth;
    let o = &t.settings.optical;
    let truths = true_passages(t);
    let tau_c = t.tau_c_s;
    let fwhm = t.optical_pulse_fwhm_s;
    let area = shape_area_per_fwhm(o.pulse_shape) * fwhm;
    let condition_truth = ConditionTruth {
        ac_coupling: o.ac_coupling,
        ac_time_constant_s: o.ac_coupling.then_some(o.ac_time_constant_s),
        ac_dip: if o.ac_coupling {
            area / o.ac_time_constant_s
        } else {
            0.0
        },
        drift_fraction: o.baseline_drift_v / o.pulse_amplitude_v,
        drift_period_tau_c: (o.baseline_drift_v > 0.0)
            .then_some(o.baseline_drift_period_s / t.tau_c_s),
        interference: o.interference_drift,
        inverted_required: truths
            .iter()
            .filter(|p| p.required && p.polarity < 0)
            .count(),
    };
    let bench = RecordBench {
        bench_seed: 0,
        seed: t.settings.seed,
        velocity_mm_s: t.velocity_mm_s,
        fs_hz: t.fs_hz,
        duration_s: t.settings.duration_s,
        tau_c_s: tau_c,
        fwhm_tau_c: t.optical_pulse_fwhm_tau_c,
        fwhm_samples: fwhm * t.fs_hz,
        snr: if o.noise_v > 0.0 {
            o.pulse_amplitude_v / o.noise_v
        } else {
            f64::INFINITY
        },
        shape: o.pulse_shape,
    };
    let required = truths.iter().filter(|p| p.required).count();
    let half_max = half_maximum_times(sim, &truths);
    let widths: Vec<f64> = truths
        .iter()
        .zip(&half_max)
        .filter(|(p, _)| p.required)
        .filter_map(|(_, h)| h.map(|(l, r)| r - l))
        .collect();
    let fwhm_width_s = if widths.is_empty() {
        fwhm
    } else {
        widths.iter().sum::<f64>() / widths.len() as f64
    };
    let (true_width_s, width_truth) = match half_prominence_ratio(sim) {
        Some(r) => (fwhm_width_s * r, WidthTruth::HalfProminence),
        None => (fwhm_width_s, WidthTruth::OnePulseFwhm),
    };
    let true_inside = truths.iter().filter(|p| p.inside).count();
    let a = match detect(&sim.recording) {
        Ok(a) => a,
        Err(e) => {
            return PassageScore {
                bench,
                truth: condition_truth,
                true_passages: true_inside,
                required,
                detected: 0,
                matched: 0,
                missed: required,
                spurious: 0,
                spurious_inverted: 0,
                polarity_errors: 0,
                count_exact: required == 0,
                too_short: required < 2,
                width_s: None,
                width_withheld: false,
                true_width_s,
                width_truth,
                fwhm_width_s,
                stated_width_s: fwhm,
                width_error: None,
                width_error_fwhm: None,
                width_error_stated: None,
                widths_used: None,
                width_lower_bound: false,
                width_shortfall: None,
                worst_timing_tau_c: None,
                mean_timing_tau_c: None,
                timing_tau_c: Vec::new(),
                reported: ConditionsReported::default(),
                error: Some(e.to_string()),
            }
        }
    };
    let start = sim.recording.meta.start_time_s;
    let tol = MATCH_TAU_C * tau_c;
    let mut taken = vec![false; truths.len()];
    let (mut spurious, mut spurious_inverted, mut polarity_errors) = (0, 0, 0);
    let mut timing = Vec::new();
    for p in &a.passages {
        let time = p.time_s - start;
        let nearest = truths
            .iter()
            .enumerate()
            .filter(|(k, _)| !taken[*k])
            .map(|(k, q)| (k, (q.time_s - time).abs()))
            .min_by(|x, y| x.1.total_cmp(&y.1));
        match nearest {
            Some((k, d)) if d <= tol => {
                taken[k] = true;
                let q = truths[k];
                if q.required {
                    // The analysis times a pulse at the midpoint of its
                    // half-maximum points; so does the truth here.
                    let centre = half_max[k].map_or(q.time_s, |(l, r)| 0.5 * (l + r));
                    timing.push((time - centre) / tau_c);
                    if q.polarity != p.polarity {
                        polarity_errors += 1;
                    }
                }
            }
            _ => {
                spurious += 1;
                if p.polarity < 0 {
                    spurious_inverted += 1;
                }
            }
        }
    }
    let missed = truths
        .iter()
        .zip(&taken)
        .filter(|(q, k)| q.required && !**k)
        .count();
    let matched = taken.iter().filter(|k| **k).count();
    let width = Some(a.tau_p_s.mean).filter(|w| w.is_finite() && *w > 0.0);
    PassageScore {
        bench,
        truth: condition_truth,
        true_passages: true_inside,
        required,
        detected: a.passages.len(),
        matched,
        missed,
        spurious,
        spurious_inverted,
        polarity_errors,
        count_exact: missed == 0 && spurious == 0,
        too_short: required < 2,
        width_s: width,
        width_withheld: width.is_none(),
        true_width_s,
        width_truth,
        fwhm_width_s,
        stated_width_s: fwhm,
        width_error: width.map(|w| w / true_width_s - 1.0),
        width_error_fwhm: width.map(|w| w / fwhm_width_s - 1.0),
        width_error_stated: width.map(|w| w / fwhm - 1.0),
        widths_used: Some(a.tau_p_s.n),
        width_lower_bound: a
            .overlap
            .is_some_and(|o| o.width_shortfall > FLAGGED_SHORTFALL),
        width_shortfall: a.overlap.map(|o| o.width_shortfall),
        worst_timing_tau_c: timing.iter().map(|e| e.abs()).reduce(f64::max),
        mean_timing_tau_c: (!timing.is_empty())
            .then(|| timing.iter().sum::<f64>() / timing.len() as f64),
        timing_tau_c: timing,
        reported: ConditionsReported::of(&a),
        error: None,
    }
}

/// For each true passage inside the record, the times the pulse passes its
/// two half-maximum points, from the recorded stage position (module docs);
/// all `None` without a position channel.
fn half_maximum_times(sim: &Simulation, truths: &[TruePassage]) -> Vec<Option<(f64, f64)>> {
    let t = &sim.truth;
    let Some(x) = sim.recording.channel(Channel::Position) else {
        return vec![None; truths.len()];
    };
    let fs = t.fs_hz;
    let o = &t.settings.optical;
    let fwhm_mm = o.width_ratio * t.d_avg_mm;
    let (hl, hr) = match o.pulse_shape {
        PulseShape::Skewed => (fwhm_mm / 3.0, 2.0 * fwhm_mm / 3.0),
        _ => (fwhm_mm / 2.0, fwhm_mm / 2.0),
    };
    let pos = |time: f64| -> Option<f64> {
        let i = time * fs;
        if i < 0.0 || i > (x.len() - 1) as f64 {
            return None;
        }
        let j = (i.floor() as usize).min(x.len() - 2);
        let f = i - j as f64;
        Some(x[j] + f * (x[j + 1] - x[j]))
    };
    // First time from `time` stepping by `dir` samples where the position
    // passes `target`, linearly interpolated.
    let crossing = |time: f64, target: f64, dir: f64| -> Option<f64> {
        let mut a = time;
        let mut pa = pos(a)?;
        for _ in 0..10 * x.len() {
            let b = a + dir / fs;
            let pb = pos(b)?;
            if (pa - target) * (pb - target) <= 0.0 && pa != pb {
                return Some(a + (b - a) * (target - pa) / (pb - pa));
            }
            a = b;
            pa = pb;
        }
        None
    };
    truths
        .iter()
        .map(|p| {
            if !p.inside {
                return None;
            }
            let xk = pos(p.time_s)?;
            let l = crossing(p.time_s, xk - 2.0 * hl, -1.0)?;
            let r = crossing(p.time_s, xk + 2.0 * hr, 1.0)?;
            Some((l, r))
        })
        .collect()
}

/// Mean width at half prominence of the recorded optical pulses as SciPy's
/// `find_peaks` / `peak_widths(rel_height = 0.5)` read it on the record
/// itself, s: peaks at least 0.7 `τ_c` apart with a prominence of at least
/// a quarter of the largest, the first and last peak left out (a pulse cut
/// by the record's end has no base on that side). Meaningful on a noise-free
/// record (`validate_passages -- --clean`): there it is the width at half
/// prominence of the *sum* of the pulses, which is narrower than one pulse's
/// FWHM (the truth) where the tails of neighbouring pulses overlap, because
/// the signal between two pulses never falls back to the dark level.
/// `None` with fewer than three peaks or no optical channel.
pub fn recorded_half_prominence_width_s(sim: &Simulation) -> Option<f64> {
    use ballpass_dsp::{find_peaks, peak_widths, Bound, FindPeaksSettings, PeakWidthsSettings};
    let y = sim.recording.channel(Channel::Optical)?;
    let fs = sim.truth.fs_hz;
    let distance = (0.7 * sim.truth.tau_c_s * fs).max(1.0);
    let all = find_peaks(
        y,
        &FindPeaksSettings {
            distance: Some(distance),
            prominence: Some(Bound::at_least(0.0)),
            ..Default::default()
        },
    )
    .ok()?;
    let proms = all.properties.prominences?;
    let top = proms.iter().copied().fold(0.0, f64::max);
    let peaks: Vec<usize> = all
        .indices
        .iter()
        .zip(&proms)
        .filter(|(_, p)| **p >= 0.25 * top)
        .map(|(i, _)| *i)
        .collect();
    if peaks.len() < 3 {
        return None;
    }
    let inner = &peaks[1..peaks.len() - 1];
    let w = peak_widths(
        y,
        inner,
        &PeakWidthsSettings {
            rel_height: 0.5,
            ..Default::default()
        },
    )
    .ok()?;
    Some(w.widths.iter().sum::<f64>() / w.widths.len() as f64 / fs)
}

/// Area of a unit-height pulse of the shape over its FWHM.
fn shape_area_per_fwhm(shape: PulseShape) -> f64 {
    match shape {
        // σ √(2π) with σ = FWHM / (2 √(2 ln 2)).
        PulseShape::Gaussian => 1.064_467_019_431_226_4,
        // (σ_l + σ_r) √(π/2) with σ_l + σ_r = FWHM / √(2 ln 2).
        PulseShape::Skewed => 1.064_467_019_431_226_4,
        // ∫ (1 + cos(π u / W)) / 2 over |u| < W is W.
        PulseShape::RaisedCosine => 1.0,
        PulseShape::Rectangular => 1.0,
        // A continuous ripple has no pulse; its mean over a period is 1/2.
        PulseShape::Ripple => f64::NAN,
    }
}
