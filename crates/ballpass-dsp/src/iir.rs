//! IIR filter design: Butterworth and Chebyshev type I filters in
//! second-order sections, designed exactly as SciPy designs them.
//!
//! The path is SciPy's `iirfilter(..., output='sos', fs=fs_hz)`:
//!
//! ```text
//! analog prototype (buttap / cheb1ap, cutoff 1 rad/s)
//!   -> pre-warp     w = 4 tan(pi Wn / 2),  Wn = f / (fs/2)
//!   -> lp2lp / lp2hp / lp2bp / lp2bs  (bandpass: wo = sqrt(w1 w2), bw = w2 - w1)
//!   -> bilinear     z = (4 + s) / (4 - s)
//!   -> zpk2sos      (pairing = 'nearest')
//! ```
//!
//! Every step reproduces SciPy 1.17's arithmetic (including NumPy's complex
//! division and `_cplxreal`'s sorting), so the sections come out in the same
//! order with the same pole-zero pairing, and agree with SciPy's to a few ulp.

use rustfft::num_complex::Complex64;

use crate::error::{invalid, DspError, Result};
use crate::npcomplex as nc;
use crate::sos::Sos;

/// Which band a digital filter passes, with its edge frequencies in Hz.
///
/// The edges are the points where the gain has fallen to `-3 dB`
/// (Butterworth) or to `-rp dB` (Chebyshev I), as in SciPy's `Wn`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FilterBand {
    /// Passes `0 .. cutoff_hz` (SciPy `btype='lowpass'`).
    LowPass {
        /// Cutoff frequency in Hz, `0 < cutoff_hz < fs_hz / 2`.
        cutoff_hz: f64,
    },
    /// Passes `cutoff_hz .. fs/2` (SciPy `btype='highpass'`).
    HighPass {
        /// Cutoff frequency in Hz, `0 < cutoff_hz < fs_hz / 2`.
        cutoff_hz: f64,
    },
    /// Passes `low_hz .. high_hz` (SciPy `btype='bandpass'`); the order of
    /// the resulting filter is twice the requested order.
    BandPass {
        /// Lower edge in Hz.
        low_hz: f64,
        /// Upper edge in Hz, `low_hz < high_hz < fs_hz / 2`.
        high_hz: f64,
    },
    /// Stops `low_hz .. high_hz` (SciPy `btype='bandstop'`); the order of
    /// the resulting filter is twice the requested order.
    BandStop {
        /// Lower edge in Hz.
        low_hz: f64,
        /// Upper edge in Hz, `low_hz < high_hz < fs_hz / 2`.
        high_hz: f64,
    },
}

impl FilterBand {
    /// The SciPy `btype` string of this band (`"lowpass"`, ...).
    pub fn scipy_name(&self) -> &'static str {
        match self {
            FilterBand::LowPass { .. } => "lowpass",
            FilterBand::HighPass { .. } => "highpass",
            FilterBand::BandPass { .. } => "bandpass",
            FilterBand::BandStop { .. } => "bandstop",
        }
    }
}

/// Settings of a digital Butterworth filter ([`butter`]).
///
/// The default is the thesis' pre-processing filter: 5th-order low-pass at
/// 20 Hz for a signal sampled at 1 kHz.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ButterSettings {
    /// Filter order `N >= 1` (band filters get `2N` poles).
    pub order: usize,
    /// Pass band and its edges in Hz.
    pub band: FilterBand,
    /// Sampling frequency in Hz.
    pub fs_hz: f64,
}

impl Default for ButterSettings {
    fn default() -> Self {
        ButterSettings {
            order: 5,
            band: FilterBand::LowPass { cutoff_hz: 20.0 },
            fs_hz: 1000.0,
        }
    }
}

impl ButterSettings {
    /// Designs the filter; see [`butter`].
    ///
    /// # Errors
    /// As [`butter`].
    pub fn design(&self) -> Result<Sos> {
        butter(self.order, self.band, self.fs_hz)
    }
}

/// Settings of a digital Chebyshev type I filter ([`cheby1`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cheby1Settings {
    /// Filter order `N >= 1`.
    pub order: usize,
    /// Peak-to-peak pass-band ripple in dB (`rp`), `> 0`.
    pub ripple_db: f64,
    /// Pass band and its edges in Hz (the edges are where the gain first
    /// drops below `-ripple_db`).
    pub band: FilterBand,
    /// Sampling frequency in Hz.
    pub fs_hz: f64,
}

impl Cheby1Settings {
    /// Designs the filter; see [`cheby1`].
    ///
    /// # Errors
    /// As [`cheby1`].
    pub fn design(&self) -> Result<Sos> {
        cheby1(self.order, self.ripple_db, self.band, self.fs_hz)
    }
}

/// Zeros, poles and gain of a transfer function
/// `H = k prod(z - z_i) / prod(z - p_i)` (SciPy's `output='zpk'`).
#[derive(Debug, Clone, PartialEq)]
pub struct Zpk {
    /// Zeros.
    pub zeros: Vec<Complex64>,
    /// Poles.
    pub poles: Vec<Complex64>,
    /// Gain `k`.
    pub gain: f64,
}

/// Digital Butterworth filter as second-order sections, matching
/// `scipy.signal.butter(order, Wn, btype, output='sos', fs=fs_hz)`.
///
/// ```text
/// |H(f)|^2 = 1 / (1 + (tan(pi f/fs) / tan(pi fc/fs))^(2N))     (low-pass)
/// ```
///
/// The cutoff is the `-3 dB` point of the digital filter (the analog
/// prototype is pre-warped before the bilinear transform).
///
/// ```
/// use ballpass_dsp::{butter, FilterBand};
/// let sos = butter(5, FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0).unwrap();
/// assert_eq!(sos.n_sections(), 3);
/// // unit gain at DC
/// let dc: f64 = sos.sections().iter().map(|s| (s[0] + s[1] + s[2]) / (s[3] + s[4] + s[5])).product();
/// assert!((dc - 1.0).abs() < 1e-12);
/// ```
///
/// # Errors
/// [`DspError::InvalidSetting`] if `order == 0`, `fs_hz` is not finite and
/// positive, an edge is not inside `(0, fs_hz / 2)`, or band edges are not
/// increasing.
pub fn butter(order: usize, band: FilterBand, fs_hz: f64) -> Result<Sos> {
    zpk2sos(&butter_zpk(order, band, fs_hz)?)
}

/// The zeros, poles and gain of [`butter`] (SciPy's `output='zpk'`).
///
/// # Errors
/// As [`butter`].
pub fn butter_zpk(order: usize, band: FilterBand, fs_hz: f64) -> Result<Zpk> {
    check_order(order)?;
    let warped = prewarp(band, fs_hz)?;
    let proto = buttap(order);
    Ok(transform(proto, band, &warped))
}

/// Digital Chebyshev type I filter as second-order sections, matching
/// `scipy.signal.cheby1(order, ripple_db, Wn, btype, output='sos', fs=fs_hz)`.
///
/// Equiripple in the pass band (ripple `ripple_db` dB peak to peak),
/// monotonic in the stop band. Even orders have a DC gain of `-ripple_db` dB.
///
/// # Errors
/// As [`butter`], and [`DspError::InvalidSetting`] if `ripple_db` is not
/// finite and positive.
pub fn cheby1(order: usize, ripple_db: f64, band: FilterBand, fs_hz: f64) -> Result<Sos> {
    zpk2sos(&cheby1_zpk(order, ripple_db, band, fs_hz)?)
}

/// The zeros, poles and gain of [`cheby1`] (SciPy's `output='zpk'`).
///
/// # Errors
/// As [`cheby1`].
pub fn cheby1_zpk(order: usize, ripple_db: f64, band: FilterBand, fs_hz: f64) -> Result<Zpk> {
    check_order(order)?;
    if !(ripple_db.is_finite() && ripple_db > 0.0) {
        return Err(invalid(
            "ripple_db",
            format!("must be finite and > 0 dB, got {ripple_db}"),
        ));
    }
    let warped = prewarp(band, fs_hz)?;
    let proto = cheb1ap(order, ripple_db);
    Ok(transform(proto, band, &warped))
}

fn check_order(order: usize) -> Result<()> {
    if order == 0 {
        return Err(invalid("order", "must be at least 1, got 0"));
    }
    if order > 64 {
        return Err(invalid(
            "order",
            format!("must be at most 64 (numerically meaningless beyond), got {order}"),
        ));
    }
    Ok(())
}

/// Validates the band against `fs_hz` and returns the pre-warped analog
/// edges `4 tan(pi Wn / 2)`, `Wn = f / (fs/2)` (SciPy's `warped`).
fn prewarp(band: FilterBand, fs_hz: f64) -> Result<Vec<f64>> {
    if !(fs_hz.is_finite() && fs_hz > 0.0) {
        return Err(invalid(
            "fs_hz",
            format!("must be finite and > 0, got {fs_hz}"),
        ));
    }
    let nyq = fs_hz / 2.0;
    let edges: Vec<(&'static str, f64)> = match band {
        FilterBand::LowPass { cutoff_hz } | FilterBand::HighPass { cutoff_hz } => {
            vec![("cutoff_hz", cutoff_hz)]
        }
        FilterBand::BandPass { low_hz, high_hz } | FilterBand::BandStop { low_hz, high_hz } => {
            vec![("low_hz", low_hz), ("high_hz", high_hz)]
        }
    };
    for &(name, f) in &edges {
        if !(f.is_finite() && f > 0.0 && f < nyq) {
            return Err(invalid(
                name,
                format!("must be inside (0, fs/2) = (0, {nyq}) Hz, got {f}"),
            ));
        }
    }
    if edges.len() == 2 && edges[0].1 >= edges[1].1 {
        return Err(invalid(
            "low_hz",
            format!(
                "band edges must increase, got low_hz = {} >= high_hz = {}",
                edges[0].1, edges[1].1
            ),
        ));
    }
    // SciPy: Wn = Wn / (fs/2); fs = 2; warped = 2*fs*tan(pi*Wn/fs).
    let warped = edges
        .iter()
        .map(|&(_, f)| {
            let wn = f / nyq;
            4.0 * (std::f64::consts::PI * wn / 2.0).tan()
        })
        .collect::<Vec<_>>();
    // Wn was checked inside (0, 1) in Hz terms; the division can still round
    // to 1.0 for an edge one ulp below Nyquist.
    for (&w, &(name, f)) in warped.iter().zip(&edges) {
        if !(w.is_finite() && w > 0.0) || f / nyq >= 1.0 {
            return Err(invalid(
                name,
                format!("is too close to fs/2 = {nyq} Hz to design a filter, got {f}"),
            ));
        }
    }
    Ok(warped)
}

/// Analog Butterworth prototype (SciPy `buttap`): no zeros, poles
/// `-exp(j pi m / (2N))`, `m = -N+1, -N+3, ..., N-1`, gain 1.
fn buttap(n: usize) -> Zpk {
    let scl = 1.0 / (2 * n) as f64; // NumPy divides complex by (2N + 0j)
    let poles = (0..n)
        .map(|i| {
            let m = -(n as f64) + 1.0 + 2.0 * i as f64;
            let theta = (std::f64::consts::PI * m) * scl;
            -nc::exp(Complex64::new(0.0, theta))
        })
        .collect();
    Zpk {
        zeros: Vec::new(),
        poles,
        gain: 1.0,
    }
}

/// Analog Chebyshev I prototype (SciPy `cheb1ap`).
///
/// ```text
/// eps = sqrt(10^(rp/10) - 1),  mu = asinh(1/eps) / N
/// p_m = -sinh(mu + j pi m / (2N)),  k = Re prod(-p) [/ sqrt(1 + eps^2) if N even]
/// ```
fn cheb1ap(n: usize, rp: f64) -> Zpk {
    let eps = (10f64.powf(0.1 * rp) - 1.0).sqrt();
    let mu = 1.0 / n as f64 * (1.0 / eps).asinh();
    let poles: Vec<Complex64> = (0..n)
        .map(|i| {
            let m = -(n as f64) + 1.0 + 2.0 * i as f64;
            let theta = std::f64::consts::PI * m / (2 * n) as f64;
            -nc::sinh(Complex64::new(mu, theta))
        })
        .collect();
    let mut gain = nc::prod(poles.iter().map(|p| -p)).re;
    if n % 2 == 0 {
        gain /= (1.0 + eps * eps).sqrt();
    }
    Zpk {
        zeros: Vec::new(),
        poles,
        gain,
    }
}

/// Frequency transformation (lp2lp/lp2hp/lp2bp/lp2bs) followed by the
/// bilinear transform with `fs = 2`, as `iirfilter` does.
fn transform(proto: Zpk, band: FilterBand, warped: &[f64]) -> Zpk {
    let analog = match band {
        FilterBand::LowPass { .. } => lp2lp_zpk(proto, warped[0]),
        FilterBand::HighPass { .. } => lp2hp_zpk(proto, warped[0]),
        FilterBand::BandPass { .. } => {
            let bw = warped[1] - warped[0];
            let wo = (warped[0] * warped[1]).sqrt();
            lp2bp_zpk(proto, wo, bw)
        }
        FilterBand::BandStop { .. } => {
            let bw = warped[1] - warped[0];
            let wo = (warped[0] * warped[1]).sqrt();
            lp2bs_zpk(proto, wo, bw)
        }
    };
    bilinear_zpk(analog, 2.0)
}

fn relative_degree(z: &Zpk) -> usize {
    // Our prototypes never have more zeros than poles.
    z.poles.len() - z.zeros.len()
}

/// SciPy `lp2lp_zpk`: `z wo`, `p wo`, `k wo^(#p - #z)`.
fn lp2lp_zpk(zpk: Zpk, wo: f64) -> Zpk {
    let degree = relative_degree(&zpk);
    Zpk {
        zeros: zpk.zeros.iter().map(|z| z * wo).collect(),
        poles: zpk.poles.iter().map(|p| p * wo).collect(),
        gain: zpk.gain * wo.powf(degree as f64),
    }
}

/// SciPy `lp2hp_zpk`: `wo / z`, `wo / p`, zeros at the origin,
/// `k Re(prod(-z) / prod(-p))`.
fn lp2hp_zpk(zpk: Zpk, wo: f64) -> Zpk {
    let degree = relative_degree(&zpk);
    let mut zeros: Vec<Complex64> = zpk.zeros.iter().map(|&z| nc::rdiv(wo, z)).collect();
    zeros.extend(std::iter::repeat_n(Complex64::new(0.0, 0.0), degree));
    let poles = zpk.poles.iter().map(|&p| nc::rdiv(wo, p)).collect();
    let num = nc::prod(zpk.zeros.iter().map(|z| -z));
    let den = nc::prod(zpk.poles.iter().map(|p| -p));
    Zpk {
        zeros,
        poles,
        gain: zpk.gain * nc::div(num, den).re,
    }
}

/// `x + sqrt(x^2 - wo^2)` and `x - sqrt(x^2 - wo^2)` for every x, in
/// SciPy's order (all `+` first, then all `-`).
fn split_around(xs: &[Complex64], wo: f64) -> Vec<Complex64> {
    let wo2 = wo.powf(2.0);
    let roots: Vec<Complex64> = xs
        .iter()
        .map(|&x| nc::sqrt(x * x - Complex64::new(wo2, 0.0)))
        .collect();
    let mut out: Vec<Complex64> = xs.iter().zip(&roots).map(|(x, r)| x + r).collect();
    out.extend(xs.iter().zip(&roots).map(|(x, r)| x - r));
    out
}

/// SciPy `lp2bp_zpk`.
fn lp2bp_zpk(zpk: Zpk, wo: f64, bw: f64) -> Zpk {
    let degree = relative_degree(&zpk);
    let z_lp: Vec<Complex64> = zpk.zeros.iter().map(|z| z * bw * 0.5).collect();
    let p_lp: Vec<Complex64> = zpk.poles.iter().map(|p| p * bw * 0.5).collect();
    let mut zeros = split_around(&z_lp, wo);
    zeros.extend(std::iter::repeat_n(Complex64::new(0.0, 0.0), degree));
    Zpk {
        zeros,
        poles: split_around(&p_lp, wo),
        gain: zpk.gain * bw.powf(degree as f64),
    }
}

/// SciPy `lp2bs_zpk`.
fn lp2bs_zpk(zpk: Zpk, wo: f64, bw: f64) -> Zpk {
    let degree = relative_degree(&zpk);
    let half = bw / 2.0;
    let z_hp: Vec<Complex64> = zpk.zeros.iter().map(|&z| nc::rdiv(half, z)).collect();
    let p_hp: Vec<Complex64> = zpk.poles.iter().map(|&p| nc::rdiv(half, p)).collect();
    let mut zeros = split_around(&z_hp, wo);
    zeros.extend(std::iter::repeat_n(Complex64::new(0.0, wo), degree));
    zeros.extend(std::iter::repeat_n(Complex64::new(-0.0, -wo), degree));
    let num = nc::prod(zpk.zeros.iter().map(|z| -z));
    let den = nc::prod(zpk.poles.iter().map(|p| -p));
    Zpk {
        zeros,
        poles: split_around(&p_hp, wo),
        gain: zpk.gain * nc::div(num, den).re,
    }
}

/// SciPy `bilinear_zpk`: `z -> (2fs + z) / (2fs - z)`, zeros at infinity
/// to `-1`, `k Re(prod(2fs - z) / prod(2fs - p))`.
fn bilinear_zpk(zpk: Zpk, fs: f64) -> Zpk {
    let degree = relative_degree(&zpk);
    let fs2 = Complex64::new(2.0 * fs, 0.0);
    let map = |x: &Complex64| nc::div(fs2 + x, fs2 - x);
    let mut zeros: Vec<Complex64> = zpk.zeros.iter().map(map).collect();
    zeros.extend(std::iter::repeat_n(Complex64::new(-1.0, 0.0), degree));
    let poles = zpk.poles.iter().map(map).collect();
    let num = nc::prod(zpk.zeros.iter().map(|z| fs2 - z));
    let den = nc::prod(zpk.poles.iter().map(|p| fs2 - p));
    Zpk {
        zeros,
        poles,
        gain: zpk.gain * nc::div(num, den).re,
    }
}

const CPLX_TOL: f64 = 100.0 * f64::EPSILON;

/// SciPy `_cplxreal`: complex values (one of each conjugate pair, positive
/// imaginary part, pairs averaged) followed by the real values, each sorted
/// as SciPy sorts them. Returned as one list with the reals' imaginary parts
/// exactly zero.
fn cplxreal(values: &[Complex64]) -> Result<Vec<Complex64>> {
    if values.is_empty() {
        return Ok(Vec::new());
    }
    let mut z = values.to_vec();
    // np.lexsort((abs(z.imag), z.real)): stable, real part first.
    z.sort_by(|a, b| {
        a.re.total_cmp(&b.re)
            .then_with(|| a.im.abs().total_cmp(&b.im.abs()))
    });
    let is_real = |v: &Complex64| v.im.abs() <= CPLX_TOL * nc::abs(*v);
    let reals: Vec<Complex64> = z
        .iter()
        .filter(|v| is_real(v))
        .map(|v| Complex64::new(v.re, 0.0))
        .collect();
    if reals.len() == z.len() {
        return Ok(reals);
    }
    let rest: Vec<Complex64> = z.iter().filter(|v| !is_real(v)).copied().collect();
    let mut zp: Vec<Complex64> = rest.iter().filter(|v| v.im > 0.0).copied().collect();
    let mut zn: Vec<Complex64> = rest.iter().filter(|v| v.im < 0.0).copied().collect();
    let unmatched = || DspError::Numerical {
        what: "zpk2sos",
        reason: "a complex pole or zero has no matching conjugate".into(),
    };
    if zp.len() != zn.len() {
        return Err(unmatched());
    }
    // Runs of (approximately) equal real part, each sorted by |imag|.
    let mut start = 0;
    while start < zp.len() {
        let mut stop = start;
        while stop + 1 < zp.len() && zp[stop + 1].re - zp[stop].re <= CPLX_TOL * nc::abs(zp[stop]) {
            stop += 1;
        }
        if stop > start {
            zp[start..=stop].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
            zn[start..=stop].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
        }
        start = stop + 1;
    }
    for (p, n) in zp.iter().zip(&zn) {
        if nc::abs(p - n.conj()) > CPLX_TOL * nc::abs(*n) {
            return Err(unmatched());
        }
    }
    let mut out: Vec<Complex64> = zp
        .iter()
        .zip(&zn)
        .map(|(p, n)| {
            let s = p + n.conj();
            Complex64::new(s.re * 0.5, s.im * 0.5)
        })
        .collect();
    out.extend(reals);
    Ok(out)
}

fn is_real(v: &Complex64) -> bool {
    v.im == 0.0
}

/// Index of the pole nearest the unit circle (first one on ties), SciPy's
/// `idx_worst` for digital systems.
fn idx_worst(p: &[Complex64], among: impl Iterator<Item = usize>) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for i in among {
        let d = (1.0 - nc::abs(p[i])).abs();
        if best.is_none_or(|(_, bd)| d < bd) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

#[derive(Clone, Copy, PartialEq)]
enum Which {
    Real,
    Complex,
    Any,
}

/// SciPy `_nearest_real_complex_idx`: the zero nearest `to` among those of
/// the requested kind (first one on ties).
fn nearest_idx(fro: &[Complex64], to: Complex64, which: Which) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, v) in fro.iter().enumerate() {
        let ok = match which {
            Which::Any => true,
            Which::Real => is_real(v),
            Which::Complex => !is_real(v),
        };
        if !ok {
            continue;
        }
        let d = nc::abs(v - to);
        if best.is_none_or(|(_, bd)| d < bd) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

/// `[b0, b1, b2, 1, a1, a2]` of one section from up to two zeros and two
/// poles (SciPy `_single_zpksos` with gain 1), right-aligned like SciPy.
fn single_section(z: &[Complex64], p: &[Complex64]) -> [f64; 6] {
    fn poly(r: &[Complex64]) -> Vec<f64> {
        match r {
            [] => vec![1.0],
            [a] => vec![1.0, -a.re],
            [a, b] => vec![1.0, (-b).re + (-a).re, ((-a) * (-b)).re],
            _ => unreachable!("a section has at most two roots"),
        }
    }
    let b = poly(z);
    let a = poly(p);
    let mut s = [0.0; 6];
    s[3 - b.len()..3].copy_from_slice(&b);
    s[6 - a.len()..6].copy_from_slice(&a);
    s
}

fn take(v: &mut Vec<Complex64>, i: usize) -> Complex64 {
    v.remove(i)
}

/// Second-order sections from zeros, poles and gain, SciPy's
/// `zpk2sos(z, p, k, pairing='nearest')` for digital systems.
///
/// Poles nearest the unit circle go last; each is paired with its nearest
/// zero; an odd order gets an extra pole and zero at the origin; the gain is
/// put in the first section's numerator.
///
/// # Errors
/// [`DspError::InvalidSetting`] if a pole, zero or the gain is not finite;
/// [`DspError::Numerical`] if a complex root has no conjugate partner (the
/// filter would not be real).
pub fn zpk2sos(zpk: &Zpk) -> Result<Sos> {
    if !zpk.gain.is_finite() {
        return Err(invalid("gain", format!("must be finite, got {}", zpk.gain)));
    }
    if zpk
        .zeros
        .iter()
        .chain(&zpk.poles)
        .any(|v| !(v.re.is_finite() && v.im.is_finite()))
    {
        return Err(invalid("zpk", "poles and zeros must be finite"));
    }
    let k = zpk.gain;
    if zpk.zeros.is_empty() && zpk.poles.is_empty() {
        return Sos::new(vec![[k, 0.0, 0.0, 1.0, 0.0, 0.0]]);
    }
    let mut z = zpk.zeros.clone();
    let mut p = zpk.poles.clone();
    let zero = Complex64::new(0.0, 0.0);
    let n = z.len().max(p.len());
    z.resize(n, zero);
    p.resize(n, zero);
    let n_sections = n.div_ceil(2);
    if p.len() % 2 == 1 {
        p.push(zero);
        z.push(zero);
    }
    let mut z = cplxreal(&z)?;
    let mut p = cplxreal(&p)?;
    let mut sos = vec![[0.0; 6]; n_sections];
    let internal = |what: &str| DspError::Numerical {
        what: "zpk2sos",
        reason: format!("pairing ran out of {what}"),
    };

    for si in (0..n_sections).rev() {
        let p1_idx = idx_worst(&p, 0..p.len()).ok_or_else(|| internal("poles"))?;
        let p1 = take(&mut p, p1_idx);
        let n_real_p = p.iter().filter(|v| is_real(v)).count();
        let n_real_z = z.iter().filter(|v| is_real(v)).count();
        if is_real(&p1) && n_real_p == 0 {
            // Special case (1): last remaining real pole.
            let z1_idx = nearest_idx(&z, p1, Which::Real).ok_or_else(|| internal("real zeros"))?;
            let z1 = take(&mut z, z1_idx);
            sos[si] = single_section(&[z1, zero], &[p1, zero]);
        } else if p.len() + 1 == z.len() && !is_real(&p1) && n_real_p == 1 && n_real_z == 1 {
            // Special case (2): must pair with a complex zero.
            let z1_idx =
                nearest_idx(&z, p1, Which::Complex).ok_or_else(|| internal("complex zeros"))?;
            let z1 = take(&mut z, z1_idx);
            sos[si] = single_section(&[z1, z1.conj()], &[p1, p1.conj()]);
        } else {
            let p2 = if is_real(&p1) {
                let idx = idx_worst(&p, (0..p.len()).filter(|&i| is_real(&p[i])))
                    .ok_or_else(|| internal("real poles"))?;
                take(&mut p, idx)
            } else {
                p1.conj()
            };
            if z.is_empty() {
                sos[si] = single_section(&[], &[p1, p2]);
            } else {
                let z1_idx = nearest_idx(&z, p1, Which::Any).ok_or_else(|| internal("zeros"))?;
                let z1 = take(&mut z, z1_idx);
                if !is_real(&z1) {
                    sos[si] = single_section(&[z1, z1.conj()], &[p1, p2]);
                } else if !z.is_empty() {
                    let z2_idx =
                        nearest_idx(&z, p1, Which::Real).ok_or_else(|| internal("real zeros"))?;
                    let z2 = take(&mut z, z2_idx);
                    sos[si] = single_section(&[z1, z2], &[p1, p2]);
                } else {
                    sos[si] = single_section(&[z1], &[p1, p2]);
                }
            }
        }
    }
    for c in &mut sos[0][..3] {
        *c *= k;
    }
    Sos::new(sos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_settings_are_errors() {
        let lp = FilterBand::LowPass { cutoff_hz: 20.0 };
        assert!(butter(0, lp, 1000.0).is_err());
        assert!(butter(5, lp, 0.0).is_err());
        assert!(butter(5, lp, f64::NAN).is_err());
        assert!(butter(5, FilterBand::LowPass { cutoff_hz: 500.0 }, 1000.0).is_err());
        assert!(butter(5, FilterBand::LowPass { cutoff_hz: 0.0 }, 1000.0).is_err());
        assert!(butter(5, FilterBand::LowPass { cutoff_hz: -3.0 }, 1000.0).is_err());
        let bad_band = FilterBand::BandPass {
            low_hz: 50.0,
            high_hz: 40.0,
        };
        assert!(butter(3, bad_band, 1000.0).is_err());
        assert!(cheby1(4, 0.0, lp, 1000.0).is_err());
        assert!(cheby1(4, f64::INFINITY, lp, 1000.0).is_err());
    }

    #[test]
    fn odd_order_band_pass_has_expected_section_count() {
        let bp = FilterBand::BandPass {
            low_hz: 10.0,
            high_hz: 40.0,
        };
        assert_eq!(butter(3, bp, 1000.0).unwrap().n_sections(), 3);
        assert_eq!(
            butter(1, FilterBand::HighPass { cutoff_hz: 5.0 }, 100.0)
                .unwrap()
                .n_sections(),
            1
        );
    }
}
