//! The exact null tail of one coherence bin when one channel carries a line
//! and the other only noise (module docs of [`super`]).
//!
//! With the line's channel fixed, the coherence of a bin is
//! `C = |uᴴY|² / (YᴴY)`: `Y` holds the noise channel's `K` segment DFTs at
//! the bin, `u` the line's unit phasor sequence. Noise that is flat over
//! the window's bandwidth gives `Y` complex Gaussian with covariance `Σ`,
//! `Σ[i, i+m] = c(m) e^{i m θ}` (`c(m)` the window's overlap correlation,
//! `θ = 2π δ · step / nperseg` turning it by the line's offset `δ` from the
//! bin). `C > c` is `Yᴴ(uuᴴ − c I)Y > 0`, a quadratic form in Gaussians
//! whose matrix `(uuᴴ − c I)Σ` has one positive eigenvalue `λ₁` and `K − 1`
//! negative ones `λ_k`, so
//!
//! ```text
//! P(C > c) = Π_{k≥2} λ₁ / (λ₁ − λ_k) = λ₁^(K−1) / p'(λ₁),
//! ```
//!
//! `p` the characteristic polynomial. With `A = λ I + c Σ`, the matrix
//! determinant lemma gives `p(λ) = det A · (1 − f(λ))`,
//! `f(λ) = uᴴ Σ A⁻¹ u`, so `λ₁` solves `f(λ) = 1` and
//! `p'(λ₁) = det A · uᴴ Σ A⁻² u`. `Σ` is banded (segments overlap only so
//! far), so one banded Cholesky factor of `A` gives `det A`, `A⁻¹u` and
//! both quadratic forms in `O(K)`. Independent segments (`Σ = I`) give
//! `λ₁ = 1 − c`, `det A = 1` and Carter's `(1 − c)^(K−1)`. `R` averaged
//! records are `R` independent blocks with the same `Σ`: `f` is the same,
//! `det A` is raised to `R` and `λ₁` to `RK − 1`.

use ballpass_dsp::Complex64;

/// Segments per record above which [`line_tail`] is replaced by Carter's
/// tail at the line's equivalent count (module docs of [`super`]).
pub(crate) const EXACT_MAX_SEGMENTS: usize = 512;

/// `c(m) = Σ_t w[t] w[t + m·step] / Σ_t w[t]²` for `m = 1, 2, …` while the
/// segments overlap (`m · step < w.len()`), at most `k − 1` of them.
pub(crate) fn overlap_correlations(w: &[f64], step: usize, k: usize) -> Vec<f64> {
    let e: f64 = w.iter().map(|v| v * v).sum();
    (1..k)
        .map_while(|m| {
            let shift = m * step;
            (step > 0 && shift < w.len())
                .then(|| w[shift..].iter().zip(w).map(|(a, b)| a * b).sum::<f64>() / e)
        })
        .collect()
}

/// What one evaluation at `λ` gives: `f(λ) = uᴴΣA⁻¹u`,
/// `g(λ) = uᴴΣA⁻²u` and `ln det A` (per record).
struct AtLambda {
    f: f64,
    g: f64,
    log_det: f64,
}

/// `A = λ I + c Σ` factored by a banded Cholesky `A = L Lᴴ` (`L` stored
/// row by row over its band), then `v = A⁻¹ 1`: `s = 1ᴴv`, `q = vᴴv`;
/// with `u = 1/√K` (the line's phasor divided out of `Y`),
/// `ΣA⁻¹ = (I − λA⁻¹)/c` gives `f = (1 − λ s/K)/c` and
/// `g = (s − λ q)/(c K)`.
fn at_lambda(corr: &[f64], k: usize, theta: f64, c: f64, lambda: f64) -> Option<AtLambda> {
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
/// [`overlap_correlations`]. `None` where the factorisation fails (a
/// window whose overlap matrix is not positive definite).
pub(crate) fn line_tail(corr: &[f64], k: usize, records: usize, theta: f64, c: f64) -> Option<f64> {
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

#[cfg(test)]
mod tests {
    use super::super::tests::hann;
    use super::*;

    /// Independent segments: Carter's `(1 − c)^(RK − 1)` exactly (up to
    /// rounding of the Newton root, 1e-12 relative).
    #[test]
    fn independent_segments_give_carters_tail() {
        for (k, r, c) in [
            (1usize, 1usize, 0.3),
            (1, 4, 0.3),
            (5, 1, 0.2),
            (12, 3, 0.05),
        ] {
            let got = line_tail(&[], k, r, 0.7, c).unwrap();
            let want = (1.0 - c).powi((r * k) as i32 - 1);
            assert!(
                (got - want).abs() <= 1e-12 * want,
                "{k} {r} {c}: {got} vs {want}"
            );
        }
    }

    /// Against the eigenvalues: `Π_{k≥2} 1/(1 − λ_k/λ₁)` of
    /// `Σ^{1/2}(uuᴴ − c I)Σ^{1/2}`, computed with NumPy/SciPy
    /// (`scipy.linalg.sqrtm`, `numpy.linalg.eigvalsh`) for periodic Hann 64
    /// at 50 % (`c(1) = 1/6`); the Newton root is good to ~1e-14, the
    /// product to ~1e-13 relative, so 1e-9 relative is loose.
    #[test]
    fn hann_half_overlap_matches_the_eigenvalue_product() {
        let w = hann(64);
        let corr = overlap_correlations(&w, 32, 1000);
        assert_eq!(corr.len(), 1);
        assert!((corr[0] - 1.0 / 6.0).abs() < 1e-15);
        let theta = |d: f64| std::f64::consts::TAU * d * 32.0 / 64.0;
        for (k, d, c, want) in [
            (3usize, 0.0, 0.5, 0.33591731886302856),
            (3, 0.3, 0.8, 0.05430081625949151),
            (3, 1.0, 0.5, 0.16960746924576292),
            (12, 0.0, 0.5, 0.0022900910943811693),
            (12, 0.5, 0.8, 2.4166584107014692e-08),
            (12, 1.0, 0.8, 6.574576055550028e-10),
        ] {
            let got = line_tail(&corr, k, 1, theta(d), c).unwrap();
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "K={k} δ={d} c={c}: {got} vs {want}"
            );
        }
    }
}
