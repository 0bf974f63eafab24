//! Bearing diagnosis (`ballpass diagnose`): which bearing of a batch sticks
//! (thesis ch. 8, Figs. 66–68).
//!
//! Every bearing has a friction ripple at each ball passage; a sticking
//! bearing's friction jumps at some passages, by random amounts. The
//! diagnosis therefore looks at the height of every ball-pass period
//! ([`super::sticking`]), pooled over a bearing's records, against the
//! bearing's own typical period and against the batch:
//!
//! - **spikes**: periods above their record's typical height by `κ`
//!   spreads of the lower half of the bearing's periods (κ = 8; each
//!   record's heights taken about its own median, since records differ a
//!   little in level). A good bearing's period exceeds that with a
//!   probability of at most `p₀` = 5e-4 (4e-4 for the Gumbel-like largest
//!   noise sample of a period, rounded up); the spike count of `N` periods
//!   is then at most binomial `(N, p₀)`.
//! - **bad** when the count reaches the binomial critical value at 1e-4
//!   (and at least 3): a good bearing is called bad by it with probability
//!   below 1e-4. The per-period rate is `p₀`, or the median spike rate of
//!   the *other* bearings of the batch when that is higher (at least three
//!   others: a bench whose good periods have heavier tails than `p₀`
//!   raises the bar for all, and one or two sticking siblings cannot move
//!   the median); or when the spread of its periods is at least three times
//!   the batch's (spikes on so many passages that they enter the bearing's
//!   own lower half and no longer stand out from it: the simulator's severe
//!   sticking puts them on 60 %; good bearings of one bench stayed within
//!   1.41× on the development fleets), and the ratio is significant at the
//!   same 1e-4: its square, as a ratio of variances, exceeds the F
//!   quantile at the spreads' degrees of freedom (a spread from few
//!   periods scatters a lot: three periods can read 3× the batch by
//!   chance). The batch reference needs three bearings or more.
//! - **suspect** when the count reaches the critical value at 1e-2 (and at
//!   least 2), or the typical period is at least twice the batch's without
//!   the spread (a bearing whose every passage rubs harder than its
//!   siblings').
//! - **inconclusive** when none of that holds but the bearing had too few
//!   periods for the spike count to catch mild sticking (spikes on 10 % of
//!   the passages) with 95 % probability: a clean bill would not mean
//!   anything.
//! - **good** otherwise.
//!
//! The friction spectrum averaged over a bearing's repeats, its low-band
//! power against the batch and its harmonics are reported as evidence (the
//! thesis' Figs. 67–68); they do not decide the verdict, because every
//! bearing has harmonics and a ripple stronger than the load cell's noise is
//! not a fault. The verdict rules' false-alarm and detection rates on
//! randomized benches are measured by `ballpass validate` (docs).

use serde::{Deserialize, Serialize};

use super::record::RecordResult;
use super::sticking::{lower_spread, StickingSettings};
use crate::stats::{f_cdf, mean_std, median, reg_inc_beta};

/// Thresholds of the diagnosis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DiagnoseSettings {
    /// Upper edge of the low band, Hz (evidence only).
    pub low_band_hz: f64,
    /// Largest chance that one period of a good bearing counts as a spike.
    pub period_false_rate: f64,
    /// False-alarm probability per bearing of the spike count for "bad".
    pub bad_false_alarm: f64,
    /// False-alarm probability per bearing of the spike count for "suspect".
    pub suspect_false_alarm: f64,
    /// Typical period over the batch's at which a bearing stands out.
    pub batch_ratio: f64,
    /// Spread of the periods over the batch's that makes spikes on most
    /// passages.
    pub batch_spread_ratio: f64,
    /// Fraction of passages with spikes the bearing must have had enough
    /// periods to catch (95 %) for a "good".
    pub mild_fraction: f64,
    /// Per-period detector settings.
    pub sticking: StickingSettings,
}

impl Default for DiagnoseSettings {
    fn default() -> Self {
        Self {
            low_band_hz: 25.0,
            period_false_rate: 5e-4,
            bad_false_alarm: 1e-4,
            suspect_false_alarm: 1e-2,
            batch_ratio: 2.0,
            batch_spread_ratio: 3.0,
            mild_fraction: 0.1,
            sticking: StickingSettings::default(),
        }
    }
}

/// good / inconclusive / suspect / bad.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Condition {
    /// No sticking, and enough periods to have seen mild sticking.
    Good,
    /// No sticking seen, but too few periods to rule out mild sticking.
    Inconclusive,
    /// Something stands out, not enough to call it sticking.
    Suspect,
    /// Sticking.
    Bad,
}

impl Condition {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Condition::Good => "good",
            Condition::Inconclusive => "inconclusive",
            Condition::Suspect => "suspect",
            Condition::Bad => "bad",
        }
    }
}

/// One harmonic of one bearing's friction.
#[derive(Debug, Clone, Serialize)]
pub struct BearingHarmonic {
    /// Harmonic number.
    pub k: usize,
    /// Mean over repeats of the PSD-over-floor ratio at k·f_c, dB.
    pub ratio_db: Option<f64>,
    /// Repeats in which it was significant.
    pub significant_in: usize,
    /// Repeats with a value.
    pub repeats: usize,
}

/// The diagnosis of one bearing.
#[derive(Debug, Clone, Serialize)]
pub struct BearingDiagnosis {
    /// Bearing name.
    pub bearing: String,
    /// Records of this bearing analysed.
    pub records: usize,
    /// Condition given in the manifest, when all records agree.
    pub manifest_condition: Option<String>,
    /// Ball-pass periods examined (all records).
    pub periods: usize,
    /// Typical height of a period above its baseline (median), N.
    pub typical_n: f64,
    /// Spread of the periods' heights below the typical (robust σ), N.
    pub spread_n: f64,
    /// Periods standing `κ` spreads above the typical.
    pub spikes: usize,
    /// Spike count that makes the bearing bad with these periods.
    pub spikes_for_bad: usize,
    /// Spike count that makes it suspect.
    pub spikes_for_suspect: usize,
    /// Largest spike over the typical height.
    pub max_spike_over_typical: Option<f64>,
    /// Typical period over the batch's.
    pub typical_over_batch: Option<f64>,
    /// Spread over the batch's.
    pub spread_over_batch: Option<f64>,
    /// Friction power below the low-band edge (averaged spectrum), N².
    pub low_band_power_n2: f64,
    /// That power over the batch median.
    pub low_band_ratio: f64,
    /// Harmonics k·f_c of the friction.
    pub harmonics: Vec<BearingHarmonic>,
    /// Verdict.
    pub verdict: Condition,
    /// The evidence that decided it, in words.
    pub evidence: Vec<String>,
    /// Rank, 1 = worst.
    pub rank: usize,
}

/// Everything `ballpass diagnose` finds.
#[derive(Debug, Clone, Serialize)]
pub struct Diagnosis {
    /// Thresholds used.
    pub settings: DiagnoseSettings,
    /// The batch's typical period height (median over bearings), N.
    pub batch_typical_n: Option<f64>,
    /// The batch's spread (median over bearings), N.
    pub batch_spread_n: Option<f64>,
    /// Bearings, worst first.
    pub bearings: Vec<BearingDiagnosis>,
    /// Frequencies of the averaged spectra, Hz.
    #[serde(skip)]
    pub freq_hz: Vec<f64>,
    /// Averaged friction spectra, one per bearing (same order as `bearings`), N²/Hz.
    #[serde(skip)]
    pub friction_psd: Vec<Vec<f64>>,
    /// Warnings (e.g. records on different frequency grids).
    pub warnings: Vec<String>,
}

/// Power of a one-sided PSD between 0 (excluded) and `edge_hz` (included):
/// `Σ PSD · Δf` over those bins (units of the PSD × Hz, N² for friction).
/// Zero for fewer than two bins.
pub fn low_band_power(freq_hz: &[f64], psd: &[f64], edge_hz: f64) -> f64 {
    let df = match freq_hz {
        [f0, f1, ..] => f1 - f0,
        _ => return 0.0,
    };
    freq_hz
        .iter()
        .zip(psd)
        .filter(|(f, _)| **f > 0.0 && **f <= edge_hz)
        .map(|(_, p)| p * df)
        .sum()
}

/// `P(Bin(n, p) ≥ c) = I_p(c, n − c + 1)`.
pub fn binomial_tail(c: usize, n: usize, p: f64) -> f64 {
    if c == 0 {
        1.0
    } else if c > n {
        0.0
    } else {
        reg_inc_beta(c as f64, (n - c + 1) as f64, p)
    }
}

/// The smallest count `c ≥ min` with `P(Bin(n, p) ≥ c) ≤ alpha`.
pub fn binomial_critical(n: usize, p: f64, alpha: f64, min: usize) -> usize {
    let mut c = min;
    while c <= n && binomial_tail(c, n, p) > alpha {
        c += 1;
    }
    c
}

/// The batch's references: medians over the bearings with periods.
#[derive(Debug, Clone, Copy)]
struct Batch {
    typical: f64,
    spread: f64,
    periods: f64,
}

/// Degrees of freedom per period of the robust spread
/// `(median − p10) / z₀.₉` of normal heights, as a variance estimate.
///
/// Large-sample quantile variances (`n Var q_p = p (1 − p) / φ(z_p)²`,
/// `n Cov(q_a, q_b) = a (1 − b) / (φ(z_a) φ(z_b))` for `a < b`) give
/// `n Var σ̂ / σ² = 1.866`; a standard deviation from `ν` degrees of
/// freedom has `Var s / σ² = 1 / (2ν)`, so `ν = 0.268 n`.
fn spread_dof_per_period() -> f64 {
    let z = 1.281_551_565_544_600_5_f64;
    let phi = |x: f64| (-0.5 * x * x).exp() / (std::f64::consts::TAU).sqrt();
    let (a, b) = (0.1, 0.5);
    let var_a = a * (1.0 - a) / phi(z).powi(2);
    let var_b = b * (1.0 - b) / phi(0.0).powi(2);
    let cov = a * (1.0 - b) / (phi(z) * phi(0.0));
    let n_var = (var_a + var_b - 2.0 * cov) / (z * z);
    1.0 / (2.0 * n_var)
}

/// Probability that a good bearing's spread from `n` periods reads at least
/// `ratio` times a batch spread from `n_batch` periods (F test on the
/// squared ratio, [`spread_dof_per_period`]).
fn spread_ratio_p(ratio: f64, n: f64, n_batch: f64) -> f64 {
    let k = spread_dof_per_period();
    let (d1, d2) = (k * n, k * n_batch);
    if d1 <= 0.0 || d2 <= 0.0 || !ratio.is_finite() {
        return 1.0;
    }
    (1.0 - f_cdf(ratio * ratio, d1, d2)).clamp(0.0, 1.0)
}

/// The spike statistics of one bearing's pooled periods.
struct Pooled {
    periods: usize,
    typical: f64,
    spread: f64,
    spikes: Vec<f64>,
}

/// Pools a bearing's periods: each record's heights about that record's
/// own median (records differ a little in level: another stretch of rail,
/// another load-cell state), the spread from the pooled lower half, the
/// typical height the median of all.
fn pool(mine: &[&&RecordResult], kappa: f64) -> Pooled {
    let per_record: Vec<&[f64]> = mine
        .iter()
        .filter_map(|r| r.sticking.as_ref())
        .map(|s| s.heights_n.as_slice())
        .filter(|h| !h.is_empty())
        .collect();
    let all: Vec<f64> = per_record.iter().flat_map(|h| h.iter().copied()).collect();
    let centred: Vec<f64> = per_record
        .iter()
        .flat_map(|h| {
            let m = median(h).unwrap_or(0.0);
            h.iter().map(move |v| v - m)
        })
        .collect();
    let typical = median(&all).unwrap_or(0.0);
    let (centre, spread) = lower_spread(&centred);
    let limit = centre + kappa * spread;
    Pooled {
        periods: all.len(),
        typical,
        spread,
        spikes: centred
            .iter()
            .filter(|&&c| spread > 0.0 && c > limit)
            .map(|c| c + typical)
            .collect(),
    }
}

/// Diagnoses every bearing of a batch from its records' results.
pub fn diagnose(records: &[&RecordResult], settings: &DiagnoseSettings) -> Diagnosis {
    let mut names: Vec<String> = records.iter().map(|r| r.bearing.clone()).collect();
    names.sort();
    names.dedup();
    let mut warnings = Vec::new();
    // The common frequency grid: the first record's; others must match.
    let freq_hz: Vec<f64> = records
        .iter()
        .find(|r| !r.friction_psd.is_empty())
        .map(|r| r.friction_psd_freq_hz.clone())
        .unwrap_or_default();
    let mut spectra = Vec::new();
    let mut partial = Vec::new();
    for name in &names {
        let mine: Vec<&&RecordResult> = records.iter().filter(|r| &r.bearing == name).collect();
        let grid: Vec<&&&RecordResult> = mine
            .iter()
            .filter(|r| !r.friction_psd.is_empty() && r.friction_psd_freq_hz == freq_hz)
            .collect();
        let skipped = mine.iter().filter(|r| !r.friction_psd.is_empty()).count() - grid.len();
        if skipped > 0 {
            warnings.push(format!(
                "bearing {name}: {skipped} record(s) left out of the averaged spectrum (different rate or segment length)"
            ));
        }
        let mut avg = vec![0.0; freq_hz.len()];
        for r in &grid {
            for (a, p) in avg.iter_mut().zip(&r.friction_psd) {
                *a += p / grid.len() as f64;
            }
        }
        let low = low_band_power(&freq_hz, &avg, settings.low_band_hz);
        spectra.push(avg);
        let pooled = pool(&mine, settings.sticking.outlier_spreads);
        partial.push((name.clone(), mine, low, pooled));
    }
    let lows: Vec<f64> = partial.iter().map(|p| p.2).collect();
    let median_low = median(&lows).unwrap_or(0.0);
    let with_periods: Vec<&Pooled> = partial
        .iter()
        .map(|p| &p.3)
        .filter(|p| p.periods > 0)
        .collect();
    let batch = (with_periods.len() >= 3).then(|| Batch {
        typical: median(&with_periods.iter().map(|p| p.typical).collect::<Vec<_>>()).unwrap_or(0.0),
        spread: median(&with_periods.iter().map(|p| p.spread).collect::<Vec<_>>()).unwrap_or(0.0),
        periods: median(
            &with_periods
                .iter()
                .map(|p| p.periods as f64)
                .collect::<Vec<_>>(),
        )
        .unwrap_or(0.0),
    });
    let k_max = records
        .iter()
        .map(|r| r.friction_harmonic_ratio_db.len())
        .max()
        .unwrap_or(0);
    let harmonics_of = |mine: &[&&RecordResult]| -> Vec<BearingHarmonic> {
        (0..k_max)
            .map(|i| {
                let vals: Vec<f64> = mine
                    .iter()
                    .filter_map(|r| r.friction_harmonic_ratio_db.get(i).copied().flatten())
                    .collect();
                BearingHarmonic {
                    k: i + 1,
                    ratio_db: mean_std(&vals).map(|m| m.mean),
                    significant_in: mine
                        .iter()
                        .filter(|r| {
                            r.friction_harmonic_significant.get(i).copied().flatten() == Some(true)
                        })
                        .count(),
                    repeats: vals.len(),
                }
            })
            .collect()
    };

    // Each bearing's spike rate; a bearing's spike bar uses the larger of
    // the nominal per-period rate and the median rate of the *other*
    // bearings (at least three of them): on a bench whose good bearings'
    // periods have heavier tails than the nominal rate assumes, their
    // exceedances raise the bar for all, while one or two sticking
    // siblings cannot move a median of the others.
    let rates: Vec<Option<f64>> = partial
        .iter()
        .map(|p| (p.3.periods > 0).then(|| p.3.spikes.len() as f64 / p.3.periods as f64))
        .collect();
    let period_rates: Vec<f64> = (0..partial.len())
        .map(|i| {
            let others: Vec<f64> = rates
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .filter_map(|(_, r)| *r)
                .collect();
            let batch_rate = if others.len() >= 3 {
                median(&others).unwrap_or(0.0)
            } else {
                0.0
            };
            settings.period_false_rate.max(batch_rate)
        })
        .collect();
    let mut bearings: Vec<BearingDiagnosis> = partial
        .into_iter()
        .zip(period_rates)
        .map(|((bearing, mine, low, pooled), period_rate)| {
            let harmonics = harmonics_of(&mine);
            let low_band_ratio = if median_low > 0.0 {
                low / median_low
            } else {
                1.0
            };
            let mut conds: Vec<&str> = mine.iter().filter_map(|r| r.condition.as_deref()).collect();
            conds.dedup();
            let manifest_condition = (conds.len() == 1
                && mine.iter().all(|r| r.condition.is_some()))
            .then(|| conds[0].to_string());
            judge(
                bearing,
                mine.len(),
                manifest_condition,
                &pooled,
                period_rate,
                batch,
                low,
                low_band_ratio,
                harmonics,
                settings,
            )
        })
        .collect();
    // Worst first: verdict, then the spike count over its bar, then the
    // typical period over the batch's.
    let severity = |b: &BearingDiagnosis| {
        (
            b.verdict,
            b.spikes as f64 / b.spikes_for_bad.max(1) as f64,
            b.typical_over_batch.unwrap_or(1.0),
        )
    };
    let mut order: Vec<usize> = (0..bearings.len()).collect();
    order.sort_by(|&a, &b| {
        let (x, y) = (severity(&bearings[a]), severity(&bearings[b]));
        y.0.cmp(&x.0)
            .then(y.1.total_cmp(&x.1))
            .then(y.2.total_cmp(&x.2))
            .then(bearings[a].bearing.cmp(&bearings[b].bearing))
    });
    let friction_psd: Vec<Vec<f64>> = order.iter().map(|&i| spectra[i].clone()).collect();
    let mut sorted: Vec<BearingDiagnosis> = Vec::with_capacity(bearings.len());
    for (rank, &i) in order.iter().enumerate() {
        let mut b = std::mem::replace(&mut bearings[i], placeholder());
        b.rank = rank + 1;
        sorted.push(b);
    }
    Diagnosis {
        settings: settings.clone(),
        batch_typical_n: batch.map(|b| b.typical),
        batch_spread_n: batch.map(|b| b.spread),
        bearings: sorted,
        freq_hz,
        friction_psd,
        warnings,
    }
}

fn placeholder() -> BearingDiagnosis {
    BearingDiagnosis {
        bearing: String::new(),
        records: 0,
        manifest_condition: None,
        periods: 0,
        typical_n: 0.0,
        spread_n: 0.0,
        spikes: 0,
        spikes_for_bad: 0,
        spikes_for_suspect: 0,
        max_spike_over_typical: None,
        typical_over_batch: None,
        spread_over_batch: None,
        low_band_power_n2: 0.0,
        low_band_ratio: 0.0,
        harmonics: Vec::new(),
        verdict: Condition::Good,
        evidence: Vec::new(),
        rank: 0,
    }
}

/// The verdict of one bearing (module docs).
#[allow(clippy::too_many_arguments)]
fn judge(
    bearing: String,
    records: usize,
    manifest_condition: Option<String>,
    p: &Pooled,
    period_rate: f64,
    batch: Option<Batch>,
    low: f64,
    low_band_ratio: f64,
    harmonics: Vec<BearingHarmonic>,
    s: &DiagnoseSettings,
) -> BearingDiagnosis {
    let n = p.periods;
    let spikes = p.spikes.len();
    let for_bad = binomial_critical(n, period_rate, s.bad_false_alarm, 3);
    let for_suspect = binomial_critical(n, period_rate, s.suspect_false_alarm, 2);
    let max_spike_over_typical = (p.typical > 0.0 && spikes > 0)
        .then(|| p.spikes.iter().copied().fold(f64::NEG_INFINITY, f64::max) / p.typical);
    let ratio = |a: f64, b: f64| (b > 0.0).then(|| a / b);
    let typical_over_batch = batch.and_then(|b| ratio(p.typical, b.typical));
    let spread_over_batch = batch.and_then(|b| ratio(p.spread, b.spread));
    let spread_p = match (spread_over_batch, batch) {
        (Some(r), Some(b)) => spread_ratio_p(r, n as f64, b.periods),
        _ => 1.0,
    };
    let mut evidence = vec![format!(
        "{n} ball-pass periods: typical rise {:.3} N (spread {:.3} N), {spikes} spike(s) {} spreads above it; {for_bad} make it bad, {for_suspect} suspect",
        p.typical, p.spread, s.sticking.outlier_spreads
    )];
    if period_rate > s.period_false_rate {
        evidence.push(format!(
            "the other bearings' periods exceed that bar at a median rate of {:.2} %, above the nominal {:.2} %: this bench's good periods scatter more, and the bar was raised to match",
            100.0 * period_rate,
            100.0 * s.period_false_rate
        ));
    }
    if let (Some(r), Some(sr)) = (typical_over_batch, spread_over_batch) {
        evidence.push(format!(
            "typical period {r:.2}× the batch's, spread {sr:.2}× the batch's"
        ));
    }
    let mut verdict = Condition::Good;
    if spikes >= for_bad {
        verdict = Condition::Bad;
        evidence.push(format!(
            "bad: {spikes} sporadic spikes in {n} periods (a good bearing reaches {for_bad} with probability below {:.0e}){}",
            s.bad_false_alarm,
            max_spike_over_typical
                .map(|m| format!(", up to {m:.1}× its typical rise"))
                .unwrap_or_default()
        ));
    }
    let high = typical_over_batch.is_some_and(|r| r >= s.batch_ratio);
    let wide = spread_over_batch.is_some_and(|r| r >= s.batch_spread_ratio);
    let scattered = wide && spread_p <= s.bad_false_alarm;
    if wide && !scattered {
        evidence.push(format!(
            "its spread is {:.2}× the batch's, but {n} periods cannot show that (a good bearing reads it with probability {spread_p:.1e})",
            spread_over_batch.unwrap_or(f64::NAN)
        ));
    }
    if scattered {
        verdict = Condition::Bad;
        evidence.push(format!(
            "bad: its passages scatter at least {}× as much as the batch's: spikes on so many passages that they are its typical passage",
            s.batch_spread_ratio
        ));
    }
    if verdict < Condition::Suspect && spikes >= for_suspect {
        verdict = Condition::Suspect;
        evidence.push(format!(
            "suspect: {spikes} spikes in {n} periods (a good bearing reaches {for_suspect} with probability below {:.0e})",
            s.suspect_false_alarm
        ));
    }
    if verdict < Condition::Suspect && high {
        verdict = Condition::Suspect;
        evidence.push(format!(
            "suspect: every passage rises at least {}× the batch's typical (no sporadic spikes)",
            s.batch_ratio
        ));
    }
    if verdict == Condition::Good {
        // Enough periods to catch mild sticking with 95 % probability?
        let catch = 1.0 - binomial_tail(for_bad, n, s.mild_fraction);
        if catch > 0.05 {
            verdict = Condition::Inconclusive;
            evidence.push(format!(
                "inconclusive: {n} periods are too few to rule out sticking on {:.0} % of the passages",
                100.0 * s.mild_fraction
            ));
        }
    }
    evidence.push(format!(
        "friction power below {} Hz is {:.2}× the batch median ({:+.1} dB){}",
        s.low_band_hz,
        low_band_ratio,
        10.0 * low_band_ratio.max(1e-300).log10(),
        harmonics
            .first()
            .and_then(|h| h.ratio_db.map(|r| format!(
                "; f_c line {r:.1} dB above its floor, significant in {}/{} repeats",
                h.significant_in, h.repeats
            )))
            .unwrap_or_default()
    ));
    BearingDiagnosis {
        bearing,
        records,
        manifest_condition,
        periods: n,
        typical_n: p.typical,
        spread_n: p.spread,
        spikes,
        spikes_for_bad: for_bad,
        spikes_for_suspect: for_suspect,
        max_spike_over_typical,
        typical_over_batch,
        spread_over_batch,
        low_band_power_n2: low,
        low_band_ratio,
        harmonics,
        verdict,
        evidence,
        rank: 0,
    }
}

#[cfg(test)]
#[path = "diagnose_tests.rs"]
mod tests;
