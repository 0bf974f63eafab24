//! The exact median of the speeds over three passes (module docs of
//! [`super`]).

use crate::error::{Error, Result};

/// Bits of `|v|` counted per pass (three passes cover the 63 bits of a
/// non-negative `f64`).
const DIGIT_BITS: u32 = 21;
/// Passes the exact median takes.
pub(super) const SELECT_PASSES: usize = 3;

/// One middle value of the speeds being selected: its rank among the
/// values still in play and the bits fixed so far.
#[derive(Clone, Copy)]
struct Target {
    rank: u64,
    prefix: u64,
}

/// Exact selection of the median of `|v|` over [`SELECT_PASSES`] passes.
pub(super) struct Median {
    n: u64,
    level: u32,
    targets: [Target; 2],
    hist: [Vec<u64>; 2],
    seen: u64,
}

impl Median {
    pub(super) fn new(n: usize) -> Self {
        let n = n as u64;
        let lo = n.saturating_sub(1) / 2;
        let t = |rank| Target { rank, prefix: 0 };
        let mut m = Median {
            n,
            level: 0,
            targets: [t(lo), t(n / 2)],
            hist: [Vec::new(), Vec::new()],
            seen: 0,
        };
        m.alloc();
        m
    }

    fn shift(&self) -> u32 {
        DIGIT_BITS * (SELECT_PASSES as u32 - 1 - self.level)
    }

    fn alloc(&mut self) {
        self.hist[0] = vec![0; 1 << DIGIT_BITS];
        self.hist[1] = if self.shared() {
            Vec::new()
        } else {
            vec![0; 1 << DIGIT_BITS]
        };
    }

    /// Whether both middle values share their bits so far (one histogram).
    fn shared(&self) -> bool {
        self.targets[0].prefix == self.targets[1].prefix
    }

    pub(super) fn add(&mut self, speeds: &[f64]) {
        let shift = self.shift();
        // At most 63: the bits above the digit, fixed so far.
        let top = shift + DIGIT_BITS;
        let mask = (1u64 << DIGIT_BITS) - 1;
        let used = if self.shared() { 1 } else { 2 };
        for &x in speeds {
            let key = x.abs().to_bits();
            self.seen += 1;
            let digit = ((key >> shift) & mask) as usize;
            for (t, h) in self.targets.iter().zip(self.hist.iter_mut()).take(used) {
                if key >> top == t.prefix >> top {
                    h[digit] += 1;
                }
            }
        }
    }

    /// Ends a pass: fixes the next bits of each middle value; the median
    /// once all are fixed.
    pub(super) fn end_pass(&mut self, name: &str) -> Result<Option<f64>> {
        super::super::support::check_count(name, self.seen as usize, self.n as usize)?;
        self.seen = 0;
        let shift = self.shift();
        let shared = self.shared();
        for i in 0..2 {
            let h = &self.hist[if shared { 0 } else { i }];
            let t = &mut self.targets[i];
            let mut below = 0u64;
            let d = h
                .iter()
                .position(|&c| {
                    if below + c > t.rank {
                        true
                    } else {
                        below += c;
                        false
                    }
                })
                .ok_or_else(|| Error::InvalidRecording {
                    source_name: name.into(),
                    reason:
                        "the speeds changed between passes (the file changed while it was read?)"
                            .into(),
                })?;
            t.rank -= below;
            t.prefix |= (d as u64) << shift;
        }
        self.level += 1;
        if self.level as usize == SELECT_PASSES {
            self.hist = [Vec::new(), Vec::new()];
            let [a, b] = self.targets.map(|t| f64::from_bits(t.prefix));
            return Ok(Some(if self.n % 2 == 1 { a } else { 0.5 * (a + b) }));
        }
        self.alloc();
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Selection over the passes against the sorted values: odd and even
    /// counts, ties, middle values far apart in their bits, zeros.
    #[test]
    fn the_median_is_the_sorted_one_to_the_bit() {
        let mut state = 11u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let sets: Vec<Vec<f64>> = vec![
            (0..1001).map(|_| 9.0 + 1e-6 * next()).collect(),
            (0..1000).map(|_| -9.0 - 1e-9 * next()).collect(),
            vec![1.0, 1.0, 1.0, 2.0],
            vec![0.0, 1e-300, 5.0, 1e10],
            (0..777)
                .map(|i| if i % 2 == 0 { 0.5 } else { 4.0 * next() })
                .collect(),
        ];
        for x in sets {
            let want =
                crate::stats::median(&x.iter().map(|v| v.abs()).collect::<Vec<_>>()).unwrap();
            let mut m = Median::new(x.len());
            let mut got = None;
            for _ in 0..SELECT_PASSES {
                // In uneven pieces, as blocks come.
                for c in x.chunks(97) {
                    m.add(c);
                }
                got = m.end_pass("test").unwrap();
            }
            assert_eq!(got.map(f64::to_bits), Some(want.to_bits()), "{x:?}");
        }
    }
}
