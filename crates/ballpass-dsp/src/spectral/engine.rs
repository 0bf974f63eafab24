//! The segment geometry, FFT plan and per-segment sums behind [`Welch`](super::Welch)
//! and [`WelchStream`](crate::WelchStream).

use std::sync::Arc;

use realfft::RealToComplex;
use rustfft::num_complex::Complex64;
use rustfft::Fft;

use super::{median, median_bias, mirror, Average, Coherence, Csd, Psd, Scaling, WelchSettings};
use crate::detrend::{DetrendType, Trend};
use crate::error::Result;
use crate::window::Window;

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

    pub(super) fn n_segments(&self, n: usize) -> usize {
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
    pub(super) fn cross_sum(
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
    pub(super) fn auto(&mut self, x: &[f64], fs_hz: f64, s: &WelchSettings) -> Psd {
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
    pub(super) fn cross(&mut self, x: &[f64], y: &[f64], fs_hz: f64, s: &WelchSettings) -> Csd {
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
    pub(super) fn coherence(
        &mut self,
        x: &[f64],
        y: &[f64],
        fs_hz: f64,
        s: &WelchSettings,
    ) -> Coherence {
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
