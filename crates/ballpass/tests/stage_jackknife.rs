//! The stage identification on a bench where the fit's own covariance is
//! too narrow: a 48 Hz stage at 2 kHz, excited mostly by the sharp
//! harmonics of rectangular ripple pulses (design bench 9 300 531 of the
//! validation domain). Without the jackknife check the stage was claimed
//! identified with f_n 6.0 % low and a 95 % interval of ±2.7 %; on that
//! bench drawn again with other noise seeds the f_n intervals held the
//! truth on 32 of 77 fits and 9 of 15 claims were more than 5 % off.

use ballpass::analysis::AnalyzeSettings;
use ballpass::model::identify::{identify, StageSpectra};
use ballpass::sim::simulate;
use ballpass::validate::Domain;

#[test]
fn a_stage_the_covariance_misjudges_is_not_claimed_and_its_interval_holds() {
    let seed = 9_300_531;
    let b = Domain::default().draw(seed);
    let s = b.settings(&b.bearing(0, false), seed);
    let st = &s.stage;
    let f_n = (st.kkp_n_per_m / st.mass_kg).sqrt() / std::f64::consts::TAU;
    let sim = simulate(&s).unwrap();
    let pred = b.geometry.predict(b.velocity_mm_s, 5).unwrap();
    let sp = StageSpectra::of_recording(
        &sim.recording,
        b.velocity_mm_s,
        pred.tau_c_s,
        AnalyzeSettings::default().load_cell,
    )
    .unwrap()
    .unwrap();
    let id = identify(&sp);
    let fe = id.natural_frequency_hz.expect("a fit");
    assert_eq!(id.jackknife_groups, 9, "one group per segment: {}", id.text);
    assert!(
        (fe.value - f_n).abs() <= fe.ci95,
        "f_n {} ± {} against the truth {f_n}",
        fe.value,
        fe.ci95
    );
    assert!(!id.identified, "claimed: {}", id.text);
    assert!(id.text.contains("not identifiable"), "{}", id.text);
}
