use super::*;

/// Horner evaluation with NumPy's `polyval` order (highest power
/// first), one point at a time: the reference of the blocked kernels.
fn polyval(p: &[f64], s: Complex64) -> Complex64 {
    p.iter().fold(Complex64::new(0.0, 0.0), |y, &c| {
        y * s + Complex64::new(c, 0.0)
    })
}

/// `b(z^-1) / a(z^-1)` at one frequency, one point at a time.
fn freqz_at(b: &[f64], a: &[f64], f: f64, fs_hz: f64) -> Complex64 {
    let w = 2.0 * std::f64::consts::PI * f / fs_hz;
    let (c, s) = crate::sincos::sincos(&[-w]);
    let zm1 = Complex64::new(c[0], s[0]);
    let ev = |c: &[f64]| {
        let mut acc = Complex64::new(c[c.len() - 1], 0.0);
        for &ci in c.iter().rev().skip(1) {
            acc = Complex64::new(ci, 0.0) + acc * zm1;
        }
        acc
    };
    nc::div(ev(b), ev(a))
}

/// The blocked evaluation is the point-by-point one, bit for bit (the
/// lanes only run side by side), at every block position and for a
/// length that leaves a partial block.
#[test]
fn blocks_equal_points_bit_for_bit() {
    let sos = crate::butter(5, crate::FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0).unwrap();
    let (b, a) = ([0.2, -0.1, 0.05, 0.3], [1.0, -1.2, 0.5, -0.05]);
    // 150 points: full blocks of 16 and of 64 lanes and a partial one.
    let f: Vec<f64> = (0..150).map(|i| i as f64 * 3.7 - 3.0).collect();
    let w: Vec<f64> = (0..150)
        .map(|i| 10f64.powf(i as f64 / 36.0 - 2.0))
        .collect();
    let hs = freqs(&b, &a, &w).unwrap().h;
    let hz = freqz(&b, &a, &f, 1000.0).unwrap().h;
    let hsos = sosfreqz(&sos, &f, 1000.0).unwrap().h;
    for i in 0..f.len() {
        let s = Complex64::new(0.0, w[i]);
        assert_eq!(hs[i], nc::div(polyval(&b, s), polyval(&a, s)), "freqs {i}");
        assert_eq!(hz[i], freqz_at(&b, &a, f[i], 1000.0), "freqz {i}");
        let want = sos
            .sections()
            .iter()
            .fold(Complex64::new(1.0, 0.0), |acc, s| {
                acc * freqz_at(&s[..3], &s[3..], f[i], 1000.0)
            });
        assert_eq!(hsos[i], want, "sosfreqz {i}");
    }
}

/// `freqz`'s Horner sums with the short first step are NumPy's bit for
/// bit where signed zeros can appear: zero and `-0.0` coefficients
/// (last, second to last, elsewhere), at 0 Hz, a quarter and half the
/// sampling rate and their negatives (where the cosine or sine is an
/// exact or near zero), in full and partial blocks.
#[test]
fn short_first_horner_step_keeps_signed_zeros() {
    let bits = |h: Complex64| (h.re.to_bits(), h.im.to_bits());
    let polys: [&[f64]; 9] = [
        &[1.0, 0.0],
        &[1.0, -0.0],
        &[0.0, 1.0],
        &[-0.0, 1.0],
        &[0.5, -0.0, 0.0],
        &[2.0, 0.0, -0.0],
        &[1.0, -0.0, 0.25, 0.0],
        &[-0.0, -0.0, 1.0],
        &[0.2, -0.1, 0.05, 0.3],
    ];
    let f: Vec<f64> = [
        0.0, -0.0, 250.0, -250.0, 500.0, -500.0, 1e-300, 125.0, 1000.0,
    ]
    .into_iter()
    .cycle()
    .take(80)
    .collect();
    for b in polys {
        for a in polys {
            let h = freqz(b, a, &f, 1000.0).unwrap().h;
            for (i, &fi) in f.iter().enumerate() {
                let want = freqz_at(b, a, fi, 1000.0);
                let same = bits(h[i]) == bits(want)
                    || (h[i].re.is_nan() || h[i].im.is_nan())
                        && (h[i].re.to_bits() == want.re.to_bits()
                            || h[i].re.is_nan() && want.re.is_nan())
                        && (h[i].im.to_bits() == want.im.to_bits()
                            || h[i].im.is_nan() && want.im.is_nan());
                assert!(same, "b {b:?} a {a:?} f {fi}: {} vs {want}", h[i]);
            }
        }
    }
}

/// `freqs` without the zero products is NumPy's `polyval` bit for bit:
/// zero and signed-zero coefficients, `w = 0` and `-0.0`, negative
/// frequencies, and values that overflow (infinities and NaN, where
/// the kernel evaluates NumPy's way).
#[test]
fn short_horner_equals_numpys_polyval_bitwise() {
    let bits = |h: Complex64| (h.re.to_bits(), h.im.to_bits());
    let w: Vec<f64> = [
        0.0, -0.0, 1.0, -2.5, 1e-300, 3.0, 1e100, 1e200, 1e300, -1e160,
    ]
    .into_iter()
    .chain((0..40).map(|i| (i as f64 - 20.0) * 0.37))
    .collect();
    let polys: [&[f64]; 7] = [
        &[0.2, -0.1, 0.05, 0.3],
        &[1.0, 0.0, 0.0, 1.0],
        &[0.0, 0.0, 2.0],
        &[1.0, -0.0, 3.0],
        &[-0.0, 1.0, -0.0],
        &[1e300, 1e300, 1.0],
        &[1.0, 4.0, 6.0, 4.0, 1.0],
    ];
    for b in polys {
        for a in polys {
            let h = freqs(b, a, &w).unwrap().h;
            for (i, &wi) in w.iter().enumerate() {
                let s = Complex64::new(0.0, wi);
                let want = nc::div(polyval(b, s), polyval(a, s));
                assert_eq!(
                    bits(h[i]),
                    bits(want),
                    "b {b:?} a {a:?} w {wi}: {} vs {want}",
                    h[i]
                );
            }
        }
    }
}

/// The division in lanes is NumPy's, bit for bit, in both branches and
/// for a zero denominator (infinities and NaN as NumPy gives them).
#[test]
fn lane_division_is_numpys() {
    let mut ar = [0.0; LANES];
    let mut ai = [0.0; LANES];
    let mut br = [0.0; LANES];
    let mut bi = [0.0; LANES];
    let cases = [
        (1.5, -2.0, -0.25, 3.0),
        (1.5, -2.0, 3.0, -0.25),
        (0.3, 0.7, 2.0, 2.0),
        (1.0, 2.0, 0.0, 0.0),
        (0.0, 0.0, 0.0, 0.0),
        (-1.0, 0.0, 0.0, 0.0),
        (1e-300, 1e300, 1e-10, -1e10),
        (4.0, 5.0, -0.0, 1.0),
    ];
    for (k, c) in cases.iter().enumerate() {
        (ar[k], ai[k], br[k], bi[k]) = *c;
    }
    assert_lanes_divide_as_numpy(ar, ai, br, bi);
}

/// [`div_lanes`] on one block equals [`nc::div`] lane by lane, bit for
/// bit (any NaN for a NaN).
fn assert_lanes_divide_as_numpy(
    ar: [f64; LANES],
    ai: [f64; LANES],
    br: [f64; LANES],
    bi: [f64; LANES],
) {
    let mut h = [Complex64::new(0.0, 0.0); LANES];
    div_lanes((Lanes(ar), Lanes(ai)), (Lanes(br), Lanes(bi)), &mut h);
    for k in 0..LANES {
        let want = nc::div(Complex64::new(ar[k], ai[k]), Complex64::new(br[k], bi[k]));
        for (g, w) in [(h[k].re, want.re), (h[k].im, want.im)] {
            assert!(
                g.to_bits() == w.to_bits() || (g.is_nan() && w.is_nan()),
                "{:?}: {g} vs {w}",
                (ar[k], ai[k], br[k], bi[k])
            );
        }
    }
}

/// A block without a zero denominator takes the path without the
/// zero case's divisions: still NumPy's division bit for bit, in both
/// branches, with signed zeros, infinities and NaN in the lanes.
#[test]
fn lane_division_without_zero_denominators_is_numpys() {
    let vals = [
        1.5,
        -2.0,
        -0.25,
        3.0,
        0.0,
        -0.0,
        1e-300,
        1e300,
        7.0,
        f64::INFINITY,
        f64::NAN,
    ];
    let mut cases = Vec::new();
    for &ar in &vals[..4] {
        for &br in &vals {
            for &bi in &vals {
                if br == 0.0 && bi == 0.0 {
                    continue;
                }
                cases.push((ar, -0.5 * ar + 0.125, br, bi));
            }
        }
    }
    for block in cases.chunks(LANES) {
        let (mut ar, mut ai, mut br, mut bi) =
            ([1.0; LANES], [0.0; LANES], [1.0; LANES], [2.0; LANES]);
        for (k, c) in block.iter().enumerate() {
            (ar[k], ai[k], br[k], bi[k]) = *c;
        }
        assert_lanes_divide_as_numpy(ar, ai, br, bi);
    }
}

/// `freqz_values_scipy_grid` returns `freqz_values`' response and
/// SciPy's grid `(2 pi f / fs) (fs / (2 pi))` computed as NumPy does,
/// bit for bit, for lengths around the block size.
#[test]
fn scipy_grid_and_response_in_one_pass() {
    let (b, a) = ([0.2, -0.1, 0.05, 0.3], [1.0, -1.2, 0.5, -0.05]);
    for n in [1, 63, 64, 65, 200] {
        let f: Vec<f64> = (0..n).map(|i| i as f64 * 2.9 + 0.1).collect();
        let (grid, h) = freqz_values_scipy_grid(&b, &a, &f, 1000.0).unwrap();
        assert_eq!(h, freqz_values(&b, &a, &f, 1000.0).unwrap());
        let two_pi = 2.0 * std::f64::consts::PI;
        for (g, v) in grid.iter().zip(&f) {
            assert_eq!(
                g.to_bits(),
                (two_pi * v / 1000.0 * (1000.0 / two_pi)).to_bits()
            );
            assert!((g - v).abs() <= 4.0 * f64::EPSILON * v.abs());
        }
        assert_eq!(grid.len(), n);
    }
    assert!(freqz_values_scipy_grid(&b, &a, &[1.0], -1.0).is_err());
}

#[test]
fn unwrap_removes_jumps() {
    let p = [3.0, -3.0, 3.1];
    let u = unwrap(&p);
    assert!((u[1] - (-3.0 + 2.0 * std::f64::consts::PI)).abs() < 1e-15);
    assert_eq!(u[2], 3.1);
}

#[test]
fn validates() {
    assert!(freqs(&[1.0], &[0.0], &[1.0]).is_err());
    assert!(freqs(&[1.0], &[1.0, 1.0], &[f64::NAN]).is_err());
    assert!(freqz(&[1.0], &[1.0], &[1.0], 0.0).is_err());
    let e: crate::DspError = freqs(&[], &[1.0], &[1.0]).unwrap_err();
    assert!(matches!(e, crate::DspError::Empty { .. }));
}
