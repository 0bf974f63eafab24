//! Numerical derivative of a sampled signal, `numpy.gradient`.

use crate::error::{check_finite, invalid, DspError, Result};

/// Sample spacing for [`gradient`] (NumPy's `varargs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Spacing<'a> {
    /// Constant step between samples (e.g. `1 / fs_hz` in seconds).
    Uniform(f64),
    /// Coordinates of each sample (same length as the signal, strictly
    /// monotonic). As NumPy, evenly spaced coordinates fall back to the
    /// uniform formulas with step `x[1] - x[0]`.
    Coordinates(&'a [f64]),
}

/// Accuracy of the one-sided differences at the two ends (NumPy's
/// `edge_order`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EdgeOrder {
    /// First order, `(f[1] - f[0]) / h` (NumPy's default).
    #[default]
    First,
    /// Second order, `(-3 f[0] + 4 f[1] - f[2]) / (2h)`.
    Second,
}

enum Dx {
    Uniform(f64),
    Steps(Vec<f64>),
}

/// Derivative of `f` by central differences inside and one-sided
/// differences at the ends, matching `numpy.gradient(f, spacing)`.
///
/// ```text
/// out[i]   = (f[i+1] - f[i-1]) / (2 h)          0 < i < n-1  (thesis Eq. 4.1)
/// out[0]   = (f[1] - f[0]) / h
/// out[n-1] = (f[n-1] - f[n-2]) / h
/// ```
///
/// Units: those of `f` per unit of the spacing (mm and s give mm/s).
///
/// ```
/// use ballpass_dsp::{gradient, Spacing};
/// let v = gradient(&[0.0, 1.0, 4.0, 9.0], Spacing::Uniform(1.0)).unwrap();
/// assert_eq!(v, vec![1.0, 2.0, 4.0, 5.0]);
/// ```
///
/// # Errors
/// As [`gradient_with_edge_order`].
pub fn gradient(f: &[f64], spacing: Spacing<'_>) -> Result<Vec<f64>> {
    gradient_with_edge_order(f, spacing, EdgeOrder::First)
}

/// [`gradient`] with a choice of edge accuracy, matching
/// `numpy.gradient(f, spacing, edge_order=...)`. For non-uniform
/// coordinates the interior uses NumPy's second-order weights
///
/// ```text
/// out[i] = -h2/(h1(h1+h2)) f[i-1] + (h2-h1)/(h1 h2) f[i] + h1/(h2(h1+h2)) f[i+1]
/// ```
///
/// with `h1 = x[i] - x[i-1]`, `h2 = x[i+1] - x[i]`.
///
/// # Errors
/// [`DspError::Empty`] / [`DspError::NonFinite`] for a bad `f` or
/// coordinates; [`DspError::TooShort`] if `f` has fewer than
/// `edge_order + 1` samples; [`DspError::LengthMismatch`] if the coordinates
/// and `f` differ in length; [`DspError::InvalidSetting`] for a zero or
/// non-finite step.
pub fn gradient_with_edge_order(
    f: &[f64],
    spacing: Spacing<'_>,
    edge_order: EdgeOrder,
) -> Result<Vec<f64>> {
    // A uniform step checks `f` through its output (below): every sample
    // enters some output, and a NaN or infinity makes that output NaN or
    // infinite (`(y - inf) c = -inf`, `(inf - inf) c = NaN`), so `f` is
    // scanned only when an output is not finite (then it may be an
    // overflow of finite samples, which NumPy returns as it is).
    let fused = matches!(spacing, Spacing::Uniform(h) if h.is_finite() && h != 0.0) && f.len() >= 3;
    if !fused {
        check_finite("f", f)?;
    }
    let needed = match edge_order {
        EdgeOrder::First => 2,
        EdgeOrder::Second => 3,
    };
    if f.len() < needed {
        return Err(DspError::TooShort {
            what: "f (gradient needs edge_order + 1 samples)",
            needed,
            found: f.len(),
        });
    }
    let dx = match spacing {
        Spacing::Uniform(h) => {
            if !(h.is_finite() && h != 0.0) {
                return Err(invalid(
                    "spacing",
                    format!("must be finite and nonzero, got {h}"),
                ));
            }
            Dx::Uniform(h)
        }
        Spacing::Coordinates(x) => {
            check_finite("coordinates", x)?;
            if x.len() != f.len() {
                return Err(DspError::LengthMismatch {
                    what: "coordinates vs f",
                    expected: f.len(),
                    found: x.len(),
                });
            }
            let d: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
            if let Some(i) = d.iter().position(|v| !(v.is_finite() && *v != 0.0)) {
                return Err(invalid(
                    "coordinates",
                    format!("must be distinct, but x[{}] - x[{i}] = {}", i + 1, d[i]),
                ));
            }
            if d.iter().all(|v| *v == d[0]) {
                Dx::Uniform(d[0])
            } else {
                Dx::Steps(d)
            }
        }
    };
    let n = f.len();
    let mut out = Vec::with_capacity(n);
    match &dx {
        Dx::Uniform(h) => {
            // The interior is `(f[i+1] - f[i-1]) * (1 / (2h))`: a product by
            // the reciprocal instead of NumPy's division by `2h`, which is
            // several times cheaper per sample and differs from NumPy's by
            // at most one rounding (a relative 2.2e-16, checked against the
            // division in `interior_is_within_one_rounding_of_numpys_division`;
            // the SciPy fixtures hold it to 1e-9). The ends are set below; the
            // interior as one pass the compiler vectorises (no zero-fill
            // first, no bounds checks), compiled for the widest vectors the
            // CPU has (the same bits in every instance: no fused operation).
            let inv_h2 = 1.0 / (2.0 * h);
            out.push(0.0);
            let finite = crate::simd::widest(
                #[inline(always)]
                || interior_uniform(f, inv_h2, &mut out),
            );
            out.push(0.0);
            if !finite {
                check_finite("f", f)?;
            }
        }
        Dx::Steps(d) => {
            out.resize(n, 0.0);
            for i in 1..n - 1 {
                let (dx1, dx2) = (d[i - 1], d[i]);
                let a = -dx2 / (dx1 * (dx1 + dx2));
                let b = (dx2 - dx1) / (dx1 * dx2);
                let c = dx1 / (dx2 * (dx1 + dx2));
                out[i] = a * f[i - 1] + b * f[i] + c * f[i + 1];
            }
        }
    }
    match edge_order {
        EdgeOrder::First => {
            let (d0, dn) = match &dx {
                Dx::Uniform(h) => (*h, *h),
                Dx::Steps(d) => (d[0], d[d.len() - 1]),
            };
            out[0] = (f[1] - f[0]) / d0;
            out[n - 1] = (f[n - 1] - f[n - 2]) / dn;
        }
        EdgeOrder::Second => {
            let (a, b, c) = match &dx {
                Dx::Uniform(h) => (-1.5 / h, 2.0 / h, -0.5 / h),
                Dx::Steps(d) => {
                    let (dx1, dx2) = (d[0], d[1]);
                    (
                        -(2.0 * dx1 + dx2) / (dx1 * (dx1 + dx2)),
                        (dx1 + dx2) / (dx1 * dx2),
                        -dx1 / (dx2 * (dx1 + dx2)),
                    )
                }
            };
            out[0] = a * f[0] + b * f[1] + c * f[2];
            let (a, b, c) = match &dx {
                Dx::Uniform(h) => (0.5 / h, -2.0 / h, 1.5 / h),
                Dx::Steps(d) => {
                    let (dx1, dx2) = (d[d.len() - 2], d[d.len() - 1]);
                    (
                        dx2 / (dx1 * (dx1 + dx2)),
                        -(dx2 + dx1) / (dx1 * dx2),
                        (2.0 * dx2 + dx1) / (dx2 * (dx1 + dx2)),
                    )
                }
            };
            out[n - 1] = a * f[n - 3] + b * f[n - 2] + c * f[n - 1];
        }
    }
    if fused && !(out[0].is_finite() && out[n - 1].is_finite()) {
        check_finite("f", f)?;
    }
    Ok(out)
}

/// Outputs per vector group of [`interior_uniform`]: 32, four AVX-512
/// registers, so that each lane's finiteness sum is added once per 32
/// outputs, in four independent chains (with 8, one chain of dependent
/// additions per 8 outputs and the group compiled in 4-, 2- and 1-wide
/// pieces: kernels bench 7.3-7.6 us against 5.2-5.4 us with 32, 6.6-6.8
/// with 16 and 10.8-11.3 with 64, where the group no longer fits the
/// registers; load 9-10).
const GROUP: usize = 32;

/// Appends the interior `out[i] = (f[i+1] - f[i-1]) * inv_h2`,
/// `0 < i < n-1`, to `out` (which holds `out[0]`), and says whether every
/// value is finite. One pass: each group of [`GROUP`] outputs is stored
/// and added into its lanes' checks (`0 x` is `+-0` for finite `x`, NaN
/// otherwise) while in registers. The first `GROUP - 1` interior values
/// are written one by one, so that the groups' stores start at `out[GROUP]`
/// and do not straddle cache lines when the buffer is aligned (numpy's and
/// the allocators' large buffers are): a store split over two lines costs
/// about twice one within a line.
#[inline(always)]
fn interior_uniform(f: &[f64], inv_h2: f64, out: &mut Vec<f64>) -> bool {
    let n = f.len();
    let mut acc = [0.0f64; GROUP];
    let head = GROUP.min(n - 1);
    for i in 1..head {
        let v = (f[i + 1] - f[i - 1]) * inv_h2;
        acc[0] += 0.0 * v;
        out.push(v);
    }
    // Outputs head .. n-1: prev[j] = f[head - 1 + j], next[j] = f[head + 1 + j].
    let (prev, next) = (&f[head - 1..n - 2], &f[head + 1..]);
    let groups = prev.chunks_exact(GROUP).zip(next.chunks_exact(GROUP));
    let done = prev.len() / GROUP * GROUP;
    for (p, q) in groups {
        let mut v = [0.0; GROUP];
        for k in 0..GROUP {
            v[k] = (q[k] - p[k]) * inv_h2;
            acc[k] += 0.0 * v[k];
        }
        out.extend_from_slice(&v);
    }
    for (p, q) in prev[done..].iter().zip(&next[done..]) {
        let v = (q - p) * inv_h2;
        acc[0] += 0.0 * v;
        out.push(v);
    }
    acc.iter().fold(true, |ok, &a| ok & (a == 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validates() {
        assert!(gradient(&[1.0], Spacing::Uniform(1.0)).is_err());
        assert!(gradient(&[1.0, 2.0], Spacing::Uniform(0.0)).is_err());
        assert!(gradient(&[1.0, 2.0], Spacing::Coordinates(&[1.0])).is_err());
        assert!(gradient(&[1.0, 2.0, 3.0], Spacing::Coordinates(&[1.0, 1.0, 2.0])).is_err());
        assert!(
            gradient_with_edge_order(&[1.0, 2.0], Spacing::Uniform(1.0), EdgeOrder::Second)
                .is_err()
        );
    }

    #[test]
    fn a_non_finite_sample_anywhere_is_an_error_and_an_overflow_is_not() {
        // The uniform step checks `f` through its output: a NaN or an
        // infinity at any position (ends, block boundaries of the check)
        // is reported with its index, as the up-front check does; finite
        // samples whose difference overflows give infinities, as NumPy.
        for n in [3, 4, 5, 1025, 1026, 3000] {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                for i in [0, 1, n / 2, n - 2, n - 1]
                    .into_iter()
                    .chain([1023, 1024, 1025])
                {
                    if i >= n {
                        continue;
                    }
                    let mut f: Vec<f64> = (0..n).map(|k| (k as f64 * 0.1).sin()).collect();
                    f[i] = bad;
                    for edge in [EdgeOrder::First, EdgeOrder::Second] {
                        match gradient_with_edge_order(&f, Spacing::Uniform(0.5), edge) {
                            Err(DspError::NonFinite { index, .. }) => assert_eq!(index, i),
                            other => panic!("n {n} i {i} {bad}: {other:?}"),
                        }
                    }
                }
            }
        }
        let f = [f64::MAX, -f64::MAX, f64::MAX, 0.0];
        let g = gradient(&f, Spacing::Uniform(1.0)).unwrap();
        assert_eq!(g[0], f64::NEG_INFINITY);
        assert_eq!(g[1], 0.0);
        assert_eq!(g[2], f64::MAX * 0.5);
    }

    /// The interior in groups of 32, the scalar head and the tail: every
    /// split of a short signal (3 to 140 samples) gives each interior
    /// value as `(f[i+1] - f[i-1]) * (1 / (2h))`, bit for bit.
    #[test]
    fn every_group_split_gives_the_stencil() {
        let all: Vec<f64> = crate::test_noise::noise(140, 7);
        let h = 0.001;
        for n in 3..=all.len() {
            let f = &all[..n];
            let g = gradient(f, Spacing::Uniform(h)).unwrap();
            assert_eq!(g.len(), n);
            for i in 1..n - 1 {
                assert_eq!(
                    g[i].to_bits(),
                    ((f[i + 1] - f[i - 1]) * (1.0 / (2.0 * h))).to_bits()
                );
            }
            assert_eq!(g[0], (f[1] - f[0]) / h);
            assert_eq!(g[n - 1], (f[n - 1] - f[n - 2]) / h);
        }
    }

    #[test]
    fn second_order_edges_are_exact_on_a_parabola() {
        // Exact to rounding (tolerance 1e-12): 2nd-order formulas differentiate
        // quadratics exactly.
        let x = [0.0, 0.5, 1.5, 3.0, 3.5];
        let f: Vec<f64> = x.iter().map(|t| t * t).collect();
        let g = gradient_with_edge_order(&f, Spacing::Coordinates(&x), EdgeOrder::Second).unwrap();
        for (gi, xi) in g.iter().zip(&x) {
            assert!((gi - 2.0 * xi).abs() < 1e-12, "{gi} vs {}", 2.0 * xi);
        }
    }

    #[test]
    fn interior_is_within_one_rounding_of_numpys_division() {
        // NumPy divides the centred difference by 2h; the kernel multiplies
        // by 1/(2h). Each is the exact quotient to half an ulp, the product
        // carries one more rounding of 1/(2h): the two differ by at most
        // 2 ulp relative (bound 4.5e-16), on steps that are not powers of two.
        for h in [1e-3, 1.0 / 3.0, 0.7, 1.0 / 4096.0, 123.456] {
            let f: Vec<f64> = crate::test_noise::noise(1000, 1)
                .into_iter()
                .enumerate()
                .map(|(i, v)| (i as f64 * 0.01).sin() + v)
                .collect();
            let g = gradient(&f, Spacing::Uniform(h)).unwrap();
            for i in 1..f.len() - 1 {
                let numpy = (f[i + 1] - f[i - 1]) / (2.0 * h);
                let rel = ((g[i] - numpy) / numpy).abs();
                assert!(
                    rel <= 4.5e-16,
                    "h {h}, i {i}: {} vs {numpy} ({rel:e})",
                    g[i]
                );
            }
            assert_eq!(g[0], (f[1] - f[0]) / h);
        }
    }
}
