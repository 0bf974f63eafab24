//! Complex arithmetic that rounds like NumPy does.
//!
//! Filter design (`butter`, `cheby1`, `zpk2sos`) makes pairing decisions by
//! comparing magnitudes of poles and zeros, so the operations below reproduce
//! the algorithms NumPy 2.4 uses on x86-64 (checked bit for bit on random
//! inputs when this module was written):
//!
//! - division: Smith's algorithm as in NumPy's `@TYPE@_divide` loop;
//! - `sqrt`: glibc's `csqrt` (NumPy calls the C library);
//! - `abs`: NumPy's SIMD `absolute` loop, `L * sqrt(fma(S/L, S/L, 1))` with
//!   `L = max(|re|, |im|)`, `S = min(|re|, |im|)`;
//! - `exp`, `sinh`: `exp(x) (cos y, sin y)`, `(sinh x cos y, cosh x sin y)`.
//!
//! Multiplication, addition and subtraction are those of `num_complex`,
//! which are the textbook formulas NumPy uses too.

use rustfft::num_complex::Complex64;

/// `a / b` with NumPy's (Smith's) algorithm.
pub(crate) fn div(a: Complex64, b: Complex64) -> Complex64 {
    let (ar, ai, br, bi) = (a.re, a.im, b.re, b.im);
    let br_abs = br.abs();
    let bi_abs = bi.abs();
    if br_abs >= bi_abs {
        if br_abs == 0.0 && bi_abs == 0.0 {
            return Complex64::new(ar / br_abs, ai / br_abs);
        }
        let rat = bi / br;
        let scl = 1.0 / (br + bi * rat);
        Complex64::new((ar + ai * rat) * scl, (ai - ar * rat) * scl)
    } else {
        let rat = br / bi;
        let scl = 1.0 / (bi + br * rat);
        Complex64::new((ar * rat + ai) * scl, (ai * rat - ar) * scl)
    }
}

/// Real scalar divided by a complex number, as NumPy does it (the scalar is
/// promoted to `x + 0j` first).
pub(crate) fn rdiv(x: f64, b: Complex64) -> Complex64 {
    div(Complex64::new(x, 0.0), b)
}

/// Principal square root, glibc's `csqrt` for finite arguments.
pub(crate) fn sqrt(z: Complex64) -> Complex64 {
    let (re, im) = (z.re, z.im);
    if im == 0.0 {
        if re < 0.0 {
            return Complex64::new(0.0, (-re).sqrt().copysign(im));
        }
        return Complex64::new(re.sqrt().abs(), 0.0f64.copysign(im));
    }
    if re == 0.0 {
        let r = (0.5 * im.abs()).sqrt();
        return Complex64::new(r, r.copysign(im));
    }
    let d = re.hypot(im);
    let (r, s);
    if re > 0.0 {
        r = (0.5 * (d + re)).sqrt();
        s = 0.5 * (im / r);
    } else {
        s = (0.5 * (d - re)).sqrt();
        r = (0.5 * (im / s)).abs();
    }
    Complex64::new(r, s.copysign(im))
}

/// `|z|` as NumPy's vectorised `absolute` computes it.
pub(crate) fn abs(z: Complex64) -> f64 {
    let re = z.re.abs();
    let im = z.im.abs();
    if re.is_infinite() || im.is_infinite() {
        return f64::INFINITY;
    }
    if re.is_nan() || im.is_nan() {
        return f64::NAN;
    }
    let larger = re.max(im);
    let smaller = re.min(im);
    if larger == 0.0 {
        return 0.0;
    }
    let ratio = smaller / larger;
    ratio.mul_add(ratio, 1.0).sqrt() * larger
}

/// `exp(z)` for finite `z`.
pub(crate) fn exp(z: Complex64) -> Complex64 {
    let e = z.re.exp();
    Complex64::new(e * z.im.cos(), e * z.im.sin())
}

/// `sinh(z)` for finite `z` of moderate size.
pub(crate) fn sinh(z: Complex64) -> Complex64 {
    Complex64::new(z.re.sinh() * z.im.cos(), z.re.cosh() * z.im.sin())
}

/// Product of a sequence, multiplied left to right from the first element
/// (NumPy's `prod` reduction); the empty product is `1`.
pub(crate) fn prod(values: impl IntoIterator<Item = Complex64>) -> Complex64 {
    let mut it = values.into_iter();
    match it.next() {
        None => Complex64::new(1.0, 0.0),
        Some(first) => it.fold(first, |acc, v| acc * v),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn division_and_sqrt_agree_with_the_definitions() {
        // Tolerance 4 ulp-ish: these are identities, not SciPy comparisons.
        let a = Complex64::new(1.5, -2.0);
        let b = Complex64::new(-0.25, 3.0);
        let q = div(a, b);
        let back = q * b;
        assert!((back - a).norm() < 1e-15 * a.norm() * 4.0);
        let r = sqrt(Complex64::new(-4.0, 0.0));
        assert_eq!(r, Complex64::new(0.0, 2.0));
        let s = sqrt(Complex64::new(3.0, -4.0));
        assert!((s * s - Complex64::new(3.0, -4.0)).norm() < 1e-15 * 5.0 * 4.0);
        assert_eq!(abs(Complex64::new(3.0, 4.0)), 5.0);
        assert_eq!(prod(Vec::new()), Complex64::new(1.0, 0.0));
    }
}
