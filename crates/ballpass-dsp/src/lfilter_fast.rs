//! [`lfilter`] split into chunks run side by side: the
//! Python package's `lfilter`, which promises SciPy's numbers to 1e-9, not
//! its rounding.
//!
//! SciPy's direct form II transposed loop waits, sample after sample, on
//! the previous output (a multiply, a subtraction and an add): one sample
//! per ~10 cycles however wide the vectors. Here a long signal is cut into
//! `LANES` chunks, each filtered from rest in one SIMD lane (the same
//! recurrence, lanes in lock step), and then each chunk's output is
//! corrected by the free response of the state it should have started
//! from (the state the previous chunk ended in), which the filter's
//! linearity makes exact:
//!
//! ```text
//! y = y_from_rest(chunk k) + free response of state s_k,   s_k = state at the end of chunk k-1
//! ```
//!
//! The free responses also run as lanes, until each has decayed below
//! `2^-70` of its start (a stable filter's free response decays
//! geometrically, so what is left is far below the rounding of the samples
//! it would be added to); one still alive at the end of its chunk carries
//! its state into the next chunk in another round (at most `LANES - 1`
//! rounds, so an unstable filter terminates too). The result differs from
//! SciPy's by rounding only, which the recurrence amplifies as it
//! amplifies its own: filters whose poles make that amplification large
//! run the plain loop (`MAX_AMPLIFICATION`); the others stay within
//! ~1e-10 of the output's scale of it (tested below against
//! [`lfilter`], and in the Python package against SciPy
//! at 1e-9).

use crate::error::{check_finite, Result};
use crate::sos::{check_ba, lfilter};

/// Chunks run side by side (a 512-bit register of f64; on narrower
/// vectors the compiler splits them).
const LANES: usize = 8;

/// Shortest chunk worth splitting for: below, the plain loop.
const MIN_CHUNK: usize = 256;

/// Free responses below this fraction of their start are dropped.
const SETTLED: f64 = 8.470_329_472_543_003e-22;

/// `scipy.signal.lfilter(b, a, x)` from rest, rounded differently (module
/// docs): equal to [`lfilter`] to rounding, several times faster on long
/// signals. Short signals, FIR filters (`len(a) == 1`) and more than 10
/// coefficients run [`lfilter`] itself.
///
/// ```
/// let (b, a) = ([0.2, 0.3], [1.0, -0.5]);
/// let x: Vec<f64> = (0..5000).map(|i| (i as f64 * 0.37).sin()).collect();
/// let (y, fast) = (ballpass_dsp::lfilter(&b, &a, &x)?, ballpass_dsp::lfilter_fast(&b, &a, &x)?);
/// assert!(y.iter().zip(&fast).all(|(p, q)| (p - q).abs() < 1e-13));
/// # Ok::<(), ballpass_dsp::DspError>(())
/// ```
///
/// # Errors
/// As [`lfilter`].
pub fn lfilter_fast(b: &[f64], a: &[f64], x: &[f64]) -> Result<Vec<f64>> {
    check_ba(b, a)?;
    let n = b.len().max(a.len());
    if a.len() == 1 || !(2..=10).contains(&n) || x.len() < LANES * MIN_CHUNK {
        check_finite("x", x)?;
        return lfilter(b, a, x);
    }
    let mut bn = [0.0; 10];
    let mut an = [0.0; 10];
    for (d, s) in bn.iter_mut().zip(b) {
        *d = s / a[0];
    }
    for (d, s) in an.iter_mut().zip(a) {
        *d = s / a[0];
    }
    if amplification(&an[..n]) > MAX_AMPLIFICATION {
        check_finite("x", x)?;
        return lfilter(b, a, x);
    }
    // `x` is checked through the filtering from rest: a NaN or infinity
    // at `x[i]` makes `b0 x[i]` and so `y[i]` NaN or infinite (`0 inf` is
    // NaN), and adding the free responses keeps it so. Only then is `x`
    // scanned (a finite `x` whose output overflows is returned as is, as
    // SciPy does).
    let (y, finite) = match n {
        2 => chunked::<2>(&bn, &an, x),
        3 => chunked::<3>(&bn, &an, x),
        4 => chunked::<4>(&bn, &an, x),
        5 => chunked::<5>(&bn, &an, x),
        6 => chunked::<6>(&bn, &an, x),
        7 => chunked::<7>(&bn, &an, x),
        8 => chunked::<8>(&bn, &an, x),
        9 => chunked::<9>(&bn, &an, x),
        _ => chunked::<10>(&bn, &an, x),
    };
    if !finite {
        check_finite("x", x)?;
    }
    Ok(y)
}

/// Largest [`amplification`] run in chunks. Measured on Butterworth and
/// Chebyshev designs of order 1-9 at 2-300 Hz (1 kHz) in `b, a` form and
/// lengths of 2 048-30 001 (the test below), the chunked result differs
/// from the plain loop by at most 0.21 times the amplification (norm-wise;
/// below an amplification of 1e-12, by a few units in the last place): at
/// this limit at most ~1e-10 of the output's scale, a tenth of the 1e-9
/// the Python package promises against SciPy. Filters past it
/// run the plain loop (SciPy's order of operations, SciPy's bits).
const MAX_AMPLIFICATION: f64 = 5e-10;

/// How much the recurrence amplifies a difference in rounding, relative to
/// the output's scale: `eps * sum |a_k| / min |A(e^{iw})|` (each step's
/// rounding is about `eps` times `sum |a_k| |y|`, and the feedback
/// `1 / A(z)` amplifies it by up to its peak gain, taken on 257 frequencies
/// from 0 to Nyquist). Poles clustered near the unit circle (a low cutoff
/// of a high order in `b, a` form) make it large: there the recurrence's
/// result is set by its rounding, and only SciPy's own order of operations
/// gives SciPy's numbers.
fn amplification(a: &[f64]) -> f64 {
    let sum: f64 = a.iter().map(|v| v.abs()).sum();
    // e^{iw} stepped by a rotation of pi / 256 (an estimate: the drift of
    // 256 steps, ~1e-14, does not matter), |A|^2 without square roots;
    // the exact form if the squares leave the normal range. The rotation
    // is one chain; the Horner sums at the 257 points are independent and
    // run in SIMD lanes (each lane with the operations of a point alone).
    let (ds, dc) = (std::f64::consts::PI / 256.0).sin_cos();
    let (mut c, mut s) = ([1.0; POINTS], [0.0; POINTS]);
    for i in 1..POINTS {
        (c[i], s[i]) = (c[i - 1] * dc - s[i - 1] * ds, s[i - 1] * dc + c[i - 1] * ds);
    }
    let min_sq = crate::simd::widest(
        #[inline(always)]
        || min_abs_sq(a, &c, &s),
    );
    let min_mag = if min_sq.is_normal() {
        min_sq.sqrt()
    } else {
        (0..POINTS)
            .map(|i| {
                let (s, c) = (std::f64::consts::PI * i as f64 / 256.0).sin_cos();
                let (re, im) = eval_conj(a, c, s);
                re.hypot(im)
            })
            .fold(f64::INFINITY, f64::min)
    };
    f64::EPSILON * sum / min_mag
}

/// Frequencies [`amplification`] looks at, 0 to Nyquist.
const POINTS: usize = 257;

/// `min |A(e^{-iw})|^2` over the points `(cos w, sin w) = (c, s)`, in
/// blocks of 8 lanes ([`eval_conj`]'s operations in each).
#[inline(always)]
fn min_abs_sq(a: &[f64], c: &[f64; POINTS], s: &[f64; POINTS]) -> f64 {
    let mut min_sq = [f64::INFINITY; LANES];
    for (cb, sb) in c.chunks(LANES).zip(s.chunks(LANES)) {
        let (mut re, mut im) = ([0.0; LANES], [0.0; LANES]);
        for &ak in a.iter().rev() {
            for k in 0..cb.len() {
                (re[k], im[k]) = (
                    re[k] * cb[k] + im[k] * sb[k] + ak,
                    im[k] * cb[k] - re[k] * sb[k],
                );
            }
        }
        for k in 0..cb.len() {
            min_sq[k] = min_sq[k].min(re[k] * re[k] + im[k] * im[k]);
        }
    }
    min_sq.iter().fold(f64::INFINITY, |m, &v| m.min(v))
}

/// `A(e^{-iw})` by Horner in `z^{-1} = (c, -s)`, `(c, s) = (cos w, sin w)`.
fn eval_conj(a: &[f64], c: f64, s: f64) -> (f64, f64) {
    let (mut re, mut im) = (0.0, 0.0);
    for &ak in a.iter().rev() {
        (re, im) = (re * c + im * s + ak, im * c - re * s);
    }
    (re, im)
}

/// DF-II-T state of every lane: `z[j][k]` is state `j` of lane `k` (state
/// `N - 1` stays zero, so that the update is one loop).
type State<const N: usize> = [[f64; LANES]; N];

/// The filter of [`lfilter_fast`] by chunks, and whether every output
/// filtered from rest was finite.
fn chunked<const N: usize>(b: &[f64; 10], a: &[f64; 10], x: &[f64]) -> (Vec<f64>, bool) {
    let b: [f64; N] = std::array::from_fn(|j| b[j]);
    let a: [f64; N] = std::array::from_fn(|j| a[j]);
    let n = x.len();
    let len = n / LANES;
    // Chunk k is x[k len .. (k + 1) len] into y[k len .. (k + 1) len]; the
    // lanes read and write one sample of each chunk per step (the loads
    // and stores hide in the wait on the previous output). `y` starts
    // zeroed, not as a copy of `x` filtered in place: writing 8 bytes a
    // sample instead of reading and writing them (the copy was 13 % of
    // the time at 30 000 samples).
    let mut y = vec![0.0; n];
    let mut z: State<N> = [[0.0; LANES]; N];
    let mut finite = crate::simd::widest(
        #[inline(always)]
        || {
            from_rest(
                &b,
                &a,
                &x[..LANES * len],
                &mut y[..LANES * len],
                len,
                &mut z,
            )
        },
    );
    // Lane LANES-1 goes on through the remainder of n / LANES.
    let mut last: [f64; N] = std::array::from_fn(|j| z[j][LANES - 1]);
    for (v, &xn) in y[LANES * len..].iter_mut().zip(&x[LANES * len..]) {
        let yn = last[0] + b[0] * xn;
        for j in 0..N - 1 {
            last[j] = last[j + 1] + xn * b[j + 1] - yn * a[j + 1];
        }
        *v = yn;
        finite &= yn.is_finite();
    }
    // carry[k]: state at the start of chunk k not yet accounted for.
    let mut carry: State<N> = [[0.0; LANES]; N];
    for j in 0..N {
        for k in 1..LANES {
            carry[j][k] = z[j][k - 1];
        }
    }
    let size = |s: &State<N>, k: usize| s.iter().map(|r| r[k].abs()).fold(0.0, f64::max);
    let mut limit = [0.0; LANES];
    for (k, l) in limit.iter_mut().enumerate() {
        *l = SETTLED * size(&carry, k);
    }
    let mut tail = [0.0; N];
    loop {
        let mut w = carry;
        crate::simd::widest(
            #[inline(always)]
            || free(&a, &mut w, &mut y[..LANES * len], len, &limit),
        );
        // The last chunk's free response goes on into the remainder.
        for j in 0..N {
            tail[j] += w[j][LANES - 1];
        }
        // Free responses alive at the end of a middle chunk go on into the
        // next one, measured against their own start.
        carry = [[0.0; LANES]; N];
        let mut next = [0.0; LANES];
        let mut again = false;
        for k in 0..LANES - 1 {
            if size(&w, k) > limit[k] {
                again = true;
                for j in 0..N {
                    carry[j][k + 1] = w[j][k];
                }
                next[k + 1] = limit[k];
            }
        }
        if !again {
            break;
        }
        limit = next;
    }
    // The remainder's share of the last chunk's free response.
    let tail_limit = SETTLED * tail.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for out in &mut y[LANES * len..] {
        if tail.iter().all(|v| v.abs() <= tail_limit) {
            break;
        }
        let yn = tail[0];
        for j in 0..N - 1 {
            tail[j] = tail[j + 1] - yn * a[j + 1];
        }
        *out += yn;
    }
    (y, finite)
}

/// Every lane filtered from rest through its chunk of `x` (`LANES` chunks
/// of `len`) into the same chunk of `y`, in lock step; whether every
/// output was finite (`0 y` summed per lane, off the recurrence's path).
#[inline(always)]
fn from_rest<const N: usize>(
    b: &[f64; N],
    a: &[f64; N],
    x: &[f64],
    y: &mut [f64],
    len: usize,
    z: &mut State<N>,
) -> bool {
    // The state in a local (registers), not behind `z`, which every step
    // would otherwise store and load again on the recurrence's path.
    let mut st = *z;
    let mut acc = [0.0; LANES];
    let (x, y) = (&x[..LANES * len], &mut y[..LANES * len]);
    for i in 0..len {
        let mut xs = [0.0; LANES];
        for k in 0..LANES {
            xs[k] = x[k * len + i];
        }
        let mut yn = [0.0; LANES];
        for k in 0..LANES {
            yn[k] = st[0][k] + b[0] * xs[k];
        }
        for j in 0..N - 1 {
            for k in 0..LANES {
                st[j][k] = st[j + 1][k] + xs[k] * b[j + 1] - yn[k] * a[j + 1];
            }
        }
        for k in 0..LANES {
            y[k * len + i] = yn[k];
            acc[k] += 0.0 * yn[k];
        }
    }
    *z = st;
    acc.iter().all(|&v| v == 0.0)
}

/// The free responses of states `w` added to the lanes' chunks of `y`, in
/// lock step, until every lane has settled below its `limit` (checked
/// every 32 samples) or its chunk ends; `w` is left with each lane's last
/// state.
#[inline(always)]
fn free<const N: usize>(
    a: &[f64; N],
    w: &mut State<N>,
    y: &mut [f64],
    len: usize,
    limit: &[f64; LANES],
) {
    // In a local, as in `from_rest`.
    let mut st = *w;
    let y = &mut y[..LANES * len];
    for i in 0..len {
        if i % 32 == 0 && (0..LANES).all(|k| st.iter().all(|r| r[k].abs() <= limit[k])) {
            break;
        }
        let yn = st[0];
        for j in 0..N - 1 {
            for k in 0..LANES {
                st[j][k] = st[j + 1][k] - yn[k] * a[j + 1];
            }
        }
        for k in 0..LANES {
            y[k * len + i] += yn[k];
        }
    }
    *w = st;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{butter, cheby1, FilterBand};

    /// Test noise plus a slow sine on an offset (a filter's slow poles
    /// see a step at the start).
    fn noise(n: usize, seed: u64) -> Vec<f64> {
        crate::test_noise::noise(n, seed)
            .into_iter()
            .enumerate()
            .map(|(i, v)| v + (i as f64 * 0.01).sin() + 3.0)
            .collect()
    }

    /// b/a of a second-order-section design, multiplied out.
    fn ba(sos: &crate::Sos) -> (Vec<f64>, Vec<f64>) {
        let mul = |p: &[f64], q: &[f64]| {
            let mut r = vec![0.0; p.len() + q.len() - 1];
            for (i, u) in p.iter().enumerate() {
                for (j, v) in q.iter().enumerate() {
                    r[i + j] += u * v;
                }
            }
            r
        };
        let (mut b, mut a) = (vec![1.0], vec![1.0]);
        for s in sos.sections() {
            b = mul(&b, &s[..3]);
            a = mul(&a, &s[3..]);
        }
        (b, a)
    }

    #[test]
    fn equals_the_plain_loop_to_rounding() {
        // Butterworth designs of order 1-9 at 2-300 Hz and Chebyshev ones
        // at 40 Hz (1 kHz; slow poles near z = 1 make free responses that
        // outlive a chunk at 2 048 samples), a first-order smoother, lengths
        // with and without a remainder. Those past MAX_AMPLIFICATION run the
        // plain loop (bit for bit); the others must be within half their
        // amplification plus 64 ulp of the plain loop, norm-wise (observed:
        // at most 0.21 times the amplification above 1e-12, the bound the
        // limit's choice rests on; a few ulp below).
        let mut filters = vec![(vec![0.2, 0.3], vec![1.0, -0.5])];
        for order in 1..=9 {
            for fc in [2.0, 20.0, 50.0, 100.0, 300.0] {
                let band = FilterBand::LowPass { cutoff_hz: fc };
                filters.push(ba(&butter(order, band, 1000.0).unwrap()));
            }
            let band = FilterBand::LowPass { cutoff_hz: 40.0 };
            filters.push(ba(&cheby1(order, 0.5, band, 1000.0).unwrap()));
        }
        let mut chunked = 0;
        for (b, a) in &filters {
            let amp = amplification(a);
            for n in [2048, 2055, 16_000, 30_001] {
                let x = noise(n, n as u64);
                let (want, got) = (lfilter(b, a, &x).unwrap(), lfilter_fast(b, a, &x).unwrap());
                if amp > MAX_AMPLIFICATION {
                    assert_eq!(want, got, "b {b:?} a {a:?} n {n}: the plain loop");
                    continue;
                }
                chunked += 1;
                let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let worst = want
                    .iter()
                    .zip(&got)
                    .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                assert!(
                    worst <= (0.5 * amp + 64.0 * f64::EPSILON) * scale,
                    "b {b:?} a {a:?} n {n}: {:e} of the scale, amplification {amp:e}",
                    worst / scale
                );
            }
        }
        // Most designs run in chunks (the 20 Hz Butterworth of order 5,
        // the analysis' low-pass, among them).
        assert!(chunked >= 100, "{chunked}");
        let lp = ba(&butter(5, FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0).unwrap());
        assert!(amplification(&lp.1) <= MAX_AMPLIFICATION);
    }

    /// The lane evaluation of the smallest `|A|^2` is the point-by-point
    /// one (the rotation, then `eval_conj` at each point), bit for bit.
    #[test]
    fn amplification_in_lanes_equals_point_by_point() {
        let (ds, dc) = (std::f64::consts::PI / 256.0).sin_cos();
        let mut designs = vec![vec![1.0, -0.5], vec![1.0, -1.001], vec![2.0, 0.3, -0.7]];
        for order in [1, 5, 9] {
            let band = FilterBand::LowPass { cutoff_hz: 20.0 };
            designs.push(ba(&butter(order, band, 1000.0).unwrap()).1);
        }
        for a in &designs {
            let (mut c, mut s) = (1.0, 0.0);
            let (mut cs, mut ss) = ([0.0; POINTS], [0.0; POINTS]);
            let mut want = f64::INFINITY;
            for i in 0..POINTS {
                (cs[i], ss[i]) = (c, s);
                let (re, im) = eval_conj(a, c, s);
                want = want.min(re * re + im * im);
                (c, s) = (c * dc - s * ds, s * dc + c * ds);
            }
            let got = crate::simd::widest(|| min_abs_sq(a, &cs, &ss));
            assert_eq!(got.to_bits(), want.to_bits(), "a {a:?}");
            assert_eq!(min_abs_sq(a, &cs, &ss).to_bits(), want.to_bits());
        }
    }

    #[test]
    fn short_fir_and_bad_input_take_the_plain_path() {
        let x = noise(100, 3);
        let (b, a) = ([0.2, 0.3], [1.0, -0.5]);
        assert_eq!(
            lfilter_fast(&b, &a, &x).unwrap(),
            lfilter(&b, &a, &x).unwrap()
        );
        let long = noise(5000, 4);
        assert_eq!(
            lfilter_fast(&[0.5, 0.5], &[2.0], &long).unwrap(),
            lfilter(&[0.5, 0.5], &[2.0], &long).unwrap()
        );
        assert!(lfilter_fast(&b, &[0.0, 1.0], &long).is_err());
        let mut bad = long.clone();
        bad[4000] = f64::NAN;
        assert!(lfilter_fast(&b, &a, &bad).is_err());
        // The chunked path checks `x` through its output: a NaN or an
        // infinity anywhere (chunk starts and ends, the remainder, the
        // last sample; b0 = 0 too) is reported with its index.
        let long = noise(5003, 6);
        let len = 5003 / LANES;
        for (b, a) in [([0.2, 0.3], [1.0, -0.5]), ([0.0, 0.3], [1.0, -0.5])] {
            for i in [
                0,
                1,
                len - 1,
                len,
                3 * len + 7,
                LANES * len - 1,
                LANES * len,
                5002,
            ] {
                for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                    let mut bad = long.clone();
                    bad[i] = v;
                    match lfilter_fast(&b, &a, &bad) {
                        Err(crate::DspError::NonFinite { index, .. }) => assert_eq!(index, i),
                        other => panic!("b {b:?} i {i} {v}: {other:?}"),
                    }
                }
            }
        }
    }

    #[test]
    fn an_unstable_filter_terminates_and_grows_as_the_plain_loop() {
        // Pole at 1.001: the free responses never settle; the rounds stop
        // after LANES - 1 carries and the result still equals the plain
        // loop to rounding of its (growing) scale.
        let (b, a) = ([1.0], [1.0, -1.001]);
        let x = noise(4096, 5);
        let (want, got) = (
            lfilter(&b, &a, &x).unwrap(),
            lfilter_fast(&b, &a, &x).unwrap(),
        );
        for (p, q) in want.iter().zip(&got) {
            assert!((p - q).abs() <= 1e-12 * p.abs().max(1.0), "{p} vs {q}");
        }
    }
}
