//! Mean power of equal-length segments at arbitrary frequencies (not
//! SciPy): `(1/S) Σ_s |Σ_n v_s[n] e^{−2πi f n dx}|²`, the Welch average of
//! already detrended and windowed segments evaluated between the FFT bins
//! (the zero-padded Welch spectrum, up to its scale), for locating a line
//! to a fraction of a bin.
//!
//! The phasor `e^{−i step n}`, `step = 2π f dx`, is rotated sample by
//! sample and renormalised every 256 points; per segment the sums
//! `Σ v·pr` and `−Σ v·pi` run in sample order, and the powers are added
//! in segment order. Every frequency gets exactly that arithmetic whatever
//! the lane count or vector width (`tests::power_alone` is the
//! one-frequency reference, checked bit for bit): frequencies run 16 at a
//! time in lock step, segments up to 4 at a time with the phasors made on
//! the way and shared by the group (independent sums keep the adder
//! busy; no phasor table in memory), compiled
//! for the widest vectors the CPU has through `crate::simd::widest` (no
//! FMA, so every operation rounds as the baseline's).

use crate::error::{check_finite, invalid, Result};

/// `(re, im)` of `L` lanes.
type Phasors<const L: usize> = ([f64; L], [f64; L]);

/// Segments summed side by side.
const G: usize = 4;

/// Mean power over `segments` (all of one length, at least one) at each
/// frequency of `freqs` (cycles per unit of `dx`, the sample spacing):
/// `(1/S) Σ_s |Σ_n v_s[n] e^{−2πi f n dx}|²` (module docs for the exact
/// arithmetic).
///
/// # Errors
/// No segment, segments of different or zero length, a non-finite sample,
/// frequency or `dx`.
pub fn segment_powers(segments: &[&[f64]], dx: f64, freqs: &[f64]) -> Result<Vec<f64>> {
    let Some(first) = segments.first() else {
        return Err(invalid("segments", "at least one segment is needed"));
    };
    let n = first.len();
    if n == 0 || segments.iter().any(|s| s.len() != n) {
        return Err(invalid(
            "segments",
            "all segments must have the same, non-zero length",
        ));
    }
    if !dx.is_finite() {
        return Err(invalid("dx", format!("must be finite, got {dx}")));
    }
    for s in segments {
        check_finite("segments", s)?;
    }
    if !freqs.is_empty() {
        check_finite("freqs", freqs)?;
    }
    // `#[inline(always)]`: the closure must be compiled inside the wide
    // function; left to the inliner, the wheel's build kept it out of line,
    // as SSE2 code (two lanes per register instead of eight).
    Ok(crate::simd::widest(
        #[inline(always)]
        || powers(segments, dx, freqs),
    ))
}

/// [`segment_powers`] on checked input: chunks of 16 frequencies (two
/// independent phasor chains per vector width hide the rotation's
/// latency), the last 8 or fewer as one chunk of 8.
#[inline(always)]
fn powers(segments: &[&[f64]], dx: f64, freqs: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(freqs.len());
    let mut rest = freqs;
    while !rest.is_empty() {
        let take = if rest.len() > 8 {
            rest.len().min(16)
        } else {
            rest.len()
        };
        let (chunk, tail) = rest.split_at(take);
        if take > 8 {
            chunk_powers::<16>(segments, dx, chunk, &mut out);
        } else {
            chunk_powers::<8>(segments, dx, chunk, &mut out);
        }
        rest = tail;
    }
    out
}

/// Appends to `out` the mean powers at the (up to `L`) frequencies of
/// `chunk`, in lock step: the segments 4 at a time, the last 1 to 3
/// together.
#[inline(always)]
fn chunk_powers<const L: usize>(segments: &[&[f64]], dx: f64, chunk: &[f64], out: &mut Vec<f64>) {
    let count = segments.len() as f64;
    // Unused lanes rotate by zero (cos 1, sin 0) and are dropped.
    let (mut c, mut sn) = ([1.0f64; L], [0.0f64; L]);
    for (j, f) in chunk.iter().enumerate() {
        let step = std::f64::consts::TAU * f * dx;
        (c[j], sn[j]) = (step.cos(), step.sin());
    }
    let mut total = [0.0f64; L];
    let mut groups = segments.chunks_exact(G);
    for group in groups.by_ref() {
        let group: &[&[f64]; G] = group.try_into().expect("G segments");
        add_powers(&mut total, &sums::<L, G>(group, &c, &sn));
    }
    match *groups.remainder() {
        [a, b, d] => add_powers(&mut total, &sums::<L, 3>(&[a, b, d], &c, &sn)),
        [a, b] => add_powers(&mut total, &sums::<L, 2>(&[a, b], &c, &sn)),
        [a] => add_powers(&mut total, &sums::<L, 1>(&[a], &c, &sn)),
        _ => {}
    }
    out.extend(total[..chunk.len()].iter().map(|t| t / count));
}

/// Adds each segment's `re² + im²` to `total`, in segment order.
#[inline(always)]
fn add_powers<const L: usize>(total: &mut [f64; L], sums: &[Phasors<L>]) {
    for (re, im) in sums {
        for j in 0..L {
            total[j] += re[j] * re[j] + im[j] * im[j];
        }
    }
}

/// `(Σ v·pr, −Σ v·pi)` of each of `K` segments, in sample order, with the
/// phasors `(pr, pi)` made on the way, lane by lane: `(1, 0)`, then
/// rotated by `(c, sn)` after each sample and renormalised after every
/// 256th rotation. The `K` segments share the phasors, which are never
/// stored (a table of them, 128-256 kB, read once per group of segments,
/// took twice the time).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // sample k of K segments at once
fn sums<const L: usize, const K: usize>(
    segs: &[&[f64]; K],
    c: &[f64; L],
    sn: &[f64; L],
) -> [Phasors<L>; K] {
    let n = segs[0].len();
    let segs: [&[f64]; K] = std::array::from_fn(|g| &segs[g][..n]);
    let mut acc = [([0.0f64; L], [0.0f64; L]); K];
    let (mut pr, mut pi) = ([1.0f64; L], [0.0f64; L]);
    let mut start = 0;
    while start < n {
        let end = (start + 256).min(n);
        for k in start..end {
            for g in 0..K {
                let v = segs[g][k];
                let (re, im) = &mut acc[g];
                for j in 0..L {
                    re[j] += v * pr[j];
                    im[j] -= v * pi[j];
                }
            }
            for j in 0..L {
                let t = pr[j] * c[j] - pi[j] * sn[j];
                pi[j] = pr[j] * sn[j] + pi[j] * c[j];
                pr[j] = t;
            }
        }
        // After the 256th rotation of a block (a partial last block's
        // phasors are not used again).
        if end - start == 256 {
            for j in 0..L {
                let a = (pr[j] * pr[j] + pi[j] * pi[j]).sqrt();
                pr[j] /= a;
                pi[j] /= a;
            }
        }
        start = end;
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean power at `f`, one frequency and one segment at a time:
    /// [`segment_powers`] must equal it bit for bit.
    pub(super) fn power_alone(segments: &[&[f64]], dx: f64, f: f64) -> f64 {
        let step = std::f64::consts::TAU * f * dx;
        let (c, sn) = (step.cos(), step.sin());
        let mut total = 0.0;
        for seg in segments {
            let (mut re, mut im) = (0.0, 0.0);
            let (mut pr, mut pi) = (1.0f64, 0.0f64);
            for (n, v) in seg.iter().enumerate() {
                re += v * pr;
                im -= v * pi;
                let t = pr * c - pi * sn;
                pi = pr * sn + pi * c;
                pr = t;
                if n % 256 == 255 {
                    let a = (pr * pr + pi * pi).sqrt();
                    pr /= a;
                    pi /= a;
                }
            }
            total += re * re + im * im;
        }
        total / segments.len() as f64
    }

    fn noise(seed: u64, len: usize) -> Vec<f64> {
        let mut state = seed;
        (0..len)
            .map(|i| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                (0.9 * i as f64).sin() + (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    #[test]
    fn lock_step_equals_one_frequency_at_a_time_bit_for_bit() {
        // 1 to 9 segments (groups of 4 and remainders of 1 to 3), 600 samples (two
        // renormalisations), 1 to 40 frequencies (chunks of 16 and of 8,
        // full and partial).
        let segs: Vec<Vec<f64>> = (0..9).map(|s| noise(s + 3, 600)).collect();
        let dx = 0.127;
        for s_count in 1..=9 {
            let segs: Vec<&[f64]> = segs[..s_count].iter().map(Vec::as_slice).collect();
            for f_count in [1, 7, 8, 9, 16, 17, 25, 40] {
                let freqs: Vec<f64> = (0..f_count).map(|j| 0.05 + 0.173 * j as f64).collect();
                let got = segment_powers(&segs, dx, &freqs).unwrap();
                let want: Vec<u64> = freqs
                    .iter()
                    .map(|&f| power_alone(&segs, dx, f).to_bits())
                    .collect();
                let got: Vec<u64> = got.iter().map(|p| p.to_bits()).collect();
                assert_eq!(got, want, "{s_count} segments, {f_count} frequencies");
                // The baseline (SSE2) instance rounds the same.
                let base: Vec<u64> = powers(&segs, dx, &freqs)
                    .iter()
                    .map(|p| p.to_bits())
                    .collect();
                assert_eq!(base, want);
            }
        }
    }

    #[test]
    fn a_sine_peaks_at_its_frequency_with_parseval_scale() {
        // A unit sine at 0.1 cycles per sample over 1000 samples (100
        // whole periods): |Σ sin(2π f n) e^{−2πi f n}|² = (N/2)².
        let x: Vec<f64> = (0..1000)
            .map(|n| (std::f64::consts::TAU * 0.1 * n as f64).sin())
            .collect();
        let p = segment_powers(&[&x], 1.0, &[0.1, 0.1005, 0.2]).unwrap();
        assert!((p[0] / 250_000.0 - 1.0).abs() < 1e-9, "{}", p[0]);
        assert!(p[1] < p[0] && p[2] < 1e-6 * p[0], "{p:?}");
    }

    #[test]
    fn bad_input_is_an_error() {
        let a = [1.0, 2.0];
        let b = [1.0];
        assert!(segment_powers(&[], 1.0, &[0.1]).is_err());
        assert!(segment_powers(&[&a, &b], 1.0, &[0.1]).is_err());
        assert!(segment_powers(&[&[]], 1.0, &[0.1]).is_err());
        assert!(segment_powers(&[&[f64::NAN, 1.0]], 1.0, &[0.1]).is_err());
        assert!(segment_powers(&[&a], f64::INFINITY, &[0.1]).is_err());
        assert!(segment_powers(&[&a], 1.0, &[f64::NAN]).is_err());
        assert_eq!(segment_powers(&[&a], 1.0, &[]).unwrap(), Vec::<f64>::new());
    }
}
