//! The position grid's resampling (module docs of [`super`], "resample"):
//! a signal's value where the running maximum of the travel first reaches
//! each grid point, by linear interpolation between samples.

/// Walks the running maximum of `sign · p` (a non-decreasing travel axis)
/// to each grid point `x0 + j dx`, `j = 0..m`, in order, and calls
/// `at(i, t)` with the sample `i` and the fraction `t` at which it first
/// reaches the point: the value there is `y[i − 1] + t (y[i] − y[i − 1])`.
/// The running maximum is taken as the walk goes, never stored.
fn walk(p: &[f64], sign: f64, x0: f64, dx: f64, m: usize, mut at: impl FnMut(usize, f64)) {
    // The running maximum at samples i - 1 and i.
    let mut prev = f64::NEG_INFINITY.max(sign * p[0]);
    let mut cur = prev.max(sign * p[1]);
    let mut i = 1;
    for j in 0..m {
        let x = x0 + j as f64 * dx;
        while i + 1 < p.len() && cur < x {
            i += 1;
            prev = cur;
            cur = cur.max(sign * p[i]);
        }
        let (a, b) = (prev, cur);
        let t = if b > a {
            ((x - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        at(i, t);
    }
}

/// Values of `y` where the running maximum of `sign · p` first reaches
/// each grid point `x0 + j dx`, `j = 0..m` (linear interpolation between
/// samples; [`walk`]).
pub(super) fn resample(p: &[f64], sign: f64, y: &[f64], x0: f64, dx: f64, m: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(m);
    walk(p, sign, x0, dx, m, |i, t| {
        out.push(y[i - 1] + t * (y[i] - y[i - 1]));
    });
    out
}

/// The walk of [`resample`] made once for several signals: for each grid
/// point, the sample `i` and the fraction `t` that [`resample`] takes
/// `y[i − 1] + t (y[i] − y[i − 1])` with.
pub(super) struct Walk {
    i: Vec<u32>,
    t: Vec<f64>,
}

impl Walk {
    /// [`resample`]'s walk over `p` (at most `u32::MAX` samples).
    pub(super) fn new(p: &[f64], sign: f64, x0: f64, dx: f64, m: usize) -> Walk {
        let (mut iv, mut tv) = (Vec::with_capacity(m), Vec::with_capacity(m));
        walk(p, sign, x0, dx, m, |i, t| {
            iv.push(i as u32);
            tv.push(t);
        });
        Walk { i: iv, t: tv }
    }

    /// [`resample`] of `y` along the walk: the same values.
    pub(super) fn apply(&self, y: &[f64]) -> Vec<f64> {
        self.i
            .iter()
            .zip(&self.t)
            .map(|(&i, &t)| {
                let i = i as usize;
                y[i - 1] + t * (y[i] - y[i - 1])
            })
            .collect()
    }
}

/// Longest record whose walks `resample_record` makes once for all its
/// signals (their indices and fractions hold about one record-length
/// buffer); a longer one walks again for each signal.
pub(super) const SHARED_WALK_MAX_SAMPLES: usize = 1 << 20;

#[cfg(test)]
mod tests {
    use super::*;

    /// The walk made once and applied to a signal gives [`resample`]'s
    /// values bit for bit, on a travel with stops and a step back.
    #[test]
    fn shared_walk_equals_resample_bitwise() {
        let n = 5000;
        let p: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / 1000.0;
                let back = if (2000..2100).contains(&i) { 0.01 } else { 0.0 };
                9.0 * t + 0.3 * (3.1 * t).sin() - back
                    + if (3001..3050).contains(&i) { -0.2 } else { 0.0 }
            })
            .collect();
        let y: Vec<f64> = (0..n)
            .map(|i| (0.0137 * i as f64).cos() * 1.7 + 0.1)
            .collect();
        let back: Vec<f64> = p.iter().map(|v| -v).collect();
        for (sign, ps) in [(1.0, &p), (-1.0, &back)] {
            let (x0, dx, m) = (0.05, 0.0158, 2500);
            let want = resample(ps, sign, &y, x0, dx, m);
            let got = Walk::new(ps, sign, x0, dx, m).apply(&y);
            assert_eq!(want.len(), got.len());
            for (a, b) in want.iter().zip(&got) {
                assert_eq!(a.to_bits(), b.to_bits());
            }
        }
    }
}
