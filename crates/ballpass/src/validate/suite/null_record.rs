//! One ripple-free record of the periodicity part, in detail (parent
//! module docs): the bench, the friction periodicity claim and its
//! statistic, and every coherence row with its level.

use serde::Serialize;

use super::super::bench::Domain;
use crate::analysis::{analyze, AnalyzeSettings};
use crate::sim::simulate;

/// One ripple-free record of the periodicity part in detail: the bench,
/// the friction periodicity claim and its statistic, and every coherence
/// row (per-record counting of the false alarms).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NullRecord {
    /// Bench seed.
    pub seed: u64,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Record length, s.
    pub duration_s: f64,
    /// Predicted ball-pass periods in the record.
    pub periods: f64,
    /// Segment length of the high-resolution spectrum, samples (after its
    /// decimation).
    pub hires_nperseg: usize,
    /// Its segments per record.
    pub hires_segments: usize,
    /// Its bin width, Hz.
    pub hires_resolution_hz: f64,
    /// The simulated load cell's discharge time constant, s (`None`: DC
    /// coupled).
    pub load_cell_tau_s: Option<f64>,
    /// The time constant the analysis undid (`None`: no restoration).
    pub load_cell_restored_tau_s: Option<f64>,
    /// Whether the analysis claimed that friction shows f_c.
    pub friction_claimed: bool,
    /// The claim's statistic: the smallest p-value of friction's harmonic
    /// tests (the claim is made when it is at most `α / friction_tests`,
    /// Holm's first step).
    pub friction_p_min: Option<f64>,
    /// Friction harmonics tested.
    pub friction_tests: usize,
    /// Every coherence row with a level.
    pub rows: Vec<NullRow>,
}

/// One coherence row of a [`NullRecord`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NullRow {
    /// Pair name.
    pub pair: String,
    /// Harmonic number.
    pub k: usize,
    /// Frequency examined, Hz.
    pub f_hz: f64,
    /// The same in high-resolution bins (`f_hz / hires_resolution_hz`).
    pub bins: f64,
    /// Coherence (largest of the three bins nearest `k f_c`).
    pub coherence: f64,
    /// The row's level.
    pub threshold: f64,
    /// `coherence > threshold`.
    pub significant: bool,
}

/// One ripple-free record (`None`: shorter than two periods).
pub(super) fn null_record(
    d: &Domain,
    duration_s: f64,
    seed: u64,
) -> Result<Option<NullRecord>, String> {
    let mut b = d.draw(seed);
    let mut s = b.settings(&b.bearing(0, false), seed);
    // Long records at the lowest rate of the domain keep the
    // suite's memory and time bounded (the test's statistics
    // depend on the record's periods, not its rate).
    if duration_s > 300.0 {
        b.fs_hz = d.fs_hz.iter().copied().fold(f64::INFINITY, f64::min);
        s.fs_hz = b.fs_hz;
    }
    let sim = simulate(&s).map_err(|e| format!("bench {seed}: {e}"))?;
    let pred = b
        .geometry
        .predict(b.velocity_mm_s, 5)
        .map_err(|e| format!("bench {seed}: {e}"))?;
    // The analysis refuses a record of fewer than two periods
    // (rightly: nothing to claim), counted apart.
    if s.duration_s < 2.0 * pred.tau_c_s {
        return Ok(None);
    }
    let a = analyze(
        std::slice::from_ref(&sim.recording),
        &pred,
        &AnalyzeSettings::default(),
    )
    .map_err(|e| format!("bench {seed}: {e}"))?;
    let h = &a.spectrum_hires;
    let p: Vec<f64> = a
        .harmonics
        .iter()
        .filter(|r| r.signal == crate::analysis::Signal::Friction)
        .filter_map(|r| r.value().and_then(|v| v.p_value))
        .collect();
    let rows = a
        .coherence
        .iter()
        .filter_map(|r| {
            Some(NullRow {
                pair: r.pair.clone(),
                k: r.k,
                f_hz: r.f_hz,
                bins: r.f_hz / h.resolution_hz,
                coherence: r.coherence,
                threshold: r.threshold?,
                significant: r.significant?,
            })
        })
        .collect();
    Ok(Some(NullRecord {
        seed,
        fs_hz: s.fs_hz,
        duration_s: s.duration_s,
        periods: a.periods_in_record,
        hires_nperseg: h.nperseg,
        hires_segments: h.n_segments,
        hires_resolution_hz: h.resolution_hz,
        load_cell_tau_s: s.load_cell.time_constant_s,
        load_cell_restored_tau_s: a
            .load_cell
            .first()
            .filter(|d| d.applied)
            .and_then(|d| d.tau_s),
        friction_claimed: !a.verdict.friction_harmonics_flagged.is_empty(),
        friction_p_min: p.iter().copied().reduce(f64::min),
        friction_tests: p.len(),
        rows,
    }))
}
