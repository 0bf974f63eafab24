//! Seeded uniform noise for the unit tests (xorshift, no dependency).

/// `n` values uniform in [-0.5, 0.5) from seed `s` (non-zero).
pub(crate) fn noise(n: usize, mut s: u64) -> Vec<f64> {
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}
