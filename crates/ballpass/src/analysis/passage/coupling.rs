//! The AC coupling of the photodetector: its rate read off the template,
//! whether undoing it is plausible, and the restored level's mean ramp
//! (module docs of [`super`], "AC coupling").

use super::lsq::{Solution, Splines};
use super::template::Pulse;

/// Fastest AC coupling looked for: `T = τ_c / 50`.
const AC_MAX_RATE_PER_PERIOD: f64 = 50.0;

/// The rate `κ = 1/T` of a first-order AC coupling: the `κ` whose
/// restored template `h_z + κ h_I` (`h_z`, `h_I`: the templates of the
/// blocks and of their running integral, same pulses) ends where it
/// starts, `κ = −Δh_z / Δh_I` with `Δ` the mean of the last
/// [`END_POINTS`] grid points less that of the first. A pulse of light
/// starts and ends at the level around it; an AC coupling pulls the level
/// after each pulse down by `κ_true` × its area, which `h_I` (a step of
/// the pulse's area) measures. 0 unless the step of `h_z` is down by more
/// than `max(0.5 %, 3 standard errors)` of the peak (standard error of an
/// end's mean: `block_noise / √(3 Σ a_k² dx)`, the step's `√2` that), or
/// when `κ` exceeds `50 / τ_c`, or leaves no pulse shape. (A dip after the
/// pulse is no measure: a skewed pulse's long tail fills it, and a rate
/// that merely removes it is short of the true one.) With `κ`, the restored
/// template's peak.
pub(super) fn ac_rate(
    hz: &Solution,
    hi: &Solution,
    pulses: &[Pulse],
    block_noise: f64,
    tau_c_s: f64,
) -> Option<(f64, f64)> {
    let (tz, ti) = (&hz.template, &hi.template);
    let g = tz.h.len();
    if g < 2 * END_POINTS + 1 || ti.h.len() != g {
        return None;
    }
    let sh = tz.shape()?;
    let step = |h: &[f64]| -> f64 {
        let k = END_POINTS as f64;
        h[g - END_POINTS..].iter().sum::<f64>() / k - h[..END_POINTS].iter().sum::<f64>() / k
    };
    let (dz, di) = (step(&tz.h), step(&ti.h));
    if di.is_nan() || di <= 0.0 {
        return None;
    }
    // Standard error of an end's mean over `END_POINTS` grid points
    // (each point the least-squares estimate from every pulse), and of the
    // step, their difference.
    let a2: f64 = pulses.iter().map(|p| p.a * p.a).sum();
    let se_end = block_noise
        / (END_POINTS as f64 * a2 * tz.dx)
            .max(f64::MIN_POSITIVE)
            .sqrt();
    let se_step = std::f64::consts::SQRT_2 * se_end;
    if dz >= -(AC_LOBE * sh.peak).max(3.0 * se_step) {
        return None;
    }
    let kappa = -dz / di;
    if kappa > AC_MAX_RATE_PER_PERIOD / tau_c_s {
        return None;
    }
    let mut t = tz.clone();
    for (v, w) in t.h.iter_mut().zip(&ti.h) {
        *v += kappa * w;
    }
    Some((kappa, t.shape()?.peak))
}

/// Whether undoing an AC coupling of rate `kappa` leaves a light level a
/// photodetector could have seen.
///
/// A first-order coupling removes the light's running mean over `T`, so the
/// recorded signal's mean over the record is the change of that running
/// mean between its ends: the light's drift between them, and at most the
/// pulses' own mean (under half a pulse) while the coupling settles. The
/// level restored is the least squares' baseline `b` (of `z + κ ∫(z − mean)
/// dt`) plus the ramp `κ × mean(z) × t` ([`with_mean_ramp`]). A coupling
/// read off a DC-coupled record (the step of wide pulses' tails, say)
/// turns the record's DC level into a ramp of `duration / T` times that
/// level, which no drift seen in `b` explains. The coupling is plausible
/// when the ramp exceeds the range of `b` by less than
/// [`AC_RAMP_EXCESS`] pulse heights.
///
/// `peak`: the restored template's peak (pulse amplitudes are in its
/// units); `mean_ramp`: the record's mean of `z` times its duration, V s.
pub(super) fn ac_plausible(
    (kappa, peak): (f64, f64),
    hz: &Solution,
    hi: &Solution,
    pulses: &[Pulse],
    fast: &[f64],
    splines: &Splines,
    mean_ramp: f64,
) -> bool {
    let nd = fast.len();
    let amps: Vec<f64> = pulses.iter().map(|p| p.a.abs()).collect();
    let height = super::signal::median(&amps) * peak;
    if height.is_nan() || height <= 0.0 || nd == 0 {
        return true;
    }
    let beta: Vec<f64> = hz
        .beta
        .iter()
        .zip(&hi.beta)
        .map(|(a, b)| a + kappa * b)
        .collect();
    let b = splines.eval(&beta, nd);
    let (lo, hi_b) = b
        .iter()
        .zip(fast)
        .map(|(a, f)| a + f)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let ramp = (kappa * mean_ramp).abs();
    ramp - (hi_b - lo) < AC_RAMP_EXCESS * height
}

/// Largest excess, in pulse heights, of the restored level's mean ramp over
/// the baseline's own range for an AC coupling to be kept
/// ([`ac_plausible`]): twice the most the pulses' mean can explain.
const AC_RAMP_EXCESS: f64 = 1.0;

/// Grid points averaged at each end of the template for its step.
const END_POINTS: usize = 3;

/// Smallest step down across the template, in pulse heights, that counts as
/// an AC coupling's (at least; three standard errors when more).
const AC_LOBE: f64 = 0.005;

/// `baseline` plus `κ (∫z dt − ∫(z − mean z) dt)`, the integrals from
/// block 0 to block `i`: `κ × mean × i dt`.
///
/// The least squares restore `z + κ ∫(z − mean) dt`
/// ([`super::signal::running_integral`]), whose baseline is the restored signal's less
/// `κ mean t`: a ramp that holds nothing of the light (an AC-coupled
/// record's mean is what its ends happen to leave, `T Δ(x − y) /
/// duration`; 0.008 V over 30 s at 1 mm/s, `T` = 1 s: a 0.23 V ramp,
/// a third of the pulse). The splines take it, so the pulses are the same
/// either way; the baseline reported gets it back.
pub(super) fn with_mean_ramp(baseline: &[f64], z: &[f64], kappa: f64, dt: f64) -> Vec<f64> {
    let rate = kappa * z.iter().sum::<f64>() / z.len().max(1) as f64;
    baseline
        .iter()
        .enumerate()
        .map(|(i, b)| b + rate * i as f64 * dt)
        .collect()
}
