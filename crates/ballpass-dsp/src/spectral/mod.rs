//! Welch spectral estimates: [`welch`], [`csd`], [`coherence`] and
//! [`periodogram`], matching
//! [`scipy.signal.welch`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.welch.html),
//! [`csd`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.csd.html),
//! [`coherence`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.coherence.html)
//! and [`periodogram`](https://docs.scipy.org/doc/scipy/reference/generated/scipy.signal.periodogram.html)
//! (SciPy 1.17), plus a reusable [`Welch`] that plans its FFT once.

use rustfft::num_complex::Complex64;

use crate::detrend::DetrendType;
use crate::error::{check_finite, invalid, DspError, Result};
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

mod engine;
mod set;
#[cfg(test)]
mod tests;

pub(crate) use engine::Engine;
pub use set::SpectralSet;
