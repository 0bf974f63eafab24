//! Cosine and sine of a block of arguments at once, for the frequency
//! responses (`freqz`, `sosfreqz`), where the C library's `cos` and `sin`
//! of every frequency were most of the time.
//!
//! ```text
//! n = round(x · 2/π)                   (ties to even)
//! r = ((x − n P1) − n P2) − n P3       (P1 + P2 + P3 = π/2 to ~100 bits;
//!                                       P1, P2 short, so n·P1, n·P2 are exact)
//! sin r, cos r: fdlibm's kernels on |r| ≤ π/4 (degree-13 odd and
//!               degree-14 even polynomials, error below 1 ulp)
//! quadrant n mod 4: (sin, cos) = (s, c), (c, −s), (−s, −c), (−c, s)
//! ```
//!
//! Every step is plain arithmetic and selects, so a block runs in SIMD
//! lanes. Against glibc's (correctly rounded in practice) `cos`/`sin`: at
//! most 1 ulp apart on 10⁶ arguments (unit test, bound 2 ulp; beside the
//! zeros, below 1e-6, ulps of 1/2 absolutely). Blocks holding an argument beyond [`REDUCED_MAX`] (where
//! the three-part reduction loses bits) use the C library for every lane.

// The constants are fdlibm's and Cephes' published decimals, kept as
// published (they round to the intended doubles).
#![allow(clippy::excessive_precision)]

/// Largest `|x|` reduced here (2^20); beyond it the C library's functions.
pub(crate) const REDUCED_MAX: f64 = 1_048_576.0;

// π/2 in three parts (Cephes' π/4 split, doubled): P1 and P2 have 26 and
// 21 significant bits.
const P1: f64 = 1.570_796_251_296_997_070_312_5;
const P2: f64 = 7.549_789_415_861_596_353_35e-8;
const P3: f64 = 5.390_302_858_158_119_052_90e-15;

// fdlibm __kernel_sin / __kernel_cos coefficients.
const S1: f64 = -1.666_666_666_666_663_243_48e-1;
const S2: f64 = 8.333_333_333_322_489_461_24e-3;
const S3: f64 = -1.984_126_982_985_794_931_34e-4;
const S4: f64 = 2.755_731_370_707_006_767_89e-6;
const S5: f64 = -2.505_076_025_340_686_341_95e-8;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;
const C1: f64 = 4.166_666_666_666_660_190_37e-2;
const C2: f64 = -1.388_888_888_887_410_957_49e-3;
const C3: f64 = 2.480_158_728_947_672_941_78e-5;
const C4: f64 = -2.755_731_435_139_066_330_35e-7;
const C5: f64 = 2.087_572_321_298_174_827_90e-9;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;

/// `(cos x, sin x)` of every lane of `x` (finite values).
#[inline(always)]
#[cfg(test)]
pub(crate) fn sincos<const L: usize>(x: &[f64; L]) -> ([f64; L], [f64; L]) {
    let (mut c, mut s) = ([0.0; L], [0.0; L]);
    sincos_into(x, &mut c, &mut s);
    (c, s)
}

/// The cosines (`c`) and sines (`s`) of every lane of `x` (finite values)
/// into the caller's arrays, so that a caller can keep its blocks aligned
/// (see `lti::Lanes`).
#[inline(always)]
pub(crate) fn sincos_into<const L: usize>(x: &[f64; L], c: &mut [f64; L], s: &mut [f64; L]) {
    if x.iter().any(|v| v.abs() > REDUCED_MAX) {
        for k in 0..L {
            (c[k], s[k]) = (x[k].cos(), x[k].sin());
        }
        return;
    }
    for k in 0..L {
        let (n, sr, cr) = reduced(x[k]);
        // Quadrant n mod 4: the low bits of n + 1.5 2^52 (exact for
        // |n| < 2^51, two's complement below zero). Bit 0 swaps sine and
        // cosine, bit 1 negates the sine, bit 0 xor bit 1 the cosine: the
        // same selections and sign flips as with n mod 4 taken in floating
        // point (`quadrant_bits_select_as_the_float_quadrant`), in five
        // fewer operations.
        let t = (n + QUADRANT_BIAS).to_bits();
        let (s0, c0) = if t & 1 == 1 { (cr, sr) } else { (sr, cr) };
        s[k] = f64::from_bits(s0.to_bits() ^ ((t & 2) << 62));
        c[k] = f64::from_bits(c0.to_bits() ^ (((t ^ (t >> 1)) & 1) << 63));
    }
}

/// The nearest multiple `n` of π/2 to `x` and the sine and cosine of the
/// remainder `x − n π/2` (`|x| ≤ REDUCED_MAX`): the kernel's arithmetic
/// before the quadrant is applied.
#[inline(always)]
fn reduced(x: f64) -> (f64, f64, f64) {
    let n = (x * std::f64::consts::FRAC_2_PI).round_ties_even();
    let r = ((x - n * P1) - n * P2) - n * P3;
    let z = r * r;
    let v = z * r;
    let sr = r + v * (S1 + z * (S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)))));
    let poly = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let cr = w + (((1.0 - w) - hz) + z * poly);
    (n, sr, cr)
}

/// 1.5 2^52: `n + QUADRANT_BIAS` holds the integer `n` in its low bits.
const QUADRANT_BIAS: f64 = 6_755_399_441_055_744.0;

#[cfg(test)]
mod tests {
    use super::*;

    /// The kernel with the quadrant taken in floating point (session 16's
    /// selection), the reference of the bit selection.
    fn sincos_float_quadrant(x: f64) -> (f64, f64) {
        let (n, sr, cr) = reduced(x);
        let q = n - 4.0 * (0.25 * n).floor();
        let odd = q == 1.0 || q == 3.0;
        let (s0, c0) = if odd { (cr, sr) } else { (sr, cr) };
        let s = if q >= 2.0 { -s0 } else { s0 };
        let c = if q == 1.0 || q == 2.0 { -c0 } else { c0 };
        (c, s)
    }

    /// The quadrant from the bits of `n` gives the float quadrant's
    /// cosines and sines bit for bit: signed zeros, every quadrant of
    /// negative and positive arguments, their boundaries and neighbours,
    /// up to the reduction's limit.
    #[test]
    fn quadrant_bits_select_as_the_float_quadrant() {
        let mut xs: Vec<f64> = vec![0.0, -0.0, 1e-300, -1e-300, REDUCED_MAX, -REDUCED_MAX];
        for k in -3000..=3000 {
            let x = k as f64 * std::f64::consts::FRAC_PI_4;
            let m = x.abs().to_bits();
            let near = |b: u64| f64::from_bits(b).copysign(x);
            xs.extend([
                x,
                near(m + 1),
                near(m.saturating_sub(1)),
                x * 0.37,
                x * 1.0e3,
            ]);
        }
        xs.retain(|x| x.abs() <= REDUCED_MAX);
        for block in xs.chunks(8) {
            let mut x = [0.0; 8];
            x[..block.len()].copy_from_slice(block);
            let (c, s) = sincos(&x);
            for k in 0..block.len() {
                let (wc, ws) = sincos_float_quadrant(x[k]);
                assert_eq!(
                    (c[k].to_bits(), s[k].to_bits()),
                    (wc.to_bits(), ws.to_bits()),
                    "x = {:e}",
                    x[k]
                );
            }
        }
    }

    /// The spacing of doubles at `|v|`.
    fn ulp(v: f64) -> f64 {
        let a = v.abs();
        f64::from_bits(a.to_bits() + 1) - a
    }

    /// Distance of `got` from `want` in ulps of `want`; below 1e-6 (beside
    /// an exact zero, where the value is the argument's rounding) in ulps
    /// of 1/2, absolutely.
    fn ulps(got: f64, want: f64) -> f64 {
        let unit = if want.abs() < 1e-6 {
            f64::EPSILON / 2.0
        } else {
            ulp(want)
        };
        (got - want).abs() / unit
    }

    #[test]
    fn within_two_ulp_of_the_c_library() {
        // 10^6 arguments: uniform on ±2π (the frequency responses' range),
        // ±1000 and ±2^20, the multiples of π/2 and π/4 and their
        // neighbours, zero and tiny values.
        let mut xs: Vec<f64> = Vec::new();
        let mut state = 12345u64;
        let mut u = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for scale in [std::f64::consts::TAU, 1000.0, REDUCED_MAX] {
            for _ in 0..300_000 {
                xs.push((2.0 * u() - 1.0) * scale);
            }
        }
        for k in -2000..=2000 {
            for base in [std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_4] {
                let x = k as f64 * base;
                // The neighbouring doubles (of the magnitude, sign kept).
                let m = x.abs().to_bits();
                let near = |b: u64| f64::from_bits(b).copysign(x);
                xs.extend([x, near(m + 1), near(m.saturating_sub(1))]);
            }
        }
        xs.extend([0.0, -0.0, 1e-300, -1e-20, 1e-8, REDUCED_MAX, -REDUCED_MAX]);
        let mut worst: f64 = 0.0;
        for block in xs.chunks(8) {
            let mut x = [0.0; 8];
            x[..block.len()].copy_from_slice(block);
            let (c, s) = sincos(&x);
            for k in 0..block.len() {
                let (ec, es) = (x[k].cos(), x[k].sin());
                let (dc, ds) = (ulps(c[k], ec), ulps(s[k], es));
                worst = worst.max(dc).max(ds);
                assert!(
                    dc <= 2.0 && ds <= 2.0,
                    "x = {:e}: cos {} vs {}, sin {} vs {}",
                    x[k],
                    c[k],
                    ec,
                    s[k],
                    es
                );
            }
        }
        eprintln!("sincos: worst {worst} ulp");
        // Exact where the frequency responses need it: z = 1 at 0, z = -1
        // at Nyquist, where sin is the C library's 1.2246e-16 to 2e-31
        // (the reduction's last part, P3, is good to ~1e-31 of π/2).
        let (c, s) = sincos(&[0.0, std::f64::consts::PI]);
        assert_eq!((c[0], s[0]), (1.0, 0.0));
        assert_eq!(c[1], -1.0);
        assert!(
            (s[1] - std::f64::consts::PI.sin()).abs() < 2e-31,
            "{}",
            s[1]
        );
        // A block with an argument beyond the reduction's range is the C
        // library's, every lane.
        let x = [1e7, 3.0, -2.5e9, 0.1];
        let (c, s) = sincos(&x);
        for k in 0..4 {
            assert_eq!((c[k], s[k]), (x[k].cos(), x[k].sin()), "{}", x[k]);
        }
    }
}
