//! FFT plans shared within a thread.
//!
//! A real FFT plan of length `n` holds its twiddle factors (`n` sines and
//! cosines) and its algorithm choice; building one costs about as much as a
//! few transforms. The plans are immutable and the planner picks the same
//! algorithm for a length every time, so a thread keeps one planner and
//! every Welch engine and correlator of that thread reuses its plans (a
//! campaign's worker threads plan each length once, not once per record).
//! The transforms are bit for bit those of a fresh plan.

use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::Arc;

use realfft::{RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

thread_local! {
    static PLANNER: RefCell<RealFftPlanner<f64>> = RefCell::new(RealFftPlanner::new());
    static COMPLEX_PLANNER: RefCell<FftPlanner<f64>> = RefCell::new(FftPlanner::new());
}

/// The forward real FFT of length `len` (cached per thread).
pub(crate) fn forward(len: usize) -> Arc<dyn RealToComplex<f64>> {
    PLANNER.with(|p| p.borrow_mut().plan_fft_forward(len))
}

/// The forward complex FFT of length `len` (cached per thread).
pub(crate) fn complex_forward(len: usize) -> Arc<dyn Fft<f64>> {
    COMPLEX_PLANNER.with(|p| p.borrow_mut().plan_fft_forward(len))
}

thread_local! {
    static HALF: RefCell<HashMap<usize, Arc<HalfComplex>>> = RefCell::new(HashMap::new());
    /// The planner of the [`HalfComplex`] FFTs, apart from `COMPLEX_PLANNER`:
    /// planning the long correlation lengths in the same planner made the
    /// Welch engine's later 4096-point FFTs ~7 % slower (measured).
    static HALF_PLANNER: RefCell<FftPlanner<f64>> = RefCell::new(FftPlanner::new());
}

/// A real FFT of even length `n` done as a complex FFT of `m = n / 2`
/// points and one twiddle pass, as realfft's `RealToComplexEven` and
/// `ComplexToRealEven` (the same twiddle operations in the same order; the
/// inner FFT is RustFFT's in-place call where realfft makes the
/// out-of-place one, so the two agree to ~1e-15 of the peak, as the tests
/// check), but with the passes exposed one bin pair at a time so callers
/// can fuse them with their own work.
///
/// Forward: pack `z[t] = x[2t] + i x[2t+1]`, `Z = FFT_m(z)`; then for
/// `k = 1 .. m/2` with `j = m - k` and `W = exp(-2 pi i / n)`
///
/// ```text
/// X[k] = (Z[k] + conj Z[j]) / 2 - i W^k (Z[k] - conj Z[j]) / 2
/// X[j] = conj( (Z[k] + conj Z[j]) / 2 + i W^k (Z[k] - conj Z[j]) / 2 )
/// X[0] = Re Z[0] + Im Z[0],   X[m] = Re Z[0] - Im Z[0]
/// ```
///
/// ([`forward_pair`]). The inverse ([`inverse_pair`]) undoes this up to a
/// factor 2, so that `IFFT_m` (unnormalised) of its output holds
/// `n x[2t] + i n x[2t+1]`.
pub(crate) struct HalfComplex {
    /// Forward complex FFT of `n / 2` points.
    pub(crate) forward: Arc<dyn Fft<f64>>,
    /// Inverse (unnormalised) complex FFT of `n / 2` points.
    pub(crate) inverse: Arc<dyn Fft<f64>>,
    /// `W^k = exp(-2 pi i k / n)` for `k = 1 ..` [`HalfComplex::pairs`]` + 1`,
    /// computed as realfft does.
    pub(crate) twiddles: Vec<Complex<f64>>,
}

impl HalfComplex {
    /// The in-place scratch length both inner FFTs accept.
    pub(crate) fn scratch_len(&self) -> usize {
        self.forward
            .get_inplace_scratch_len()
            .max(self.inverse.get_inplace_scratch_len())
    }

    /// The number of bin pairs `(k, m - k)`, `k >= 1`, the twiddle passes
    /// visit (`m/2 - 1` for even `m`, `(m-1)/2` for odd `m`).
    pub(crate) fn pairs(&self) -> usize {
        self.twiddles.len()
    }
}

/// The real FFT of even length `len` as a half-length complex FFT (cached
/// per thread).
pub(crate) fn half_complex(len: usize) -> Arc<HalfComplex> {
    debug_assert!(len % 2 == 0 && len > 0);
    HALF.with(|h| {
        Arc::clone(h.borrow_mut().entry(len).or_insert_with(|| {
            let m = len / 2;
            let pairs = if len % 4 == 0 { len / 4 - 1 } else { len / 4 };
            // As realfft's `compute_twiddle`: one rounding of the angle,
            // then cos and sin.
            let step = -2.0 * std::f64::consts::PI / len as f64;
            let twiddles = (1..=pairs)
                .map(|k| {
                    let angle = step * k as f64;
                    Complex::new(angle.cos(), angle.sin())
                })
                .collect();
            Arc::new(HalfComplex {
                forward: HALF_PLANNER.with(|p| p.borrow_mut().plan_fft_forward(m)),
                inverse: HALF_PLANNER.with(|p| p.borrow_mut().plan_fft_inverse(m)),
                twiddles,
            })
        }))
    })
}

/// The forward post-processing of one bin pair: `(X[k], X[j])` from
/// `(Z[k], Z[j])` and `w = W^k` (see [`HalfComplex`]); realfft's
/// operations with its halved twiddle `w / 2` (an exact scaling).
#[inline(always)]
pub(crate) fn forward_pair(
    w: Complex<f64>,
    zk: Complex<f64>,
    zj: Complex<f64>,
) -> (Complex<f64>, Complex<f64>) {
    let (tre, tim) = (w.re * 0.5, w.im * 0.5);
    let sum = zk + zj;
    let diff = zk - zj;
    let half_sum_re = 0.5 * sum.re;
    let half_diff_im = 0.5 * diff.im;
    let twiddled_re = sum.im * tre + diff.re * tim;
    let twiddled_im = sum.im * tim - diff.re * tre;
    (
        Complex::new(half_sum_re + twiddled_re, half_diff_im + twiddled_im),
        Complex::new(half_sum_re - twiddled_re, twiddled_im - half_diff_im),
    )
}

/// The first forward bins: `(X[0], X[m])` from `Z[0]` (both real).
#[inline(always)]
pub(crate) fn forward_ends(z0: Complex<f64>) -> (Complex<f64>, Complex<f64>) {
    (
        Complex::new(z0.re + z0.im, 0.0),
        Complex::new(z0.re - z0.im, 0.0),
    )
}

/// The inverse pre-processing of one bin pair: the inputs at `k` and `j`
/// of the inverse complex FFT from the spectrum `(X[k], X[j])` and
/// `w = W^k`; realfft's operations with its twiddle `conj w`.
#[inline(always)]
pub(crate) fn inverse_pair(
    w: Complex<f64>,
    xk: Complex<f64>,
    xj: Complex<f64>,
) -> (Complex<f64>, Complex<f64>) {
    let (tre, tim) = (w.re, -w.im);
    let sum = xk + xj;
    let diff = xk - xj;
    let twiddled_re = sum.im * tre + diff.re * tim;
    let twiddled_im = sum.im * tim - diff.re * tre;
    (
        Complex::new(sum.re - twiddled_re, diff.im - twiddled_im),
        Complex::new(sum.re + twiddled_re, -twiddled_im - diff.im),
    )
}

/// The inverse pre-processing of the ends: the input at 0 from `X[0]` and
/// `X[m]`, whose imaginary parts are taken as zero.
#[inline(always)]
pub(crate) fn inverse_ends(x0: Complex<f64>, xm: Complex<f64>) -> Complex<f64> {
    let (a, b) = (Complex::new(x0.re, 0.0), Complex::new(xm.re, 0.0));
    let sum = a + b;
    let diff = a - b;
    Complex::new(sum.re - sum.im, diff.re - diff.im)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The real FFT of `x` (length `h`'s `n`) through [`HalfComplex`]:
    /// `n/2 + 1` bins.
    fn forward_real(h: &HalfComplex, x: &[f64]) -> Vec<Complex<f64>> {
        let m = x.len() / 2;
        let mut z: Vec<Complex<f64>> = x.chunks(2).map(|p| Complex::new(p[0], p[1])).collect();
        h.forward.process(&mut z);
        let mut out = vec![Complex::new(0.0, 0.0); m + 1];
        (out[0], out[m]) = forward_ends(z[0]);
        for (i, w) in h.twiddles.iter().enumerate() {
            let (k, j) = (i + 1, m - 1 - i);
            (out[k], out[j]) = forward_pair(*w, z[k], z[j]);
        }
        if m % 2 == 0 && m > 1 {
            out[m / 2] = z[m / 2].conj();
        }
        out
    }

    /// The inverse (times `n`) of [`forward_real`].
    fn inverse_real(h: &HalfComplex, spec: &[Complex<f64>]) -> Vec<f64> {
        let m = spec.len() - 1;
        let mut z = vec![Complex::new(0.0, 0.0); m];
        z[0] = inverse_ends(spec[0], spec[m]);
        for (i, w) in h.twiddles.iter().enumerate() {
            let (k, j) = (i + 1, m - 1 - i);
            (z[k], z[j]) = inverse_pair(*w, spec[k], spec[j]);
        }
        if m % 2 == 0 && m > 1 {
            z[m / 2] = (spec[m / 2] + spec[m / 2]).conj();
        }
        h.inverse.process(&mut z);
        z.iter().flat_map(|c| [c.re, c.im]).collect()
    }

    fn signal(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| ((i * 7919 % 1013) as f64 / 1013.0 - 0.5) + (i as f64 * 0.01).sin())
            .collect()
    }

    #[test]
    fn half_complex_equals_realfft_and_naive_dft() {
        for n in [2, 4, 6, 8, 10, 12, 18, 30, 64, 96, 162, 1000, 4374, 6912] {
            let h = half_complex(n);
            let x = signal(n);
            let ours = forward_real(&h, &x);
            let mut planner = RealFftPlanner::<f64>::new();
            let r2c = planner.plan_fft_forward(n);
            let mut input = x.clone();
            let mut theirs = r2c.make_output_vec();
            r2c.process(&mut input, &mut theirs).unwrap();
            let peak = theirs.iter().fold(0.0f64, |a, v| a.max(v.norm()));
            for (k, (a, b)) in ours.iter().zip(&theirs).enumerate() {
                assert!((a - b).norm() <= 1e-15 * peak, "n {n} bin {k}: {a} vs {b}");
                // Naive DFT, summed in long form.
                let mut s = Complex::new(0.0, 0.0);
                for (t, v) in x.iter().enumerate() {
                    let ang = -2.0 * std::f64::consts::PI * ((k * t) % n) as f64 / n as f64;
                    s += Complex::new(ang.cos(), ang.sin()) * v;
                }
                assert!(
                    (a - s).norm() <= 1e-13 * peak,
                    "n {n} bin {k}: {a} vs DFT {s}"
                );
            }
            let c2r = planner.plan_fft_inverse(n);
            let back = inverse_real(&h, &ours);
            let mut spec = theirs.clone();
            let mut want = c2r.make_output_vec();
            c2r.process(&mut spec, &mut want).unwrap();
            let scale = n as f64 * x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (t, ((a, b), v)) in back.iter().zip(&want).zip(&x).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-15 * scale,
                    "n {n} sample {t}: {a} vs {b}"
                );
                assert!((a / n as f64 - v).abs() <= 1e-13 * scale / n as f64);
            }
        }
    }
}
