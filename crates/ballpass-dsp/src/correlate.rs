//! Full-lag cross- and auto-correlation by FFT, as
//! [`scipy.signal.correlate(x, y, mode='full', method='fft')`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.correlate.html)
//! with the lags of
//! [`scipy.signal.correlation_lags`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.correlation_lags.html).

use std::sync::Arc;

use rustfft::num_complex::Complex;

use crate::error::{check_finite, DspError, Result};
use crate::fftplan::{forward_ends, forward_pair, inverse_ends, inverse_pair, HalfComplex};

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

/// From the raw half-length transforms `zx`, `zy` of `x` and `y` (see
/// [`HalfComplex`]), the input of the inverse transform of the
/// cross-spectrum `P[k] = X[k] conj Y[k]` (or `|X[k]|^2` when `AUTO`, with
/// `zy` equal to `zx`), one bin pair `(k, m - k)` at a time: the forward
/// post-processing, the product and the inverse pre-processing in one
/// pass, with realfft's operations in realfft's order (the values equal
/// the separate passes' bit for bit; tested).
#[inline(always)]
fn product_pass<const AUTO: bool>(
    fft: &HalfComplex,
    zx: &[Complex<f64>],
    zy: &[Complex<f64>],
    out: &mut [Complex<f64>],
) {
    let m = out.len();
    let prod = |x: Complex<f64>, y: Complex<f64>| {
        if AUTO {
            Complex::new(x.norm_sqr(), 0.0)
        } else {
            x * y.conj()
        }
    };
    let (Some(&x0), Some(&y0)) = (zx.first(), zy.first()) else {
        return;
    };
    let (x0, xm) = forward_ends(x0);
    let (y0, ym) = forward_ends(y0);
    out[0] = inverse_ends(prod(x0, y0), prod(xm, ym));
    let pairs = fft.pairs();
    let (lo, hi) = out[1..].split_at_mut(pairs);
    let skip = hi.len() - pairs;
    let hi = &mut hi[skip..];
    // Pair i: bins k = 1 + i (lo[i]) and m - k (hi[pairs - 1 - i]).
    let n = pairs;
    let (xl, xh, yl, yh) = (&zx[1..=n], &zx[m - n..m], &zy[1..=n], &zy[m - n..m]);
    let (w, lo, hi) = (&fft.twiddles[..n], &mut lo[..n], &mut hi[..n]);
    // Whole blocks of P pairs (vector code), then the pairs left over one
    // by one.
    let b = n / P * P;
    let blocks = (w[..b].chunks_exact(P).zip(xl.chunks_exact(P)))
        .zip(xh[n - b..].rchunks_exact(P).zip(yl.chunks_exact(P)))
        .zip(yh[n - b..].rchunks_exact(P))
        .zip(
            lo[..b]
                .chunks_exact_mut(P)
                .zip(hi[n - b..].rchunks_exact_mut(P)),
        );
    for ((((w, xl), (xh, yl)), yh), (ol, oh)) in blocks {
        pair_block::<AUTO>(w, (xl, xh), (yl, yh), (ol, oh));
    }
    for i in b..n {
        let r = n - 1 - i;
        let (xk, xj) = forward_pair(w[i], xl[i], xh[r]);
        let (yk, yj) = if AUTO {
            (xk, xj)
        } else {
            forward_pair(w[i], yl[i], yh[r])
        };
        (lo[i], hi[r]) = inverse_pair(w[i], prod(xk, yk), prod(xj, yj));
    }
    if m % 2 == 0 && m > 1 {
        // The centre bin k = m/2: X = conj Z, and the inverse input is
        // conj(2 P).
        let c = m / 2;
        let p = prod(zx[c].conj(), zy[c].conj());
        out[c] = (p + p).conj();
    }
}

/// Bin pairs per block of [`pair_block`].
const P: usize = 8;

/// One component (real or imaginary parts) of [`P`] bins, one bin per
/// lane: the block arithmetic is the same operation in every lane, which
/// the compiler turns into plain vector code (no lane shuffles but those
/// that split the interleaved bins on load and join them on store).
type L = [f64; P];

/// The real and imaginary parts of `b`, lane `t` holding `b[t]` (or
/// `b[P - 1 - t]` when `rev`).
#[inline(always)]
fn split(b: &[Complex<f64>; P], rev: bool) -> (L, L) {
    // Interleaved first (one plain load), then picked lane by lane.
    let v: [f64; 2 * P] = std::array::from_fn(|i| {
        let c = b[i / 2];
        if i % 2 == 0 {
            c.re
        } else {
            c.im
        }
    });
    let at = |t: usize| if rev { P - 1 - t } else { t };
    (
        std::array::from_fn(|t| v[2 * at(t)]),
        std::array::from_fn(|t| v[2 * at(t) + 1]),
    )
}

/// The inverse of [`split`].
#[inline(always)]
fn join(o: &mut [Complex<f64>; P], (re, im): (L, L), rev: bool) {
    let at = |t: usize| if rev { P - 1 - t } else { t };
    let v: [f64; 2 * P] = std::array::from_fn(|i| {
        if i % 2 == 0 {
            re[at(i / 2)]
        } else {
            im[at(i / 2)]
        }
    });
    for (c, p) in o.iter_mut().zip(v.chunks_exact(2)) {
        *c = Complex::new(p[0], p[1]);
    }
}

/// `f(a[t], b[t])` in every lane.
#[inline(always)]
fn lanes(a: L, b: L, f: impl Fn(f64, f64) -> f64) -> L {
    std::array::from_fn(|t| f(a[t], b[t]))
}

/// The part [`forward_pair`] and [`inverse_pair`] share, in every lane:
/// with `s = a + b` and `d = a - b`, `(s.re, d.im, s.im tre + d.re tim,
/// s.im tim - d.re tre)`.
#[inline(always)]
fn twiddled(a: (L, L), b: (L, L), tre: L, tim: L) -> (L, L, L, L) {
    let (sum_re, sum_im) = (lanes(a.0, b.0, |a, b| a + b), lanes(a.1, b.1, |a, b| a + b));
    let (diff_re, diff_im) = (lanes(a.0, b.0, |a, b| a - b), lanes(a.1, b.1, |a, b| a - b));
    (
        sum_re,
        diff_im,
        std::array::from_fn(|t| sum_im[t] * tre[t] + diff_re[t] * tim[t]),
        std::array::from_fn(|t| sum_im[t] * tim[t] - diff_re[t] * tre[t]),
    )
}

/// [`forward_pair`] in every lane: the same operations in the same order.
#[inline(always)]
fn forward_lanes(w: (L, L), zk: (L, L), zj: (L, L)) -> ((L, L), (L, L)) {
    let (tre, tim) = (w.0.map(|v| v * 0.5), w.1.map(|v| v * 0.5));
    let (sum_re, diff_im, twiddled_re, twiddled_im) = twiddled(zk, zj, tre, tim);
    let half_sum_re = sum_re.map(|v| 0.5 * v);
    let half_diff_im = diff_im.map(|v| 0.5 * v);
    (
        (
            lanes(half_sum_re, twiddled_re, |a, b| a + b),
            lanes(half_diff_im, twiddled_im, |a, b| a + b),
        ),
        (
            lanes(half_sum_re, twiddled_re, |a, b| a - b),
            lanes(twiddled_im, half_diff_im, |a, b| a - b),
        ),
    )
}

/// [`inverse_pair`] in every lane: the same operations in the same order.
#[inline(always)]
fn inverse_lanes(w: (L, L), xk: (L, L), xj: (L, L)) -> ((L, L), (L, L)) {
    let (tre, tim) = (w.0, w.1.map(|v| -v));
    let (sum_re, diff_im, twiddled_re, twiddled_im) = twiddled(xk, xj, tre, tim);
    (
        (
            lanes(sum_re, twiddled_re, |a, b| a - b),
            lanes(diff_im, twiddled_im, |a, b| a - b),
        ),
        (
            lanes(sum_re, twiddled_re, |a, b| a + b),
            std::array::from_fn(|t| -twiddled_im[t] - diff_im[t]),
        ),
    )
}

/// The product of [`product_pass`] in every lane: `x conj(y)` as
/// `num_complex` computes it (`(x.re b.re - x.im b.im, x.re b.im + x.im
/// b.re)` with `b = conj y`), or `(|x|^2, 0)` when `AUTO`.
#[inline(always)]
fn product_lanes<const AUTO: bool>(x: (L, L), y: (L, L)) -> (L, L) {
    if AUTO {
        (
            std::array::from_fn(|t| x.0[t] * x.0[t] + x.1[t] * x.1[t]),
            [0.0; P],
        )
    } else {
        let (b_re, b_im) = (y.0, y.1.map(|v| -v));
        (
            std::array::from_fn(|t| x.0[t] * b_re[t] - x.1[t] * b_im[t]),
            std::array::from_fn(|t| x.0[t] * b_im[t] + x.1[t] * b_re[t]),
        )
    }
}

/// [`P`] bin pairs of [`product_pass`]: pair `t` is `xl[t]` with
/// `xh[P - 1 - t]` (and the same for `y` and the outputs), twiddle `w[t]`;
/// each lane does the single-pair functions' operations
/// ([`forward_pair`], the product, [`inverse_pair`]), so the values are
/// theirs bit for bit (tested).
#[inline(always)]
fn pair_block<const AUTO: bool>(
    w: &[Complex<f64>],
    (xl, xh): (&[Complex<f64>], &[Complex<f64>]),
    (yl, yh): (&[Complex<f64>], &[Complex<f64>]),
    (ol, oh): (&mut [Complex<f64>], &mut [Complex<f64>]),
) {
    type B<'s> = &'s [Complex<f64>; P];
    type O<'s> = &'s mut [Complex<f64>; P];
    let (Ok(w), Ok(xl), Ok(xh), Ok(yl), Ok(yh), Ok(ol), Ok(oh)) = (
        B::try_from(w),
        B::try_from(xl),
        B::try_from(xh),
        B::try_from(yl),
        B::try_from(yh),
        O::try_from(ol),
        O::try_from(oh),
    ) else {
        // `product_pass` hands over blocks of exactly P bins.
        if cfg!(debug_assertions) {
            unreachable!("pair_block takes blocks of {P} bins");
        }
        return;
    };
    let w = split(w, false);
    let (xk, xj) = forward_lanes(w, split(xl, false), split(xh, true));
    let (pk, pj) = if AUTO {
        (product_lanes::<true>(xk, xk), product_lanes::<true>(xj, xj))
    } else {
        let (yk, yj) = forward_lanes(w, split(yl, false), split(yh, true));
        (
            product_lanes::<false>(xk, yk),
            product_lanes::<false>(xj, yj),
        )
    };
    let (qk, qj) = inverse_lanes(w, pk, pj);
    join(ol, qk, false);
    join(oh, qj, true);
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
}
