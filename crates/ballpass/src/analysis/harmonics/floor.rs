//! The floor a harmonic line is tested against and the null distribution
//! of the test's statistic (parent module docs): the degrees of freedom and
//! bin-correlation inflation of one spectrum, the tail of the largest of a
//! few `χ²_ν/ν` bins under a log-normal floor error, and the least-squares
//! polynomial in `ln f` the floor is fitted with.

use super::super::spectra::Spectra;
use super::super::AnalyzeSettings;
use crate::stats::{gamma_p_many, gamma_p_with};

/// What the harmonic test needs of one spectrum: its degrees of freedom
/// and the variance inflation of neighbouring bins' correlation.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TestContext {
    pub(super) nu: f64,
    pub(super) inflation: f64,
    pub(super) alpha: f64,
    /// `ln Γ(ν/2)`, for the χ² CDFs.
    ln_gamma_half_nu: f64,
    /// The threshold without the floor's uncertainty for 1, 2, 3 tested
    /// bins ([`TestContext::base`]).
    bases: [f64; 3],
}

impl TestContext {
    pub(crate) fn new(s: &Spectra, settings: &AnalyzeSettings) -> Option<TestContext> {
        let nu = s.info.dof;
        if nu.is_nan() || nu <= 0.0 {
            return None;
        }
        let w = settings.window.to_dsp().values(s.info.nperseg).ok()?;
        let n = w.len() as f64;
        let e: f64 = w.iter().map(|v| v * v).sum();
        let rho = |j: f64| {
            let (mut re, mut im) = (0.0, 0.0);
            for (i, v) in w.iter().enumerate() {
                let a = std::f64::consts::TAU * j * i as f64 / n;
                re += v * v * a.cos();
                im -= v * v * a.sin();
            }
            (re * re + im * im) / (e * e)
        };
        let inflation = 1.0 + 2.0 * (rho(1.0) + rho(2.0) + rho(3.0));
        let alpha = 1.0 - settings.confidence;
        Some(TestContext {
            nu,
            inflation,
            alpha,
            ln_gamma_half_nu: crate::stats::ln_gamma(0.5 * nu),
            bases: [1, 2, 3].map(|n_b| Self::base_of(alpha, nu, n_b)),
        })
    }

    /// The threshold of the largest of `n_b` bins' `χ²_ν/ν` without the
    /// floor's uncertainty.
    fn base_of(alpha: f64, nu: f64, n_b: usize) -> f64 {
        crate::stats::chi2_ppf((1.0 - alpha).powf(1.0 / n_b as f64), nu) / nu
    }

    /// [`TestContext::base_of`] for this spectrum (made once per context for
    /// the 1 to 3 bins a test takes).
    fn base(&self, n_b: usize) -> f64 {
        match n_b {
            1..=3 => self.bases[n_b - 1],
            _ => Self::base_of(self.alpha, self.nu, n_b),
        }
    }

    /// `P(max of n_b bins' χ²_ν/ν · e^{−ε} > t)`, `ε ~ N(0, var)`, the
    /// expectation over `ε` by 24-point Gauss–Hermite quadrature.
    pub(super) fn tail(&self, t: f64, n_b: usize, var: f64) -> f64 {
        // chi2_cdf(ν x, ν)^n_b, ln Γ(ν/2) made once.
        let (a, lg) = (0.5 * self.nu, self.ln_gamma_half_nu);
        let sd = var.max(0.0).sqrt();
        if sd < 1e-9 {
            return 1.0 - gamma_p_with(a, lg, 0.5 * (self.nu * t)).powi(n_b as i32);
        }
        // The 24 nodes' CDFs side by side (the same bits as one by one).
        let xs: [f64; 24] = std::array::from_fn(|i| 0.5 * (self.nu * (t * (sd * GH_X[i]).exp())));
        let cdf = gamma_p_many(a, lg, &xs);
        let e: f64 = cdf
            .iter()
            .zip(GH_W)
            .map(|(p, w)| w * p.powi(n_b as i32))
            .sum();
        (1.0 - e).clamp(0.0, 1.0)
    }

    /// The `t` with `tail(t) = alpha`: bisection in `ln t` between the
    /// thresholds without the floor's uncertainty and with ±6 of its σ, to
    /// 0.1 % (the threshold is reported, not tested against).
    pub(super) fn threshold(&self, n_b: usize, var: f64) -> f64 {
        let base = self.base(n_b);
        let sd = var.max(0.0).sqrt();
        let (mut lo, mut hi) = (base.ln() - 0.1, base.ln() + 6.0 * sd + 0.1);
        while hi - lo > 1e-3 {
            let mid = 0.5 * (lo + hi);
            if self.tail(mid.exp(), n_b, var) > self.alpha {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (0.5 * (lo + hi)).exp()
    }
}

/// Nodes and weights of 24-point Gauss–Hermite quadrature for the standard
/// normal density (`numpy.polynomial.hermite_e.hermegauss(24)`, weights
/// divided by `√(2π)`; they sum to 1).
const GH_X: [f64; 24] = [
    -8.507803519195257,
    -7.437890666021663,
    -6.541675005098634,
    -5.732747175251201,
    -4.97804137463912,
    -4.260383605019905,
    -3.56930676407356,
    -2.8977286432233136,
    -2.2404678516917524,
    -1.5934804298164202,
    -0.953421922932109,
    -0.31737009662945237,
    0.31737009662945237,
    0.953421922932109,
    1.5934804298164202,
    2.2404678516917524,
    2.8977286432233136,
    3.56930676407356,
    4.260383605019905,
    4.97804137463912,
    5.732747175251201,
    6.541675005098634,
    7.437890666021663,
    8.507803519195257,
];
const GH_W: [f64; 24] = [
    9.39019368904204e-17,
    3.7149741527624003e-13,
    1.7186649279648716e-10,
    2.26746167348065e-08,
    1.2176597454425883e-06,
    3.2095005652746016e-05,
    0.00046471871877939644,
    0.003976608929181307,
    0.021126344408967556,
    0.07206936401717823,
    0.1614595128670001,
    0.2408701155466404,
    0.2408701155466404,
    0.1614595128670001,
    0.07206936401717823,
    0.021126344408967556,
    0.003976608929181307,
    0.00046471871877939644,
    3.2095005652746016e-05,
    1.2176597454425883e-06,
    2.26746167348065e-08,
    1.7186649279648716e-10,
    3.7149741527624003e-13,
    9.39019368904204e-17,
];

/// A least-squares polynomial in `u = (x − centre) / scale`.
pub(super) struct PolyFit {
    pub(super) centre: f64,
    pub(super) scale: f64,
    pub(super) coef: Vec<f64>,
    /// `(UᵀU)⁻¹` of the design.
    pub(super) inv: [[f64; 3]; 3],
}

/// Least-squares polynomial (degree 1 or 2) of `y` on `x`, by the normal
/// equations on centred and scaled `x` (a few dozen points; well
/// conditioned once centred and scaled).
pub(super) fn poly_fit(x: &[f64], y: &[f64], degree: usize) -> Option<PolyFit> {
    let m = x.len() as f64;
    let xc = x.iter().sum::<f64>() / m;
    let sc = x
        .iter()
        .map(|v| (v - xc).abs())
        .fold(0.0, f64::max)
        .max(1e-12);
    let p = degree + 1;
    let mut ata = [[0.0; 3]; 3];
    let mut aty = [0.0; 3];
    for (xi, yi) in x.iter().zip(y) {
        let u = (xi - xc) / sc;
        let row = [1.0, u, u * u];
        for a in 0..p {
            aty[a] += row[a] * yi;
            for b in 0..p {
                ata[a][b] += row[a] * row[b];
            }
        }
    }
    let inv = invert(&ata, p)?;
    let coef: Vec<f64> = (0..p)
        .map(|a| (0..p).map(|b| inv[a][b] * aty[b]).sum())
        .collect();
    Some(PolyFit {
        centre: xc,
        scale: sc,
        coef,
        inv,
    })
}

/// Inverse of the leading `p x p` block (Gauss–Jordan with pivoting).
fn invert(a: &[[f64; 3]; 3], p: usize) -> Option<[[f64; 3]; 3]> {
    let mut m = *a;
    let mut inv = [[0.0; 3]; 3];
    for (i, row) in inv.iter_mut().enumerate().take(p) {
        row[i] = 1.0;
    }
    for c in 0..p {
        let piv = (c..p).max_by(|&i, &j| m[i][c].abs().total_cmp(&m[j][c].abs()))?;
        if m[piv][c].abs() < 1e-12 {
            return None;
        }
        m.swap(c, piv);
        inv.swap(c, piv);
        let d = m[c][c];
        for k in 0..p {
            m[c][k] /= d;
            inv[c][k] /= d;
        }
        for r in 0..p {
            if r != c {
                let f = m[r][c];
                for k in 0..p {
                    m[r][k] -= f * m[c][k];
                    inv[r][k] -= f * inv[c][k];
                }
            }
        }
    }
    Some(inv)
}
