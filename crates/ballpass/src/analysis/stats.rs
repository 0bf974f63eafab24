//! Small statistics used by the significance tests: the regularised lower
//! incomplete gamma function, the chi-square quantile, and the equivalent
//! degrees of freedom of a Welch estimate.

/// `ln Γ(x)` for `x > 0` (Lanczos, g = 7, 9 terms; relative error ~1e-15).
pub(crate) fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1-x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised lower incomplete gamma `P(a, x) = γ(a, x) / Γ(a)` for
/// `a > 0`, `x >= 0` (series below `a + 1`, Lentz continued fraction above;
/// as `scipy.special.gammainc`).
pub(crate) fn gamma_p(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let ln_pre = a * x.ln() - x - ln_gamma(a);
    if x < a + 1.0 {
        let mut term = 1.0 / a;
        let mut sum = term;
        let mut ap = a;
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-17 {
                break;
            }
        }
        (sum.ln() + ln_pre).exp().min(1.0)
    } else {
        // Q(a, x) by the continued fraction (modified Lentz).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (1.0 - (ln_pre.exp() * h)).max(0.0)
    }
}

/// Chi-square CDF with `nu > 0` degrees of freedom: `P(nu/2, x/2)`.
pub(crate) fn chi2_cdf(x: f64, nu: f64) -> f64 {
    gamma_p(0.5 * nu, 0.5 * x)
}

/// Chi-square quantile: the `x` with `chi2_cdf(x, nu) = p`, for
/// `0 < p < 1`, `nu > 0` (as `scipy.stats.chi2.ppf(p, nu)`).
///
/// Bracketed bisection on the CDF, finished by Newton steps on the
/// log-density; relative accuracy ~1e-12.
pub(crate) fn chi2_ppf(p: f64, nu: f64) -> f64 {
    debug_assert!(p > 0.0 && p < 1.0 && nu > 0.0);
    let mut lo = 0.0;
    let mut hi = nu.max(1.0);
    while chi2_cdf(hi, nu) < p {
        lo = hi;
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi2_cdf(mid, nu) < p {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-13 * hi {
            break;
        }
    }
    let mut x = 0.5 * (lo + hi);
    // Newton on F(x) - p with density f(x) = x^(k-1) e^(-x/2) / (2^k Γ(k)), k = nu/2.
    let k = 0.5 * nu;
    for _ in 0..3 {
        let ln_f = (k - 1.0) * x.ln() - 0.5 * x - k * 2f64.ln() - ln_gamma(k);
        let f = ln_f.exp();
        if !(f.is_finite() && f > 0.0) {
            break;
        }
        let step = (chi2_cdf(x, nu) - p) / f;
        let next = x - step;
        if !(next > lo && next < hi) {
            break;
        }
        x = next;
    }
    x
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
pub(crate) fn welch_dof(w: &[f64], step: usize, k: usize) -> f64 {
    if k == 0 {
        return 0.0;
    }
    let e: f64 = w.iter().map(|v| v * v).sum();
    let mut s = 0.0;
    for m in 1..k {
        let shift = m * step;
        if shift >= w.len() {
            break;
        }
        let c: f64 = w[shift..].iter().zip(w).map(|(a, b)| a * b).sum::<f64>() / e;
        s += (1.0 - m as f64 / k as f64) * c * c;
    }
    2.0 * k as f64 / (1.0 + 2.0 * s)
}

/// Median of a slice (mean of the two middle values for an even count);
/// `None` when empty.
pub(crate) fn median(v: &[f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    Some(if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    })
}

/// Mean and standard deviation (`ddof` 0 or 1) of a slice; `None` when
/// there are not more values than `ddof`.
pub(crate) fn mean_std(v: &[f64], ddof: usize) -> Option<(f64, f64)> {
    if v.len() <= ddof {
        return None;
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let ss: f64 = v.iter().map(|x| (x - mean) * (x - mean)).sum();
    Some((mean, (ss / (n - ddof as f64)).sqrt()))
}

/// Vertex of the parabola through `(-1, a)`, `(0, b)`, `(1, c)`: offset in
/// `[-0.5, 0.5]` from the middle sample and the interpolated value.
/// A flat or degenerate triple gives offset 0.
pub(crate) fn parabolic_peak(a: f64, b: f64, c: f64) -> (f64, f64) {
    let den = a - 2.0 * b + c;
    if den == 0.0 || !den.is_finite() {
        return (0.0, b);
    }
    let d = (0.5 * (a - c) / den).clamp(-0.5, 0.5);
    (d, b - 0.25 * (a - c) * d)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let (m, s) = mean_std(&[1.0, 2.0, 3.0, 4.0], 1).unwrap();
        assert!((m - 2.5).abs() < 1e-15 && (s - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert!(mean_std(&[1.0], 1).is_none());
        // Parabola y = 1 - (x - 0.3)^2 sampled at -1, 0, 1.
        let f = |x: f64| 1.0 - (x - 0.3) * (x - 0.3);
        let (d, v) = parabolic_peak(f(-1.0), f(0.0), f(1.0));
        assert!((d - 0.3).abs() < 1e-12 && (v - 1.0).abs() < 1e-12);
    }
}
