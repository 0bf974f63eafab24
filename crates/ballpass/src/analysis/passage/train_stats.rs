//! A train's statistics over its passages (periods, widths, amplitudes),
//! shared by the whole-record detection and the streamed windows.

use super::signal::median;
use super::Passage;
use crate::stats::MeanStd;

/// A train's statistics over its passages: the periods, the widths and
/// amplitudes of the passages whose width is used, and f_c's period over
/// the periods that are not gaps (a missed passage makes a period twice as
/// long: those of 1.6 median periods and more are left out). The
/// whole-record detection and the streamed one's windows share it.
#[derive(Debug, Clone)]
pub(crate) struct TrainStats {
    /// Every period between consecutive passages, s.
    pub tau_c_all: Vec<f64>,
    /// The periods shorter than 1.6 × their median, s.
    pub regular: Vec<f64>,
    /// Median period, s.
    pub med_tau: f64,
    /// Period over `regular` (over all periods when none is regular).
    pub tau_c: MeanStd,
    /// Width (FWHM) of the passages whose width is used; NaN when none.
    pub tau_p: MeanStd,
    /// Gaussian σ of the same passages (falls back to `tau_p`).
    pub sigma: MeanStd,
    /// Width over period of the same passages (falls back to `tau_p`).
    pub tau_p_over_tau_c: MeanStd,
    /// Amplitude of every passage (falls back to the period's).
    pub amplitude: MeanStd,
}

impl TrainStats {
    /// `None` when no period is known (fewer than two passages).
    pub(crate) fn of(passages: &[Passage]) -> Option<Self> {
        let col = |f: &dyn Fn(&Passage) -> Option<f64>| -> Vec<f64> {
            passages.iter().filter_map(f).collect()
        };
        let tau_c_all = col(&|p| p.tau_c_s);
        let all = MeanStd::of(&tau_c_all)?;
        let used = |p: &Passage| p.width_used;
        let tau_p = MeanStd::of(&col(&|p| used(p).then_some(p.tau_p_s))).unwrap_or(MeanStd {
            mean: f64::NAN,
            std: f64::NAN,
            n: 0,
        });
        let sigma = MeanStd::of(&col(&|p| used(p).then_some(p.sigma_s))).unwrap_or(tau_p);
        let tau_p_over_tau_c =
            MeanStd::of(&col(&|p| p.tau_p_over_tau_c.filter(|_| used(p)))).unwrap_or(tau_p);
        let amplitude = MeanStd::of(&col(&|p| Some(p.amplitude_v))).unwrap_or(all);
        let med_tau = median(&tau_c_all);
        let regular: Vec<f64> = tau_c_all
            .iter()
            .copied()
            .filter(|t| *t < 1.6 * med_tau)
            .collect();
        let tau_c = MeanStd::of(&regular).unwrap_or(all);
        Some(Self {
            tau_c_all,
            regular,
            med_tau,
            tau_c,
            tau_p,
            sigma,
            tau_p_over_tau_c,
            amplitude,
        })
    }
}
