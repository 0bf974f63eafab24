//! Load-cell DC restoration: a quartz load cell with its charge amplifier is
//! a first-order high-pass (`H(s) = τ s / (τ s + 1)`, thesis §3.3 and Fig.
//! 54): a constant friction decays in the recording as `F e^{-t/τ}`, the
//! friction at low frequencies is attenuated and its phase advanced by
//! `atan(1 / (ω τ))`. Undoing it before the analysis removes the decay
//! (which otherwise raises the low-frequency spectrum, biases correlation
//! lags and looks like a spike at the record start) and restores the
//! amplitude and phase of slow ball-pass frequencies.
//!
//! # Estimating τ from the record
//!
//! At constant velocity the friction is its Coulomb level plus fluctuations
//! about it, so the recording is `y(t) = c + A e^{-t/τ} + fluctuations`
//! (`c` the amplifier's offset). The fit runs on the recording averaged
//! over windows of one ball-pass period (which removes the ripple at `f_c`
//! and its harmonics; at least 20 ms, at most 1/20 of the record), with the
//! same averaging applied to the model, so a decay faster than the window
//! is still fitted exactly:
//!
//! ```text
//! s[i]  = mean(y[i .. i+W])
//! b_τ[i] = mean(e^{-j/(fs τ)}, j = i .. i+W)   (closed form)
//! RSS(τ) = min over c, A of Σ (s[i] − c − A b_τ[i])²    (τ on a log grid, then golden section)
//! ```
//!
//! The decay is **identified** when it explains the averaged record far
//! better than a constant — an F test with 2 and `n_eff − 3` degrees of
//! freedom at 99.9 %, `n_eff` the number of independent points of the
//! averaged residual (from its lag-one autocorrelation) — and the profile
//! 95 % interval of τ, `RSS(τ) ≤ RSS_min (1 + F_{0.95}(1, n_eff − 3) /
//! (n_eff − 3))`, is closed above inside the grid (up to 50 record
//! lengths). Otherwise the record does not show its discharge (a DC-coupled
//! sensor, a discharge over before the record, or one too slow to tell
//! from a line) and nothing is undone unless τ is given.
//!
//! # Restoring
//!
//! ```text
//! x(t) = (y(t) − c) + (1/τ) ∫_0^t (y(u) − c) du        (trapezoidal rule)
//! ```
//!
//! the exact inverse of the high-pass. The level before the record is not
//! in the data: `x` starts at the recording's first value, so the restored
//! friction's absolute level is the one the load cell saw at the record
//! start (its fluctuations, spectra, phases and spikes are the friction's).

use std::borrow::Cow;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::stats::f_ppf;

/// What to do about the load cell's discharge.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadCellCorrection {
    /// Estimate τ from the record; undo the high-pass when it is identified.
    #[default]
    Auto,
    /// The time constant is known (a bench profile or a flag), s.
    TimeConstant(f64),
    /// Leave the friction as recorded (a DC-coupled force sensor).
    Off,
}

impl LoadCellCorrection {
    /// Checks a given time constant.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a non-positive or non-finite τ.
    pub fn validate(&self) -> Result<()> {
        match *self {
            LoadCellCorrection::TimeConstant(t) if !(t.is_finite() && t > 0.0) => {
                Err(Error::setting(
                    "load-cell time constant",
                    format!("must be a positive number of s, got {t}"),
                ))
            }
            _ => Ok(()),
        }
    }
}

/// The fit of a discharge `c + A e^{-t/τ}` to one record (module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DischargeFit {
    /// Best-fitting time constant, s.
    pub tau_s: f64,
    /// Lower end of its 95 % interval, s.
    pub tau_low_s: f64,
    /// Upper end of its 95 % interval, s (`None`: not closed: any longer τ
    /// fits as well).
    pub tau_high_s: Option<f64>,
    /// Decaying part at the first sample, N.
    pub amplitude_n: f64,
    /// Level the decay tends to (amplifier offset), N.
    pub offset_n: f64,
    /// Test statistic: the square of the start's z against the record after
    /// the decay, or (long τ) the F statistic against a constant.
    pub f_statistic: f64,
    /// Ball-period means of the long-τ F test (NaN for the short-τ test).
    pub n_eff: f64,
    /// Whether the record identifies τ (significant and closed interval).
    pub identified: bool,
}

/// What was done to the friction channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DcRestoration {
    /// Whether the high-pass was undone.
    pub applied: bool,
    /// The time constant undone, s.
    pub tau_s: Option<f64>,
    /// `estimated`, `given` or `none`.
    pub source: String,
    /// The fit, when one was made.
    pub fit: Option<DischargeFit>,
    /// Mean of the recorded friction over its standard deviation. A
    /// DC-coupled sensor reads the Coulomb level (tens of standard
    /// deviations); a discharged quartz load cell reads about zero.
    pub level_over_spread: f64,
    /// The friction looks AC coupled (level within 3 standard deviations of
    /// zero) and no τ was identified or given: its phases and amplitudes at
    /// low frequencies carry the unknown high-pass.
    pub unknown_high_pass: bool,
    /// In words.
    pub note: String,
}

impl DcRestoration {
    /// The warning for an AC-coupled friction channel of unknown τ at the
    /// ball-pass frequency `f_c_hz`, if there is one.
    pub fn warning(&self, f_c_hz: f64) -> Option<String> {
        self.unknown_high_pass.then(|| {
            let tau_10 = 1.0 / (std::f64::consts::TAU * f_c_hz * 10f64.to_radians().tan());
            format!(
                "the friction channel averages {:.2} of its standard deviation, as a quartz load cell does once its DC has discharged, and the record shows no discharge to estimate its time constant τ from: friction phases at f_c = {f_c_hz:.4} Hz are advanced by atan(1 / (2π f_c τ)) (10° or more if τ < {tau_10:.2} s) and amplitudes reduced; give the load cell's τ (--load-cell-tau, or the profile's [analysis] load_cell = {{ time_constant = τ }})",
                self.level_over_spread
            )
        })
    }
}

/// Fits a discharge to `y` (module docs); `period_s` is the ball-pass
/// period (the averaging window of the long-τ test). `None` for records too
/// short to fit (fewer than 40 averaged points).
pub fn fit_discharge(y: &[f64], fs_hz: f64, period_s: f64) -> Option<DischargeFit> {
    let w = block_width(y.len(), fs_hz);
    fit_discharge_blocks(Blocks::new(y, fs_hz, w), y.len(), fs_hz, period_s)
}

/// Samples per block mean of [`fit_discharge`] for a record of `n`
/// samples: at least 20 ms, and at most 20 000 blocks.
pub(crate) fn block_width(n: usize, fs_hz: f64) -> usize {
    ((0.02 * fs_hz).round() as usize)
        .max(n.div_ceil(20_000))
        .max(1)
}

/// [`fit_discharge`] from the record's block means (`block_width` samples
/// each, the trailing partial block dropped), for a record of `n`
/// samples: what a streamed record gives.
pub(crate) fn fit_discharge_means(
    means: Vec<f64>,
    n: usize,
    fs_hz: f64,
    period_s: f64,
) -> Option<DischargeFit> {
    let w = block_width(n, fs_hz);
    fit_discharge_blocks(Blocks::of_means(means, fs_hz, w), n, fs_hz, period_s)
}

fn fit_discharge_blocks(
    blocks: Blocks,
    n: usize,
    fs_hz: f64,
    period_s: f64,
) -> Option<DischargeFit> {
    let duration = n as f64 / fs_hz;
    let w = blocks.w;
    if blocks.s.len() < 40 {
        return None;
    }
    let tau_lo = (0.05_f64).max(4.0 * w as f64 / fs_hz);
    let tau_hi = 50.0 * duration;
    let grid: Vec<f64> = (0..=240)
        .map(|k| (tau_lo.ln() + (tau_hi / tau_lo).ln() * k as f64 / 240.0).exp())
        .collect();
    // The grid's fits are independent: in parallel (rayon), in order.
    let rss = blocks.profile(&grid);
    let best = (0..grid.len()).min_by(|&a, &b| rss[a].total_cmp(&rss[b]))?;
    let tau = golden_min(
        grid[best.saturating_sub(1)].ln(),
        grid[(best + 1).min(grid.len() - 1)].ln(),
        |lt| blocks.fit(lt.exp()).2,
    )
    .exp();
    let (c, amp, rss_min) = blocks.fit(tau);
    let m = blocks.s.len() as f64;
    let res_var = rss_min / (m - 3.0);

    // The test. A decay short against the record: its matched-filter
    // amplitude at the start against the same statistic over the record
    // after it (an empirical null that carries the ripple, roughness and
    // noise at the decay's own time scale). A long one: the F test of the
    // decay against a constant on ball-period means.
    let (identified_by_null, inflation) = blocks.null_test(tau, c, amp);
    let interval = |profile: &[f64], limit: f64| {
        let inside: Vec<usize> = (0..grid.len()).filter(|&k| profile[k] <= limit).collect();
        let low = inside.first().map_or(tau, |&k| grid[k].min(tau));
        let closed = inside.last().is_some_and(|&k| k + 1 < grid.len());
        (
            low,
            closed.then(|| grid[*inside.last().expect("non-empty")].max(tau)),
        )
    };
    let (significant, f_stat, n_eff, (tau_low_s, tau_high_s)) = match identified_by_null {
        Some(z) => {
            // Profile interval, the residual variance scaled by how much
            // more the local amplitude varies than white noise makes it.
            let limit = rss_min + inflation.max(1.0) * res_var * 3.841_458_820_694_124;
            (z >= 6.0, z * z, f64::NAN, interval(&rss, limit))
        }
        None => {
            let coarse = blocks.coarse(period_s);
            let n = coarse.s.len() as f64;
            let (_, _, rss_c) = coarse.fit(tau);
            let mean = coarse.s.iter().sum::<f64>() / n;
            let rss0: f64 = coarse.s.iter().map(|v| (v - mean).powi(2)).sum();
            let f = if rss_c > 0.0 {
                ((rss0 - rss_c) / 2.0) / (rss_c / (n - 3.0))
            } else {
                f64::INFINITY
            };
            let profile = coarse.profile(&grid);
            let limit = rss_c * (1.0 + f_ppf(0.95, 1.0, n - 3.0) / (n - 3.0));
            (
                n > 6.0 && f > f_ppf(0.999, 2.0, n - 3.0),
                f,
                n,
                interval(&profile, limit),
            )
        }
    };
    Some(DischargeFit {
        tau_s: tau,
        tau_low_s,
        tau_high_s,
        amplitude_n: amp,
        offset_n: c,
        f_statistic: f_stat,
        n_eff,
        identified: significant && tau <= 20.0 * duration && tau > tau_lo * 1.01,
    })
}

/// Golden-section minimum of `f` on `[a, b]`.
fn golden_min(mut a: f64, mut b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let g = 0.618_033_988_749_895;
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..40 {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = f(x2);
        }
    }
    0.5 * (a + b)
}

/// Time constants fitted side by side by [`Blocks::rss_lanes`].
const LANES: usize = 8;

/// A record as means of consecutive blocks of `w` samples, and the
/// discharge model averaged the same way.
struct Blocks {
    s: Vec<f64>,
    /// Mean of `s` (every fit uses it).
    s_mean: f64,
    /// Block width, s.
    dt: f64,
    /// `1 / (fs)`, s, and samples per block.
    fs: f64,
    w: usize,
}

impl Blocks {
    fn new(y: &[f64], fs: f64, w: usize) -> Self {
        let s = y
            .chunks_exact(w)
            .map(|c| c.iter().sum::<f64>() / w as f64)
            .collect::<Vec<f64>>();
        Self::of_means(s, fs, w)
    }

    fn of_means(s: Vec<f64>, fs: f64, w: usize) -> Self {
        Self {
            s_mean: s.iter().sum::<f64>() / s.len() as f64,
            s,
            dt: w as f64 / fs,
            fs,
            w,
        }
    }

    /// `e^{-t/τ}` averaged over each block.
    /// With its sum, accumulated as it is made (in the order and from the
    /// `-0.0` of `Iterator::sum`).
    fn basis_and_sum(&self, tau: f64) -> (Vec<f64>, f64) {
        let a = 1.0 / (self.fs * tau);
        let wf = self.w as f64;
        // mean_{j<w} e^{-a j} = (1 - e^{-a w}) / (w (1 - e^{-a})), via expm1.
        let g = if a * wf < 1e-12 {
            1.0
        } else {
            (-a * wf).exp_m1() / (wf * (-a).exp_m1())
        };
        let r = (-a * wf).exp();
        let mut v = g;
        let mut sum = -0.0;
        let b = self
            .s
            .iter()
            .map(|_| {
                let out = v;
                sum += out;
                v *= r;
                out
            })
            .collect();
        (b, sum)
    }

    /// Least squares of `s = c + A b_τ`: `(c, A, RSS)`.
    fn fit(&self, tau: f64) -> (f64, f64, f64) {
        let (b, sum_b) = self.basis_and_sum(tau);
        let m = b.len() as f64;
        let (mb, ms) = (sum_b / m, self.s_mean);
        let (mut sbb, mut sbs) = (0.0, 0.0);
        for (bi, si) in b.iter().zip(&self.s) {
            sbb += (bi - mb) * (bi - mb);
            sbs += (bi - mb) * (si - ms);
        }
        let a = if sbb > 0.0 { sbs / sbb } else { 0.0 };
        let c = ms - a * mb;
        let rss = b
            .iter()
            .zip(&self.s)
            .map(|(bi, si)| (si - c - a * bi).powi(2))
            .sum();
        (c, a, rss)
    }

    /// The RSS of [`Blocks::fit`] at each of `taus`, the same bits: the
    /// fits run [`LANES`] at a time in lock step (each lane does one fit's
    /// operations in its order, so the serial sums interleave instead of
    /// waiting on each other), the groups in parallel (rayon), in order.
    fn profile(&self, taus: &[f64]) -> Vec<f64> {
        taus.par_chunks(LANES)
            .flat_map_iter(|group| {
                let mut t = [f64::NAN; LANES];
                t[..group.len()].copy_from_slice(group);
                self.rss_lanes(t).into_iter().take(group.len())
            })
            .collect()
    }

    /// [`Blocks::fit`]'s RSS for [`LANES`] time constants, lane by lane the
    /// operations of [`Blocks::basis_and_sum`] and [`Blocks::fit`] in their
    /// order (tested bit for bit).
    fn rss_lanes(&self, taus: [f64; LANES]) -> [f64; LANES] {
        let wf = self.w as f64;
        let mut v = [0.0; LANES];
        let mut r = [0.0; LANES];
        for l in 0..LANES {
            let a = 1.0 / (self.fs * taus[l]);
            v[l] = if a * wf < 1e-12 {
                1.0
            } else {
                (-a * wf).exp_m1() / (wf * (-a).exp_m1())
            };
            r[l] = (-a * wf).exp();
        }
        let mut sum = [-0.0; LANES];
        let mut b = vec![[0.0; LANES]; self.s.len()];
        for out in b.iter_mut() {
            *out = v;
            sum = std::array::from_fn(|l| sum[l] + v[l]);
            v = std::array::from_fn(|l| v[l] * r[l]);
        }
        let m = b.len() as f64;
        let ms = self.s_mean;
        let mb = sum.map(|s| s / m);
        let (mut sbb, mut sbs) = ([0.0; LANES], [0.0; LANES]);
        for (bi, si) in b.iter().zip(&self.s) {
            let d: [f64; LANES] = std::array::from_fn(|l| bi[l] - mb[l]);
            sbb = std::array::from_fn(|l| sbb[l] + d[l] * d[l]);
            sbs = std::array::from_fn(|l| sbs[l] + d[l] * (si - ms));
        }
        let a: [f64; LANES] =
            std::array::from_fn(|l| if sbb[l] > 0.0 { sbs[l] / sbb[l] } else { 0.0 });
        let c: [f64; LANES] = std::array::from_fn(|l| ms - a[l] * mb[l]);
        let mut rss = [-0.0; LANES];
        for (bi, si) in b.iter().zip(&self.s) {
            rss = std::array::from_fn(|l| rss[l] + (si - c[l] - a[l] * bi[l]).powi(2));
        }
        rss
    }

    /// The matched-filter amplitude of a decay of `tau` starting at block
    /// `k0`, against the level `c`.
    fn local_amplitude(&self, k0: usize, len: usize, tau: f64, c: f64) -> f64 {
        let r = (-self.dt / tau).exp();
        let (mut num, mut den, mut e) = (0.0, 0.0, 1.0);
        for v in &self.s[k0..k0 + len] {
            num += e * (v - c);
            den += e * e;
            e *= r;
        }
        num / den
    }

    /// z of the start's matched-filter amplitude against the same statistic
    /// after the decay (needs 8 windows there), and the variance inflation
    /// of that statistic over white noise.
    fn null_test(&self, tau: f64, c: f64, amp: f64) -> (Option<f64>, f64) {
        let len = ((5.0 * tau / self.dt).ceil() as usize).max(5);
        let start = (8.0 * tau / self.dt).ceil() as usize;
        let hop = len.div_ceil(2);
        let m = self.s.len();
        if start + len > m {
            return (None, 1.0);
        }
        let null: Vec<f64> = (start..=m - len)
            .step_by(hop)
            .map(|k| self.local_amplitude(k, len, tau, c))
            .collect();
        if null.len() < 8 {
            return (None, 1.0);
        }
        let med = crate::stats::median(&null).unwrap_or(0.0);
        let sd = crate::stats::robust_sigma(&null).unwrap_or(0.0);
        // White-noise spread of the statistic from the residual variance
        // after the decay.
        let tail = &self.s[start..];
        let mt = tail.iter().sum::<f64>() / tail.len() as f64;
        let var = tail.iter().map(|v| (v - mt).powi(2)).sum::<f64>() / tail.len() as f64;
        let r = (-self.dt / tau).exp();
        let e2: f64 = (0..len).map(|i| r.powi(2 * i as i32)).sum();
        let white = (var / e2).sqrt();
        let inflation = if white > 0.0 {
            (sd / white).powi(2)
        } else {
            1.0
        };
        if sd <= 0.0 {
            return (Some(f64::INFINITY), inflation);
        }
        let a0 = self.local_amplitude(0, len, tau, c);
        let z = (a0 - med) / sd * amp.signum();
        (Some(z), inflation)
    }

    /// The same record as means over ball periods (at least 1/20 of the
    /// record).
    fn coarse(&self, period_s: f64) -> Blocks {
        let per = ((period_s / self.dt).round() as usize)
            .max(1)
            .min((self.s.len() / 20).max(1));
        let s: Vec<f64> = self
            .s
            .chunks_exact(per)
            .map(|c| c.iter().sum::<f64>() / per as f64)
            .collect();
        Blocks {
            s_mean: s.iter().sum::<f64>() / s.len() as f64,
            s,
            dt: self.dt * per as f64,
            fs: self.fs,
            w: self.w * per,
        }
    }
}

/// Undoes a first-order high-pass of time constant `tau_s` (module docs),
/// after removing the amplifier offset `offset`.
pub fn restore(y: &[f64], fs_hz: f64, tau_s: f64, offset: f64) -> Vec<f64> {
    let k = 0.5 / (fs_hz * tau_s);
    let mut out = Vec::with_capacity(y.len());
    let mut integral = 0.0;
    let mut prev = None;
    for &v in y {
        let u = v - offset;
        if let Some(p) = prev {
            integral += k * (p + u);
        }
        out.push(u + integral);
        prev = Some(u);
    }
    out
}

/// Applies `correction` to a friction channel: the friction to analyse and
/// what was done. `period_s` is the (predicted) ball-pass period.
///
/// # Errors
/// [`Error::InvalidSetting`] for an invalid given time constant.
pub fn restore_friction<'a>(
    y: &'a [f64],
    fs_hz: f64,
    period_s: f64,
    correction: LoadCellCorrection,
) -> Result<(Cow<'a, [f64]>, DcRestoration)> {
    correction.validate()?;
    let level_over_spread = {
        let m = crate::stats::MeanStd::of(y);
        m.map_or(0.0, |m| {
            if m.std > 0.0 {
                m.mean / m.std
            } else {
                f64::INFINITY
            }
        })
    };
    let decision = match correction {
        LoadCellCorrection::Off => Decision::Off,
        LoadCellCorrection::TimeConstant(tau) => Decision::Given {
            tau,
            // The amplifier offset: the level a decay of this τ tends to.
            offset: offset_for(y, fs_hz, tau),
        },
        LoadCellCorrection::Auto => Decision::Auto(fit_discharge(y, fs_hz, period_s)),
    };
    let (undo, d) = decide(decision, level_over_spread);
    Ok(match undo {
        Some((tau, offset)) => (Cow::Owned(restore(y, fs_hz, tau, offset)), d),
        None => (Cow::Borrowed(y), d),
    })
}

/// What [`restore_friction`] found out before restoring.
pub(crate) enum Decision {
    /// Restoration off.
    Off,
    /// τ given; `offset` the amplifier offset for it.
    Given { tau: f64, offset: f64 },
    /// τ estimated (`None`: too short to fit).
    Auto(Option<DischargeFit>),
}

/// The `(τ, offset)` to undo (if any) and what was done, from a
/// [`Decision`] and the recording's mean over its standard deviation.
pub(crate) fn decide(
    decision: Decision,
    level_over_spread: f64,
) -> (Option<(f64, f64)>, DcRestoration) {
    let unchanged = |fit: Option<DischargeFit>, note: String, auto: bool| DcRestoration {
        applied: false,
        tau_s: None,
        source: "none".into(),
        fit,
        level_over_spread,
        unknown_high_pass: auto && level_over_spread.abs() < 3.0,
        note,
    };
    match decision {
        Decision::Off => (
            None,
            unchanged(
                None,
                "load-cell DC restoration off: friction analysed as recorded".into(),
                false,
            ),
        ),
        Decision::Given { tau, offset } => (
            Some((tau, offset)),
            DcRestoration {
                applied: true,
                tau_s: Some(tau),
                source: "given".into(),
                fit: None,
                level_over_spread,
                unknown_high_pass: false,
                note: format!("load-cell discharge undone with the given τ = {tau:.3} s"),
            },
        ),
        Decision::Auto(fit) => match fit {
            Some(f) if f.identified => {
                let note = format!(
                    "load-cell discharge undone: τ = {:.3} s (95 % interval {:.3}–{:.3} s), estimated from the record's decay of {:+.3} N",
                    f.tau_s,
                    f.tau_low_s,
                    f.tau_high_s.unwrap_or(f.tau_s),
                    f.amplitude_n
                );
                (
                    Some((f.tau_s, f.offset_n)),
                    DcRestoration {
                        applied: true,
                        tau_s: Some(f.tau_s),
                        source: "estimated".into(),
                        fit: Some(f),
                        level_over_spread,
                        unknown_high_pass: false,
                        note,
                    },
                )
            }
            other => {
                let note = "no load-cell decay identified in the record (a DC-coupled sensor, a discharge over before the record, or one too slow to tell from a trend): friction analysed as recorded; give the load cell's τ if it discharges".to_string();
                (None, unchanged(other, note, true))
            }
        },
    }
}

/// The level `c` of the least-squares fit `y = c + A e^{-t/τ}` with `τ`
/// given (every 10th sample).
fn offset_for(y: &[f64], fs_hz: f64, tau: f64) -> f64 {
    let pts: Vec<(f64, f64)> = y
        .iter()
        .enumerate()
        .step_by(10)
        .map(|(i, &v)| ((-(i as f64) / (fs_hz * tau)).exp(), v))
        .collect();
    let m = pts.len() as f64;
    let (mb, ms) = (
        pts.iter().map(|p| p.0).sum::<f64>() / m,
        pts.iter().map(|p| p.1).sum::<f64>() / m,
    );
    let (mut sbb, mut sbs) = (0.0, 0.0);
    for (b, s) in &pts {
        sbb += (b - mb) * (b - mb);
        sbs += (b - mb) * (s - ms);
    }
    let a = if sbb > 0.0 { sbs / sbb } else { 0.0 };
    ms - a * mb
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{simulate, SimSettings};

    /// The discrete inverse undoes the simulator's high-pass of a step: a
    /// constant 3 N through τ = 2 s comes back flat to 1e-4 N (trapezoidal
    /// rule at 1 kHz against the exact discretisation at 20 kHz).
    #[test]
    fn restore_undoes_a_high_pass() {
        let (fs, tau) = (1000.0, 2.0);
        let y: Vec<f64> = (0..20_000)
            .map(|i| 3.0 * (-(i as f64) / fs / tau).exp())
            .collect();
        let x = restore(&y, fs, tau, 0.0);
        for v in x.iter().step_by(997) {
            assert!((v - 3.0).abs() < 1e-4, "{v}");
        }
    }

    /// The lock-step profile gives every fit's RSS bit for bit, over a
    /// group left incomplete (11 time constants: 8 + 3), on fine and
    /// coarse blocks of a decaying, rippled record.
    #[test]
    fn profile_equals_the_fits_bit_for_bit() {
        let fs = 1000.0;
        let y: Vec<f64> = (0..12_000)
            .map(|i| {
                let t = i as f64 / fs;
                1.5 * (-t / 0.8).exp()
                    + 0.2
                    + 0.05 * (7.0 * t).sin()
                    + 1e-3 * ((i * 37 % 101) as f64)
            })
            .collect();
        let blocks = Blocks::new(&y, fs, 20);
        let taus: Vec<f64> = (0..11).map(|k| 0.05 * 1.7f64.powi(k)).collect();
        for b in [&blocks, &blocks.coarse(0.3)] {
            let lanes = b.profile(&taus);
            assert_eq!(lanes.len(), taus.len());
            for (t, rss) in taus.iter().zip(&lanes) {
                assert_eq!(rss.to_bits(), b.fit(*t).2.to_bits(), "τ {t}");
            }
        }
    }

    /// On simulated records the estimated τ's interval holds the truth, and
    /// a DC-coupled sensor shows no decay.
    #[test]
    fn the_simulated_discharge_is_identified() {
        for (tau, settle, v) in [(0.5, 0.5, 2.0), (10.0, 4.0, 9.0), (3.0, 1.0, 20.0)] {
            let mut s = SimSettings::for_bearing("sr25w", v).unwrap();
            s.load_cell.time_constant_s = Some(tau);
            s.motion.settle_time_s = Some(settle);
            s.duration_s = 60.0;
            let sim = simulate(&s).unwrap();
            let y = sim
                .recording
                .channel(crate::recording::Channel::Friction)
                .unwrap();
            let f = fit_discharge(y, s.fs_hz, sim.truth.tau_c_nominal_s).unwrap();
            assert!(f.identified, "τ {tau}: {f:?}");
            assert!(
                f.tau_low_s <= tau && f.tau_high_s.unwrap() >= tau,
                "τ {tau}: {f:?}"
            );
        }
        let mut s = SimSettings::default();
        s.load_cell.time_constant_s = None;
        let sim = simulate(&s).unwrap();
        let y = sim
            .recording
            .channel(crate::recording::Channel::Friction)
            .unwrap();
        let f = fit_discharge(y, s.fs_hz, sim.truth.tau_c_nominal_s).unwrap();
        assert!(!f.identified, "{f:?}");
    }
}
