//! The sinusoid model signals of thesis §6.2 (Eqs. 6.7–6.9) and their analytic
//! correlations and spectra (Eqs. 6.10–6.17, corrected by docs/methods.md §4 and §9).
//!
//! Every model signal is a DC level plus one sinusoid at the ball-pass
//! frequency:
//!
//! ```text
//! x(t) = c_x + p_x cos(ω_c t) + q_x sin(ω_c t)
//! friction      F_f(t) = F_c + a_f sin(ω_c t)     (Eq. 6.7)
//! velocity err. v_e(t) =       a_v cos(ω_c t)     (Eq. 6.8)
//! optical       s(t)   = S   + a_s sin(ω_c t)     (Eq. 6.9)
//! ```
//!
//! # Lag conventions
//!
//! Two correlation conventions are in use and they are mirror images
//! (docs/methods.md §9, CONVENTIONS.md):
//!
//! ```text
//! Eq. 6.12 (thesis ch. 6):        R_xy(τ) = ⟨x(t) y(t+τ)⟩
//! Eq. 7.1  (scipy correlate, MATLAB xcorr, ballpass):
//!                                  R_xy(τ) = ⟨x(t+τ) y(t)⟩ = R^{6.12}_xy(−τ)
//! ```
//!
//! With Eq. 7.1, if y is x delayed by d the peak is at τ = −d. ballpass reports
//! correlations in Eq. 7.1 by default ([`LagConvention::Eq71`]); the Eq. 6.12
//! form is available to reproduce the thesis' printed results. The spectra are
//! the unitary Fourier transforms of the Eq. 6.12 correlation, which is what
//! `scipy.signal.csd(x, y)` (`conj(X)·Y`) estimates.
//!
//! With Eq. 6.12 the analytic results are (docs/methods.md §4):
//!
//! ```text
//! R_xy(τ) = c_x c_y + ½[(p_x p_y + q_x q_y) cos ω_c τ + (p_x q_y − q_x p_y) sin ω_c τ]
//! R_Fve = −(a_f a_v/2) sin ω_c τ,  R_Fs = F_c S + (a_f a_s/2) cos ω_c τ,  R_sve = −(a_s a_v/2) sin ω_c τ
//! S_xy(ω) = c_x c_y √(2π) δ(ω) + W δ(ω − ω_c) + W* δ(ω + ω_c),
//!           W = ½ √(π/2) [(p_x p_y + q_x q_y) − j (p_x q_y − q_x p_y)]
//! S_Fve(ω) = +j (a_f a_v/2) √(π/2) δ(ω − ω_c) − j (a_f a_v/2) √(π/2) δ(ω + ω_c)   (Eq. 6.17 corrected)
//! ```

use std::f64::consts::PI;

use rustfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Which correlation convention a lag is expressed in (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LagConvention {
    /// `R_xy(τ) = ⟨x(t+τ) y(t)⟩`: thesis Eq. 7.1, `scipy.signal.correlate`,
    /// MATLAB `xcorr`. A peak at `τ = −d` means y lags x by d.
    #[default]
    Eq71,
    /// `R_xy(τ) = ⟨x(t) y(t+τ)⟩`: thesis Eq. 6.12. A peak at `τ = +d` means
    /// y lags x by d.
    Eq612,
}

/// A DC level plus one sinusoid at the ball-pass frequency:
/// `x(t) = dc + cos_amp·cos(ω_c t) + sin_amp·sin(ω_c t)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sinusoid {
    /// Constant part `c`, in the signal's unit.
    pub dc: f64,
    /// Amplitude of the cosine `p`.
    pub cos_amp: f64,
    /// Amplitude of the sine `q`.
    pub sin_amp: f64,
}

impl Sinusoid {
    /// Value at time `t_s` for angular frequency `omega_rad_s`.
    pub fn value(&self, omega_rad_s: f64, t_s: f64) -> f64 {
        let (s, c) = (omega_rad_s * t_s).sin_cos();
        self.dc + self.cos_amp * c + self.sin_amp * s
    }

    /// Coefficients `(c, P, Q)` of the Eq. 6.12 cross-correlation with `y`:
    /// `R_xy(τ) = c + P cos ω_c τ + Q sin ω_c τ`.
    fn cross_terms(&self, y: &Sinusoid) -> (f64, f64, f64) {
        (
            self.dc * y.dc,
            0.5 * (self.cos_amp * y.cos_amp + self.sin_amp * y.sin_amp),
            0.5 * (self.cos_amp * y.sin_amp - self.sin_amp * y.cos_amp),
        )
    }
}

/// The three model signals of thesis §6.2 at one ball-pass frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SinusoidModel {
    /// Ball-pass frequency `f_c`, Hz.
    pub f_c_hz: f64,
    /// Coulomb friction `F_c`, N.
    pub friction_dc_n: f64,
    /// Friction sinusoid amplitude `a_f`, N.
    pub friction_amp_n: f64,
    /// Velocity-error cosine amplitude `a_v`, mm/s.
    pub velocity_amp_mm_s: f64,
    /// Photodetector DC level `S`, V.
    pub optical_dc_v: f64,
    /// Photodetector sinusoid amplitude `a_s`, V.
    pub optical_amp_v: f64,
}

impl Default for SinusoidModel {
    /// Unit amplitudes, unit DC levels, `f_c = 1 Hz`.
    fn default() -> Self {
        Self {
            f_c_hz: 1.0,
            friction_dc_n: 1.0,
            friction_amp_n: 1.0,
            velocity_amp_mm_s: 1.0,
            optical_dc_v: 1.0,
            optical_amp_v: 1.0,
        }
    }
}

/// One of the three model signals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ModelSignal {
    /// Friction force `F_f` (Eq. 6.7), N.
    Friction,
    /// Velocity error `v_e` (Eq. 6.8), mm/s.
    VelocityError,
    /// Optical sensor `s` (Eq. 6.9), V.
    Optical,
}

impl ModelSignal {
    /// All three, in the thesis' order.
    pub const ALL: [ModelSignal; 3] = [
        ModelSignal::Friction,
        ModelSignal::VelocityError,
        ModelSignal::Optical,
    ];

    /// Short name used in tables (`F`, `ve`, `s`).
    pub fn symbol(self) -> &'static str {
        match self {
            ModelSignal::Friction => "F",
            ModelSignal::VelocityError => "ve",
            ModelSignal::Optical => "s",
        }
    }
}

/// A Dirac line `weight · δ(ω − omega_rad_s)` of a spectral density.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpectralLine {
    /// Where the line sits, rad/s.
    pub omega_rad_s: f64,
    /// Real part of its complex weight (unitary transform, see the module docs).
    pub weight_re: f64,
    /// Imaginary part of its complex weight.
    pub weight_im: f64,
}

impl SpectralLine {
    fn new(omega_rad_s: f64, weight: Complex64) -> Self {
        Self {
            omega_rad_s,
            weight_re: weight.re,
            weight_im: weight.im,
        }
    }

    /// The complex weight.
    pub fn weight(&self) -> Complex64 {
        Complex64::new(self.weight_re, self.weight_im)
    }
}

/// Where the correlation peak nearest zero lag sits and what phase it means.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CorrelationPeak {
    /// Lag of the peak nearest zero, s, in the stated convention.
    pub tau_phi_s: f64,
    /// `φ = 360° τ_φ / τ_c`, degrees (docs/methods.md §8), in (−180, 180].
    pub phase_deg: f64,
    /// The convention the lag is expressed in.
    pub convention: LagConvention,
    /// How much y lags x, s (negative: y leads x), independent of convention.
    pub y_lags_x_s: f64,
}

impl SinusoidModel {
    /// Checks that `f_c` is positive and every amplitude finite.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] naming the bad field.
    pub fn validate(&self) -> Result<()> {
        if !(self.f_c_hz.is_finite() && self.f_c_hz > 0.0) {
            return Err(Error::setting(
                "f_c",
                format!("must be a positive number of Hz, got {}", self.f_c_hz),
            ));
        }
        for (name, v) in [
            ("friction DC", self.friction_dc_n),
            ("friction amplitude", self.friction_amp_n),
            ("velocity amplitude", self.velocity_amp_mm_s),
            ("optical DC", self.optical_dc_v),
            ("optical amplitude", self.optical_amp_v),
        ] {
            if !v.is_finite() {
                return Err(Error::setting(name, format!("must be finite, got {v}")));
            }
        }
        Ok(())
    }

    /// Angular ball-pass frequency `ω_c = 2π f_c`, rad/s.
    pub fn omega_c_rad_s(&self) -> f64 {
        2.0 * PI * self.f_c_hz
    }

    /// Ball-pass period `τ_c = 1 / f_c`, s.
    pub fn tau_c_s(&self) -> f64 {
        1.0 / self.f_c_hz
    }

    /// The signal as a [`Sinusoid`].
    pub fn signal(&self, which: ModelSignal) -> Sinusoid {
        match which {
            ModelSignal::Friction => Sinusoid {
                dc: self.friction_dc_n,
                cos_amp: 0.0,
                sin_amp: self.friction_amp_n,
            },
            ModelSignal::VelocityError => Sinusoid {
                dc: 0.0,
                cos_amp: self.velocity_amp_mm_s,
                sin_amp: 0.0,
            },
            ModelSignal::Optical => Sinusoid {
                dc: self.optical_dc_v,
                cos_amp: 0.0,
                sin_amp: self.optical_amp_v,
            },
        }
    }

    /// Value of a model signal at `t_s`.
    pub fn value(&self, which: ModelSignal, t_s: f64) -> f64 {
        self.signal(which).value(self.omega_c_rad_s(), t_s)
    }

    /// Analytic cross-correlation `R_xy(τ)` at lag `tau_s` in `convention`
    /// (auto-correlation when `x == y`).
    ///
    /// ```
    /// use ballpass::model::signals::{LagConvention, ModelSignal as M, SinusoidModel};
    /// let m = SinusoidModel { f_c_hz: 1.0, ..Default::default() };
    /// // Eq. 6.12: R_Fve(τ) = −(a_f a_v / 2) sin ω_c τ, so −½ at τ = τ_c/4.
    /// let r = m.correlation(M::Friction, M::VelocityError, 0.25, LagConvention::Eq612);
    /// assert!((r + 0.5).abs() < 1e-12);
    /// ```
    pub fn correlation(
        &self,
        x: ModelSignal,
        y: ModelSignal,
        tau_s: f64,
        convention: LagConvention,
    ) -> f64 {
        let (c, p, q) = self.signal(x).cross_terms(&self.signal(y));
        let tau = match convention {
            LagConvention::Eq612 => tau_s,
            LagConvention::Eq71 => -tau_s,
        };
        let (s, co) = (self.omega_c_rad_s() * tau).sin_cos();
        c + p * co + q * s
    }

    /// The Dirac lines of the cross-spectral density `S_xy(ω)` (unitary
    /// transform of the Eq. 6.12 correlation; `conj(X)·Y` as scipy `csd`).
    /// Lines of zero weight are left out.
    ///
    /// ```
    /// use ballpass::model::signals::{ModelSignal as M, SinusoidModel};
    /// let m = SinusoidModel::default();
    /// // docs/methods.md §4: S_Fve has +j (a_f a_v / 2) √(π/2) at +ω_c.
    /// let lines = m.cross_spectrum(M::Friction, M::VelocityError);
    /// let w = lines.iter().find(|l| l.omega_rad_s > 0.0).unwrap().weight();
    /// assert!(w.re.abs() < 1e-15 && (w.im - 0.5 * (std::f64::consts::PI / 2.0).sqrt()).abs() < 1e-15);
    /// ```
    pub fn cross_spectrum(&self, x: ModelSignal, y: ModelSignal) -> Vec<SpectralLine> {
        let (c, p, q) = self.signal(x).cross_terms(&self.signal(y));
        let wc = self.omega_c_rad_s();
        let k = (PI / 2.0).sqrt();
        // FT[cos] = √(π/2)[δ(ω−ω0)+δ(ω+ω0)], FT[sin] = −j√(π/2)[δ(ω−ω0)−δ(ω+ω0)].
        let w_pos = Complex64::new(p * k, -q * k);
        let mut lines = Vec::with_capacity(3);
        if w_pos.norm() > 0.0 {
            lines.push(SpectralLine::new(-wc, w_pos.conj()));
        }
        if c != 0.0 {
            lines.push(SpectralLine::new(
                0.0,
                Complex64::new(c * (2.0 * PI).sqrt(), 0.0),
            ));
        }
        if w_pos.norm() > 0.0 {
            lines.push(SpectralLine::new(wc, w_pos));
        }
        lines
    }

    /// The correlation peak nearest zero lag and the phase it implies
    /// (`φ = 360° τ_φ / τ_c`, docs/methods.md §8), or `None` when x and y share no
    /// periodic content.
    ///
    /// ```
    /// use ballpass::model::signals::{LagConvention, ModelSignal as M, SinusoidModel};
    /// let m = SinusoidModel { f_c_hz: 1.0, ..Default::default() };
    /// // The velocity error (cos) leads friction (sin) by a quarter period.
    /// let pk = m.correlation_peak(M::Friction, M::VelocityError, LagConvention::Eq612).unwrap();
    /// assert!((pk.tau_phi_s + 0.25).abs() < 1e-12 && (pk.phase_deg + 90.0).abs() < 1e-9);
    /// assert!((pk.y_lags_x_s + 0.25).abs() < 1e-12);
    /// ```
    pub fn correlation_peak(
        &self,
        x: ModelSignal,
        y: ModelSignal,
        convention: LagConvention,
    ) -> Option<CorrelationPeak> {
        let (_, p, q) = self.signal(x).cross_terms(&self.signal(y));
        if p == 0.0 && q == 0.0 {
            return None;
        }
        // Eq. 6.12: p cos ωτ + q sin ωτ = M cos(ωτ − θ), θ = atan2(q, p) in (−π, π].
        let theta = q.atan2(p);
        let tau_612 = theta / self.omega_c_rad_s();
        // `+ 0.0` turns a −0 into 0 for printing.
        let tau_phi_s = match convention {
            LagConvention::Eq612 => tau_612,
            LagConvention::Eq71 => -tau_612,
        } + 0.0;
        let mut phase_deg = 360.0 * tau_phi_s * self.f_c_hz;
        if phase_deg <= -180.0 {
            phase_deg += 360.0;
        }
        Some(CorrelationPeak {
            tau_phi_s,
            phase_deg,
            convention,
            y_lags_x_s: tau_612 + 0.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ModelSignal as M;

    fn model() -> SinusoidModel {
        SinusoidModel {
            f_c_hz: 1.10959,
            friction_dc_n: 2.5,
            friction_amp_n: 0.3,
            velocity_amp_mm_s: 0.07,
            optical_dc_v: 1.2,
            optical_amp_v: 0.4,
        }
    }

    /// Time average of x(t) y(t+τ) over whole periods by the trapezoid rule,
    /// which is exact (to rounding) for trigonometric polynomials of degree < n.
    fn numeric_612(m: &SinusoidModel, x: M, y: M, tau: f64) -> f64 {
        let n = 64;
        let tc = m.tau_c_s();
        (0..n)
            .map(|i| {
                let t = tc * i as f64 / n as f64;
                m.value(x, t) * m.value(y, t + tau)
            })
            .sum::<f64>()
            / n as f64
    }

    #[test]
    fn correlations_match_time_averages_in_both_conventions() {
        let m = model();
        for x in M::ALL {
            for y in M::ALL {
                for k in 0..13 {
                    let tau = (k as f64 - 6.0) * 0.137;
                    let num = numeric_612(&m, x, y, tau);
                    // Exact quadrature of a degree-2 trigonometric polynomial: only
                    // rounding differs (values are O(10), so 1e-12 absolute).
                    let a = m.correlation(x, y, tau, LagConvention::Eq612);
                    assert!((a - num).abs() < 1e-12, "{x:?},{y:?},{tau}: {a} vs {num}");
                    let b = m.correlation(x, y, -tau, LagConvention::Eq71);
                    assert!((b - num).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn thesis_closed_forms_hold() {
        let m = model();
        let w = m.omega_c_rad_s();
        for tau in [-0.4, 0.0, 0.1, 0.77] {
            let r = |x, y| m.correlation(x, y, tau, LagConvention::Eq612);
            // Eq. 6.13 as corrected in docs/methods.md §4. Tolerance: rounding of O(1) values.
            let fve = -(0.3 * 0.07 / 2.0) * (w * tau).sin();
            let fs = 2.5 * 1.2 + (0.3 * 0.4 / 2.0) * (w * tau).cos();
            let sve = -(0.4 * 0.07 / 2.0) * (w * tau).sin();
            assert!((r(M::Friction, M::VelocityError) - fve).abs() < 1e-14);
            assert!((r(M::Friction, M::Optical) - fs).abs() < 1e-14);
            assert!((r(M::Optical, M::VelocityError) - sve).abs() < 1e-14);
            // docs/methods.md §4: the printed integrand v_e(t) s(t+τ) gives +(a_v a_s/2) sin.
            let vs = (0.07 * 0.4 / 2.0) * (w * tau).sin();
            assert!((r(M::VelocityError, M::Optical) - vs).abs() < 1e-14);
        }
    }

    #[test]
    fn cross_spectrum_sign_follows_conj_x_times_y() {
        // Fourier coefficient at +ω_c of x is X1 = (p − jq)/2; the line weight
        // of S_xy at +ω_c must be √(2π) conj(X1) Y1 (unitary convention, docs/methods.md §4).
        let m = model();
        let k = (2.0 * PI).sqrt();
        for x in M::ALL {
            for y in M::ALL {
                let (sx, sy) = (m.signal(x), m.signal(y));
                let x1 = Complex64::new(sx.cos_amp, -sx.sin_amp) / 2.0;
                let y1 = Complex64::new(sy.cos_amp, -sy.sin_amp) / 2.0;
                let want = k * x1.conj() * y1;
                let lines = m.cross_spectrum(x, y);
                let got = lines
                    .iter()
                    .find(|l| l.omega_rad_s > 0.0)
                    .map_or(Complex64::new(0.0, 0.0), |l| l.weight());
                // Same products computed two ways: rounding only.
                assert!((got - want).norm() < 1e-15, "{x:?},{y:?}: {got} vs {want}");
                let dc = lines.iter().find(|l| l.omega_rad_s == 0.0);
                assert_eq!(dc.is_some(), sx.dc * sy.dc != 0.0);
            }
        }
        // S_Fve is +j at +ω_c (the thesis printed −j).
        let l = m.cross_spectrum(M::Friction, M::VelocityError);
        assert!(l[1].omega_rad_s > 0.0 && l[1].weight_im > 0.0);
    }

    #[test]
    fn peaks_follow_each_convention() {
        let m = model();
        let tc = m.tau_c_s();
        let a = m
            .correlation_peak(M::Friction, M::VelocityError, LagConvention::Eq71)
            .unwrap();
        // Eq. 7.1: v_e leads F by τ_c/4, so the peak sits at +τ_c/4.
        assert!((a.tau_phi_s - tc / 4.0).abs() < 1e-12);
        assert!((a.phase_deg - 90.0).abs() < 1e-9);
        assert!((a.y_lags_x_s + tc / 4.0).abs() < 1e-12);
        // The peak really is a maximum of the correlation.
        let r0 = m.correlation(M::Friction, M::VelocityError, a.tau_phi_s, a.convention);
        for d in [-0.01, 0.01] {
            assert!(
                m.correlation(M::Friction, M::VelocityError, a.tau_phi_s + d, a.convention) < r0
            );
        }
        assert!(m
            .correlation_peak(M::Friction, M::Friction, LagConvention::Eq71)
            .is_some_and(|p| p.tau_phi_s == 0.0));
        let flat = SinusoidModel {
            velocity_amp_mm_s: 0.0,
            ..model()
        };
        assert!(flat
            .correlation_peak(M::Friction, M::VelocityError, LagConvention::Eq71)
            .is_none());
        assert!(SinusoidModel {
            f_c_hz: 0.0,
            ..model()
        }
        .validate()
        .is_err());
    }
}
