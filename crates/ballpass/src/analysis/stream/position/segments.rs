//! The Welch segments of the position grid, summed per candidate segment
//! length, with their autocorrelations (module docs of [`super`]).

use ballpass_dsp::{DetrendType, Welch, WelchSettings};
use rustfft::num_complex::Complex64;

use crate::analysis::AnalyzeSettings;
use crate::error::{Error, Result};

/// Welch segments of one candidate length, summed over the runs.
pub(super) struct Candidate {
    pub(super) n: usize,
    welch: Welch,
    pub(super) window: Vec<f64>,
    fft: std::sync::Arc<dyn rustfft::Fft<f64>>,
    ifft: std::sync::Arc<dyn rustfft::Fft<f64>>,
    /// Per signal: PSD sums, autocorrelation sums.
    pub(super) psd: Vec<Vec<f64>>,
    pub(super) acf: Vec<Vec<f64>>,
    pub(super) segments: usize,
    pub(super) freq: Vec<f64>,
    /// The current run's last samples per signal, and its segments.
    buf: Vec<Vec<f64>>,
    run_segments: usize,
    scratch: Vec<Complex64>,
}

impl Candidate {
    pub(super) fn new(n: usize, k: usize, settings: &AnalyzeSettings) -> Result<Self> {
        let welch = Welch::new(WelchSettings {
            window: settings.window.to_dsp(),
            nperseg: n,
            noverlap: Some(n / 2),
            detrend: DetrendType::Linear,
            ..WelchSettings::default()
        })
        .map_err(|e| Error::dsp("position-domain Welch", e))?;
        let window = settings
            .window
            .to_dsp()
            .values(n)
            .map_err(|e| Error::dsp("window", e))?;
        let mut planner = rustfft::FftPlanner::new();
        Ok(Candidate {
            n,
            welch,
            window,
            fft: planner.plan_fft_forward(2 * n),
            ifft: planner.plan_fft_inverse(2 * n),
            psd: vec![Vec::new(); k],
            acf: vec![vec![0.0; n]; k],
            segments: 0,
            freq: Vec::new(),
            buf: vec![Vec::new(); k],
            run_segments: 0,
            scratch: Vec::new(),
        })
    }

    /// Adds one grid point of every signal; a segment when `n` are held.
    pub(super) fn push(&mut self, xs: &[f64], dx: f64) -> Result<()> {
        for (b, &x) in self.buf.iter_mut().zip(xs) {
            b.push(x);
        }
        if self.buf[0].len() < self.n {
            return Ok(());
        }
        for j in 0..self.buf.len() {
            let seg = &self.buf[j];
            let p = self
                .welch
                .psd(seg, 1.0 / dx)
                .map_err(|e| Error::dsp("position-domain Welch", e))?;
            if self.psd[j].is_empty() {
                self.psd[j] = p.pxx;
                self.freq = p.freq_hz;
            } else {
                self.psd[j]
                    .iter_mut()
                    .zip(&p.pxx)
                    .for_each(|(a, b)| *a += b);
            }
            // The windowed, detrended segment's autocorrelation (lags 0..n)
            // by a zero-padded FFT of twice its length.
            let mut s = seg.clone();
            ballpass_dsp::detrend_in_place(&mut s, DetrendType::Linear)
                .map_err(|e| Error::dsp("position-domain detrend", e))?;
            self.scratch.clear();
            self.scratch.extend(
                s.iter()
                    .zip(&self.window)
                    .map(|(v, w)| Complex64::new(v * w, 0.0)),
            );
            self.scratch.resize(2 * self.n, Complex64::new(0.0, 0.0));
            self.fft.process(&mut self.scratch);
            for c in &mut self.scratch {
                *c = Complex64::new(c.norm_sqr(), 0.0);
            }
            self.ifft.process(&mut self.scratch);
            let scale = 1.0 / (2 * self.n) as f64;
            for (a, c) in self.acf[j].iter_mut().zip(&self.scratch) {
                *a += c.re * scale;
            }
        }
        self.segments += 1;
        self.run_segments += 1;
        for b in &mut self.buf {
            b.drain(..self.n / 2);
        }
        Ok(())
    }

    /// Ends a run: its segments.
    pub(super) fn end_run(&mut self) -> usize {
        self.buf.iter_mut().for_each(Vec::clear);
        std::mem::take(&mut self.run_segments)
    }
}
