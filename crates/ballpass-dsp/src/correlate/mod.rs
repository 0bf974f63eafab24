//! Full-lag cross- and auto-correlation by FFT, as
//! [`scipy.signal.correlate(x, y, mode='full', method='fft')`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.correlate.html)
//! with the lags of
//! [`scipy.signal.correlation_lags`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.correlation_lags.html).

use std::sync::Arc;

use rustfft::num_complex::Complex;

use crate::error::{check_finite, DspError, Result};
use crate::fftplan::HalfComplex;

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
    // A half-open range (an inclusive one keeps an end flag that stops
    // the loop from vectorising), filled in the widest vectors.
    let (first, end) = (1 - ny as i64, nx as i64);
    crate::simd::widest(
        #[inline(always)]
        || (first..end).collect(),
    )
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
/// The sums are computed by FFT (real transforms of a 3-smooth length
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
///
/// The real FFTs of length `len` run as complex FFTs of `len / 2` (see
/// [`HalfComplex`]); the spectra are kept as those raw half-length
/// transforms, and one pass ([`product_pass`]) turns two of them into the
/// input of the inverse transform.
#[derive(Clone)]
struct Plan {
    len: usize,
    fft: Arc<HalfComplex>,
    /// Raw half-length transform of `x` (`len / 2` bins).
    spec_x: Vec<Complex<f64>>,
    /// Raw half-length transform of `y`.
    spec_y: Vec<Complex<f64>>,
    /// Input of the inverse transform, then its output
    /// `len r[2t] + i len r[2t+1]`.
    buf: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
    /// One raw transform per signal of [`Correlator::correlate_pairs`],
    /// kept between calls (a campaign correlates a record per call).
    signal_spectra: Vec<Vec<Complex<f64>>>,
}

impl Plan {
    fn new(len: usize) -> Plan {
        let fft = crate::fftplan::half_complex(len);
        let m = len / 2;
        let zero = Complex::new(0.0, 0.0);
        Plan {
            len,
            spec_x: vec![zero; m],
            spec_y: vec![zero; m],
            buf: vec![zero; m],
            scratch: vec![zero; fft.scratch_len()],
            signal_spectra: Vec::new(),
            fft,
        }
    }

    /// Raw half-length transform of zero-padded `x` into `spec_x` (or
    /// `spec_y`): `Z = FFT_m(z)`, `z[t] = x[2t] + i x[2t+1]`.
    fn transform(&mut self, x: &[f64], into_y: bool) {
        let out = if into_y {
            &mut self.spec_y
        } else {
            &mut self.spec_x
        };
        transform_into(&self.fft, &mut self.scratch, x, out);
    }
}

/// Raw half-length transform of zero-padded `x` into `out` (which has
/// `len / 2` bins), as [`Plan::transform`].
fn transform_into(
    fft: &HalfComplex,
    scratch: &mut [Complex<f64>],
    x: &[f64],
    out: &mut [Complex<f64>],
) {
    pack(x, out);
    fft.forward.process_with_scratch(out, scratch);
}

/// `sum x^2`, the zero-lag sum the `coeff` normalisation divides by: per
/// block of 1024 samples eight interleaved accumulators (so that the loop
/// vectorises; run through [`crate::simd::widest`]), the blocks added in
/// order, so each accumulator adds at most 128 terms. The `coeff` results
/// are checked against NumPy by `correlate_matches_numpy_full` (1e-12 of
/// the peak).
pub(crate) fn energy(x: &[f64]) -> f64 {
    crate::simd::widest(
        #[inline(always)]
        || {
            x.chunks(1024)
                .map(|block| {
                    let mut acc = [0.0f64; 8];
                    let lanes = block.chunks_exact(8);
                    let rest = lanes.remainder();
                    for c in lanes {
                        for (a, v) in acc.iter_mut().zip(c) {
                            *a += v * v;
                        }
                    }
                    let mut sum: f64 = acc.iter().sum();
                    for v in rest {
                        sum += v * v;
                    }
                    sum
                })
                .sum()
        },
    )
}

/// `out[t] = x[2t] + i x[2t+1]`, zero past the end of `x`.
fn pack(x: &[f64], out: &mut [Complex<f64>]) {
    let pairs = x.chunks_exact(2);
    let rest = pairs.remainder();
    let mut n = 0;
    for (o, p) in out.iter_mut().zip(pairs) {
        *o = Complex::new(p[0], p[1]);
        n += 1;
    }
    if let (Some(o), [last]) = (out.get_mut(n), rest) {
        *o = Complex::new(*last, 0.0);
        n += 1;
    }
    out[n..].fill(Complex::new(0.0, 0.0));
}

/// A reusable full-lag correlator: holds FFT plans and buffers for the
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
        let Plan {
            fft,
            spec_x,
            spec_y,
            buf,
            ..
        } = plan;
        crate::simd::widest(
            #[inline(always)]
            || product_pass::<false>(fft, spec_x, spec_y, buf),
        );
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
        let Plan {
            fft, spec_x, buf, ..
        } = plan;
        crate::simd::widest(
            #[inline(always)]
            || product_pass::<true>(fft, spec_x, spec_x, buf),
        );
        let norm = self.norm_with(x.len(), || {
            let e = energy(x);
            (e, e)
        })?;
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
        // Each signal's transform into its own kept buffer, and its energy
        // once (for `Coeff`), however many pairs use it.
        let m = plan.len / 2;
        let mut spectra = std::mem::take(&mut plan.signal_spectra);
        spectra.resize_with(signals.len(), Vec::new);
        for (s, spec) in signals.iter().zip(spectra.iter_mut()) {
            spec.resize(m, Complex::new(0.0, 0.0));
            transform_into(&plan.fft, &mut plan.scratch, s, spec);
        }
        let energies: Vec<f64> = if self.settings.normalization == Normalization::Coeff {
            signals.iter().map(|s| energy(s)).collect()
        } else {
            Vec::new()
        };
        let mut results = Vec::with_capacity(pairs.len());
        for &(a, b) in pairs {
            let plan = self.plan.as_mut().expect("planned above");
            let (fft, buf) = (&plan.fft, &mut plan.buf);
            let (sa, sb) = (&spectra[a], &spectra[b]);
            if a == b {
                crate::simd::widest(
                    #[inline(always)]
                    || product_pass::<true>(fft, sa, sa, buf),
                );
            } else {
                crate::simd::widest(
                    #[inline(always)]
                    || product_pass::<false>(fft, sa, sb, buf),
                );
            }
            let mut out = Correlation {
                lags: Vec::new(),
                values: Vec::new(),
            };
            let norm = self.norm_with(n, || (energies[a], energies[b]));
            let plan = self.plan.as_mut().expect("planned above");
            let norm = match norm {
                Ok(norm) => norm,
                Err(e) => {
                    plan.signal_spectra = spectra;
                    return Err(e);
                }
            };
            inverse_to_lags(plan, n, n, &mut out.values, norm);
            set_lags(&mut out, n, n);
            results.push(out);
        }
        self.plan.as_mut().expect("planned above").signal_spectra = spectra;
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
        self.norm_with(x.len(), || (energy(x), energy(y)))
    }

    /// [`Self::norm`] for inputs of which `x` has `nx` samples, with their
    /// energies `(sum x^2, sum y^2)` from `energies` (called only for
    /// `Coeff`).
    fn norm_with(&self, nx: usize, energies: impl FnOnce() -> (f64, f64)) -> Result<Norm> {
        Ok(match self.settings.normalization {
            Normalization::None => Norm::None,
            Normalization::Biased => Norm::Times(1.0 / nx as f64),
            Normalization::Unbiased => Norm::Unbiased,
            Normalization::Coeff => {
                let (exx, eyy) = energies();
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

/// Inverse FFT of `plan.buf` (from [`product_pass`]) and the
/// rearrangement of the circular result into lags `-(ny-1) ..= nx-1`.
fn inverse_to_lags(plan: &mut Plan, nx: usize, ny: usize, out: &mut Vec<f64>, norm: Norm) {
    let len = plan.len;
    plan.fft
        .inverse
        .process_with_scratch(&mut plan.buf, &mut plan.scratch);
    let scale = 1.0 / len as f64;
    let n_out = nx + ny - 1;
    if out.len() != n_out {
        out.clear();
        out.resize(n_out, 0.0);
    }
    // Negative lags m = -(ny-1) ..= -1 sit at the end of the circular result.
    let (neg, pos) = out.split_at_mut(ny - 1);
    let (from_neg, buf) = (len - (ny - 1), &plan.buf[..]);
    crate::simd::widest(
        #[inline(always)]
        || match norm {
            Norm::None => {
                unpack(buf, from_neg, neg, |_, v| v * scale);
                unpack(buf, 0, pos, |_, v| v * scale);
            }
            Norm::Times(f) => {
                unpack(buf, from_neg, neg, |_, v| v * scale * f);
                unpack(buf, 0, pos, |_, v| v * scale * f);
            }
            Norm::Unbiased => {
                // Output i is lag m = i - (ny-1), with N - |m| overlapping terms.
                unpack(buf, from_neg, neg, |i, v| {
                    let m = (ny - 1) - i;
                    v * scale / (nx - m) as f64
                });
                unpack(buf, 0, pos, |m, v| v * scale / (nx - m) as f64);
            }
        },
    );
}

/// `dst[i] = f(i, r[from + i])` where `r[2t] = buf[t].re` and
/// `r[2t+1] = buf[t].im` (the inverse transform's real output).
#[inline(always)]
fn unpack(buf: &[Complex<f64>], from: usize, dst: &mut [f64], f: impl Fn(usize, f64) -> f64) {
    let mut src = &buf[from / 2..];
    let mut dst = dst;
    let mut first = 0;
    if from % 2 == 1 {
        let (Some(o), Some(c)) = (dst.first_mut(), src.first()) else {
            return;
        };
        *o = f(0, c.im);
        (dst, src, first) = (&mut dst[1..], &src[1..], 1);
    }
    let n = (dst.len() / 2).min(src.len());
    let (src, (pairs, rest)) = (&src[..n], dst.split_at_mut(2 * n));
    for t in 0..n {
        pairs[2 * t] = f(first + 2 * t, src[t].re);
        pairs[2 * t + 1] = f(first + 2 * t + 1, src[t].im);
    }
    if let (Some(o), Some(c)) = (rest.first_mut(), buf.get((from + first) / 2 + n)) {
        *o = f(first + 2 * n, c.re);
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

mod pairs;
#[cfg(test)]
mod tests;

use pairs::product_pass;
