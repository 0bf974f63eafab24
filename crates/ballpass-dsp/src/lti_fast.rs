//! [`freqs`](crate::freqs) with fewer operations: the Python package's
//! `freqs`, which promises SciPy's numbers to 1e-9, not its rounding.
//!
//! NumPy evaluates `b(s)` at `s = j w` by complex Horner steps, `y s + c`
//! as a full complex product with `s.re = 0` (four products, four sums per
//! coefficient), which [`freqs`](crate::freqs) reproduces for NumPy's bits.
//! With real coefficients the powers of `j w` alternate between real and
//! imaginary, so
//!
//! ```text
//! b(j w) = E(w^2) + j w O(w^2)
//! E(u)   = b_M - b_{M-2} u + b_{M-4} u^2 - ...       (even powers of s)
//! O(u)   = b_{M-1} - b_{M-3} u + b_{M-5} u^2 - ...   (odd powers)
//! ```
//!
//! two real Horner chains of half the degree: one product and one sum per
//! coefficient. The quotient is then [`freqs`](crate::freqs)' own (Smith's
//! division, as NumPy's). The sums are the same terms grouped differently,
//! so the results differ from NumPy's by rounding, relative to `|b(j w)|`
//! by about `eps` times the ratio of the largest term to the sum (the
//! conditioning of the polynomial at that point, which NumPy's order has
//! too); the Python package's tests hold them to SciPy at 1e-9. A block
//! whose result is not finite (overflowing powers of a huge `w`, a zero
//! denominator) is evaluated again by NumPy's steps, so infinities and
//! NaNs come out as NumPy's.

use rustfft::num_complex::Complex64;

use crate::error::{check_finite, Result};
use crate::lti::{by_blocks, check_poly, div_lanes, polyval_jw, LANES};

/// `scipy.signal.freqs(b, a, worN=w)`'s values, rounded differently from
/// [`freqs_values`](crate::freqs_values) (module docs): equal to SciPy's to
/// ~1e-15 relative on well-conditioned polynomials, about twice as fast.
///
/// ```
/// let (b, a) = ([1.0, 0.5], [1.0, 1.2, 3.0, 0.7]);
/// let w: Vec<f64> = (0..100).map(|i| 0.05 * i as f64).collect();
/// let exact = ballpass_dsp::freqs_values(&b, &a, &w)?;
/// let fast = ballpass_dsp::freqs_values_fast(&b, &a, &w)?;
/// assert!(exact.iter().zip(&fast).all(|(p, q)| (p - q).norm() <= 1e-14 * p.norm()));
/// # Ok::<(), ballpass_dsp::DspError>(())
/// ```
///
/// # Errors
/// As [`freqs_values`](crate::freqs_values).
pub fn freqs_values_fast(b: &[f64], a: &[f64], w_rad_s: &[f64]) -> Result<Vec<Complex64>> {
    check_poly("b", b)?;
    check_poly("a", a)?;
    check_finite("w_rad_s", w_rad_s)?;
    let (be, bo) = split(b);
    let (ae, ao) = split(a);
    Ok(crate::simd::widest(
        #[inline(always)]
        || {
            by_blocks(w_rad_s, |w: &[f64; LANES], h: &mut [Complex64]| {
                div_lanes(at_jw(&be, &bo, w), at_jw(&ae, &ao, w), h);
                if h.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
                    div_lanes(polyval_jw(b, w), polyval_jw(a, w), h);
                }
            })
        },
    ))
}

/// The coefficients of `E` and `O` (module docs), highest power of `u`
/// first, signs applied.
fn split(p: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let (mut even, mut odd) = (Vec::new(), Vec::new());
    // p[i] multiplies s^m, m = M - i; j^m = (-1)^(m/2) for even m and
    // j (-1)^((m-1)/2) for odd m.
    let m_top = p.len() - 1;
    for (i, &c) in p.iter().enumerate() {
        let m = m_top - i;
        let sign = if (m / 2) % 2 == 0 { 1.0 } else { -1.0 };
        if m % 2 == 0 {
            even.push((m / 2, sign * c));
        } else {
            odd.push(((m - 1) / 2, sign * c));
        }
    }
    let dense = |terms: Vec<(usize, f64)>| {
        let top = terms.first().map_or(0, |t| t.0);
        let mut out = vec![0.0; top + 1];
        for (k, c) in terms {
            out[top - k] = c;
        }
        out
    };
    (dense(even), dense(odd))
}

/// `E(w^2) + j w O(w^2)` for a block of `w`.
#[inline(always)]
fn at_jw(e: &[f64], o: &[f64], w: &[f64; LANES]) -> ([f64; LANES], [f64; LANES]) {
    let mut u = [0.0; LANES];
    for k in 0..LANES {
        u[k] = w[k] * w[k];
    }
    let (mut re, mut im) = ([0.0; LANES], [0.0; LANES]);
    for &c in e {
        for k in 0..LANES {
            re[k] = re[k] * u[k] + c;
        }
    }
    for &c in o {
        for k in 0..LANES {
            im[k] = im[k] * u[k] + c;
        }
    }
    for k in 0..LANES {
        im[k] *= w[k];
    }
    (re, im)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::freqs_values;

    #[test]
    fn equals_numpys_steps_to_rounding() {
        // Polynomials of degree 0-9 (random coefficients, and Butterworth
        // denominators), 2 000 frequencies from 1e-3 to 1e4 rad/s and w = 0.
        // Bound: 1e-13 of |H| per point; observed ~1e-15 (the polynomials
        // are well conditioned on the axis: no zero of b or a near it).
        let mut s = 11u64;
        let mut rnd = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 + 0.1
        };
        let mut w: Vec<f64> = (0..2000)
            .map(|i| 10f64.powf(-3.0 + 7.0 * i as f64 / 1999.0))
            .collect();
        w.push(0.0);
        for nb in 1..=10 {
            for na in 1..=10 {
                let b: Vec<f64> = (0..nb).map(|_| rnd()).collect();
                let a: Vec<f64> = (0..na).map(|_| rnd()).collect();
                let (want, got) = (
                    freqs_values(&b, &a, &w).unwrap(),
                    freqs_values_fast(&b, &a, &w).unwrap(),
                );
                for (i, (p, q)) in want.iter().zip(&got).enumerate() {
                    assert!(
                        (p - q).norm() <= 1e-13 * p.norm(),
                        "b {b:?} a {a:?} w {}: {p} vs {q}",
                        w[i]
                    );
                }
            }
        }
    }

    #[test]
    fn overflow_and_zero_denominators_come_out_as_numpys() {
        // w^9 overflows at w = 1e40: NumPy's steps give its infinities and
        // NaNs, which the fast path hands over to. A pure s denominator is
        // zero at w = 0.
        let w = [0.0, 1.0, 1e40, 1e300];
        for (b, a) in [
            (vec![1.0; 10], vec![1.0, 0.0]),
            (vec![1.0, 2.0], vec![2.0; 10]),
        ] {
            let (want, got) = (
                freqs_values(&b, &a, &w).unwrap(),
                freqs_values_fast(&b, &a, &w).unwrap(),
            );
            for (p, q) in want.iter().zip(&got) {
                assert_eq!(p.re.is_nan(), q.re.is_nan(), "{p} vs {q}");
                assert_eq!(p.im.is_nan(), q.im.is_nan(), "{p} vs {q}");
                if p.re.is_finite() && p.im.is_finite() {
                    assert!((p - q).norm() <= 1e-13 * p.norm(), "{p} vs {q}");
                } else {
                    assert_eq!(
                        (p.re.to_bits(), p.im.to_bits()),
                        (q.re.to_bits(), q.im.to_bits())
                    );
                }
            }
        }
        assert!(freqs_values_fast(&[0.0], &[1.0], &w).is_err());
    }
}
