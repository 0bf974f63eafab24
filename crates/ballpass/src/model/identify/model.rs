//! The model the stage fit ([`super`]) fits: the PD stage seen through the
//! measurement chain, the load cell's high-pass and the restoration that
//! undid it, and the stage behind the fitted linear parameters.

use ballpass_dsp::Complex64;

/// `Z` of the stage seen through the chain, at `ω`, from the linear
/// parameters ([`super`]).
fn z_model(p: &[f64; N_PARAMS], w: f64) -> Complex64 {
    Complex64::new(p[0] + p[1] * w * w, p[2] * w - p[3] / w - p[4] * w * w * w)
}

/// Parameters of the joint fit: the five of the stage and chain
/// (`N_STAGE`), the friction channel's white noise density
/// (`NOISE`), and the rate `1/τ` of the load cell's own high-pass
/// (`HIGH_PASS`) ([`super`]).
pub(super) const N_PARAMS: usize = 7;

/// The stage-and-chain parameters, first in the fit's parameter vector.
pub(super) const N_STAGE: usize = 5;

/// Index of the friction channel's noise density in the parameters.
pub(super) const NOISE: usize = 5;

/// Index of the load cell's high-pass rate in the parameters.
pub(super) const HIGH_PASS: usize = 6;

/// The restoration's transfer at `ω` (`fs` the rate, `tau` the time
/// constant undone): `1 + 1/(j ω' τ)`, the trapezoidal integration of
/// [`crate::analysis::load_cell::restore`] at the bilinear-warped
/// `ω' = 2 fs tan(ω / (2 fs))`; 1 when nothing was undone.
pub(super) fn restoration(w: f64, fs: f64, tau: Option<f64>) -> Complex64 {
    match tau {
        Some(tau) => {
            let wp = 2.0 * fs * (w / (2.0 * fs)).tan();
            Complex64::new(1.0, -1.0 / (wp * tau))
        }
        None => Complex64::new(1.0, 0.0),
    }
}

/// The measured `Z` the model predicts without the noise bias: the stage
/// and chain ([`z_model`]) times the load cell's own high-pass
/// `1 / (1 + (1/τ) / (j ω))` (rate `p[HIGH_PASS]`) and the restoration
/// `rh`.
pub(super) fn z_chain(p: &[f64; N_PARAMS], w: f64, rh: Complex64) -> Complex64 {
    z_model(p, w) * rh / Complex64::new(1.0, -p[HIGH_PASS] / w)
}

/// The stage and measurement chain behind the linear parameters
/// `p = [c − τ k, τ m − s c, m − τ c + s k, k, s m]` (the chain
/// `1 − j ω τ − s ω²`: [`super`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct Stage {
    pub(super) m: f64,
    pub(super) c: f64,
    pub(super) k: f64,
    pub(super) tau: f64,
}

impl Stage {
    /// Solves for `(m, c, k, τ, s)` by fixed-point iteration from
    /// `τ = s = 0` (it contracts while `τ² k / m` and `s k / m` are small,
    /// i.e. the chain is fast against the resonance); `None` when
    /// non-physical or not converged.
    pub(super) fn from_params(p: [f64; N_STAGE]) -> Option<Stage> {
        let k = p[3];
        let (mut m, mut c, mut tau) = (p[2], p[0], 0.0);
        for _ in 0..200 {
            if m.is_nan() || m <= 0.0 {
                return None;
            }
            let s_next = p[4] / m;
            let tau_next = (p[1] + s_next * c) / m;
            let m_next = p[2] + tau_next * c - s_next * k;
            let c_next = p[0] + tau_next * k;
            let done = (tau_next - tau).abs() <= 1e-13 * tau_next.abs().max(1e-9)
                && (m_next - m).abs() <= 1e-13 * m.abs();
            tau = tau_next;
            m = m_next;
            c = c_next;
            if done {
                break;
            }
        }
        let st = Stage { m, c, k, tau };
        (m > 0.0 && c > 0.0 && k > 0.0 && tau.is_finite() && st.f_n().is_finite()).then_some(st)
    }

    pub(super) fn f_n(&self) -> f64 {
        (self.k / self.m).sqrt() / std::f64::consts::TAU
    }

    pub(super) fn zeta(&self) -> f64 {
        self.c / (2.0 * (self.m * self.k).sqrt())
    }
}
