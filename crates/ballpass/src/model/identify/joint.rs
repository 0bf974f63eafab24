//! The joint weighted least squares of the stage fit ([`super`]): seven
//! parameters, the bins' errors correlated as the Hann window makes them,
//! the covariance by the sandwich rule, once with the window's correlation
//! and once with the residuals' own (Bartlett kernel, Newey–West).

use super::{HANN_ERROR_CORRELATION, N_PARAMS};

/// The joint weighted least squares of the stage fit: parameters, weighted
/// residual sum and the parameters' covariance, by the sandwich over the
/// bins correlated as the window makes them (`cov`) and over the bins
/// correlated as the residuals are (`cov_hac`).
pub(super) struct JointFit {
    pub(super) theta: [f64; N_PARAMS],
    pub(super) chi2: f64,
    pub(super) cov: [[f64; N_PARAMS]; N_PARAMS],
    pub(super) cov_hac: [[f64; N_PARAMS]; N_PARAMS],
}

/// One row of the fit: regressors, value, variance, the key whose
/// neighbours (±1, ±2) are the window-correlated rows, and the frequency
/// bin (the real and imaginary rows of a bin share it).
pub(super) type Row = ([f64; N_PARAMS], f64, f64, usize, usize);

/// Solves the weighted least squares over `rows` (ordered by bin); rows
/// whose keys differ by 1 or 2 are bins whose errors correlate through the
/// window ([`HANN_ERROR_CORRELATION`]), and the covariance is
/// `(Xᵀ W X)⁻¹ Xᵀ W Σ W X (Xᵀ W X)⁻¹` with that `Σ`. `cov_hac` replaces
/// `Σ` by the residuals' own correlation across bins ([`hac_meat`]).
/// `None` when the regressors do not separate the parameters.
pub(super) fn joint_fit(rows: &[Row]) -> Option<JointFit> {
    const P: usize = N_PARAMS;
    // Scale every column to unit weighted norm (they differ by many orders
    // of magnitude: 1 and ω², ω and 1/ω).
    let mut sc = [0.0; P];
    for (x, _, v, _, _) in rows {
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
    for (x, y, v, _, _) in rows {
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
        .map(|(x, _, v, _, _)| xs(x).map(|e| e / v))
        .collect();
    let mut resid = Vec::with_capacity(rows.len());
    for (r, (x, y, v, _, _)) in rows.iter().enumerate() {
        let x = xs(x);
        let e = y - (0..P).map(|j| x[j] * th[j]).sum::<f64>();
        resid.push(e);
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
    let sandwich = |m: &[[f64; P]; P]| {
        let mut cov = [[0.0; P]; P];
        for i in 0..P {
            for j in 0..P {
                let s: f64 = (0..P)
                    .map(|k| ai[i][k] * (0..P).map(|l| m[k][l] * ai[l][j]).sum::<f64>())
                    .sum();
                cov[i][j] = s / (sc[i] * sc[j]);
            }
        }
        cov
    };
    Some(JointFit {
        theta: std::array::from_fn(|i| th[i] / sc[i]),
        chi2,
        cov: sandwich(&m),
        cov_hac: sandwich(&hac_meat(rows, &bw, &resid)),
    })
}

/// The meat of the sandwich from the residuals themselves, correlated
/// across bins as they are (heteroskedasticity and autocorrelation
/// consistent, Newey & West 1987): each bin's score `Σ xᵢ eᵢ / vᵢ` (its real
/// and imaginary rows), their products up to `L` bins apart weighted by
/// the Bartlett kernel `1 − l/(L+1)`. `L` is chosen from the data by
/// Andrews' (1991) AR(1) rule, `L = ⌈1.1447 (α n)^{1/3}⌉` with
/// `α = 4ρ² / ((1−ρ)² (1+ρ)²)`, `ρ` the lag-one correlation of the
/// standardised residuals across neighbouring bins (at least 2: the
/// window alone correlates neighbours). A misfit that is smooth across
/// frequency raises `ρ` and the products, and so the variance, where the
/// χ² scaling would treat it as independent noise.
fn hac_meat(rows: &[Row], bw: &[[f64; N_PARAMS]], resid: &[f64]) -> [[f64; N_PARAMS]; N_PARAMS] {
    const P: usize = N_PARAMS;
    // Per-bin scores (rows come ordered by bin).
    let mut scores: Vec<(usize, [f64; P])> = Vec::new();
    for (r, row) in rows.iter().enumerate() {
        let g = bw[r].map(|b| b * resid[r]);
        match scores.last_mut() {
            Some((bin, acc)) if *bin == row.4 => {
                for (a, gi) in acc.iter_mut().zip(g) {
                    *a += gi;
                }
            }
            _ => scores.push((row.4, g)),
        }
    }
    // Lag-one correlation of the standardised residuals: rows whose keys
    // differ by one (the same part of neighbouring bins).
    let (mut num, mut den) = (0.0, 0.0);
    for (r, row) in rows.iter().enumerate() {
        let u = resid[r] / row.2.sqrt();
        den += u * u;
        if let Some(r2) = (r + 1..(r + 4).min(rows.len())).find(|&r2| rows[r2].3 == row.3 + 1) {
            num += u * resid[r2] / rows[r2].2.sqrt();
        }
    }
    let rho = if den > 0.0 {
        (num / den).clamp(0.0, 0.97)
    } else {
        0.0
    };
    let alpha = 4.0 * rho * rho / ((1.0 - rho).powi(2) * (1.0 + rho).powi(2));
    let n = scores.len() as f64;
    let lags = ((1.1447 * (alpha * n).cbrt()).ceil() as usize).max(2);
    let mut m = [[0.0; P]; P];
    for (a, (bin_a, ga)) in scores.iter().enumerate() {
        add_outer(&mut m, ga, ga, 1.0);
        for (bin_b, gb) in &scores[a + 1..] {
            let lag = bin_b - bin_a;
            if lag > lags {
                break;
            }
            let k = 1.0 - lag as f64 / (lags + 1) as f64;
            add_outer(&mut m, ga, gb, k);
            add_outer(&mut m, gb, ga, k);
        }
    }
    m
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
