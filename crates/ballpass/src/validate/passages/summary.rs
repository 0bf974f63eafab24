//! Many records' scores, summarised: the headline rates (detection,
//! false passages, timing and width errors) with their exact intervals,
//! the same per group of benches, and the condition verdicts' rates.

use serde::{Deserialize, Serialize};

use super::PassageScore;
use crate::sim::PulseShape;
use crate::validate::score::Rate;

/// The spread of a quantity over many records or passages: its median,
/// 90th percentile and largest value, the two percentiles with their
/// distribution-free 95 % intervals (order statistics whose ranks are the
/// binomial's 2.5 % and 97.5 % points, the quantile's counterpart of the
/// Clopper–Pearson interval).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Values.
    pub n: usize,
    /// Median.
    pub p50: f64,
    /// 95 % interval of the median.
    pub p50_ci95: [f64; 2],
    /// 90th percentile.
    pub p90: f64,
    /// 95 % interval of the 90th percentile.
    pub p90_ci95: [f64; 2],
    /// Largest value.
    pub max: f64,
}

impl Spread {
    /// The spread of `v` (NaN throughout when empty).
    pub fn of(v: &[f64]) -> Self {
        let mut v: Vec<f64> = v.iter().copied().filter(|x| !x.is_nan()).collect();
        v.sort_by(f64::total_cmp);
        let (p50, p50_ci95) = quantile_with_interval(&v, 0.5);
        let (p90, p90_ci95) = quantile_with_interval(&v, 0.9);
        Self {
            n: v.len(),
            p50,
            p50_ci95,
            p90,
            p90_ci95,
            max: v.last().copied().unwrap_or(f64::NAN),
        }
    }
}

/// The `q` quantile of sorted `v` (linear between order statistics) and its
/// 95 % interval `[v_(l), v_(u)]`: `l` the largest rank with
/// `P(Bin(n, q) < l) ≤ 2.5 %`, `u` the smallest with `P(Bin(n, q) < u) ≥
/// 97.5 %` (1-based ranks, clamped to the sample: the ends are open when
/// `n` is too small for a 95 % interval).
fn quantile_with_interval(v: &[f64], q: f64) -> (f64, [f64; 2]) {
    let n = v.len();
    if n == 0 {
        return (f64::NAN, [f64::NAN; 2]);
    }
    let pos = q * (n - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(n - 1);
    let point = v[lo] + (pos - lo as f64) * (v[hi] - v[lo]);
    // P(Bin(n, q) ≤ j) = I_{1−q}(n − j, j + 1) for j < n.
    let cdf = |j: usize| -> f64 {
        if j >= n {
            1.0
        } else {
            crate::stats::reg_inc_beta((n - j) as f64, (j + 1) as f64, 1.0 - q)
        }
    };
    // Rank r (1-based) is below the quantile with probability P(Bin < r) = cdf(r − 1).
    let l = (1..=n).rev().find(|&r| cdf(r - 1) <= 0.025).unwrap_or(1);
    let u = (1..=n).find(|&r| cdf(r - 1) >= 0.975).unwrap_or(n);
    (point, [v[l - 1], v[u - 1]])
}

/// The figures a lab reads first, over every record that is not too short
/// and has no coherent-light interference (under interference a pulse can
/// fade away or invert, which the condition verdicts score).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Headline {
    /// Records scored (not too short, no interference).
    pub records: usize,
    /// Required passages matched by a detection, over all required.
    pub detection: Rate,
    /// Detections that match no true passage, over all detections.
    pub false_passages: Rate,
    /// Records with at least one false passage.
    pub records_with_false_passages: Rate,
    /// Records whose count is exact.
    pub count_exact: Rate,
    /// Records whose analysis failed (no passages reported).
    pub failed: Rate,
    /// `|t_detected − t_true|` of every matched required passage, `τ_c`.
    pub timing_tau_c: Spread,
    /// Matched required passages timed within 0.02 `τ_c`.
    pub timing_within_0_02: Rate,
    /// `|mean τ_p / truth − 1|` per record, against the headline truth
    /// (the width at half prominence of the pulses as recorded, module docs
    /// of [`super`]).
    pub width_error: Spread,
    /// Records with `|width error| ≤ 3 %` (a record without a width is not).
    pub width_within_3pct: Rate,
    /// The same at SNR ≥ 10 (the acceptance's condition).
    pub width_error_snr10: Spread,
    /// Records at SNR ≥ 10 with `|width error| ≤ 3 %` (a withheld width is not).
    pub width_within_3pct_snr10: Rate,
    /// The same against the second truth, one pulse's FWHM.
    pub width_within_3pct_fwhm_snr10: Rate,
    /// Records at SNR ≥ 10 whose analysis succeeded without a width
    /// (withheld, or every pulse cut by an end): the coverage line.
    pub width_withheld_snr10: Rate,
    /// Records at SNR ≥ 10 with a width, within 3 % (of those with one).
    pub width_within_3pct_measured_snr10: Rate,
    /// Records at SNR ≥ 10 whose headline truth is one pulse's FWHM (the
    /// noise-free record held fewer than three pulses).
    pub width_truth_fwhm_snr10: Rate,
    /// Signed mean width error (the bias), at SNR ≥ 10.
    pub width_bias_snr10: f64,
    /// Records at SNR ≥ 10 whose widths the analysis reported as lower
    /// bounds (overlapping pulses).
    pub width_lower_bound_snr10: Rate,
    /// Of those, the ones whose bound held: the width not above the truth
    /// by more than 3 %, nor below it by more than the stated shortfall
    /// and 3 %.
    pub width_bound_held_snr10: Rate,
    /// Records at SNR ≥ 10 whose width is within 3 %, or reported as a
    /// lower bound that held.
    pub width_within_3pct_or_bound_snr10: Rate,
}

impl Headline {
    /// The headline figures of `scores` (see the fields).
    pub fn of(scores: &[PassageScore]) -> Self {
        let s: Vec<&PassageScore> = scores
            .iter()
            .filter(|r| !r.too_short && !r.truth.interference)
            .collect();
        let required: usize = s.iter().map(|r| r.required).sum();
        let missed: usize = s.iter().map(|r| r.missed).sum();
        let detected: usize = s.iter().map(|r| r.detected).sum();
        let spurious: usize = s.iter().map(|r| r.spurious).sum();
        let timing: Vec<f64> = s
            .iter()
            .flat_map(|r| r.timing_tau_c.iter().map(|e| e.abs()))
            .collect();
        let widths = |min_snr: f64| -> Vec<Option<f64>> {
            s.iter()
                .filter(|r| r.bench.snr >= min_snr)
                .map(|r| r.width_error.map(f64::abs))
                .collect()
        };
        let within = |w: &[Option<f64>]| {
            Rate::of(
                w.iter().filter(|e| e.is_some_and(|e| e <= 0.03)).count(),
                w.len(),
            )
        };
        let spread =
            |w: &[Option<f64>]| Spread::of(&w.iter().flatten().copied().collect::<Vec<_>>());
        let (all, snr10) = (widths(0.0), widths(10.0));
        let bias: Vec<f64> = s
            .iter()
            .filter(|r| r.bench.snr >= 10.0)
            .filter_map(|r| r.width_error)
            .collect();
        let snr10_rows: Vec<&&PassageScore> = s.iter().filter(|r| r.bench.snr >= 10.0).collect();
        let held = |r: &PassageScore| {
            r.width_error
                .is_some_and(|e| e <= 0.03 && e >= -(r.width_shortfall.unwrap_or(0.0) + 0.03))
        };
        let bound: Vec<&&&PassageScore> =
            snr10_rows.iter().filter(|r| r.width_lower_bound).collect();
        let fwhm10: Vec<Option<f64>> = snr10_rows
            .iter()
            .map(|r| r.width_error_fwhm.map(f64::abs))
            .collect();
        let measured10: Vec<Option<f64>> = snr10.iter().filter(|e| e.is_some()).copied().collect();
        Self {
            width_within_3pct_fwhm_snr10: within(&fwhm10),
            width_withheld_snr10: Rate::of(
                snr10_rows.iter().filter(|r| r.width_withheld).count(),
                snr10_rows.len(),
            ),
            width_within_3pct_measured_snr10: within(&measured10),
            width_truth_fwhm_snr10: Rate::of(
                snr10_rows
                    .iter()
                    .filter(|r| r.width_truth == super::WidthTruth::OnePulseFwhm)
                    .count(),
                snr10_rows.len(),
            ),
            width_lower_bound_snr10: Rate::of(bound.len(), snr10_rows.len()),
            width_bound_held_snr10: Rate::of(bound.iter().filter(|r| held(r)).count(), bound.len()),
            width_within_3pct_or_bound_snr10: Rate::of(
                snr10_rows
                    .iter()
                    .filter(|r| {
                        if r.width_lower_bound {
                            held(r)
                        } else {
                            r.width_error.is_some_and(|e| e.abs() <= 0.03)
                        }
                    })
                    .count(),
                snr10_rows.len(),
            ),
            records: s.len(),
            detection: Rate::of(required - missed, required),
            false_passages: Rate::of(spurious, detected),
            records_with_false_passages: Rate::of(
                s.iter().filter(|r| r.spurious > 0).count(),
                s.len(),
            ),
            count_exact: Rate::of(s.iter().filter(|r| r.count_exact).count(), s.len()),
            failed: Rate::of(s.iter().filter(|r| r.error.is_some()).count(), s.len()),
            timing_within_0_02: Rate::of(
                timing.iter().filter(|e| **e <= 0.02).count(),
                timing.len(),
            ),
            timing_tau_c: Spread::of(&timing),
            width_error: spread(&all),
            width_within_3pct: within(&all),
            width_error_snr10: spread(&snr10),
            width_within_3pct_snr10: within(&snr10),
            width_bias_snr10: if bias.is_empty() {
                f64::NAN
            } else {
                bias.iter().sum::<f64>() / bias.len() as f64
            },
        }
    }
}

/// The scores of one group of records.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroupRow {
    /// Which records (`"SNR 5–10"`, ...).
    pub group: String,
    /// Records with an exact count (of those not too short).
    pub count_exact: Rate,
    /// Records too short to score the count (fewer than two required passages).
    pub too_short: usize,
    /// Required passages missed, over all required.
    pub missed: Rate,
    /// Spurious detections per record (mean).
    pub spurious_per_record: f64,
    /// Inverted-spurious detections per record (mean).
    pub inverted_spurious_per_record: f64,
    /// Records whose analysis failed.
    pub failed: usize,
    /// Mean of `|width error|` over the records with a width.
    pub mean_abs_width_error: f64,
    /// Mean signed width error (the bias).
    pub mean_width_error: f64,
    /// 95th percentile of `|width error|`.
    pub p95_abs_width_error: f64,
    /// Records with `|width error| ≤ 3 %`.
    pub width_within_3pct: Rate,
    /// 95th percentile of the worst timing error per record, `τ_c`.
    pub p95_worst_timing_tau_c: f64,
}

/// A condition verdict's false-alarm and detection rates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConditionRow {
    /// The condition and what counts as present / absent.
    pub condition: String,
    /// Reported where absent.
    pub false_alarm: Rate,
    /// Reported where present.
    pub detection: Rate,
}

/// Scores of many records, grouped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassageSummary {
    /// Records scored.
    pub records: usize,
    /// The headline figures.
    pub headline: Headline,
    /// Per group of records.
    pub groups: Vec<GroupRow>,
    /// Per condition.
    pub conditions: Vec<ConditionRow>,
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let pos = q / 100.0 * (v.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(v.len() - 1);
    v[lo] + (pos - lo as f64) * (v[hi] - v[lo])
}

fn group_row(name: &str, s: &[&PassageScore]) -> GroupRow {
    let n = s.len();
    let scored: Vec<&&PassageScore> = s.iter().filter(|r| !r.too_short).collect();
    let exact = scored.iter().filter(|r| r.count_exact).count();
    let required: usize = scored.iter().map(|r| r.required).sum();
    let missed: usize = scored.iter().map(|r| r.missed).sum();
    let spur: usize = s.iter().map(|r| r.spurious).sum();
    let spur_inv: usize = s.iter().map(|r| r.spurious_inverted).sum();
    let we: Vec<f64> = s.iter().filter_map(|r| r.width_error).collect();
    let mut abs: Vec<f64> = we.iter().map(|e| e.abs()).collect();
    let mut timing: Vec<f64> = s.iter().filter_map(|r| r.worst_timing_tau_c).collect();
    let mean = |v: &[f64]| {
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let per = |k: usize| {
        if n == 0 {
            f64::NAN
        } else {
            k as f64 / n as f64
        }
    };
    GroupRow {
        group: name.to_string(),
        count_exact: Rate::of(exact, scored.len()),
        too_short: n - scored.len(),
        missed: Rate::of(missed, required),
        spurious_per_record: per(spur),
        inverted_spurious_per_record: per(spur_inv),
        failed: scored.iter().filter(|r| r.error.is_some()).count(),
        mean_abs_width_error: mean(&abs),
        mean_width_error: mean(&we),
        width_within_3pct: Rate::of(
            abs.iter().filter(|e| **e <= 0.03).count(),
            s.len(), // a record without a width is not within 3 %
        ),
        p95_abs_width_error: percentile(&mut abs, 95.0),
        p95_worst_timing_tau_c: percentile(&mut timing, 95.0),
    }
}

/// Condition verdicts: what counts as present and as absent.
///
/// - AC coupling: present when the coupling's dip per pulse (`ac_dip`) is
///   at least 2 % of the pulse; absent when DC coupled.
/// - Baseline drift: present when the drift's peak is at least 20 % of the
///   pulse height; absent without drift and without interference.
/// - Inverted pulses: present when the fringe inverts at least one required
///   passage; absent without interference.
/// - Missed passages: present when the analysis missed a required passage
///   or the fringe faded one; absent when the count is exact and nothing faded.
/// - Period mismatch: never present (the velocity given is the true one).
fn condition_rows(s: &[PassageScore]) -> Vec<ConditionRow> {
    let row = |name: &str,
               present: &dyn Fn(&PassageScore) -> Option<bool>,
               said: &dyn Fn(&PassageScore) -> bool| {
        let (mut fa, mut na, mut de, mut np) = (0, 0, 0, 0);
        for r in s.iter().filter(|r| r.error.is_none()) {
            match present(r) {
                Some(true) => {
                    np += 1;
                    de += usize::from(said(r));
                }
                Some(false) => {
                    na += 1;
                    fa += usize::from(said(r));
                }
                None => {}
            }
        }
        ConditionRow {
            condition: name.to_string(),
            false_alarm: Rate::of(fa, na),
            detection: Rate::of(de, np),
        }
    };
    vec![
        row(
            "ac_coupling (present: dip ≥ 2 % of the pulse; absent: DC coupled)",
            &|r| {
                if !r.truth.ac_coupling {
                    Some(false)
                } else {
                    (r.truth.ac_dip >= 0.02).then_some(true)
                }
            },
            &|r| r.reported.ac_coupling,
        ),
        row(
            "baseline_drift (present: drift ≥ 20 % of the pulse; absent: no drift, no interference)",
            &|r| {
                if r.truth.interference {
                    None
                } else if r.truth.drift_fraction >= 0.2 {
                    Some(true)
                } else if r.truth.drift_fraction == 0.0 {
                    Some(false)
                } else {
                    None
                }
            },
            &|r| r.reported.baseline_drift,
        ),
        row(
            "inverted_pulses (present: interference inverting a required passage; absent: no interference)",
            &|r| {
                if !r.truth.interference {
                    Some(false)
                } else {
                    (r.truth.inverted_required > 0).then_some(true)
                }
            },
            &|r| r.reported.inverted_pulses,
        ),
        row(
            "missed_passages (present: a required passage missed or a pulse faded by interference; absent: count exact, no interference)",
            &|r| {
                if r.missed > 0 || (r.truth.interference && r.true_passages > r.required + 2) {
                    Some(true)
                } else if r.count_exact && !r.truth.interference {
                    Some(false)
                } else {
                    None
                }
            },
            &|r| r.reported.missed_passages,
        ),
        // The benches' geometry and speed are right, so a measured period
        // far from the predicted one is the detector's: the count broken.
        row(
            "period_mismatch (present: count broken, a required passage missed or a spurious one; absent: count exact)",
            &|r| {
                if r.too_short {
                    None
                } else {
                    Some(!r.count_exact)
                }
            },
            &|r| r.reported.period_mismatch,
        ),
    ]
}

/// Groups scores by SNR, FWHM, shape and condition, and rates the
/// condition verdicts.
pub fn summarize(scores: &[PassageScore]) -> PassageSummary {
    type Filter = Box<dyn Fn(&PassageScore) -> bool>;
    let band = |lo: f64, hi: f64, f: fn(&PassageScore) -> f64| -> Filter {
        Box::new(move |r| (lo..hi).contains(&f(r)))
    };
    let clean = |r: &PassageScore| !r.truth.interference;
    let groups: Vec<(String, Filter)> = vec![
        ("all".into(), Box::new(|_| true)),
        ("no interference".into(), Box::new(clean)),
        (
            "no interference, SNR ≥ 10 (acceptance)".into(),
            Box::new(move |r| clean(r) && r.bench.snr >= 10.0),
        ),
        ("SNR 5–10".into(), band(5.0, 10.0, |r| r.bench.snr)),
        ("SNR 10–20".into(), band(10.0, 20.0, |r| r.bench.snr)),
        ("SNR 20–50".into(), band(20.0, 50.01, |r| r.bench.snr)),
        (
            "FWHM 0.05–0.15 τc".into(),
            band(0.0, 0.15, |r| r.bench.fwhm_tau_c),
        ),
        (
            "FWHM 0.15–0.3 τc".into(),
            band(0.15, 0.3, |r| r.bench.fwhm_tau_c),
        ),
        (
            "FWHM 0.3–0.45 τc".into(),
            band(0.3, 1.0, |r| r.bench.fwhm_tau_c),
        ),
        ("AC coupled".into(), Box::new(|r| r.truth.ac_coupling)),
        ("DC coupled".into(), Box::new(|r| !r.truth.ac_coupling)),
        ("drift".into(), Box::new(|r| r.truth.drift_fraction > 0.0)),
        (
            "no drift".into(),
            Box::new(|r| r.truth.drift_fraction == 0.0),
        ),
        ("interference".into(), Box::new(|r| r.truth.interference)),
        (
            "gaussian".into(),
            Box::new(|r| r.bench.shape == PulseShape::Gaussian),
        ),
        (
            "raised cosine".into(),
            Box::new(|r| r.bench.shape == PulseShape::RaisedCosine),
        ),
        (
            "skewed".into(),
            Box::new(|r| r.bench.shape == PulseShape::Skewed),
        ),
        (
            "rectangular".into(),
            Box::new(|r| r.bench.shape == PulseShape::Rectangular),
        ),
    ];
    PassageSummary {
        records: scores.len(),
        headline: Headline::of(scores),
        groups: groups
            .iter()
            .map(|(name, f)| {
                let sel: Vec<&PassageScore> = scores.iter().filter(|r| f(r)).collect();
                group_row(name, &sel)
            })
            .filter(|g| g.count_exact.n + g.too_short > 0)
            .collect(),
        conditions: condition_rows(scores),
    }
}

impl PassageSummary {
    /// The summary as two Markdown tables (groups, then conditions).
    pub fn to_markdown(&self) -> String {
        use std::fmt::Write as _;
        let pct = |v: f64| {
            if v.is_finite() {
                format!("{:.1}", 100.0 * v)
            } else {
                "–".into()
            }
        };
        let rate = |r: &Rate| {
            format!(
                "{} ({}/{}; {}–{})",
                pct(r.rate),
                r.k,
                r.n,
                pct(r.ci95[0]),
                pct(r.ci95[1])
            )
        };
        let spread = |x: &Spread, scale: f64, digits: usize| {
            format!(
                "p50 {:.d$} ({:.d$}–{:.d$}), p90 {:.d$} ({:.d$}–{:.d$}), max {:.d$}",
                scale * x.p50,
                scale * x.p50_ci95[0],
                scale * x.p50_ci95[1],
                scale * x.p90,
                scale * x.p90_ci95[0],
                scale * x.p90_ci95[1],
                scale * x.max,
                d = digits
            )
        };
        let h = &self.headline;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "Headline ({} records: not too short, no interference; 95 % intervals)\n",
            h.records
        );
        let _ = writeln!(s, "| figure | value |\n|---|---|");
        let rows = [
            ("detection (required passages found)", rate(&h.detection)),
            ("false passages (of detections)", rate(&h.false_passages)),
            (
                "records with a false passage",
                rate(&h.records_with_false_passages),
            ),
            ("records with the count exact", rate(&h.count_exact)),
            ("records failed", rate(&h.failed)),
            (
                "timing error, τc (passages)",
                spread(&h.timing_tau_c, 1.0, 4),
            ),
            ("passages timed within 0.02 τc", rate(&h.timing_within_0_02)),
            (
                "abs width error, % (records; truth: half prominence as recorded)",
                spread(&h.width_error, 100.0, 2),
            ),
            ("records with width within 3 %", rate(&h.width_within_3pct)),
            (
                "abs width error at SNR ≥ 10, %",
                spread(&h.width_error_snr10, 100.0, 2),
            ),
            (
                "width within 3 % at SNR ≥ 10 (truth: width at half prominence as recorded; withheld counts as not within)",
                rate(&h.width_within_3pct_snr10),
            ),
            (
                "width within 3 % at SNR ≥ 10 against one pulse's FWHM",
                rate(&h.width_within_3pct_fwhm_snr10),
            ),
            (
                "widths withheld at SNR ≥ 10 (analysis succeeded, no width)",
                rate(&h.width_withheld_snr10),
            ),
            (
                "width within 3 % at SNR ≥ 10, of the records with a width",
                rate(&h.width_within_3pct_measured_snr10),
            ),
            (
                "records at SNR ≥ 10 whose truth is one pulse's FWHM (< 3 clean pulses)",
                rate(&h.width_truth_fwhm_snr10),
            ),
            (
                "widths reported as possibly low (overlapping pulses) at SNR ≥ 10",
                rate(&h.width_lower_bound_snr10),
            ),
            (
                "of those, within the stated range (≤ +3 %, ≥ −(shortfall + 3 %))",
                rate(&h.width_bound_held_snr10),
            ),
            (
                "width within 3 %, or within the stated range when reported, at SNR ≥ 10",
                rate(&h.width_within_3pct_or_bound_snr10),
            ),
            ("width bias at SNR ≥ 10, %", pct(h.width_bias_snr10)),
        ];
        for (name, value) in rows {
            let _ = writeln!(s, "| {name} | {value} |");
        }
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "| records | n | too short | count exact % (k/n; 95 % CI) | missed % | spurious/rec | inverted spurious/rec | failed | mean abs width err % | width bias % | p95 abs width err % | within 3 % | p95 worst timing τc |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for g in &self.groups {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {:.3} | {:.3} | {} | {} | {} | {} | {} | {:.3} |",
                g.group,
                g.count_exact.n + g.too_short,
                g.too_short,
                rate(&g.count_exact),
                pct(g.missed.rate),
                g.spurious_per_record,
                g.inverted_spurious_per_record,
                g.failed,
                pct(g.mean_abs_width_error),
                pct(g.mean_width_error),
                pct(g.p95_abs_width_error),
                pct(g.width_within_3pct.rate),
                g.p95_worst_timing_tau_c
            );
        }
        let _ = writeln!(s);
        let _ = writeln!(
            s,
            "| condition | false alarm % (k/n; 95 % CI) | detection % (k/n; 95 % CI) |"
        );
        let _ = writeln!(s, "|---|---|---|");
        for c in &self.conditions {
            let _ = writeln!(
                s,
                "| {} | {} | {} |",
                c.condition,
                rate(&c.false_alarm),
                rate(&c.detection)
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantile_intervals_are_the_binomial_order_statistics() {
        // Values 1..=n, so the k-th order statistic is k. Ranks from SciPy:
        // max r with binom.cdf(r − 1, n, q) ≤ 0.025, min r with ≥ 0.975:
        // n 100, q 0.5: 40, 61; q 0.9: 84, 96; n 20, q 0.5: 6, 15.
        let v: Vec<f64> = (1..=100).map(f64::from).collect();
        let s = Spread::of(&v);
        assert_eq!(s.n, 100);
        assert!(
            (s.p50 - 50.5).abs() < 1e-12 && s.p50_ci95 == [40.0, 61.0],
            "{s:?}"
        );
        assert!(
            (s.p90 - 90.1).abs() < 1e-9 && s.p90_ci95 == [84.0, 96.0],
            "{s:?}"
        );
        assert_eq!(s.max, 100.0);
        let v: Vec<f64> = (1..=20).rev().map(f64::from).collect();
        assert_eq!(Spread::of(&v).p50_ci95, [6.0, 15.0]);
        assert!(Spread::of(&[]).p50.is_nan());
    }
}
