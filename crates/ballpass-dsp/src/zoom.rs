//! The thesis' "zoom processing" (§7.2, Fig. 61), kept under a name that
//! says what it computes: the average of the Welch spectra of the `M`
//! polyphase components of a signal.
//!
//! **Offered only to reproduce the thesis' figures.** As docs/methods.md §10 shows,
//! taking every `M`-th sample without an anti-alias filter folds all power
//! above `fs / (2M)` into the band (a 60 Hz hum at 1 kHz with `M = 20`
//! lands at 10 Hz), and averaging over the `M` phases cancels the alias
//! cross-terms but *adds the folded power*. The `M` branches are almost
//! perfectly correlated, so the average gains no independent averages:
//! the variance is that of the per-branch segment count, not `M` times it.
//! For a high-resolution spectrum, low-pass at `<= fs / (2M)` and decimate
//! once, or run Welch with `M`-times longer segments.

use crate::error::{check_finite, invalid, DspError, Result};
use crate::spectral::{Csd, Psd, Welch, WelchSettings};
use crate::Complex64;

/// Splits `x` into `m` branches `x_i[k] = x[m k + i]`, `k < len / m`.
fn branches(x: &[f64], m: usize) -> Vec<Vec<f64>> {
    let len = x.len() / m;
    (0..m)
        .map(|i| (0..len).map(|k| x[m * k + i]).collect())
        .collect()
}

fn check_decimation(decimation: usize, n: usize) -> Result<()> {
    if decimation == 0 {
        return Err(invalid(
            "decimation",
            "decimation factor M must be at least 1, got 0",
        ));
    }
    if n < decimation {
        return Err(DspError::TooShort {
            what: "x (polyphase branches need one sample each)",
            needed: decimation,
            found: n,
        });
    }
    Ok(())
}

/// Thesis "zoom processing" auto spectrum: the mean over `i = 0..M` of the
/// Welch PSDs of the delayed decimations `x_i[k] = x[M k + i]`, each
/// sampled at `fs_hz / M`.
///
/// ```text
/// L      = floor(N / M)                       (each branch keeps L samples;
///                                              up to M - 1 trailing samples dropped)
/// x_i[k] = x[M k + i],          k = 0 .. L-1, i = 0 .. M-1
/// Pxx    = (1/M) sum_i welch(x_i, fs / M)     (settings applied to every branch)
/// ```
///
/// Frequencies run to `fs / (2M)` with bin spacing `fs / (M nfft)`.
/// `n_segments` is the per-branch segment count, which is the number of
/// (roughly) independent averages: see docs/methods.md §10 and the module docs —
/// this estimate **aliases**, adds the folded power of everything above
/// `fs / (2M)`, and does not gain `M`-fold averaging. It exists only to
/// reproduce the thesis (Figs. 63, 65, 68).
///
/// With `M = 1` it is [`welch`](crate::welch).
///
/// ```
/// use ballpass_dsp::{polyphase_average_psd, WelchSettings};
/// // A 40 Hz tone at fs = 100 Hz with M = 2: the branches run at 50 Hz,
/// // so the tone aliases to 10 Hz instead of disappearing.
/// let x: Vec<f64> = (0..4000)
///     .map(|n| (2.0 * std::f64::consts::PI * 40.0 * n as f64 / 100.0).cos())
///     .collect();
/// let s = WelchSettings { nperseg: 100, ..Default::default() };
/// let p = polyphase_average_psd(&x, 100.0, 2, &s).unwrap();
/// let k = p.pxx.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap().0;
/// assert!((p.freq_hz[k] - 10.0).abs() < 1e-9);
/// ```
///
/// # Errors
/// As [`welch`](crate::welch) for `x` and the settings (checked per
/// branch); [`DspError::InvalidSetting`] for `decimation == 0`;
/// [`DspError::TooShort`] if `x` has fewer than `decimation` samples.
pub fn polyphase_average_psd(
    x: &[f64],
    fs_hz: f64,
    decimation: usize,
    settings: &WelchSettings,
) -> Result<Psd> {
    check_finite("x", x)?;
    check_decimation(decimation, x.len())?;
    let fs_branch = fs_hz / decimation as f64;
    let branches = branches(x, decimation);
    let mut welch = Welch::for_len(settings.clone(), x.len() / decimation)?;
    let mut out: Option<Psd> = None;
    for b in &branches {
        let p = welch.psd(b, fs_branch)?;
        match &mut out {
            None => out = Some(p),
            Some(acc) => acc.pxx.iter_mut().zip(&p.pxx).for_each(|(a, v)| *a += v),
        }
    }
    let mut out = out.expect("decimation >= 1 gives at least one branch");
    let inv = decimation as f64;
    out.pxx.iter_mut().for_each(|v| *v /= inv);
    Ok(out)
}

/// Thesis "zoom processing" cross spectrum: the mean over the `M` polyphase
/// branches of the Welch CSDs `conj(X_i) Y_i` of `x_i[k] = x[M k + i]` and
/// `y_i[k] = y[M k + i]`, each at `fs_hz / M`.
///
/// Same construction, caveats and docs/methods.md §10 warning as
/// [`polyphase_average_psd`]; offered only to reproduce the thesis.
///
/// # Errors
/// As [`polyphase_average_psd`], and [`DspError::LengthMismatch`] if `x`
/// and `y` differ in length.
pub fn polyphase_average_csd(
    x: &[f64],
    y: &[f64],
    fs_hz: f64,
    decimation: usize,
    settings: &WelchSettings,
) -> Result<Csd> {
    check_finite("x", x)?;
    check_finite("y", y)?;
    if x.len() != y.len() {
        return Err(DspError::LengthMismatch {
            what: "x and y (polyphase average csd)",
            expected: x.len(),
            found: y.len(),
        });
    }
    check_decimation(decimation, x.len())?;
    let fs_branch = fs_hz / decimation as f64;
    let bx = branches(x, decimation);
    let by = branches(y, decimation);
    let mut welch = Welch::for_len(settings.clone(), x.len() / decimation)?;
    let mut out: Option<Csd> = None;
    for (a, b) in bx.iter().zip(&by) {
        let p = welch.csd(a, b, fs_branch)?;
        match &mut out {
            None => out = Some(p),
            Some(acc) => acc.pxy.iter_mut().zip(&p.pxy).for_each(|(s, v)| *s += v),
        }
    }
    let mut out = out.expect("decimation >= 1 gives at least one branch");
    let inv = decimation as f64;
    out.pxy.iter_mut().for_each(|v: &mut Complex64| *v /= inv);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_one_is_welch() {
        let x: Vec<f64> = (0..600).map(|i| ((i * 31 % 17) as f64).sin()).collect();
        let s = WelchSettings {
            nperseg: 64,
            ..Default::default()
        };
        let a = polyphase_average_psd(&x, 10.0, 1, &s).unwrap();
        let b = crate::welch(&x, 10.0, &s).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn errors() {
        let s = WelchSettings::default();
        assert!(polyphase_average_psd(&[1.0; 10], 1.0, 0, &s).is_err());
        assert!(polyphase_average_psd(&[1.0; 3], 1.0, 4, &s).is_err());
        assert!(polyphase_average_csd(&[1.0; 10], &[1.0; 9], 1.0, 2, &s).is_err());
        assert!(polyphase_average_psd(&[1.0; 10], -1.0, 2, &s).is_err());
    }
}
