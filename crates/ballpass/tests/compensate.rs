//! The compensation table in closed loop on the simulator (issue 17); the
//! randomized rates are measured by `benches/compensate/`.

use ballpass::model::compensate::compensate;
use ballpass::model::stage::PdLoop;
use ballpass::sim::{simulate, Condition, SimSettings};
use ballpass::validate::compensation::check;

fn bench(condition: Condition, seed: u64) -> SimSettings {
    SimSettings {
        velocity_mm_s: 20.0,
        condition,
        seed,
        ..Default::default()
    }
}

#[test]
fn the_table_cancels_a_good_bearings_ripple_in_closed_loop() {
    let c = check(&bench(Condition::Good, 11)).unwrap();
    // The goals on one good bench: ≥ 80 % of the f_c component
    // gone, the std down, the std predicted within 20 %.
    assert!(c.f_c_reduction() >= 0.8, "{c:?}");
    assert!(c.std_after_um_s < c.std_before_um_s, "{c:?}");
    assert!(c.std_prediction_error() <= 0.2, "{c:?}");
}

#[test]
fn a_sticking_bearings_mean_spike_is_compensated_too() {
    // The random part of the spikes stays; the mean at f_c goes. Half is
    // a floor well below what the benches show (0.74–0.94), above what a
    // table at the wrong phase could give (it would add, not remove).
    let c = check(&bench(Condition::Sticking, 12)).unwrap();
    assert!(c.f_c_reduction() >= 0.5, "{c:?}");
}

#[test]
fn the_table_is_written_with_its_units_and_spacing() {
    let s = bench(Condition::Good, 13);
    let sim = simulate(&s).unwrap();
    let pred = s.geometry.predict(20.0, 5).unwrap();
    let gains =
        PdLoop::from_products(s.stage.mass_kg, s.stage.kkp_n_per_m, s.stage.kkd_n_s_per_m).unwrap();
    let comp = compensate(
        std::slice::from_ref(&sim.recording),
        &pred,
        &Default::default(),
        Some(gains),
    )
    .unwrap();
    assert_eq!(comp.force_n.len(), comp.bins);
    assert!((comp.phase_spacing * comp.bins as f64 - 1.0).abs() < 1e-12);
    // Zero mean: the table carries the ripple only.
    assert!(comp.force_n.iter().sum::<f64>().abs() < 1e-9);
    let dir = std::env::temp_dir().join(format!("ballpass-compensate-{}", std::process::id()));
    let files = comp.write(&dir).unwrap();
    let csv = std::fs::read_to_string(dir.join("compensation_phase.csv")).unwrap();
    assert!(
        csv.starts_with("phase,force_n,velocity_error_after_um_s\n"),
        "{csv}"
    );
    assert_eq!(csv.lines().count(), comp.bins + 1);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&files[0]).unwrap()).unwrap();
    assert_eq!(json["schema"], "ballpass.compensation/1");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn without_an_identified_stage_or_gains_it_says_what_to_give() {
    // 1 mm/s for 30 s: the friction barely excites the 1.1 Hz resonance.
    let s = SimSettings {
        velocity_mm_s: 1.0,
        duration_s: 400.0,
        seed: 14,
        ..Default::default()
    };
    let sim = simulate(&s).unwrap();
    let pred = s.geometry.predict(1.0, 5).unwrap();
    match compensate(
        std::slice::from_ref(&sim.recording),
        &pred,
        &Default::default(),
        None,
    ) {
        Ok(c) => assert_eq!(
            c.stage_source,
            ballpass::model::compensate::StageSource::Identified
        ),
        Err(e) => assert!(e.to_string().contains("give the loop gains"), "{e}"),
    }
}

#[test]
fn a_stage_that_nearly_stalls_is_flagged() {
    // A sticking bearing at 1.5 mm/s: velocity-error std near the velocity.
    let s = SimSettings {
        velocity_mm_s: 1.5,
        duration_s: 220.0,
        condition: Condition::Sticking,
        seed: 15,
        ..Default::default()
    };
    let sim = simulate(&s).unwrap();
    let pred = s.geometry.predict(1.5, 5).unwrap();
    let gains =
        PdLoop::from_products(s.stage.mass_kg, s.stage.kkp_n_per_m, s.stage.kkd_n_s_per_m).unwrap();
    let c = compensate(
        std::slice::from_ref(&sim.recording),
        &pred,
        &Default::default(),
        Some(gains),
    )
    .unwrap();
    let stalls =
        c.prediction.std_before_um_s * 1e-3 / 1.5 > ballpass::model::compensate::STALL_FRACTION;
    assert_eq!(
        c.warnings.first().is_some_and(|w| w.contains("stalls")),
        stalls,
        "{:?}",
        c.warnings
    );
    assert!(
        stalls,
        "std {} µm/s at 1.5 mm/s",
        c.prediction.std_before_um_s
    );
}

/// A simulated runaway (session 13): a near-stall sticking bench (2.43
/// mm/s, velocity-error std 0.8 of v; bench 5 of the compensation
/// benches' seed 17 000 000, cut to 16 s) on which the table built without
/// the guard raises the std by 60 % in closed loop. The product refuses a
/// table there (the replay says it makes the velocity error worse) and so
/// does not raise the std; a table given would have to lower it.
#[test]
fn a_near_stall_bench_whose_unguarded_table_runs_away_is_not_made_worse() {
    use ballpass::validate::compensation_guard::guard_check;
    let mut s = ballpass::validate::compensation::bench(17_000_000, 5);
    s.duration_s = 16.0;
    let g = guard_check(&s).unwrap();
    let p = &g.product;
    let u = g.unguarded.as_ref().expect("the guard changed the table");
    // The runaway is real: ≥ 30 % more std with the unguarded table (1.62
    // measured; a table that only missed the goal would not reach it).
    assert!(u.std_um_s > 1.3 * p.std_before_um_s, "{g:?}");
    // The product's std does not grow: equal when refused (the same
    // bench run again, the same seed), below when a table is given.
    if p.refused {
        assert!(
            (p.std_after_um_s - p.std_before_um_s).abs() <= 1e-9 * p.std_before_um_s,
            "{g:?}"
        );
    } else {
        assert!(p.std_after_um_s < p.std_before_um_s, "{g:?}");
    }
    assert!(p.std_after_um_s < u.std_um_s, "{g:?}");
}

/// The second round (session 14): a near-stall bench of the design seeds
/// (20 000 000, draw 67, 2.18 mm/s, std 63 % of v, cut to 60 s) on which
/// the product's table leaves a large part of the f_c component; the
/// table corrected from the run made with it leaves much less, and the
/// std stays where the first table put it.
#[test]
fn a_second_round_from_records_taken_with_the_table_lowers_the_f_c_component() {
    use ballpass::validate::compensation_second::second_round_check;
    let mut s = ballpass::validate::compensation::bench(20_000_000, 67);
    s.duration_s = 60.0;
    let c = second_round_check(&s).unwrap();
    let p = &c.first;
    let r = c.second.as_ref().expect("a table was given");
    // Measured (debug test profile): f_c 290.5 µm/s before, 178.8 with
    // the product's table (−38 %, a miss), 19.0 after the second round
    // (−93 %); std 1291 → 1148 → 1101 µm/s. The margins: the second round
    // at most half of the first's f_c (0.11 measured) and within the goal
    // (0.066 of before measured, the goal 0.2); the std below the one
    // without a table and within 10 % of the first round's (−4.1 %
    // measured; session 10 saw −8 to +1.5 % on 19 near-stall benches);
    // the std predicted (the first round's) within the 20 %.
    assert!(
        r.f_c_after_um_s < 0.5 * p.f_c_after_um_s,
        "second round did not halve the f_c component: {c:?}"
    );
    assert!(
        r.f_c_after_um_s <= 0.2 * p.f_c_before_um_s,
        "second round misses the goal: {c:?}"
    );
    assert!(r.std_after_um_s < p.std_before_um_s, "{c:?}");
    assert!(
        (r.std_after_um_s / p.std_after_um_s - 1.0).abs() < 0.1,
        "the std moved by more than 10 %: {c:?}"
    );
    assert!(
        (r.std_predicted_um_s / r.std_after_um_s - 1.0).abs() < 0.2,
        "std predicted not within 20 %: {c:?}"
    );
}

/// A table withheld (all zeros) is not refined: records taken without a
/// table say nothing of the compensated stage.
#[test]
fn a_second_round_on_a_withheld_table_is_refused_with_a_reason() {
    let s = bench(Condition::Good, 3);
    let sim = simulate(&s).unwrap();
    let pred = s.geometry.predict(s.velocity_mm_s, 5).unwrap();
    let a = ballpass::analysis::analyze(
        std::slice::from_ref(&sim.recording),
        &pred,
        &ballpass::analysis::AnalyzeSettings::default(),
    )
    .unwrap();
    let stage =
        PdLoop::from_products(s.stage.mass_kg, s.stage.kkp_n_per_m, s.stage.kkd_n_s_per_m).unwrap();
    let e = ballpass::model::compensate::second::second_round(&[0.0; 64], &stage, &a, 0.01)
        .unwrap_err();
    assert!(e.contains("all zeros"), "{e}");
    let e =
        ballpass::model::compensate::second::second_round(&[1.0; 2], &stage, &a, 0.01).unwrap_err();
    assert!(e.contains("2 bins"), "{e}");
    let ok =
        ballpass::model::compensate::second::second_round(&[0.5; 64], &stage, &a, 0.01).unwrap();
    assert_eq!(ok.force_n.len(), 64);
    assert!(ok.std_after_um_s.is_finite() && ok.f_c_with_table_um_s.is_finite());
}
