//! The stage identification on a bench whose encoder quantisation the
//! motion does not spread: a 48 Hz, ζ 0.20 stage at 2 kHz and 2.34 mm/s
//! with a 0.1 µm encoder (11.7 counts per sample: ten phases of a count),
//! excited mostly by the harmonics of sharp rectangular ripple pulses
//! (record 29 100 047 of that lab's profile, the one wrong claim of
//! `ballpass validate` on seeds 29 000 000+). The previous release claimed
//! it identified with ζ 36 % low (−9.5 of its standard errors); on that
//! bench drawn again with 40 noise seeds ζ read 35 % low pooled, and
//! within 3 % when the speed is 2.3417 mm/s instead. The claim is now
//! refused with the reason; the same bench at 2.3417 mm/s passes the
//! check.
//!
//! The bias comes through the friction's harmonic lines. The same stage
//! driven by broadband friction (no ripple, roughness 5 % of the Coulomb
//! level over 0.5 mm) is identified right behind the same encoder (with
//! the check switched off, 78 of 200 such records identified, all within
//! ±5 % f_n and ±20 % ζ), so `analyze` refuses the stage only where the
//! friction shows a harmonic above its floor.

use ballpass::analysis::{analyze, Analysis, AnalyzeSettings};
use ballpass::model::identify::{identify, StageSpectra};
use ballpass::sim::simulate;
use ballpass::validate::Domain;

const LAB48B: &str = r#"{"fs_hz":[2000],"duration_s":41.9,"velocity_mm_s":2.34,"stage_f_n_hz":48.05,"stage_zeta":0.2,"stage_mass_kg":206.9,"friction_noise_n":0.005,"load_cell_tau_s":6.66,"load_cell_dc_probability":0.0,
"ball_diameter_mm":6.418,"balls_in_race":35,"free_space_per_ball":0.3485,"coulomb_n":3.818,"ripple_fraction":0.0764,"friction_pulse_width_ratio":0.0788,"friction_shapes":["rectangular"],"roughness_fraction":0.00131,"roughness_length_mm":1.625}"#;

/// The lab's bench with broadband friction instead of its ripple.
fn broadband() -> String {
    LAB48B
        .replace(r#""ripple_fraction":0.0764"#, r#""ripple_fraction":0.0"#)
        .replace(
            r#""roughness_fraction":0.00131"#,
            r#""roughness_fraction":0.05"#,
        )
        .replace(
            r#""roughness_length_mm":1.625"#,
            r#""roughness_length_mm":0.5"#,
        )
}

/// `analyze` on record `seed` of `domain`, with the stage's truth (f_n, ζ).
fn analysed(domain: &str, seed: u64) -> (Analysis, [f64; 2]) {
    let domain: Domain = serde_json::from_str(domain).unwrap();
    let b = domain.draw(seed);
    let s = b.settings(&b.bearing(0, false), seed);
    let sim = simulate(&s).unwrap();
    let pred = b.geometry.predict(s.velocity_mm_s, 5).unwrap();
    let a = analyze(&[sim.recording], &pred, &AnalyzeSettings::default()).unwrap();
    let st = &s.stage;
    let f_n = (st.kkp_n_per_m / st.mass_kg).sqrt() / std::f64::consts::TAU;
    let zeta = st.kkd_n_s_per_m / (2.0 * (st.mass_kg * st.kkp_n_per_m).sqrt());
    (a, [f_n, zeta])
}

fn spectra(velocity_mm_s: Option<f64>) -> StageSpectra {
    let seed = 29_100_047;
    let domain: Domain = serde_json::from_str(LAB48B).unwrap();
    let b = domain.draw(seed);
    let mut s = b.settings(&b.bearing(0, false), seed);
    if let Some(v) = velocity_mm_s {
        s.velocity_mm_s = v;
    }
    let sim = simulate(&s).unwrap();
    let pred = b.geometry.predict(s.velocity_mm_s, 5).unwrap();
    StageSpectra::of_recording(
        &sim.recording,
        s.velocity_mm_s,
        pred.tau_c_s,
        AnalyzeSettings::default().load_cell,
    )
    .unwrap()
    .unwrap()
}

#[test]
fn a_stage_behind_an_undithered_encoder_is_not_claimed() {
    let sp = spectra(None);
    let e = sp.encoder.expect("a counting encoder");
    assert!((e.counts_per_sample - 11.7).abs() < 1e-4, "{e:?}");
    assert!(e.undithered(), "{e:?}");
    let id = identify(&sp);
    assert!(!id.identified, "claimed: {}", id.text);
    assert!(id.text.contains("encoder's quantisation"), "{}", id.text);
    // The same bench at a speed of no simple fraction of a count per
    // sample: the check passes.
    let sp = spectra(Some(2.3417));
    let e = sp.encoder.expect("a counting encoder");
    assert!(!e.undithered(), "{e:?}");
}

#[test]
fn the_check_refuses_only_where_the_friction_shows_lines() {
    // The lab's record: friction lines shown, the stage refused.
    let (a, _) = analysed(LAB48B, 29_100_047);
    assert!(!a.verdict.friction_harmonics_flagged.is_empty());
    let id = a.stage.expect("a stage fit");
    assert!(!id.identified, "claimed: {}", id.text);
    assert!(id.text.contains("encoder's quantisation"), "{}", id.text);
    // Broadband friction behind the same encoder: identified, and right.
    let (a, [f_n, zeta]) = analysed(&broadband(), 36_500_100);
    let e = a
        .stage_spectra
        .as_ref()
        .and_then(|sp| sp.encoder)
        .expect("a counting encoder");
    assert!(e.undithered(), "{e:?}");
    assert!(a.verdict.friction_harmonics_flagged.is_empty());
    let id = a.stage.expect("a stage fit");
    assert!(id.identified, "{}", id.text);
    let (fe, ze) = (id.natural_frequency_hz.unwrap(), id.damping_ratio.unwrap());
    assert!(
        (fe.value / f_n - 1.0).abs() <= 0.05,
        "f_n {} vs {f_n}",
        fe.value
    );
    assert!(
        (ze.value / zeta - 1.0).abs() <= 0.2,
        "ζ {} vs {zeta}",
        ze.value
    );
}
