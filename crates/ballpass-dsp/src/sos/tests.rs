use super::*;

#[test]
fn sos_rejects_bad_sections() {
    assert!(Sos::new(vec![]).is_err());
    assert!(Sos::new(vec![[1.0, 0.0, 0.0, 2.0, 0.0, 0.0]]).is_err());
    assert!(Sos::new(vec![[f64::NAN, 0.0, 0.0, 1.0, 0.0, 0.0]]).is_err());
}

#[test]
fn filtfilt_rejects_short_signals() {
    let sos = crate::butter(5, crate::FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0).unwrap();
    assert_eq!(sos.default_padlen(), 18);
    let err = sosfiltfilt(&sos, &[1.0; 18]).unwrap_err();
    assert!(matches!(
        err,
        DspError::TooShort {
            needed: 19,
            found: 18,
            ..
        }
    ));
    assert!(sosfiltfilt(&sos, &[1.0; 19]).is_ok());
    assert!(sosfiltfilt(&sos, &[]).is_err());
    assert!(sosfiltfilt(&sos, &[1.0, f64::NAN]).is_err());
}

/// The fixed-size loops are the general one, bit for bit, for every
/// filter length they cover and past it.
#[test]
fn lfilter_fixed_sizes_equal_the_general_loop() {
    let x: Vec<f64> = (0..300)
        .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
        .collect();
    for n in 2..=11 {
        let b: Vec<f64> = (0..n).map(|k| 0.3 / (k as f64 + 1.0)).collect();
        let mut a: Vec<f64> = (0..n).map(|k| (-0.4f64).powi(k as i32) / 2.0).collect();
        a[0] = 2.0;
        let zi: Vec<f64> = (1..n).map(|k| 0.1 * k as f64).collect();
        let got = lfilter_with_state(&b, &a, &x, &zi).unwrap();
        let (bn, an): (Vec<f64>, Vec<f64>) = (
            b.iter().map(|v| v / a[0]).collect(),
            a.iter().map(|v| v / a[0]).collect(),
        );
        let mut z = zi.clone();
        let mut y = Vec::new();
        for &xn in &x {
            let yn = z[0] + bn[0] * xn;
            for k in 0..n - 2 {
                z[k] = z[k + 1] + xn * bn[k + 1] - yn * an[k + 1];
            }
            z[n - 2] = xn * bn[n - 1] - yn * an[n - 1];
            y.push(yn);
        }
        assert_eq!(got.y, y, "n = {n}");
        assert_eq!(got.zf, z, "n = {n}");
    }
}

#[test]
fn lfilter_validates() {
    assert!(lfilter(&[1.0], &[0.0, 1.0], &[1.0]).is_err());
    assert!(lfilter(&[], &[1.0], &[1.0]).is_err());
    assert!(lfilter_with_state(&[1.0, 1.0], &[1.0], &[1.0], &[]).is_err());
    // integrator: pole at z = 1 has no steady state
    assert!(lfilter_zi(&[1.0], &[1.0, -1.0]).is_err());
}
