//! Session 19's calibrated coherence level, kept unchanged as the
//! reference the faster one of session 20 is tested against (a banded
//! Cholesky factor over all `K` rows per trial `λ`, Newton from `λ = 0`,
//! a fresh start for every trial level; see [`super::line_tail`]).

use super::SpectrumInfo;
use ballpass_dsp::Complex64;
use std::f64::consts::TAU;

/// What one evaluation at `λ` gives: `f(λ) = uᴴΣA⁻¹u`,
/// `g(λ) = uᴴΣA⁻²u` and `ln det A` (per record).
pub(super) struct AtLambda {
    pub(super) f: f64,
    pub(super) g: f64,
    pub(super) log_det: f64,
}

/// `A = λ I + c Σ` factored by a banded Cholesky `A = L Lᴴ` (`L` stored
/// row by row over its band), then `v = A⁻¹ 1`: `s = 1ᴴv`, `q = vᴴv`;
/// with `u = 1/√K` (the line's phasor divided out of `Y`),
/// `ΣA⁻¹ = (I − λA⁻¹)/c` gives `f = (1 − λ s/K)/c` and
/// `g = (s − λ q)/(c K)`.
pub(super) fn at_lambda(
    corr: &[f64],
    k: usize,
    theta: f64,
    c: f64,
    lambda: f64,
) -> Option<AtLambda> {
    let b = corr.len().min(k.saturating_sub(1));
    // Sub-diagonal m of A: c · c(m) e^{−i m θ} (A[i][i−m]); its conjugate above.
    let sub: Vec<Complex64> = (1..=b)
        .map(|m| Complex64::from_polar(c * corr[m - 1], -(m as f64) * theta))
        .collect();
    let diag = lambda + c;
    // l[i][p] for column j = i − b + p (p = 0..=b); the diagonal at p = b.
    let mut l = vec![Complex64::new(0.0, 0.0); k * (b + 1)];
    let at = |i: usize, j: usize| i * (b + 1) + (b + j - i);
    let mut log_det = 0.0;
    for i in 0..k {
        let j0 = i.saturating_sub(b);
        for j in j0..=i {
            let mut s = if i == j {
                Complex64::new(diag, 0.0)
            } else {
                sub[i - j - 1]
            };
            for p in j0.max(j.saturating_sub(b))..j {
                s -= l[at(i, p)] * l[at(j, p)].conj();
            }
            if i == j {
                if s.re.is_nan() || s.re <= 0.0 {
                    return None;
                }
                let d = s.re.sqrt();
                log_det += 2.0 * d.ln();
                l[at(i, i)] = Complex64::new(d, 0.0);
            } else {
                l[at(i, j)] = s / l[at(j, j)].re;
            }
        }
    }
    // L y = 1.
    let mut y = vec![Complex64::new(0.0, 0.0); k];
    for i in 0..k {
        let mut s = Complex64::new(1.0, 0.0);
        for p in i.saturating_sub(b)..i {
            s -= l[at(i, p)] * y[p];
        }
        y[i] = s / l[at(i, i)].re;
    }
    // Lᴴ v = y.
    let mut v = y;
    for i in (0..k).rev() {
        let mut s = v[i];
        for r in (i + 1)..(i + b + 1).min(k) {
            s -= l[at(r, i)].conj() * v[r];
        }
        v[i] = s / l[at(i, i)].re;
    }
    let s: f64 = v.iter().map(|z| z.re).sum();
    let q: f64 = v.iter().map(|z| z.norm_sqr()).sum();
    let kf = k as f64;
    Some(AtLambda {
        f: (1.0 - lambda * s / kf) / c,
        g: (s - lambda * q) / (c * kf),
        log_det,
    })
}

/// `P(C > c)` for a bin of `k` segments per record averaged over `records`
/// records, noise in one channel and a line in the other `theta` radians
/// per segment step off the bin (module docs); `corr` from
/// [`super::line_tail::overlap_correlations`]. `None` where the factorisation fails (a
/// window whose overlap matrix is not positive definite).
pub(super) fn line_tail(corr: &[f64], k: usize, records: usize, theta: f64, c: f64) -> Option<f64> {
    if k == 0 || records == 0 {
        return None;
    }
    if c <= 0.0 {
        return Some(1.0);
    }
    if c >= 1.0 {
        return Some(0.0);
    }
    // f is a sum of |α|² μ / (λ + c μ) over Σ's eigenpairs: decreasing and
    // convex in λ > 0, with f(0) = 1/c > 1. Newton from λ = 0 approaches
    // the root from below without overshooting it.
    let mut lambda = 0.0;
    let mut e = at_lambda(corr, k, theta, c, lambda)?;
    for _ in 0..200 {
        let step = (e.f - 1.0) / e.g;
        if !(step.is_finite() && step >= 0.0) {
            break;
        }
        lambda += step;
        e = at_lambda(corr, k, theta, c, lambda)?;
        if step <= 1e-15 * lambda {
            break;
        }
    }
    if !(lambda > 0.0 && e.g > 0.0) {
        return None;
    }
    let n = (records * k) as f64;
    let log_p = (n - 1.0) * lambda.ln() - records as f64 * e.log_det - e.g.ln();
    Some(log_p.exp().clamp(0.0, 1.0))
}

/// Session 19's row level (see [`super::coherence_row_level`]).
pub(super) fn coherence_row_level(
    info: &SpectrumInfo,
    w: &[f64],
    offset_bins: f64,
    confidence: f64,
) -> Option<f64> {
    let a = super::coherence_row_rate(confidence);
    let n_power = 0.5 * info.dof;
    if !(n_power > 1.0 && a > 0.0 && a < 1.0 && w.len() == info.nperseg) {
        return None;
    }
    let step = info.nperseg.checked_sub(info.noverlap).filter(|&s| s > 0);
    let k = info.n_segments.max(1);
    let r = info.n_records.max(1);
    let corr = step.map(|st| super::line_tail::overlap_correlations(w, st, k));
    let turn = |d: f64| step.map_or(0.0, |st| TAU * d * st as f64 / info.nperseg as f64);
    let exact = k <= super::line_tail::EXACT_MAX_SEGMENTS;
    // Per bin: ln of its tail at x = ln(1 − c).
    let bins: Vec<(f64, f64)> = [offset_bins + 1.0, offset_bins, offset_bins - 1.0]
        .iter()
        .map(|&d| {
            let n_line = match step {
                Some(st) => {
                    r as f64 * crate::analysis::phase::line_segments_turned(w, st, k, turn(d))
                }
                None => n_power,
            };
            (d, n_line)
        })
        .collect();
    let tail = |x: f64| -> f64 {
        let c = -x.exp_m1();
        bins.iter()
            .map(|&(d, n_line)| {
                let noise = ((n_power - 1.0) * x).exp();
                let line = match (&corr, exact) {
                    (Some(corr), true) => line_tail(corr, k, r, turn(d), c)
                        .unwrap_or_else(|| ((n_line - 1.0) * x).exp()),
                    _ => ((n_line.max(1.0) - 1.0) * x).exp(),
                };
                noise.max(line)
            })
            .sum()
    };
    // The same root search as the product's (only the tails differ).
    super::level_of_tail(tail, a, n_power)
}
