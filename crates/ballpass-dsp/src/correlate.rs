//! Full-lag cross- and auto-correlation by FFT, as
//! [`scipy.signal.correlate(x, y, mode='full', method='fft')`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.correlate.html)
//! with the lags of
//! [`scipy.signal.correlation_lags`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.correlation_lags.html).

use std::sync::Arc;

use realfft::{ComplexToReal, RealToComplex};
use rustfft::num_complex::Complex;

use crate::error::{check_finite, DspError, Result};

/// How the raw lag sums are scaled.
///
/// With `z[m]` the raw sum (see [`correlate`]) and `N` the common length of
/// `x` and `y`:
///
/// ```text
/// None:      r[m] = z[m]
/// Biased:    r[m] = z[m] / N
/// Unbiased:  r[m] = z[m] / (N - |m|)
/// Coeff:     r[m] = z[m] / sqrt(sum x^2 * sum y^2)      (= z[m] / sqrt(Rxx[0] Ryy[0]))
/// ```
///
/// These are MATLAB `xcorr`'s `'none'`, `'biased'`, `'unbiased'` and
/// `'normalized'` (SciPy offers only `None`). `Biased` and `Unbiased` need
/// `x` and `y` of equal length (`N` is ambiguous otherwise; MATLAB would
/// zero-pad the shorter one); `None` and `Coeff` accept any lengths.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Normalization {
    /// Raw sums, as SciPy and MATLAB `xcorr(x, y)`.
    #[default]
    None,
    /// Divide by the length `N` (lengths must be equal).
    Biased,
    /// Divide by the number of overlapping samples `N - |m|` (lengths must be equal).
    Unbiased,
    /// Divide by `sqrt(Rxx[0] Ryy[0])`, so an autocorrelation is 1 at lag 0.
    Coeff,
}

/// Settings of a [`Correlator`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CorrelateSettings {
    /// Scaling of the lag sums (default: none, as SciPy).
    pub normalization: Normalization,
}

/// A full-lag correlation: one value per lag.
#[derive(Debug, Clone, PartialEq)]
pub struct Correlation {
    /// Lags in samples, `-(Ny-1) ..= Nx-1` in steps of one.
    pub lags: Vec<i64>,
    /// Correlation at each lag, normalised as requested.
    pub values: Vec<f64>,
}

impl Correlation {
    /// Lags in seconds, `lags[i] / fs_hz`.
    ///
    /// With [`correlate`]'s convention, a positive lag `m` pairs `x[n + m]`
    /// with `y[n]`: if `y` is `x` delayed by `d` samples, the peak is at
    /// `-d / fs_hz` seconds.
    pub fn lag_s(&self, fs_hz: f64) -> Vec<f64> {
        self.lags.iter().map(|&m| m as f64 / fs_hz).collect()
    }

    /// Value at lag `m` (samples), if `m` is in range.
    pub fn at_lag(&self, m: i64) -> Option<f64> {
        let first = *self.lags.first()?;
        let i = usize::try_from(m - first).ok()?;
        self.values.get(i).copied()
    }
}

/// Lags of a full correlation of lengths `nx` and `ny`: `-(ny-1) ..= nx-1`,
/// as `scipy.signal.correlation_lags(nx, ny, mode='full')`.
///
/// Empty if either length is zero.
///
/// ```
/// assert_eq!(ballpass_dsp::correlation_lags(3, 2), vec![-1, 0, 1, 2]);
/// ```
pub fn correlation_lags(nx: usize, ny: usize) -> Vec<i64> {
    if nx == 0 || ny == 0 {
        return Vec::new();
    }
    (-(ny as i64 - 1)..=(nx as i64 - 1)).collect()
}

/// Full-lag correlation of `x` and `y` with a one-off [`Correlator`].
///
/// ```text
/// z[m] = sum_n x[n + m] y[n],   m = -(Ny-1) ..= Nx-1
/// ```
///
/// This equals `numpy.correlate(x, y, 'full')`,
/// `scipy.signal.correlate(x, y)` and MATLAB `xcorr(x, y)` (the thesis'
/// Eq. 7.1). If `y` is `x` delayed by `d` samples the peak is at `m = -d`.
/// The sums are computed by FFT (real transforms of a 5-smooth length
/// `>= Nx + Ny - 1`), so each value carries an absolute rounding error of
/// order `1e-16 * sqrt(sum x^2 * sum y^2)`, as SciPy's `method='fft'`.
///
/// ```
/// use ballpass_dsp::{correlate, Normalization};
/// let c = correlate(&[1.0, 2.0, 3.0], &[0.0, 1.0, 0.5], Normalization::None).unwrap();
/// // numpy.correlate([1, 2, 3], [0, 1, 0.5], 'full') == [0.5, 2, 3.5, 3, 0]
/// assert_eq!(c.lags, vec![-2, -1, 0, 1, 2]);
/// let want = [0.5, 2.0, 3.5, 3.0, 0.0];
/// assert!(c.values.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12));
/// ```
///
/// # Errors
/// [`DspError::Empty`] or [`DspError::NonFinite`] for `x` or `y`;
/// [`DspError::LengthMismatch`] for `Biased`/`Unbiased` with unequal
/// lengths; [`DspError::Numerical`] for `Coeff` when `x` or `y` is all zeros.
pub fn correlate(x: &[f64], y: &[f64], normalization: Normalization) -> Result<Correlation> {
    Correlator::new(CorrelateSettings { normalization }).correlate(x, y)
}

/// Plans and buffers for one FFT length.
#[derive(Clone)]
struct Plan {
    len: usize,
    forward: Arc<dyn RealToComplex<f64>>,
    inverse: Arc<dyn ComplexToReal<f64>>,
    buf: Vec<f64>,
    spec_x: Vec<Complex<f64>>,
    spec_y: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
}

impl Plan {
    fn new(len: usize) -> Plan {
        let forward = crate::fftplan::forward(len);
        let inverse = crate::fftplan::inverse(len);
        let scratch_len = forward.get_scratch_len().max(inverse.get_scratch_len());
        Plan {
            len,
            buf: forward.make_input_vec(),
            spec_x: forward.make_output_vec(),
            spec_y: forward.make_output_vec(),
            scratch: vec![Complex::new(0.0, 0.0); scratch_len],
            forward,
            inverse,
        }
    }

    /// Zero-padded forward transform of `x` into `spec_x` (or `spec_y`).
    fn transform(&mut self, x: &[f64], into_y: bool) {
        self.buf[..x.len()].copy_from_slice(x);
        self.buf[x.len()..].fill(0.0);
        let out = if into_y {
            &mut self.spec_y
        } else {
            &mut self.spec_x
        };
        self.forward
            .process_with_scratch(&mut self.buf, out, &mut self.scratch)
            .expect("buffer lengths come from the plan");
    }
}

/// A reusable full-lag correlator: holds realfft plans and buffers for the
/// last FFT length used, so repeated correlations of equal-length records
/// plan once.
///
/// `Correlator` is `Send + Sync` and cheap to clone (plans are shared
/// `Arc`s); give each thread its own clone. See [`correlate`] for the
/// formula and conventions. In a hot loop prefer
/// [`Correlator::correlate_into`]: a full-lag result of two 30 000-sample
/// records is ~1 MB, and fresh pages from the allocator can cost more than
/// the FFTs themselves.
///
/// ```
/// use ballpass_dsp::{CorrelateSettings, Correlator, Normalization};
/// let mut c = Correlator::new(CorrelateSettings { normalization: Normalization::Coeff });
/// let x = [1.0, -2.0, 0.5, 3.0];
/// let r = c.autocorrelate(&x).unwrap();
/// assert!((r.at_lag(0).unwrap() - 1.0).abs() < 1e-12);
/// ```
#[derive(Clone)]
pub struct Correlator {
    settings: CorrelateSettings,
    plan: Option<Plan>,
}

impl std::fmt::Debug for Correlator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Correlator")
            .field("settings", &self.settings)
            .field("fft_len", &self.plan.as_ref().map(|p| p.len))
            .finish()
    }
}

impl Correlator {
    /// A correlator with the given settings; FFTs are planned on first use.
    pub fn new(settings: CorrelateSettings) -> Correlator {
        Correlator {
            settings,
            plan: None,
        }
    }

    /// A correlator already planned for inputs of lengths `nx` and `ny`.
    pub fn with_lengths(settings: CorrelateSettings, nx: usize, ny: usize) -> Correlator {
        let mut c = Correlator::new(settings);
        c.plan_for(nx + ny);
        c
    }

    /// The settings this correlator was built with.
    pub fn settings(&self) -> &CorrelateSettings {
        &self.settings
    }

    /// Full-lag cross-correlation `z[m] = sum_n x[n + m] y[n]`, normalised
    /// per the settings. See [`correlate`].
    ///
    /// # Errors
    /// As [`correlate`].
    pub fn correlate(&mut self, x: &[f64], y: &[f64]) -> Result<Correlation> {
        let mut out = Correlation {
            lags: Vec::new(),
            values: Vec::new(),
        };
        self.correlate_into(x, y, &mut out)?;
        Ok(out)
    }

    /// [`Correlator::correlate`] writing into `out`, whose vectors are
    /// reused (no allocation once they are large enough).
    ///
    /// # Errors
    /// As [`correlate`]; `out` is unspecified on error.
    pub fn correlate_into(&mut self, x: &[f64], y: &[f64], out: &mut Correlation) -> Result<()> {
        check_finite("x", x)?;
        check_finite("y", y)?;
        self.check_lengths(x.len(), y.len())?;
        let plan = self.plan_for(x.len() + y.len());
        plan.transform(x, false);
        plan.transform(y, true);
        for (a, b) in plan.spec_x.iter_mut().zip(&plan.spec_y) {
            *a *= b.conj();
        }
        let norm = self.norm(x, y)?;
        let plan = self.plan.as_mut().expect("planned above");
        inverse_to_lags(plan, x.len(), y.len(), &mut out.values, norm);
        set_lags(out, x.len(), y.len());
        Ok(())
    }

    /// Full-lag autocorrelation `z[m] = sum_n x[n + m] x[n]` (one forward
    /// FFT instead of two). Equal to `correlate(x, x)`.
    ///
    /// # Errors
    /// As [`correlate`].
    pub fn autocorrelate(&mut self, x: &[f64]) -> Result<Correlation> {
        let mut out = Correlation {
            lags: Vec::new(),
            values: Vec::new(),
        };
        self.autocorrelate_into(x, &mut out)?;
        Ok(out)
    }

    /// [`Correlator::autocorrelate`] writing into `out` (buffers reused).
    ///
    /// # Errors
    /// As [`correlate`]; `out` is unspecified on error.
    pub fn autocorrelate_into(&mut self, x: &[f64], out: &mut Correlation) -> Result<()> {
        check_finite("x", x)?;
        let plan = self.plan_for(2 * x.len());
        plan.transform(x, false);
        for a in plan.spec_x.iter_mut() {
            *a = Complex::new(a.norm_sqr(), 0.0);
        }
        let norm = self.norm(x, x)?;
        let plan = self.plan.as_mut().expect("planned above");
        inverse_to_lags(plan, x.len(), x.len(), &mut out.values, norm);
        set_lags(out, x.len(), x.len());
        Ok(())
    }

    /// Full-lag correlations `z[m] = sum_n s_a[n + m] s_b[n]` of several
    /// signals for the listed index pairs `(a, b)`, normalised per the
    /// settings; each signal is transformed once, so `k` signals and `p`
    /// pairs cost `k` forward and `p` inverse FFTs instead of `2p` and `p`.
    ///
    /// Result `i` equals `correlate(signals[a_i], signals[b_i])` (a pair
    /// `(a, a)` is an autocorrelation).
    ///
    /// ```
    /// use ballpass_dsp::{CorrelateSettings, Correlator};
    /// let x = [1.0, 2.0, 3.0];
    /// let y = [0.0, 1.0, 0.5];
    /// let mut c = Correlator::new(CorrelateSettings::default());
    /// let r = c.correlate_pairs(&[&x, &y], &[(0, 0), (0, 1)]).unwrap();
    /// let want = [0.5, 2.0, 3.5, 3.0, 0.0]; // numpy.correlate(x, y, 'full')
    /// assert!(r[1].values.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12));
    /// ```
    ///
    /// # Errors
    /// As [`correlate`]; also [`DspError::LengthMismatch`] if the signals
    /// differ in length and [`DspError::InvalidSetting`] for a pair index
    /// out of range.
    pub fn correlate_pairs(
        &mut self,
        signals: &[&[f64]],
        pairs: &[(usize, usize)],
    ) -> Result<Vec<Correlation>> {
        let n = crate::error::check_signal_set(signals, pairs, "signals (correlate_pairs)")?;
        let plan = self.plan_for(2 * n);
        let spectra: Vec<Vec<Complex<f64>>> = signals
            .iter()
            .map(|s| {
                plan.transform(s, false);
                plan.spec_x.clone()
            })
            .collect();
        let mut results = Vec::with_capacity(pairs.len());
        for &(a, b) in pairs {
            let plan = self.plan.as_mut().expect("planned above");
            if a == b {
                for (o, v) in plan.spec_x.iter_mut().zip(&spectra[a]) {
                    *o = Complex::new(v.norm_sqr(), 0.0);
                }
            } else {
                for ((o, x), y) in plan.spec_x.iter_mut().zip(&spectra[a]).zip(&spectra[b]) {
                    *o = x * y.conj();
                }
            }
            let mut out = Correlation {
                lags: Vec::new(),
                values: Vec::new(),
            };
            let norm = self.norm(signals[a], signals[b])?;
            let plan = self.plan.as_mut().expect("planned above");
            inverse_to_lags(plan, n, n, &mut out.values, norm);
            set_lags(&mut out, n, n);
            results.push(out);
        }
        Ok(results)
    }

    fn check_lengths(&self, nx: usize, ny: usize) -> Result<()> {
        match self.settings.normalization {
            Normalization::Biased | Normalization::Unbiased if nx != ny => {
                Err(DspError::LengthMismatch {
                    what: "x and y (biased/unbiased correlation)",
                    expected: nx,
                    found: ny,
                })
            }
            _ => Ok(()),
        }
    }

    /// The plan for full correlations with `nx + ny` total samples.
    fn plan_for(&mut self, n_total: usize) -> &mut Plan {
        let len = next_fast_even_len(n_total.saturating_sub(1).max(1));
        if self.plan.as_ref().map(|p| p.len) != Some(len) {
            self.plan = Some(Plan::new(len));
        }
        self.plan.as_mut().expect("plan was just set")
    }

    /// The scaling of the lag sums for `x` and `y` (see [`Normalization`]).
    fn norm(&self, x: &[f64], y: &[f64]) -> Result<Norm> {
        Ok(match self.settings.normalization {
            Normalization::None => Norm::None,
            Normalization::Biased => Norm::Times(1.0 / x.len() as f64),
            Normalization::Unbiased => Norm::Unbiased,
            Normalization::Coeff => {
                let exx: f64 = x.iter().map(|v| v * v).sum();
                let eyy: f64 = y.iter().map(|v| v * v).sum();
                if exx == 0.0 || eyy == 0.0 {
                    return Err(DspError::Numerical {
                        what: "coefficient-normalised correlation",
                        reason: format!(
                            "{} is all zeros (zero energy), so R[0] cannot normalise it",
                            if exx == 0.0 { "x" } else { "y" }
                        ),
                    });
                }
                Norm::Times(1.0 / (exx * eyy).sqrt())
            }
        })
    }
}

/// How [`inverse_to_lags`] scales each lag sum after the inverse FFT's
/// `1 / len`: the same two roundings as scaling in a second pass.
#[derive(Debug, Clone, Copy)]
enum Norm {
    /// No further scaling.
    None,
    /// Times a constant (biased: `1 / N`; coeff: `1 / sqrt(Rxx[0] Ryy[0])`).
    Times(f64),
    /// Divided by the overlap `N - |m|`.
    Unbiased,
}

/// `out.lags = -(ny-1) ..= nx-1`, rewritten only when it is not already.
fn set_lags(out: &mut Correlation, nx: usize, ny: usize) {
    let first = -(ny as i64 - 1);
    let len = nx + ny - 1;
    if out.lags.len() != len || out.lags.first() != Some(&first) {
        out.lags.clear();
        out.lags.extend(first..=(nx as i64 - 1));
    }
}

/// Inverse FFT of `plan.spec_x` (a cross-spectrum) and the rearrangement of
/// the circular result into lags `-(ny-1) ..= nx-1`.
fn inverse_to_lags(plan: &mut Plan, nx: usize, ny: usize, out: &mut Vec<f64>, norm: Norm) {
    let len = plan.len;
    // A real signal's DC (and, for even lengths, Nyquist) bins are real;
    // clear the rounding residue so realfft accepts the spectrum.
    plan.spec_x[0].im = 0.0;
    if len % 2 == 0 {
        let last = plan.spec_x.len() - 1;
        plan.spec_x[last].im = 0.0;
    }
    plan.inverse
        .process_with_scratch(&mut plan.spec_x, &mut plan.buf, &mut plan.scratch)
        .expect("buffer lengths come from the plan and DC/Nyquist are real");
    let scale = 1.0 / len as f64;
    out.clear();
    out.reserve(nx + ny - 1);
    // Negative lags m = -(ny-1) ..= -1 sit at the end of the circular result.
    let (neg, pos) = (&plan.buf[len - (ny - 1)..], &plan.buf[..nx]);
    match norm {
        Norm::None => {
            out.extend(neg.iter().map(|v| v * scale));
            out.extend(pos.iter().map(|v| v * scale));
        }
        Norm::Times(f) => {
            out.extend(neg.iter().map(|v| v * scale * f));
            out.extend(pos.iter().map(|v| v * scale * f));
        }
        Norm::Unbiased => {
            // Output i is lag m = i - (ny-1), with N - |m| overlapping terms.
            out.extend(neg.iter().enumerate().map(|(i, v)| {
                let m = (ny - 1) - i;
                v * scale / (nx - m) as f64
            }));
            out.extend(
                pos.iter()
                    .enumerate()
                    .map(|(m, v)| v * scale / (nx - m) as f64),
            );
        }
    }
}

/// Smallest even `n >= target` whose only prime factors are 2 and 3.
///
/// SciPy's `next_fast_len` also admits 5 (pocketfft has fast radix-5
/// passes); RustFFT's radix-2/3 paths are faster, so the next 3-smooth
/// length wins although it is up to ~4 % longer: a forward plus inverse
/// real FFT of 62 208 = 2^8 3^5 takes 6-17 % less time than of
/// 60 000 = 2^5 3 5^4, and 3-12 % less at the other lengths measured
/// (2 000 to 200 000).
pub(crate) fn next_fast_even_len(target: usize) -> usize {
    let mut n = target.max(2);
    n += n % 2;
    loop {
        let mut m = n;
        for p in [2, 3] {
            while m % p == 0 {
                m /= p;
            }
        }
        if m == 1 {
            return n;
        }
        n += 2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
