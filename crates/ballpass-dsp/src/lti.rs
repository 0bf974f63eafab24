//! Frequency responses of linear time-invariant systems: analog
//! (`freqs`, `bode`) and digital (`freqz`, `sosfreqz`).

use rustfft::num_complex::Complex64;

use crate::error::{check_finite, invalid, Result};
use crate::npcomplex as nc;
use crate::sos::Sos;

/// Complex frequency response of an analog system at angular frequencies.
#[derive(Debug, Clone, PartialEq)]
pub struct AnalogResponse {
    /// Angular frequencies in rad/s (as given).
    pub w_rad_s: Vec<f64>,
    /// `H(j w)` at each frequency.
    pub h: Vec<Complex64>,
}

/// Bode diagram of an analog system.
#[derive(Debug, Clone, PartialEq)]
pub struct Bode {
    /// Angular frequencies in rad/s (as given).
    pub w_rad_s: Vec<f64>,
    /// `20 log10 |H(j w)|` in dB.
    pub magnitude_db: Vec<f64>,
    /// `arg H(j w)` in degrees, unwrapped along the frequency axis
    /// (`numpy.unwrap`), starting in `(-180, 180]`.
    pub phase_deg: Vec<f64>,
}

/// Complex frequency response of a digital filter at frequencies in Hz.
#[derive(Debug, Clone, PartialEq)]
pub struct DigitalResponse {
    /// Frequencies in Hz (as given).
    pub freq_hz: Vec<f64>,
    /// `H(exp(j 2 pi f / fs))` at each frequency.
    pub h: Vec<Complex64>,
}

fn check_poly(what: &'static str, p: &[f64]) -> Result<()> {
    check_finite(what, p)?;
    if p.iter().all(|v| *v == 0.0) {
        return Err(invalid(what, "polynomial is identically zero"));
    }
    Ok(())
}

/// Frequency response of the analog filter `b(s) / a(s)` (coefficients with
/// the highest power first), matching `scipy.signal.freqs(b, a, worN=w)`.
///
/// ```text
/// H(j w) = (b0 (jw)^M + ... + bM) / (a0 (jw)^N + ... + aN)
/// ```
///
/// ```
/// // first-order low-pass 1 / (s + 1): -3 dB and -45 degrees at 1 rad/s
/// let r = ballpass_dsp::freqs(&[1.0], &[1.0, 1.0], &[1.0]).unwrap();
/// assert!((r.h[0].norm() - 0.5f64.sqrt()).abs() < 1e-15);
/// ```
///
/// # Errors
/// [`crate::DspError::Empty`] / [`crate::DspError::NonFinite`] for bad inputs;
/// [`crate::DspError::InvalidSetting`] if `a` or `b` is identically zero.
pub fn freqs(b: &[f64], a: &[f64], w_rad_s: &[f64]) -> Result<AnalogResponse> {
    Ok(AnalogResponse {
        h: freqs_values(b, a, w_rad_s)?,
        w_rad_s: w_rad_s.to_vec(),
    })
}

/// [`freqs`]' response values alone (no copy of the frequencies).
///
/// # Errors
/// As [`freqs`].
pub fn freqs_values(b: &[f64], a: &[f64], w_rad_s: &[f64]) -> Result<Vec<Complex64>> {
    check_poly("b", b)?;
    check_poly("a", a)?;
    check_finite("w_rad_s", w_rad_s)?;
    // A coefficient -0.0 is the one case where dropping the zero products
    // could change a sign of zero (see `polyval_jw_short`).
    let short = !b.iter().chain(a).any(|c| *c == 0.0 && c.is_sign_negative());
    Ok(crate::simd::widest(
        #[inline(always)]
        || {
            by_full_blocks(w_rad_s, |w: &Lanes<LANES>, h: &mut [Complex64; LANES]| {
                if short {
                    let (nb, na) = (polyval_jw_short(b, w), polyval_jw_short(a, w));
                    if all_finite_lanes(&[&nb.0 .0, &nb.1 .0, &na.0 .0, &na.1 .0]) {
                        return div_lanes(nb, na, &mut h[..]);
                    }
                }
                div_lanes(polyval_jw(b, w), polyval_jw(a, w), &mut h[..]);
            })
        },
    ))
}

/// [`polyval_jw`] without the products by `s.re = 0`: `(c - i w, r w + 0)`
/// per step, half the operations and the same bits whenever every value
/// stays finite and no coefficient is `-0.0`. NumPy's step is
/// `((r 0 - i w) + c, (r w + i 0) + 0)`. With `i w` nonzero, `r 0 - i w`
/// is `-(i w)` exactly, so the real part is `c - i w` rounded once, as
/// here; with `i w` zero both give `c` for `c != 0` and `+0` for
/// `c = +0` (every sum of zeros with `+0` is `+0`, as is `+0 - (±0)`).
/// The imaginary part is `r w` when nonzero, and `+0` when `r w` is a
/// zero (`±0 + ±0 + 0 = +0`) in both. A NaN or infinity is not handled
/// (`i 0` is NaN for `i` infinite): once one appears it stays in `(r, i)`
/// (an infinity times a nonzero `w` is infinite, times zero NaN), so the
/// caller checks the results and evaluates NumPy's way when one is not
/// finite.
#[inline(always)]
fn polyval_jw_short(p: &[f64], w: &[f64; LANES]) -> (Lanes<LANES>, Lanes<LANES>) {
    let (mut yr, mut yi) = (Lanes::zero(), Lanes::zero());
    for &c in p {
        for k in 0..LANES {
            let (r, i) = (yr[k], yi[k]);
            yr[k] = c - i * w[k];
            yi[k] = r * w[k] + 0.0;
        }
    }
    (yr, yi)
}

/// Whether every value of the lane arrays is finite (`0 x` sums to `0`
/// iff so), branch-free.
#[inline(always)]
fn all_finite_lanes(v: &[&[f64; LANES]; 4]) -> bool {
    let mut acc = [0.0; LANES];
    for a in v {
        for k in 0..LANES {
            acc[k] += 0.0 * a[k];
        }
    }
    acc.iter().fold(true, |ok, &s| ok & (s == 0.0))
}

/// Points evaluated in lock step: the responses at different frequencies
/// are independent, so [`LANES`] of them run side by side (in SIMD
/// registers, the Horner chains of one point no longer waiting on each
/// other), each lane with exactly the arithmetic of a point on its own.
/// 16: two or more independent chains per register width, so that the
/// Horner steps' latency is hidden.
const LANES: usize = 16;

/// [`LANES`] for `freqz`: there each block is a long dependent sequence
/// (sine and cosine, then the Horner sums on them, then the division), so
/// more lanes per block give the core more independent work at each step
/// (Rust kernels bench, 30 000 points: 16 lanes 194 us, 32 lanes
/// 174-181 us, 64 lanes 171 us; `freqs`, without the sine and cosine, is
/// slower with 32 than with 16: 102-109 against 81 us).
const FREQZ_LANES: usize = 64;

/// One block's values of a lane kernel, 64-byte aligned. The blocks live
/// on the stack (a block of 64 lanes is eight AVX-512 registers, more than
/// the kernels can keep in registers), and plain `[f64; L]` arrays are
/// only 8-byte aligned: where they then sat depended on where the process's
/// stack happened to start (randomised per process), and in half of the
/// processes every 64-byte access split over two cache lines (Python
/// `freqz`, 30 000 points: 221-231 us in those processes, 184-186 in the
/// others, one wheel). Aligned, every process gets the fast layout.
#[derive(Clone, Copy)]
#[repr(C, align(64))]
struct Lanes<const L: usize>([f64; L]);

impl<const L: usize> Lanes<L> {
    #[inline(always)]
    fn zero() -> Self {
        Lanes([0.0; L])
    }
}

impl<const L: usize> std::ops::Deref for Lanes<L> {
    type Target = [f64; L];
    #[inline(always)]
    fn deref(&self) -> &[f64; L] {
        &self.0
    }
}

impl<const L: usize> std::ops::DerefMut for Lanes<L> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [f64; L] {
        &mut self.0
    }
}

/// `eval` on the points `x` in blocks of [`LANES`] (the last block padded
/// with zeros, its extra results dropped): one result per point.
#[inline(always)]
fn by_blocks<const L: usize>(
    x: &[f64],
    mut eval: impl FnMut(&Lanes<L>, &mut [Complex64]),
) -> Vec<Complex64> {
    // Grown block by block (zeroed while the block is in L1, not the whole
    // output up front).
    let mut h = Vec::with_capacity(x.len());
    for xs in x.chunks(L) {
        let mut block = Lanes::zero();
        block[..xs.len()].copy_from_slice(xs);
        let start = h.len();
        h.resize(start + xs.len(), Complex64::new(0.0, 0.0));
        eval(&block, &mut h[start..]);
    }
    h
}

/// [`by_blocks`] with `eval` filling a whole block of results, which is
/// then appended to the output (a fixed-size copy, wide stores). Writing
/// each block's results into a slice of the output as long as the block
/// (what [`by_blocks`] does) makes one
/// scalar store and a length check per result, and the slice had to be
/// zeroed first. For `freqs` (Rust kernels bench, 30 000 points): 103-105
/// -> 92-93 us. Not for `freqz` / `sosfreqz`: with the sine and cosine in
/// the block, the compiler then spilled the block's arrays and reloaded
/// constants (freqz 209-211 -> 224-227 us), so they keep [`by_blocks`].
#[inline(always)]
fn by_full_blocks(
    x: &[f64],
    mut eval: impl FnMut(&Lanes<LANES>, &mut [Complex64; LANES]),
) -> Vec<Complex64> {
    // One call of `eval` in the loop (a second one for the last block
    // took it out of line: 2.6x slower).
    let mut h = Vec::with_capacity(x.len());
    let mut out = [Complex64::new(0.0, 0.0); LANES];
    for xs in x.chunks(LANES) {
        let mut block = Lanes::zero();
        block[..xs.len()].copy_from_slice(xs);
        eval(&block, &mut out);
        if xs.len() == LANES {
            h.extend_from_slice(&out);
        } else {
            h.extend_from_slice(&out[..xs.len()]);
        }
    }
    h
}

/// [`polyval`] at `s = j w` for a block of `w`, as separate real and
/// imaginary parts, with `polyval`'s operations (`y s` as the complex
/// product with `s.re = 0`, then `+ (c, 0)`).
#[inline(always)]
fn polyval_jw(p: &[f64], w: &[f64; LANES]) -> (Lanes<LANES>, Lanes<LANES>) {
    let (mut yr, mut yi) = (Lanes::zero(), Lanes::zero());
    for &c in p {
        for k in 0..LANES {
            let (r, i) = (yr[k], yi[k]);
            yr[k] = (r * 0.0 - i * w[k]) + c;
            yi[k] = (r * w[k] + i * 0.0) + 0.0;
        }
    }
    (yr, yi)
}

/// `numpy.unwrap` with period `2 pi`: adds multiples of `2 pi` so that
/// consecutive values differ by at most `pi`.
pub fn unwrap(p: &[f64]) -> Vec<f64> {
    use std::f64::consts::PI;
    let period = 2.0 * PI;
    let (lo, hi) = (-PI, PI);
    let mut out = Vec::with_capacity(p.len());
    let mut correction = 0.0;
    for (i, &v) in p.iter().enumerate() {
        if i > 0 {
            let dd = v - p[i - 1];
            let mut ddmod = py_mod(dd - lo, period) + lo;
            if ddmod == lo && dd > 0.0 {
                ddmod = hi;
            }
            let mut ph = ddmod - dd;
            if dd.abs() < PI {
                ph = 0.0;
            }
            correction += ph;
            out.push(v + correction);
        } else {
            out.push(v);
        }
    }
    out
}

/// Python/NumPy floating `%`: the result has the sign of the divisor.
fn py_mod(a: f64, b: f64) -> f64 {
    let m = a % b;
    if m != 0.0 {
        if (b < 0.0) != (m < 0.0) {
            m + b
        } else {
            m
        }
    } else {
        0.0f64.copysign(b)
    }
}

/// Bode magnitude and phase of the analog filter `b(s) / a(s)`, matching
/// `scipy.signal.bode((b, a), w=w_rad_s)`.
///
/// ```text
/// magnitude_db = 20 log10 |H(j w)|
/// phase_deg    = unwrap(atan2(Im H, Re H)) * 180 / pi
/// ```
///
/// SciPy evaluates a `(b, a)` tuple through its poles and zeros; this
/// evaluates the polynomials directly (the results agree to rounding for
/// well-conditioned polynomials).
///
/// # Errors
/// As [`freqs`].
pub fn bode(b: &[f64], a: &[f64], w_rad_s: &[f64]) -> Result<Bode> {
    let r = freqs(b, a, w_rad_s)?;
    let magnitude_db = r.h.iter().map(|h| 20.0 * nc::abs(*h).log10()).collect();
    let wrapped: Vec<f64> = r.h.iter().map(|h| h.im.atan2(h.re)).collect();
    let phase_deg = unwrap(&wrapped)
        .into_iter()
        .map(|p| p * 180.0 / std::f64::consts::PI)
        .collect();
    Ok(Bode {
        w_rad_s: r.w_rad_s,
        magnitude_db,
        phase_deg,
    })
}

fn check_freqs(freq_hz: &[f64], fs_hz: f64) -> Result<()> {
    if !(fs_hz.is_finite() && fs_hz > 0.0) {
        return Err(invalid(
            "fs_hz",
            format!("must be finite and > 0, got {fs_hz}"),
        ));
    }
    check_finite("freq_hz", freq_hz)
}

/// `z^-1 = exp(-j 2 pi f / fs) = (cos(-w), sin(-w))` for a block of
/// frequencies, as real and imaginary parts: the cosine and sine of the
/// block in SIMD lanes ([`crate::sincos`], within 2 ulp of the C
/// library's that NumPy's `exp` calls).
#[inline(always)]
fn unit_delays<const L: usize>(f: &[f64; L], fs_hz: f64) -> (Lanes<L>, Lanes<L>) {
    let (mut zr, mut zi) = (Lanes::zero(), Lanes::zero());
    crate::sincos::sincos_into(&minus_omega(f, fs_hz), &mut zr, &mut zi);
    (zr, zi)
}

/// `-w = -(2 pi f / fs)` for a block of frequencies, rounded as NumPy's
/// `2 * pi * f / fs` (then negated, exactly).
#[inline(always)]
fn minus_omega<const L: usize>(f: &[f64; L], fs_hz: f64) -> Lanes<L> {
    let mut minus_w = Lanes::zero();
    for k in 0..L {
        minus_w[k] = -(2.0 * std::f64::consts::PI * f[k] / fs_hz);
    }
    minus_w
}

/// `a / b` for a block, lane by lane with [`nc::div`]'s operations (NumPy's
/// Smith division, bit for bit) written as selects instead of branches, so
/// the lanes run in SIMD. The zero denominator's two divisions are made
/// only in a block that has one (as selects in every lane they cost
/// freqs 92 against 81 us, freqz 209 against 194 us in the Rust kernels
/// bench).
#[inline(always)]
fn div_lanes<const L: usize>(
    (ar, ai): (Lanes<L>, Lanes<L>),
    (br, bi): (Lanes<L>, Lanes<L>),
    h: &mut [Complex64],
) {
    let (mut re, mut im) = (Lanes::<L>::zero(), Lanes::<L>::zero());
    let mut any_zero = false;
    for k in 0..L {
        any_zero |= (br[k] == 0.0) & (bi[k] == 0.0);
        let real_larger = br[k].abs() >= bi[k].abs();
        let (p, q) = if real_larger {
            (bi[k], br[k])
        } else {
            (br[k], bi[k])
        };
        let rat = p / q;
        let scl = 1.0 / (q + p * rat);
        (re[k], im[k]) = if real_larger {
            ((ar[k] + ai[k] * rat) * scl, (ai[k] - ar[k] * rat) * scl)
        } else {
            ((ar[k] * rat + ai[k]) * scl, (ai[k] * rat - ar[k]) * scl)
        };
    }
    if any_zero {
        // NumPy divides by the zero denominator's magnitude (infinities
        // and NaN as it gives them).
        for k in 0..L {
            if br[k] == 0.0 && bi[k] == 0.0 {
                let d = br[k].abs();
                (re[k], im[k]) = (ar[k] / d, ai[k] / d);
            }
        }
    }
    // A full block as a fixed-size array: its interleaved (re, im) stores
    // are then vector stores. Through a slice of run-time length (what
    // `by_blocks` hands over) they compiled to two scalar loads and two
    // scalar stores per result.
    if let Ok(h) = <&mut [Complex64; L]>::try_from(&mut *h) {
        for k in 0..L {
            h[k] = Complex64::new(re[k], im[k]);
        }
    } else {
        for (k, h) in h.iter_mut().enumerate() {
            *h = Complex64::new(re[k], im[k]);
        }
    }
}

/// `c(z^-1)` at a block of `z^-1` (NumPy `polyval` from the lowest power,
/// as SciPy's `freqz`): `acc = (c_k, 0) + acc z^-1` from the last
/// coefficient down, real and imaginary parts.
///
/// The first step, from `acc = (r, +0)`, is `(c_k + r zr, 0 + r zi)`
/// without the products by the zero: the same bits for finite `r`, `zr`,
/// `zi` (as here: checked coefficients, cosines and sines). NumPy's real
/// part is `c_k + (r zr - (+0) zi)`: with `r zr` nonzero the zero product
/// does not change it; with `r zr` a zero, `r zr - (+-0)` is a zero whose
/// sign is lost in `c_k + ` unless `c_k` is `-0.0` (only then do the two
/// differ, so a `-0.0` coefficient takes NumPy's step). The imaginary part
/// `0 + (r zi + (+0) zr)` is `r zi` when that is nonzero and `+0`
/// otherwise, as `0 + r zi`. Four of the step's eight operations, a tenth
/// of a butter(5) response's Horner work. `SHORT` says whether to take it
/// ([`short_first_step`] of the polynomial): a constant, so that the
/// block loop has one path (a branch on the coefficient inside the block
/// made the loop larger and slower: Python freqz 181-186 against 178-180 us).
#[inline(always)]
fn polyval_z<const L: usize, const SHORT: bool>(
    c: &[f64],
    zr: &[f64; L],
    zi: &[f64; L],
) -> (Lanes<L>, Lanes<L>) {
    let r = c[c.len() - 1];
    let (mut ar, mut ai) = (Lanes([r; L]), Lanes::zero());
    let mut rest = c.iter().rev().skip(1);
    if SHORT {
        if let Some(&ci) = rest.next() {
            for k in 0..L {
                (ar[k], ai[k]) = (ci + r * zr[k], 0.0 + r * zi[k]);
            }
        }
    }
    for &ci in rest {
        horner_z_step(ci, &mut ar, &mut ai, zr, zi);
    }
    (ar, ai)
}

/// Whether [`polyval_z`]'s short first step gives NumPy's bits for `c`:
/// its second-to-last coefficient (the first step's) is not `-0.0`.
fn short_first_step(c: &[f64]) -> bool {
    c.len() < 2 || !(c[c.len() - 2] == 0.0 && c[c.len() - 2].is_sign_negative())
}

/// One step of [`polyval_z`], NumPy's operations: `acc = (ci, 0) + acc z^-1`.
#[inline(always)]
fn horner_z_step<const L: usize>(
    ci: f64,
    ar: &mut [f64; L],
    ai: &mut [f64; L],
    zr: &[f64; L],
    zi: &[f64; L],
) {
    for k in 0..L {
        let (r, i) = (ar[k], ai[k]);
        let (mr, mi) = (r * zr[k] - i * zi[k], r * zi[k] + i * zr[k]);
        (ar[k], ai[k]) = (ci + mr, 0.0 + mi);
    }
}

/// `b(z^-1) / a(z^-1)` at a block of `z^-1`, into `h`.
#[inline(always)]
fn ratio_z<const L: usize, const SHORT: bool>(
    b: &[f64],
    a: &[f64],
    zr: &[f64; L],
    zi: &[f64; L],
    h: &mut [Complex64],
) {
    div_lanes(
        polyval_z::<L, SHORT>(b, zr, zi),
        polyval_z::<L, SHORT>(a, zr, zi),
        h,
    );
}

/// Frequency response of the digital filter `b(z) / a(z)` (coefficients of
/// `z^0, z^-1, ...`), matching `scipy.signal.freqz(b, a, worN=freq_hz, fs=fs_hz)`.
///
/// ```text
/// H(f) = sum_k b[k] e^{-j 2 pi f k / fs} / sum_k a[k] e^{-j 2 pi f k / fs}
/// ```
///
/// # Errors
/// [`crate::DspError::Empty`] / [`crate::DspError::NonFinite`] for bad inputs;
/// [`crate::DspError::InvalidSetting`] for a zero denominator or a bad `fs_hz`.
pub fn freqz(b: &[f64], a: &[f64], freq_hz: &[f64], fs_hz: f64) -> Result<DigitalResponse> {
    Ok(DigitalResponse {
        h: freqz_values(b, a, freq_hz, fs_hz)?,
        freq_hz: freq_hz.to_vec(),
    })
}

/// [`freqz`]' response values alone (no copy of the frequencies).
///
/// # Errors
/// As [`freqz`].
pub fn freqz_values(b: &[f64], a: &[f64], freq_hz: &[f64], fs_hz: f64) -> Result<Vec<Complex64>> {
    let short = freqz_checked(b, a, freq_hz, fs_hz)?;
    Ok(crate::simd::widest(
        #[inline(always)]
        || {
            if short {
                freqz_blocks::<true>(b, a, freq_hz, fs_hz)
            } else {
                freqz_blocks::<false>(b, a, freq_hz, fs_hz)
            }
        },
    ))
}

/// [`freqz`]'s checks of its inputs; whether both polynomials take the
/// short first Horner step ([`short_first_step`]).
fn freqz_checked(b: &[f64], a: &[f64], freq_hz: &[f64], fs_hz: f64) -> Result<bool> {
    check_poly("b", b)?;
    check_poly("a", a)?;
    check_freqs(freq_hz, fs_hz)?;
    Ok(short_first_step(b) && short_first_step(a))
}

/// [`freqz_values`]' block loop, with or without the short first Horner
/// step.
#[inline(always)]
fn freqz_blocks<const SHORT: bool>(
    b: &[f64],
    a: &[f64],
    freq_hz: &[f64],
    fs_hz: f64,
) -> Vec<Complex64> {
    by_blocks(freq_hz, |f: &Lanes<FREQZ_LANES>, h| {
        let (zr, zi) = unit_delays(f, fs_hz);
        ratio_z::<_, SHORT>(b, a, &zr, &zi, h);
    })
}

/// [`freqz_values`] together with the frequencies
/// `scipy.signal.freqz(b, a, worN=freq_hz, fs=fs_hz)` returns beside them:
/// SciPy evaluates at `w = 2 pi f / fs` (rad/sample) and returns
/// `w (fs / (2 pi))`, which is `f` to within an ulp or two; here with
/// NumPy's operations in NumPy's order, so bit for bit SciPy's. The
/// quotient `2 pi f / fs` is the one the response is evaluated at, so it
/// is divided once for both (the Python package's `freqz` with given
/// frequencies; a second pass over the frequencies with its own division
/// cost about as much as the division of the response).
///
/// # Errors
/// As [`freqz`].
pub fn freqz_values_scipy_grid(
    b: &[f64],
    a: &[f64],
    freq_hz: &[f64],
    fs_hz: f64,
) -> Result<(Vec<f64>, Vec<Complex64>)> {
    let short = freqz_checked(b, a, freq_hz, fs_hz)?;
    Ok(crate::simd::widest(
        #[inline(always)]
        || {
            if short {
                freqz_grid_blocks::<true>(b, a, freq_hz, fs_hz)
            } else {
                freqz_grid_blocks::<false>(b, a, freq_hz, fs_hz)
            }
        },
    ))
}

/// [`freqz_values_scipy_grid`]'s block loop, with or without the short
/// first Horner step.
#[inline(always)]
fn freqz_grid_blocks<const SHORT: bool>(
    b: &[f64],
    a: &[f64],
    freq_hz: &[f64],
    fs_hz: f64,
) -> (Vec<f64>, Vec<Complex64>) {
    let back = fs_hz / (2.0 * std::f64::consts::PI);
    let mut grid = Vec::with_capacity(freq_hz.len());
    let h = by_blocks(freq_hz, |f: &Lanes<FREQZ_LANES>, h| {
        let minus_w = minus_omega(f, fs_hz);
        let mut w = Lanes::<FREQZ_LANES>::zero();
        for k in 0..FREQZ_LANES {
            w[k] = -minus_w[k] * back;
        }
        grid.extend_from_slice(&w[..h.len()]);
        let (mut zr, mut zi) = (Lanes::zero(), Lanes::zero());
        crate::sincos::sincos_into(&minus_w, &mut zr, &mut zi);
        ratio_z::<_, SHORT>(b, a, &zr, &zi, h);
    });
    (grid, h)
}

/// Frequency response of second-order sections, the product of the
/// sections' [`freqz`], matching
/// `scipy.signal.freqz_sos(sos, worN=freq_hz, fs=fs_hz)` (formerly `sosfreqz`).
///
/// ```
/// use ballpass_dsp::{butter, sosfreqz, FilterBand};
/// let sos = butter(5, FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0).unwrap();
/// let r = sosfreqz(&sos, &[20.0], 1000.0).unwrap();
/// let db = 20.0 * r.h[0].norm().log10();
/// assert!((db + 3.0103).abs() < 1e-3); // -3 dB at the cutoff
/// ```
///
/// # Errors
/// As [`freqz`].
pub fn sosfreqz(sos: &Sos, freq_hz: &[f64], fs_hz: f64) -> Result<DigitalResponse> {
    Ok(DigitalResponse {
        h: sosfreqz_values(sos, freq_hz, fs_hz)?,
        freq_hz: freq_hz.to_vec(),
    })
}

/// [`sosfreqz`]' response values alone (no copy of the frequencies).
///
/// # Errors
/// As [`sosfreqz`].
pub fn sosfreqz_values(sos: &Sos, freq_hz: &[f64], fs_hz: f64) -> Result<Vec<Complex64>> {
    check_freqs(freq_hz, fs_hz)?;
    // The sections' responses at one frequency share its `z^-1`.
    Ok(crate::simd::widest(
        #[inline(always)]
        || {
            by_blocks(freq_hz, |f: &Lanes<LANES>, h| {
                let (zr, zi) = unit_delays(f, fs_hz);
                let mut hs = [Complex64::new(0.0, 0.0); LANES];
                let mut acc = [Complex64::new(1.0, 0.0); LANES];
                for s in sos.sections() {
                    ratio_z::<_, false>(&s[..3], &s[3..], &zr, &zi, &mut hs);
                    for (acc, hs) in acc.iter_mut().zip(&hs) {
                        *acc *= *hs;
                    }
                }
                h.copy_from_slice(&acc[..h.len()]);
            })
        },
    ))
}

#[cfg(test)]
#[path = "lti_tests.rs"]
mod tests;
