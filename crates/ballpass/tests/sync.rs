//! The synchronous average held to the simulator's truth (issue 17: the
//! disturbance waveform per ball passage).

use ballpass::analysis::sync::SyncKey;
use ballpass::analysis::{analyze, AnalyzeSettings, Signal};
use ballpass::bearing::lookup;
use ballpass::recording::{Channels, Recording};
use ballpass::sim::{simulate, Condition, SimSettings};

#[path = "common/ripple.rs"]
mod ripple;
use ripple::ripple_only;

fn analyse(rec: &Recording, v: f64) -> ballpass::analysis::Analysis {
    let pred = lookup("sr25w").unwrap().geometry.predict(v, 5).unwrap();
    analyze(
        std::slice::from_ref(rec),
        &pred,
        &AnalyzeSettings::default(),
    )
    .unwrap()
}

#[test]
fn friction_and_velocity_error_waveforms_match_the_simulated_ripple() {
    for (v, seed) in [(9.0, 1), (20.0, 2)] {
        let sim = ripple_only(v, seed);
        let t = &sim.truth;
        let a = analyse(&sim.recording, v);
        let sync = a.sync.as_ref().expect("a synchronous average");
        assert_eq!(sync.key, SyncKey::OpticalPassage);
        let f = sync.waveform(Signal::Friction).unwrap();
        // Fundamental of the Gaussian pulse train (truth), read through the
        // load cell (|H| ≥ 0.99 at f_c) and the 20 Hz low-pass (≥ 0.99):
        // 5 % covers those and the noise of ~30 periods (0.02 N white noise
        // low-passed, ~1 % of the line).
        let rel = f.fundamental_amplitude / t.friction_fundamental_n - 1.0;
        assert!(
            rel.abs() < 0.05,
            "v {v}: fundamental {} vs {}",
            f.fundamental_amplitude,
            t.friction_fundamental_n
        );
        // The friction pulse of the next ball comes `optical_delay` before
        // its optical passage: at 1 − delay/τ_c of the period. 0.02 period
        // (7°) covers the ball-spacing jitter (±0.6 %) and the load cell's
        // phase (< 1°).
        let expect = (-t.optical_delay_s / t.tau_c_s).rem_euclid(1.0);
        let d = (f.fundamental_peak_phase - expect + 0.5).rem_euclid(1.0) - 0.5;
        assert!(
            d.abs() < 0.02,
            "v {v}: friction peak at {} vs {expect}",
            f.fundamental_peak_phase
        );
        // Peak-to-peak: the 0.2 N pulse (low-passed at 20 Hz: its FWHM is
        // ≥ 63 ms, so the peak keeps > 95 %); 10 %.
        assert!(
            (f.peak_to_peak / 0.2 - 1.0).abs() < 0.10,
            "v {v}: p-p {}",
            f.peak_to_peak
        );
        assert!(
            f.variance_explained > 0.5,
            "v {v}: explained {}",
            f.variance_explained
        );
        // Velocity error: the stage's response to the friction line,
        // |G_vf(f_c)| times the friction fundamental, lagging by the truth's
        // lag. 10 % and 0.03 period: the encoder's quantisation noise after
        // averaging, and the central difference's gain at f_c (> 0.99).
        let ve = sync.waveform(Signal::VelocityError).unwrap();
        let expect_um_s = t.g_vf_gain_mm_s_per_n * 1e3 * t.friction_fundamental_n;
        let rel = ve.fundamental_amplitude / expect_um_s - 1.0;
        assert!(
            rel.abs() < 0.10,
            "v {v}: ve fundamental {} vs {expect_um_s}",
            ve.fundamental_amplitude
        );
        let lag = t.velocity_error_lag_force_tau_c;
        let d = (ve.fundamental_peak_phase - (f.fundamental_peak_phase + lag) + 0.5)
            .rem_euclid(1.0)
            - 0.5;
        assert!(
            d.abs() < 0.03,
            "v {v}: ve peak {} friction {} lag {lag}",
            ve.fundamental_peak_phase,
            f.fundamental_peak_phase
        );
        assert_eq!(ve.unit, "µm/s");
    }
}

#[test]
fn without_the_optical_channel_it_keys_on_the_encoder_and_says_so() {
    let v = 20.0;
    let sim = ripple_only(v, 3);
    let r = &sim.recording;
    let no_optical = Recording::new(
        r.fs_hz(),
        Channels {
            friction_n: r
                .channel(ballpass::recording::Channel::Friction)
                .map(<[f64]>::to_vec),
            position_mm: r
                .channel(ballpass::recording::Channel::Position)
                .map(<[f64]>::to_vec),
            optical_v: None,
        },
        r.meta.clone(),
    )
    .unwrap();
    let a = analyse(&no_optical, v);
    let sync = a.sync.as_ref().unwrap();
    assert_eq!(sync.key, SyncKey::EncoderPitch);
    assert!(sync.notes[0].contains("encoder"), "{:?}", sync.notes);
    assert!((sync.pitch_mm.unwrap() - 2.0 * sim.truth.d_avg_mm).abs() < 1e-9);
    // The passages sit on the rail up to the random split of the free space
    // (a few % of a pitch), which smears the line by at most a few %: 10 %.
    let f = sync.waveform(Signal::Friction).unwrap();
    let rel = f.fundamental_amplitude / sim.truth.friction_fundamental_n - 1.0;
    assert!(
        rel.abs() < 0.10,
        "{} vs {}",
        f.fundamental_amplitude,
        sim.truth.friction_fundamental_n
    );
    assert!(sync.per_ball.is_empty());
}

#[test]
fn balls_are_numbered_as_the_simulator_numbers_them() {
    // 20 mm/s for 30 s: ~74 passages, every ball of 36 at least twice.
    let mut s = SimSettings::for_bearing("sr25w", 20.0).unwrap();
    s.condition = Condition::Sticking;
    s.seed = 4;
    let sim = simulate(&s).unwrap();
    let a = analyse(&sim.recording, 20.0);
    let sync = a.sync.as_ref().unwrap();
    let t = &sim.truth;
    if sync.periods_rejected == 0 {
        assert_eq!(sync.per_ball.len(), 36, "{}", sync.per_ball_note);
        // Ball b of ours is the truth's ball balls[0] + b (mod 36): the
        // simulator's circuit order.
        let b0 = t.optical_passage_balls[0];
        for (k, &b) in t.optical_passage_balls.iter().enumerate() {
            assert_eq!((b0 + k) % 36, b);
        }
        let total: usize = sync.per_ball.iter().map(|r| r.periods).sum();
        assert_eq!(total, sync.periods_used);
    } else {
        assert!(sync.per_ball.is_empty() && sync.per_ball_note.contains("rejected"));
    }
}
