//! Direct (time-domain) correlation with a short weight vector, the "valid"
//! part only, as [`numpy.correlate(x, w, mode='valid')`](https://numpy.org/doc/stable/reference/generated/numpy.correlate.html):
//!
//! ```text
//! out[i] = sum_{j=0}^{m-1} w[j] x[i + j],   i = 0 .. n - m   (n - m + 1 outputs)
//! ```
//!
//! for `n = x.len() >= m = w.len() >= 1`. Each output is summed in the order
//! of `j`, one accumulator per output, so it equals the plain left-to-right
//! sum bit for bit (NumPy sums with its own dot product, which may order the
//! terms differently: agreement with it is to rounding, ~1e-16 relative).
//!
//! Meant for short kernels (a smoothing window of tens of taps); a long
//! kernel is cheaper by FFT ([`crate::correlate()`]).

use crate::error::{DspError, Result};

/// Outputs computed side by side: one vector register of accumulators with
/// AVX-512 (two with AVX2), so every tap is one broadcast, load, multiply
/// and add per block.
const LANES: usize = 8;

/// `numpy.correlate(x, w, 'valid')`: `out[i] = sum_j w[j] x[i + j]`, summed
/// in the order of `j` (see the module docs).
///
/// # Errors
/// [`DspError::Empty`] for an empty `x` or `w`,
/// [`DspError::InvalidSetting`] (name `weights`) when `w` is longer than `x`.
/// Non-finite samples are not rejected: they propagate as in NumPy.
pub fn correlate_valid(x: &[f64], w: &[f64]) -> Result<Vec<f64>> {
    if x.is_empty() {
        return Err(DspError::Empty { what: "x" });
    }
    if w.is_empty() {
        return Err(DspError::Empty { what: "weights" });
    }
    if w.len() > x.len() {
        return Err(crate::error::invalid(
            "weights",
            format!("{} weights are more than the {} samples", w.len(), x.len()),
        ));
    }
    let mut out = Vec::with_capacity(x.len() - w.len() + 1);
    crate::simd::widest(|| valid_into(x, w, &mut out));
    Ok(out)
}

/// The loop of [`correlate_valid`] (`#[inline(always)]` so that
/// [`crate::simd::widest`] compiles it for the CPU's vectors).
#[inline(always)]
fn valid_into(x: &[f64], w: &[f64], out: &mut Vec<f64>) {
    let m = w.len();
    let count = x.len() - m + 1;
    // `sum()` of an empty iterator: the start value of every output sum,
    // so that the blocked sums below equal `Iterator::sum` bit for bit.
    let zero: f64 = std::iter::empty::<f64>().sum();
    let mut i = 0;
    while i + LANES <= count {
        let win = &x[i..i + LANES - 1 + m];
        let mut acc = [zero; LANES];
        for (j, &wj) in w.iter().enumerate() {
            let v: &[f64; LANES] = win[j..j + LANES].try_into().expect("LANES samples");
            for (a, &v) in acc.iter_mut().zip(v) {
                *a += wj * v;
            }
        }
        out.extend(acc);
        i += LANES;
    }
    out.extend((i..count).map(|i| {
        w.iter()
            .zip(&x[i..i + m])
            .map(|(wj, v)| wj * v)
            .sum::<f64>()
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plain(x: &[f64], w: &[f64]) -> Vec<f64> {
        (0..=x.len() - w.len())
            .map(|i| w.iter().enumerate().map(|(j, wj)| wj * x[i + j]).sum())
            .collect()
    }

    #[test]
    fn equals_the_plain_sum_bit_for_bit() {
        let mut s = 7u64;
        let mut next = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for (n, m) in [
            (1, 1),
            (5, 5),
            (7, 3),
            (8, 1),
            (9, 2),
            (16, 9),
            (100, 17),
            (1000, 64),
        ] {
            let x: Vec<f64> = (0..n).map(|_| next()).collect();
            let w: Vec<f64> = (0..m).map(|_| next()).collect();
            let got = correlate_valid(&x, &w).unwrap();
            let want = plain(&x, &w);
            assert_eq!(got.len(), n - m + 1);
            for (g, e) in got.iter().zip(&want) {
                assert_eq!(g.to_bits(), e.to_bits(), "n={n} m={m}");
            }
        }
    }

    #[test]
    fn numpy_example() {
        // numpy.correlate([1, 2, 3], [0, 1, 0.5], 'valid') == [3.5]
        assert_eq!(
            correlate_valid(&[1.0, 2.0, 3.0], &[0.0, 1.0, 0.5]).unwrap(),
            vec![3.5]
        );
        // numpy.correlate([1, 2, 3, 4], [1, -1], 'valid') == [-1, -1, -1]
        assert_eq!(
            correlate_valid(&[1.0, 2.0, 3.0, 4.0], &[1.0, -1.0]).unwrap(),
            vec![-1.0; 3]
        );
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(correlate_valid(&[], &[1.0]).is_err());
        assert!(correlate_valid(&[1.0], &[]).is_err());
        let e = correlate_valid(&[1.0, 2.0], &[1.0, 2.0, 3.0]).unwrap_err();
        assert!(e.to_string().contains("3 weights"), "{e}");
    }
}
