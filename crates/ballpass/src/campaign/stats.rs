//! Small statistics for campaign tables: mean and spread, robust levels,
//! least-squares lines with confidence intervals (Student's t).

use serde::{Deserialize, Serialize};

/// Mean and sample standard deviation (ddof = 1; 0 for a single value).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanStd {
    /// Arithmetic mean.
    pub mean: f64,
    /// Sample standard deviation (n − 1 in the denominator).
    pub std: f64,
    /// Number of values.
    pub n: usize,
}

/// Mean and sample standard deviation of the finite values in `x`;
/// `None` when there are none.
pub fn mean_std(x: &[f64]) -> Option<MeanStd> {
    let v: Vec<f64> = x.iter().copied().filter(|x| x.is_finite()).collect();
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
    Some(MeanStd { mean, std, n })
}

/// Median of the finite values (mean of the middle two for an even count).
pub fn median(x: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = x.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// Median absolute deviation scaled to a normal standard deviation:
/// `1.4826 · median(|x − median(x)|)`.
pub fn robust_sigma(x: &[f64]) -> Option<f64> {
    let m = median(x)?;
    let dev: Vec<f64> = x.iter().map(|v| (v - m).abs()).collect();
    median(&dev).map(|d| 1.482_602_218_505_602 * d)
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

/// Quantile of Student's t distribution with `dof` degrees of freedom
/// (`scipy.stats.t.ppf(p, dof)`), for 0 < p < 1 and dof > 0.
///
/// Inverts the regularised incomplete beta function by bisection to full
/// double precision (the function is monotone, so bisection cannot fail).
/// Returns NaN outside the domain.
pub fn student_t_quantile(p: f64, dof: f64) -> f64 {
    if !(p > 0.0 && p < 1.0 && dof > 0.0) {
        return f64::NAN;
    }
    if p == 0.5 {
        return 0.0;
    }
    let upper = p > 0.5;
    let q = if upper { 1.0 - p } else { p }; // lower-tail probability of -|t|
                                             // P(T <= -t) = I_{dof/(dof+t²)}(dof/2, 1/2) / 2, decreasing in t.
    let tail = |t: f64| 0.5 * reg_inc_beta(dof / 2.0, 0.5, dof / (dof + t * t));
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    while tail(hi) > q {
        hi *= 2.0;
        if hi > 1e300 {
            break;
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if tail(mid) > q {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-15 * hi {
            break;
        }
    }
    let t = 0.5 * (lo + hi);
    if upper {
        t
    } else {
        -t
    }
}

/// Regularised incomplete beta function `I_x(a, b)` by Lentz's continued
/// fraction (Numerical Recipes §6.4), for a, b > 0 and 0 ≤ x ≤ 1.
pub fn reg_inc_beta(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let ln_front = ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln();
    if x < (a + 1.0) / (a + b + 2.0) {
        ln_front.exp() * beta_cf(a, b, x) / a
    } else {
        1.0 - ln_front.exp() * beta_cf(b, a, 1.0 - x) / b
    }
}

fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < TINY {
        d = TINY;
    }
    d = 1.0 / d;
    let mut h = d;
    for m in 1..1000 {
        let m = f64::from(m);
        let m2 = 2.0 * m;
        let aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        h *= d * c;
        let aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if d.abs() < TINY {
            d = TINY;
        }
        c = 1.0 + aa / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-16 {
            break;
        }
    }
    h
}

/// Natural log of the gamma function for x > 0 (Lanczos, g = 7, n = 9;
/// relative error below 1e-15 over the range used here).
pub fn ln_gamma(x: f64) -> f64 {
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
        // Reflection.
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
