//! Pulse-train models of the optical sensor and of friction (thesis §6.3),
//! with the Fourier coefficients as corrected in docs/methods.md §5–6.
//!
//! # Rectangular train (Eqs. 6.18–6.22, docs/methods.md §5)
//!
//! One period is `S` on `[0, τ_c − τ_p)` and `S + P` on `[τ_c − τ_p, τ_c)`;
//! with `r = τ_p / τ_c`:
//!
//! ```text
//! a_0 = 2 P r          a_n = (P / nπ) sin(2π n r)          b_n = (P / nπ) [cos(2π n r) − 1]
//! s_r(t) = S + P r + Σ_{n=1}^{N} (2P / nπ) sin(nπ r) cos(nπ (2t + τ_p) / τ_c)
//! ```
//!
//! # Gaussian train (Eqs. 6.23–6.28, docs/methods.md §6)
//!
//! Pulses `g(t) = P exp(−(t − kτ_c − t_0)² / (2σ²))` repeated over all k, with
//! `r = σ / τ_c` (the thesis writes σ as τ_p in Eq. 6.23). Exactly, by Poisson
//! summation:
//!
//! ```text
//! s_g(t) = S + Σ_n C_n exp(j 2π n t / τ_c),    C_n = √(2π) P r exp(−2π² n² r²) exp(−j 2π n t_0 / τ_c)
//! ```
//!
//! The width at half maximum of one pulse is `τ_p = 2√(2 ln 2) σ`
//! (CONVENTIONS.md); [`sigma_ratio_from_fwhm_ratio`] converts.

use std::f64::consts::PI;

use rustfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// `2√(2 ln 2)`: full width at half maximum of a Gaussian over its sigma.
pub const FWHM_PER_SIGMA: f64 = 2.354_820_045_030_949_3;

/// Converts a width-at-half-maximum ratio `τ_p / τ_c` to the sigma ratio `σ / τ_c`.
pub fn sigma_ratio_from_fwhm_ratio(fwhm_ratio: f64) -> f64 {
    fwhm_ratio / FWHM_PER_SIGMA
}

fn check_ratio(name: &str, r: f64, max: f64) -> Result<()> {
    if r.is_finite() && r > 0.0 && r < max {
        Ok(())
    } else {
        Err(Error::setting(
            name,
            format!("must be a number in (0, {max}), got {r}"),
        ))
    }
}

fn check_finite(name: &str, v: f64) -> Result<()> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(Error::setting(name, format!("must be finite, got {v}")))
    }
}

fn check_period(tau_c_s: f64) -> Result<()> {
    if tau_c_s.is_finite() && tau_c_s > 0.0 {
        Ok(())
    } else {
        Err(Error::setting(
            "tau_c",
            format!("must be a positive number of s, got {tau_c_s}"),
        ))
    }
}

/// A periodic train of rectangular pulses (Eq. 6.18).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RectangularTrain {
    /// Period `τ_c`, s.
    pub tau_c_s: f64,
    /// Duty ratio `r = τ_p / τ_c`, in (0, 1).
    pub ratio: f64,
    /// Pulse height `P`.
    pub amplitude: f64,
    /// Base level `S`.
    pub dc: f64,
}

/// The real Fourier coefficients of a [`RectangularTrain`] (docs/methods.md §5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RectangularCoefficients {
    /// `a_0 = 2 P r` (the series' constant term is `S + a_0 / 2`).
    pub a0: f64,
    /// `a_n` for n = 1..=N (index 0 holds n = 1).
    pub a: Vec<f64>,
    /// `b_n` for n = 1..=N (index 0 holds n = 1).
    pub b: Vec<f64>,
}

impl RectangularTrain {
    /// Builds and validates a train.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when `τ_c` is not positive, `r` not in (0, 1)
    /// or a level not finite.
    pub fn new(tau_c_s: f64, ratio: f64, amplitude: f64, dc: f64) -> Result<Self> {
        check_period(tau_c_s)?;
        check_ratio("pulse ratio tau_p/tau_c", ratio, 1.0)?;
        check_finite("pulse amplitude", amplitude)?;
        check_finite("DC level", dc)?;
        Ok(Self {
            tau_c_s,
            ratio,
            amplitude,
            dc,
        })
    }

    /// `a_0`, `a_n`, `b_n` for n = 1..=`order` (docs/methods.md §5).
    ///
    /// ```
    /// use ballpass::model::pulse_train::RectangularTrain;
    /// let c = RectangularTrain::new(1.0, 0.155, 1.0, 0.0).unwrap().coefficients(1);
    /// // docs/methods.md §5: a0, a1, b1 = 0.310, 0.26326, −0.13939 at r = 0.155.
    /// assert!((c.a0 - 0.310).abs() < 5e-4);
    /// // docs/methods.md truncates (0.2632679 is printed 0.26326): one unit of the last digit.
    /// assert!((c.a[0] - 0.26326).abs() < 1e-5 && (c.b[0] + 0.13939).abs() < 1e-5);
    /// ```
    pub fn coefficients(&self, order: usize) -> RectangularCoefficients {
        let p = self.amplitude;
        let r = self.ratio;
        let (a, b) = (1..=order)
            .map(|n| {
                let n = n as f64;
                let (s, c) = (2.0 * PI * n * r).sin_cos();
                (p / (n * PI) * s, p / (n * PI) * (c - 1.0))
            })
            .unzip();
        RectangularCoefficients {
            a0: 2.0 * p * r,
            a,
            b,
        }
    }

    /// The exact train at `t_s`: `S + P` inside a pulse, `S` outside, and the
    /// mean `S + P/2` exactly on a jump (where a Fourier series converges).
    pub fn value(&self, t_s: f64) -> f64 {
        let u = (t_s / self.tau_c_s).rem_euclid(1.0);
        let start = 1.0 - self.ratio;
        let eps = 1e-12;
        if (u - start).abs() < eps || u < eps || (1.0 - u) < eps {
            self.dc + 0.5 * self.amplitude
        } else if u > start {
            self.dc + self.amplitude
        } else {
            self.dc
        }
    }

    /// The corrected series (docs/methods.md §5) truncated at order `order`, at `t_s`.
    pub fn partial_sum(&self, t_s: f64, order: usize) -> f64 {
        let r = self.ratio;
        let p = self.amplitude;
        // cos(nθ) by the Chebyshev recurrence, θ = π (2t + τ_p) / τ_c.
        let theta = PI * (2.0 * t_s / self.tau_c_s + r);
        let two_cos = 2.0 * theta.cos();
        let (mut c_prev, mut c_cur) = (1.0, theta.cos());
        let mut sum = 0.0;
        for n in 1..=order {
            let nf = n as f64;
            sum += 2.0 * p / (nf * PI) * (nf * PI * r).sin() * c_cur;
            let c_next = two_cos * c_cur - c_prev;
            c_prev = c_cur;
            c_cur = c_next;
        }
        self.dc + p * r + sum
    }

    /// Gibbs overshoot of the order-`order` series above the pulse top, as a
    /// fraction of the jump `P` (docs/methods.md §5: 10.05 %, 9.10 %, 8.96 % at
    /// N = 20, 200, 2000 for r = 0.155, tending to 8.95 %).
    ///
    /// Found by a grid over the four ripples after the rising edge (where the
    /// largest lobe sits) refined by golden-section search.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when `order` is zero.
    pub fn gibbs_overshoot(&self, order: usize) -> Result<f64> {
        if order == 0 {
            return Err(Error::setting("order", "must be at least 1, got 0"));
        }
        let tc = self.tau_c_s;
        let rise = tc * (1.0 - self.ratio);
        // The first lobe after a jump sits about τ_c / (2N) inside; scan the
        // first few lobes (and the whole pulse when it is shorter).
        let span = (4.0 * tc / order as f64).min(self.ratio * tc);
        let grid = 400;
        let f = |t: f64| self.partial_sum(t, order);
        let h = span / grid as f64;
        let (mut best_t, mut best) = (rise, f64::NEG_INFINITY);
        for i in 0..=grid {
            let t = rise + i as f64 * h;
            let v = f(t);
            if v > best {
                best = v;
                best_t = t;
            }
        }
        // Golden-section refinement in [best_t − h, best_t + h].
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut lo, mut hi) = (best_t - h, best_t + h);
        for _ in 0..80 {
            let m1 = hi - g * (hi - lo);
            let m2 = lo + g * (hi - lo);
            if f(m1) > f(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        let top = f(0.5 * (lo + hi)).max(best);
        Ok((top - (self.dc + self.amplitude)) / self.amplitude.abs())
    }
}

/// A periodic train of equal Gaussian pulses (Eq. 6.24 with `P_n = P`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GaussianTrain {
    /// Period `τ_c`, s.
    pub tau_c_s: f64,
    /// Sigma ratio `r = σ / τ_c` (the `τ_p / τ_c` of Eq. 6.23 and docs/methods.md §6).
    pub sigma_ratio: f64,
    /// Pulse height `P`.
    pub amplitude: f64,
    /// Base level `S`.
    pub dc: f64,
    /// Centre of pulse 0, `t_0`, s.
    pub t0_s: f64,
}

impl GaussianTrain {
    /// Builds and validates a train.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when `τ_c` is not positive, `r` not in (0, 1)
    /// or a level or `t_0` not finite.
    pub fn new(tau_c_s: f64, sigma_ratio: f64, amplitude: f64, dc: f64, t0_s: f64) -> Result<Self> {
        check_period(tau_c_s)?;
        check_ratio("pulse ratio sigma/tau_c", sigma_ratio, 1.0)?;
        check_finite("pulse amplitude", amplitude)?;
        check_finite("DC level", dc)?;
        check_finite("t0", t0_s)?;
        Ok(Self {
            tau_c_s,
            sigma_ratio,
            amplitude,
            dc,
            t0_s,
        })
    }

    /// Sigma of one pulse, s.
    pub fn sigma_s(&self) -> f64 {
        self.sigma_ratio * self.tau_c_s
    }

    /// Width at half maximum of one pulse `τ_p = 2√(2 ln 2) σ`, s.
    pub fn fwhm_s(&self) -> f64 {
        FWHM_PER_SIGMA * self.sigma_s()
    }

    /// Exact complex Fourier coefficient `C_n` (docs/methods.md §6), `n` may be negative;
    /// the DC level `S` is not included in `C_0`.
    ///
    /// ```text
    /// C_n = √(2π) P r exp(−2π² n² r²) exp(−j 2π n t_0 / τ_c)
    /// ```
    ///
    /// ```
    /// use ballpass::model::pulse_train::GaussianTrain;
    /// let g = GaussianTrain::new(1.0, 0.155, 1.0, 0.0, 0.0).unwrap();
    /// // docs/methods.md §6 reference values, printed to 5 significant digits.
    /// for (n, c) in [(0, 0.38853), (1, 0.24180), (2, 0.058290), (3, 0.0054426)] {
    ///     assert!((g.coefficient(n).re - c).abs() / c < 5e-5);
    /// }
    /// ```
    pub fn coefficient(&self, n: i64) -> Complex64 {
        let r = self.sigma_ratio;
        let nf = n as f64;
        let mag = (2.0 * PI).sqrt() * self.amplitude * r * (-2.0 * PI * PI * nf * nf * r * r).exp();
        Complex64::from_polar(1.0, -2.0 * PI * nf * self.t0_s / self.tau_c_s) * mag
    }

    /// `C_0 ..= C_order`.
    pub fn coefficients(&self, order: usize) -> Vec<Complex64> {
        (0..=order as i64).map(|n| self.coefficient(n)).collect()
    }

    /// The coefficients the thesis printed (Eq. 6.27, missing `P`), for
    /// comparison only: `√π r/2 exp(−(π n r / 2)²)`.
    pub fn thesis_printed_coefficient(&self, n: i64) -> f64 {
        let r = self.sigma_ratio;
        let x = PI * n as f64 * r / 2.0;
        PI.sqrt() * r / 2.0 * (-x * x).exp()
    }

    /// Smallest order N with `|C_n| ≤ tol · |C_0|` for every n > N (the decay
    /// is monotone), at most 100 000.
    pub fn order_for(&self, tol: f64) -> usize {
        let r = self.sigma_ratio;
        let tol = tol.clamp(1e-300, 1.0);
        // exp(−2π² n² r²) ≤ tol  ⇔  n ≥ √(−ln tol / 2) / (π r)
        let n = ((-tol.ln() / 2.0).sqrt() / (PI * r)).ceil();
        (n as usize).min(100_000)
    }

    /// The exact train at `t_s`: `S + Σ_k g(t − kτ_c − t_0)` over every pulse
    /// that contributes more than 1e-18 of `P`.
    pub fn value(&self, t_s: f64) -> f64 {
        let tc = self.tau_c_s;
        let sigma = self.sigma_s();
        // Position relative to the nearest pulse centre.
        let u = (t_s - self.t0_s) / tc;
        let k0 = u.round();
        let reach = (9.3 * sigma / tc).ceil() as i64 + 1; // e^{−9.3²/2} ≈ 1.6e-19
        let mut sum = 0.0;
        for k in -reach..=reach {
            let d = (u - k0 - k as f64) * tc;
            sum += (-d * d / (2.0 * sigma * sigma)).exp();
        }
        self.dc + self.amplitude * sum
    }

    /// The Fourier series (Eq. 6.25 with the corrected `C_n`) truncated at `order`.
    pub fn partial_sum(&self, t_s: f64, order: usize) -> f64 {
        let w = 2.0 * PI * t_s / self.tau_c_s;
        let mut sum = self.coefficient(0).re;
        for n in 1..=order as i64 {
            let e = Complex64::from_polar(1.0, w * n as f64);
            sum += 2.0 * (self.coefficient(n) * e).re;
        }
        self.dc + sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use realfft::RealFftPlanner;

    fn fft_coefficients(samples: &[f64]) -> Vec<Complex64> {
        let m = samples.len();
        let mut planner = RealFftPlanner::<f64>::new();
        let fft = planner.plan_fft_forward(m);
        let mut input = samples.to_vec();
        let mut out = fft.make_output_vec();
        fft.process(&mut input, &mut out).unwrap();
        out.into_iter().map(|c| c / m as f64).collect()
    }

    #[test]
    fn gaussian_coefficients_match_errata_reference() {
        let g = GaussianTrain::new(0.9, 0.155, 1.0, 0.0, 0.0).unwrap();
        let refs = [0.38853, 0.24180, 0.058290, 0.0054426, 1.968e-4];
        for (n, want) in refs.iter().enumerate() {
            let got = g.coefficient(n as i64);
            // docs/methods.md prints 5 (4 for n = 4) significant digits: half a unit in the
            // last digit is ≤ 5e-5 relative (2.6e-4 for 1.968e-4).
            let tol = if n == 4 { 2.6e-4 } else { 5e-5 };
            assert!((got.re - want).abs() / want < tol, "C_{n} = {got}");
            assert_eq!(got.im, 0.0);
        }
        // The printed (wrong) formula's values, docs/methods.md §6, for the record.
        for (n, want) in [0.13737, 0.12946, 0.10837, 0.08057].iter().enumerate() {
            assert!((g.thesis_printed_coefficient(n as i64) - want).abs() / want < 5e-5);
        }
    }

    #[test]
    fn gaussian_coefficients_match_fft_of_sampled_train() {
        let tc = 0.81111;
        let g = GaussianTrain::new(tc, 0.155, 2.3, 0.7, 0.21).unwrap();
        let m = 512;
        let samples: Vec<f64> = (0..m).map(|i| g.value(tc * i as f64 / m as f64)).collect();
        let x = fft_coefficients(&samples);
        // C_n decays below 1e-16 by n ≈ 9, so aliasing from n ± 512 is nil and the
        // DFT equals C_n to rounding (docs/methods.md §6: agreement to 1e-12).
        for (n, xn) in x.iter().enumerate().take(40) {
            let mut want = g.coefficient(n as i64);
            if n == 0 {
                want += g.dc;
            }
            assert!((xn - want).norm() < 1e-12, "n = {n}: {xn} vs {want}");
        }
    }

    #[test]
    fn gaussian_series_reconstructs_the_train() {
        let g = GaussianTrain::new(1.3, 0.155, 1.0, 0.2, 0.4).unwrap();
        let order = g.order_for(1e-16);
        assert!((9..=12).contains(&order), "{order}");
        for i in 0..50 {
            let t = -1.0 + i as f64 * 0.097;
            // Truncation below 1e-16 of P; the rest is rounding.
            assert!((g.partial_sum(t, order) - g.value(t)).abs() < 1e-13);
        }
        assert!((g.fwhm_s() / g.sigma_s() - 2.0 * (2.0 * 2f64.ln()).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn rectangular_coefficients_match_errata_and_fft() {
        let tc = 2.0;
        let r = 0.155;
        let train = RectangularTrain::new(tc, r, 1.0, 0.0).unwrap();
        let c = train.coefficients(6);
        // docs/methods.md §5: a0 = 0.310 (3 decimals), a1 = 0.26326, b1 = −0.13939 (5
        // decimals, truncated rather than rounded: 0.2632679 is printed 0.26326),
        // so one unit of the last printed digit.
        assert!((c.a0 - 0.310).abs() < 5e-4);
        assert!((c.a[0] - 0.26326).abs() < 1e-5);
        assert!((c.b[0] + 0.13939).abs() < 1e-5);
        // FFT of the sampled train with the jump mean on the jumps: the DFT
        // aliases c_{n+kM}, whose ~1/(kM) tails leave O(1e-5) at M = 2^16
        // (docs/methods.md §5 quotes agreement within 1e-4).
        let m = 1 << 16;
        let samples: Vec<f64> = (0..m)
            .map(|i| train.value(tc * i as f64 / m as f64))
            .collect();
        let x = fft_coefficients(&samples);
        assert!((2.0 * x[0].re - c.a0).abs() < 1e-4);
        for (n, xn) in x.iter().enumerate().take(7).skip(1) {
            // x_n = (a_n − j b_n) / 2
            assert!((2.0 * xn.re - c.a[n - 1]).abs() < 1e-4, "a_{n}");
            assert!((-2.0 * xn.im - c.b[n - 1]).abs() < 1e-4, "b_{n}");
        }
    }

    #[test]
    fn rectangular_series_equals_coefficient_form_and_converges() {
        let train = RectangularTrain::new(0.5, 0.155, 1.5, 0.3).unwrap();
        let c = train.coefficients(30);
        for i in 0..40 {
            let t = i as f64 * 0.0131;
            let w = 2.0 * PI * t / train.tau_c_s;
            let direct = train.dc
                + c.a0 / 2.0
                + (1..=30)
                    .map(|n| {
                        let nf = n as f64;
                        c.a[n - 1] * (nf * w).cos() + c.b[n - 1] * (nf * w).sin()
                    })
                    .sum::<f64>();
            // The closed form and the a_n/b_n form are the same sum: rounding only.
            assert!((train.partial_sum(t, 30) - direct).abs() < 1e-12);
        }
        // Far from the jumps the series converges to the train: at the centre of
        // the pulse and of the gap, order 2000 is within 1e-3 P (error ~ 1/(Nπ Δ)).
        for t in [0.5 * (1.0 - 0.155 / 2.0), 0.2] {
            let t = t * train.tau_c_s;
            assert!((train.partial_sum(t, 2000) - train.value(t)).abs() < 1e-3 * 1.5);
        }
    }

    #[test]
    fn gibbs_overshoot_matches_errata() {
        let train = RectangularTrain::new(1.0, 0.155, 1.0, 0.0).unwrap();
        // docs/methods.md §5 prints 10.05 %, 9.10 %, 8.96 % (two decimals of a percent:
        // ±5e-5 as a fraction).
        for (n, want) in [(20, 0.1005), (200, 0.0910), (2000, 0.0896)] {
            let got = train.gibbs_overshoot(n).unwrap();
            assert!((got - want).abs() < 5e-5, "N = {n}: {got}");
        }
        assert!(train.gibbs_overshoot(0).is_err());
    }

    #[test]
    fn bad_settings_are_errors() {
        assert!(GaussianTrain::new(0.0, 0.1, 1.0, 0.0, 0.0).is_err());
        assert!(GaussianTrain::new(1.0, 0.0, 1.0, 0.0, 0.0).is_err());
        assert!(GaussianTrain::new(1.0, 0.1, f64::NAN, 0.0, 0.0).is_err());
        assert!(RectangularTrain::new(1.0, 1.0, 1.0, 0.0).is_err());
        assert!(RectangularTrain::new(-1.0, 0.5, 1.0, 0.0).is_err());
        assert!((sigma_ratio_from_fwhm_ratio(FWHM_PER_SIGMA) - 1.0).abs() < 1e-15);
    }
}
