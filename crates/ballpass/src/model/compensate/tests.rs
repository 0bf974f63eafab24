//! The replay against the linear loop, and the records' frame check.

use super::replay::{correct_fundamental, replay};
use super::travel::{at_index, travel_bins, travel_table, RecordKeys};
use super::{rail_grid, RECORD_OFFSET_LIMIT};
use crate::analysis::AnalyzeSettings;
use crate::model::stage::PdLoop;

/// The default simulated stage (240 kg, f_n 1.11 Hz, ζ 0.35).
fn stage() -> PdLoop {
    let s = crate::sim::StageSettings::default();
    PdLoop::from_products(s.mass_kg, s.kkp_n_per_m, s.kkd_n_s_per_m).unwrap()
}

/// A record met at exactly `v` mm/s for `seconds` at 1 kHz: friction
/// `friction(x)` N against position `x`, passages every `P` from 0.
fn met_at(v: f64, pitch: f64, seconds: f64, friction: impl Fn(f64) -> f64) -> RecordKeys {
    let fs = 1000.0;
    let n = (seconds * fs) as usize;
    let x: Vec<f64> = (0..n).map(|i| v * i as f64 / fs).collect();
    let f = x.iter().map(|&x| friction(x)).collect();
    let passages: Vec<f64> = (0..)
        .map(|k| k as f64 * pitch / v * fs)
        .take_while(|&u| u < (n - 1) as f64)
        .collect();
    let passage_mm = passages.iter().map(|&u| at_index(&x, u)).collect();
    RecordKeys {
        fs_hz: fs,
        friction_n: f,
        velocity_error_std_um_s: 0.0,
        position_mm: x,
        passages,
        passage_mm,
    }
}

/// [`met_at`] with friction `3 + a·cos(2πx/P)` N.
fn record(v: f64, pitch: f64, a: f64, seconds: f64) -> RecordKeys {
    met_at(v, pitch, seconds, |x| {
        3.0 + a * (std::f64::consts::TAU * x / pitch).cos()
    })
}

/// A small sinusoidal friction leaves the stage in its linear range: the
/// replay's f_c component is `|G_vf(ω_c)|·a` (thesis Eq. 6.6), and the
/// table against travel takes it away.
#[test]
fn the_replay_is_the_linear_loop_for_a_small_friction_and_the_table_cancels_it() {
    let (v, pitch, a) = (9.0, 8.1, 0.2);
    let keys = vec![record(v, pitch, a, 30.0)];
    let st = stage();
    let settings = AnalyzeSettings::default();
    let w = std::f64::consts::TAU * v / pitch;
    let want = st.g_vf(w).norm() * a * 1e6;
    let before = replay(&keys, &st, None, pitch, v, &settings).unwrap();
    // 2 %: the start transient (settled in ~1 s of 30) and the linear
    // interpolation of the 20 Hz low-passed friction.
    assert!(
        (before.f_c_um_s - want).abs() < 0.02 * want,
        "{} vs {want}",
        before.f_c_um_s
    );
    let (s, c) = travel_bins(&keys, |k| &k.friction_n, pitch, 64);
    let table = travel_table(&s, &c).unwrap();
    let after = replay(&keys, &st, Some(&table), pitch, v, &settings).unwrap();
    // The table is the friction's periodic part to the bins' linear
    // interpolation (64 bins: 0.1 % of a); 3 % left is generous.
    assert!(after.f_c_um_s < 0.03 * want, "{} vs {want}", after.f_c_um_s);
    // The friction met with the table on is the same sinusoid (the stage
    // barely moves off the reference).
    let met = after.friction_met_n.unwrap();
    for (j, m) in met.iter().enumerate() {
        let x = j as f64 / 64.0 * pitch;
        let f = a * (std::f64::consts::TAU * x / pitch).cos();
        // The mean over ±1/128 period of a cosine: cos·sinc, 0.04 % low.
        assert!((m - f).abs() < 0.002, "bin {j}: {m} vs {f}");
    }
}

/// The fundamental's correction from the replay alone, without the
/// friction: starting from no table, one step of `−R_1 / G_vf` on the
/// linear loop is the friction's fundamental (thesis Eq. 6.6), and the
/// replay with it leaves almost no f_c component.
#[test]
fn the_fundamental_correction_is_the_friction_s_fundamental_in_the_linear_loop() {
    let (v, pitch, a) = (9.0, 8.1, 0.2);
    let keys = vec![record(v, pitch, a, 30.0)];
    let st = stage();
    let settings = AnalyzeSettings::default();
    let w = std::f64::consts::TAU * v / pitch;
    let before = replay(&keys, &st, None, pitch, v, &settings).unwrap();
    let mut table = vec![0.0; 64];
    correct_fundamental(&mut table, &before.waveform_um_s, &st, w);
    // The friction's periodic part is a·cos(2πφ) in travel, and time and
    // travel phase agree at a constant velocity: the table is that cosine
    // to the 2 % of the replay's f_c component (start transient, low-pass).
    for (j, u) in table.iter().enumerate() {
        let f = a * (std::f64::consts::TAU * j as f64 / 64.0).cos();
        assert!((u - f).abs() < 0.02 * a, "bin {j}: {u} vs {f}");
    }
    let after = replay(&keys, &st, Some(&table), pitch, v, &settings).unwrap();
    assert!(
        after.f_c_um_s < 0.03 * before.f_c_um_s,
        "{} vs {}",
        after.f_c_um_s,
        before.f_c_um_s
    );
}

/// Passage positions on one grid with a slow wander (1 % of the pitch),
/// split in two records; the second shifted by `shift` pitches.
fn two_records(shift: f64) -> Vec<RecordKeys> {
    let pitch = 8.1;
    let pos: Vec<f64> = (0..40)
        .map(|k| 1.0 + k as f64 * pitch + 0.01 * pitch * (k as f64 / 6.0).sin())
        .collect();
    let rec = |xs: &[f64]| RecordKeys {
        fs_hz: 1000.0,
        friction_n: vec![0.0; 2],
        velocity_error_std_um_s: 0.0,
        position_mm: vec![xs[0], xs[xs.len() - 1]],
        passages: vec![0.0; xs.len()],
        passage_mm: xs.to_vec(),
    };
    let second: Vec<f64> = pos[20..].iter().map(|x| x + shift * pitch).collect();
    vec![rec(&pos[..20]), rec(&second)]
}

#[test]
fn records_in_one_frame_agree_and_a_re_zeroed_record_sits_apart() {
    let one = rail_grid(&two_records(0.0), 8.1).unwrap();
    // The halves' phases differ by the wander's mean over each half, at
    // most its peak-to-peak, 2 % of the pitch.
    assert!(one.offset_spread < 0.02, "{one:?}");
    assert!(one.offset_spread <= RECORD_OFFSET_LIMIT);
    for shift in [0.1, 0.3, -0.2, 1.1] {
        let g = rail_grid(&two_records(shift), 8.1).unwrap();
        // The shift, modulo a pitch, within the wander.
        let want = (shift - shift.round()).abs();
        assert!(
            (g.offset_spread - want).abs() < 0.02,
            "shift {shift}: {g:?}"
        );
        assert!(g.offset_spread > RECORD_OFFSET_LIMIT, "shift {shift}");
    }
    // One record: nothing to compare.
    let single = rail_grid(&two_records(0.0)[..1], 8.1).unwrap();
    assert_eq!(single.offset_spread, 0.0);
}

/// A record cut from the middle of a run reads its friction about zero
/// mean (the load-cell discharge is not undone): replayed at that level,
/// a friction with stalling spikes is held at zero where it reads negative,
/// and the replay misses the record's velocity error. The fitted level
/// gives it back.
#[test]
fn the_friction_level_is_fitted_to_the_records_velocity_error() {
    let (v, pitch, fs) = (2.0, 8.0, 1000.0);
    let n = (40.0 * fs) as usize;
    let x: Vec<f64> = (0..n).map(|i| v * i as f64 / fs).collect();
    // 4 N with roughness-like ripple, and a 20 N spike (FWHM 0.4 mm) per
    // pitch: the default stage stalls on it at 2 mm/s.
    let f: Vec<f64> = x
        .iter()
        .map(|&x| {
            let ph = (x / pitch).fract() - 0.5;
            4.0 + 0.5 * (std::f64::consts::TAU * x / 1.3).sin()
                + 20.0 * (-0.5 * (ph * pitch / 0.17).powi(2)).exp()
        })
        .collect();
    let passages: Vec<f64> = (0..)
        .map(|k| k as f64 * pitch / v * fs)
        .take_while(|&u| u < (n - 1) as f64)
        .collect();
    let passage_mm = passages.iter().map(|&u| at_index(&x, u)).collect();
    let mut k = RecordKeys {
        fs_hz: fs,
        friction_n: f.clone(),
        velocity_error_std_um_s: 0.0,
        position_mm: x,
        passages,
        passage_mm,
    };
    let settings = AnalyzeSettings::default();
    let truth = replay(
        std::slice::from_ref(&k),
        &stage(),
        None,
        pitch,
        v,
        &settings,
    )
    .unwrap();
    // Near stall: the std is a large part of the velocity.
    assert!(truth.std_um_s > 0.15e3 * v, "{}", truth.std_um_s);
    k.velocity_error_std_um_s = truth.std_um_s;
    let mean = f.iter().sum::<f64>() / n as f64;
    k.friction_n = f.iter().map(|y| y - mean).collect();
    let cut = replay(
        std::slice::from_ref(&k),
        &stage(),
        None,
        pitch,
        v,
        &settings,
    )
    .unwrap();
    assert!(
        (cut.std_um_s - truth.std_um_s).abs() > 0.03 * truth.std_um_s,
        "the level should matter: {} vs {}",
        cut.std_um_s,
        truth.std_um_s
    );
    let mut keys = vec![k];
    let fit = super::replay::fit_levels(&mut keys, &stage(), pitch, v, &settings).unwrap();
    assert!(fit[0].restored_n.abs() < 1e-9);
    let again = replay(&keys, &stage(), None, pitch, v, &settings).unwrap();
    // The candidate levels are 0.5 std apart; on the plateau above the
    // true level the replay moves by well under 1 %.
    assert!(
        (again.std_um_s - truth.std_um_s).abs() < 0.01 * truth.std_um_s,
        "fitted level {}: std {} vs {}",
        fit[0].fitted_n,
        again.std_um_s,
        truth.std_um_s
    );
}

#[test]
fn the_f_c_interval_is_ordered_scaled_by_regime_and_keeps_the_replay_s_residual() {
    use super::STALL_FRACTION;
    use super::{f_c_after_interval, F_C_AFTER_OVER_MODEL_ERROR, SEVERE_STALL_FRACTION};
    // Replay residual 0: the bounds are the calibrated ratios times the
    // model error, in the regime of the std over the velocity (exact).
    for (stall, row) in [
        (0.01, 0),
        (STALL_FRACTION, 0),
        (0.3, 1),
        (SEVERE_STALL_FRACTION, 1),
        (SEVERE_STALL_FRACTION + 0.01, 2),
    ] {
        let got = f_c_after_interval(0.0, 10.0, stall);
        let want = F_C_AFTER_OVER_MODEL_ERROR[row].map(|k| 10.0 * k);
        assert_eq!(got, want, "stall {stall}");
        assert!(got[0] <= got[1] && got[1] <= got[2]);
    }
    // A replay that itself predicts a large residual keeps it as the floor
    // of every bound (hypot).
    let got = f_c_after_interval(300.0, 4.0, 0.7);
    assert!(got.iter().all(|&x| (300.0..300.1).contains(&x)), "{got:?}");
}

/// The rounds' guard on a trace like the runaway ones (session 11's design
/// benches: the replay's std with the table climbing from below to several
/// times the one without a table): the first round not below the bare
/// replay is refused and the lowest before it kept; rounds that stay below
/// are all kept, however they wander.
#[test]
fn the_round_guard_refuses_a_runaway_round_and_keeps_the_lowest_before() {
    use super::replay::round_refused;
    let bare = 1400.0;
    // Running away: friction against travel, rounds 1, 2 (kept), round 3
    // above the bare replay: refused, round 1 (the lowest) kept.
    assert_eq!(round_refused(&[1005.0, 980.0], bare), None);
    assert_eq!(round_refused(&[1005.0, 980.0, 1300.0], bare), None);
    assert_eq!(
        round_refused(&[1005.0, 980.0, 1300.0, 6361.0], bare),
        Some(1)
    );
    // Equal to the bare replay: the table does not help, refused.
    assert_eq!(round_refused(&[1005.0, 1400.0], bare), Some(0));
    // Oscillating below the bare replay (as on many near-stall benches):
    // every round kept.
    for k in 2..=5 {
        let stds = [1682.0, 1210.0, 1386.0, 1211.0, 1358.0];
        assert_eq!(round_refused(&stds[..k], 2260.0), None, "{k}");
    }
    // A replay that cannot say (NaN) refuses the round.
    assert_eq!(round_refused(&[900.0, f64::NAN], bare), Some(0));
}

/// A near-stall record (spikes whose height varies from ball to ball, so
/// the compensated stage still sticks): the guarded design keeps only what
/// the replay says helps (its table's replay below the bare one, each
/// correction kept lowering the replay's f_c component), and where it
/// refuses nothing it is the unguarded design.
#[test]
fn the_guarded_design_keeps_only_steps_the_replay_supports() {
    use super::replay::{design, DesignAt};
    let (v, pitch) = (3.0f64, 8.1f64);
    let keys = vec![met_at(v, pitch, 12.0 * pitch / v, |x| {
        let k = (x / pitch).floor() as u64;
        // Ball-to-ball spread of the spike height, fixed pseudo-random.
        let r = (k.wrapping_mul(2_654_435_761) % 1000) as f64 / 500.0 - 1.0;
        let ph = (x / pitch).fract() - 0.5;
        4.0 + 0.5 * (std::f64::consts::TAU * x / 1.3).sin()
            + 20.0 * (1.0 + 0.9 * r) * (-0.5 * (ph * pitch / 0.17).powi(2)).exp()
    })];
    let at = DesignAt {
        pitch_mm: pitch,
        velocity_mm_s: v,
        settings: AnalyzeSettings::default(),
        measured_v1: None,
        w_c_rad_s: Some(std::f64::consts::TAU * v / pitch),
        fundamental_only: false,
    };
    let g = design(&keys, &stage(), &at, 64, false, true).unwrap();
    let d = design(&keys, &stage(), &at, 64, false, false).unwrap();
    let bare = g.trace.bare.std_um_s;
    // Near stall without a table.
    assert!(bare > 0.3e3 * v, "{bare}");
    assert!(g.after.std_um_s < bare, "{} vs {bare}", g.after.std_um_s);
    let mut prev = g.trace.fixed_point_after.f_c_um_s;
    for c in &g.trace.corrections[..g.kept.corrections] {
        assert!(c.f_c_um_s < prev, "{:?}", g.trace.corrections);
        prev = c.f_c_um_s;
    }
    if g.kept.refused_round.is_none() && g.kept.corrections == super::replay::FUNDAMENTAL_STEPS {
        assert_eq!(g.table, d.table);
    }
    assert!(!g.guard_text().is_empty());
    // The table given (session 13): this one, whose replay is below the
    // bare one; none when its replay is not below (equal included) or
    // cannot say, with both stds in the reason.
    use super::replay::select;
    assert_eq!(select(&g), Ok(()));
    for worse in [bare, 1.5 * bare, f64::NAN] {
        let mut h = g.clone();
        h.after.std_um_s = worse;
        let why = select(&h).unwrap_err();
        assert!(why.contains(&format!("{bare:.0} without")), "{why}");
    }
}
