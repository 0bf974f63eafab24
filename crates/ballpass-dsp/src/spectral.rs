//! Welch spectral estimates: [`welch`], [`csd`], [`coherence`] and
//! [`periodogram`], matching
//! [`scipy.signal.welch`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.welch.html),
//! [`csd`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.csd.html),
//! [`coherence`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.coherence.html)
//! and [`periodogram`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.periodogram.html)
//! (SciPy 1.17), plus a reusable [`Welch`] that plans its FFT once.

use std::sync::Arc;

use realfft::RealToComplex;
use rustfft::num_complex::Complex64;
use rustfft::Fft;

use crate::detrend::{DetrendType, Trend};
use crate::error::{check_finite, check_signal_set, invalid, DspError, Result};
use crate::window::Window;

/// Units of a spectral estimate.
///
/// With `w` the window and `fs` the sampling rate, each segment's
/// `conj(X[k]) Y[k]` is multiplied by
///
/// ```text
/// Density:   1 / (fs * sum w^2)     -> units^2 / Hz   (SciPy 'density')
/// Spectrum:  1 / (sum w)^2          -> units^2        (SciPy 'spectrum')
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scaling {
    /// Power spectral density (default).
    #[default]
    Density,
    /// Power spectrum (squared RMS amplitude per bin).
    Spectrum,
}

/// How the per-segment spectra are combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Average {
    /// Arithmetic mean (default).
    #[default]
    Mean,
    /// Median (of real and imaginary parts separately for cross spectra),
    /// divided by SciPy's bias `b(K) = 1 + sum_{k=1}^{(K-1)//2} (1/(2k+1) - 1/(2k))`
    /// for `K > 1` segments.
    Median,
}

/// Settings of [`welch`], [`csd`], [`coherence`] and a [`Welch`].
///
/// Defaults are SciPy's: periodic Hann, 256-sample segments, half overlap,
/// no zero padding, per-segment mean removal, density scaling, one-sided,
/// mean average.
#[derive(Debug, Clone, PartialEq)]
pub struct WelchSettings {
    /// Window applied to each segment (default periodic Hann).
    pub window: Window,
    /// Segment length in samples (default 256). For a named window longer
    /// than the signal it becomes the signal length, as in SciPy; a
    /// [`Window::Custom`] must have exactly `nperseg` values.
    pub nperseg: usize,
    /// Samples shared by consecutive segments (default `nperseg / 2`, of
    /// the possibly shortened `nperseg`). Must be `< nperseg`.
    pub noverlap: Option<usize>,
    /// FFT length, `>= nperseg`; segments are zero-padded to it (default
    /// `nperseg`).
    pub nfft: Option<usize>,
    /// Trend removed from each segment before windowing (default
    /// [`DetrendType::Constant`], SciPy's `detrend='constant'`).
    pub detrend: DetrendType,
    /// Density or spectrum units.
    pub scaling: Scaling,
    /// One-sided (`rfftfreq` bins, every bin except DC and an even-length
    /// Nyquist doubled) or two-sided (`fftfreq` order: `0, df, ...,
    /// -2 df, -df`, nothing doubled). Default one-sided.
    pub onesided: bool,
    /// Mean or median of the segment spectra.
    pub average: Average,
}

impl Default for WelchSettings {
    fn default() -> Self {
        WelchSettings {
            window: Window::Hann,
            nperseg: 256,
            noverlap: None,
            nfft: None,
            detrend: DetrendType::Constant,
            scaling: Scaling::Density,
            onesided: true,
            average: Average::Mean,
        }
    }
}

/// Settings of [`periodogram`]; defaults are SciPy's (boxcar window,
/// `nfft` = signal length, mean removal, density, one-sided).
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodogramSettings {
    /// Window over the whole (possibly truncated) signal (default boxcar).
    pub window: Window,
    /// FFT length: `None` = signal length; larger zero-pads; smaller
    /// truncates the signal to its first `nfft` samples (as SciPy).
    pub nfft: Option<usize>,
    /// Trend removed before windowing (default constant).
    pub detrend: DetrendType,
    /// Density or spectrum units.
    pub scaling: Scaling,
    /// One-sided (default) or two-sided, as in [`WelchSettings::onesided`].
    pub onesided: bool,
}

impl Default for PeriodogramSettings {
    fn default() -> Self {
        PeriodogramSettings {
            window: Window::Boxcar,
            nfft: None,
            detrend: DetrendType::Constant,
            scaling: Scaling::Density,
            onesided: true,
        }
    }
}

/// A power spectral density (or power spectrum) estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd {
    /// Bin frequencies in Hz (`rfftfreq` or `fftfreq` order).
    pub freq_hz: Vec<f64>,
    /// Power per bin, units²/Hz (density) or units² (spectrum).
    pub pxx: Vec<f64>,
    /// Number of segments averaged (for chi-square confidence intervals:
    /// with overlap these are not all independent).
    pub n_segments: usize,
}

/// A cross spectral density estimate, `Pxy = conj(X) Y` per segment.
///
/// If `y` is `x` delayed by `d` samples, `arg Pxy(f) = -2 pi f d / fs`.
#[derive(Debug, Clone, PartialEq)]
pub struct Csd {
    /// Bin frequencies in Hz (`rfftfreq` or `fftfreq` order).
    pub freq_hz: Vec<f64>,
    /// Complex cross spectrum per bin.
    pub pxy: Vec<Complex64>,
    /// Number of segments averaged.
    pub n_segments: usize,
}

/// Magnitude-squared coherence, `Cxy = |Pxy|^2 / (Pxx Pyy)`, in `[0, 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Coherence {
    /// Bin frequencies in Hz.
    pub freq_hz: Vec<f64>,
    /// Coherence per bin; NaN where `Pxx` or `Pyy` is zero (as SciPy).
    pub cxy: Vec<f64>,
    /// Number of segments averaged.
    pub n_segments: usize,
}

/// The segment geometry and FFT plan for one segment length.
#[derive(Clone)]
pub(crate) struct Engine {
    pub(crate) nperseg: usize,
    pub(crate) noverlap: usize,
    pub(crate) nfft: usize,
    window: Vec<f64>,
    win_sum: f64,
    win_sq_sum: f64,
    fft: Arc<dyn RealToComplex<f64>>,
    buf: Vec<f64>,
    pub(crate) spec_x: Vec<Complex64>,
    spec_y: Vec<Complex64>,
    scratch: Vec<Complex64>,
    /// Complex FFT of two real segments at once, planned on first use
    /// (a single-segment periodogram never needs it).
    pair: Option<PairFft>,
}

/// `conj(X[k]) Y[k]` from `W[k]` and `W[nfft - k]` of `W = FFT(x_seg + i
/// y_seg)` (see [`Engine::pair_fft`]).
#[inline(always)]
fn pair_cross(wk: Complex64, wj: Complex64) -> Complex64 {
    Complex64::new(
        0.5 * (wk.re * wj.im + wk.im * wj.re),
        -0.25 * (wk.norm_sqr() - wj.norm_sqr()),
    )
}

/// A complex FFT of `nfft` points with its buffer (see [`Engine::pair_fft`]).
#[derive(Clone)]
struct PairFft {
    fft: Arc<dyn Fft<f64>>,
    buf: Vec<Complex64>,
    scratch: Vec<Complex64>,
}

impl PairFft {
    fn new(nfft: usize) -> PairFft {
        let fft = crate::fftplan::complex_forward(nfft);
        PairFft {
            buf: vec![Complex64::new(0.0, 0.0); nfft],
            scratch: vec![Complex64::new(0.0, 0.0); fft.get_inplace_scratch_len()],
            fft,
        }
    }
}

impl Engine {
    pub(crate) fn new(
        window: &Window,
        nperseg: usize,
        noverlap: usize,
        nfft: usize,
    ) -> Result<Engine> {
        let window = window.values(nperseg)?;
        let fft = crate::fftplan::forward(nfft);
        Ok(Engine {
            nperseg,
            noverlap,
            nfft,
            win_sum: window.iter().sum(),
            win_sq_sum: window.iter().map(|w| w * w).sum(),
            window,
            buf: fft.make_input_vec(),
            spec_x: fft.make_output_vec(),
            spec_y: fft.make_output_vec(),
            scratch: fft.make_scratch_vec(),
            fft,
            pair: None,
        })
    }

    pub(crate) fn n_bins(&self) -> usize {
        self.nfft / 2 + 1
    }

    fn n_segments(&self, n: usize) -> usize {
        (n - self.noverlap) / (self.nperseg - self.noverlap)
    }

    /// Detrended, windowed, zero-padded FFT of the segment at `start`.
    pub(crate) fn segment_fft(
        &mut self,
        x: &[f64],
        start: usize,
        detrend: DetrendType,
        into_y: bool,
    ) {
        let seg = &x[start..start + self.nperseg];
        // One pass: (x - trend) * w, as SciPy's detrend-then-window.
        let t = Trend::fit(seg, detrend);
        let out = self.buf[..self.nperseg]
            .iter_mut()
            .zip(seg)
            .zip(&self.window);
        match detrend {
            DetrendType::None => out.for_each(|((b, v), w)| *b = v * w),
            DetrendType::Constant => {
                let m = t.at(0);
                out.for_each(|((b, v), w)| *b = (v - m) * w)
            }
            DetrendType::Linear => out
                .enumerate()
                .for_each(|(i, ((b, v), w))| *b = (v - t.at(i)) * w),
        }
        self.buf[self.nperseg..].fill(0.0);
        let out = if into_y {
            &mut self.spec_y
        } else {
            &mut self.spec_x
        };
        self.fft
            .process_with_scratch(&mut self.buf, out, &mut self.scratch)
            .expect("buffer lengths come from the plan");
    }

    /// FFT `W = FFT_nfft(a + i b)` into the pair buffer of two detrended,
    /// windowed, zero-padded segments `a` (of `x` at `start_a`) and `b` (of
    /// `y` at `start_b`), prepared as in [`Engine::segment_fft`].
    ///
    /// With `j = nfft - k` (mod `nfft`), the segments' spectra are
    /// `A[k] = (W[k] + conj W[j]) / 2` and `B[k] = (W[k] - conj W[j]) / (2i)`, so
    ///
    /// ```text
    /// |A[k]|^2 + |B[k]|^2 = (|W[k]|^2 + |W[j]|^2) / 2
    /// conj(A[k]) B[k]     = Im(W[k] W[j]) / 2 - i (|W[k]|^2 - |W[j]|^2) / 4
    /// ```
    ///
    /// (one complex FFT instead of two real ones, and no separation pass).
    #[inline(always)]
    fn pair_fft(
        &mut self,
        (x, start_a): (&[f64], usize),
        (y, start_b): (&[f64], usize),
        detrend: DetrendType,
    ) {
        let n = self.nperseg;
        let (a, b) = (&x[start_a..start_a + n], &y[start_b..start_b + n]);
        let (ta, tb) = (Trend::fit(a, detrend), Trend::fit(b, detrend));
        let nfft = self.nfft;
        let pair = self.pair.get_or_insert_with(|| PairFft::new(nfft));
        let out = pair.buf[..n]
            .iter_mut()
            .zip(a.iter().zip(b))
            .zip(&self.window);
        match detrend {
            DetrendType::None => out.for_each(|((c, (u, v)), w)| *c = Complex64::new(u * w, v * w)),
            DetrendType::Constant => {
                let (ma, mb) = (ta.at(0), tb.at(0));
                out.for_each(|((c, (u, v)), w)| *c = Complex64::new((u - ma) * w, (v - mb) * w))
            }
            DetrendType::Linear => out.enumerate().for_each(|(i, ((c, (u, v)), w))| {
                *c = Complex64::new((u - ta.at(i)) * w, (v - tb.at(i)) * w)
            }),
        }
        pair.buf[n..].fill(Complex64::new(0.0, 0.0));
        pair.fft
            .process_with_scratch(&mut pair.buf, &mut pair.scratch);
    }

    /// `f(&mut out[k], W[k], W[nfft - k])` for `k = 0 .. n_bins` (`W[0]`
    /// twice for `k = 0`) with `W` from the last [`Engine::pair_fft`].
    #[inline(always)]
    fn pair_bins<T>(&self, out: &mut [T], f: impl Fn(&mut T, Complex64, Complex64)) {
        let Some(w) = self.pair.as_ref().map(|p| &p.buf[..]) else {
            return;
        };
        let nb = self.n_bins().min(out.len());
        let (Some(o), Some(&w0)) = (out.first_mut(), w.first()) else {
            return;
        };
        f(o, w0, w0);
        let upper = &w[w.len() + 1 - nb..];
        for ((o, &wk), &wj) in out[1..nb].iter_mut().zip(&w[1..nb]).zip(upper.iter().rev()) {
            f(o, wk, wj);
        }
    }

    /// `acc[k] += conj(X[k]) Y[k]` over the first `nseg` segments of `x`
    /// and `y` (mean averaging), from [`Engine::pair_fft`].
    #[inline(always)]
    fn cross_sum(
        &mut self,
        x: &[f64],
        y: &[f64],
        nseg: usize,
        detrend: DetrendType,
        acc: &mut [Complex64],
    ) {
        let step = self.nperseg - self.noverlap;
        for seg in 0..nseg {
            self.pair_fft((x, seg * step), (y, seg * step), detrend);
            self.pair_bins(acc, |o, wk, wj| *o += pair_cross(wk, wj));
        }
    }

    /// Per-bin factor: scaling times one-sided doubling.
    pub(crate) fn bin_factors(&self, fs_hz: f64, scaling: Scaling, onesided: bool) -> Vec<f64> {
        let scale = match scaling {
            Scaling::Density => 1.0 / (fs_hz * self.win_sq_sum),
            Scaling::Spectrum => 1.0 / (self.win_sum * self.win_sum),
        };
        let nb = self.n_bins();
        let mut f = vec![scale; nb];
        if onesided {
            let end = if self.nfft % 2 == 0 { nb - 1 } else { nb };
            f[1.min(end)..end].iter_mut().for_each(|v| *v *= 2.0);
        }
        f
    }

    pub(crate) fn freqs(&self, fs_hz: f64, onesided: bool) -> Vec<f64> {
        // numpy: val = 1 / (n * d) with d = 1 / fs; then k * val.
        let val = 1.0 / (self.nfft as f64 * (1.0 / fs_hz));
        if onesided {
            (0..self.n_bins()).map(|k| k as f64 * val).collect()
        } else {
            let n = self.nfft as i64;
            let npos = (n - 1) / 2 + 1;
            (0..npos)
                .chain(-(n / 2)..0)
                .map(|k| k as f64 * val)
                .collect()
        }
    }

    /// Auto spectrum of `x` (already validated, `len >= nperseg`).
    fn auto(&mut self, x: &[f64], fs_hz: f64, s: &WelchSettings) -> Psd {
        let nseg = self.n_segments(x.len());
        let step = self.nperseg - self.noverlap;
        let nb = self.n_bins();
        let use_median = s.average == Average::Median && nseg > 1;
        let mut acc = vec![0.0; nb];
        let mut all = Vec::with_capacity(if use_median { nseg * nb } else { 0 });
        // Mean: two segments per complex FFT (see `pair_fft`); a leftover
        // segment (and every segment for the median) by a real FFT.
        let paired = if use_median { 0 } else { nseg / 2 };
        for pair in 0..paired {
            let start = 2 * pair * step;
            self.pair_fft((x, start), (x, start + step), s.detrend);
            self.pair_bins(&mut acc, |a, wk, wj| {
                *a += 0.5 * (wk.norm_sqr() + wj.norm_sqr())
            });
        }
        for seg in 2 * paired..nseg {
            self.segment_fft(x, seg * step, s.detrend, false);
            if use_median {
                all.extend(self.spec_x.iter().map(|c| c.norm_sqr()));
            } else {
                acc.iter_mut()
                    .zip(&self.spec_x)
                    .for_each(|(a, c)| *a += c.norm_sqr());
            }
        }
        let fac = self.bin_factors(fs_hz, s.scaling, s.onesided);
        let mut p: Vec<f64> = if use_median {
            let bias = median_bias(nseg);
            let mut col = vec![0.0; nseg];
            (0..nb)
                .map(|k| {
                    col.iter_mut()
                        .enumerate()
                        .for_each(|(j, v)| *v = all[j * nb + k] * fac[k]);
                    median(&mut col) / bias
                })
                .collect()
        } else {
            let inv = 1.0 / nseg as f64;
            acc.iter().zip(&fac).map(|(a, f)| a * f * inv).collect()
        };
        if !s.onesided {
            p = mirror(&p, self.nfft, |v| v);
        }
        Psd {
            freq_hz: self.freqs(fs_hz, s.onesided),
            pxx: p,
            n_segments: nseg,
        }
    }

    /// Cross spectrum of equal-length `x`, `y` (validated).
    fn cross(&mut self, x: &[f64], y: &[f64], fs_hz: f64, s: &WelchSettings) -> Csd {
        let nseg = self.n_segments(x.len());
        let step = self.nperseg - self.noverlap;
        let nb = self.n_bins();
        let use_median = s.average == Average::Median && nseg > 1;
        let mut acc = vec![Complex64::new(0.0, 0.0); nb];
        let mut all = Vec::with_capacity(if use_median { nseg * nb } else { 0 });
        if use_median {
            let mut seg_pxy = vec![Complex64::new(0.0, 0.0); nb];
            for seg in 0..nseg {
                self.pair_fft((x, seg * step), (y, seg * step), s.detrend);
                self.pair_bins(&mut seg_pxy, |o, wk, wj| *o = pair_cross(wk, wj));
                all.extend_from_slice(&seg_pxy);
            }
        } else {
            // The segment loop with the CPU's widest vectors (the FFT has
            // its own dispatch): the same operations in the same order, so
            // the same bits (tested).
            crate::simd::widest(|| self.cross_sum(x, y, nseg, s.detrend, &mut acc));
        }
        let fac = self.bin_factors(fs_hz, s.scaling, s.onesided);
        let mut p: Vec<Complex64> = if use_median {
            let bias = median_bias(nseg);
            let mut re = vec![0.0; nseg];
            let mut im = vec![0.0; nseg];
            (0..nb)
                .map(|k| {
                    for j in 0..nseg {
                        let v = all[j * nb + k] * fac[k];
                        re[j] = v.re;
                        im[j] = v.im;
                    }
                    Complex64::new(median(&mut re) / bias, median(&mut im) / bias)
                })
                .collect()
        } else {
            let inv = 1.0 / nseg as f64;
            acc.iter().zip(&fac).map(|(a, f)| a * (f * inv)).collect()
        };
        if !s.onesided {
            p = mirror(&p, self.nfft, |v| v.conj());
        }
        Csd {
            freq_hz: self.freqs(fs_hz, s.onesided),
            pxy: p,
            n_segments: nseg,
        }
    }

    /// Coherence of equal-length `x`, `y` (validated), mean-averaged.
    fn coherence(&mut self, x: &[f64], y: &[f64], fs_hz: f64, s: &WelchSettings) -> Coherence {
        let nseg = self.n_segments(x.len());
        let step = self.nperseg - self.noverlap;
        let nb = self.n_bins();
        let mut sxx = vec![0.0; nb];
        let mut syy = vec![0.0; nb];
        let mut sxy = vec![Complex64::new(0.0, 0.0); nb];
        for seg in 0..nseg {
            self.segment_fft(x, seg * step, s.detrend, false);
            self.segment_fft(y, seg * step, s.detrend, true);
            for k in 0..nb {
                let (a, b) = (self.spec_x[k], self.spec_y[k]);
                sxx[k] += a.norm_sqr();
                syy[k] += b.norm_sqr();
                sxy[k] += a.conj() * b;
            }
        }
        // Scale as SciPy does before dividing (the factors cancel up to rounding).
        let fac = self.bin_factors(fs_hz, Scaling::Density, s.onesided);
        let inv = 1.0 / nseg as f64;
        let mut c: Vec<f64> = (0..nb)
            .map(|k| {
                let f = fac[k] * inv;
                let pxy = sxy[k] * f;
                pxy.norm_sqr() / (sxx[k] * f) / (syy[k] * f)
            })
            .collect();
        if !s.onesided {
            c = mirror(&c, self.nfft, |v| v);
        }
        Coherence {
            freq_hz: self.freqs(fs_hz, s.onesided),
            cxy: c,
            n_segments: nseg,
        }
    }
}

/// Two-sided spectrum of length `nfft` in `fftfreq` order from the
/// non-negative bins `p` (`nfft / 2 + 1` of them): `P[nfft - k] = conj(P[k])`.
pub(crate) fn mirror<T: Copy>(p: &[T], nfft: usize, conj: impl Fn(T) -> T) -> Vec<T> {
    let mut out = Vec::with_capacity(nfft);
    out.extend_from_slice(p);
    out.truncate(nfft);
    for k in p.len()..nfft {
        out.push(conj(p[nfft - k]));
    }
    out
}

/// Median of `v` (reordered in place); mean of the two middle values for
/// an even count, as `numpy.median`.
fn median(v: &mut [f64]) -> f64 {
    v.sort_unstable_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// SciPy's `_median_bias(n)`: `1 + sum_{k=1}^{(n-1)//2} (1/(2k+1) - 1/(2k))`.
fn median_bias(n: usize) -> f64 {
    1.0 + (1..=(n.saturating_sub(1)) / 2)
        .map(|k| {
            let ii = 2.0 * k as f64;
            1.0 / (ii + 1.0) - 1.0 / ii
        })
        .sum::<f64>()
}

fn check_fs(fs_hz: f64) -> Result<()> {
    if !(fs_hz.is_finite() && fs_hz > 0.0) {
        return Err(invalid(
            "fs_hz",
            format!("sampling rate must be finite and > 0, got {fs_hz}"),
        ));
    }
    Ok(())
}

/// Checks the segment settings that do not depend on the signal.
pub(crate) fn check_settings(s: &WelchSettings) -> Result<()> {
    if s.nperseg == 0 {
        return Err(invalid(
            "nperseg",
            "segment length must be at least 1, got 0",
        ));
    }
    if let Some(nfft) = s.nfft {
        if nfft < s.nperseg {
            return Err(invalid(
                "nfft",
                format!("nfft = {nfft} must be >= nperseg = {}", s.nperseg),
            ));
        }
    }
    if let Some(nov) = s.noverlap {
        if nov >= s.nperseg {
            return Err(invalid(
                "noverlap",
                format!("noverlap = {nov} must be < nperseg = {}", s.nperseg),
            ));
        }
    }
    if let Window::Custom(_) = s.window {
        s.window.values(s.nperseg)?;
    }
    Ok(())
}

/// The segment geometry `(nperseg, noverlap, nfft)` for a signal of `n`
/// samples, shortening `nperseg` to `n` as SciPy does for named windows.
pub(crate) fn geometry(s: &WelchSettings, n: usize) -> Result<(usize, usize, usize)> {
    let mut nperseg = s.nperseg;
    if n < nperseg {
        if let Window::Custom(w) = &s.window {
            return Err(DspError::TooShort {
                what: "signal (custom window length)",
                needed: w.len(),
                found: n,
            });
        }
        nperseg = n;
    }
    let nfft = s.nfft.unwrap_or(nperseg);
    let noverlap = s.noverlap.unwrap_or(nperseg / 2);
    if noverlap >= nperseg {
        return Err(invalid(
            "noverlap",
            format!(
                "noverlap = {noverlap} must be < nperseg = {nperseg} \
                 (nperseg shortened to the signal length {n})"
            ),
        ));
    }
    Ok((nperseg, noverlap, nfft))
}

/// A Welch estimator that plans its FFT and window once and reuses them
/// (and its buffers) across channels and records.
///
/// `Welch` is `Send + Sync` and cheap to clone (the plan is a shared
/// `Arc`); give each thread its own clone. A signal shorter than
/// `nperseg` (allowed for named windows, as in SciPy) is handled with a
/// one-off plan for that call.
///
/// ```
/// use ballpass_dsp::{Welch, WelchSettings};
/// let mut w = Welch::new(WelchSettings { nperseg: 64, ..Default::default() }).unwrap();
/// let fs_hz = 100.0;
/// // A unit-amplitude sine at a bin centre has power 1/2 (RMS²) in total.
/// let x: Vec<f64> = (0..1000)
///     .map(|n| (2.0 * std::f64::consts::PI * 12.5 * n as f64 / fs_hz).sin())
///     .collect();
/// let p = w.psd(&x, fs_hz).unwrap();
/// let df = p.freq_hz[1] - p.freq_hz[0];
/// let power: f64 = p.pxx.iter().sum::<f64>() * df;
/// assert!((power - 0.5).abs() < 1e-3 * 0.5 * 1.5); // Hann: 1.5 bins noise bandwidth
/// assert_eq!(p.n_segments, 30);
/// ```
#[derive(Clone)]
pub struct Welch {
    settings: WelchSettings,
    engine: Engine,
}

impl std::fmt::Debug for Welch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Welch")
            .field("settings", &self.settings)
            .finish()
    }
}

impl Welch {
    /// Validates `settings` and plans the FFT for `nperseg`.
    ///
    /// # Errors
    /// [`DspError::InvalidSetting`] for `nperseg == 0`,
    /// `noverlap >= nperseg`, `nfft < nperseg`, or a custom window whose
    /// length is not `nperseg` or that holds a non-finite value.
    pub fn new(settings: WelchSettings) -> Result<Welch> {
        let n = settings.nperseg;
        Welch::for_len(settings, n)
    }

    /// A `Welch` planned for signals of `n >= 1` samples.
    pub(crate) fn for_len(settings: WelchSettings, n: usize) -> Result<Welch> {
        check_settings(&settings)?;
        let (nperseg, noverlap, nfft) = geometry(&settings, n)?;
        let engine = Engine::new(&settings.window, nperseg, noverlap, nfft)?;
        Ok(Welch { settings, engine })
    }

    /// The settings this estimator was built with.
    pub fn settings(&self) -> &WelchSettings {
        &self.settings
    }

    /// The engine for a signal of `n` samples: the planned one, or a
    /// one-off one when `nperseg` is shortened to `n`.
    fn engine_for(&self, n: usize) -> Result<Option<Engine>> {
        let (nperseg, noverlap, nfft) = geometry(&self.settings, n)?;
        if nperseg == self.engine.nperseg {
            Ok(None)
        } else {
            Engine::new(&self.settings.window, nperseg, noverlap, nfft).map(Some)
        }
    }

    /// Power spectral density of `x` sampled at `fs_hz`, as
    /// `scipy.signal.welch(x, fs, ...)` with this estimator's settings.
    ///
    /// ```text
    /// X_j[k] = FFT_nfft( w * detrend(x[j step .. j step + nperseg]) ),  step = nperseg - noverlap
    /// Pxx[k] = c_k * avg_j |X_j[k]|^2,   j = 0 .. (N - noverlap) / step
    /// ```
    ///
    /// with `c_k` the [`Scaling`] factor (doubled for one-sided non-DC,
    /// non-Nyquist bins). Trailing samples that do not fill a segment are
    /// dropped.
    ///
    /// # Errors
    /// [`DspError::Empty`]/[`DspError::NonFinite`] for `x`,
    /// [`DspError::InvalidSetting`] for `fs_hz` not finite and positive or
    /// a `noverlap` not below a shortened `nperseg`,
    /// [`DspError::TooShort`] for a custom window longer than `x`.
    pub fn psd(&mut self, x: &[f64], fs_hz: f64) -> Result<Psd> {
        check_fs(fs_hz)?;
        check_finite("x", x)?;
        let s = &self.settings;
        Ok(match self.engine_for(x.len())? {
            Some(mut e) => e.auto(x, fs_hz, s),
            None => self.engine.auto(x, fs_hz, s),
        })
    }

    /// Cross spectral density `Pxy = avg_j conj(X_j) Y_j` (scaled as
    /// [`Welch::psd`]), as `scipy.signal.csd(x, y, fs, ...)`.
    ///
    /// If `y` is `x` delayed by `d` samples, `arg Pxy(f) = -2 pi f d / fs`.
    /// When the lengths differ the shorter signal is zero-padded at the end
    /// to the longer one's length, as SciPy does.
    ///
    /// # Errors
    /// As [`Welch::psd`], for `x` and `y`.
    pub fn csd(&mut self, x: &[f64], y: &[f64], fs_hz: f64) -> Result<Csd> {
        check_fs(fs_hz)?;
        crate::simd::widest(|| {
            check_finite("x", x)?;
            check_finite("y", y)
        })?;
        let n = x.len().max(y.len());
        let pad = |v: &[f64]| {
            let mut p = v.to_vec();
            p.resize(n, 0.0);
            p
        };
        let (xp, yp);
        let (x, y) = match x.len().cmp(&y.len()) {
            std::cmp::Ordering::Equal => (x, y),
            std::cmp::Ordering::Less => {
                xp = pad(x);
                (&xp[..], y)
            }
            std::cmp::Ordering::Greater => {
                yp = pad(y);
                (x, &yp[..])
            }
        };
        let s = &self.settings;
        Ok(match self.engine_for(n)? {
            Some(mut e) => e.cross(x, y, fs_hz, s),
            None => self.engine.cross(x, y, fs_hz, s),
        })
    }

    /// Magnitude-squared coherence `|Pxy|^2 / (Pxx Pyy)`, as
    /// `scipy.signal.coherence(x, y, fs, ...)`.
    ///
    /// Uses this estimator's window, `nperseg`, `noverlap`, `nfft`,
    /// `detrend` and `onesided`; `scaling` cancels and is ignored. Bins
    /// where `Pxx` or `Pyy` is zero hold NaN, as in SciPy.
    ///
    /// # Errors
    /// As [`Welch::psd`], for `x` and `y`; also
    /// [`DspError::LengthMismatch`] if the lengths differ (SciPy would
    /// mix segment sets of different signals) and
    /// [`DspError::InvalidSetting`] for [`Average::Median`] (SciPy's
    /// coherence always takes the mean; a median ratio is not bounded by 1).
    pub fn coherence(&mut self, x: &[f64], y: &[f64], fs_hz: f64) -> Result<Coherence> {
        check_fs(fs_hz)?;
        check_finite("x", x)?;
        check_finite("y", y)?;
        if x.len() != y.len() {
            return Err(DspError::LengthMismatch {
                what: "x and y (coherence)",
                expected: x.len(),
                found: y.len(),
            });
        }
        if self.settings.average == Average::Median {
            return Err(invalid(
                "average",
                "coherence is defined with mean averaging only (as scipy.signal.coherence)",
            ));
        }
        let s = &self.settings;
        Ok(match self.engine_for(x.len())? {
            Some(mut e) => e.coherence(x, y, fs_hz, s),
            None => self.engine.coherence(x, y, fs_hz, s),
        })
    }
}

/// Welch power spectral density with a one-off [`Welch`]; see
/// [`Welch::psd`] for the formula.
///
/// ```
/// use ballpass_dsp::{welch, DetrendType, WelchSettings, Window};
/// // Boxcar, no overlap, no detrending, segments tiling the signal: the
/// // one-sided density integrates to the mean square (Parseval).
/// let x: Vec<f64> = (0..1024).map(|n| ((n * 37 % 101) as f64 - 50.0) / 10.0).collect();
/// let s = WelchSettings {
///     window: Window::Boxcar,
///     nperseg: 128,
///     noverlap: Some(0),
///     detrend: DetrendType::None,
///     ..Default::default()
/// };
/// let p = welch(&x, 10.0, &s).unwrap();
/// let ms = x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64;
/// let integral = p.pxx.iter().sum::<f64>() * p.freq_hz[1];
/// assert!((integral - ms).abs() < 1e-12 * ms);
/// assert_eq!(p.n_segments, 8);
/// ```
///
/// # Errors
/// As [`Welch::new`] and [`Welch::psd`].
pub fn welch(x: &[f64], fs_hz: f64, settings: &WelchSettings) -> Result<Psd> {
    check_settings(settings)?;
    check_fs(fs_hz)?;
    check_finite("x", x)?;
    let (nperseg, noverlap, nfft) = geometry(settings, x.len())?;
    let mut e = Engine::new(&settings.window, nperseg, noverlap, nfft)?;
    Ok(e.auto(x, fs_hz, settings))
}

/// Welch cross spectral density `Pxy = conj(X) Y` with a one-off
/// [`Welch`]; see [`Welch::csd`].
///
/// # Errors
/// As [`Welch::new`] and [`Welch::csd`].
pub fn csd(x: &[f64], y: &[f64], fs_hz: f64, settings: &WelchSettings) -> Result<Csd> {
    check_finite("x", x)?;
    check_finite("y", y)?;
    Welch::for_len(settings.clone(), x.len().max(y.len()))?.csd(x, y, fs_hz)
}

/// Magnitude-squared coherence with a one-off [`Welch`]; see
/// [`Welch::coherence`].
///
/// ```
/// use ballpass_dsp::{coherence, WelchSettings};
/// let x: Vec<f64> = (0..2048).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
/// let y: Vec<f64> = x.iter().map(|v| -3.0 * v).collect();
/// let c = coherence(&x, &y, 1.0, &WelchSettings::default()).unwrap();
/// assert!(c.cxy[1..].iter().all(|&v| (v - 1.0).abs() < 1e-9));
/// ```
///
/// # Errors
/// As [`Welch::new`] and [`Welch::coherence`].
pub fn coherence(x: &[f64], y: &[f64], fs_hz: f64, settings: &WelchSettings) -> Result<Coherence> {
    check_finite("x", x)?;
    check_finite("y", y)?;
    Welch::for_len(settings.clone(), x.len().max(y.len()))?.coherence(x, y, fs_hz)
}

/// Periodogram: one segment spanning the whole signal, as
/// `scipy.signal.periodogram(x, fs, ...)`.
///
/// ```text
/// Pxx[k] = c_k |FFT_nfft( w * detrend(x[0 .. nperseg]) )[k]|^2
/// ```
///
/// with `nperseg = min(N, nfft)` and `c_k` as in [`Welch::psd`].
///
/// ```
/// use ballpass_dsp::{periodogram, PeriodogramSettings, Scaling};
/// // 2 Vrms sine at a bin centre: the spectrum peak is 2² V².
/// let fs_hz = 1000.0;
/// let x: Vec<f64> = (0..1000)
///     .map(|n| 2.0 * 2f64.sqrt() * (2.0 * std::f64::consts::PI * 100.0 * n as f64 / fs_hz).sin())
///     .collect();
/// let s = PeriodogramSettings { scaling: Scaling::Spectrum, ..Default::default() };
/// let p = periodogram(&x, fs_hz, &s).unwrap();
/// assert!((p.pxx[100] - 4.0).abs() < 1e-9);
/// ```
///
/// # Errors
/// [`DspError::Empty`]/[`DspError::NonFinite`] for `x`,
/// [`DspError::InvalidSetting`] for `fs_hz`, `nfft == 0`, or a custom
/// window whose length is not `min(N, nfft)`.
pub fn periodogram(x: &[f64], fs_hz: f64, settings: &PeriodogramSettings) -> Result<Psd> {
    check_fs(fs_hz)?;
    check_finite("x", x)?;
    let n = x.len();
    let (x, nperseg, nfft) = match settings.nfft {
        None => (x, n, n),
        Some(0) => return Err(invalid("nfft", "FFT length must be at least 1, got 0")),
        Some(nfft) if nfft >= n => (x, n, nfft),
        Some(nfft) => (&x[..nfft], nfft, nfft),
    };
    let ws = WelchSettings {
        window: settings.window.clone(),
        nperseg,
        noverlap: Some(0),
        nfft: Some(nfft),
        detrend: settings.detrend,
        scaling: settings.scaling,
        onesided: settings.onesided,
        average: Average::Mean,
    };
    welch(x, fs_hz, &ws)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The csd segment loop compiled for the CPU's widest vectors adds the
    /// same bits as the baseline build, for every detrend.
    #[test]
    fn wide_cross_sum_equals_the_baseline_bitwise() {
        let mut st = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            st = st
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (st >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let x: Vec<f64> = (0..5000).map(|_| next()).collect();
        let y: Vec<f64> = (0..5000).map(|_| next() + 0.1).collect();
        for detrend in [
            DetrendType::None,
            DetrendType::Constant,
            DetrendType::Linear,
        ] {
            let mut e = Engine::new(&Window::Hann, 1000, 300, 1200).unwrap();
            let nseg = e.n_segments(x.len());
            let mut wide = vec![Complex64::new(0.0, 0.0); e.n_bins()];
            let mut base = wide.clone();
            crate::simd::widest(|| e.cross_sum(&x, &y, nseg, detrend, &mut wide));
            e.cross_sum(&x, &y, nseg, detrend, &mut base);
            let bits = |v: &[Complex64]| {
                v.iter()
                    .map(|z| (z.re.to_bits(), z.im.to_bits()))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(&wide), bits(&base), "{detrend:?}");
        }
    }

    #[test]
    fn median_bias_matches_scipy_values() {
        // scipy.signal._spectral_py._median_bias(n) for n = 1, 2, 3, 5
        // (1, 1, 1 - 1/6, 1 - 1/6 - 1/20); tolerance: rounding of a short sum.
        assert_eq!(median_bias(1), 1.0);
        assert_eq!(median_bias(2), 1.0);
        assert!((median_bias(3) - (1.0 - 1.0 / 6.0)).abs() < 1e-15);
        assert!((median_bias(5) - (1.0 - 1.0 / 6.0 - 1.0 / 20.0)).abs() < 1e-15);
    }

    #[test]
    fn welch_is_send_sync() {
        fn assert_send_sync<T: Send + Sync>() {}
        assert_send_sync::<Welch>();
    }

    #[test]
    fn coherence_of_mean_removed_single_samples_is_nan() {
        // One-sample segments detrend to zero: Pxx = Pyy = 0, so 0/0 as in SciPy.
        let c = coherence(&[1.0], &[2.0], 1.0, &WelchSettings::default()).unwrap();
        assert_eq!(c.freq_hz, vec![0.0]);
        assert!(c.cxy[0].is_nan());
    }

    #[test]
    fn fftfreq_order() {
        let e = Engine::new(&Window::Boxcar, 5, 0, 5).unwrap();
        assert_eq!(e.freqs(5.0, false), vec![0.0, 1.0, 2.0, -2.0, -1.0]);
        let e = Engine::new(&Window::Boxcar, 4, 0, 4).unwrap();
        assert_eq!(e.freqs(4.0, false), vec![0.0, 1.0, -2.0, -1.0]);
        assert_eq!(e.freqs(4.0, true), vec![0.0, 1.0, 2.0]);
    }

    #[test]
    fn settings_errors() {
        let x = vec![1.0; 100];
        let bad = |s: WelchSettings| welch(&x, 1.0, &s).unwrap_err();
        let d = WelchSettings::default;
        assert!(matches!(
            bad(WelchSettings { nperseg: 0, ..d() }),
            DspError::InvalidSetting {
                name: "nperseg",
                ..
            }
        ));
        assert!(matches!(
            bad(WelchSettings {
                nperseg: 8,
                noverlap: Some(8),
                ..d()
            }),
            DspError::InvalidSetting {
                name: "noverlap",
                ..
            }
        ));
        assert!(matches!(
            bad(WelchSettings {
                nperseg: 8,
                nfft: Some(7),
                ..d()
            }),
            DspError::InvalidSetting { name: "nfft", .. }
        ));
        assert!(matches!(
            bad(WelchSettings {
                nperseg: 8,
                window: Window::Custom(vec![1.0; 7]),
                ..d()
            }),
            DspError::InvalidSetting { name: "window", .. }
        ));
        assert!(matches!(
            bad(WelchSettings {
                nperseg: 200,
                window: Window::Custom(vec![1.0; 200]),
                ..d()
            }),
            DspError::TooShort { .. }
        ));
        // Shortened nperseg (100) with an explicit overlap that no longer fits.
        assert!(matches!(
            bad(WelchSettings {
                nperseg: 256,
                noverlap: Some(150),
                ..d()
            }),
            DspError::InvalidSetting {
                name: "noverlap",
                ..
            }
        ));
        assert!(welch(&x, 0.0, &d()).is_err());
        assert!(welch(&x, f64::NAN, &d()).is_err());
        assert!(welch(&[], 1.0, &d()).is_err());
        assert!(matches!(
            welch(&[1.0, f64::NAN, 2.0], 1.0, &d()).unwrap_err(),
            DspError::NonFinite {
                what: "x",
                index: 1,
                ..
            }
        ));
        assert!(matches!(
            csd(&x, &[f64::INFINITY], 1.0, &d()).unwrap_err(),
            DspError::NonFinite {
                what: "y",
                index: 0,
                ..
            }
        ));
        assert!(csd(&x, &x, -2.0, &d()).is_err());
        assert!(coherence(&x, &x[..99], 1.0, &d()).is_err());
        assert!(coherence(
            &x,
            &x,
            1.0,
            &WelchSettings {
                average: Average::Median,
                ..d()
            }
        )
        .is_err());
        assert!(periodogram(
            &x,
            1.0,
            &PeriodogramSettings {
                nfft: Some(0),
                ..Default::default()
            }
        )
        .is_err());
    }
}

/// Auto- and cross-spectra of several equal-length signals, from one set of
/// segment FFTs (see [`Welch::spectra`]).
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralSet {
    /// Bin frequencies in Hz (`rfftfreq` or `fftfreq` order).
    pub freq_hz: Vec<f64>,
    /// The power spectral density of each signal, in input order.
    pub auto: Vec<Vec<f64>>,
    /// The cross spectral density of each requested pair `(i, j)`,
    /// `conj(X_i) X_j` averaged, in the order of the pairs.
    pub cross: Vec<Vec<Complex64>>,
    /// Number of segments averaged.
    pub n_segments: usize,
}

impl Welch {
    /// The PSD of every signal and the CSD of every pair `(i, j)` of
    /// `signals` (indices into it): [`Welch::psd`] of each signal and
    /// [`Welch::csd`] of each pair, but with each segment of each signal
    /// transformed once (one real FFT) instead of once per spectrum it
    /// enters: three signals and their three pairs take 3 real FFTs per
    /// segment instead of the equivalent of 9. The single-spectrum calls
    /// pack segments into complex FFTs differently, so the results agree
    /// with them to rounding (`spectra_set_equals_psd_and_csd` bounds the
    /// difference at 1e-13 of each series' peak), and with median
    /// averaging (computed by them) exactly. SciPy has no such call; its
    /// `welch` and `csd` are matched.
    ///
    /// # Errors
    /// As [`Welch::psd`] for every signal; [`DspError::LengthMismatch`] if
    /// the signals' lengths differ; [`DspError::InvalidSetting`] for a pair
    /// index out of range.
    pub fn spectra(
        &mut self,
        signals: &[&[f64]],
        pairs: &[(usize, usize)],
        fs_hz: f64,
    ) -> Result<SpectralSet> {
        check_fs(fs_hz)?;
        let n = check_signal_set(signals, pairs, "signals (spectra)")?;
        if self.settings.average == Average::Median {
            // Medians need every segment's value; the single-spectrum
            // paths keep them. Same results, three times the FFTs.
            let mut auto = Vec::with_capacity(signals.len());
            let mut freq_hz = Vec::new();
            let mut n_segments = 0;
            for x in signals {
                let p = self.psd(x, fs_hz)?;
                (freq_hz, n_segments) = (p.freq_hz, p.n_segments);
                auto.push(p.pxx);
            }
            let cross = pairs
                .iter()
                .map(|&(i, j)| self.csd(signals[i], signals[j], fs_hz).map(|c| c.pxy))
                .collect::<Result<_>>()?;
            return Ok(SpectralSet {
                freq_hz,
                auto,
                cross,
                n_segments,
            });
        }
        let s = self.settings.clone();
        Ok(match self.engine_for(n)? {
            Some(mut e) => e.set(signals, pairs, fs_hz, &s),
            None => self.engine.set(signals, pairs, fs_hz, &s),
        })
    }
}

impl Engine {
    /// [`Welch::spectra`] with mean averaging (inputs validated): one real
    /// FFT per signal and segment ([`Engine::segment_fft`]), then the
    /// products, sums and scalings of the single-spectrum paths.
    fn set(
        &mut self,
        signals: &[&[f64]],
        pairs: &[(usize, usize)],
        fs_hz: f64,
        s: &WelchSettings,
    ) -> SpectralSet {
        let nseg = self.n_segments(signals[0].len());
        let step = self.nperseg - self.noverlap;
        let nb = self.n_bins();
        let mut specs = vec![vec![Complex64::new(0.0, 0.0); nb]; signals.len()];
        let mut auto = vec![vec![0.0; nb]; signals.len()];
        let mut cross = vec![vec![Complex64::new(0.0, 0.0); nb]; pairs.len()];
        for seg in 0..nseg {
            for (x, spec) in signals.iter().zip(specs.iter_mut()) {
                self.segment_fft(x, seg * step, s.detrend, false);
                spec.copy_from_slice(&self.spec_x);
            }
            for (acc, spec) in auto.iter_mut().zip(&specs) {
                acc.iter_mut()
                    .zip(spec)
                    .for_each(|(a, c)| *a += c.norm_sqr());
            }
            for (acc, &(i, j)) in cross.iter_mut().zip(pairs) {
                // conj(a) * b, written as in `Engine::cross`.
                for ((s, a), b) in acc.iter_mut().zip(&specs[i]).zip(&specs[j]) {
                    s.re += a.re * b.re + a.im * b.im;
                    s.im += a.re * b.im - a.im * b.re;
                }
            }
        }
        let fac = self.bin_factors(fs_hz, s.scaling, s.onesided);
        let inv = 1.0 / nseg as f64;
        let auto = auto
            .into_iter()
            .map(|acc| {
                let p: Vec<f64> = acc.iter().zip(&fac).map(|(a, f)| a * f * inv).collect();
                if s.onesided {
                    p
                } else {
                    mirror(&p, self.nfft, |v| v)
                }
            })
            .collect();
        let cross = cross
            .into_iter()
            .map(|acc| {
                let p: Vec<Complex64> = acc.iter().zip(&fac).map(|(a, f)| a * (f * inv)).collect();
                if s.onesided {
                    p
                } else {
                    mirror(&p, self.nfft, |v| v.conj())
                }
            })
            .collect();
        SpectralSet {
            freq_hz: self.freqs(fs_hz, s.onesided),
            auto,
            cross,
            n_segments: nseg,
        }
    }
}
