//! The load cell's time constant for the compensation (session 15).
//!
//! The table and its prediction come from the records' friction with the
//! quartz load cell's discharge undone ([`crate::analysis::load_cell`]).
//! A wrong τ leaves `(1/τ_used − 1/τ) ∫ f dt` in the friction: at the
//! ball-pass frequency a part `1/(ω_c τ)` of the ripple in quadrature,
//! which moves the table's fundamental where `ω_c τ` is small (slow runs,
//! fast discharges), and near stall the integral of the stalls' friction
//! spikes. The analysis fits τ from the record's decay, which needs the
//! friction's level to stay put; on a stalling record it does not.
//!
//! # The rule
//!
//! When τ is not given, each candidate `τ` of [`TAU_GRID_S`] (and the
//! friction as recorded, a DC-coupled sensor) is tried: the records'
//! friction restored with it (`super::travel::friction_of`), its level
//! fitted as the replay fits it (`super::replay::fit_levels`), and
//! replayed through the stage without a table. The replay then stands for
//! the stage moving under that friction; its synchronous velocity error
//! is compared with the records' (the encoder's, which the load cell does
//! not touch). The candidate whose replay agrees best is used:
//!
//! ```text
//! miss(τ) = |V_1,replay(τ) − V_1,records|        (fundamentals, µm/s)
//! τ*      = argmin miss(τ), refined between grid points ([`choose`])
//! ```
//!
//! The table is then built from the records analysed with `τ*`. Above
//! [`super::SEVERE_STALL_FRACTION`] of the velocity the replay does not
//! stand for the stage well enough to decide τ (on the design benches its
//! choice was 2–20 times off the simulated one on 5 of 6): there τ stays as the
//! analysis decided, and a warning says that τ is not decided by the
//! records and should be given.

use rayon::prelude::*;
use serde::Serialize;

use super::{replay, travel};
use crate::analysis::load_cell::LoadCellCorrection;
use crate::analysis::{Analysis, Signal};
use crate::model::stage::PdLoop;
use crate::recording::Recording;

/// The time constants tried, s: the verdicts' domain (0.3 s to 100 s),
/// log-spaced by a factor of 2^(1/2).
pub const TAU_GRID_S: [f64; 18] = [
    0.3, 0.424, 0.6, 0.849, 1.2, 1.70, 2.4, 3.39, 4.8, 6.79, 9.6, 13.6, 19.2, 27.2, 38.4, 54.3,
    76.8, 108.6,
];

/// One candidate's agreement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TauCandidate {
    /// The time constant, s (`None`: the friction as recorded).
    pub tau_s: Option<f64>,
    /// Amplitude of the difference between the fundamentals of the
    /// replay's velocity error without a table and the records', µm/s.
    pub f_c_miss_um_s: f64,
    /// Rms over the bins of the difference between the replay's mean
    /// velocity error over one period and the records', µm/s.
    pub waveform_miss_um_s: f64,
}

/// The correction that undoes `tau` (`None`: none).
pub(crate) fn correction(tau: Option<f64>) -> LoadCellCorrection {
    tau.map_or(LoadCellCorrection::Off, LoadCellCorrection::TimeConstant)
}

/// Each of `taus` tried on the records `recs` of the analysis `a`
/// (module docs), through `stage`; `refined` as the table's design.
///
/// # Errors
/// Why the replay cannot be made (as the design's).
pub(crate) fn scan(
    a: &Analysis,
    recs: &[Recording],
    stage: &PdLoop,
    refined: bool,
    taus: &[Option<f64>],
) -> Result<Scan, String> {
    let keys0 = travel::record_keys(recs, a, refined)?;
    let at = replay::DesignAt::of(a);
    let measured: Vec<f64> = a
        .sync
        .as_ref()
        .and_then(|s| s.waveform(Signal::VelocityError))
        .map(|w| {
            let m = w.mean.iter().sum::<f64>() / w.mean.len().max(1) as f64;
            w.mean.iter().map(|x| x - m).collect()
        })
        .ok_or("no synchronous velocity error")?;
    let m1 = crate::analysis::sync::coefficient(&measured, 1);
    // The candidates are independent: tried side by side, then taken in
    // order (the first candidate's error is the one returned).
    let tried: Vec<Tried> = taus
        .par_iter()
        .map(|&tau| try_one(tau, &keys0, recs, a, stage, &at, refined, &measured, m1))
        .collect();
    let mut out = Vec::with_capacity(taus.len());
    let mut replayed_v1 = Vec::with_capacity(taus.len());
    for t in tried {
        let (c, r1) = t?;
        out.push(c);
        replayed_v1.push(r1);
    }
    Ok(Scan {
        candidates: out,
        replayed_v1,
        measured_v1: m1,
    })
}

/// One candidate's agreement and its replayed fundamental, or why it
/// could not be replayed.
type Tried = Result<(TauCandidate, (f64, f64)), String>;

/// One candidate `tau` of [`scan`]: its agreement and its replayed
/// fundamental.
#[allow(clippy::too_many_arguments)]
fn try_one(
    tau: Option<f64>,
    keys0: &[travel::RecordKeys],
    recs: &[Recording],
    a: &Analysis,
    stage: &PdLoop,
    at: &replay::DesignAt,
    refined: bool,
    measured: &[f64],
    m1: (f64, f64),
) -> Tried {
    let mut keys = keys0.to_vec();
    for (k, r) in keys.iter_mut().zip(recs) {
        k.friction_n = travel::friction_of(r, a, correction(tau), refined)?;
    }
    if refined {
        replay::fit_levels(
            &mut keys,
            stage,
            at.pitch_mm,
            at.velocity_mm_s,
            &at.settings,
        )?;
    }
    let bare = replay::replay(
        &keys,
        stage,
        None,
        at.pitch_mm,
        at.velocity_mm_s,
        &at.settings,
    )?;
    let r1 = crate::analysis::sync::coefficient(&bare.waveform_um_s, 1);
    let waveform_miss_um_s = if bare.waveform_um_s.len() == measured.len() {
        (bare
            .waveform_um_s
            .iter()
            .zip(measured)
            .map(|(r, m)| (r - m).powi(2))
            .sum::<f64>()
            / measured.len() as f64)
            .sqrt()
    } else {
        f64::NAN
    };
    Ok((
        TauCandidate {
            tau_s: tau,
            f_c_miss_um_s: 2.0 * (m1.0 - r1.0).hypot(m1.1 - r1.1),
            waveform_miss_um_s,
        },
        r1,
    ))
}

/// The candidates' agreement, and the fundamentals behind it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Scan {
    /// Each candidate's agreement.
    pub candidates: Vec<TauCandidate>,
    /// Fundamental (coefficient) of each candidate's replayed velocity
    /// error without a table, µm/s.
    pub replayed_v1: Vec<(f64, f64)>,
    /// The same of the records', µm/s.
    pub measured_v1: (f64, f64),
}

/// How the τ undone for the compensation was decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TauSource {
    /// Given by the user (a time constant, or off for a DC-coupled sensor).
    Given,
    /// Chosen by the replay's agreement with the records (module docs).
    Replay,
    /// As the analysis decided from the record's decay (the replay could
    /// not be made).
    Analysis,
}

/// The load cell's τ the compensation used (`compensation.json`,
/// `load_cell`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoadCellUsed {
    /// The time constant undone, s (`None`: the friction as recorded).
    pub tau_s: Option<f64>,
    /// How it was decided.
    pub source: TauSource,
    /// The τ the analysis fitted from the records' decay and would have
    /// undone, s (`None`: none identified; first record).
    pub analysis_tau_s: Option<f64>,
    /// The candidates tried ([`TauSource::Replay`]; empty otherwise).
    pub candidates: Vec<TauCandidate>,
    /// Whether the records decide τ well enough for the table (module
    /// docs); `false` comes with a warning.
    pub determined: bool,
    /// In words.
    pub note: String,
}

impl LoadCellUsed {
    /// As the analysis `a` undid it (τ given by the user, or the
    /// analysis' own decision), `source` saying which.
    pub(crate) fn of_analysis(a: &Analysis, source: TauSource, why: &str) -> Self {
        let first = a.load_cell.first();
        let tau_s = first.and_then(|d| d.tau_s);
        Self {
            tau_s,
            source,
            analysis_tau_s: analysis_tau_s(a),
            candidates: Vec::new(),
            determined: true,
            note: format!(
                "{}{why}",
                first.map_or("no friction channel".to_string(), |d| d.note.clone())
            ),
        }
    }
}

/// The τ the analysis `a` fitted from the records' decay (first record),
/// s; `None` when it identified none.
pub(crate) fn analysis_tau_s(a: &Analysis) -> Option<f64> {
    a.load_cell
        .first()
        .and_then(|d| d.fit.as_ref().filter(|f| f.identified).map(|f| f.tau_s))
}

/// Candidates in the order tried: the friction as recorded, then
/// [`TAU_GRID_S`].
pub(crate) fn candidates() -> Vec<Option<f64>> {
    std::iter::once(None)
        .chain(TAU_GRID_S.iter().map(|&t| Some(t)))
        .collect()
}

/// The rule (module docs) on the scan `sc`: the τ (`None`: the friction
/// as recorded) whose replayed fundamental is nearest the records',
/// between the two grid points about the best one. A wrong τ adds to the
/// friction a part proportional to `1/τ_used − 1/τ`, so between grid
/// points the replayed fundamental is taken linear in `x = 1/τ` (the
/// friction as recorded at `x = 0`), and `x` is the point of that segment
/// nearest the records' fundamental. `None` when no candidate was
/// replayed.
pub(crate) fn choose(sc: &Scan) -> Option<Option<f64>> {
    let x = |t: Option<f64>| t.map_or(0.0, |t| 1.0 / t);
    // Candidates ordered by x, with their fundamentals.
    let mut pts: Vec<(f64, (f64, f64), f64)> = sc
        .candidates
        .iter()
        .zip(&sc.replayed_v1)
        .filter(|(c, _)| c.f_c_miss_um_s.is_finite())
        .map(|(c, &r)| (x(c.tau_s), r, c.f_c_miss_um_s))
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (ib, best) = pts
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .2.total_cmp(&b.1 .2))?;
    let m = sc.measured_v1;
    let mut pick = (best.0, best.2);
    for j in [ib.wrapping_sub(1), ib + 1] {
        let Some(other) = pts.get(j) else { continue };
        let d = (other.1 .0 - best.1 .0, other.1 .1 - best.1 .1);
        let n2 = d.0 * d.0 + d.1 * d.1;
        if n2 <= 0.0 {
            continue;
        }
        let e = (m.0 - best.1 .0, m.1 - best.1 .1);
        let t = ((e.0 * d.0 + e.1 * d.1) / n2).clamp(0.0, 1.0);
        let miss = 2.0 * (e.0 - t * d.0).hypot(e.1 - t * d.1);
        if miss < pick.1 {
            pick = (best.0 + t * (other.0 - best.0), miss);
        }
    }
    Some((pick.0 > 0.0).then(|| 1.0 / pick.0))
}

impl LoadCellUsed {
    /// Chosen by the replay: `tau_s` of `candidates`.
    pub(crate) fn chosen(
        tau_s: Option<f64>,
        determined: bool,
        analysis_tau_s: Option<f64>,
        candidates: Vec<TauCandidate>,
    ) -> Self {
        let what = tau_s.map_or_else(
            || "the friction taken as recorded (no discharge undone)".to_string(),
            |t| format!("the load cell's discharge undone with τ = {t:.3} s"),
        );
        let fitted = analysis_tau_s.map_or_else(
            || "the records' decay identified none".to_string(),
            |t| format!("the records' decay gave {t:.3} s"),
        );
        let note = if determined {
            format!(
                "{what}: of the friction as recorded and τ from {} to {} s, the one with which \
                 the replay through the stage gives the records' velocity error best ({fitted})",
                TAU_GRID_S[0],
                TAU_GRID_S[TAU_GRID_S.len() - 1]
            )
        } else {
            format!("{what}: the records do not decide the load cell's τ ({fitted}); give it")
        };
        Self {
            tau_s,
            source: TauSource::Replay,
            analysis_tau_s,
            candidates,
            determined,
            note,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scan whose replayed fundamental is exactly linear in `1/τ`
    /// (the friction's error is `(1/τ_used − 1/τ) ∫ f dt`), equal to the
    /// records' at `tau`.
    fn linear_scan(tau: Option<f64>) -> Scan {
        let x0 = tau.map_or(0.0, |t| 1.0 / t);
        let m = (3.0, -2.0);
        let slope = (40.0, 25.0);
        let taus = candidates();
        let replayed_v1: Vec<(f64, f64)> = taus
            .iter()
            .map(|t| {
                let dx = t.map_or(0.0, |t| 1.0 / t) - x0;
                (m.0 + slope.0 * dx, m.1 + slope.1 * dx)
            })
            .collect();
        Scan {
            candidates: taus
                .iter()
                .zip(&replayed_v1)
                .map(|(&tau_s, r)| TauCandidate {
                    tau_s,
                    f_c_miss_um_s: 2.0 * (r.0 - m.0).hypot(r.1 - m.1),
                    waveform_miss_um_s: f64::NAN,
                })
                .collect(),
            replayed_v1,
            measured_v1: m,
        }
    }

    #[test]
    fn the_rule_finds_a_time_constant_between_grid_points() {
        // Exact up to rounding: the segment holds the records' fundamental.
        for tau in [0.35, 0.5, 1.0, 2.0, 7.3, 10.0, 45.0, 90.0] {
            let got = choose(&linear_scan(Some(tau))).unwrap().unwrap();
            assert!((got / tau - 1.0).abs() < 1e-9, "{tau} → {got}");
        }
    }

    #[test]
    fn the_rule_takes_the_friction_as_recorded_for_a_dc_coupled_sensor() {
        assert_eq!(choose(&linear_scan(None)), Some(None));
        // Outside the grid: the nearest end (0.3 s).
        let got = choose(&linear_scan(Some(0.1))).unwrap().unwrap();
        assert!((got - 0.3).abs() < 1e-12, "{got}");
    }

    #[test]
    fn no_replayed_candidate_gives_no_choice() {
        let mut sc = linear_scan(Some(1.0));
        for c in &mut sc.candidates {
            c.f_c_miss_um_s = f64::NAN;
        }
        assert_eq!(choose(&sc), None);
    }
}
