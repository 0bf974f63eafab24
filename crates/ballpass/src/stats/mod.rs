//! Small statistics shared by the analyses and the campaigns: mean and
//! spread, medians and robust levels, least-squares lines with confidence
//! intervals (Student's t), the chi-square distribution used by the
//! significance tests, the equivalent degrees of freedom of a Welch estimate,
//! and parabolic peak interpolation.
//!
//! Non-finite values: [`median`], [`robust_sigma`] and [`mean_std`] ignore
//! them; [`MeanStd::of`] takes the values as they are.

use serde::{Deserialize, Serialize};

mod dist;

pub use dist::{
    binomial_interval, chi2_cdf, chi2_ppf, digamma, f_cdf, f_ppf, gamma_p, gamma_p_many,
    gamma_p_with, ln_gamma, normal_cdf, reg_inc_beta, student_t_quantile, trigamma,
};

/// Mean and sample standard deviation (ddof = 1; 0 for a single value).
///
/// Serialised as `{"mean", "std", "n"}` in `analysis.json` and the campaign
/// outputs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanStd {
    /// Arithmetic mean.
    pub mean: f64,
    /// Sample standard deviation (n − 1 in the denominator); 0 for one value.
    pub std: f64,
    /// Number of values.
    pub n: usize,
}

impl MeanStd {
    /// Mean and sample standard deviation of all of `v` (no filtering):
    ///
    /// ```text
    /// mean = Σ v / n,   std = sqrt(Σ (v − mean)² / (n − 1))   (0 when n = 1)
    /// ```
    ///
    /// `None` when `v` is empty.
    pub fn of(v: &[f64]) -> Option<Self> {
        if v.is_empty() {
            return None;
        }
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n as f64;
        let std = if n > 1 {
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            0.0
        };
        Some(Self { mean, std, n })
    }
}

/// Mean and sample standard deviation of the finite values in `x`
/// ([`MeanStd::of`] after dropping NaN and ±∞); `None` when there are none.
pub fn mean_std(x: &[f64]) -> Option<MeanStd> {
    let v: Vec<f64> = x.iter().copied().filter(|x| x.is_finite()).collect();
    MeanStd::of(&v)
}

/// Median of the finite values (mean of the middle two for an even count,
/// `0.5 (lo + hi)`); `None` when there are none.
pub fn median(x: &[f64]) -> Option<f64> {
    median_with(x, &mut Vec::new())
}

/// [`median()`] with a scratch buffer reused between calls, found by
/// selection on [`order_key`]s: under `total_cmp` the order statistics are
/// unique, so the value is that of a full sort bit for bit (tested).
pub(crate) fn median_with(x: &[f64], scratch: &mut Vec<i64>) -> Option<f64> {
    scratch.clear();
    scratch.extend(x.iter().filter(|x| x.is_finite()).map(|&v| order_key(v)));
    median_of_keys(scratch)
}

/// A key whose integer order is [`f64::total_cmp`]'s order: the transform
/// `total_cmp` applies to both sides of every comparison, done once per
/// value, so that a selection compares plain integers (in a microbenchmark
/// of the running percentile's selections, 800-sample windows of 30 000
/// samples, 226 -> 182 µs). [`from_order_key`] undoes it.
#[inline]
pub(crate) fn order_key(x: f64) -> i64 {
    let b = x.to_bits() as i64;
    b ^ (((b >> 63) as u64) >> 1) as i64
}

/// The value of an [`order_key`] (the transform is its own inverse).
#[inline]
pub(crate) fn from_order_key(k: i64) -> f64 {
    f64::from_bits(order_key(f64::from_bits(k as u64)) as u64)
}

/// NumPy's default (linear) percentile `q` (0..=100) of the values whose
/// [`order_key`]s are `keys`, which it reorders; NaN when empty:
///
/// ```text
/// pos = q/100 (n - 1),  lo = floor(pos),  p = v_(lo) + (pos - lo) (v_(lo+1) - v_(lo))
/// ```
///
/// with `v_(k)` the `k`-th smallest under `total_cmp`.
pub(crate) fn percentile_of_keys(keys: &mut [i64], q: f64) -> f64 {
    if keys.is_empty() {
        return f64::NAN;
    }
    let pos = q / 100.0 * (keys.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let frac = pos - lo as f64;
    let (_, &mut a, rest) = keys.select_nth_unstable(lo);
    let a = from_order_key(a);
    if frac == 0.0 {
        return a;
    }
    match rest.iter().min() {
        Some(&b) => a + frac * (from_order_key(b) - a),
        None => a,
    }
}

/// The median as [`median()`] defines it (`0.5 (lo + hi)` of the middle two
/// for an even count) of the values whose [`order_key`]s are `keys`, which
/// it reorders; `None` when empty.
pub(crate) fn median_of_keys(keys: &mut [i64]) -> Option<f64> {
    let n = keys.len();
    if n == 0 {
        return None;
    }
    let (lower, &mut mid, _) = keys.select_nth_unstable(n / 2);
    let mid = from_order_key(mid);
    Some(if n % 2 == 1 {
        mid
    } else {
        let below = from_order_key(
            *lower
                .iter()
                .max()
                .expect("an even count leaves values below"),
        );
        0.5 * (below + mid)
    })
}

/// Median absolute deviation scaled to a normal standard deviation:
/// `1.4826 · median(|x − median(x)|)`.
pub fn robust_sigma(x: &[f64]) -> Option<f64> {
    robust_sigma_with(x, &mut Vec::new())
}

/// [`robust_sigma`] with a scratch buffer reused between calls.
pub(crate) fn robust_sigma_with(x: &[f64], scratch: &mut Vec<i64>) -> Option<f64> {
    let m = median_with(x, scratch)?;
    let dev: Vec<f64> = x.iter().map(|v| (v - m).abs()).collect();
    median_with(&dev, scratch).map(|d| 1.482_602_218_505_602 * d)
}

/// A least-squares straight line `y = slope · x + intercept` with 95 %
/// confidence half-widths from Student's t with n − 2 degrees of freedom.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LinearFit {
    /// Slope.
    pub slope: f64,
    /// Intercept.
    pub intercept: f64,
    /// Standard error of the slope.
    pub slope_stderr: f64,
    /// Standard error of the intercept.
    pub intercept_stderr: f64,
    /// Half-width of the 95 % confidence interval of the slope.
    pub slope_ci95: f64,
    /// Half-width of the 95 % confidence interval of the intercept.
    pub intercept_ci95: f64,
    /// Coefficient of determination.
    pub r2: f64,
    /// Number of points.
    pub n: usize,
}

/// Ordinary least-squares line through `(x, y)` (as `scipy.stats.linregress`).
///
/// Returns `None` with fewer than 3 points or when all `x` are equal
/// (no confidence interval can be given then).
pub fn linear_fit(x: &[f64], y: &[f64]) -> Option<LinearFit> {
    let n = x.len().min(y.len());
    if n < 3 {
        return None;
    }
    let nf = n as f64;
    let mx = x[..n].iter().sum::<f64>() / nf;
    let my = y[..n].iter().sum::<f64>() / nf;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (dx, dy) = (x[i] - mx, y[i] - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    if sxx <= 0.0 || !sxx.is_finite() {
        return None;
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let r2 = if syy > 0.0 {
        (sxy * sxy / (sxx * syy)).min(1.0)
    } else {
        1.0
    };
    let dof = nf - 2.0;
    let resid = ((1.0 - r2) * syy).max(0.0);
    let slope_stderr = (resid / dof / sxx).sqrt();
    let intercept_stderr = slope_stderr * (x[..n].iter().map(|v| v * v).sum::<f64>() / nf).sqrt();
    let t = student_t_quantile(0.975, dof);
    Some(LinearFit {
        slope,
        intercept,
        slope_stderr,
        intercept_stderr,
        slope_ci95: t * slope_stderr,
        intercept_ci95: t * intercept_stderr,
        r2,
        n,
    })
}

/// A least-squares line through the origin `y = slope · x`, with the 95 %
/// confidence half-width of the slope (t with n − 1 degrees of freedom).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct OriginFit {
    /// Slope.
    pub slope: f64,
    /// Standard error of the slope.
    pub slope_stderr: f64,
    /// Half-width of the 95 % confidence interval.
    pub slope_ci95: f64,
    /// Number of points.
    pub n: usize,
}

/// Least-squares slope of a line through the origin; `None` with fewer than 2
/// points or all `x` zero.
pub fn origin_fit(x: &[f64], y: &[f64]) -> Option<OriginFit> {
    let n = x.len().min(y.len());
    if n < 2 {
        return None;
    }
    let sxx: f64 = x[..n].iter().map(|v| v * v).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = x[..n].iter().zip(&y[..n]).map(|(a, b)| a * b).sum::<f64>() / sxx;
    let rss: f64 = x[..n]
        .iter()
        .zip(&y[..n])
        .map(|(a, b)| (b - slope * a).powi(2))
        .sum();
    let dof = (n - 1) as f64;
    let slope_stderr = (rss / dof / sxx).sqrt();
    Some(OriginFit {
        slope,
        slope_stderr,
        slope_ci95: student_t_quantile(0.975, dof) * slope_stderr,
        n,
    })
}

/// Equivalent degrees of freedom of a Welch average of `k` segments of
/// window `w` stepped by `step` samples (Percival & Walden 1993, Eq. 292b;
/// Welch 1967):
///
/// ```text
/// h   = w / sqrt(sum w^2)
/// rho(m) = (sum_t h[t] h[t + m step])^2
/// nu  = 2 k / (1 + 2 sum_{m=1}^{k-1} (1 - m/k) rho(m))
/// ```
///
/// It assumes Gaussian noise whose spectrum is flat over the window's
/// bandwidth. `k = 1` gives 2; Hann with 50 % overlap and many segments
/// gives about `1.89 k`. Bins at DC and Nyquist (real-valued) carry half of
/// that; they are never used for harmonics of `f_c > 0`.
pub fn welch_dof(w: &[f64], step: usize, k: usize) -> f64 {
    if k == 0 {
        return 0.0;
    }
    2.0 * k as f64 / (1.0 + 2.0 * overlap_terms(w, step, k, |_, c| c))
}

/// `Σ_{m=1}^{k−1} (1 − m/k) c(m) cos(m θ)`, with `c(m) = Σ_t w[t]
/// w[t + m·step] / Σ_t w[t]²` the overlap correlation of `k` segments of
/// window `w` at hop `step`: the equivalent segment count of the cross
/// spectrum of a line and noise in a bin whose frequency differs from the
/// line's by `θ / (2π · step)` cycles per sample (the line's segment phasor
/// and the noise's correlation between segments `m` hops apart turn by
/// `m θ` against each other; `θ = 0`: a line's phase on its own bin).
/// [`welch_dof`] sums `c(m)²` instead (the power of noise).
pub(crate) fn overlap_sum_turned(w: &[f64], step: usize, k: usize, theta: f64) -> f64 {
    // cos(0) is exactly 1: θ = 0 weighs every term by one.
    overlap_terms(w, step, k, |m, _| (m as f64 * theta).cos())
}

/// `Σ_{m=1}^{k−1} ((1 − m/k) c(m)) · weight(m, c(m))`.
fn overlap_terms(w: &[f64], step: usize, k: usize, weight: impl Fn(usize, f64) -> f64) -> f64 {
    let e: f64 = w.iter().map(|v| v * v).sum();
    let mut s = 0.0;
    for m in 1..k {
        let shift = m * step;
        if shift >= w.len() {
            break;
        }
        let c: f64 = w[shift..].iter().zip(w).map(|(a, b)| a * b).sum::<f64>() / e;
        // Evaluated as ((1 − m/k) c) · weight (a weight of 1 leaves the
        // product exact).
        let t = (1.0 - m as f64 / k as f64) * c;
        s += t * weight(m, c);
    }
    s
}

/// Vertex of the parabola through `(-1, a)`, `(0, b)`, `(1, c)`: offset in
/// `[-0.5, 0.5]` from the middle sample and the interpolated value.
/// A flat or degenerate triple gives offset 0.
pub fn parabolic_peak(a: f64, b: f64, c: f64) -> (f64, f64) {
    let den = a - 2.0 * b + c;
    if den == 0.0 || !den.is_finite() {
        return (0.0, b);
    }
    let d = (0.5 * (a - c) / den).clamp(-0.5, 0.5);
    (d, b - 0.25 * (a - c) * d)
}

/// Seeded noise for the unit tests of several modules (one generator each,
/// so every test's data stay what they were).
#[cfg(test)]
pub(crate) mod test_noise {
    /// Standard normal noise: splitmix64 → two uniforms → Box–Muller.
    pub(crate) fn gaussian(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        let mut next = || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (u, v) = (next().max(1e-300), next());
                (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
            })
            .collect()
    }

    /// Uniform noise in [-0.5, 0.5) from a 64-bit LCG.
    pub(crate) fn uniform(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use super::test_noise::gaussian as noise;

    /// The selection median and robust σ (`crate::stats`, by order keys)
    /// equal the sorting ones bit for bit (odd and even counts, ties, NaN
    /// and infinities dropped, signed zeros, empty input).
    #[test]
    fn selection_median_equals_the_sorting_median() {
        fn sorting_median(x: &[f64]) -> Option<f64> {
            let mut v: Vec<f64> = x.iter().copied().filter(|x| x.is_finite()).collect();
            v.sort_by(f64::total_cmp);
            let n = v.len();
            (n > 0).then(|| {
                if n % 2 == 1 {
                    v[n / 2]
                } else {
                    0.5 * (v[n / 2 - 1] + v[n / 2])
                }
            })
        }
        let mut scratch = Vec::new();
        let mut cases: Vec<Vec<f64>> = vec![
            vec![],
            vec![f64::NAN],
            vec![1.0],
            vec![2.0, 1.0],
            vec![0.0, -0.0, 0.0, -0.0],
            vec![3.0, f64::NAN, 1.0, f64::INFINITY, 2.0, 2.0],
        ];
        for n in [7, 8, 450, 451, 30_000] {
            cases.push(noise(n, n as u64));
            cases.push(noise(n, 3).iter().map(|v| (v * 4.0).round()).collect());
        }
        for x in &cases {
            let want = sorting_median(x);
            assert_eq!(
                median_with(x, &mut scratch).map(f64::to_bits),
                want.map(f64::to_bits),
                "{} values",
                x.len()
            );
            let want_sigma = want.and_then(|m| {
                let dev: Vec<f64> = x.iter().map(|v| (v - m).abs()).collect();
                sorting_median(&dev).map(|d| 1.482_602_218_505_602 * d)
            });
            assert_eq!(
                robust_sigma_with(x, &mut scratch).map(f64::to_bits),
                want_sigma.map(f64::to_bits),
                "{} values",
                x.len()
            );
        }
    }

    #[test]
    fn order_keys_sort_as_total_cmp_and_come_back() {
        let v = [
            f64::NEG_INFINITY,
            -1e300,
            -2.5,
            -f64::MIN_POSITIVE,
            -0.0,
            0.0,
            f64::MIN_POSITIVE,
            1.0,
            3.5,
            1e300,
            f64::INFINITY,
            f64::NAN,
            -f64::NAN,
        ];
        for a in v {
            assert_eq!(from_order_key(order_key(a)).to_bits(), a.to_bits());
            for b in v {
                assert_eq!(order_key(a).cmp(&order_key(b)), a.total_cmp(&b), "{a} {b}");
            }
        }
    }

    #[test]
    fn key_statistics_equal_the_sorting_ones() {
        let mut s = 3u64;
        for n in [1usize, 2, 3, 4, 10, 101, 1000] {
            let x: Vec<f64> = (0..n)
                .map(|i| {
                    s = s
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    // Repeated values and both zeros now and then.
                    match i % 7 {
                        0 => 0.0,
                        1 => -0.0,
                        2 => 1.5,
                        _ => (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5,
                    }
                })
                .collect();
            let mut keys: Vec<i64> = x.iter().map(|&v| order_key(v)).collect();
            let mut sorted = x.clone();
            sorted.sort_by(f64::total_cmp);
            let want = if n % 2 == 1 {
                sorted[n / 2]
            } else {
                0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
            };
            assert_eq!(
                median_of_keys(&mut keys).map(f64::to_bits),
                Some(want.to_bits()),
                "n={n}"
            );
            for q in [0.0, 10.0, 25.0, 50.0, 75.0, 100.0] {
                let pos = q / 100.0 * (n - 1) as f64;
                let lo = pos.floor() as usize;
                let want = if lo + 1 < n {
                    sorted[lo] + (pos - lo as f64) * (sorted[lo + 1] - sorted[lo])
                } else {
                    sorted[lo]
                };
                let mut keys: Vec<i64> = x.iter().map(|&v| order_key(v)).collect();
                assert_eq!(percentile_of_keys(&mut keys, q), want, "n={n} q={q}");
            }
        }
        assert!(percentile_of_keys(&mut [], 50.0).is_nan());
        assert_eq!(median_of_keys(&mut []), None);
    }

    /// Reference values from scipy.stats.t.ppf (scipy 1.17.1). The bisection
    /// stops at 1e-15 relative and the continued fraction and Lanczos series
    /// are good to ~1e-14, so 1e-11 relative is a safe, still strict bound.
    #[test]
    fn t_quantiles_match_scipy() {
        for (p, dof, want) in [
            (0.975, 1.0, 12.706204736174694),
            (0.975, 2.0, 4.302652729749462),
            (0.975, 5.0, 2.5705818356363146),
            (0.975, 18.0, 2.1009220402410382),
            (0.975, 98.0, 1.9844674545084815),
            (0.995, 10.0, 3.16927267261695),
            (0.9, 3.0, 1.637744353696209),
            (0.6, 7.0, 0.2631668613520229),
        ] {
            let got = student_t_quantile(p, dof);
            assert!(
                (got - want).abs() / want < 1e-11,
                "t({p}, {dof}) = {got}, scipy {want}"
            );
            assert!((student_t_quantile(1.0 - p, dof) + want).abs() / want < 1e-11);
        }
        assert!(student_t_quantile(0.0, 3.0).is_nan());
        assert!(student_t_quantile(0.5, 0.0).is_nan());
    }

    /// Reference from scipy.stats.linregress on the same points; the sums are
    /// exact to a few ulps, hence 1e-12.
    #[test]
    fn linear_fit_matches_linregress() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        let y = [2.1, 3.9, 6.2, 7.8, 10.1, 12.2, 13.8, 16.1];
        let f = linear_fit(&x, &y).unwrap();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-3);
        assert!(close(f.slope, 1.9976190476190478), "{}", f.slope);
        assert!(close(f.intercept, 0.0357142857142847), "{}", f.intercept);
        assert!(close(f.r2, 0.9988392866011391), "{}", f.r2);
        assert!(
            close(f.slope_stderr, 0.02780044426688155),
            "{}",
            f.slope_stderr
        );
        assert!(
            close(f.intercept_stderr, 0.14038536208101496),
            "{}",
            f.intercept_stderr
        );
        assert!(close(
            f.slope_ci95,
            2.4469118511449786 * 0.02780044426688155
        ));
        assert!(linear_fit(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]).is_none());
        assert!(linear_fit(&[1.0, 2.0], &[1.0, 2.0]).is_none());
    }

    #[test]
    fn robust_levels() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(&[]), None);
        // One wild outlier does not move the robust sigma.
        let s = robust_sigma(&[1.0, 2.0, 3.0, 4.0, 1000.0]).unwrap();
        assert!((s - 1.482_602_218_505_602).abs() < 1e-12);
        let m = mean_std(&[1.0, 2.0, 3.0, f64::NAN]).unwrap();
        assert_eq!((m.mean, m.std, m.n), (2.0, 1.0, 3));
        let o = origin_fit(&[1.0, 2.0, 3.0], &[2.0, 4.0, 6.0]).unwrap();
        assert!((o.slope - 2.0).abs() < 1e-15 && o.slope_stderr < 1e-12);
    }

    /// `scipy.stats.chi2.ppf(p, nu)` (SciPy 1.17), printed with `repr`.
    const PPF: [(f64, f64, f64); 10] = [
        (2.0, 0.99, 9.21034037197618),
        (2.0, 0.5, 1.386294361119891),
        (10.0, 0.99, 23.209251158954356),
        (20.0, 0.999, 45.31474661812586),
        (3.7, 0.95, 8.99713556762768),
        (47.3, 0.99, 72.81537344645498),
        (200.0, 0.99, 249.4451229814416),
        (1.0, 0.5, 0.454936423119572),
        (0.5, 0.9, 1.5007857444736732),
        (2000.0, 0.99966, 2221.9326794908825),
    ];

    #[test]
    fn chi2_ppf_outside_domain_is_nan() {
        assert!(chi2_ppf(1.0, 3.0).is_nan());
        assert!(chi2_ppf(0.0, 3.0).is_nan());
        assert!(chi2_ppf(0.5, 0.0).is_nan());
        assert!(chi2_ppf(f64::NAN, 3.0).is_nan());
    }

    #[test]
    fn chi2_ppf_matches_scipy() {
        for (nu, p, want) in PPF {
            let got = chi2_ppf(p, nu);
            // The series/continued fraction are accurate to ~1e-14 and the
            // root is polished to that; 1e-10 relative leaves margin for
            // ln_gamma's error amplified by large nu.
            assert!(
                (got - want).abs() <= 1e-10 * want,
                "chi2.ppf({p}, {nu}) = {got}, scipy {want}"
            );
        }
    }

    /// The pinned fixture of `tools/gen_stats_fixtures.py`: chi-square
    /// quantiles over the Welch degrees of freedom (fractional, 0.5 to
    /// 3790) and band/test tail probabilities 1e-4 to 0.9999.
    #[test]
    fn chi2_ppf_matches_the_scipy_fixture() {
        let v: serde_json::Value =
            serde_json::from_str(include_str!("../../tests/fixtures/stats/chi2_ppf.json")).unwrap();
        let rows = v["rows"].as_array().unwrap();
        assert!(rows.len() > 200);
        for r in rows {
            let (nu, p, want) = (
                r[0].as_f64().unwrap(),
                r[1].as_f64().unwrap(),
                r[2].as_f64().unwrap(),
            );
            let got = chi2_ppf(p, nu);
            // Relative 1e-9: the CDF is accurate to ~1e-14 and the root is
            // bisected to 1e-13 relative; in the far lower tail of small
            // ν the quantile ∝ p^(2/ν) amplifies the CDF's relative error
            // by 2/ν (4 at ν = 0.5).
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "chi2.ppf({p}, {nu}) = {got}, scipy {want}"
            );
        }
    }

    #[test]
    fn gamma_p_matches_scipy() {
        // scipy.special.gammainc(a, x) (SciPy 1.17).
        for (a, x, want) in [
            (0.5, 0.1, 0.34527915398142317),
            (3.0, 2.5, 0.45618688411667035),
            (10.0, 15.0, 0.9301463393005901),
            (100.0, 90.0, 0.15822098918643007),
        ] {
            let got = gamma_p(a, x);
            // Same algorithms as Cephes; 1e-12 relative covers the
            // accumulated rounding of up to a few hundred terms.
            assert!((got - want).abs() <= 1e-12 * want, "P({a}, {x}) = {got}");
        }
    }

    #[test]
    fn gamma_p_many_equals_gamma_p_bit_for_bit() {
        // Both branches (series below a + 1, continued fraction above),
        // lanes stopping after different numbers of terms, x <= 0, NaN,
        // far tails (0 and 1).
        for a in [0.5, 1.0, 3.7, 17.5, 48.25, 250.0] {
            let xs: [f64; 24] = std::array::from_fn(|i| match i {
                0 => 0.0,
                1 => -1.0,
                2 => f64::NAN,
                3 => 1e-300,
                4 => 1e6,
                // 0.26 a to 1.8 a
                _ => 0.25 * a * (0.15 * (i as f64 - 4.0)).exp2(),
            });
            let lg = ln_gamma(a);
            let many = gamma_p_many(a, lg, &xs);
            for (x, got) in xs.iter().zip(many) {
                assert_eq!(got.to_bits(), gamma_p(a, *x).to_bits(), "P({a}, {x})");
                assert_eq!(gamma_p_with(a, lg, *x).to_bits(), gamma_p(a, *x).to_bits());
            }
        }
    }

    #[test]
    fn welch_dof_limits() {
        let n = 256;
        let hann: Vec<f64> = (0..n)
            .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos())
            .collect();
        // One segment: a periodogram, 2 dof exactly.
        assert_eq!(welch_dof(&hann, 128, 1), 2.0);
        // No overlap: independent segments, 2k dof.
        assert!((welch_dof(&hann, 256, 10) - 20.0).abs() < 1e-12);
        // Hann 50 %: rho(1) = (sum h[t] h[t+N/2])^2 = (1/6)^2 for the
        // periodic window, so nu -> 2k / (1 + 2/36) for large k
        // (Percival & Walden Table 294: 1.89k).
        let k = 10_000;
        let nu = welch_dof(&hann, 128, k);
        let want = 2.0 * k as f64 / (1.0 + 2.0 / 36.0 * (1.0 - 1.0 / k as f64));
        assert!((nu - want).abs() < 1e-6 * want, "{nu} vs {want}");
    }

    #[test]
    fn helpers() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
        assert_eq!(median(&[]), None);
        let m = MeanStd::of(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        assert!((m.mean - 2.5).abs() < 1e-15 && (m.std - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert_eq!(
            MeanStd::of(&[1.0]),
            Some(MeanStd {
                mean: 1.0,
                std: 0.0,
                n: 1
            })
        );
        assert!(MeanStd::of(&[]).is_none());
        // `of` keeps non-finite values, `mean_std` drops them.
        assert!(MeanStd::of(&[1.0, f64::NAN]).unwrap().mean.is_nan());
        assert_eq!(median(&[f64::NAN, 1.0, 3.0]), Some(2.0));
        // Parabola y = 1 - (x - 0.3)^2 sampled at -1, 0, 1.
        let f = |x: f64| 1.0 - (x - 0.3) * (x - 0.3);
        let (d, v) = parabolic_peak(f(-1.0), f(0.0), f(1.0));
        assert!((d - 0.3).abs() < 1e-12 && (v - 1.0).abs() < 1e-12);
    }
}
