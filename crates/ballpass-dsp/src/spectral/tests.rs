use super::*;

/// The csd segment loop compiled for the CPU's widest vectors adds the
/// same bits as the baseline build, for every detrend.
#[test]
fn wide_cross_sum_equals_the_baseline_bitwise() {
    let mut st = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = || {
        st = st
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (st >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let x: Vec<f64> = (0..5000).map(|_| next()).collect();
    let y: Vec<f64> = (0..5000).map(|_| next() + 0.1).collect();
    for detrend in [
        DetrendType::None,
        DetrendType::Constant,
        DetrendType::Linear,
    ] {
        let mut e = Engine::new(&Window::Hann, 1000, 300, 1200).unwrap();
        let nseg = e.n_segments(x.len());
        let mut wide = vec![Complex64::new(0.0, 0.0); e.n_bins()];
        let mut base = wide.clone();
        crate::simd::widest(|| e.cross_sum(&x, &y, nseg, detrend, &mut wide));
        e.cross_sum(&x, &y, nseg, detrend, &mut base);
        let bits = |v: &[Complex64]| {
            v.iter()
                .map(|z| (z.re.to_bits(), z.im.to_bits()))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&wide), bits(&base), "{detrend:?}");
    }
}

#[test]
fn median_bias_matches_scipy_values() {
    // scipy.signal._spectral_py._median_bias(n) for n = 1, 2, 3, 5
    // (1, 1, 1 - 1/6, 1 - 1/6 - 1/20); tolerance: rounding of a short sum.
    assert_eq!(median_bias(1), 1.0);
    assert_eq!(median_bias(2), 1.0);
    assert!((median_bias(3) - (1.0 - 1.0 / 6.0)).abs() < 1e-15);
    assert!((median_bias(5) - (1.0 - 1.0 / 6.0 - 1.0 / 20.0)).abs() < 1e-15);
}

#[test]
fn welch_is_send_sync() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Welch>();
}

#[test]
fn coherence_of_mean_removed_single_samples_is_nan() {
    // One-sample segments detrend to zero: Pxx = Pyy = 0, so 0/0 as in SciPy.
    let c = coherence(&[1.0], &[2.0], 1.0, &WelchSettings::default()).unwrap();
    assert_eq!(c.freq_hz, vec![0.0]);
    assert!(c.cxy[0].is_nan());
}

#[test]
fn fftfreq_order() {
    let e = Engine::new(&Window::Boxcar, 5, 0, 5).unwrap();
    assert_eq!(e.freqs(5.0, false), vec![0.0, 1.0, 2.0, -2.0, -1.0]);
    let e = Engine::new(&Window::Boxcar, 4, 0, 4).unwrap();
    assert_eq!(e.freqs(4.0, false), vec![0.0, 1.0, -2.0, -1.0]);
    assert_eq!(e.freqs(4.0, true), vec![0.0, 1.0, 2.0]);
}

#[test]
fn settings_errors() {
    let x = vec![1.0; 100];
    let bad = |s: WelchSettings| welch(&x, 1.0, &s).unwrap_err();
    let d = WelchSettings::default;
    assert!(matches!(
        bad(WelchSettings { nperseg: 0, ..d() }),
        DspError::InvalidSetting {
            name: "nperseg",
            ..
        }
    ));
    assert!(matches!(
        bad(WelchSettings {
            nperseg: 8,
            noverlap: Some(8),
            ..d()
        }),
        DspError::InvalidSetting {
            name: "noverlap",
            ..
        }
    ));
    assert!(matches!(
        bad(WelchSettings {
            nperseg: 8,
            nfft: Some(7),
            ..d()
        }),
        DspError::InvalidSetting { name: "nfft", .. }
    ));
    assert!(matches!(
        bad(WelchSettings {
            nperseg: 8,
            window: Window::Custom(vec![1.0; 7]),
            ..d()
        }),
        DspError::InvalidSetting { name: "window", .. }
    ));
    assert!(matches!(
        bad(WelchSettings {
            nperseg: 200,
            window: Window::Custom(vec![1.0; 200]),
            ..d()
        }),
        DspError::TooShort { .. }
    ));
    // Shortened nperseg (100) with an explicit overlap that no longer fits.
    assert!(matches!(
        bad(WelchSettings {
            nperseg: 256,
            noverlap: Some(150),
            ..d()
        }),
        DspError::InvalidSetting {
            name: "noverlap",
            ..
        }
    ));
    assert!(welch(&x, 0.0, &d()).is_err());
    assert!(welch(&x, f64::NAN, &d()).is_err());
    assert!(welch(&[], 1.0, &d()).is_err());
    assert!(matches!(
        welch(&[1.0, f64::NAN, 2.0], 1.0, &d()).unwrap_err(),
        DspError::NonFinite {
            what: "x",
            index: 1,
            ..
        }
    ));
    assert!(matches!(
        csd(&x, &[f64::INFINITY], 1.0, &d()).unwrap_err(),
        DspError::NonFinite {
            what: "y",
            index: 0,
            ..
        }
    ));
    assert!(csd(&x, &x, -2.0, &d()).is_err());
    assert!(coherence(&x, &x[..99], 1.0, &d()).is_err());
    assert!(coherence(
        &x,
        &x,
        1.0,
        &WelchSettings {
            average: Average::Median,
            ..d()
        }
    )
    .is_err());
    assert!(periodogram(
        &x,
        1.0,
        &PeriodogramSettings {
            nfft: Some(0),
            ..Default::default()
        }
    )
    .is_err());
}
