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
    let n = x.len();
    if n == 0 {
        return;
    }
    match kind {
        DetrendType::None => {}
        DetrendType::Constant => {
            let mean = x.iter().sum::<f64>() / n as f64;
            x.iter_mut().for_each(|v| *v -= mean);
        }
        DetrendType::Linear => {
            let mean = x.iter().sum::<f64>() / n as f64;
            if n == 1 {
                x[0] -= mean;
                return;
            }
            let c = (n - 1) as f64 / 2.0;
            let sxt: f64 = x.iter().enumerate().map(|(i, v)| (i as f64 - c) * v).sum();
            // sum_{i} (i - c)^2 = N (N^2 - 1) / 12
            let nf = n as f64;
            let stt = nf * (nf * nf - 1.0) / 12.0;
            let slope = sxt / stt;
            x.iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v -= mean + slope * (i as f64 - c));
        }
    }
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
