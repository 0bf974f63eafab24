//! The stage as a PD position loop (thesis §6.1, Eqs. 6.1–6.6, checked in
//! docs/methods.md §3), the numerical differentiators of Fig. 28 (docs/methods.md §2), and the
//! velocity response to a Gaussian friction pulse train (Eq. 6.29 corrected
//! in docs/methods.md §7).
//!
//! Units are SI inside this module: mass in kg, position in m, force in N.
//! With `k = K K_P` (N/m, a stiffness) and `c = K K_D` (N·s/m, a damping):
//!
//! ```text
//! G_xr(s) = (k + c s) / (m s² + c s + k)        reference → position
//! G_xf(s) = 1 / (m s² + c s + k)               friction → position, m/N
//! G_vf(s) = s / (m s² + c s + k)               friction → velocity, (m/s)/N
//! ω_n = √(k/m),  ζ = c / (2√(m k)),  zero of G_xr at k/c = ω_n / (2ζ)
//! ```
//!
//! Friction enters with a `+` sign (docs/methods.md §3). The loop is type 2: a ramp
//! reference is tracked with no steady error and constant friction leaves a
//! position offset `F_c / k` but no velocity error.

use std::f64::consts::PI;

use rustfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::model::pulse_train::GaussianTrain;

fn positive(name: &str, unit: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::setting(
            name,
            format!("must be a positive number of {unit}, got {v}"),
        ))
    }
}

/// A mass under PD position control.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PdLoop {
    /// Moving mass `m`, kg.
    pub mass_kg: f64,
    /// Loop stiffness `K K_P`, N/m.
    pub stiffness_n_per_m: f64,
    /// Loop damping `K K_D`, N·s/m.
    pub damping_n_s_per_m: f64,
}

/// Peaks and corners of the three loop responses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LoopFeatures {
    /// Natural frequency `ω_n = √(K K_P / m)`, rad/s.
    pub omega_n_rad_s: f64,
    /// Natural frequency `f_n = ω_n / 2π`, Hz.
    pub f_n_hz: f64,
    /// Damping ratio `ζ = K K_D / (2√(m K K_P))`.
    pub damping_ratio: f64,
    /// Zero of `G_xr` at `K_P / K_D = ω_n / (2ζ)`, rad/s.
    pub g_xr_zero_rad_s: f64,
    /// Peak of `|G_xr|` at `ω_n √(√(1+8ζ²) − 1) / (2ζ)`, rad/s (docs/methods.md §3).
    pub g_xr_peak_rad_s: f64,
    /// `|G_xr|` at its peak (always > 1).
    pub g_xr_peak_gain: f64,
    /// `|G_xr| > 1` for all `0 < ω < √2 ω_n`: that upper edge, rad/s.
    pub g_xr_above_unity_until_rad_s: f64,
    /// Peak of `|G_xf|` at `ω_n √(1 − 2ζ²)`, rad/s, when `ζ < 1/√2`.
    pub g_xf_peak_rad_s: Option<f64>,
    /// `|G_xf|` at its peak, m/N (`1/k` when there is no resonant peak, at ω = 0).
    pub g_xf_peak_m_per_n: f64,
    /// Peak of `|G_vf|`, exactly at `ω_n`, rad/s (docs/methods.md §3).
    pub g_vf_peak_rad_s: f64,
    /// `|G_vf|` at its peak `= 1 / (K K_D)`, (m/s)/N.
    pub g_vf_peak_m_s_per_n: f64,
}

/// One frequency of the Bode table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BodeRow {
    /// Frequency, Hz.
    pub f_hz: f64,
    /// Angular frequency, rad/s.
    pub omega_rad_s: f64,
    /// `|G_xr|`, dB.
    pub g_xr_db: f64,
    /// `arg G_xr`, degrees.
    pub g_xr_phase_deg: f64,
    /// `|G_xf|`, dB re 1 m/N.
    pub g_xf_db: f64,
    /// `arg G_xf`, degrees.
    pub g_xf_phase_deg: f64,
    /// `|G_vf|`, dB re 1 (m/s)/N.
    pub g_vf_db: f64,
    /// `arg G_vf`, degrees.
    pub g_vf_phase_deg: f64,
}

/// A log-spaced frequency axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrequencyAxis {
    /// First frequency, Hz.
    pub f_min_hz: f64,
    /// Last frequency, Hz.
    pub f_max_hz: f64,
    /// Number of points (log-spaced, both ends included).
    pub points: usize,
}

impl Default for FrequencyAxis {
    /// 0.01 Hz to 1 kHz, 500 points.
    fn default() -> Self {
        Self {
            f_min_hz: 0.01,
            f_max_hz: 1000.0,
            points: 500,
        }
    }
}

impl FrequencyAxis {
    /// The frequencies, Hz.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] unless `0 < f_min < f_max` and `points ≥ 2`.
    pub fn frequencies_hz(&self) -> Result<Vec<f64>> {
        positive("f_min", "Hz", self.f_min_hz)?;
        positive("f_max", "Hz", self.f_max_hz)?;
        if self.f_max_hz <= self.f_min_hz {
            return Err(Error::setting(
                "f_max",
                format!(
                    "must exceed f_min ({} Hz), got {} Hz",
                    self.f_min_hz, self.f_max_hz
                ),
            ));
        }
        if !(2..=1_000_000).contains(&self.points) {
            return Err(Error::setting(
                "points",
                format!("must be 2 to 1000000, got {}", self.points),
            ));
        }
        let (a, b) = (self.f_min_hz.ln(), self.f_max_hz.ln());
        let n = self.points - 1;
        Ok((0..=n)
            .map(|i| (a + (b - a) * i as f64 / n as f64).exp())
            .collect())
    }
}

fn db(z: Complex64) -> f64 {
    20.0 * z.norm().log10()
}

fn deg(z: Complex64) -> f64 {
    z.arg().to_degrees()
}

impl PdLoop {
    /// From the gains of Eq. 6.1: `K` (N/A), `K_P` (A/m), `K_D` (A·s/m).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a value that is not positive and finite.
    pub fn from_gains(
        mass_kg: f64,
        motor_constant_n_per_a: f64,
        kp_a_per_m: f64,
        kd_a_s_per_m: f64,
    ) -> Result<Self> {
        positive("mass", "kg", mass_kg)?;
        positive("motor constant", "N/A", motor_constant_n_per_a)?;
        positive("kp", "A/m", kp_a_per_m)?;
        positive("kd", "A·s/m", kd_a_s_per_m)?;
        Self::from_products(
            mass_kg,
            motor_constant_n_per_a * kp_a_per_m,
            motor_constant_n_per_a * kd_a_s_per_m,
        )
    }

    /// From the loop stiffness `K K_P` (N/m) and damping `K K_D` (N·s/m).
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a value that is not positive and finite.
    pub fn from_products(
        mass_kg: f64,
        stiffness_n_per_m: f64,
        damping_n_s_per_m: f64,
    ) -> Result<Self> {
        positive("mass", "kg", mass_kg)?;
        positive("loop stiffness K*KP", "N/m", stiffness_n_per_m)?;
        positive("loop damping K*KD", "N·s/m", damping_n_s_per_m)?;
        Ok(Self {
            mass_kg,
            stiffness_n_per_m,
            damping_n_s_per_m,
        })
    }

    /// From the natural frequency `f_n` (Hz) and damping ratio `ζ`:
    /// `K K_P = m ω_n²`, `K K_D = 2 ζ m ω_n`.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a value that is not positive and finite.
    pub fn from_natural(
        mass_kg: f64,
        natural_frequency_hz: f64,
        damping_ratio: f64,
    ) -> Result<Self> {
        positive("mass", "kg", mass_kg)?;
        positive("natural frequency", "Hz", natural_frequency_hz)?;
        positive("damping ratio", "(dimensionless)", damping_ratio)?;
        let wn = 2.0 * PI * natural_frequency_hz;
        Self::from_products(
            mass_kg,
            mass_kg * wn * wn,
            2.0 * damping_ratio * mass_kg * wn,
        )
    }

    /// `ω_n = √(K K_P / m)`, rad/s.
    pub fn omega_n_rad_s(&self) -> f64 {
        (self.stiffness_n_per_m / self.mass_kg).sqrt()
    }

    /// `ζ = K K_D / (2√(m K K_P))`.
    pub fn damping_ratio(&self) -> f64 {
        self.damping_n_s_per_m / (2.0 * (self.mass_kg * self.stiffness_n_per_m).sqrt())
    }

    fn denominator(&self, omega_rad_s: f64) -> Complex64 {
        let s = Complex64::new(0.0, omega_rad_s);
        s * s * self.mass_kg + s * self.damping_n_s_per_m + self.stiffness_n_per_m
    }

    /// `G_xr(jω)` (Eq. 6.3), dimensionless.
    pub fn g_xr(&self, omega_rad_s: f64) -> Complex64 {
        Complex64::new(self.stiffness_n_per_m, self.damping_n_s_per_m * omega_rad_s)
            / self.denominator(omega_rad_s)
    }

    /// `G_xf(jω)` (Eq. 6.5), m/N.
    pub fn g_xf(&self, omega_rad_s: f64) -> Complex64 {
        Complex64::new(1.0, 0.0) / self.denominator(omega_rad_s)
    }

    /// `G_vf(jω)` (Eq. 6.6), (m/s)/N.
    pub fn g_vf(&self, omega_rad_s: f64) -> Complex64 {
        Complex64::new(0.0, omega_rad_s) / self.denominator(omega_rad_s)
    }

    /// Natural frequency, damping, zero and the peaks of the three responses.
    pub fn features(&self) -> LoopFeatures {
        let wn = self.omega_n_rad_s();
        let z = self.damping_ratio();
        let g_xr_peak = wn * ((1.0 + 8.0 * z * z).sqrt() - 1.0).sqrt() / (2.0 * z);
        let g_xf_peak =
            (z < std::f64::consts::FRAC_1_SQRT_2).then(|| wn * (1.0 - 2.0 * z * z).sqrt());
        LoopFeatures {
            omega_n_rad_s: wn,
            f_n_hz: wn / (2.0 * PI),
            damping_ratio: z,
            g_xr_zero_rad_s: self.stiffness_n_per_m / self.damping_n_s_per_m,
            g_xr_peak_rad_s: g_xr_peak,
            g_xr_peak_gain: self.g_xr(g_xr_peak).norm(),
            g_xr_above_unity_until_rad_s: 2f64.sqrt() * wn,
            g_xf_peak_rad_s: g_xf_peak,
            g_xf_peak_m_per_n: self.g_xf(g_xf_peak.unwrap_or(0.0)).norm(),
            g_vf_peak_rad_s: wn,
            g_vf_peak_m_s_per_n: 1.0 / self.damping_n_s_per_m,
        }
    }

    /// Magnitude (dB) and phase (degrees, unwrapped along the axis) of the
    /// three responses, as `scipy.signal.bode` reports them.
    ///
    /// # Errors
    /// As [`FrequencyAxis::frequencies_hz`].
    pub fn bode(&self, axis: &FrequencyAxis) -> Result<Vec<BodeRow>> {
        let mut rows: Vec<BodeRow> = axis
            .frequencies_hz()?
            .into_iter()
            .map(|f| {
                let w = 2.0 * PI * f;
                let (xr, xf, vf) = (self.g_xr(w), self.g_xf(w), self.g_vf(w));
                BodeRow {
                    f_hz: f,
                    omega_rad_s: w,
                    g_xr_db: db(xr),
                    g_xr_phase_deg: deg(xr),
                    g_xf_db: db(xf),
                    g_xf_phase_deg: deg(xf),
                    g_vf_db: db(vf),
                    g_vf_phase_deg: deg(vf),
                }
            })
            .collect();
        for i in 1..rows.len() {
            let prev = rows[i - 1];
            let r = &mut rows[i];
            r.g_xr_phase_deg = unwrap_deg(prev.g_xr_phase_deg, r.g_xr_phase_deg);
            r.g_xf_phase_deg = unwrap_deg(prev.g_xf_phase_deg, r.g_xf_phase_deg);
            r.g_vf_phase_deg = unwrap_deg(prev.g_vf_phase_deg, r.g_vf_phase_deg);
        }
        Ok(rows)
    }
}

fn unwrap_deg(prev: f64, cur: f64) -> f64 {
    cur - 360.0 * ((cur - prev) / 360.0).round()
}

/// Frequency responses of three numerical differentiators relative to the
/// ideal `jω`, at one frequency (thesis Fig. 28, docs/methods.md §2).
///
/// ```text
/// centred (Eq. 4.1, offline)  H = j sin(ωT)/T            gain ratio sin(ωT)/(ωT), phase +90°
/// forward                     H = (e^{jωT} − 1)/T        gain ratio sinc(ωT/2),   phase 90° + 180° f/F_s
/// causal centred              H = (1 − e^{−2jωT})/(2T)   gain ratio sin(ωT)/(ωT), phase 90° − 360° f/F_s
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DifferenceRow {
    /// Frequency, Hz.
    pub f_hz: f64,
    /// `|H_centred| / ω`.
    pub centred_gain_ratio: f64,
    /// `arg H_centred`, degrees.
    pub centred_phase_deg: f64,
    /// `|H_forward| / ω`.
    pub forward_gain_ratio: f64,
    /// `arg H_forward`, degrees.
    pub forward_phase_deg: f64,
    /// `|H_causal| / ω`.
    pub causal_centred_gain_ratio: f64,
    /// `arg H_causal`, degrees (unwrapped along the axis).
    pub causal_centred_phase_deg: f64,
}

/// The differentiator responses of [`DifferenceRow`] at `points` frequencies
/// spaced evenly over `(0, F_s/2]`.
///
/// # Errors
/// [`Error::InvalidSetting`] when `fs_hz` is not positive or `points` is 0.
pub fn difference_responses(fs_hz: f64, points: usize) -> Result<Vec<DifferenceRow>> {
    positive("sampling rate", "Hz", fs_hz)?;
    if !(1..=1_000_000).contains(&points) {
        return Err(Error::setting(
            "points",
            format!("must be 1 to 1000000, got {points}"),
        ));
    }
    let t = 1.0 / fs_hz;
    let mut rows = Vec::with_capacity(points);
    let mut prev_causal = 90.0;
    for i in 1..=points {
        let f = 0.5 * fs_hz * i as f64 / points as f64;
        let w = 2.0 * PI * f;
        let wt = w * t;
        let centred = Complex64::new(0.0, wt.sin() / t);
        let forward = (Complex64::from_polar(1.0, wt) - 1.0) / t;
        let causal = (1.0 - Complex64::from_polar(1.0, -2.0 * wt)) / (2.0 * t);
        // Where a gain is zero (Nyquist) its phase is the limit from below.
        let centred_phase = 90.0;
        let forward_phase = 90.0 + 180.0 * f / fs_hz;
        let causal_phase = if causal.norm() > 1e-12 / t {
            unwrap_deg(prev_causal, deg(causal))
        } else {
            90.0 - 360.0 * f / fs_hz
        };
        prev_causal = causal_phase;
        rows.push(DifferenceRow {
            f_hz: f,
            centred_gain_ratio: centred.norm() / w,
            centred_phase_deg: centred_phase,
            forward_gain_ratio: forward.norm() / w,
            forward_phase_deg: if forward.norm() > 0.0 {
                unwrap_deg(forward_phase, deg(forward))
            } else {
                forward_phase
            },
            causal_centred_gain_ratio: causal.norm() / w,
            causal_centred_phase_deg: causal_phase,
        });
    }
    Ok(rows)
}

/// Settings of [`velocity_response`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct VelocityResponseSettings {
    /// Highest harmonic kept; `None` keeps every `C_n` above 1e-16 `C_0`.
    pub harmonics: Option<usize>,
    /// Samples over the one period returned.
    pub points_per_period: usize,
}

impl Default for VelocityResponseSettings {
    /// Automatic order, 1000 points per period.
    fn default() -> Self {
        Self {
            harmonics: None,
            points_per_period: 1000,
        }
    }
}

/// One harmonic of the friction train and of the velocity it causes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HarmonicRow {
    /// Harmonic number n.
    pub n: usize,
    /// `n f_c`, Hz.
    pub f_hz: f64,
    /// `Re C_n`, N.
    pub c_re_n: f64,
    /// `Im C_n`, N.
    pub c_im_n: f64,
    /// `|G_vf(j n ω_c)|`, (mm/s)/N.
    pub g_vf_mm_s_per_n: f64,
    /// `arg G_vf(j n ω_c)`, degrees.
    pub g_vf_phase_deg: f64,
    /// `Re D_n`, mm/s.
    pub d_re_mm_s: f64,
    /// `Im D_n`, mm/s.
    pub d_im_mm_s: f64,
    /// `|D_n|`, mm/s.
    pub d_abs_mm_s: f64,
}

/// One period of the stage's velocity under a Gaussian friction pulse train.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VelocityResponse {
    /// Ball-pass frequency, Hz.
    pub f_c_hz: f64,
    /// Harmonics 0..=N with `D_n = C_n G_vf(j n ω_c)` (docs/methods.md §7).
    pub harmonics: Vec<HarmonicRow>,
    /// Sample times over one period `[0, τ_c)`, s.
    pub time_s: Vec<f64>,
    /// The friction train, N.
    pub friction_n: Vec<f64>,
    /// Velocity deviation from the tracking velocity, mm/s (complex `D_n`).
    pub velocity_mm_s: Vec<f64>,
    /// Position deviation, µm (`X_n = C_n G_xf(j n ω_c)`, including the
    /// static offset `C_0 / (K K_P)`).
    pub position_um: Vec<f64>,
    /// The thesis' printed form `D_n = C_n |G_vf|` (magnitude only), mm/s,
    /// for comparison.
    pub velocity_magnitude_only_mm_s: Vec<f64>,
    /// Peak-to-peak of `velocity_mm_s`, mm/s.
    pub velocity_peak_to_peak_mm_s: f64,
    /// `max |v_magnitude_only − v| / max |v|`: how wrong the printed form is.
    pub magnitude_only_error_of_peak: f64,
}

/// Velocity (and position) of the loop over one period when the friction is
/// the Gaussian train `friction` (thesis Eq. 6.29 as corrected in docs/methods.md §7):
///
/// ```text
/// v(t) = Σ_n D_n exp(j n ω_c t),   D_n = C_n G_vf(j n ω_c),   D_{−n} = D_n*,   D_0 = 0
/// ```
///
/// # Errors
/// [`Error::InvalidSetting`] when `points_per_period < 2`.
pub fn velocity_response(
    stage: &PdLoop,
    friction: &GaussianTrain,
    settings: &VelocityResponseSettings,
) -> Result<VelocityResponse> {
    if !(2..=10_000_000).contains(&settings.points_per_period) {
        return Err(Error::setting(
            "points per period",
            format!("must be 2 to 10000000, got {}", settings.points_per_period),
        ));
    }
    let order = settings
        .harmonics
        .unwrap_or_else(|| friction.order_for(1e-16))
        .min(100_000);
    let tc = friction.tau_c_s;
    let wc = 2.0 * PI / tc;
    let mut harmonics = Vec::with_capacity(order + 1);
    let mut d = Vec::with_capacity(order + 1);
    let mut d_mag = Vec::with_capacity(order + 1);
    let mut x = Vec::with_capacity(order + 1);
    for n in 0..=order {
        let c = friction.coefficient(n as i64);
        let g = stage.g_vf(n as f64 * wc) * 1e3; // (mm/s)/N
        let dn = c * g;
        d.push(dn);
        d_mag.push(c * g.norm());
        x.push(c * stage.g_xf(n as f64 * wc) * 1e6); // µm
        harmonics.push(HarmonicRow {
            n,
            f_hz: n as f64 / tc,
            c_re_n: c.re,
            c_im_n: c.im,
            g_vf_mm_s_per_n: g.norm(),
            g_vf_phase_deg: if n == 0 { 90.0 } else { deg(g) },
            d_re_mm_s: dn.re,
            d_im_mm_s: dn.im,
            d_abs_mm_s: dn.norm(),
        });
    }
    let m = settings.points_per_period;
    let synth = |coef: &[Complex64], t: f64| -> f64 {
        let e1 = Complex64::from_polar(1.0, wc * t);
        let mut e = e1;
        let mut sum = coef[0].re;
        for c in &coef[1..] {
            sum += 2.0 * (c * e).re;
            e *= e1;
        }
        sum
    };
    let time_s: Vec<f64> = (0..m).map(|i| tc * i as f64 / m as f64).collect();
    let velocity_mm_s: Vec<f64> = time_s.iter().map(|&t| synth(&d, t)).collect();
    let velocity_magnitude_only_mm_s: Vec<f64> = time_s.iter().map(|&t| synth(&d_mag, t)).collect();
    let position_um = time_s.iter().map(|&t| synth(&x, t)).collect();
    let friction_n = time_s.iter().map(|&t| friction.value(t)).collect();
    let (lo, hi) = velocity_mm_s
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let peak = velocity_mm_s.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let err = velocity_mm_s
        .iter()
        .zip(&velocity_magnitude_only_mm_s)
        .fold(0.0f64, |a, (v, w)| a.max((v - w).abs()));
    Ok(VelocityResponse {
        f_c_hz: 1.0 / tc,
        harmonics,
        time_s,
        friction_n,
        velocity_mm_s,
        position_um,
        velocity_magnitude_only_mm_s,
        velocity_peak_to_peak_mm_s: hi - lo,
        magnitude_only_error_of_peak: if peak > 0.0 { err / peak } else { 0.0 },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gains_and_natural_parameters_agree() {
        let a = PdLoop::from_gains(12.0, 40.0, 3.0e4, 60.0).unwrap();
        let f = a.features();
        let b = PdLoop::from_natural(12.0, f.f_n_hz, f.damping_ratio).unwrap();
        // Round trip through √ and products: a few ulps.
        assert!((b.stiffness_n_per_m / a.stiffness_n_per_m - 1.0).abs() < 1e-12);
        assert!((b.damping_n_s_per_m / a.damping_n_s_per_m - 1.0).abs() < 1e-12);
        assert!((f.omega_n_rad_s - (40.0 * 3.0e4 / 12.0f64).sqrt()).abs() < 1e-9);
        // docs/methods.md §3: zero of G_xr at K_P/K_D = ω_n/(2ζ).
        assert!((f.g_xr_zero_rad_s - 3.0e4 / 60.0).abs() < 1e-9);
        assert!((f.g_xr_zero_rad_s - f.omega_n_rad_s / (2.0 * f.damping_ratio)).abs() < 1e-9);
        assert!(PdLoop::from_gains(0.0, 1.0, 1.0, 1.0).is_err());
        assert!(PdLoop::from_natural(1.0, 10.0, -0.1).is_err());
    }

    /// Largest |G| on a fine grid followed by golden-section refinement.
    fn numeric_peak(g: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
        let n = 20000;
        let h = (hi - lo) / n as f64;
        let best = (0..=n)
            .map(|i| lo + i as f64 * h)
            .max_by(|a, b| g(*a).total_cmp(&g(*b)))
            .unwrap();
        let (mut a, mut b) = ((best - h).max(lo), best + h);
        let r = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..100 {
            let (m1, m2) = (b - r * (b - a), a + r * (b - a));
            if g(m1) > g(m2) {
                b = m2;
            } else {
                a = m1;
            }
        }
        0.5 * (a + b)
    }

    #[test]
    fn peaks_are_where_errata_says() {
        for zeta in [0.05, 0.3, 0.7, 1.5] {
            let p = PdLoop::from_natural(2.0, 10.0, zeta).unwrap();
            let f = p.features();
            let wn = f.omega_n_rad_s;
            let xr = numeric_peak(|w| p.g_xr(w).norm(), 1e-3, 3.0 * wn);
            let vf = numeric_peak(|w| p.g_vf(w).norm(), 1e-3, 3.0 * wn);
            // A maximum is flat: locating it numerically is good to ~√ε of ω.
            assert!(
                (xr / f.g_xr_peak_rad_s - 1.0).abs() < 1e-6,
                "ζ={zeta}: {xr}"
            );
            assert!((vf / wn - 1.0).abs() < 1e-6);
            assert!(
                (p.g_vf(wn).norm() - f.g_vf_peak_m_s_per_n).abs() < 1e-12 * f.g_vf_peak_m_s_per_n
            );
            assert!(f.g_xr_peak_gain > 1.0);
            // |G_xr| > 1 below √2 ω_n, < 1 above, and G_xr(0) = 1.
            assert!(p.g_xr(0.9 * f.g_xr_above_unity_until_rad_s).norm() > 1.0);
            assert!(p.g_xr(1.1 * f.g_xr_above_unity_until_rad_s).norm() < 1.0);
            assert!((p.g_xr(0.0).norm() - 1.0).abs() < 1e-15);
            match f.g_xf_peak_rad_s {
                Some(w) => {
                    let num = numeric_peak(|w| p.g_xf(w).norm(), 1e-3, 3.0 * wn);
                    assert!((num / w - 1.0).abs() < 1e-6);
                }
                None => assert!(zeta >= std::f64::consts::FRAC_1_SQRT_2),
            }
        }
    }

    #[test]
    fn bode_slopes_and_phases() {
        let p = PdLoop::from_natural(1.0, 10.0, 0.2).unwrap();
        let rows = p
            .bode(&FrequencyAxis {
                f_min_hz: 0.001,
                f_max_hz: 1.0e5,
                points: 801,
            })
            .unwrap();
        let (first, last) = (rows[0], rows[rows.len() - 1]);
        let prev = rows[rows.len() - 101]; // one decade below the last
                                           // Asymptotes four decades from ω_n hold to ~1e-8 dB/dec scale; 0.01 is ample.
        assert!((last.g_xr_db - prev.g_xr_db + 20.0).abs() < 0.01);
        assert!((last.g_xf_db - prev.g_xf_db + 40.0).abs() < 0.01);
        assert!((last.g_vf_db - prev.g_vf_db + 20.0).abs() < 0.01);
        assert!((rows[100].g_vf_db - first.g_vf_db - 20.0).abs() < 0.01);
        assert!(first.g_xr_db.abs() < 1e-3);
        assert!((last.g_xf_phase_deg + 180.0).abs() < 0.1);
        assert!(
            (first.g_vf_phase_deg - 90.0).abs() < 0.1 && (last.g_vf_phase_deg + 90.0).abs() < 0.1
        );
        assert!(p
            .bode(&FrequencyAxis {
                f_min_hz: 1.0,
                f_max_hz: 0.5,
                points: 10
            })
            .is_err());
    }

    #[test]
    fn difference_responses_match_errata_section_2() {
        let rows = difference_responses(1000.0, 500).unwrap();
        let at = |f: f64| rows.iter().find(|r| (r.f_hz - f).abs() < 1e-9).unwrap();
        let r = at(20.0);
        // docs/methods.md §2 prints 0.99737 (5 decimals) and 93.6° (1 decimal).
        assert!((r.centred_gain_ratio - 0.99737).abs() < 5e-6);
        assert!((r.centred_phase_deg - 90.0).abs() < 1e-12);
        assert!((r.forward_phase_deg - 93.6).abs() < 0.05);
        assert!((r.causal_centred_phase_deg - (90.0 - 7.2)).abs() < 1e-9);
        // 0.6366 = 2/π at F_s/4, 0 at Nyquist; forward phase 180° there.
        assert!((at(250.0).centred_gain_ratio - 2.0 / PI).abs() < 1e-12);
        let ny = at(500.0);
        assert!(ny.centred_gain_ratio.abs() < 1e-12);
        assert!((ny.forward_phase_deg - 180.0).abs() < 1e-9);
        for r in &rows {
            let wt = 2.0 * PI * r.f_hz / 1000.0;
            // Closed forms of docs/methods.md §2; rounding only.
            assert!((r.forward_gain_ratio - (wt / 2.0).sin() / (wt / 2.0)).abs() < 1e-12);
            assert!((r.forward_phase_deg - (90.0 + 180.0 * r.f_hz / 1000.0)).abs() < 1e-9);
            assert!((r.causal_centred_phase_deg - (90.0 - 360.0 * r.f_hz / 1000.0)).abs() < 1e-9);
        }
        assert!(difference_responses(0.0, 10).is_err());
    }

    /// Periodic steady state of m ẍ + c ẋ + k x = f(t) by RK4 shooting:
    /// integrate one period from zero state and from the two unit states, then
    /// solve (I − Φ) z0 = z_forced(τ_c) for the periodic initial state.
    fn rk4_periodic_velocity(
        p: &PdLoop,
        f: &GaussianTrain,
        steps: usize,
        out_at: &[usize],
    ) -> Vec<f64> {
        let (m, c, k) = (p.mass_kg, p.damping_n_s_per_m, p.stiffness_n_per_m);
        let h = f.tau_c_s / steps as f64;
        let run = |z0: [f64; 2], forced: bool, record: bool| -> ([f64; 2], Vec<f64>) {
            let deriv = |t: f64, z: [f64; 2]| -> [f64; 2] {
                let force = if forced { f.value(t) } else { 0.0 };
                [z[1], (force - c * z[1] - k * z[0]) / m]
            };
            let mut z = z0;
            let mut rec = Vec::new();
            let mut next = 0;
            for i in 0..=steps {
                if record && next < out_at.len() && out_at[next] == i {
                    rec.push(z[1]);
                    next += 1;
                }
                if i == steps {
                    break;
                }
                let t = i as f64 * h;
                let k1 = deriv(t, z);
                let k2 = deriv(
                    t + h / 2.0,
                    [z[0] + h / 2.0 * k1[0], z[1] + h / 2.0 * k1[1]],
                );
                let k3 = deriv(
                    t + h / 2.0,
                    [z[0] + h / 2.0 * k2[0], z[1] + h / 2.0 * k2[1]],
                );
                let k4 = deriv(t + h, [z[0] + h * k3[0], z[1] + h * k3[1]]);
                for j in 0..2 {
                    z[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
                }
            }
            (z, rec)
        };
        let (zf, _) = run([0.0, 0.0], true, false);
        let (p1, _) = run([1.0, 0.0], false, false);
        let (p2, _) = run([0.0, 1.0], false, false);
        // (I − Φ) z0 = zf with Φ = [p1 p2] as columns.
        let a = [[1.0 - p1[0], -p2[0]], [-p1[1], 1.0 - p2[1]]];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let z0 = [
            (zf[0] * a[1][1] - a[0][1] * zf[1]) / det,
            (a[0][0] * zf[1] - a[1][0] * zf[0]) / det,
        ];
        run(z0, true, true).1
    }

    #[test]
    fn velocity_response_matches_time_domain_simulation() {
        // docs/methods.md §7 test case: ω_n = 15 ω_c, ζ = 0.05, r = 0.155.
        let tc = 0.90123;
        let stage = PdLoop::from_natural(3.0, 15.0 / tc, 0.05).unwrap();
        let friction = GaussianTrain::new(tc, 0.155, 0.8, 2.0, 0.3 * tc).unwrap();
        let resp = velocity_response(
            &stage,
            &friction,
            &VelocityResponseSettings {
                harmonics: None,
                points_per_period: 100,
            },
        )
        .unwrap();
        let steps = 40_000;
        let idx: Vec<usize> = (0..100).map(|i| i * steps / 100).collect();
        let ode = rk4_periodic_velocity(&stage, &friction, steps, &idx);
        let peak = resp
            .velocity_mm_s
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        let err = resp
            .velocity_mm_s
            .iter()
            .zip(&ode)
            .fold(0.0f64, |a, (v, o)| a.max((v - o * 1e3).abs()));
        // RK4 with h ω_n = 15·2π/40000 ≈ 2.4e-3 has global error ~ (h ω_n)^4 ≈ 3e-11
        // relative; the series is truncated below 1e-16. docs/methods.md §7 reports 2e-10.
        assert!(err / peak < 2e-10, "relative error {}", err / peak);
        // The printed magnitude-only form is badly wrong (docs/methods.md §7: 162 % of
        // peak for a pulse at t0 = 0; here it is off by more than the peak).
        assert!(resp.magnitude_only_error_of_peak > 1.0);
        assert_eq!(resp.harmonics[0].d_abs_mm_s, 0.0);
    }

    #[test]
    fn magnitude_only_error_is_162_percent_in_errata_case() {
        let tc = 1.0;
        let stage = PdLoop::from_natural(1.0, 15.0, 0.05).unwrap();
        let friction = GaussianTrain::new(tc, 0.155, 1.0, 0.0, 0.0).unwrap();
        let resp =
            velocity_response(&stage, &friction, &VelocityResponseSettings::default()).unwrap();
        // docs/methods.md §7 prints 162 % (three digits: ±0.5 %).
        assert!(
            (resp.magnitude_only_error_of_peak - 1.62).abs() < 0.005,
            "{}",
            resp.magnitude_only_error_of_peak
        );
    }
}
