//! Sensor models, each run at the simulator's internal rate and discretised
//! exactly for inputs held over a step (zero-order hold).
//!
//! - [`HighPass1`]: first-order high-pass `H(s) = tau s / (tau s + 1)`: the
//!   quartz load cell's dissipating charge, and the photodetector's optional
//!   AC coupling.
//! - [`Butterworth2`]: the 400 Hz analog anti-alias low-pass of the load cell
//!   and photodetector, `H(s) = wc^2 / (s^2 + sqrt(2) wc s + wc^2)`,
//!   discretised by ZOH of its state-space form (not bilinear: no
//!   prewarping needed, the analog response is followed exactly for
//!   step-wise inputs).
//! - [`quantize`]: the incremental encoder, which counts whole steps.

use super::stage::zoh2;

/// First-order high-pass `y = u - z`, `tau z' = u - z`, exact for held `u`:
/// `z[k+1] = a z[k] + (1 - a) u[k]`, `a = exp(-dt / tau)`.
#[derive(Debug, Clone)]
pub struct HighPass1 {
    a: f64,
    z: f64,
}

impl HighPass1 {
    /// A high-pass with time constant `tau_s` for steps of `dt_s`, with its
    /// low-pass state `z` set to `z0` (the input level it has "forgotten").
    pub fn new(tau_s: f64, dt_s: f64, z0: f64) -> Self {
        Self {
            a: (-dt_s / tau_s).exp(),
            z: z0,
        }
    }

    /// Output for input `u` held over the coming step, then advances.
    pub fn step(&mut self, u: f64) -> f64 {
        let y = u - self.z;
        self.z = self.a * self.z + (1.0 - self.a) * u;
        y
    }

    /// Frequency response `j w tau / (1 + j w tau)` as (re, im).
    pub fn response(tau_s: f64, omega_rad_s: f64) -> (f64, f64) {
        let wt = omega_rad_s * tau_s;
        let d = 1.0 + wt * wt;
        (wt * wt / d, wt / d)
    }
}

/// Second-order Butterworth low-pass, state `(y, y')`, ZOH-exact.
#[derive(Debug, Clone)]
pub struct Butterworth2 {
    ad: [[f64; 2]; 2],
    bd: [f64; 2],
    x: [f64; 2],
}

impl Butterworth2 {
    /// Cut-off `fc_hz` (-3 dB), step `dt_s`, settled at input level `u0`.
    pub fn new(fc_hz: f64, dt_s: f64, u0: f64) -> Self {
        let w = std::f64::consts::TAU * fc_hz;
        let (ad, bd) = zoh2(
            [[0.0, 1.0], [-w * w, -std::f64::consts::SQRT_2 * w]],
            [0.0, w * w],
            dt_s,
        );
        Self {
            ad,
            bd,
            x: [u0, 0.0],
        }
    }

    /// Current output.
    pub fn output(&self) -> f64 {
        self.x[0]
    }

    /// Advances one step with input `u` held over it.
    pub fn step(&mut self, u: f64) {
        let [y, v] = self.x;
        self.x = [
            self.ad[0][0] * y + self.ad[0][1] * v + self.bd[0] * u,
            self.ad[1][0] * y + self.ad[1][1] * v + self.bd[1] * u,
        ];
    }

    /// Frequency response of the analog filter as (re, im).
    pub fn response(fc_hz: f64, omega_rad_s: f64) -> (f64, f64) {
        let w = std::f64::consts::TAU * fc_hz;
        let (a, b) = (
            w * w - omega_rad_s * omega_rad_s,
            std::f64::consts::SQRT_2 * w * omega_rad_s,
        );
        let d = a * a + b * b;
        (w * w * a / d, -w * w * b / d)
    }
}

/// Incremental encoder reading: the number of whole steps counted,
/// `floor(x / q) q`.
pub fn quantize(x: f64, step: f64) -> f64 {
    (x / step).floor() * step
}

/// Gaussian pulse `exp(-u^2 / (2 sigma^2))`, zero beyond `PULSE_CUTOFF_SIGMAS`.
pub fn gaussian(u: f64, sigma: f64) -> f64 {
    let z = u / sigma;
    if z.abs() > PULSE_CUTOFF_SIGMAS {
        0.0
    } else {
        (-0.5 * z * z).exp()
    }
}

/// Pulses are evaluated within this many sigmas of their centre only; the
/// neglected tail is below `exp(-18) = 1.5e-8` of the peak.
pub const PULSE_CUTOFF_SIGMAS: f64 = 6.0;

/// Gaussian sigma from the full width at half maximum (= width at half
/// prominence of an isolated pulse): `sigma = fwhm / (2 sqrt(2 ln 2))`.
pub fn sigma_from_fwhm(fwhm: f64) -> f64 {
    fwhm / (2.0 * (2.0 * std::f64::consts::LN_2).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A held step through the high-pass decays exactly as exp(-t/tau):
    /// the discretisation is exact, so 1e-12 relative.
    #[test]
    fn high_pass_step_decays_with_its_time_constant() {
        let (tau, dt) = (10.0, 1e-3);
        let mut hp = HighPass1::new(tau, dt, 0.0);
        for k in 0..20_000 {
            let y = hp.step(3.0);
            let expect = 3.0 * (-(k as f64) * dt / tau).exp();
            assert!((y - expect).abs() < 1e-12 * 3.0, "k {k}: {y} vs {expect}");
        }
    }

    /// The low-pass follows the analog filter: a held sinusoid well below
    /// the step rate comes out with the analog gain and phase. At 100 Hz with
    /// 20 kHz steps the hold itself adds a half-step delay (pi f dt = 0.9°) and
    /// sinc droop 4e-4, so the phase is compared after removing the half step
    /// and the gain to 1e-3.
    #[test]
    fn butterworth_matches_analog_response() {
        let (fc, dt, f) = (400.0, 5e-5, 100.0);
        let w = std::f64::consts::TAU * f;
        let mut lp = Butterworth2::new(fc, dt, 0.0);
        let n = 40_000;
        let (mut c, mut s) = (0.0, 0.0);
        for k in 0..n {
            let t = k as f64 * dt;
            let y = lp.output();
            if k >= n / 2 {
                c += y * (w * t).cos();
                s += y * (w * t).sin();
            }
            lp.step((w * (t + dt / 2.0)).sin());
        }
        let m = (n / 2) as f64;
        let (re, im) = (2.0 * s / m, 2.0 * c / m);
        let (hr, hi) = Butterworth2::response(fc, w);
        let gain = (re * re + im * im).sqrt() / (hr * hr + hi * hi).sqrt();
        let dphase = im.atan2(re) - hi.atan2(hr);
        assert!((gain - 1.0).abs() < 1e-3, "gain ratio {gain}");
        assert!(dphase.abs() < 1e-3, "phase error {dphase} rad");
        // -3 dB at the cut-off.
        let (hr, hi) = Butterworth2::response(fc, std::f64::consts::TAU * fc);
        assert!(((hr * hr + hi * hi).sqrt() - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
    }

    #[test]
    fn encoder_counts_whole_steps_and_fwhm_converts() {
        assert_eq!(quantize(0.00034, 1e-4) / 1e-4, 3.0);
        assert_eq!(quantize(-0.00001, 1e-4) / 1e-4, -1.0);
        let s = sigma_from_fwhm(1.0);
        assert!((gaussian(0.5, s) - 0.5).abs() < 1e-12);
    }
}
