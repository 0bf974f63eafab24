use super::*;
use crate::sim::rng::Rng;

/// A record of `x(t) = a cos(2π φ(t) + θ0) + noise`, `φ` advancing one per
/// key, the keys at jittered intervals around `t_c`.
fn synthetic(
    a: f64,
    theta0: f64,
    noise: f64,
    t_c: f64,
    jitter: f64,
    seed: u64,
) -> (Vec<f64>, Vec<f64>, f64) {
    let fs = 1000.0;
    let mut rng = Rng::stream(seed, 99);
    let mut keys = vec![0.37];
    while *keys.last().unwrap() < 40.0 {
        let last = *keys.last().unwrap();
        keys.push(last + t_c * (1.0 + jitter * (rng.uniform() - 0.5)));
    }
    let n = (40.0 * fs) as usize;
    let x: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 / fs;
            let k = keys.partition_point(|&k| k <= t);
            let phi = if k == 0 {
                (t - keys[0]) / t_c
            } else {
                (t - keys[k - 1]) / (keys[k] - keys[k - 1])
            };
            a * (std::f64::consts::TAU * phi + theta0).cos() + noise * rng.normal()
        })
        .collect();
    (x, keys, fs)
}

fn input<'a>(x: &'a [f64], keys: &[f64], fs: f64) -> SyncInput<'a> {
    SyncInput {
        source: "synthetic".into(),
        fs_hz: fs,
        friction_n: Some(x),
        velocity_error_mm_s: None,
        key_times_s: keys.to_vec(),
    }
}

#[test]
fn a_clean_cosine_comes_back_with_its_amplitude_phase_and_all_its_variance() {
    let (x, keys, fs) = synthetic(0.3, 1.0, 0.0, 0.9, 0.1, 1);
    let avg = synchronous_average(
        &[input(&x, &keys, fs)],
        SyncKey::OpticalPassage,
        None,
        &SyncSettings::default(),
    )
    .unwrap();
    let w = avg.waveform(Signal::Friction).unwrap();
    // Linear interpolation of a 1 kHz cosine with ~900 samples per cycle:
    // error below (2π/900)²/8 ≈ 6e-6 relative; 1e-3 leaves room.
    assert!(
        (w.fundamental_amplitude - 0.3).abs() < 1e-3,
        "{}",
        w.fundamental_amplitude
    );
    assert!((w.fundamental_phase_deg - 1f64.to_degrees()).abs() < 0.2);
    let peak = (-1.0 / std::f64::consts::TAU).rem_euclid(1.0);
    assert!((w.fundamental_peak_phase - peak).abs() < 1e-3);
    // 64 point samples of a cosine: p-p within (1 - cos(π/64)) of 2a.
    assert!((w.peak_to_peak - 0.6).abs() < 0.6 * 1.3e-3);
    assert!(w.variance_explained > 0.999, "{}", w.variance_explained);
    assert_eq!(avg.periods_rejected, 0);
}

#[test]
fn the_band_covers_the_true_waveform_at_its_confidence() {
    // 40 noisy records; the 95 % band should hold the true value in about
    // 95 % of bins x records. Binomial spread over 40 x 64 correlated bins
    // is a few percent, so [0.90, 0.99] fails only a broken interval.
    let mut inside = 0usize;
    let mut total = 0usize;
    for seed in 0..40 {
        let (x, keys, fs) = synthetic(0.2, 0.0, 0.5, 0.8, 0.1, 100 + seed);
        let avg = synchronous_average(
            &[input(&x, &keys, fs)],
            SyncKey::OpticalPassage,
            None,
            &SyncSettings::default(),
        )
        .unwrap();
        let w = avg.waveform(Signal::Friction).unwrap();
        for (j, (lo, hi)) in w.band_low.iter().zip(&w.band_high).enumerate() {
            let truth = 0.2 * (std::f64::consts::TAU * j as f64 / 64.0).cos();
            inside += usize::from(*lo <= truth && truth <= *hi);
            total += 1;
        }
    }
    let rate = inside as f64 / total as f64;
    assert!((0.90..=0.99).contains(&rate), "coverage {rate}");
}

#[test]
fn a_missed_key_is_rejected_and_stops_the_ball_split() {
    let (x, mut keys, fs) = synthetic(0.3, 0.0, 0.01, 0.9, 0.05, 2);
    let avg = synchronous_average(
        &[input(&x, &keys, fs)],
        SyncKey::OpticalPassage,
        Some(7),
        &SyncSettings::default(),
    )
    .unwrap();
    assert_eq!(avg.per_ball.len(), 7, "{}", avg.per_ball_note);
    keys.remove(10);
    let avg = synchronous_average(
        &[input(&x, &keys, fs)],
        SyncKey::OpticalPassage,
        Some(7),
        &SyncSettings::default(),
    )
    .unwrap();
    assert_eq!(avg.periods_rejected, 1);
    assert!(avg.per_ball.is_empty());
    assert!(
        avg.per_ball_note.contains("rejected"),
        "{}",
        avg.per_ball_note
    );
}

#[test]
fn encoder_keys_fall_at_each_pitch_of_travel() {
    // 9 mm/s for 10 s at 1 kHz: crossings of k * 8.1 mm at k * 0.9 s.
    let pos: Vec<f64> = (0..10_000).map(|i| 5.0 + 9.0 * i as f64 / 1000.0).collect();
    let keys = encoder_keys(&pos, 1000.0, 8.1);
    assert_eq!(keys.len(), 12);
    for (k, t) in keys.iter().enumerate() {
        assert!((t - 0.9 * k as f64).abs() < 1e-9, "{k} {t}");
    }
    // Backwards motion counts down.
    let back: Vec<f64> = pos.iter().map(|p| -p).collect();
    assert_eq!(encoder_keys(&back, 1000.0, 8.1), keys);
}

/// The keys as they were computed before the block-wise accumulator (the
/// direction from the first and last samples, one pass): the reference
/// the accumulator must equal to the bit.
fn keys_in_one_pass(position_mm: &[f64], fs_hz: f64, pitch_mm: f64) -> Vec<f64> {
    let (Some(&x0), Some(&x1)) = (position_mm.first(), position_mm.last()) else {
        return Vec::new();
    };
    if pitch_mm.is_nan() || pitch_mm <= 0.0 || x0 == x1 {
        return Vec::new();
    }
    let dir = (x1 - x0).signum();
    let mut keys = vec![0.0];
    let mut level = pitch_mm;
    for (i, w) in position_mm.windows(2).enumerate() {
        let (a, b) = ((w[0] - x0) * dir, (w[1] - x0) * dir);
        while b >= level && a < level {
            let frac = if b > a { (level - a) / (b - a) } else { 0.0 };
            keys.push((i as f64 + frac) / fs_hz);
            level += pitch_mm;
        }
        while b >= level + pitch_mm {
            level += pitch_mm;
        }
    }
    keys
}

#[test]
fn encoder_keys_fed_in_blocks_equal_one_pass_to_the_bit() {
    // Noisy travel that backs up now and then (steps of up to a pitch back),
    // both ways, fed in uneven blocks.
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for (dir, pitch) in [(1.0, 8.1), (-1.0, 8.1), (1.0, 0.7), (-1.0, 3.3)] {
        let mut x = 2.0;
        let pos: Vec<f64> = (0..20_000)
            .map(|i| {
                x += dir * (0.009 + 0.004 * (uniform() - 0.5));
                if i % 3001 == 3000 {
                    x -= dir * pitch * uniform();
                }
                x
            })
            .collect();
        let reference = keys_in_one_pass(&pos, 1000.0, pitch);
        assert!(reference.len() > 10, "{}", reference.len());
        assert_eq!(encoder_keys(&pos, 1000.0, pitch), reference);
        let mut acc = super::EncoderKeys::new(1000.0, pitch);
        let mut at = 0;
        for size in [1usize, 2, 777, 4096, 13].iter().cycle() {
            if at == pos.len() {
                break;
            }
            let end = (at + size).min(pos.len());
            acc.push(&pos[at..end]);
            at = end;
        }
        assert_eq!(acc.finish(), reference, "dir {dir} pitch {pitch}");
    }
    // No travel, no valid pitch, no samples: no keys, as before.
    assert!(encoder_keys(&[1.0; 50], 1000.0, 8.1).is_empty());
    let ramp: Vec<f64> = (0..50).map(f64::from).collect();
    for pitch in [0.0, -1.0, f64::NAN] {
        assert!(encoder_keys(&ramp, 1000.0, pitch).is_empty());
    }
    assert!(encoder_keys(&[], 1000.0, 8.1).is_empty());
}

#[test]
fn too_few_periods_is_an_error_naming_the_record() {
    let x = vec![0.0; 100];
    let e = synchronous_average(
        &[input(&x, &[0.01, 0.05], 1000.0)],
        SyncKey::OpticalPassage,
        None,
        &SyncSettings::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("synthetic") && e.contains("at least 2"), "{e}");
}
