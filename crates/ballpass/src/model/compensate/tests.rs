//! The replay against the linear loop, and the records' frame check.

use super::replay::replay;
use super::travel::{at_index, travel_bins, travel_table, RecordKeys};
use super::{rail_grid, RECORD_OFFSET_LIMIT};
use crate::analysis::AnalyzeSettings;
use crate::model::stage::PdLoop;

/// The default simulated stage (240 kg, f_n 1.11 Hz, ζ 0.35).
fn stage() -> PdLoop {
    let s = crate::sim::StageSettings::default();
    PdLoop::from_products(s.mass_kg, s.kkp_n_per_m, s.kkd_n_s_per_m).unwrap()
}

/// A record met at exactly `v` mm/s: friction `3 + a·cos(2πx/P)` N against
/// position, passages every `P` from `x0`.
fn record(v: f64, pitch: f64, a: f64, seconds: f64) -> RecordKeys {
    let fs = 1000.0;
    let n = (seconds * fs) as usize;
    let x: Vec<f64> = (0..n).map(|i| v * i as f64 / fs).collect();
    let f = x
        .iter()
        .map(|x| 3.0 + a * (std::f64::consts::TAU * x / pitch).cos())
        .collect();
    let passages: Vec<f64> = (0..)
        .map(|k| k as f64 * pitch / v * fs)
        .take_while(|&u| u < (n - 1) as f64)
        .collect();
    let passage_mm = passages.iter().map(|&u| at_index(&x, u)).collect();
    RecordKeys {
        fs_hz: fs,
        friction_n: f,
        position_mm: x,
        passages,
        passage_mm,
    }
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
