//! The conditions a record shows (module docs of [`super`], "Conditions
//! reported"), each with what it means and the thesis' fix.

use super::{Condition, ConditionKind, Passage};

/// What the conditions are judged on.
pub(super) struct Inputs<'a> {
    /// The passages, in time order.
    pub passages: &'a [Passage],
    /// Time to the next passage of each passage but the last, s.
    pub tau_c_all: &'a [f64],
    /// Their median, s.
    pub med_tau: f64,
    /// Baseline under the pulses (of the restored signal), per block.
    pub baseline: &'a [f64],
    /// Blocks per ball-pass period.
    pub blocks_per_period: f64,
    /// Median pulse amplitude, V.
    pub med_amp: f64,
    /// Noise of one block of the signal, V.
    pub block_noise: f64,
    /// AC coupling undone: time constant, s, and the dip each pulse left
    /// (its area over the time constant), in pulse heights.
    pub ac: Option<(f64, f64)>,
    /// Measured and predicted ball-pass frequencies, Hz.
    pub f_c: f64,
    pub f_c_predicted: Option<f64>,
    /// The longest period one ball spacing can give (all the race's free
    /// space in one gap: `(d + d_ext) / (v/2)`), s, when the velocity and
    /// geometry are known.
    pub tau_single_max: Option<f64>,
    /// The widths were withheld: the median bend of the baseline under a
    /// pulse, in pulse heights (`withhold.rs`).
    pub withheld_bend: Option<f64>,
    /// The widths were withheld: the standard error of the mean width
    /// from their scatter beyond noise, relative (`withhold.rs`).
    pub withheld_scatter_se: Option<f64>,
}

/// Smallest dip per pulse, in pulse heights, for the AC coupling to be
/// reported (its effect on the widths is undone either way). The template
/// of a DC-coupled record can end a fraction of a percent lower than it
/// starts (its ends lie in the pulse's tails when the pulses are wide),
/// which reads as a coupling of `T` ten or more periods long; that small a
/// dip moves the widths by less than 0.5 %, and is not worth a warning.
pub(super) const AC_DIP_REPORTED: f64 = 0.02;

/// How far from a whole number of predicted periods a gap may be and
/// still count as that many periods (`missed_against_prediction`). A
/// gap of one passage's period varies with the balls' spacing (from the
/// ball diameter to it plus the free space, around `d_avg`) and the
/// stage's velocity ripple, by a few percent; a quarter period keeps the
/// multiples apart (a gap halfway between two is neither).
const MULTIPLE_TOLERANCE: f64 = 0.25;

const MISSED_ADVICE: &str = "weak passages fall below the threshold: lower min_snr only if the noise allows; fading pulses with a laser source are the interference of thesis Fig. 32 (use an LED)";

/// Passages missed, judged against the period `tau_predicted` that the
/// velocity and geometry predict rather than the median of the gaps found
/// (which, from two or three gaps, is no period): `(gaps, passages
/// missed)` when every gap lies within [`MULTIPLE_TOLERANCE`] of a whole
/// number `n ≥ 1` of predicted periods, some `n ≥ 2`, and not every `n`
/// the same. The last clause keeps a wrong velocity or geometry out: a
/// train whose every gap is `n` predicted periods is a prediction `n`
/// times off as much as every `n`-th passage missed, which the period
/// mismatch reports; gaps of different whole numbers of periods are not
/// one period, whatever the scale. A gap that one ball spacing could give
/// (at most `tau_single_max`: all the free space in one gap) is never
/// counted as two or more periods; the rule then abstains.
fn missed_against_prediction(
    tau_c_all: &[f64],
    tau_predicted: f64,
    tau_single_max: Option<f64>,
) -> Option<(usize, f64)> {
    if !(tau_predicted.is_finite() && tau_predicted > 0.0) {
        return None;
    }
    let mut multiples = Vec::with_capacity(tau_c_all.len());
    for &t in tau_c_all {
        let r = t / tau_predicted;
        let n = r.round();
        if n < 1.0 || (r - n).abs() > MULTIPLE_TOLERANCE {
            return None;
        }
        if n >= 2.0 && tau_single_max.is_some_and(|m| t <= m) {
            return None;
        }
        multiples.push(n);
    }
    let first = *multiples.first()?;
    if multiples.iter().all(|&n| n == first) {
        return None;
    }
    let long = multiples.iter().filter(|&&n| n >= 2.0).count();
    let missing: f64 = multiples.iter().map(|n| n - 1.0).sum();
    (long > 0).then_some((long, missing))
}

/// Baseline wander reported above this fraction of the median pulse.
const DRIFT_FRACTION: f64 = 0.2;

pub(super) fn conditions(c: &Inputs) -> Vec<Condition> {
    let mut out = Vec::new();
    let n_inv = c.passages.iter().filter(|p| p.polarity < 0).count();

    // Baseline drift: the baseline's range, half a period in from either end.
    let skip = (0.5 * c.blocks_per_period).round() as usize;
    let inner = if c.baseline.len() > 2 * skip + 2 {
        &c.baseline[skip..c.baseline.len() - skip]
    } else {
        c.baseline
    };
    if !inner.is_empty() {
        let hi = inner.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
        let lo = inner.iter().fold(f64::INFINITY, |a, &b| a.min(b));
        let range = hi - lo;
        if range > DRIFT_FRACTION * c.med_amp && range > 5.0 * c.block_noise {
            out.push(Condition {
                kind: ConditionKind::BaselineDrift,
                measure: range / c.med_amp,
                message: format!(
                    "the level under the pulses wanders by {range:.3e} V ({:.0}% of the median pulse) over the record",
                    100.0 * range / c.med_amp
                ),
                advice: "pulses were measured against the fitted baseline, so counts and widths hold; a wandering level with a laser source is the strain-dependent interference of thesis §5.2 (Figs. 32, 36): use an incoherent source (LED, thesis §5.3) and keep the fibre still".into(),
            });
        }
    }

    if let Some(bend) = c.withheld_bend {
        out.push(Condition {
            kind: ConditionKind::WidthsWithheld,
            measure: bend,
            message: format!(
                "the level under the pulses bends by {:.0}% of a pulse across a pulse (median over the pulses): the baseline moves as fast as the pulses, and a width cannot be told from it; the widths tau_p are withheld (counts and times hold)",
                100.0 * bend
            ),
            advice: "a level that moves within a pulse with a laser source is the strain-dependent interference of thesis §5.2 (Figs. 32, 36): use an incoherent source (LED, thesis §5.3), keep the fibre still, and record again to measure widths".into(),
        });
    }

    if let Some(se) = c.withheld_scatter_se {
        out.push(Condition {
            kind: ConditionKind::WidthsWithheld,
            measure: se,
            message: format!(
                "the widths disagree from pulse to pulse by more than their noise explains, which leaves their mean uncertain by {:.1}% (one standard error): a level that moves at the pulses' own scale reads as wider or narrower pulses; the widths tau_p are withheld (counts and times hold)",
                100.0 * se
            ),
            advice: "a level that moves within a pulse with a laser source is the strain-dependent interference of thesis §5.2 (Figs. 32, 36): use an incoherent source (LED, thesis §5.3), keep the fibre still, and record again to measure widths".into(),
        });
    }

    if let Some((tau, dip)) = c.ac {
        if dip >= AC_DIP_REPORTED {
            out.push(Condition {
                kind: ConditionKind::AcCoupling,
                measure: dip,
                message: format!(
                    "the photodetector was AC coupled (time constant {tau:.3} s): each pulse pulled the level after it down by {:.1}% of its height (thesis Fig. 38); the coupling was undone before the pulses were measured",
                    100.0 * dip
                ),
                advice: "record the photodetector DC coupled (thesis Fig. 39): ballpass undid a first-order coupling, but a coupling of another order would leave the widths tau_p and the fits of this record biased".into(),
            });
        }
    }

    if n_inv > 0 {
        out.push(Condition {
            kind: ConditionKind::InvertedPulses,
            measure: n_inv as f64 / c.passages.len() as f64,
            message: format!(
                "{n_inv} of {} passages are inverted pulses: interference between the incident and reflected light of a coherent source (thesis Fig. 32)",
                c.passages.len()
            ),
            advice: "use an incoherent light source (LED, thesis §5.3) or multimode fibre; AC coupling does not cure it. Amplitudes of this record are not comparable between passages; inverted passages are counted and timed, polarity −1".into(),
        });
    }

    // Missed passages: against the predicted period where it tells, else
    // against the median gap found.
    let against_prediction = c.f_c_predicted.and_then(|p| {
        let tau_p = 1.0 / p;
        let (n_long, missing) =
            missed_against_prediction(c.tau_c_all, tau_p, c.tau_single_max)?;
        Some((
            missing,
            format!(
                "{n_long} gap(s) of two or more of the periods the velocity and geometry predict ({tau_p:.4} s), every gap a whole number of them: about {missing:.0} passage(s) too weak to detect"
            ),
        ))
    });
    let missed = against_prediction.or_else(|| {
        let long: Vec<f64> = c
            .tau_c_all
            .iter()
            .copied()
            .filter(|t| *t >= 1.6 * c.med_tau)
            .collect();
        let missing: f64 = long.iter().map(|t| (t / c.med_tau).round() - 1.0).sum();
        (!long.is_empty()).then(|| {
            (
                missing,
                format!(
                    "{} gap(s) of 1.6 periods or more: about {missing:.0} passage(s) too weak to detect",
                    long.len()
                ),
            )
        })
    });
    if let Some((missing, message)) = missed {
        out.push(Condition {
            kind: ConditionKind::MissedPassages,
            measure: missing,
            message,
            advice: MISSED_ADVICE.into(),
        });
    }

    if let Some(p) = c.f_c_predicted {
        let e = (c.f_c - p) / p;
        if e.abs() > 0.2 {
            // With pulses inverted or missed, the passages found are not
            // every ball's, and their period is not the balls' either.
            let symptom = out.iter().any(|k| {
                matches!(
                    k.kind,
                    ConditionKind::InvertedPulses | ConditionKind::MissedPassages
                )
            });
            out.push(Condition {
                kind: ConditionKind::PeriodMismatch,
                measure: e,
                message: format!(
                    "measured f_c = {:.4} Hz is {:+.0}% from the predicted {p:.4} Hz",
                    c.f_c,
                    100.0 * e
                ),
                advice: if symptom {
                    "the passages found are not every ball's (see the inverted or missed passages reported): fix the optical signal first; the measured f_c of this record is not the bearing's".into()
                } else {
                    "check the tracking velocity and the bearing geometry given; passages closer than 0.7 predicted periods are merged".into()
                },
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn passage(i: usize, polarity: i8) -> Passage {
        Passage {
            index: i,
            time_s: i as f64,
            peak_time_s: i as f64,
            polarity,
            tau_c_s: Some(1.0),
            tau_p_s: 0.1,
            sigma_s: 0.04,
            amplitude_v: 0.5 * f64::from(polarity),
            height_v: 0.5,
            tau_p_over_tau_c: Some(0.1),
            spacing_mm: None,
            edge: false,
            width_used: true,
        }
    }

    fn mismatch_advice(passages: &[Passage], tau_c_all: &[f64]) -> String {
        let baseline = vec![0.0; 100];
        let out = conditions(&Inputs {
            passages,
            tau_c_all,
            med_tau: 1.0,
            baseline: &baseline,
            blocks_per_period: 10.0,
            med_amp: 0.5,
            block_noise: 0.01,
            ac: None,
            f_c: 1.0,
            // Predicted 1.4 Hz: the measured period is 40 % long.
            f_c_predicted: Some(1.4),
            tau_single_max: None,
            withheld_bend: None,
            withheld_scatter_se: None,
        });
        let m = out
            .iter()
            .find(|c| c.kind == ConditionKind::PeriodMismatch)
            .expect("a 29 % mismatch is reported");
        m.advice.clone()
    }

    /// A period far from the prediction points at the velocity and the
    /// geometry only when every ball's pulse was found; with pulses
    /// inverted or missed, at the optical signal.
    #[test]
    fn period_mismatch_advice_follows_its_cause() {
        let clean: Vec<Passage> = (0..10).map(|i| passage(i, 1)).collect();
        let ones = vec![1.0; 9];
        assert!(mismatch_advice(&clean, &ones).starts_with("check the tracking velocity"));

        let mut inverted = clean.clone();
        inverted[4].polarity = -1;
        assert!(mismatch_advice(&inverted, &ones).contains("fix the optical signal first"));

        let mut gaps = ones.clone();
        gaps[3] = 2.0;
        assert!(mismatch_advice(&clean, &gaps).contains("fix the optical signal first"));
    }

    fn kinds(tau_c_all: &[f64], f_c: f64, f_c_predicted: f64) -> Vec<Condition> {
        kinds_max(tau_c_all, f_c, f_c_predicted, 1.45)
    }

    fn kinds_max(
        tau_c_all: &[f64],
        f_c: f64,
        f_c_predicted: f64,
        tau_single_max: f64,
    ) -> Vec<Condition> {
        let passages: Vec<Passage> = (0..=tau_c_all.len()).map(|i| passage(i, 1)).collect();
        let baseline = vec![0.0; 100];
        let mut sorted = tau_c_all.to_vec();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let med_tau = 0.5 * (sorted[(n - 1) / 2] + sorted[n / 2]);
        conditions(&Inputs {
            passages: &passages,
            tau_c_all,
            med_tau,
            baseline: &baseline,
            blocks_per_period: 10.0,
            med_amp: 0.5,
            block_noise: 0.01,
            ac: None,
            f_c,
            f_c_predicted: Some(f_c_predicted),
            tau_single_max: Some(tau_single_max),
            withheld_bend: None,
            withheld_scatter_se: None,
        })
    }

    /// Two gaps of 5.9 and 2.0 predicted periods (fresh10's record
    /// 15 500 028: 3 of 18 passages found): their median is no period,
    /// so the long one is not 1.6 medians; against the prediction both are
    /// whole numbers of periods, different ones, and the passages missed
    /// are reported, with the period mismatch's advice at the optical
    /// signal, not at the velocity.
    #[test]
    fn gaps_of_whole_predicted_periods_are_missed_passages() {
        let out = kinds(&[5.9, 2.0], 1.0 / 3.95, 1.0);
        let missed = out
            .iter()
            .find(|c| c.kind == ConditionKind::MissedPassages)
            .expect("missed passages reported");
        assert_eq!(missed.measure, 6.0);
        let m = out
            .iter()
            .find(|c| c.kind == ConditionKind::PeriodMismatch)
            .expect("the mismatch is still reported");
        assert!(m.advice.contains("fix the optical signal first"));
    }

    /// Every gap the same whole number of predicted periods: a velocity or
    /// geometry that many times off as much as passages missed; the period
    /// mismatch points at the velocity, as before. A gap between two whole
    /// numbers keeps the prediction out too.
    #[test]
    fn a_train_uniformly_off_the_prediction_is_a_period_mismatch() {
        for gaps in [&[2.02, 1.97, 2.05, 1.99][..], &[3.1, 2.9], &[2.0, 1.5, 1.0]] {
            let f_c = gaps.len() as f64 / gaps.iter().sum::<f64>();
            let out = kinds(gaps, f_c, 1.0);
            assert!(
                !out.iter().any(|c| c.kind == ConditionKind::MissedPassages),
                "{gaps:?}"
            );
            let m = out
                .iter()
                .find(|c| c.kind == ConditionKind::PeriodMismatch)
                .expect("mismatch");
            assert!(
                m.advice.starts_with("check the tracking velocity"),
                "{gaps:?}"
            );
        }
        // A gap one ball spacing can give (all the free space in one gap)
        // is not two periods, whatever the prediction says: the rule
        // abstains (and two gaps have no median to judge by).
        let out = kinds_max(&[1.0, 1.8], 2.0 / 2.8, 1.0, 1.85);
        assert!(!out.iter().any(|c| c.kind == ConditionKind::MissedPassages));
        let out = kinds_max(&[1.0, 1.8], 2.0 / 2.8, 1.0, 1.45);
        assert!(out.iter().any(|c| c.kind == ConditionKind::MissedPassages));
        // A train a predicted period apart with one passage missed: the
        // same count either way.
        let out = kinds(&[1.0, 1.02, 2.01, 0.98], 1.0, 1.0);
        let missed = out
            .iter()
            .find(|c| c.kind == ConditionKind::MissedPassages)
            .expect("missed");
        assert_eq!(missed.measure, 1.0);
    }
}
