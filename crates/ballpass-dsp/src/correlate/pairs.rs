//! The pass between the forward and inverse transforms of a correlation:
//! forward post-processing, the spectral product and the inverse
//! pre-processing of each bin pair in one pass, [`P`] pairs per vector block.

use rustfft::num_complex::Complex;

use crate::fftplan::{forward_ends, forward_pair, inverse_ends, inverse_pair, HalfComplex};

/// From the raw half-length transforms `zx`, `zy` of `x` and `y` (see
/// [`HalfComplex`]), the input of the inverse transform of the
/// cross-spectrum `P[k] = X[k] conj Y[k]` (or `|X[k]|^2` when `AUTO`, with
/// `zy` equal to `zx`), one bin pair `(k, m - k)` at a time: the forward
/// post-processing, the product and the inverse pre-processing in one
/// pass, with realfft's operations in realfft's order (the values equal
/// the separate passes' bit for bit; tested).
#[inline(always)]
pub(super) fn product_pass<const AUTO: bool>(
    fft: &HalfComplex,
    zx: &[Complex<f64>],
    zy: &[Complex<f64>],
    out: &mut [Complex<f64>],
) {
    let m = out.len();
    let prod = |x: Complex<f64>, y: Complex<f64>| {
        if AUTO {
            Complex::new(x.norm_sqr(), 0.0)
        } else {
            x * y.conj()
        }
    };
    let (Some(&x0), Some(&y0)) = (zx.first(), zy.first()) else {
        return;
    };
    let (x0, xm) = forward_ends(x0);
    let (y0, ym) = forward_ends(y0);
    out[0] = inverse_ends(prod(x0, y0), prod(xm, ym));
    let pairs = fft.pairs();
    let (lo, hi) = out[1..].split_at_mut(pairs);
    let skip = hi.len() - pairs;
    let hi = &mut hi[skip..];
    // Pair i: bins k = 1 + i (lo[i]) and m - k (hi[pairs - 1 - i]).
    let n = pairs;
    let (xl, xh, yl, yh) = (&zx[1..=n], &zx[m - n..m], &zy[1..=n], &zy[m - n..m]);
    let (w, lo, hi) = (&fft.twiddles[..n], &mut lo[..n], &mut hi[..n]);
    // Whole blocks of P pairs (vector code), then the pairs left over one
    // by one.
    let b = n / P * P;
    let blocks = (w[..b].chunks_exact(P).zip(xl.chunks_exact(P)))
        .zip(xh[n - b..].rchunks_exact(P).zip(yl.chunks_exact(P)))
        .zip(yh[n - b..].rchunks_exact(P))
        .zip(
            lo[..b]
                .chunks_exact_mut(P)
                .zip(hi[n - b..].rchunks_exact_mut(P)),
        );
    for ((((w, xl), (xh, yl)), yh), (ol, oh)) in blocks {
        pair_block::<AUTO>(w, (xl, xh), (yl, yh), (ol, oh));
    }
    for i in b..n {
        let r = n - 1 - i;
        let (xk, xj) = forward_pair(w[i], xl[i], xh[r]);
        let (yk, yj) = if AUTO {
            (xk, xj)
        } else {
            forward_pair(w[i], yl[i], yh[r])
        };
        (lo[i], hi[r]) = inverse_pair(w[i], prod(xk, yk), prod(xj, yj));
    }
    if m % 2 == 0 && m > 1 {
        // The centre bin k = m/2: X = conj Z, and the inverse input is
        // conj(2 P).
        let c = m / 2;
        let p = prod(zx[c].conj(), zy[c].conj());
        out[c] = (p + p).conj();
    }
}

/// Bin pairs per block of [`pair_block`].
const P: usize = 8;

/// One component (real or imaginary parts) of [`P`] bins, one bin per
/// lane: the block arithmetic is the same operation in every lane, which
/// the compiler turns into plain vector code (no lane shuffles but those
/// that split the interleaved bins on load and join them on store).
type L = [f64; P];

/// The real and imaginary parts of `b`, lane `t` holding `b[t]` (or
/// `b[P - 1 - t]` when `rev`).
#[inline(always)]
fn split(b: &[Complex<f64>; P], rev: bool) -> (L, L) {
    // Interleaved first (one plain load), then picked lane by lane.
    let v: [f64; 2 * P] = std::array::from_fn(|i| {
        let c = b[i / 2];
        if i % 2 == 0 {
            c.re
        } else {
            c.im
        }
    });
    let at = |t: usize| if rev { P - 1 - t } else { t };
    (
        std::array::from_fn(|t| v[2 * at(t)]),
        std::array::from_fn(|t| v[2 * at(t) + 1]),
    )
}

/// The inverse of [`split`].
#[inline(always)]
fn join(o: &mut [Complex<f64>; P], (re, im): (L, L), rev: bool) {
    let at = |t: usize| if rev { P - 1 - t } else { t };
    let v: [f64; 2 * P] = std::array::from_fn(|i| {
        if i % 2 == 0 {
            re[at(i / 2)]
        } else {
            im[at(i / 2)]
        }
    });
    for (c, p) in o.iter_mut().zip(v.chunks_exact(2)) {
        *c = Complex::new(p[0], p[1]);
    }
}

/// `f(a[t], b[t])` in every lane.
#[inline(always)]
fn lanes(a: L, b: L, f: impl Fn(f64, f64) -> f64) -> L {
    std::array::from_fn(|t| f(a[t], b[t]))
}

/// The part [`forward_pair`] and [`inverse_pair`] share, in every lane:
/// with `s = a + b` and `d = a - b`, `(s.re, d.im, s.im tre + d.re tim,
/// s.im tim - d.re tre)`.
#[inline(always)]
fn twiddled(a: (L, L), b: (L, L), tre: L, tim: L) -> (L, L, L, L) {
    let (sum_re, sum_im) = (lanes(a.0, b.0, |a, b| a + b), lanes(a.1, b.1, |a, b| a + b));
    let (diff_re, diff_im) = (lanes(a.0, b.0, |a, b| a - b), lanes(a.1, b.1, |a, b| a - b));
    (
        sum_re,
        diff_im,
        std::array::from_fn(|t| sum_im[t] * tre[t] + diff_re[t] * tim[t]),
        std::array::from_fn(|t| sum_im[t] * tim[t] - diff_re[t] * tre[t]),
    )
}

/// [`forward_pair`] in every lane: the same operations in the same order.
#[inline(always)]
fn forward_lanes(w: (L, L), zk: (L, L), zj: (L, L)) -> ((L, L), (L, L)) {
    let (tre, tim) = (w.0.map(|v| v * 0.5), w.1.map(|v| v * 0.5));
    let (sum_re, diff_im, twiddled_re, twiddled_im) = twiddled(zk, zj, tre, tim);
    let half_sum_re = sum_re.map(|v| 0.5 * v);
    let half_diff_im = diff_im.map(|v| 0.5 * v);
    (
        (
            lanes(half_sum_re, twiddled_re, |a, b| a + b),
            lanes(half_diff_im, twiddled_im, |a, b| a + b),
        ),
        (
            lanes(half_sum_re, twiddled_re, |a, b| a - b),
            lanes(twiddled_im, half_diff_im, |a, b| a - b),
        ),
    )
}

/// [`inverse_pair`] in every lane: the same operations in the same order.
#[inline(always)]
fn inverse_lanes(w: (L, L), xk: (L, L), xj: (L, L)) -> ((L, L), (L, L)) {
    let (tre, tim) = (w.0, w.1.map(|v| -v));
    let (sum_re, diff_im, twiddled_re, twiddled_im) = twiddled(xk, xj, tre, tim);
    (
        (
            lanes(sum_re, twiddled_re, |a, b| a - b),
            lanes(diff_im, twiddled_im, |a, b| a - b),
        ),
        (
            lanes(sum_re, twiddled_re, |a, b| a + b),
            std::array::from_fn(|t| -twiddled_im[t] - diff_im[t]),
        ),
    )
}

/// The product of [`product_pass`] in every lane: `x conj(y)` as
/// `num_complex` computes it (`(x.re b.re - x.im b.im, x.re b.im + x.im
/// b.re)` with `b = conj y`), or `(|x|^2, 0)` when `AUTO`.
#[inline(always)]
fn product_lanes<const AUTO: bool>(x: (L, L), y: (L, L)) -> (L, L) {
    if AUTO {
        (
            std::array::from_fn(|t| x.0[t] * x.0[t] + x.1[t] * x.1[t]),
            [0.0; P],
        )
    } else {
        let (b_re, b_im) = (y.0, y.1.map(|v| -v));
        (
            std::array::from_fn(|t| x.0[t] * b_re[t] - x.1[t] * b_im[t]),
            std::array::from_fn(|t| x.0[t] * b_im[t] + x.1[t] * b_re[t]),
        )
    }
}

/// [`P`] bin pairs of [`product_pass`]: pair `t` is `xl[t]` with
/// `xh[P - 1 - t]` (and the same for `y` and the outputs), twiddle `w[t]`;
/// each lane does the single-pair functions' operations
/// ([`forward_pair`], the product, [`inverse_pair`]), so the values are
/// theirs bit for bit (tested).
#[inline(always)]
fn pair_block<const AUTO: bool>(
    w: &[Complex<f64>],
    (xl, xh): (&[Complex<f64>], &[Complex<f64>]),
    (yl, yh): (&[Complex<f64>], &[Complex<f64>]),
    (ol, oh): (&mut [Complex<f64>], &mut [Complex<f64>]),
) {
    type B<'s> = &'s [Complex<f64>; P];
    type O<'s> = &'s mut [Complex<f64>; P];
    let (Ok(w), Ok(xl), Ok(xh), Ok(yl), Ok(yh), Ok(ol), Ok(oh)) = (
        B::try_from(w),
        B::try_from(xl),
        B::try_from(xh),
        B::try_from(yl),
        B::try_from(yh),
        O::try_from(ol),
        O::try_from(oh),
    ) else {
        // `product_pass` hands over blocks of exactly P bins.
        if cfg!(debug_assertions) {
            unreachable!("pair_block takes blocks of {P} bins");
        }
        return;
    };
    let w = split(w, false);
    let (xk, xj) = forward_lanes(w, split(xl, false), split(xh, true));
    let (pk, pj) = if AUTO {
        (product_lanes::<true>(xk, xk), product_lanes::<true>(xj, xj))
    } else {
        let (yk, yj) = forward_lanes(w, split(yl, false), split(yh, true));
        (
            product_lanes::<false>(xk, yk),
            product_lanes::<false>(xj, yj),
        )
    };
    let (qk, qj) = inverse_lanes(w, pk, pj);
    join(ol, qk, false);
    join(oh, qj, true);
}
