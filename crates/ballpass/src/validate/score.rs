//! Rates with their exact binomial intervals.

use serde::{Deserialize, Serialize};

use crate::stats::reg_inc_beta;

/// `k` of `n`, the rate and its exact (Clopper–Pearson) 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Rate {
    /// Events.
    pub k: usize,
    /// Trials.
    pub n: usize,
    /// `k / n` (0 for `n = 0`).
    pub rate: f64,
    /// 95 % interval.
    pub ci95: [f64; 2],
}

impl Rate {
    /// The rate of `k` in `n`.
    pub fn of(k: usize, n: usize) -> Self {
        Self {
            k,
            n,
            rate: if n == 0 { 0.0 } else { k as f64 / n as f64 },
            ci95: clopper_pearson(k, n, 0.95),
        }
    }
}

impl std::fmt::Display for Rate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}/{} = {:.2} % (95 %: {:.2}–{:.2} %)",
            self.k,
            self.n,
            100.0 * self.rate,
            100.0 * self.ci95[0],
            100.0 * self.ci95[1]
        )
    }
}

/// Exact (Clopper–Pearson) interval of level `level` for `k` events in `n`
/// trials: the beta quantiles `B(α/2; k, n − k + 1)` and
/// `B(1 − α/2; k + 1, n − k)`, `α = 1 − level` (0 and 1 at the ends; the
/// whole of `[0, 1]` for `n = 0`).
pub fn clopper_pearson(k: usize, n: usize, level: f64) -> [f64; 2] {
    if n == 0 {
        return [0.0, 1.0];
    }
    let k = k.min(n);
    let alpha = 1.0 - level;
    let (kf, nf) = (k as f64, n as f64);
    let lo = if k == 0 {
        0.0
    } else {
        beta_quantile(alpha / 2.0, kf, nf - kf + 1.0)
    };
    let hi = if k == n {
        1.0
    } else {
        beta_quantile(1.0 - alpha / 2.0, kf + 1.0, nf - kf)
    };
    [lo, hi]
}

/// The `p` quantile of the beta distribution `(a, b)`, by bisection on its
/// CDF (monotone; 100 halvings leave an interval below 1e-30).
fn beta_quantile(p: f64, a: f64, b: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if reg_inc_beta(a, b, mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clopper_pearson_matches_scipy() {
        // scipy.stats.beta.ppf(0.025, k, n − k + 1) and
        // beta.ppf(0.975, k + 1, n − k) (SciPy 1.x); the continued fraction
        // is good to ~1e-12, so 1e-9 leaves room.
        let cases = [
            (0, 10, 0.0, 0.308_497_107_818_760_7),
            (50, 100, 0.398_321_129_503_300_95, 0.601_678_870_496_699),
            (3, 20, 0.032_070_937_185_463_7, 0.378_926_826_545_313_96),
            (400, 400, 0.990_820_195_416_334_7, 1.0),
        ];
        for (k, n, lo, hi) in cases {
            let r = Rate::of(k, n);
            assert!((r.ci95[0] - lo).abs() < 1e-9, "{k}/{n}: {r:?}");
            assert!((r.ci95[1] - hi).abs() < 1e-9, "{k}/{n}: {r:?}");
        }
        assert_eq!(Rate::of(0, 0).ci95, [0.0, 1.0]);
    }
}
