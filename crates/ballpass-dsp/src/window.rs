//! Periodic (DFT-even) windows for spectral estimation, as
//! [`scipy.signal.get_window(name, n)`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.get_window.html)
//! with its default `fftbins=True`.

use crate::error::{invalid, Result};

/// A window for Welch-type spectral estimates.
///
/// The named windows are the *periodic* forms that `get_window` returns by
/// default (`fftbins=True`): the symmetric window of length `n + 1` with its
/// last sample dropped. For `n` samples and `i = 0..n`:
///
/// ```text
/// Hann:     w[i] = 0.5  + 0.5  cos(-pi + 2 pi i / n)   (= sin^2(pi i / n))
/// Hamming:  w[i] = 0.54 + 0.46 cos(-pi + 2 pi i / n)
/// Boxcar:   w[i] = 1
/// ```
///
/// computed the way SciPy's `general_cosine` does, so values agree to the
/// last bit or two. A window of length 1 is `[1.0]` and of length 0 is empty,
/// as in SciPy.
///
/// ```
/// use ballpass_dsp::Window;
/// let w = Window::Hann.values(4).unwrap();
/// // scipy.signal.get_window('hann', 4) == [0, 0.5, 1, 0.5]
/// assert_eq!(w[0], 0.0);
/// assert!((w[1] - 0.5).abs() < 1e-15 && (w[2] - 1.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Window {
    /// Periodic Hann (`'hann'`), SciPy's default for `welch`/`csd`.
    #[default]
    Hann,
    /// Periodic Hamming (`'hamming'`).
    Hamming,
    /// Rectangular window (`'boxcar'`), the default of `periodogram`.
    Boxcar,
    /// Explicit window values; their count must equal the segment length.
    Custom(Vec<f64>),
}

impl Window {
    /// The `n` window values.
    ///
    /// # Errors
    /// [`DspError::InvalidSetting`](crate::DspError::InvalidSetting) (name
    /// `window`) when a custom window's length is not `n` or it holds a
    /// non-finite value.
    pub fn values(&self, n: usize) -> Result<Vec<f64>> {
        match self {
            Window::Hann => Ok(general_cosine_periodic(n, 0.5, 0.5)),
            // SciPy builds hamming as general_hamming(M, 0.54): [0.54, 1 - 0.54].
            Window::Hamming => Ok(general_cosine_periodic(n, 0.54, 1.0 - 0.54)),
            Window::Boxcar => Ok(vec![1.0; n]),
            Window::Custom(w) => {
                if w.len() != n {
                    return Err(invalid(
                        "window",
                        format!(
                            "custom window has {} values, segment length is {n}",
                            w.len()
                        ),
                    ));
                }
                if let Some(i) = w.iter().position(|v| !v.is_finite()) {
                    return Err(invalid(
                        "window",
                        format!("custom window value {i} is {}", w[i]),
                    ));
                }
                Ok(w.clone())
            }
        }
    }

    /// The SciPy name of the window (`"hann"`, `"hamming"`, `"boxcar"`, or
    /// `"custom"`).
    pub fn name(&self) -> &'static str {
        match self {
            Window::Hann => "hann",
            Window::Hamming => "hamming",
            Window::Boxcar => "boxcar",
            Window::Custom(_) => "custom",
        }
    }
}

/// `a0 + a1 cos(fac)` with `fac = linspace(-pi, pi, n + 1)[:n]`, as SciPy's
/// `_general_cosine_impl(n, [a0, a1], sym=False)`.
///
/// The last few windows made on a thread are kept and copied out again: a
/// campaign builds the same 4096-point window for every record, and `n`
/// cosines cost far more than copying `n` values.
fn general_cosine_periodic(n: usize, a0: f64, a1: f64) -> Vec<f64> {
    use std::cell::RefCell;
    /// Windows kept per thread.
    const KEEP: usize = 4;
    /// Longest window kept (512 kB): a longer one is rare and costly to hold.
    const KEEP_MAX_LEN: usize = 1 << 16;
    type Key = (u64, u64, usize);
    thread_local! {
        static RECENT: RefCell<Vec<(Key, Vec<f64>)>> = const { RefCell::new(Vec::new()) };
    }
    if n <= 1 {
        return vec![1.0; n];
    }
    let key = (a0.to_bits(), a1.to_bits(), n);
    if let Some(w) =
        RECENT.with_borrow(|r| r.iter().find(|(k, _)| *k == key).map(|(_, w)| w.clone()))
    {
        return w;
    }
    let w = compute_general_cosine_periodic(n, a0, a1);
    if n > KEEP_MAX_LEN {
        return w;
    }
    RECENT.with_borrow_mut(|r| {
        if r.len() == KEEP {
            r.remove(0);
        }
        r.push((key, w.clone()));
    });
    w
}

/// [`general_cosine_periodic`] computed.
fn compute_general_cosine_periodic(n: usize, a0: f64, a1: f64) -> Vec<f64> {
    // numpy.linspace(start, stop, m): i * ((stop - start) / (m - 1)) + start,
    // with m - 1 = n here (the extended symmetric window).
    let step = (2.0 * std::f64::consts::PI) / n as f64;
    (0..n)
        .map(|i| {
            let fac = i as f64 * step - std::f64::consts::PI;
            // SciPy: w = 0; w += a0 * cos(0 * fac); w += a1 * cos(fac),
            // and 0 + a0 * 1 is exactly a0.
            a0 + a1 * fac.cos()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hann_is_sin_squared() {
        // Tolerance 1e-15: two formulas for the same number differ by rounding only.
        for n in [2usize, 3, 7, 8, 256] {
            let w = Window::Hann.values(n).unwrap();
            for (i, v) in w.iter().enumerate() {
                let s = (std::f64::consts::PI * i as f64 / n as f64).sin();
                assert!((v - s * s).abs() < 1e-15, "n={n} i={i}");
            }
        }
    }

    #[test]
    fn kept_windows_equal_computed_ones() {
        // More distinct windows than are kept, each asked for twice, in an
        // order that evicts: every answer equals a fresh computation.
        for round in 0..3 {
            for n in [16usize, 17, 4096, 31, 64, 16] {
                for (a0, a1) in [(0.5, 0.5), (0.54, 0.46)] {
                    let w = general_cosine_periodic(n, a0, a1);
                    assert_eq!(w, compute_general_cosine_periodic(n, a0, a1), "{round} {n}");
                }
            }
        }
    }

    #[test]
    fn short_windows_and_mismatch() {
        assert_eq!(Window::Hann.values(0).unwrap(), Vec::<f64>::new());
        assert_eq!(Window::Hamming.values(1).unwrap(), vec![1.0]);
        assert!(Window::Custom(vec![1.0; 3]).values(4).is_err());
        assert!(Window::Custom(vec![1.0, f64::NAN]).values(2).is_err());
        assert_eq!(
            Window::Custom(vec![0.5; 2]).values(2).unwrap(),
            vec![0.5; 2]
        );
    }
}
