//! Zero-phase (forward-backward) filtering: [`ZeroPhaseFilter`] and
//! [`sosfiltfilt`], as `scipy.signal.sosfiltfilt`.

use super::{sosfilt_zi, Sos};
use crate::biquad::Cascade;
use crate::error::{all_finite, check_finite, invalid, DspError, Result};

/// How [`sosfiltfilt`] extends the signal at both ends before filtering
/// (SciPy's `padtype`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PadType {
    /// Point-symmetric about the end sample: `2 x[0] - x[k]` (SciPy `'odd'`,
    /// the default).
    #[default]
    Odd,
    /// Mirror about the end sample: `x[k]` (SciPy `'even'`).
    Even,
    /// Repeat the end sample (SciPy `'constant'`).
    Constant,
    /// No extension; the padding length is then 0 (SciPy `padtype=None`).
    None,
}

/// How many samples [`sosfiltfilt`] adds at each end (SciPy's `padlen`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PadLen {
    /// SciPy's default, [`Sos::default_padlen`].
    #[default]
    Auto,
    /// This many samples (must be less than the signal length).
    Samples(usize),
}

/// Settings of [`ZeroPhaseFilter`] / [`sosfiltfilt`]; the default is SciPy's
/// (`padtype='odd'`, `padlen=None`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FiltFiltSettings {
    /// End extension.
    pub pad_type: PadType,
    /// Extension length.
    pub pad_len: PadLen,
}

/// A zero-phase (forward-backward) filter, planned once and run on many
/// signals: `scipy.signal.sosfiltfilt(sos, x, padtype, padlen)`.
///
/// ```text
/// ext = pad(x, padlen)                          (odd: 2 x[0] - x[padlen..1], ...)
/// y   = sosfilt(sos, ext, zi = zi * ext[0])     forward
/// y   = sosfilt(sos, rev(y), zi = zi * y[-1])   backward, then reversed
/// out = y[padlen .. len - padlen]
/// ```
///
/// with `zi = sosfilt_zi(sos)`. The magnitude response is `|H|^2`, the phase
/// is zero. Holds no scratch, so it is `Send + Sync` and can be shared
/// between threads.
#[derive(Debug, Clone, PartialEq)]
pub struct ZeroPhaseFilter {
    sos: Sos,
    pub(crate) cascade: Cascade,
    zi: Vec<[f64; 2]>,
    pub(crate) pad_type: PadType,
    pub(crate) pad_len: usize,
}

impl ZeroPhaseFilter {
    /// Plans the filter: computes `sosfilt_zi` and the padding length.
    ///
    /// # Errors
    /// As [`sosfilt_zi`].
    pub fn new(sos: Sos, settings: FiltFiltSettings) -> Result<ZeroPhaseFilter> {
        let zi = sosfilt_zi(&sos)?;
        let pad_len = match (settings.pad_type, settings.pad_len) {
            (PadType::None, _) => 0,
            (_, PadLen::Auto) => sos.default_padlen(),
            (_, PadLen::Samples(n)) => n,
        };
        Ok(ZeroPhaseFilter {
            cascade: Cascade::new(&sos.0),
            sos,
            zi,
            pad_type: settings.pad_type,
            pad_len,
        })
    }

    /// The sections this filter runs.
    pub fn sos(&self) -> &Sos {
        &self.sos
    }

    /// Samples added at each end (SciPy's `edge`).
    pub fn pad_len(&self) -> usize {
        self.pad_len
    }

    /// Filters `x` forward and backward.
    ///
    /// # Errors
    /// [`DspError::Empty`] / [`DspError::NonFinite`] for a bad `x`;
    /// [`DspError::TooShort`] if `x.len() <= pad_len` (SciPy raises
    /// "The length of the input vector x must be greater than padlen").
    pub fn apply(&self, x: &[f64]) -> Result<Vec<f64>> {
        let mut out = Vec::new();
        self.apply_into(x, &mut out)?;
        Ok(out)
    }

    /// As [`ZeroPhaseFilter::apply`], writing into `out` (cleared first) so
    /// that its allocation can be reused.
    ///
    /// # Errors
    /// As [`ZeroPhaseFilter::apply`].
    pub fn apply_into(&self, x: &[f64], out: &mut Vec<f64>) -> Result<()> {
        self.pad_into(x, out)?;
        self.filter_padded(out, x.len());
        Ok(())
    }

    /// Filters several signals forward and backward, as [`ZeroPhaseFilter::apply`]
    /// on each (the analysis filters friction, velocity error and optical
    /// channels with one filter).
    ///
    /// Signals of equal length are paired and run as the two lanes of one
    /// SIMD pass; an odd one out, or one of another length, runs alone, and
    /// so does every signal long enough for `apply` to split it into more
    /// than two chunks (4 or 8 on a CPU with AVX2 or AVX-512F), which is
    /// faster than a pair. The results equal `apply`'s to rounding (the
    /// paired lanes run sample by sample, `apply` splits a long signal into
    /// chunks; both stay within the fixture tolerances of SciPy).
    ///
    /// ```
    /// use ballpass_dsp::{butter, FiltFiltSettings, FilterBand, ZeroPhaseFilter};
    /// let sos = butter(5, FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0)?;
    /// let filter = ZeroPhaseFilter::new(sos, FiltFiltSettings::default())?;
    /// let (a, b) = (vec![1.0; 100], vec![-2.0; 100]);
    /// let y = filter.apply_many(&[&a, &b])?;
    /// assert!(y[1].iter().all(|v| (v + 2.0).abs() < 1e-12)); // DC passes
    /// # Ok::<(), ballpass_dsp::DspError>(())
    /// ```
    ///
    /// # Errors
    /// As [`ZeroPhaseFilter::apply`] for any signal; the message names the
    /// signal's position in `xs`.
    pub fn apply_many(&self, xs: &[&[f64]]) -> Result<Vec<Vec<f64>>> {
        let mut out: Vec<Vec<f64>> = Vec::with_capacity(xs.len());
        for (k, x) in xs.iter().enumerate() {
            let mut buf = Vec::new();
            self.pad_into(x, &mut buf)
                .map_err(|e| invalid("xs", format!("signal {k}: {e}")))?;
            out.push(buf);
        }
        let mut i = 0;
        while i < out.len() {
            let n = xs[i].len();
            let pair = i + 1 < out.len() && out[i].len() == out[i + 1].len();
            if pair && self.cascade.pairs_pay(n + self.pad_len) {
                let (a, b) = out.split_at_mut(i + 1);
                self.filter_pair(&mut a[i], &mut b[0], n);
                i += 2;
            } else {
                self.filter_padded(&mut out[i], n);
                i += 1;
            }
        }
        Ok(out)
    }

    /// Checks `x` and writes it with its end extensions into `out`, rotated
    /// so that the signal comes first:
    ///
    /// ```text
    /// out = [x (n) | right extension (edge) | left extension (edge)]
    /// ```
    ///
    /// The backward pass never needs the left extension (its outputs there
    /// are dropped), so it is filtered on its own first, only for the state
    /// it leaves; the result then ends up at the start of `out` and is
    /// trimmed by truncation instead of a copy.
    fn pad_into(&self, x: &[f64], out: &mut Vec<f64>) -> Result<()> {
        let n = x.len();
        let edge = self.pad_len;
        if n <= edge {
            check_finite("x", x)?;
            return Err(DspError::TooShort {
                what: "x (sosfiltfilt needs more samples than padlen)",
                needed: edge + 1,
                found: n,
            });
        }
        out.clear();
        out.reserve(n + 2 * edge);
        // Copy and check block by block, each block checked while in L1.
        for block in x.chunks(1024) {
            out.extend_from_slice(block);
            if !all_finite(block) {
                check_finite("x", x)?;
            }
        }
        let (first, last) = (x[0], x[n - 1]);
        match self.pad_type {
            PadType::Odd => {
                out.extend((0..edge).map(|i| 2.0 * last - x[n - 2 - i]));
                out.extend((0..edge).map(|i| 2.0 * first - x[edge - i]));
            }
            PadType::Even => {
                out.extend((0..edge).map(|i| x[n - 2 - i]));
                out.extend((0..edge).map(|i| x[edge - i]));
            }
            PadType::Constant => {
                out.extend(std::iter::repeat_n(last, edge));
                out.extend(std::iter::repeat_n(first, edge));
            }
            PadType::None => {}
        }
        Ok(())
    }

    /// `sosfilt_zi` scaled to the level `v`: the steady state for a
    /// constant input `v`.
    pub(crate) fn steady(&self, v: f64) -> Vec<[f64; 2]> {
        self.zi.iter().map(|r| [r[0] * v, r[1] * v]).collect()
    }

    /// Splits a buffer laid out by [`ZeroPhaseFilter::pad_into`] for a
    /// signal of `n` samples into the part both passes run over (signal and
    /// right extension) and the left extension, and runs the forward pass
    /// over the left extension: the DF-II-T state it leaves is returned.
    fn lead_in<'a>(&self, buf: &'a mut [f64], n: usize) -> (&'a mut [f64], Vec<[f64; 2]>) {
        let (main, left) = buf.split_at_mut(n + self.pad_len);
        let x0 = left.first().copied().unwrap_or(main[0]);
        let mut z = self.steady(x0);
        self.cascade.filter(left, &mut z, false);
        (main, z)
    }

    /// Forward and backward pass over a buffer laid out by
    /// [`ZeroPhaseFilter::pad_into`] for a signal of `n` samples, which is
    /// left holding the `n` filtered samples.
    fn filter_padded(&self, buf: &mut Vec<f64>, n: usize) {
        let (main, z) = self.lead_in(buf, n);
        self.cascade.filter_from(main, &z, false);
        let z = self.steady(main[main.len() - 1]);
        self.cascade.filter_from(main, &z, true);
        buf.truncate(n);
    }

    /// [`ZeroPhaseFilter::filter_padded`] on two padded signals of equal
    /// length `n` at once.
    fn filter_pair(&self, a: &mut Vec<f64>, b: &mut Vec<f64>, n: usize) {
        let ((ma, za), (mb, zb)) = (self.lead_in(a, n), self.lead_in(b, n));
        self.cascade
            .filter_pair([&mut *ma, &mut *mb], [&za, &zb], false);
        let (za, zb) = (self.steady(ma[ma.len() - 1]), self.steady(mb[mb.len() - 1]));
        self.cascade.filter_pair([ma, mb], [&za, &zb], true);
        a.truncate(n);
        b.truncate(n);
    }
}

/// Zero-phase forward-backward filtering with SciPy's defaults
/// (`padtype='odd'`, `padlen = 3 (2 n_sections + 1 - min(#b2==0, #a2==0))`),
/// matching `scipy.signal.sosfiltfilt(sos, x)`. See [`ZeroPhaseFilter`] to
/// plan once and filter many signals.
///
/// ```
/// use ballpass_dsp::{butter, sosfiltfilt, FilterBand};
/// let sos = butter(5, FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0).unwrap();
/// let x = vec![3.0; 100];
/// let y = sosfiltfilt(&sos, &x).unwrap();
/// assert!(y.iter().all(|v| (v - 3.0).abs() < 1e-12)); // DC passes untouched
/// ```
///
/// # Errors
/// As [`ZeroPhaseFilter::new`] and [`ZeroPhaseFilter::apply`]; for the
/// 5th-order Butterworth `x` needs at least 19 samples.
pub fn sosfiltfilt(sos: &Sos, x: &[f64]) -> Result<Vec<f64>> {
    ZeroPhaseFilter::new(sos.clone(), FiltFiltSettings::default())?.apply(x)
}
