use super::*;
use crate::fftplan::{forward_ends, forward_pair, inverse_ends, inverse_pair};

#[test]
fn fast_len() {
    assert_eq!(next_fast_even_len(1), 2);
    assert_eq!(next_fast_even_len(59999), 62208);
    assert_eq!(next_fast_even_len(7), 8);
    assert_eq!(next_fast_even_len(13), 16);
    assert_eq!(next_fast_even_len(31), 32);
    assert_eq!(next_fast_even_len(33), 36);
    assert_eq!(next_fast_even_len(37), 48);
}

/// [`product_pass`] one pair at a time with the single-pair functions.
fn product_pass_by_pairs(
    fft: &HalfComplex,
    zx: &[Complex<f64>],
    zy: &[Complex<f64>],
    auto: bool,
) -> Vec<Complex<f64>> {
    let m = zx.len();
    let prod = |x: Complex<f64>, y: Complex<f64>| {
        if auto {
            Complex::new(x.norm_sqr(), 0.0)
        } else {
            x * y.conj()
        }
    };
    let mut out = vec![Complex::new(0.0, 0.0); m];
    let ((x0, xm), (y0, ym)) = (forward_ends(zx[0]), forward_ends(zy[0]));
    out[0] = inverse_ends(prod(x0, y0), prod(xm, ym));
    for (i, w) in fft.twiddles.iter().enumerate() {
        let (k, j) = (i + 1, m - 1 - i);
        let (xk, xj) = forward_pair(*w, zx[k], zx[j]);
        let (yk, yj) = forward_pair(*w, zy[k], zy[j]);
        (out[k], out[j]) = inverse_pair(*w, prod(xk, yk), prod(xj, yj));
    }
    if m % 2 == 0 && m > 1 {
        let p = prod(zx[m / 2].conj(), zy[m / 2].conj());
        out[m / 2] = (p + p).conj();
    }
    out
}

#[test]
fn product_pass_blocks_equal_single_pairs() {
    for len in [2, 4, 6, 8, 12, 18, 24, 36, 48, 54, 96, 162, 1296, 1458] {
        let fft = crate::fftplan::half_complex(len);
        let m = len / 2;
        let z = |a: usize, b: usize| -> Vec<Complex<f64>> {
            (0..m)
                .map(|i| {
                    let (u, v) = ((i * a % 11) as f64, (i * b % 7) as f64);
                    Complex::new(u - 5.0 + 0.1 * v, 0.3 * v - 1.0 / (1.0 + u))
                })
                .collect()
        };
        // Bins with zero parts too, so that the signs of zeros are
        // checked as well.
        let with_zeros = |mut v: Vec<Complex<f64>>| {
            for (i, c) in v.iter_mut().enumerate() {
                match i % 5 {
                    1 => c.re = 0.0,
                    3 => *c = Complex::new(-0.0, 0.0),
                    _ => {}
                }
            }
            v
        };
        for (zx, zy) in [
            (z(37, 13), z(17, 5)),
            (with_zeros(z(37, 13)), with_zeros(z(3, 5))),
        ] {
            let zero = Complex::new(0.0, 0.0);
            let (mut cross, mut auto) = (vec![zero; m], vec![zero; m]);
            crate::simd::widest(|| product_pass::<false>(&fft, &zx, &zy, &mut cross));
            crate::simd::widest(|| product_pass::<true>(&fft, &zx, &zx, &mut auto));
            let bits = |v: &[Complex<f64>]| -> Vec<(u64, u64)> {
                v.iter().map(|c| (c.re.to_bits(), c.im.to_bits())).collect()
            };
            // The same bits, zeros' signs included, in the wide and the
            // baseline instance.
            let by_pairs = product_pass_by_pairs(&fft, &zx, &zy, false);
            assert_eq!(bits(&cross), bits(&by_pairs), "{len}");
            let by_pairs = product_pass_by_pairs(&fft, &zx, &zx, true);
            assert_eq!(bits(&auto), bits(&by_pairs), "{len}");
            let (mut base_cross, mut base_auto) = (vec![zero; m], vec![zero; m]);
            product_pass::<false>(&fft, &zx, &zy, &mut base_cross);
            product_pass::<true>(&fft, &zx, &zx, &mut base_auto);
            assert_eq!(bits(&cross), bits(&base_cross), "{len}");
            assert_eq!(bits(&auto), bits(&base_auto), "{len}");
        }
    }
}

#[test]
fn correlator_is_send_sync() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Correlator>();
}

#[test]
fn delayed_copy_peaks_at_minus_delay() {
    let x: Vec<f64> = (0..50).map(|i| ((i * 37 % 11) as f64) - 5.0).collect();
    let d = 3;
    let y: Vec<f64> = (0..50)
        .map(|i| if i >= d { x[i - d] } else { 0.0 })
        .collect();
    let c = correlate(&x, &y, Normalization::None).unwrap();
    let imax = (0..c.values.len())
        .max_by(|&a, &b| c.values[a].total_cmp(&c.values[b]))
        .unwrap();
    assert_eq!(c.lags[imax], -(d as i64));
}

#[test]
fn correlate_pairs_equals_one_by_one() {
    let x: Vec<f64> = (0..37).map(|i| ((i * 37 % 11) as f64) - 5.0).collect();
    let y: Vec<f64> = (0..37).map(|i| ((i * 13 % 7) as f64) * 0.5).collect();
    for norm in [
        Normalization::None,
        Normalization::Biased,
        Normalization::Unbiased,
        Normalization::Coeff,
    ] {
        let mut c = Correlator::new(CorrelateSettings {
            normalization: norm,
        });
        let all = c
            .correlate_pairs(&[&x, &y], &[(0, 0), (1, 1), (0, 1), (1, 0)])
            .unwrap();
        let one = [
            correlate(&x, &x, norm).unwrap(),
            correlate(&y, &y, norm).unwrap(),
            correlate(&x, &y, norm).unwrap(),
            correlate(&y, &x, norm).unwrap(),
        ];
        for (a, b) in all.iter().zip(&one) {
            assert_eq!(a.lags, b.lags);
            let scale = b.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            // Same FFT length and plan; only the order of the products
            // differs, so agreement is at rounding level of the peak.
            for (u, v) in a.values.iter().zip(&b.values) {
                assert!((u - v).abs() <= 1e-13 * scale, "{norm:?}: {u} vs {v}");
            }
        }
    }
    let mut c = Correlator::new(CorrelateSettings::default());
    assert!(c.correlate_pairs(&[&x, &y[..5]], &[(0, 1)]).is_err());
    assert!(c.correlate_pairs(&[&x], &[(0, 1)]).is_err());
    assert!(c.correlate_pairs(&[], &[]).is_err());
}

#[test]
fn errors() {
    assert!(matches!(
        correlate(&[], &[1.0], Normalization::None),
        Err(DspError::Empty { what: "x" })
    ));
    assert!(matches!(
        correlate(&[1.0, 2.0], &[1.0], Normalization::Biased),
        Err(DspError::LengthMismatch { .. })
    ));
    assert!(matches!(
        correlate(&[0.0, 0.0], &[1.0], Normalization::Coeff),
        Err(DspError::Numerical { .. })
    ));
    assert!(correlate(&[1.0, 2.0], &[1.0], Normalization::Coeff).is_ok());
    assert!(correlate(&[1.0, f64::NAN], &[1.0], Normalization::None).is_err());
}
