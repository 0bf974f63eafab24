//! Correlations over a lag window `-L ..= L`, block by block, in memory
//! that does not grow with the record.
//!
//! [`Correlator`](crate::Correlator) transforms whole signals at an FFT
//! length of about `2 N`: for an hour-long record at 1 kHz that is seven
//! million lags per series and hundreds of megabytes of spectra, although
//! only the lags within a few hundred ball periods are ever looked at.
//! [`correlate_pairs_window`] gives the same sums for `|m| <= L` only:
//!
//! ```text
//! z[m] = sum_n x[n + m] y[n],   m = -L ..= L   (x[i] = 0 outside 0..N)
//! ```
//!
//! # How
//! The sum over `n` is cut into blocks `n in [b, b + B)`. For each block the
//! `y` samples `y[b .. b + B]` and the `x` samples `x[b - L .. b + B + L]`
//! (zeros beyond the record's ends) are transformed at a fixed FFT length
//! `P >= B + 2 L`, so that the circular correlation of the two holds the
//! block's share of every `z[m]`, `|m| <= L`, at index `m + L` with no
//! wrap-around. Every block has the same geometry, so the products
//! `X_b conj(Y_b)` are summed over the blocks in the frequency domain and
//! transformed back once per pair at the end. Memory: two spectra per
//! signal and one per pair, of `P / 2 + 1` bins, with `B = max(2 L, 8192)`.
//! Work: `2 k` real FFTs of length `P` per block for `k` signals, about as
//! many operations as the whole-record transform.
//!
//! The result equals the whole-record correlation's lags `-L ..= L` to
//! rounding (each value within about `1e-15 * sqrt(sum x^2 sum y^2)` times
//! a small multiple of `log2 P` and of the number of blocks' square root),
//! not to the bit: the sums are grouped differently.

use std::sync::Arc;

use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex;

use crate::correlate::{energy, next_fast_even_len, Correlation, Normalization};
use crate::error::{check_finite, DspError, Result};

/// Shortest block of `y` samples per transform (the block is `2 L` when
/// that is longer): below a few thousand samples the fixed cost per FFT
/// dominates.
const MIN_BLOCK: usize = 8192;

/// Correlations `z[m] = sum_n s_a[n + m] s_b[n]` for `|m| <= max_lag` of
/// equal-length signals, for the listed index pairs `(a, b)`, normalised
/// as [`Normalization`] says (with `N` the whole length, so the values are
/// those of the whole-record correlation at the same lags).
///
/// `max_lag` beyond `N - 1` is taken as `N - 1` (the full range). Result
/// `i` has lags `-L ..= L` and equals
/// `correlate(signals[a_i], signals[b_i])` on those lags to rounding (see
/// the module docs).
///
/// ```
/// use ballpass_dsp::{correlate, correlate_pairs_window, Normalization};
/// let x: Vec<f64> = (0..5000).map(|i| (i as f64 * 0.01).sin()).collect();
/// let y: Vec<f64> = (0..5000).map(|i| (i as f64 * 0.013).cos()).collect();
/// let w = correlate_pairs_window(&[&x, &y], &[(0, 1)], 40, Normalization::None).unwrap();
/// let full = correlate(&x, &y, Normalization::None).unwrap();
/// assert_eq!(w[0].lags.len(), 81);
/// for (m, v) in w[0].lags.iter().zip(&w[0].values) {
///     assert!((v - full.at_lag(*m).unwrap()).abs() < 1e-9);
/// }
/// ```
///
/// # Errors
/// [`DspError::Empty`], [`DspError::NonFinite`] or
/// [`DspError::LengthMismatch`] for the signals;
/// [`DspError::InvalidSetting`] for a pair index out of range;
/// [`DspError::Numerical`] for `Coeff` when a signal of a pair is all zeros.
pub fn correlate_pairs_window(
    signals: &[&[f64]],
    pairs: &[(usize, usize)],
    max_lag: usize,
    normalization: Normalization,
) -> Result<Vec<Correlation>> {
    let n = crate::error::check_signal_set(signals, pairs, "signals (correlate_pairs_window)")?;
    let mut w = WindowCorrelation::new(signals.len(), pairs, n, max_lag, normalization)?;
    // In pieces of a block, so that only a block and the window are copied.
    let piece = w.block;
    let mut at = 0;
    while at < n {
        let to = (at + piece).min(n);
        let parts: Vec<&[f64]> = signals.iter().map(|s| &s[at..to]).collect();
        w.push(&parts)?;
        at = to;
    }
    // The whole-signal energies as `Correlator` sums them.
    w.energies = signals.iter().map(|s| energy(s)).collect();
    w.finish()
}

/// [`correlate_pairs_window`] on signals that arrive in pieces
/// ([`WindowCorrelation::push`]) of a known total length `n`: each block
/// is transformed as soon as the samples `L` past its end have arrived,
/// so it holds `B + 2 L` samples per signal besides the spectra. The
/// result does not depend on how the signals are cut into pieces; it
/// equals [`correlate_pairs_window`]'s to the bit except for `Coeff`, whose
/// energies are summed piece by piece (same to rounding).
pub struct WindowCorrelation {
    pairs: Vec<(usize, usize)>,
    n: usize,
    l: usize,
    block: usize,
    len: usize,
    normalization: Normalization,
    fwd: Arc<dyn RealToComplex<f64>>,
    inv: Arc<dyn ComplexToReal<f64>>,
    time: Vec<f64>,
    scratch: Vec<Complex<f64>>,
    x_spec: Vec<Vec<Complex<f64>>>,
    y_spec: Vec<Vec<Complex<f64>>>,
    acc: Vec<Vec<Complex<f64>>>,
    used: Vec<bool>,
    /// Samples `hist_start ..` of each signal.
    hist: Vec<Vec<f64>>,
    hist_start: usize,
    seen: usize,
    /// Start of the next block.
    b: usize,
    energies: Vec<f64>,
}

impl std::fmt::Debug for WindowCorrelation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WindowCorrelation")
            .field("n", &self.n)
            .field("max_lag", &self.l)
            .field("seen", &self.seen)
            .finish()
    }
}

impl WindowCorrelation {
    /// A window correlation of `k` signals of `n` samples each for the
    /// index `pairs`, lags `-L ..= L` with `L = min(max_lag, n - 1)`.
    ///
    /// # Errors
    /// [`DspError::Empty`] for `n == 0` or no signals,
    /// [`DspError::InvalidSetting`] for a pair index out of range.
    pub fn new(
        k: usize,
        pairs: &[(usize, usize)],
        n: usize,
        max_lag: usize,
        normalization: Normalization,
    ) -> Result<WindowCorrelation> {
        if n == 0 || k == 0 {
            return Err(DspError::Empty { what: "signals" });
        }
        if let Some(&(a, b)) = pairs.iter().find(|&&(a, b)| a >= k || b >= k) {
            return Err(crate::error::invalid(
                "pairs",
                format!("pair ({a}, {b}) is out of range for {k} signals"),
            ));
        }
        let l = max_lag.min(n - 1);
        let block = (2 * l).max(MIN_BLOCK).min(n);
        let len = next_fast_even_len(block + 2 * l);
        let mut planner = RealFftPlanner::<f64>::new();
        let fwd: Arc<dyn RealToComplex<f64>> = planner.plan_fft_forward(len);
        let inv: Arc<dyn ComplexToReal<f64>> = planner.plan_fft_inverse(len);
        let bins = len / 2 + 1;
        let zero = Complex::new(0.0, 0.0);
        Ok(WindowCorrelation {
            pairs: pairs.to_vec(),
            n,
            l,
            block,
            len,
            normalization,
            time: fwd.make_input_vec(),
            scratch: fwd.make_scratch_vec(),
            fwd,
            inv,
            x_spec: vec![vec![zero; bins]; k],
            y_spec: vec![vec![zero; bins]; k],
            acc: vec![vec![zero; bins]; pairs.len()],
            used: (0..k)
                .map(|i| pairs.iter().any(|&(a, b)| a == i || b == i))
                .collect(),
            hist: vec![Vec::new(); k],
            hist_start: 0,
            seen: 0,
            b: 0,
            energies: vec![0.0; k],
        })
    }

    /// The largest lag `L`.
    pub fn max_lag(&self) -> usize {
        self.l
    }

    /// Feeds the next samples of every signal (equal lengths).
    ///
    /// # Errors
    /// [`DspError::LengthMismatch`] for pieces of different lengths or more
    /// samples than `n`; [`DspError::NonFinite`] for a non-finite sample.
    pub fn push(&mut self, pieces: &[&[f64]]) -> Result<()> {
        let m = pieces.first().map_or(0, |p| p.len());
        if pieces.len() != self.hist.len() || pieces.iter().any(|p| p.len() != m) {
            return Err(DspError::LengthMismatch {
                what: "pieces (WindowCorrelation::push)",
                expected: m,
                found: pieces
                    .iter()
                    .map(|p| p.len())
                    .find(|&l| l != m)
                    .unwrap_or(pieces.len()),
            });
        }
        if self.seen + m > self.n {
            return Err(DspError::LengthMismatch {
                what: "samples (WindowCorrelation::push)",
                expected: self.n,
                found: self.seen + m,
            });
        }
        if m == 0 {
            return Ok(());
        }
        for ((h, p), e) in self.hist.iter_mut().zip(pieces).zip(&mut self.energies) {
            check_finite("signal", p)?;
            h.extend_from_slice(p);
            *e += energy(p);
        }
        self.seen += m;
        while self.b < self.n {
            let bl = self.block.min(self.n - self.b);
            if self.seen < (self.b + bl + self.l).min(self.n) {
                break;
            }
            self.process(bl)?;
            self.b += bl;
            let keep_from = self.b.saturating_sub(self.l);
            if keep_from > self.hist_start {
                let d = keep_from - self.hist_start;
                for h in &mut self.hist {
                    h.drain(..d);
                }
                self.hist_start = keep_from;
            }
        }
        Ok(())
    }

    /// The block at `self.b` of `bl` samples.
    fn process(&mut self, bl: usize) -> Result<()> {
        let (b, l, n) = (self.b, self.l, self.n);
        for (i, s) in self.hist.iter().enumerate() {
            if !self.used[i] {
                continue;
            }
            // x[b - L .. b + B + L], zeros outside the record.
            self.time.iter_mut().for_each(|v| *v = 0.0);
            let lo = b as isize - l as isize;
            let from = lo.max(0) as usize;
            let to = (b + bl + l).min(n);
            let at = (from as isize - lo) as usize;
            let h0 = self.hist_start;
            self.time[at..at + (to - from)].copy_from_slice(&s[from - h0..to - h0]);
            self.fwd
                .process_with_scratch(&mut self.time, &mut self.x_spec[i], &mut self.scratch)
                .map_err(|e| fft_failed(&e))?;
            self.time.iter_mut().for_each(|v| *v = 0.0);
            self.time[..bl].copy_from_slice(&s[b - h0..b + bl - h0]);
            self.fwd
                .process_with_scratch(&mut self.time, &mut self.y_spec[i], &mut self.scratch)
                .map_err(|e| fft_failed(&e))?;
        }
        for (&(a, c), sum) in self.pairs.iter().zip(self.acc.iter_mut()) {
            for ((s, x), y) in sum.iter_mut().zip(&self.x_spec[a]).zip(&self.y_spec[c]) {
                *s += x * y.conj();
            }
        }
        Ok(())
    }

    /// The correlations, once all `n` samples have been pushed.
    ///
    /// # Errors
    /// [`DspError::LengthMismatch`] if fewer than `n` samples were pushed;
    /// [`DspError::Numerical`] for `Coeff` when a signal of a pair is all
    /// zeros.
    pub fn finish(self) -> Result<Vec<Correlation>> {
        let WindowCorrelation {
            pairs,
            n,
            l,
            len,
            normalization,
            inv,
            mut time,
            acc,
            seen,
            energies,
            ..
        } = self;
        if seen != n {
            return Err(DspError::LengthMismatch {
                what: "samples (WindowCorrelation::finish)",
                expected: n,
                found: seen,
            });
        }
        for &(a, b) in &pairs {
            if let Some(which) = [a, b]
                .into_iter()
                .find(|&i| normalization == Normalization::Coeff && energies[i] == 0.0)
            {
                return Err(DspError::Numerical {
                    what: "coefficient-normalised correlation",
                    reason: format!(
                        "signal {which} is all zeros (zero energy), so R[0] cannot normalise it"
                    ),
                });
            }
        }
        let bins = len / 2 + 1;
        let mut inv_scratch = inv.make_scratch_vec();
        let lags: Vec<i64> = (-(l as i64)..=l as i64).collect();
        let scale = 1.0 / len as f64;
        let mut out = Vec::with_capacity(pairs.len());
        for (&(a, c), mut sum) in pairs.iter().zip(acc) {
            // A real signal's spectrum has real DC and Nyquist bins; the sums
            // of products do too up to rounding, which the inverse transform
            // would reject.
            sum[0].im = 0.0;
            sum[bins - 1].im = 0.0;
            inv.process_with_scratch(&mut sum, &mut time, &mut inv_scratch)
                .map_err(|e| fft_failed(&e))?;
            let f = match normalization {
                Normalization::None | Normalization::Unbiased => scale,
                Normalization::Biased => scale / n as f64,
                Normalization::Coeff => scale / (energies[a] * energies[c]).sqrt(),
            };
            let values = lags
                .iter()
                .zip(&time[..=2 * l])
                .map(|(&m, &v)| {
                    if normalization == Normalization::Unbiased {
                        v * scale / (n - m.unsigned_abs() as usize) as f64
                    } else {
                        v * f
                    }
                })
                .collect();
            out.push(Correlation {
                lags: lags.clone(),
                values,
            });
        }
        Ok(out)
    }
}

fn fft_failed(e: &impl std::fmt::Display) -> DspError {
    DspError::Numerical {
        what: "windowed correlation",
        reason: format!("FFT buffer sizes disagree ({e}); this is a bug"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::correlate::correlate;
    use crate::test_noise::noise;

    /// Every lag of the window against the whole-record FFT correlation and,
    /// on short inputs, the direct sum, for lengths that make one block,
    /// several, a short last block, and windows wider than the record.
    /// Tolerance: both sides are FFT sums of ~N products of O(1) values;
    /// 1e-12 of sqrt(sum x^2 sum y^2) leaves three orders of magnitude for
    /// their rounding (~1e-15 * log2 P each).
    #[test]
    fn windowed_lags_equal_the_whole_record_correlation() {
        for (n, l) in [
            (1usize, 0usize),
            (5, 3),
            (100, 10),
            (9000, 5),
            (20_000, 100),
            (50_001, 7000),
            (30_000, 40_000),
        ] {
            let x = noise(n, 1 + n as u64);
            let y: Vec<f64> = noise(n, 7 + l as u64).iter().map(|v| v + 0.3).collect();
            for norm in [
                Normalization::None,
                Normalization::Biased,
                Normalization::Unbiased,
                Normalization::Coeff,
            ] {
                let w =
                    correlate_pairs_window(&[&x, &y], &[(0, 0), (0, 1), (1, 0)], l, norm).unwrap();
                let scale = match norm {
                    Normalization::None => (energy(&x) * energy(&y)).sqrt(),
                    Normalization::Biased | Normalization::Unbiased => {
                        (energy(&x) * energy(&y)).sqrt() / n as f64
                    }
                    Normalization::Coeff => 1.0,
                };
                let l_eff = l.min(n - 1) as i64;
                for (r, (p, q)) in w.iter().zip([(&x, &x), (&x, &y), (&y, &x)]) {
                    let full = correlate(p, q, norm).unwrap();
                    assert_eq!(r.lags.first(), Some(&-l_eff));
                    assert_eq!(r.lags.last(), Some(&l_eff));
                    for (&m, &v) in r.lags.iter().zip(&r.values) {
                        let want = full.at_lag(m).unwrap();
                        // Unbiased divides the far lags by few overlaps.
                        let tol = match norm {
                            Normalization::Unbiased => {
                                1e-12 * scale * n as f64 / (n as f64 - m.abs() as f64)
                            }
                            _ => 1e-12 * scale,
                        };
                        assert!(
                            (v - want).abs() <= tol,
                            "n {n} L {l} {norm:?} m {m}: {v} vs {want}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn direct_sum_on_a_short_record() {
        let x = noise(300, 3);
        let y = noise(300, 4);
        let w = correlate_pairs_window(&[&x, &y], &[(0, 1)], 25, Normalization::None).unwrap();
        for (&m, &v) in w[0].lags.iter().zip(&w[0].values) {
            let direct: f64 = (0..300i64)
                .filter(|&k| (0..300).contains(&(k + m)))
                .map(|k| x[(k + m) as usize] * y[k as usize])
                .sum();
            // direct sum of 300 products of |v| < 0.5: rounding ~1e-15.
            assert!((v - direct).abs() < 1e-12, "m {m}: {v} vs {direct}");
        }
    }

    #[test]
    fn pieces_of_any_size_give_the_one_shot_result_to_the_bit() {
        let n = 40_000;
        let (x, y) = (noise(n, 11), noise(n, 12));
        let one = correlate_pairs_window(
            &[&x, &y],
            &[(0, 0), (0, 1), (1, 1)],
            3000,
            Normalization::None,
        )
        .unwrap();
        for piece in [1, 977, 8192, 40_000] {
            let mut w =
                WindowCorrelation::new(2, &[(0, 0), (0, 1), (1, 1)], n, 3000, Normalization::None)
                    .unwrap();
            for (a, b) in x.chunks(piece).zip(y.chunks(piece)) {
                w.push(&[a, b]).unwrap();
            }
            let s = w.finish().unwrap();
            for (p, q) in s.iter().zip(&one) {
                assert_eq!(p.values, q.values, "piece {piece}");
            }
        }
        let mut w = WindowCorrelation::new(1, &[(0, 0)], 10, 3, Normalization::None).unwrap();
        w.push(&[&[1.0; 4]]).unwrap();
        assert!(w.push(&[&[1.0; 7]]).is_err());
        assert!(w.finish().is_err());
    }

    #[test]
    fn bad_input_is_an_error() {
        let x = [1.0, 2.0, 3.0];
        let z = [0.0; 3];
        assert!(matches!(
            correlate_pairs_window(&[&x, &z], &[(0, 1)], 1, Normalization::Coeff),
            Err(DspError::Numerical { .. })
        ));
        assert!(matches!(
            correlate_pairs_window(&[&x, &[1.0, 2.0]], &[(0, 1)], 1, Normalization::None),
            Err(DspError::LengthMismatch { .. })
        ));
        assert!(correlate_pairs_window(&[&x], &[(0, 1)], 1, Normalization::None).is_err());
        assert!(
            correlate_pairs_window(&[&[1.0, f64::NAN]], &[(0, 0)], 1, Normalization::None).is_err()
        );
    }
}
