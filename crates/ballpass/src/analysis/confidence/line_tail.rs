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
//! both quadratic forms in `O(K)`, and fewer rows than that suffice
//! (the factor's rows converge: [`LineTail`]). Independent segments (`Σ = I`) give
//! `λ₁ = 1 − c`, `det A = 1` and Carter's `(1 − c)^(K−1)`. `R` averaged
//! records are `R` independent blocks with the same `Σ`: `f` is the same,
//! `det A` is raised to `R` and `λ₁` to `RK − 1`.

use ballpass_dsp::Complex64;

/// Segments per record above which [`LineTail`] is replaced by Carter's
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
#[derive(Debug, Clone, Copy)]
struct AtLambda {
    f: f64,
    g: f64,
    log_det: f64,
}

/// Newton stops once a step is below this fraction of `λ`: `f` is convex
/// and decreasing, so the root's error after a step of `s` is at most
/// `s²/λ` (`f''/|f'| ≤ 2/λ` for a sum of `μ/(λ + cμ)`), below 1e-18 of `λ`
/// here, far under rounding.
const NEWTON_STEP_TOL: f64 = 1e-9;

/// The exact tail of one bin (module docs) as a function of the level
/// `c`, for one window overlap, segment count and offset. It keeps the
/// last root `λ₁` so that the next level's Newton iteration starts next to
/// its root (a root search over `c` asks for many nearby levels), and its
/// work space, so that no evaluation allocates.
///
/// `A = λ I + c Σ` is a banded Hermitian Toeplitz matrix, so the rows of
/// its Cholesky factor converge to a fixed row a few band-widths in (the
/// factor of the infinite matrix), the solution of `L y = 1` converges to a
/// constant after them, and that of `Lᴴ v = y` is constant from there up
/// to a few band-widths before its end. Each converges to a fixed point in
/// floating point too: once the last `b + 1` rows (or values) are equal to
/// the bit, every later one is computed from the same numbers by the same
/// operations and is equal to the bit as well. [`Self::at_lambda`] stops
/// at that point and counts the rest, so it computes the same factor and
/// solution as a factorisation of all `K` rows (only the sums' rounding
/// differs), in as many rows as they take to converge instead of `K` (the
/// `coherence_level` bench: a level's time flat from `K` = 58 to 512).
/// Where no fixed point is reached to the bit, it simply factors every
/// row.
pub(crate) struct LineTail {
    k: usize,
    records: usize,
    /// `c(m) e^{−i m θ}`, `m = 1..=b`: the sub-diagonals of `Σ`.
    turned: Vec<Complex64>,
    /// `uᴴΣu = 1 + (2/K) Σ (K − m) c(m) cos(mθ)`.
    rayleigh: f64,
    /// The last level and its root `λ₁` (none yet: `λ₁ ≤ 0`).
    last: (f64, f64),
    rows: Vec<Complex64>,
    y: Vec<Complex64>,
    v: Vec<Complex64>,
}

impl LineTail {
    /// The tail of a bin of `k` segments per record averaged over
    /// `records` records, the line `theta` radians per segment step off the
    /// bin; `corr` from [`overlap_correlations`].
    pub(crate) fn new(corr: &[f64], k: usize, records: usize, theta: f64) -> Self {
        let b = corr.len().min(k.saturating_sub(1));
        let turned: Vec<Complex64> = (1..=b)
            .map(|m| Complex64::from_polar(corr[m - 1], -(m as f64) * theta))
            .collect();
        let kf = k.max(1) as f64;
        let rayleigh = 1.0
            + 2.0
                * corr[..b]
                    .iter()
                    .enumerate()
                    .map(|(i, cm)| (kf - (i + 1) as f64) / kf * cm * ((i + 1) as f64 * theta).cos())
                    .sum::<f64>();
        LineTail {
            k,
            records,
            turned,
            rayleigh,
            last: (0.0, 0.0),
            rows: Vec::new(),
            y: Vec::new(),
            v: Vec::new(),
        }
    }

    /// `P(C > c)` (module docs); `None` where the factorisation fails (a
    /// window whose overlap matrix is not positive definite).
    pub(crate) fn tail(&mut self, c: f64) -> Option<f64> {
        let (k, records) = (self.k, self.records);
        if k == 0 || records == 0 {
            return None;
        }
        if c <= 0.0 {
            return Some(1.0);
        }
        if c >= 1.0 {
            return Some(0.0);
        }
        // f is a sum of |α|² μ / (λ + c μ) over Σ's eigenpairs: decreasing
        // and convex in λ > 0, with f(0) = 1/c > 1. The start: the last
        // root scaled to this level, or else uᴴΣu (1 − c), which is at or
        // right of the root (f is at most the same sum with μ at its mean
        // uᴴΣu, by concavity in μ). From the right one Newton step lands
        // left of the root (convexity; not below 0), and from the left
        // Newton approaches it without overshooting.
        let (c_last, l_last) = self.last;
        let mut lambda = if l_last > 0.0 {
            l_last * (1.0 - c) / (1.0 - c_last)
        } else {
            self.rayleigh * (1.0 - c)
        };
        if !(lambda.is_finite() && lambda > 0.0) {
            lambda = 0.0;
        }
        let mut e = self.at_lambda(c, lambda)?;
        for _ in 0..200 {
            let step = (e.f - 1.0) / e.g;
            if !step.is_finite() {
                break;
            }
            lambda = (lambda + step).max(0.0);
            e = self.at_lambda(c, lambda)?;
            if step.abs() <= NEWTON_STEP_TOL * lambda {
                break;
            }
        }
        if !(lambda > 0.0 && e.g > 0.0) {
            return None;
        }
        self.last = (c, lambda);
        let n = (records * k) as f64;
        let log_p = (n - 1.0) * lambda.ln() - records as f64 * e.log_det - e.g.ln();
        Some(log_p.exp().clamp(0.0, 1.0))
    }

    /// `A = λ I + c Σ` factored by a banded Cholesky `A = L Lᴴ` (`L` stored
    /// row by row over its band, up to its fixed row: type docs), then
    /// `v = A⁻¹ 1`: `s = 1ᴴv`, `q = vᴴv`; with `u = 1/√K` (the line's
    /// phasor divided out of `Y`), `ΣA⁻¹ = (I − λA⁻¹)/c` gives
    /// `f = (1 − λ s/K)/c` and `g = (s − λ q)/(c K)`.
    fn at_lambda(&mut self, c: f64, lambda: f64) -> Option<AtLambda> {
        let k = self.k;
        let b = self.turned.len();
        let w = b + 1;
        let zero = Complex64::new(0.0, 0.0);
        let turned = &self.turned;
        // Row i of L holds columns i − b ..= i at 0 ..= b (diagonal at b).
        let rows = &mut self.rows;
        rows.clear();
        let mut log_det = 0.0;
        let mut pivots = 1.0f64;
        let mut pivot = 1.0f64;
        // Rows past `fixed` equal row `fixed` (type docs).
        let mut fixed = k - 1;
        let mut same = 0usize;
        for i in 0..k {
            rows.resize((i + 1) * w, zero);
            let j0 = i.saturating_sub(b);
            for j in j0..=i {
                let mut s = if i == j {
                    Complex64::new(lambda + c, 0.0)
                } else {
                    turned[i - j - 1] * c
                };
                // Columns p ≥ max(j0, j − b) = j0 of both rows.
                for p in j0..j {
                    s -= rows[i * w + b + p - i] * rows[j * w + b + p - j].conj();
                }
                if i == j {
                    if s.re.is_nan() || s.re <= 0.0 {
                        return None;
                    }
                    // ln det A = Σ ln d²: the pivots multiplied, one
                    // logarithm per run of them while the product stays
                    // far from under- or overflow.
                    if !(1e-100..=1e100).contains(&pivots) {
                        log_det += pivots.ln();
                        pivots = 1.0;
                    }
                    pivots *= s.re;
                    pivot = s.re;
                    rows[i * w + b] = Complex64::new(s.re.sqrt(), 0.0);
                } else {
                    rows[i * w + b + j - i] = s / rows[j * w + b].re;
                }
            }
            if i > b && rows[i * w..(i + 1) * w] == rows[(i - 1) * w..i * w] {
                same += 1;
            } else {
                same = 0;
            }
            // Row i + 1 is computed from rows i + 1 − b ..= i as row i was
            // from the ones before: equal to the bit once those are.
            if i >= b && same >= b && i + 1 < k {
                fixed = i;
                log_det += (k - 1 - i) as f64 * pivot.ln();
                break;
            }
        }
        log_det += pivots.ln();
        let row = |r: usize| r.min(fixed) * w;
        // L y = 1, up to y's fixed value.
        let y = &mut self.y;
        y.clear();
        let mut y_fixed = k - 1;
        let mut same = 0usize;
        for i in 0..k {
            let ri = row(i);
            let mut s = Complex64::new(1.0, 0.0);
            for p in i.saturating_sub(b)..i {
                s -= rows[ri + b + p - i] * y[p];
            }
            let yi = s / rows[ri + b].re;
            if i > 0 && yi == y[i - 1] {
                same += 1;
            } else {
                same = 0;
            }
            y.push(yi);
            if i >= fixed && i >= b && same >= b && i + 1 < k {
                y_fixed = i;
                break;
            }
        }
        let y_at = |i: usize| y[i.min(y_fixed)];
        // Lᴴ v = y from the end; v is constant between the two boundary
        // layers (from max(fixed, y_fixed) on, until b + 1 rows from the end).
        let v = &mut self.v;
        v.clear();
        v.resize(k, zero);
        let lo = fixed.max(y_fixed);
        let (mut sum_re, mut sum_sq) = (0.0, 0.0);
        let mut same = 0usize;
        let mut i = k;
        while i > 0 {
            i -= 1;
            let mut s = y_at(i);
            for r in (i + 1)..(i + b + 1).min(k) {
                s -= rows[row(r) + b + i - r].conj() * v[r];
            }
            let vi = s / rows[row(i) + b].re;
            v[i] = vi;
            sum_re += vi.re;
            sum_sq += vi.norm_sqr();
            if i + 1 < k && vi == v[i + 1] {
                same += 1;
            } else {
                same = 0;
            }
            // v[i − 1] is computed from the same row, y and v[i ..= i + b −
            // 1] as v[i] was from v[i + 1 ..= i + b]: equal down to lo.
            if i > lo && i + b < k && same >= b {
                let n = (i - lo) as f64;
                sum_re += n * vi.re;
                sum_sq += n * vi.norm_sqr();
                // Only v[lo ..< lo + b] is read again.
                for slot in &mut v[lo..(lo + b).min(i)] {
                    *slot = vi;
                }
                i = lo;
                same = 0;
            }
        }
        let kf = k as f64;
        Some(AtLambda {
            f: (1.0 - lambda * sum_re / kf) / c,
            g: (sum_re - lambda * sum_sq) / (c * kf),
            log_det,
        })
    }
}

/// `P(C > c)` for a bin of `k` segments per record averaged over `records`
/// records, noise in one channel and a line in the other `theta` radians
/// per segment step off the bin (module docs); `corr` from
/// [`overlap_correlations`]. `None` where the factorisation fails (a
/// window whose overlap matrix is not positive definite). One level; a
/// search over levels keeps a [`LineTail`].
#[cfg(test)]
pub(crate) fn line_tail(corr: &[f64], k: usize, records: usize, theta: f64, c: f64) -> Option<f64> {
    LineTail::new(corr, k, records, theta).tail(c)
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

    /// Windows and overlaps of the comparisons below: periodic Hann 64 at
    /// 50 % (`b = 1`), 75 % (`b = 3`) and 25 %, rectangular at 50 %
    /// (`c(1) = 1/2`, the strongest overlap correlation), and a Blackman
    /// window at two thirds (`b = 2`, steps not dividing the length).
    fn overlap_cases() -> Vec<(&'static str, Vec<f64>, usize)> {
        let blackman: Vec<f64> = (0..63)
            .map(|i| {
                let x = std::f64::consts::TAU * i as f64 / 63.0;
                0.42 - 0.5 * x.cos() + 0.08 * (2.0 * x).cos()
            })
            .collect();
        vec![
            ("hann 50 %", hann(64), 32),
            ("hann 75 %", hann(64), 16),
            ("hann 25 %", hann(64), 48),
            ("boxcar 50 %", vec![1.0; 64], 32),
            ("blackman 2/3", blackman, 21),
        ]
    }

    /// `κ(A)` bound for `A = λ I + c Σ`: the eigenvalues of the banded
    /// Toeplitz `Σ` lie within the range of its symbol
    /// `1 + 2 Σ c(m) cos(m ω)` (4096 points of `ω`).
    fn condition(corr: &[f64], k: usize, c: f64, lambda: f64) -> f64 {
        let b = corr.len().min(k - 1);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for j in 0..4096 {
            let om = std::f64::consts::TAU * j as f64 / 4096.0;
            let s: f64 = 1.0
                + 2.0
                    * corr[..b]
                        .iter()
                        .enumerate()
                        .map(|(m, cm)| cm * ((m + 1) as f64 * om).cos())
                        .sum::<f64>();
            lo = lo.min(s);
            hi = hi.max(s);
        }
        (lambda + c * hi) / (lambda + c * lo.max(0.0)).max(1e-300)
    }

    /// Segment counts from 2 to `EXACT_MAX_SEGMENTS`: every count to 40,
    /// then a spread to the largest.
    fn counts() -> Vec<usize> {
        let mut ks: Vec<usize> = (2..=40).collect();
        ks.extend([
            47,
            64,
            99,
            128,
            150,
            200,
            257,
            333,
            400,
            511,
            EXACT_MAX_SEGMENTS,
        ]);
        ks
    }

    /// Rows after the fixed one equal it to the bit (type docs of
    /// [`LineTail`]), so one evaluation gives the factorisation of every
    /// row's `f`, `g` and `ln det A` but for the sums' rounding: equal to
    /// session 19's evaluation (kept in `super::super::reference`) over
    /// windows, overlaps, counts, offsets, levels and `λ` on both sides of
    /// the root. Tolerances: `ln det A` 1e-13 relative (absolute near 0)
    /// plus the pivots' rounding, `(K + 64) ε κ` absolute (`κ` the
    /// condition number of `A`); `f = (1 − λs/K)/c` and `g = (s − λq)/(cK)` are differences
    /// of sums of `K` terms, whose rounding (in both evaluations) is about
    /// `K ε κ` of their terms:
    /// `(K + 64) ε κ` relative to `1 + 1/(c f)` and `1 + λ/(c uᴴΣu)` (`s`
    /// over `s − λq`) times themselves.
    #[test]
    fn evaluation_equals_the_full_factorisation() {
        use super::super::reference;
        let mut shortened = 0usize;
        let mut total = 0usize;
        let mut worst = [0.0f64; 3];
        for (name, w, step) in overlap_cases() {
            for k in counts() {
                let corr = overlap_correlations(&w, step, k);
                for theta in [0.0, 0.4, -1.3, std::f64::consts::PI, 2.9] {
                    let mut t = LineTail::new(&corr, k, 1, theta);
                    for c in [0.01, 0.2, 0.7, 0.99] {
                        for lambda in [0.0, 0.03, 0.5 * (1.0 - c), 1.0 - c, 2.0] {
                            let got = t.at_lambda(c, lambda).unwrap();
                            let want = reference::at_lambda(&corr, k, theta, c, lambda).unwrap();
                            let kappa = condition(&corr, k, c, lambda);
                            total += 1;
                            if t.rows.len() < k * (corr.len().min(k - 1) + 1) {
                                shortened += 1;
                            }
                            for (i, (what, a, b, scale)) in [
                                ("f", got.f, want.f, 1.0 + 1.0 / (c * want.f).abs()),
                                ("g", got.g, want.g, 1.0 + lambda / (c * t.rayleigh)),
                                ("ln det", got.log_det, want.log_det, 1.0),
                            ]
                            .into_iter()
                            .enumerate()
                            {
                                let err = (a - b).abs() / (b.abs().max(1.0) * scale);
                                let rounding = (k + 64) as f64 * f64::EPSILON * kappa;
                                let tol = if i == 2 {
                                    1e-13 + rounding / b.abs().max(1.0)
                                } else {
                                    rounding
                                };
                                worst[i] = worst[i].max(err / tol);
                                assert!(
                                    err <= tol,
                                    "{name} K={k} θ={theta} c={c} λ={lambda}: {what} {a} vs {b}"
                                );
                            }
                        }
                    }
                }
            }
        }
        eprintln!(
            "evaluation: worst differences over their tolerance: f {:.3}, g {:.3}, ln det {:.3}",
            worst[0], worst[1], worst[2]
        );
        // The shortcut is taken: most evaluations stop before the last row.
        assert!(shortened * 2 > total, "{shortened} of {total} shortened");
    }

    /// The tail with the new start and stop of Newton's iteration and a
    /// kept root, level after level as a root search asks for them, against
    /// session 19's (a fresh iteration from `λ = 0` per level) over the same
    /// grid and 1 or 3 records. Tolerance: 1e-12 relative plus the tail's
    /// own rounding in both. `f = (1 − λs/K)/c` is known to about `ε/c`
    /// near its root (the difference cancels to `c`) times `κ`, so the root `λ₁` to
    /// `ε/(c g)` and the tail, whose logarithm holds `(n − 1) ln λ₁`, to
    /// `(n − 1) ε κ/(c g λ₁)` relative (`κ` the condition number of `A`,
    /// by which the rounding of `f` grows); 16 times that. (Where the tail is
    /// below 1e-250 its logarithm is compared instead, so that an underflow
    /// to 0 counts as equal.)
    #[test]
    fn tail_equals_session_19s() {
        use super::super::reference;
        let mut worst = 0.0f64;
        for (name, w, step) in overlap_cases() {
            for k in counts() {
                let corr = overlap_correlations(&w, step, k);
                for theta in [0.0, 0.4, -1.3, std::f64::consts::PI, 2.9] {
                    for r in [1usize, 3] {
                        let mut t = LineTail::new(&corr, k, r, theta);
                        for c in [0.3, 0.31, 0.05, 0.0501, 0.9, 0.001, 0.5, 0.999] {
                            let got = t.tail(c).unwrap();
                            let want = reference::line_tail(&corr, k, r, theta, c).unwrap();
                            let lambda = t.last.1;
                            let g = t.at_lambda(c, lambda).unwrap().g;
                            let n = (r * k) as f64;
                            let kappa = condition(&corr, k, c, lambda);
                            let tol =
                                1e-12 + 16.0 * (n - 1.0) * f64::EPSILON * kappa / (c * g * lambda);
                            let err = if want > 1e-250 {
                                (got - want).abs() / want
                            } else {
                                (got.max(1e-300).ln() - want.max(1e-300).ln()).abs()
                            };
                            worst = worst.max(err / tol);
                            assert!(
                                err <= tol,
                                "{name} K={k} R={r} θ={theta} c={c}: {got:e} vs {want:e} ({err:e} > {tol:e})"
                            );
                        }
                    }
                }
            }
        }
        eprintln!("tail: worst difference over its tolerance {worst:.3}");
    }
}
