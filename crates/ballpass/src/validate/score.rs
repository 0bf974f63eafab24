//! Rates with their exact binomial intervals.

use serde::{Deserialize, Serialize};

use crate::stats::binomial_interval;

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
            ci95: binomial_interval(k, n, 0.95),
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
