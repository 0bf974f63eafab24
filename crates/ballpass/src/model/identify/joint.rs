//! The joint weighted least squares of the stage fit ([`super`]): five
//! parameters, the bins' errors correlated as the Hann window makes them,
//! the covariance by the sandwich rule.

use super::{HANN_ERROR_CORRELATION, N_PARAMS};

/// The joint weighted least squares of the stage fit: parameters, weighted
/// residual sum and the parameters' covariance (sandwich over the
/// correlated bins).
pub(super) struct JointFit {
    pub(super) theta: [f64; N_PARAMS],
    pub(super) chi2: f64,
    pub(super) cov: [[f64; N_PARAMS]; N_PARAMS],
}

/// Solves the weighted least squares over `rows` = (regressors, value,
/// variance, bin key); rows whose keys differ by 1 or 2 are bins whose
/// errors correlate through the window ([`HANN_ERROR_CORRELATION`]), and
/// the covariance is `(Xᵀ W X)⁻¹ Xᵀ W Σ W X (Xᵀ W X)⁻¹` with that `Σ`.
/// `None` when the regressors do not separate the parameters.
pub(super) fn joint_fit(rows: &[([f64; N_PARAMS], f64, f64, usize)]) -> Option<JointFit> {
    const P: usize = N_PARAMS;
    // Scale every column to unit weighted norm (they differ by many orders
    // of magnitude: 1 and ω², ω and 1/ω).
    let mut sc = [0.0; P];
    for (x, _, v, _) in rows {
        for j in 0..P {
            sc[j] += x[j] * x[j] / v;
        }
    }
    if sc.iter().any(|s| !(*s > 0.0 && s.is_finite())) {
        return None;
    }
    let sc = sc.map(f64::sqrt);
    let xs = |x: &[f64; P]| -> [f64; P] { std::array::from_fn(|j| x[j] / sc[j]) };
    let mut a = [[0.0; P]; P];
    let mut b = [0.0; P];
    for (x, y, v, _) in rows {
        let x = xs(x);
        for i in 0..P {
            b[i] += x[i] * y / v;
            for j in 0..P {
                a[i][j] += x[i] * x[j] / v;
            }
        }
    }
    let ai = invert(a)?;
    let th: [f64; P] = std::array::from_fn(|i| (0..P).map(|j| ai[i][j] * b[j]).sum());
    let mut chi2 = 0.0;
    let mut m = [[0.0; P]; P];
    let bw: Vec<[f64; P]> = rows
        .iter()
        .map(|(x, _, v, _)| xs(x).map(|e| e / v))
        .collect();
    for (r, (x, y, v, _)) in rows.iter().enumerate() {
        let x = xs(x);
        let e = y - (0..P).map(|j| x[j] * th[j]).sum::<f64>();
        chi2 += e * e / v;
        add_outer(&mut m, &bw[r], &bw[r], *v);
        for r2 in r + 1..(r + 6).min(rows.len()) {
            let lag = rows[r2].3.wrapping_sub(rows[r].3);
            if let Some(&(_, rho2)) = HANN_ERROR_CORRELATION.iter().find(|(l, _)| *l == lag) {
                let c = rho2 * (v * rows[r2].2).sqrt();
                add_outer(&mut m, &bw[r], &bw[r2], c);
                add_outer(&mut m, &bw[r2], &bw[r], c);
            }
        }
    }
    let mut cov = [[0.0; P]; P];
    for i in 0..P {
        for j in 0..P {
            let s: f64 = (0..P)
                .map(|k| ai[i][k] * (0..P).map(|l| m[k][l] * ai[l][j]).sum::<f64>())
                .sum();
            cov[i][j] = s / (sc[i] * sc[j]);
        }
    }
    Some(JointFit {
        theta: std::array::from_fn(|i| th[i] / sc[i]),
        chi2,
        cov,
    })
}

/// `m += c u vᵀ`.
fn add_outer(
    m: &mut [[f64; N_PARAMS]; N_PARAMS],
    u: &[f64; N_PARAMS],
    v: &[f64; N_PARAMS],
    c: f64,
) {
    for i in 0..N_PARAMS {
        for j in 0..N_PARAMS {
            m[i][j] += c * u[i] * v[j];
        }
    }
}

/// Inverse of a symmetric positive-definite matrix with unit-scaled
/// columns (Gauss–Jordan, partial pivoting); `None` when a pivot vanishes
/// (1e-12: the columns are then dependent to within rounding).
fn invert(mut a: [[f64; N_PARAMS]; N_PARAMS]) -> Option<[[f64; N_PARAMS]; N_PARAMS]> {
    const P: usize = N_PARAMS;
    let mut inv = [[0.0; P]; P];
    for (i, row) in inv.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for c in 0..P {
        let piv = (c..P).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[piv][c].abs().is_nan() || a[piv][c].abs() <= 1e-12 {
            return None;
        }
        a.swap(c, piv);
        inv.swap(c, piv);
        let d = a[c][c];
        for j in 0..P {
            a[c][j] /= d;
            inv[c][j] /= d;
        }
        for r in 0..P {
            if r != c {
                let f = a[r][c];
                if f != 0.0 {
                    for j in 0..P {
                        a[r][j] -= f * a[c][j];
                        inv[r][j] -= f * inv[c][j];
                    }
                }
            }
        }
    }
    Some(inv)
}
