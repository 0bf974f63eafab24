//! Bearing diagnosis (`ballpass diagnose`): which bearing of a batch is bad
//! (thesis ch. 8, Figs. 66–68).
//!
//! Per bearing, over its repeats:
//! - the friction auto-spectrum averaged over the repeats, and its power in
//!   the low band (default below 25 Hz) relative to the batch median;
//! - the prominence of each harmonic k·f_c above its local floor (from each
//!   record's analysis), against the batch median;
//! - sticking events (friction spikes above a multiple of the bearing's
//!   robust level, see [`super::sticking`]) and whether they come at
//!   ball-pass multiples.
//!
//! Verdict rules (thresholds are [`DiagnoseSettings`] and are reported):
//! - **bad**: low-band power ≥ `bad_low_band_ratio` × the batch median, or
//!   ≥ `bad_events_per_record` sticking spikes per record whose intervals are
//!   whole ball periods in at least `timing_fraction_min` of cases;
//! - **suspect**: low-band power ≥ `suspect_low_band_ratio` × the median, or
//!   ≥ `suspect_events_per_record` spikes per record, or the friction line at
//!   f_c ≥ `harmonic_excess_db` above the batch median and significant in at
//!   least half the repeats;
//! - **good** otherwise.

use serde::{Deserialize, Serialize};

use super::record::RecordResult;
use super::sticking::StickingSettings;
use crate::stats::{mean_std, median, MeanStd};

/// Thresholds of the diagnosis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DiagnoseSettings {
    /// Upper edge of the low band, Hz.
    pub low_band_hz: f64,
    /// Low-band power over the batch median at or above which a bearing is bad.
    pub bad_low_band_ratio: f64,
    /// Low-band power over the batch median at or above which a bearing is suspect.
    pub suspect_low_band_ratio: f64,
    /// Sticking spikes per record (with ball-pass timing) that make a bearing bad.
    pub bad_events_per_record: f64,
    /// Sticking spikes per record that make a bearing suspect.
    pub suspect_events_per_record: f64,
    /// Fraction of spike intervals at whole ball periods needed for "ball-pass timing".
    pub timing_fraction_min: f64,
    /// Excess of the friction line at f_c over the batch median, dB, for suspect.
    pub harmonic_excess_db: f64,
    /// Sticking-event detector settings.
    pub sticking: StickingSettings,
}

impl Default for DiagnoseSettings {
    fn default() -> Self {
        Self {
            low_band_hz: 25.0,
            bad_low_band_ratio: 10.0,
            suspect_low_band_ratio: 3.0,
            bad_events_per_record: 3.0,
            suspect_events_per_record: 0.5,
            timing_fraction_min: 0.7,
            harmonic_excess_db: 6.0,
            sticking: StickingSettings::default(),
        }
    }
}

/// good / suspect / bad.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Condition {
    /// Nothing stands out.
    Good,
    /// Something stands out, not enough to call it bad.
    Suspect,
    /// Sticking or a friction spectrum far above the batch.
    Bad,
}

impl Condition {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Condition::Good => "good",
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
    /// Friction power below the low-band edge (averaged spectrum), N².
    pub low_band_power_n2: f64,
    /// That power over the batch median.
    pub low_band_ratio: f64,
    /// Harmonics k·f_c of the friction.
    pub harmonics: Vec<BearingHarmonic>,
    /// Sticking spikes per record.
    pub events_per_record: Option<MeanStd>,
    /// Fraction of spike intervals at whole ball periods (pooled).
    pub timing_fraction: Option<f64>,
    /// Largest spike over the robust level.
    pub max_spike_over_level: Option<f64>,
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
        partial.push((name.clone(), mine, low));
    }
    let lows: Vec<f64> = partial.iter().map(|p| p.2).collect();
    let median_low = median(&lows).unwrap_or(0.0);
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
    let all_h: Vec<Vec<BearingHarmonic>> = partial.iter().map(|p| harmonics_of(&p.1)).collect();
    let k1_median = median(
        &all_h
            .iter()
            .filter_map(|h| h.first().and_then(|h| h.ratio_db))
            .collect::<Vec<_>>(),
    );

    let mut bearings: Vec<BearingDiagnosis> = partial
        .into_iter()
        .zip(all_h)
        .map(|((bearing, mine, low), harmonics)| {
            let low_band_ratio = if median_low > 0.0 { low / median_low } else { 1.0 };
            let counts: Vec<f64> = mine.iter().filter_map(|r| r.sticking.as_ref().map(|s| s.times_s.len() as f64)).collect();
            let events_per_record = mean_std(&counts);
            let (mut near, mut intervals) = (0.0, 0.0);
            let mut max_spike: Option<f64> = None;
            for s in mine.iter().filter_map(|r| r.sticking.as_ref()) {
                if let Some(f) = s.timing_fraction {
                    let n = (s.times_s.len() - 1) as f64;
                    near += f * n;
                    intervals += n;
                }
                if let Some(m) = s.max_height_over_level {
                    max_spike = Some(max_spike.map_or(m, |x: f64| x.max(m)));
                }
            }
            let timing_fraction = (intervals > 0.0).then(|| near / intervals);
            let mut conds: Vec<&str> = mine.iter().filter_map(|r| r.condition.as_deref()).collect();
            conds.dedup();
            let manifest_condition = (conds.len() == 1 && mine.iter().all(|r| r.condition.is_some())).then(|| conds[0].to_string());

            let mut evidence = Vec::new();
            let mut verdict = Condition::Good;
            let epr = events_per_record.map_or(0.0, |m| m.mean);
            let timed = timing_fraction.is_some_and(|f| f >= settings.timing_fraction_min);
            evidence.push(format!(
                "friction power below {} Hz is {:.2}× the batch median ({:+.1} dB)",
                settings.low_band_hz,
                low_band_ratio,
                10.0 * low_band_ratio.max(1e-300).log10()
            ));
            if low_band_ratio >= settings.bad_low_band_ratio {
                verdict = Condition::Bad;
                evidence.push(format!("bad: low-band power at or above {}× the batch median", settings.bad_low_band_ratio));
            } else if low_band_ratio >= settings.suspect_low_band_ratio {
                verdict = verdict.max(Condition::Suspect);
                evidence.push(format!("suspect: low-band power at or above {}× the batch median", settings.suspect_low_band_ratio));
            }
            if epr > 0.0 {
                evidence.push(format!(
                    "{epr:.1} sticking spikes per record above {} robust σ{}{}",
                    settings.sticking.spike_factor,
                    max_spike.map(|m| format!(" (up to {m:.0}× the robust level)")).unwrap_or_default(),
                    timing_fraction
                        .map(|f| format!(", {:.0} % of their intervals whole ball periods{}", 100.0 * f, if timed { " (ball-pass timing)" } else { "" }))
                        .unwrap_or_default()
                ));
            } else {
                evidence.push("no sticking spikes".into());
            }
            if epr >= settings.bad_events_per_record && timed {
                verdict = Condition::Bad;
                evidence.push(format!(
                    "bad: at least {} spikes per record at ball-pass multiples",
                    settings.bad_events_per_record
                ));
            } else if epr >= settings.suspect_events_per_record {
                verdict = verdict.max(Condition::Suspect);
                evidence.push(format!("suspect: at least {} spikes per record", settings.suspect_events_per_record));
            }
            if let (Some(h1), Some(med)) = (harmonics.first(), k1_median) {
                if let Some(r) = h1.ratio_db {
                    evidence.push(format!(
                        "friction at f_c {r:.1} dB above its floor (batch median {med:.1} dB), significant in {}/{} repeats",
                        h1.significant_in, h1.repeats
                    ));
                    if r - med >= settings.harmonic_excess_db && 2 * h1.significant_in >= h1.repeats && h1.repeats > 0 {
                        verdict = verdict.max(Condition::Suspect);
                        evidence.push(format!("suspect: the f_c line stands {} dB or more above the batch", settings.harmonic_excess_db));
                    }
                }
            }
            BearingDiagnosis {
                bearing,
                records: mine.len(),
                manifest_condition,
                low_band_power_n2: low,
                low_band_ratio,
                harmonics,
                events_per_record,
                timing_fraction,
                max_spike_over_level: max_spike,
                verdict,
                evidence,
                rank: 0,
            }
        })
        .collect();
    // Worst first: verdict, then low-band ratio, then spikes.
    let mut order: Vec<usize> = (0..bearings.len()).collect();
    order.sort_by(|&a, &b| {
        let (x, y) = (&bearings[a], &bearings[b]);
        y.verdict
            .cmp(&x.verdict)
            .then(y.low_band_ratio.total_cmp(&x.low_band_ratio))
            .then(x.bearing.cmp(&y.bearing))
    });
    let friction_psd: Vec<Vec<f64>> = order.iter().map(|&i| spectra[i].clone()).collect();
    let mut sorted: Vec<BearingDiagnosis> = Vec::with_capacity(bearings.len());
    for (rank, &i) in order.iter().enumerate() {
        let mut b = bearings[i].clone();
        b.rank = rank + 1;
        sorted.push(b);
    }
    bearings.clear();
    Diagnosis {
        settings: settings.clone(),
        bearings: sorted,
        freq_hz,
        friction_psd,
        warnings,
    }
}

#[cfg(test)]
mod tests {
    use super::super::sticking::StickingEvents;
    use super::super::sweep::tests::record;
    use super::*;

    fn bearing_record(name: &str, repeat: u32, scale: f64, spikes: usize) -> RecordResult {
        let mut r = record(20.0, repeat);
        r.bearing = name.into();
        r.friction_psd_freq_hz = (0..200).map(|i| f64::from(i) * 0.25).collect();
        r.friction_psd = (0..200)
            .map(|i| scale * (1.0 + 0.1 * f64::from((i * 7 + repeat as i32) % 5)))
            .collect();
        let tau = r.tau_c_s.unwrap();
        let times: Vec<f64> = (0..spikes).map(|k| 0.5 + 2.0 * k as f64 * tau).collect();
        r.sticking = Some(StickingEvents {
            robust_level_n: 0.1,
            threshold_n: 0.8,
            heights_n: vec![5.0; spikes],
            max_height_over_level: (spikes > 0).then_some(50.0),
            rate_per_s: spikes as f64 / 30.0,
            timing_fraction: (spikes >= 2).then_some(1.0),
            times_s: times,
        });
        r
    }

    #[test]
    fn the_sticking_bearing_and_only_it_is_bad() {
        let mut recs = Vec::new();
        for b in 1..=5 {
            for rep in 1..=10 {
                let bad = b == 4;
                recs.push(bearing_record(
                    &format!("bearing{b}"),
                    rep,
                    if bad {
                        100.0
                    } else {
                        1.0 + 0.05 * f64::from(b)
                    },
                    if bad { 20 } else { 0 },
                ));
            }
        }
        let refs: Vec<&RecordResult> = recs.iter().collect();
        let d = diagnose(&refs, &DiagnoseSettings::default());
        assert_eq!(d.bearings.len(), 5);
        assert_eq!(d.bearings[0].bearing, "bearing4");
        assert_eq!(d.bearings[0].verdict, Condition::Bad);
        assert_eq!(d.bearings[0].rank, 1);
        assert!(
            d.bearings[1..].iter().all(|b| b.verdict == Condition::Good),
            "{:?}",
            d.bearings
        );
        assert!(d.bearings[0].low_band_ratio > 50.0);
        assert!(d.bearings[0]
            .evidence
            .iter()
            .any(|e| e.contains("ball-pass timing")));
        assert_eq!(d.friction_psd.len(), 5);
        // The averaged spectrum of the bad bearing is its own (ranked first).
        assert!(d.friction_psd[0][10] > 50.0);
    }

    /// A flat PSD of 2 unit²/Hz on a 0.25 Hz grid holds 2 · 25 = 50 units²
    /// between 0 and 25 Hz (the DC bin excluded, the edge bin included).
    #[test]
    fn low_band_power_integrates_the_band() {
        let f: Vec<f64> = (0..200).map(|i| f64::from(i) * 0.25).collect();
        let p = vec![2.0; 200];
        assert_eq!(low_band_power(&f, &p, 25.0), 50.0);
        assert_eq!(low_band_power(&f[..1], &p[..1], 25.0), 0.0);
    }

    #[test]
    fn an_all_good_batch_has_nothing_bad() {
        let recs: Vec<RecordResult> = (1..=4)
            .flat_map(|b| {
                (1..=10).map(move |rep| {
                    bearing_record(&format!("b{b}"), rep, 1.0 + 0.1 * f64::from(b), 0)
                })
            })
            .collect();
        let refs: Vec<&RecordResult> = recs.iter().collect();
        let d = diagnose(&refs, &DiagnoseSettings::default());
        assert!(
            d.bearings.iter().all(|b| b.verdict == Condition::Good),
            "{:?}",
            d.bearings
        );
    }
}
