//! The bearing diagnosis on randomized fleets: five bearings on one drawn
//! bench, each with its own small departures, none, one or two of them
//! sticking; every record simulated, run through the campaign's per-record
//! work and diagnosed together, and each verdict scored against the
//! simulator's truth.

use rayon::prelude::*;
use serde::Serialize;

use super::bench::{Bench, Domain};
use super::score::Rate;
use crate::campaign::diagnose::{diagnose, Condition, DiagnoseSettings};
use crate::campaign::run::{entry_for, process_recording, CampaignSettings};
use crate::sim::rng::{derive_seed, Rng};
use crate::sim::simulate;

/// How fleets are drawn.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FleetSpec {
    /// Bearings per fleet.
    pub bearings: usize,
    /// Fewest and most repeats per bearing.
    pub repeats: (u32, u32),
    /// Chance that a fleet has one sticking bearing (else none; a tenth of
    /// those with one have a second).
    pub sticking_fleet_probability: f64,
}

impl Default for FleetSpec {
    fn default() -> Self {
        Self {
            bearings: 5,
            repeats: (2, 10),
            sticking_fleet_probability: 0.7,
        }
    }
}

/// One bearing of a scored fleet.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BearingOutcome {
    /// Index in the fleet.
    pub index: usize,
    /// Whether it really sticks.
    pub sticks: bool,
    /// Its sticking severity (0 mild to 1 severe), when it sticks.
    pub severity: Option<f64>,
    /// The verdict.
    pub verdict: Condition,
    /// Periods examined.
    pub periods: usize,
    /// Spikes counted, and the count that makes it bad.
    pub spikes: (usize, usize),
    /// Typical period over the batch's.
    pub typical_over_batch: Option<f64>,
    /// Spread over the batch's.
    pub spread_over_batch: Option<f64>,
}

/// One scored fleet.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FleetOutcome {
    /// The bench.
    pub bench: Bench,
    /// Repeats per bearing.
    pub repeats: u32,
    /// Its bearings (empty when the fleet could not be analysed).
    pub bearings: Vec<BearingOutcome>,
    /// Why not, if so.
    pub error: Option<String>,
}

/// Draws and diagnoses one fleet (deterministic in `seed`).
pub fn run_fleet(domain: &Domain, spec: &FleetSpec, seed: u64) -> FleetOutcome {
    let bench = domain.draw(seed);
    let mut r = Rng::stream(seed, 77);
    let (lo, hi) = spec.repeats;
    let repeats = lo + ((r.uniform() * f64::from(hi - lo + 1)) as u32).min(hi - lo);
    let n_stick = if r.uniform() < spec.sticking_fleet_probability {
        if r.uniform() < 0.1 {
            2
        } else {
            1
        }
    } else {
        0
    };
    let mut sticking: Vec<usize> = Vec::new();
    while sticking.len() < n_stick.min(spec.bearings) {
        let i = ((r.uniform() * spec.bearings as f64) as usize).min(spec.bearings - 1);
        if !sticking.contains(&i) {
            sticking.push(i);
        }
    }
    let draws: Vec<_> = (0..spec.bearings)
        .map(|i| bench.bearing(i as u64, sticking.contains(&i)))
        .collect();
    let settings = CampaignSettings::default();
    let jobs: Vec<(usize, u32)> = (0..spec.bearings)
        .flat_map(|b| (1..=repeats).map(move |k| (b, k)))
        .collect();
    let results: Result<Vec<_>, String> = jobs
        .par_iter()
        .map(|&(b, k)| {
            let s = bench.settings(
                &draws[b],
                derive_seed(seed, (b as u64) * 1000 + u64::from(k)),
            );
            let sim = simulate(&s).map_err(|e| e.to_string())?;
            let e = entry_for(
                std::path::Path::new(&format!("b{b}_r{k}")),
                &format!("b{b}"),
                bench.velocity_mm_s,
                k,
            );
            process_recording(&sim.recording, &e, bench.geometry, &settings)
                .map_err(|e| e.to_string())
        })
        .collect();
    let results = match results {
        Ok(r) => r,
        Err(e) => {
            return FleetOutcome {
                bench,
                repeats,
                bearings: Vec::new(),
                error: Some(e),
            }
        }
    };
    let refs: Vec<_> = results.iter().collect();
    let d = diagnose(&refs, &DiagnoseSettings::default());
    let mut bearings: Vec<BearingOutcome> = d
        .bearings
        .iter()
        .map(|b| {
            let index: usize = b.bearing[1..].parse().expect("b<index>");
            BearingOutcome {
                index,
                sticks: sticking.contains(&index),
                severity: draws[index].sticking.map(|s| s.severity),
                verdict: b.verdict,
                periods: b.periods,
                spikes: (b.spikes, b.spikes_for_bad),
                typical_over_batch: b.typical_over_batch,
                spread_over_batch: b.spread_over_batch,
            }
        })
        .collect();
    bearings.sort_by_key(|b| b.index);
    FleetOutcome {
        bench,
        repeats,
        bearings,
        error: None,
    }
}

/// The fleet verdicts' rates.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FleetScore {
    /// Fleets run.
    pub fleets: usize,
    /// Fleets that could not be analysed (with the first reason).
    pub failed: Vec<String>,
    /// Good bearings called bad.
    pub good_called_bad: Rate,
    /// Good bearings called suspect.
    pub good_called_suspect: Rate,
    /// Good bearings left inconclusive.
    pub good_inconclusive: Rate,
    /// Sticking bearings called bad, among those with enough periods for a
    /// verdict (not inconclusive).
    pub sticking_called_bad: Rate,
    /// Sticking bearings called bad or suspect, same.
    pub sticking_flagged: Rate,
    /// Sticking bearings left inconclusive (too few periods).
    pub sticking_inconclusive: Rate,
    /// Mild sticking (severity below 0.2) called bad, among those decided.
    pub mild_called_bad: Rate,
}

/// Scores fleets.
pub fn score(outcomes: &[FleetOutcome]) -> FleetScore {
    let all: Vec<&BearingOutcome> = outcomes.iter().flat_map(|f| &f.bearings).collect();
    let good: Vec<&&BearingOutcome> = all.iter().filter(|b| !b.sticks).collect();
    let stick: Vec<&&BearingOutcome> = all.iter().filter(|b| b.sticks).collect();
    let decided: Vec<&&&BearingOutcome> = stick
        .iter()
        .filter(|b| b.verdict != Condition::Inconclusive)
        .collect();
    let mild: Vec<&&&&BearingOutcome> = decided
        .iter()
        .filter(|b| b.severity.is_some_and(|s| s < 0.2))
        .collect();
    let count = |v: &[bool]| Rate::of(v.iter().filter(|x| **x).count(), v.len());
    FleetScore {
        fleets: outcomes.len(),
        failed: outcomes.iter().filter_map(|f| f.error.clone()).collect(),
        good_called_bad: count(
            &good
                .iter()
                .map(|b| b.verdict == Condition::Bad)
                .collect::<Vec<_>>(),
        ),
        good_called_suspect: count(
            &good
                .iter()
                .map(|b| b.verdict == Condition::Suspect)
                .collect::<Vec<_>>(),
        ),
        good_inconclusive: count(
            &good
                .iter()
                .map(|b| b.verdict == Condition::Inconclusive)
                .collect::<Vec<_>>(),
        ),
        sticking_called_bad: count(
            &decided
                .iter()
                .map(|b| b.verdict == Condition::Bad)
                .collect::<Vec<_>>(),
        ),
        sticking_flagged: count(
            &decided
                .iter()
                .map(|b| b.verdict >= Condition::Suspect)
                .collect::<Vec<_>>(),
        ),
        sticking_inconclusive: count(
            &stick
                .iter()
                .map(|b| b.verdict == Condition::Inconclusive)
                .collect::<Vec<_>>(),
        ),
        mild_called_bad: count(
            &mild
                .iter()
                .map(|b| b.verdict == Condition::Bad)
                .collect::<Vec<_>>(),
        ),
    }
}
