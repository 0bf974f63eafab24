//! A small dense Levenberg–Marquardt solver for the pulse-train fits.
//!
//! Kept private to [`crate::analysis`]: the fits have at most a few dozen
//! parameters and a few thousand residuals, so a numerical Jacobian by
//! central differences and a dense normal-equation solve are ample.

/// Outcome of [`minimize`].
#[derive(Debug, Clone)]
pub(crate) struct LmResult {
    /// Parameters at the minimum found.
    pub theta: Vec<f64>,
    /// Iterations used.
    pub iterations: usize,
    /// Whether the relative cost or step fell below tolerance.
    pub converged: bool,
}

fn cost_of(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// Minimises `Σ r_i(θ)²` from `theta0`. `residuals(θ, r)` fills `r`
/// (length `m`); `scale[j]` is a typical size of θ_j, used for the
/// finite-difference step (`1e-6 · max(|θ_j|, scale_j)`).
pub(crate) fn minimize(
    residuals: impl Fn(&[f64], &mut [f64]),
    theta0: &[f64],
    scale: &[f64],
    m: usize,
    max_iter: usize,
) -> LmResult {
    let p = theta0.len();
    let mut theta = theta0.to_vec();
    let mut r = vec![0.0; m];
    residuals(&theta, &mut r);
    let mut cost = cost_of(&r);
    let mut lambda = 1e-3;
    let mut jac = vec![0.0; m * p]; // column-major: jac[j*m + i]
    let (mut rp, mut rm) = (vec![0.0; m], vec![0.0; m]);
    let mut converged = false;
    let mut it = 0;
    while it < max_iter {
        it += 1;
        for j in 0..p {
            let h = 1e-6 * theta[j].abs().max(scale[j]);
            let mut t = theta.clone();
            t[j] = theta[j] + h;
            residuals(&t, &mut rp);
            t[j] = theta[j] - h;
            residuals(&t, &mut rm);
            for i in 0..m {
                jac[j * m + i] = (rp[i] - rm[i]) / (2.0 * h);
            }
        }
        let mut jtj = vec![0.0; p * p];
        let mut jtr = vec![0.0; p];
        for a in 0..p {
            let ca = &jac[a * m..(a + 1) * m];
            jtr[a] = ca.iter().zip(&r).map(|(x, y)| x * y).sum();
            for b in a..p {
                let cb = &jac[b * m..(b + 1) * m];
                let v: f64 = ca.iter().zip(cb).map(|(x, y)| x * y).sum();
                jtj[a * p + b] = v;
                jtj[b * p + a] = v;
            }
        }
        let mut improved = false;
        for _ in 0..30 {
            let mut a = jtj.clone();
            for d in 0..p {
                a[d * p + d] += lambda * jtj[d * p + d].max(1e-300);
            }
            let Some(step) = solve(&mut a, &jtr.iter().map(|v| -v).collect::<Vec<_>>(), p) else {
                lambda *= 10.0;
                continue;
            };
            let cand: Vec<f64> = theta.iter().zip(&step).map(|(t, s)| t + s).collect();
            residuals(&cand, &mut rp);
            let c = cost_of(&rp);
            if c.is_finite() && c < cost {
                let rel = (cost - c) / cost.max(1e-300);
                let small_step = step
                    .iter()
                    .zip(&cand)
                    .zip(scale)
                    .all(|((s, t), sc)| s.abs() <= 1e-10 * t.abs().max(*sc));
                theta = cand;
                std::mem::swap(&mut r, &mut rp);
                cost = c;
                lambda = (lambda / 10.0).max(1e-12);
                improved = true;
                if rel < 1e-12 || small_step {
                    converged = true;
                }
                break;
            }
            lambda *= 10.0;
            if lambda > 1e12 {
                break;
            }
        }
        if !improved {
            // No step lowers the cost: a (local) minimum to working precision.
            converged = true;
            break;
        }
        if converged {
            break;
        }
    }
    LmResult {
        theta,
        iterations: it,
        converged,
    }
}

/// Solves `a x = b` (p×p, row-major) by Gaussian elimination with partial
/// pivoting; `None` when singular.
fn solve(a: &mut [f64], b: &[f64], p: usize) -> Option<Vec<f64>> {
    let mut b = b.to_vec();
    for col in 0..p {
        let piv =
            (col..p).max_by(|&i, &j| a[i * p + col].abs().total_cmp(&a[j * p + col].abs()))?;
        if a[piv * p + col].abs() < 1e-300 || !a[piv * p + col].is_finite() {
            return None;
        }
        if piv != col {
            for k in 0..p {
                a.swap(col * p + k, piv * p + k);
            }
            b.swap(col, piv);
        }
        for row in col + 1..p {
            let f = a[row * p + col] / a[col * p + col];
            if f != 0.0 {
                for k in col..p {
                    a[row * p + k] -= f * a[col * p + k];
                }
                b[row] -= f * b[col];
            }
        }
    }
    let mut x = vec![0.0; p];
    for row in (0..p).rev() {
        let s: f64 = (row + 1..p).map(|k| a[row * p + k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row * p + row];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_an_exponential_exactly() {
        // y = 2.5 exp(−0.7 t) + 0.3 sampled without noise: the minimum is exact.
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.5 * (-0.7 * t).exp() + 0.3).collect();
        let res = minimize(
            |th, r| {
                for i in 0..t.len() {
                    r[i] = th[0] * (-th[1] * t[i]).exp() + th[2] - y[i];
                }
            },
            &[1.0, 0.2, 0.0],
            &[1.0, 1.0, 1.0],
            t.len(),
            200,
        );
        assert!(res.converged);
        // Exact data: the solution is recovered to finite-difference accuracy.
        for (got, want) in res.theta.iter().zip([2.5, 0.7, 0.3]) {
            assert!((got - want).abs() < 1e-7, "{got} vs {want}");
        }
    }

    #[test]
    fn singular_systems_are_refused() {
        let mut a = vec![1.0, 2.0, 2.0, 4.0];
        assert!(solve(&mut a, &[1.0, 2.0], 2).is_none());
    }
}
