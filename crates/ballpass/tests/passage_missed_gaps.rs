//! Passages missed under a drift almost in step with the pulse train
//! (session 20): `fresh10`'s record 15 500 028 (skewed pulses of 0.44 τ_c
//! that never fall to the dark level, SNR 20, DC coupled, a drift of 0.40
//! pulse heights at 1.14 τ_c, 89 s at 1 kHz, 18 passages). The detector
//! of session 19 found 3 of them, 5.9 and 2.0 predicted periods apart, and
//! blamed the velocity and the geometry (a period mismatch of −75 %).

use ballpass::analysis::passage::{detect_passages, ConditionKind, PassageSettings};
use ballpass::sim::simulate;
use ballpass::validate::Domain;

/// The passages missed are reported as missed, and the period mismatch,
/// if any, points at the optical signal, not at the velocity.
#[test]
fn passages_missed_under_a_drift_in_step_are_not_blamed_on_the_velocity() {
    let seed = 15_500_028;
    let bench = Domain::default().draw(seed);
    let sim = simulate(&bench.settings(&bench.bearing(0, false), seed)).expect("simulates");
    let settings = PassageSettings {
        geometry: Some(bench.geometry),
        ..PassageSettings::default()
    };
    let a = detect_passages(&sim.recording, &settings).expect("passages found");
    let has = |k| a.conditions.iter().any(|c| c.kind == k);
    if let Some(m) = a
        .conditions
        .iter()
        .find(|c| c.kind == ConditionKind::PeriodMismatch)
    {
        assert!(
            !m.advice.starts_with("check the tracking velocity"),
            "{}",
            m.advice
        );
    }
    let missed = a
        .conditions
        .iter()
        .find(|c| c.kind == ConditionKind::MissedPassages);
    // The record holds 18 passages; fewer found means some were missed,
    // which must be said.
    assert!(
        a.count >= 18 || missed.is_some(),
        "{} found, {:?}",
        a.count,
        a.conditions
    );
    assert!(!has(ConditionKind::InvertedPulses));
}
