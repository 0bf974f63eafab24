//! Trend removal, as
//! [`scipy.signal.detrend`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.detrend.html)
//! with one segment (`bp=0`).

use crate::error::{check_finite, Result};

/// Which trend to remove.
///
/// ```text
/// None:      y[n] = x[n]
/// Constant:  y[n] = x[n] - mean(x)
/// Linear:    y[n] = x[n] - (a + b n),  (a, b) the least-squares line through x
/// ```
///
/// `Linear` is the default, as for `scipy.signal.detrend`. (Welch's
/// per-segment default is `Constant`; see
/// [`WelchSettings`](crate::WelchSettings).)
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DetrendType {
    /// Leave the data as it is (SciPy's `detrend=False` in `welch`).
    None,
    /// Remove the mean (`type='constant'`).
    Constant,
    /// Remove the least-squares straight line (`type='linear'`).
    #[default]
    Linear,
}

/// Removes a constant or linear trend, as `scipy.signal.detrend(x, type=...)`.
///
/// See [`DetrendType`] for the formulas. A single sample detrends to `0`
/// for both `Constant` and `Linear` (SciPy's least-squares fit through one
/// point is exact).
///
/// SciPy solves the linear fit with `lstsq`; here it is solved in closed
/// form about the centre index, `b = sum (n - c) x[n] / sum (n - c)^2` with
/// `c = (N - 1) / 2`, which is the same least-squares line and equally
/// well conditioned. Results agree to rounding.
///
/// ```
/// use ballpass_dsp::{detrend, DetrendType};
/// let y = detrend(&[1.0, 3.0, 5.0, 7.0], DetrendType::Linear).unwrap();
/// assert!(y.iter().all(|v| v.abs() < 1e-12));
/// let y = detrend(&[1.0, 2.0, 6.0], DetrendType::Constant).unwrap();
/// assert_eq!(y, vec![-2.0, -1.0, 3.0]);
/// ```
///
/// # Errors
/// [`DspError::Empty`](crate::DspError::Empty) or
/// [`DspError::NonFinite`](crate::DspError::NonFinite) for `x`.
pub fn detrend(x: &[f64], kind: DetrendType) -> Result<Vec<f64>> {
    let mut y = x.to_vec();
    detrend_in_place(&mut y, kind)?;
    Ok(y)
}

/// [`detrend`] that overwrites its input (no allocation).
///
/// # Errors
/// As [`detrend`]; `x` is left unchanged on error.
pub fn detrend_in_place(x: &mut [f64], kind: DetrendType) -> Result<()> {
    check_finite("x", x)?;
    detrend_unchecked(x, kind);
    Ok(())
}

/// [`detrend_in_place`] without validation, for segments already checked.
pub(crate) fn detrend_unchecked(x: &mut [f64], kind: DetrendType) {
    let t = Trend::fit(x, kind);
    x.iter_mut().enumerate().for_each(|(i, v)| *v -= t.at(i));
}

/// A fitted trend `offset + slope * (n - center)`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Trend {
    offset: f64,
    slope: f64,
    center: f64,
}

impl Trend {
    /// Least-squares constant or line through `x` (zero for `None` or an
    /// empty `x`).
    #[inline(always)]
    pub(crate) fn fit(x: &[f64], kind: DetrendType) -> Trend {
        let n = x.len();
        let zero = Trend {
            offset: 0.0,
            slope: 0.0,
            center: 0.0,
        };
        if n == 0 || kind == DetrendType::None {
            return zero;
        }
        let mean = pairwise_sum(x) / n as f64;
        if kind == DetrendType::Constant || n == 1 {
            return Trend {
                offset: mean,
                ..zero
            };
        }
        let c = (n - 1) as f64 / 2.0;
        let sxt = centered_moment(x, c);
        // sum_{i} (i - c)^2 = N (N^2 - 1) / 12
        let nf = n as f64;
        let stt = nf * (nf * nf - 1.0) / 12.0;
        Trend {
            offset: mean,
            slope: sxt / stt,
            center: c,
        }
    }

    /// The trend's value at index `i`.
    #[inline]
    pub(crate) fn at(&self, i: usize) -> f64 {
        self.offset + self.slope * (i as f64 - self.center)
    }
}

/// Sum with eight interleaved accumulators in blocks of 128, split
/// pairwise above that (numpy's `pairwise_sum` scheme): rounding error
/// grows like `log2(N)` and the loop vectorises.
///
/// The recursion `sum(x) = sum(x[..h]) + sum(x[h..])` (`h` = half the
/// length rounded down to a multiple of 8) is run with an explicit stack,
/// so that the function can be inlined into code compiled for wider
/// vectors (a recursive function cannot be): the same additions in the
/// same order as the recursive form (tested bitwise).
#[inline(always)]
pub(crate) fn pairwise_sum(x: &[f64]) -> f64 {
    if x.len() <= 128 {
        return leaf_sum(x);
    }
    // Depth is at most log2(len / 64) < 58, so these bounds are never met.
    const DEPTH: usize = 64;
    // `Some((start, len))`: sum that range; `None`: add the last two sums.
    let mut todo: [Option<(usize, usize)>; 2 * DEPTH] = [None; 2 * DEPTH];
    let mut sums = [0.0f64; DEPTH];
    let (mut nt, mut ns) = (1, 0);
    todo[0] = Some((0, x.len()));
    while nt > 0 {
        nt -= 1;
        match todo[nt] {
            Some((start, len)) if len <= 128 => {
                sums[ns] = leaf_sum(&x[start..start + len]);
                ns += 1;
            }
            Some((start, len)) => {
                let mut half = len / 2;
                half -= half % 8;
                // Popped in reverse: left half, right half, then the sum.
                todo[nt] = None;
                todo[nt + 1] = Some((start + half, len - half));
                todo[nt + 2] = Some((start, half));
                nt += 3;
            }
            None => {
                ns -= 1;
                sums[ns - 1] += sums[ns];
            }
        }
    }
    sums[0]
}

/// [`pairwise_sum`] of at most 128 values: eight interleaved accumulators.
#[inline(always)]
fn leaf_sum(x: &[f64]) -> f64 {
    let mut acc = [0.0f64; 8];
    let chunks = x.chunks_exact(8);
    let rem = chunks.remainder();
    for c in chunks {
        for (a, v) in acc.iter_mut().zip(c) {
            *a += v;
        }
    }
    let mut s = ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]));
    for v in rem {
        s += v;
    }
    s
}

/// `sum_i (i - c) x[i]`, vectorisable (eight accumulators).
#[inline(always)]
fn centered_moment(x: &[f64], c: f64) -> f64 {
    let mut acc = [0.0f64; 8];
    let chunks = x.chunks_exact(8);
    let rem_start = x.len() - chunks.remainder().len();
    for (j, ch) in chunks.enumerate() {
        let base = (8 * j) as f64 - c;
        for (k, (a, v)) in acc.iter_mut().zip(ch).enumerate() {
            *a += (base + k as f64) * v;
        }
    }
    let mut s = acc.iter().sum::<f64>();
    for (i, v) in x.iter().enumerate().skip(rem_start) {
        s += (i as f64 - c) * v;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_removes_line_and_keeps_orthogonal_part() {
        // Tolerance 1e-12: the residual of an exact line is rounding only
        // (values are O(100)).
        let x: Vec<f64> = (0..11).map(|i| 3.0 - 7.5 * i as f64).collect();
        let y = detrend(&x, DetrendType::Linear).unwrap();
        assert!(y.iter().all(|v| v.abs() < 1e-12), "{y:?}");
        // A symmetric bump has no linear part but a mean.
        let b = [1.0, 0.0, -1.0, 0.0, 1.0];
        let y = detrend(&b, DetrendType::Linear).unwrap();
        let m = 1.0 / 5.0;
        for (yi, bi) in y.iter().zip(b) {
            assert!((yi - (bi - m)).abs() < 1e-15);
        }
    }

    /// The explicit-stack [`pairwise_sum`] adds as the recursive form does.
    #[test]
    fn pairwise_sum_equals_the_recursive_form_bitwise() {
        fn recursive(x: &[f64]) -> f64 {
            if x.len() <= 128 {
                leaf_sum(x)
            } else {
                let mut half = x.len() / 2;
                half -= half % 8;
                recursive(&x[..half]) + recursive(&x[half..])
            }
        }
        let mut s = 0x2545_f491_4f6c_dd1d_u64;
        let x: Vec<f64> = (0..70_001)
            .map(|_| {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.3) * 1e3
            })
            .collect();
        for n in [
            0, 1, 127, 128, 129, 136, 255, 256, 257, 1000, 4096, 4097, 30_000, 70_001,
        ] {
            assert_eq!(
                pairwise_sum(&x[..n]).to_bits(),
                recursive(&x[..n]).to_bits(),
                "n={n}"
            );
        }
    }

    #[test]
    fn pairwise_sum_is_exact_on_integers() {
        for n in [0usize, 1, 7, 8, 9, 127, 128, 129, 1000, 4097] {
            let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
            assert_eq!(
                pairwise_sum(&x),
                (n * n.saturating_sub(1) / 2) as f64,
                "n={n}"
            );
            let c = 3.5;
            let want: f64 = (0..n).map(|i| (i as f64 - c) * i as f64).sum();
            assert_eq!(centered_moment(&x, c), want, "n={n}");
        }
    }

    #[test]
    fn single_sample_and_errors() {
        assert_eq!(detrend(&[4.0], DetrendType::Linear).unwrap(), vec![0.0]);
        assert_eq!(detrend(&[4.0], DetrendType::None).unwrap(), vec![4.0]);
        assert!(detrend(&[], DetrendType::Constant).is_err());
        let mut x = [1.0, f64::INFINITY];
        assert!(detrend_in_place(&mut x, DetrendType::Linear).is_err());
        assert_eq!(x[0], 1.0);
    }
}
