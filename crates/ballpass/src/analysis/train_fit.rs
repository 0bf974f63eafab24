//! Residuals and analytic Jacobians of the two pulse-train models fitted by
//! [`crate::analysis::passage`], solved with [`ballpass_dsp::least_squares`].
//!
//! ```text
//! Gaussian (Eq. 6.24), θ = [S, t0, τ, σ, P_0 … P_{K−1}]:
//!   s_g(t) = S + Σ_j P_j exp(−u_j² / 2),   u_j = (t − t0 − j τ) / σ
//!   ∂/∂S = 1   ∂/∂P_j = e_j   ∂/∂t0 = Σ P_j e_j u_j / σ
//!   ∂/∂τ = Σ j P_j e_j u_j / σ   ∂/∂σ = Σ P_j e_j u_j² / σ
//! Rectangular of order N (Eq. 6.22, docs/methods.md §5), θ = [S, P, t_s, τ, r]:
//!   s_r(t) = S + P r + Σ_{n=1}^{N} (2P / nπ) sin(nπ r) cos(n φ),   φ = π (2 (t − t_s) / τ + r)
//!   A = ∂(Σ)/∂φ = −(2P/π) Σ sin(nπ r) sin(n φ)
//!   ∂/∂S = 1   ∂/∂P = r + (2/π) Σ sin(nπ r) cos(nφ) / n
//!   ∂/∂t_s = −2π A / τ   ∂/∂τ = −2π (t − t_s) A / τ²
//!   ∂/∂r = P + 2P Σ cos(nπ r) cos(nφ) + π A
//! ```
//!
//! Each sample of the Gaussian train sees only the pulses within 12 σ of it
//! (the rest contribute below 1e-31 of a pulse), so each Jacobian row has at
//! most a handful of non-zero entries and `JᵀJ` costs `O(m)`.

use ballpass_dsp::{least_squares, FnProblem, LeastSquares, Termination};

/// Reach of a Gaussian pulse, sigmas: `exp(−72)` ≈ 5e-32 beyond it.
const REACH_SIGMAS: f64 = 12.0;
/// Index of the first Gaussian amplitude in θ.
pub(crate) const G_AMP0: usize = 4;

/// Range of pulse indices `lo..hi` within reach of time `t`.
fn pulses_near(t: f64, t0: f64, tau: f64, sig: f64, k: usize) -> (usize, usize) {
    let tau = if tau.abs() > 1e-300 { tau } else { 1e-300 };
    let jc = ((t - t0) / tau).round();
    let reach = (REACH_SIGMAS * sig / tau.abs()).ceil() + 1.0;
    let lo = (jc - reach).clamp(0.0, k as f64) as usize;
    let hi = (jc + reach + 1.0).clamp(0.0, k as f64) as usize;
    (lo, hi)
}

/// Value of the Gaussian train `θ` at `t` (see the module docs).
pub(crate) fn gaussian_value(th: &[f64], t: f64) -> f64 {
    let (s, t0, tau, sig) = (th[0], th[1], th[2], th[3].abs().max(1e-300));
    let amps = &th[G_AMP0..];
    let (lo, hi) = pulses_near(t, t0, tau, sig, amps.len());
    s + (lo..hi)
        .map(|j| {
            let u = (t - t0 - j as f64 * tau) / sig;
            amps[j] * (-0.5 * u * u).exp()
        })
        .sum::<f64>()
}

/// Value of the rectangular train `θ = [S, P, t_s, τ, r]` of order `order` at `t`.
pub(crate) fn rectangular_value(th: &[f64], order: usize, t: f64) -> f64 {
    rect_terms(th, order, t).0
}

/// `(value, ∂/∂P, A, ∂/∂r explicit part)` of the rectangular train at `t`.
fn rect_terms(th: &[f64], order: usize, t: f64) -> (f64, f64, f64, f64) {
    use std::f64::consts::PI;
    let (s, p, ts, tau, r) = (th[0], th[1], th[2], th[3], th[4]);
    let phi = PI * (2.0 * (t - ts) / tau + r);
    // e^{j n φ} and e^{j n π r} by rotation.
    let (sp, cp) = phi.sin_cos();
    let (sr, cr) = (PI * r).sin_cos();
    let (mut c_n, mut s_n) = (cp, sp);
    let (mut cr_n, mut sr_n) = (cr, sr);
    let (mut sum_cos_n, mut sum_sin, mut sum_cos) = (0.0, 0.0, 0.0);
    for n in 1..=order {
        let nf = n as f64;
        sum_cos_n += sr_n * c_n / nf;
        sum_sin += sr_n * s_n;
        sum_cos += cr_n * c_n;
        (c_n, s_n) = (c_n * cp - s_n * sp, s_n * cp + c_n * sp);
        (cr_n, sr_n) = (cr_n * cr - sr_n * sr, sr_n * cr + cr_n * sr);
    }
    let dp = r + 2.0 / PI * sum_cos_n;
    let value = s + p * dp;
    let a = -2.0 * p / PI * sum_sin;
    let dr = p + 2.0 * p * sum_cos;
    (value, dp, a, dr)
}

/// Writes `∂s_g(t)/∂θ` into `row` (zero on entry; only the pulses within
/// reach of `t` are written).
fn gaussian_jacobian_row(th: &[f64], t: f64, row: &mut [f64]) {
    let (t0, tau, sig_raw) = (th[1], th[2], th[3]);
    let sig = sig_raw.abs().max(1e-300);
    let sign = if sig_raw < 0.0 { -1.0 } else { 1.0 };
    let amps = &th[G_AMP0..];
    row[0] = 1.0;
    let (lo, hi) = pulses_near(t, t0, tau, sig, amps.len());
    let (mut dt0, mut dtau, mut dsig) = (0.0, 0.0, 0.0);
    for j in lo..hi {
        let u = (t - t0 - j as f64 * tau) / sig;
        let e = (-0.5 * u * u).exp();
        row[G_AMP0 + j] = e;
        let g = amps[j] * e * u / sig;
        dt0 += g;
        dtau += g * j as f64;
        dsig += g * u;
    }
    row[1] = dt0;
    row[2] = dtau;
    row[3] = dsig * sign;
}

/// Writes `∂s_r(t)/∂θ` into `row` (length 5).
fn rectangular_jacobian_row(th: &[f64], order: usize, t: f64, row: &mut [f64]) {
    use std::f64::consts::PI;
    let (ts, tau) = (th[2], th[3]);
    let (_, dp, a, dr) = rect_terms(th, order, t);
    row[0] = 1.0;
    row[1] = dp;
    row[2] = -2.0 * PI * a / tau;
    row[3] = -2.0 * PI * (t - ts) * a / (tau * tau);
    row[4] = dr + PI * a;
}

/// Outcome of one fit.
pub(crate) struct Solved {
    pub params: Vec<f64>,
    pub residuals: Vec<f64>,
    pub iterations: usize,
    pub converged: bool,
}

fn converged(t: Termination) -> bool {
    !matches!(t, Termination::MaxIterations)
}

fn solver() -> LeastSquares {
    LeastSquares {
        max_iterations: 100,
        ..LeastSquares::default()
    }
}

/// Minimises the `m` residuals `resid` with the analytic Jacobian `jac`
/// from `th0`, and returns the fit with its residuals.
fn solve(
    m: usize,
    th0: &[f64],
    resid: impl Fn(&[f64], &mut [f64]),
    jac: impl Fn(&[f64], &mut [f64]),
) -> ballpass_dsp::Result<Solved> {
    let problem = FnProblem::with_jacobian(m, &resid, jac);
    let fit = least_squares(&problem, th0, &solver())?;
    let mut r = vec![0.0; m];
    resid(&fit.params, &mut r);
    Ok(Solved {
        params: fit.params,
        residuals: r,
        iterations: fit.iterations,
        converged: converged(fit.termination),
    })
}

/// Fits the Gaussian train to samples `(t, d)` from `th0`.
pub(crate) fn fit_gaussian(t: &[f64], d: &[f64], th0: &[f64]) -> ballpass_dsp::Result<Solved> {
    let m = t.len();
    let n = th0.len();
    let resid = |th: &[f64], r: &mut [f64]| {
        for i in 0..m {
            r[i] = gaussian_value(th, t[i]) - d[i];
        }
    };
    let jac = |th: &[f64], jm: &mut [f64]| {
        for (i, row) in jm.chunks_exact_mut(n).enumerate() {
            gaussian_jacobian_row(th, t[i], row);
        }
    };
    solve(m, th0, resid, jac)
}

/// Fits the rectangular train of order `order` to samples `(t, d)` from `th0`.
pub(crate) fn fit_rectangular(
    t: &[f64],
    d: &[f64],
    th0: &[f64; 5],
    order: usize,
) -> ballpass_dsp::Result<Solved> {
    let m = t.len();
    let resid = |th: &[f64], r: &mut [f64]| {
        for i in 0..m {
            r[i] = rectangular_value(th, order, t[i]) - d[i];
        }
    };
    let jac = |th: &[f64], jm: &mut [f64]| {
        for (i, row) in jm.chunks_exact_mut(5).enumerate() {
            rectangular_jacobian_row(th, order, t[i], row);
        }
    };
    solve(m, th0, resid, jac)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central differences of `f` in each parameter, as a reference Jacobian row.
    fn numeric_row(f: impl Fn(&[f64]) -> f64, th: &[f64]) -> Vec<f64> {
        (0..th.len())
            .map(|j| {
                let h = 1e-6 * th[j].abs().max(1e-3);
                let mut a = th.to_vec();
                let mut b = th.to_vec();
                a[j] += h;
                b[j] -= h;
                (f(&a) - f(&b)) / (2.0 * h)
            })
            .collect()
    }

    #[test]
    fn analytic_jacobians_match_central_differences() {
        // Tolerance 1e-6 relative to the row's largest entry: central
        // differences with h = 1e-6 |θ| have truncation error ~h² · f''' and
        // rounding ~eps / h ≈ 2e-10 of the scale.
        let th = [0.1, 0.3, 0.8, 0.05, 0.5, 0.45, 0.55];
        let thr = [0.05, 0.5, 0.1, 0.8, 0.2];
        for i in 0..240 {
            let ti = i as f64 * 0.01;
            let mut row = vec![0.0; th.len()];
            gaussian_jacobian_row(&th, ti, &mut row);
            let mut row_r = vec![0.0; 5];
            rectangular_jacobian_row(&thr, 20, ti, &mut row_r);
            for (name, ana, num) in [
                ("gaussian", row, numeric_row(|p| gaussian_value(p, ti), &th)),
                (
                    "rectangular",
                    row_r,
                    numeric_row(|p| rectangular_value(p, 20, ti), &thr),
                ),
            ] {
                let scale = num.iter().fold(1e-12f64, |a, v| a.max(v.abs()));
                for j in 0..num.len() {
                    assert!(
                        (ana[j] - num[j]).abs() <= 1e-6 * scale,
                        "{name} t={ti} j={j}: {} vs {}",
                        ana[j],
                        num[j]
                    );
                }
            }
        }
    }

    #[test]
    fn rectangular_value_matches_the_model_partial_sum() {
        // Same series as model::pulse_train (Eq. 6.22 corrected), shifted by
        // t_s: agreement to rounding (1e-12 of the amplitude).
        let train = crate::model::pulse_train::RectangularTrain::new(0.8, 0.2, 0.5, 0.05).unwrap();
        for i in 0..200 {
            let t = i as f64 * 0.013;
            let a = rectangular_value(&[0.05, 0.5, 0.0, 0.8, 0.2], 20, t);
            let b = train.partial_sum(t, 20);
            assert!((a - b).abs() < 1e-12, "t={t}: {a} vs {b}");
        }
    }

    #[test]
    fn fits_recover_noise_free_trains() {
        // Noise-free data from the model itself: the fit must return the
        // generating parameters to 1e-6 relative (LM tolerances 1e-8).
        let t: Vec<f64> = (0..2000).map(|i| i as f64 * 0.002).collect();
        let truth = [0.02, 0.31, 0.8, 0.052, 0.5, 0.47, 0.53, 0.5, 0.49];
        let d: Vec<f64> = t.iter().map(|&x| gaussian_value(&truth, x)).collect();
        let start = [0.0, 0.30, 0.79, 0.06, 0.45, 0.45, 0.45, 0.45, 0.45];
        let g = fit_gaussian(&t, &d, &start).unwrap();
        assert!(g.converged);
        for (a, b) in g.params.iter().zip(&truth) {
            assert!((a - b).abs() <= 1e-6 * b.abs().max(0.1), "{a} vs {b}");
        }
        let truth_r = [0.05, 0.5, 0.1, 0.8, 0.2];
        let d: Vec<f64> = t
            .iter()
            .map(|&x| rectangular_value(&truth_r, 10, x))
            .collect();
        let r = fit_rectangular(&t, &d, &[0.0, 0.45, 0.11, 0.79, 0.18], 10).unwrap();
        for (a, b) in r.params.iter().zip(&truth_r) {
            assert!((a - b).abs() <= 1e-6 * b.abs().max(0.1), "{a} vs {b}");
        }
    }
}
