//! The pulse-train models of thesis §6.3 fitted to the record: the Gaussian
//! train (Eq. 6.24) and the rectangular train of order N (Eq. 6.22, as
//! corrected in docs/methods.md §5), by [`ballpass_dsp::least_squares`] with the
//! analytic Jacobians of [`crate::analysis::train_fit`].

use super::signal::median;
use super::{
    FitQuality, GaussianTrainFit, Passage, PassageSettings, RectangularTrainFit, TrainFits,
    FWHM_PER_SIGMA,
};
use crate::analysis::train_fit;

/// Most samples per ball-pass period used by the pulse-train fits.
const FIT_SAMPLES_PER_PERIOD: f64 = 150.0;

fn quality(
    resid: &[f64],
    data: &[f64],
    med_amp: f64,
    iterations: usize,
    converged: bool,
) -> FitQuality {
    let m = data.len().max(1) as f64;
    let mean = data.iter().sum::<f64>() / m;
    let ss_tot: f64 = data.iter().map(|v| (v - mean).powi(2)).sum();
    let ss_res: f64 = resid.iter().map(|v| v * v).sum();
    let rms = (ss_res / m).sqrt();
    FitQuality {
        rms_residual_v: rms,
        rms_over_amplitude: rms / med_amp,
        r_squared: if ss_tot > 0.0 {
            1.0 - ss_res / ss_tot
        } else {
            0.0
        },
        samples: data.len(),
        iterations,
        converged,
    }
}

/// Fits the Gaussian (Eq. 6.24) and rectangular (Eq. 6.22 corrected) trains
/// to the first `fit_pulses` passages of the baseline-removed signal (the
/// whole record when it has no more).
pub(super) fn fit_trains(
    y: &[f64],
    fs: f64,
    t_start: f64,
    passages: &[Passage],
    settings: &PassageSettings,
    med_amp: f64,
) -> TrainFits {
    let k = settings.fit_pulses.min(passages.len());
    let used = &passages[..k];
    let tau0 = {
        let t: Vec<f64> = used
            .iter()
            .filter_map(|p| p.tau_c_s)
            .take(k.saturating_sub(1))
            .collect();
        if t.is_empty() {
            passages[1].time_s - passages[0].time_s
        } else {
            median(&t)
        }
    };
    let from = (used[0].time_s - 0.5 * tau0).max(t_start);
    let to = (used[k - 1].time_s + 0.5 * tau0).min(t_start + y.len() as f64 / fs);
    let i0 = ((from - t_start) * fs).ceil().max(0.0) as usize;
    let i1 = (((to - t_start) * fs).floor() as usize).min(y.len() - 1);
    // At most FIT_SAMPLES_PER_PERIOD samples per period keeps the fit cheap;
    // the pulses (FWHM ≈ 0.155 τ_c) are still sampled ~20 times at half height.
    let stride = ((tau0 * fs / FIT_SAMPLES_PER_PERIOD).floor() as usize).max(1);
    let idx: Vec<usize> = (i0..=i1).step_by(stride).collect();
    let t: Vec<f64> = idx.iter().map(|&i| t_start + i as f64 / fs).collect();
    let d: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
    let m = t.len();
    let mut fits = TrainFits {
        from_s: from,
        to_s: to,
        pulses: k,
        gaussian: None,
        rectangular: None,
        better: None,
        notes: Vec::new(),
    };
    if m < 8 + k {
        fits.notes.push(format!(
            "only {m} samples between {from:.3} s and {to:.3} s for {k} pulses: no fit"
        ));
        return fits;
    }
    let widths: Vec<f64> = used.iter().map(|p| p.tau_p_s).collect();
    let tau_p0 = median(&widths);
    let sigma0 = tau_p0 / FWHM_PER_SIGMA;

    // Gaussian: θ = [S, t0, τ, σ, P_0 .. P_{k−1}], started from the
    // detections (first centre, median period and width, each prominence).
    let mut th0 = vec![0.0, used[0].time_s, tau0, sigma0];
    th0.extend(used.iter().map(|p| p.amplitude_v));
    match train_fit::fit_gaussian(&t, &d, &th0) {
        Ok(g) => {
            let sig = g.params[3].abs();
            fits.gaussian = Some(GaussianTrainFit {
                dc_v: g.params[0],
                t0_s: g.params[1],
                tau_c_s: g.params[2],
                sigma_s: sig,
                tau_p_s: FWHM_PER_SIGMA * sig,
                amplitudes_v: g.params[train_fit::G_AMP0..].to_vec(),
                quality: quality(&g.residuals, &d, med_amp, g.iterations, g.converged),
            });
        }
        Err(e) => fits.notes.push(format!("Gaussian train fit failed: {e}")),
    }

    // Rectangular, order N: θ = [S, P, t_s, τ, r]; the pulse occupies
    // [t_s + τ − rτ, t_s + τ) of each period (Eq. 6.18).
    let order = settings.rectangular_order;
    let r0 = (tau_p0 / tau0).clamp(0.01, 0.9);
    // Centre of the first pulse at t_s + τ(1 − r/2).
    let ts0 = used[0].time_s - tau0 * (1.0 - r0 / 2.0);
    match train_fit::fit_rectangular(&t, &d, &[0.0, med_amp, ts0, tau0, r0], order) {
        Ok(rf) => {
            fits.rectangular = Some(RectangularTrainFit {
                dc_v: rf.params[0],
                amplitude_v: rf.params[1],
                t_start_s: rf.params[2],
                tau_c_s: rf.params[3],
                tau_p_s: rf.params[4] * rf.params[3],
                ratio: rf.params[4],
                order,
                quality: quality(&rf.residuals, &d, med_amp, rf.iterations, rf.converged),
            });
        }
        Err(e) => fits
            .notes
            .push(format!("rectangular train fit failed: {e}")),
    }
    if let (Some(a), Some(b)) = (&fits.gaussian, &fits.rectangular) {
        fits.better = Some(
            if a.quality.rms_residual_v <= b.quality.rms_residual_v {
                "gaussian"
            } else {
                "rectangular"
            }
            .into(),
        );
    }
    fits
}
