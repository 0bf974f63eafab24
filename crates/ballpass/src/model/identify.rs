//! Closed-loop identification of the stage from a recording: the measured
//! friction → velocity-error response and a PD-loop fit with confidence
//! intervals.
//!
//! The friction a bearing makes is set by where the truck is on the rail
//! (roughness, ball passages), not by the small velocity error, so in the
//! loop of thesis Fig. 40 it is an input the stage responds to:
//! `v_e = −G_vf(s) f`, `G_vf(s) = s / (m s² + K K_D s + K K_P)` (Eq. 6.6,
//! friction opposing motion). From the two recorded signals (friction with
//! its load-cell discharge undone; velocity error from the encoder by the
//! centred difference):
//!
//! ```text
//! H1(f)   = P_fv(f) / P_ff(f)        (Welch, MATLAB tfestimate's H1), γ²(f) its coherence
//! H(f)    = H1(f) / D(f)             D = sin(ωT)/(ωT): the centred difference's own gain
//! Z(f)    = −1 / H(f) = K K_D + j (m ω − K K_P / ω)        linear in (m, K K_D, K K_P)
//! ```
//!
//! A real bench measures the force through anti-alias filters and
//! sample-and-hold, a small delay `τ_d` between force and velocity error
//! that bends the phase of `Z` where `m ω` is large. To first order in
//! `ω τ_d`, `Z_meas = Z (1 − j ω τ_d)`, which stays linear in four
//! parameters:
//!
//! ```text
//! Re Z = (K K_D − τ_d K K_P) + τ_d m ω²,     Im Z = (m − τ_d K K_D) ω − K K_P / ω
//! ```
//!
//! fitted as two weighted least squares over the bins whose coherence is
//! significant (99 %), each component weighted by the inverse of its
//! variance `|Z|² (1 − γ²) / (2 n_d γ²)` (Bendat & Piersol, Random Data,
//! Eq. 9.65; `n_d` the Welch segments' equivalent count), the covariance
//! scaled up by the reduced χ² when the model misfits; `(m, K K_D, K K_P,
//! τ_d)` follow by a fixed-point solve. The fit is repeated over the two
//! decades around the resonance found. Then
//!
//! ```text
//! f_n = sqrt(K K_P / m) / 2π,   ζ = K K_D / (2 sqrt(m K K_P)),   |G_vf|max = 1 / (K K_D)
//! ```
//!
//! with 95 % intervals by the delta method (numerical gradients). The stage is **identified**
//! when those intervals are within ±5 % (f_n) and ±20 % (ζ), and the
//! spectral resolution is fine enough for the resonance (at most a quarter
//! of its half-power bandwidth `2 ζ f_n`); otherwise the answer is "not
//! identifiable" with the reason (too little coherent band around the
//! resonance, most often because the friction does not excite it).

use ballpass_dsp::{Complex64, Welch, WelchSettings};
use serde::Serialize;

use crate::analysis::load_cell::{restore_friction, LoadCellCorrection};
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};

/// The friction → velocity-error spectra of one or more records, to be
/// pooled and fitted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageSpectra {
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Bin frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Friction auto-spectrum (sum over records), N²/Hz.
    pub p_ff: Vec<f64>,
    /// Velocity-error auto-spectrum (sum), (m/s)²/Hz.
    pub p_vv: Vec<f64>,
    /// Cross spectrum `conj(F) V` (sum), N·(m/s)/Hz.
    pub p_fv: Vec<Complex64>,
    /// Records summed.
    pub records: usize,
    /// Equivalent segments (all records), for the error of `H1`.
    pub n_d: f64,
}

/// Segment length of the identification spectra for a record of `n`
/// samples: 16 s (a 1/16 Hz resolution for the slowest stages), at most a
/// quarter of the record, a power of two.
pub fn nperseg_for(n: usize, fs_hz: f64) -> usize {
    let want = (16.0 * fs_hz).min(n as f64 / 4.0).max(16.0);
    let mut p = 16usize;
    while (p * 2) as f64 <= want {
        p *= 2;
    }
    p
}

impl StageSpectra {
    /// The spectra of one record: `friction_n` (discharge undone),
    /// `velocity_error_mm_s` (centred difference of the encoder), both
    /// linearly detrended here, Hann segments of `nperseg` with half overlap.
    ///
    /// # Errors
    /// [`Error::Dsp`] if the Welch estimate rejects the signals.
    pub fn of(
        friction_n: &[f64],
        velocity_error_mm_s: &[f64],
        fs_hz: f64,
        nperseg: usize,
    ) -> Result<StageSpectra> {
        let mut f = friction_n.to_vec();
        let mut v: Vec<f64> = velocity_error_mm_s.iter().map(|x| x * 1e-3).collect();
        for s in [&mut f, &mut v] {
            ballpass_dsp::detrend_in_place(s, ballpass_dsp::DetrendType::Linear)
                .map_err(|e| Error::dsp("stage identification detrend", e))?;
        }
        let mut welch = Welch::new(WelchSettings {
            nperseg,
            ..WelchSettings::default()
        })
        .map_err(|e| Error::dsp("stage identification Welch", e))?;
        let set = welch
            .spectra(&[&f, &v], &[(0, 1)], fs_hz)
            .map_err(|e| Error::dsp("stage identification spectra", e))?;
        let w: Vec<f64> = (0..nperseg)
            .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / nperseg as f64).cos())
            .collect();
        let nu = crate::stats::welch_dof(&w, nperseg / 2, set.n_segments);
        let mut auto = set.auto.into_iter();
        Ok(StageSpectra {
            fs_hz,
            freq_hz: set.freq_hz,
            p_ff: auto.next().unwrap_or_default(),
            p_vv: auto.next().unwrap_or_default(),
            p_fv: set.cross.into_iter().next().unwrap_or_default(),
            records: 1,
            n_d: nu / 2.0,
        })
    }

    /// The spectra of a recording with friction and position channels
    /// (`None` without either): the friction with the load cell's discharge
    /// undone as `correction` says (`period_s` the predicted ball-pass
    /// period, for its estimate), the velocity error from the encoder by the
    /// centred difference.
    ///
    /// # Errors
    /// As [`StageSpectra::of`] and [`restore_friction`].
    pub fn of_recording(
        rec: &Recording,
        velocity_mm_s: f64,
        period_s: f64,
        correction: LoadCellCorrection,
    ) -> Result<Option<StageSpectra>> {
        let (Some(f), Some(p)) = (
            rec.channel(Channel::Friction),
            rec.channel(Channel::Position),
        ) else {
            return Ok(None);
        };
        let fs = rec.fs_hz();
        let (friction, _) = restore_friction(f, fs, period_s, correction)?;
        let nperseg = nperseg_for(friction.len(), fs);
        StageSpectra::of_signals(&friction, p, fs, velocity_mm_s, nperseg).map(Some)
    }

    /// The spectra from a friction channel (discharge already undone) and
    /// the encoder position (mm): the velocity error by the centred
    /// difference.
    ///
    /// # Errors
    /// As [`StageSpectra::of`].
    pub fn of_signals(
        friction_n: &[f64],
        position_mm: &[f64],
        fs_hz: f64,
        velocity_mm_s: f64,
        nperseg: usize,
    ) -> Result<StageSpectra> {
        let v: Vec<f64> =
            ballpass_dsp::gradient(position_mm, ballpass_dsp::Spacing::Uniform(1.0 / fs_hz))
                .map_err(|e| Error::dsp("stage identification velocity", e))?
                .into_iter()
                .map(|x| x - velocity_mm_s)
                .collect();
        StageSpectra::of(friction_n, &v, fs_hz, nperseg)
    }

    /// Adds another record's spectra on the same grid; `false` (nothing
    /// added) when the grid differs.
    pub fn add(&mut self, other: &StageSpectra) -> bool {
        if self.records == 0 {
            *self = other.clone();
            return true;
        }
        if other.fs_hz != self.fs_hz || other.freq_hz != self.freq_hz {
            return false;
        }
        for (a, b) in self.p_ff.iter_mut().zip(&other.p_ff) {
            *a += b;
        }
        for (a, b) in self.p_vv.iter_mut().zip(&other.p_vv) {
            *a += b;
        }
        for (a, b) in self.p_fv.iter_mut().zip(&other.p_fv) {
            *a += b;
        }
        self.records += other.records;
        self.n_d += other.n_d;
        true
    }
}

/// A value with its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Estimate {
    /// The value.
    pub value: f64,
    /// 95 % half-width.
    pub ci95: f64,
}

/// The stage identified from the data.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StageIdentification {
    /// Records pooled.
    pub records: usize,
    /// Bins with significant coherence used in the fit.
    pub bins_used: usize,
    /// Frequency range of those bins, Hz.
    pub band_hz: Option<[f64; 2]>,
    /// Spectral resolution, Hz.
    pub resolution_hz: f64,
    /// Coherence a bin needs (99 %).
    pub coherence_threshold: f64,
    /// Effective moving mass `m`, kg.
    pub mass_kg: Option<Estimate>,
    /// `K K_D`, N·s/m.
    pub kkd_n_s_per_m: Option<Estimate>,
    /// `K K_P`, N/m.
    pub kkp_n_per_m: Option<Estimate>,
    /// Delay of the measurement chain between force and velocity error
    /// (anti-alias filters, sample-and-hold), s.
    pub delay_s: Option<Estimate>,
    /// Natural frequency, Hz.
    pub natural_frequency_hz: Option<Estimate>,
    /// Damping ratio.
    pub damping_ratio: Option<Estimate>,
    /// Peak of `|G_vf|` (at `f_n`), (mm/s)/N.
    pub peak_gain_mm_s_per_n: Option<Estimate>,
    /// Reduced χ² of the fit (1 when the model explains the data to its
    /// noise).
    pub reduced_chi2: Option<f64>,
    /// Whether the intervals are tight enough (module docs).
    pub identified: bool,
    /// In words, with the reason when not identified.
    pub text: String,
}

/// Fits the PD stage to pooled spectra (module docs).
pub fn identify(s: &StageSpectra) -> StageIdentification {
    // Pass 1 over every coherent bin below a quarter of the rate; then the
    // fit is repeated over two decades centred (geometrically) on the
    // resonance found, where the PD model is meant to hold (far above it the
    // measurement chain's own filters take over the phase).
    let mut band = [0.0, 0.25 * s.fs_hz];
    let mut out = fit_band(s, band);
    for _ in 0..3 {
        let Some(fe) = out.natural_frequency_hz else {
            break;
        };
        let next = [fe.value / 10.0, (fe.value * 10.0).min(0.25 * s.fs_hz)];
        if next == band {
            break;
        }
        band = next;
        out = fit_band(s, band);
    }
    // Model adequacy: the PD model must explain the coherent response to
    // within its noise (reduced χ² at most 3, i.e. residuals at most ~1.7×
    // their standard error); otherwise its parameters are not the stage's.
    if out.identified && out.reduced_chi2.is_some_and(|r| r > MAX_REDUCED_CHI2) {
        out.identified = false;
        out.text = format!(
            "stage not identifiable: the PD model does not fit the measured friction → velocity-error response (reduced χ² {:.1} over {} coherent bins, at most {MAX_REDUCED_CHI2} accepted); its best fit would be f_n = {:.3} Hz, ζ = {:.3}",
            out.reduced_chi2.unwrap_or(f64::NAN),
            out.bins_used,
            out.natural_frequency_hz.map_or(f64::NAN, |e| e.value),
            out.damping_ratio.map_or(f64::NAN, |e| e.value),
        );
    }
    out
}

/// Largest reduced χ² with which the PD model is taken to describe the
/// stage (module docs).
pub const MAX_REDUCED_CHI2: f64 = 3.0;

fn fit_band(s: &StageSpectra, band_limits: [f64; 2]) -> StageIdentification {
    let df = s.freq_hz.get(1).copied().unwrap_or(0.0);
    let n_d = s.n_d.max(1.0);
    let threshold = if n_d > 1.0 {
        1.0 - 0.01f64.powf(1.0 / (n_d - 1.0))
    } else {
        1.0
    };
    let t = 1.0 / s.fs_hz;
    // Two decoupled weighted least squares, Re Z = p0 + p1 ω² and
    // Im Z = p2 ω − p3 / ω (module docs: the PD stage seen through a
    // measurement chain of small delay τ_d).
    let mut re = Wls2::default();
    let mut im = Wls2::default();
    let mut band: Option<[f64; 2]> = None;
    let mut bins = 0;
    for (i, &f) in s.freq_hz.iter().enumerate() {
        // Above DC, inside the band (at most a quarter of the rate, where
        // the centred difference still passes 64 % and is corrected).
        if i < 2 || f > band_limits[1] || f < band_limits[0] {
            continue;
        }
        let (pff, pvv, pfv) = (s.p_ff[i], s.p_vv[i], s.p_fv[i]);
        if !(pff > 0.0 && pvv > 0.0) {
            continue;
        }
        let g2 = pfv.norm_sqr() / (pff * pvv);
        if g2.is_nan() || g2 <= threshold {
            continue;
        }
        let w = std::f64::consts::TAU * f;
        let d = (w * t).sin() / (w * t);
        let h = pfv / pff / d;
        let z = -(Complex64::new(1.0, 0.0) / h);
        let var = z.norm_sqr() * (1.0 - g2) / (2.0 * n_d * g2);
        let wt = 1.0 / var.max(f64::MIN_POSITIVE);
        re.add([1.0, w * w], z.re, wt);
        im.add([w, -1.0 / w], z.im, wt);
        bins += 1;
        band = Some(match band {
            None => [f, f],
            Some([a, _]) => [a, f],
        });
    }
    let mut out = StageIdentification {
        records: s.records,
        bins_used: bins,
        band_hz: band,
        resolution_hz: df,
        coherence_threshold: threshold,
        mass_kg: None,
        kkd_n_s_per_m: None,
        kkp_n_per_m: None,
        delay_s: None,
        natural_frequency_hz: None,
        damping_ratio: None,
        peak_gain_mm_s_per_n: None,
        reduced_chi2: None,
        identified: false,
        text: String::new(),
    };
    if bins < 4 {
        out.text = format!(
            "stage not identifiable: only {bins} frequency bin(s) where friction and velocity error are coherent (99 %); the friction does not excite the stage enough"
        );
        return out;
    }
    let (Some(fit_re), Some(fit_im)) = (re.solve(), im.solve()) else {
        out.text = "stage not identifiable: the coherent band does not separate mass, damping and stiffness".into();
        return out;
    };
    let dof = (2.0 * bins as f64 - 4.0).max(1.0);
    let red = (fit_re.chi2 + fit_im.chi2) / dof;
    let inflate = red.max(1.0);
    let p = [
        fit_re.theta[0],
        fit_re.theta[1],
        fit_im.theta[0],
        fit_im.theta[1],
    ];
    let mut cov = [[0.0; 4]; 4];
    for i in 0..2 {
        for j in 0..2 {
            cov[i][j] = fit_re.cov[i][j] * inflate;
            cov[i + 2][j + 2] = fit_im.cov[i][j] * inflate;
        }
    }
    out.reduced_chi2 = Some(red);
    let Some(st) = Stage::from_params(p) else {
        out.text = format!(
            "stage not identifiable: the fit gives a non-physical stage over {bins} coherent bins ({:.2}–{:.2} Hz)",
            band.map_or(0.0, |b| b[0]),
            band.map_or(0.0, |b| b[1])
        );
        return out;
    };
    // Delta method with a numerical gradient of each derived value in p.
    let var_of = |g: &dyn Fn(&Stage) -> f64| -> f64 {
        let mut grad = [0.0; 4];
        for (k, gk) in grad.iter_mut().enumerate() {
            let h = 1e-6 * p[k].abs().max(1e-300);
            let mut hi = p;
            let mut lo = p;
            hi[k] += h;
            lo[k] -= h;
            *gk = match (Stage::from_params(hi), Stage::from_params(lo)) {
                (Some(a), Some(b)) => (g(&a) - g(&b)) / (2.0 * h),
                _ => f64::NAN,
            };
        }
        (0..4)
            .map(|i| (0..4).map(|j| grad[i] * cov[i][j] * grad[j]).sum::<f64>())
            .sum()
    };
    let est = |v: f64, var: f64| Estimate {
        value: v,
        ci95: if var.is_finite() {
            1.96 * var.max(0.0).sqrt()
        } else {
            f64::INFINITY
        },
    };
    let fnat = st.f_n();
    let zeta = st.zeta();
    out.mass_kg = Some(est(st.m, var_of(&|x| x.m)));
    out.kkd_n_s_per_m = Some(est(st.c, var_of(&|x| x.c)));
    out.kkp_n_per_m = Some(est(st.k, var_of(&|x| x.k)));
    out.delay_s = Some(est(st.tau, var_of(&|x| x.tau)));
    let fn_e = est(fnat, var_of(&|x| x.f_n()));
    let z_e = est(zeta, var_of(&|x| x.zeta()));
    let peak = 1e3 / st.c;
    out.natural_frequency_hz = Some(fn_e);
    out.damping_ratio = Some(z_e);
    out.peak_gain_mm_s_per_n = Some(est(peak, var_of(&|x| 1e3 / x.c)));
    let tight = fn_e.ci95 <= 0.05 * fnat && z_e.ci95 <= 0.2 * zeta;
    let resolved = df <= 0.25 * 2.0 * zeta * fnat;
    out.identified = tight && resolved;
    out.text = if out.identified {
        format!(
            "stage identified from {bins} coherent bins ({:.2}–{:.2} Hz): f_n = {fnat:.3} ± {:.3} Hz, ζ = {zeta:.3} ± {:.3}, |G_vf| peak {peak:.3} (mm/s)/N",
            band.map_or(0.0, |b| b[0]),
            band.map_or(0.0, |b| b[1]),
            fn_e.ci95,
            z_e.ci95
        )
    } else if !resolved {
        format!(
            "stage not identifiable: the resonance (f_n ≈ {fnat:.3} Hz, ζ ≈ {zeta:.3}) is narrower than the {df:.3} Hz resolution allows; longer records would resolve it"
        )
    } else {
        format!(
            "stage not identifiable: f_n = {fnat:.3} ± {:.3} Hz, ζ = {zeta:.3} ± {:.3} (95 %) are not within ±5 % and ±20 %; the coherent band {:.2}–{:.2} Hz does not pin the resonance down",
            fn_e.ci95,
            z_e.ci95,
            band.map_or(0.0, |b| b[0]),
            band.map_or(0.0, |b| b[1])
        )
    };
    out
}

/// The stage and measurement-chain delay behind the linear parameters
/// `p = [c − τ k, τ m, m − τ c, k]`.
#[derive(Debug, Clone, Copy)]
struct Stage {
    m: f64,
    c: f64,
    k: f64,
    tau: f64,
}

impl Stage {
    /// Solves for `(m, c, k, τ)` by fixed-point iteration from `τ = 0`
    /// (it contracts while `τ² k / m` is small, i.e. the delay is small
    /// against the resonance's period); `None` when non-physical or not
    /// converged.
    fn from_params(p: [f64; 4]) -> Option<Stage> {
        let k = p[3];
        let (mut m, mut c, mut tau) = (p[2], p[0], 0.0);
        for _ in 0..200 {
            if m.is_nan() || m <= 0.0 {
                return None;
            }
            let tau_next = p[1] / m;
            let m_next = p[2] + tau_next * c;
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

    fn f_n(&self) -> f64 {
        (self.k / self.m).sqrt() / std::f64::consts::TAU
    }

    fn zeta(&self) -> f64 {
        self.c / (2.0 * (self.m * self.k).sqrt())
    }
}

/// A two-parameter weighted least squares, accumulated row by row.
#[derive(Debug, Default)]
struct Wls2 {
    ata: [[f64; 2]; 2],
    atb: [f64; 2],
    btb: f64,
}

/// Its solution, the weighted residual sum and the parameters' covariance
/// (weights taken as inverse variances).
struct Wls2Fit {
    theta: [f64; 2],
    chi2: f64,
    cov: [[f64; 2]; 2],
}

impl Wls2 {
    fn add(&mut self, row: [f64; 2], y: f64, w: f64) {
        for i in 0..2 {
            self.atb[i] += w * row[i] * y;
            for j in 0..2 {
                self.ata[i][j] += w * row[i] * row[j];
            }
        }
        self.btb += w * y * y;
    }

    fn solve(&self) -> Option<Wls2Fit> {
        let a = self.ata;
        // Scale to unit diagonal before inverting (the columns differ by
        // many orders of magnitude: 1 and ω², ω and 1/ω).
        let d = [a[0][0].sqrt(), a[1][1].sqrt()];
        if !(d[0] > 0.0 && d[1] > 0.0) {
            return None;
        }
        let r = a[0][1] / (d[0] * d[1]);
        let det = 1.0 - r * r;
        if det.is_nan() || det <= 1e-12 {
            return None;
        }
        let inv_s = [[1.0 / det, -r / det], [-r / det, 1.0 / det]];
        let mut cov = [[0.0; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                cov[i][j] = inv_s[i][j] / (d[i] * d[j]);
            }
        }
        let theta = [
            cov[0][0] * self.atb[0] + cov[0][1] * self.atb[1],
            cov[1][0] * self.atb[0] + cov[1][1] * self.atb[1],
        ];
        let chi2 = (self.btb - theta[0] * self.atb[0] - theta[1] * self.atb[1]).max(0.0);
        Some(Wls2Fit { theta, chi2, cov })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::Channel;
    use crate::sim::{simulate, SimSettings, StageSettings};

    /// A stage the friction excites (5 Hz, ζ = 0.3, soft enough that the
    /// velocity error stands above the encoder's quantisation): identified
    /// from two minutes, its interval holding the truth.
    #[test]
    fn a_simulated_stage_is_identified() {
        let (fnat, zeta, mass) = (5.0, 0.3, 60.0);
        let wn = std::f64::consts::TAU * fnat;
        let mut s = SimSettings {
            duration_s: 120.0,
            stage: StageSettings {
                mass_kg: mass,
                kkp_n_per_m: mass * wn * wn,
                kkd_n_s_per_m: 2.0 * zeta * mass * wn,
            },
            ..SimSettings::default()
        };
        s.load_cell.time_constant_s = None;
        s.friction.roughness_length_mm = 0.3;
        let sim = simulate(&s).unwrap();
        let r = &sim.recording;
        let f = r.channel(Channel::Friction).unwrap();
        let p = r.channel(Channel::Position).unwrap();
        let v: Vec<f64> = ballpass_dsp::gradient(p, ballpass_dsp::Spacing::Uniform(1e-3))
            .unwrap()
            .iter()
            .map(|x| x - s.velocity_mm_s)
            .collect();
        let sp = StageSpectra::of(f, &v, 1000.0, nperseg_for(f.len(), 1000.0)).unwrap();
        let id = identify(&sp);
        let fe = id.natural_frequency_hz.unwrap();
        let ze = id.damping_ratio.unwrap();
        assert!(id.identified, "{id:#?}");
        assert!(
            (fe.value - fnat).abs() <= fe.ci95.max(0.05 * fnat),
            "{id:#?}"
        );
        assert!(
            (ze.value - zeta).abs() <= ze.ci95.max(0.2 * zeta),
            "{id:#?}"
        );
    }
}
