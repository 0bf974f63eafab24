//! Nonlinear least squares by Levenberg–Marquardt, dependency-free.
//!
//! Minimises `cost(p) = 0.5 * sum_i r_i(p)^2` over the parameters `p`. Each
//! iteration solves the damped normal equations by Cholesky:
//!
//! ```text
//! (JᵀJ + λ·diag(JᵀJ)) h = -Jᵀr          (Marquardt's scaling)
//! ρ = (cost(p) - cost(p + h)) / (0.5 · hᵀ(λ·diag(JᵀJ)·h - Jᵀr))
//! ρ > 0: accept, λ ← λ·max(1/3, 1 - (2ρ - 1)³)      else: λ ← λ·ν, ν ← 2ν
//! ```
//!
//! (Nielsen's damping update.) Stopping tests as MINPACK's `lmder`:
//! `ftol` on the relative reduction of the cost (actual and predicted),
//! `xtol` on the relative size of the step, `gtol` on the largest cosine
//! between the residual vector and a Jacobian column.
//!
//! The Jacobian is the problem's own ([`Problem::jacobian`]) or forward
//! differences (`h_j = sqrt(eps) · max(1, |p_j|)`, as SciPy's `'2-point'`).
//! `JᵀJ` is accumulated row by row over the non-zero entries of each row, so
//! a model in which each residual depends on few parameters (a pulse train:
//! a sample sees its neighbouring pulses only) costs `O(m · nnz²)`, not
//! `O(m · n²)`.
//!
//! SciPy's `least_squares(method='lm')` (MINPACK) takes a different path
//! (trust region in scaled variables); both stop at the same minimum to
//! within their tolerances.
//!
//! ```
//! use ballpass_dsp::{least_squares, FnProblem, LeastSquares};
//! // y = a·exp(-k·t) sampled without noise: recovers a = 2, k = 0.5.
//! let t: Vec<f64> = (0..20).map(|i| i as f64 * 0.5).collect();
//! let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.5 * t).exp()).collect();
//! let problem = FnProblem::new(t.len(), |p: &[f64], r: &mut [f64]| {
//!     for i in 0..t.len() {
//!         r[i] = p[0] * (-p[1] * t[i]).exp() - y[i];
//!     }
//! });
//! let fit = least_squares(&problem, &[1.0, 1.0], &LeastSquares::default())?;
//! assert!((fit.params[0] - 2.0).abs() < 1e-9 && (fit.params[1] - 0.5).abs() < 1e-9);
//! # Ok::<(), ballpass_dsp::DspError>(())
//! ```

use crate::error::{invalid, DspError, Result};

/// A least-squares problem: `m` residuals of `n` parameters.
pub trait Problem {
    /// Number of residuals `m` (>= number of parameters).
    fn num_residuals(&self) -> usize;

    /// Writes `r(params)` into `residuals` (length `m`).
    fn residuals(&self, params: &[f64], residuals: &mut [f64]);

    /// Writes the Jacobian `∂r_i/∂p_j` at `params` into `jacobian`, row-major
    /// `m × n` (element `i * n + j`), which is all zeros on entry: a sparse
    /// model writes its non-zero entries only. Returns `false` (the default)
    /// to have the solver use forward differences instead.
    fn jacobian(&self, params: &[f64], jacobian: &mut [f64]) -> bool {
        let _ = (params, jacobian);
        false
    }
}

/// A [`Problem`] made of closures: residuals, and optionally a Jacobian.
pub struct FnProblem<R, J = fn(&[f64], &mut [f64])> {
    m: usize,
    residuals: R,
    jacobian: Option<J>,
}

impl<R: Fn(&[f64], &mut [f64])> FnProblem<R> {
    /// `m` residuals computed by `residuals(params, out)`; forward-difference
    /// Jacobian.
    pub fn new(m: usize, residuals: R) -> Self {
        FnProblem {
            m,
            residuals,
            jacobian: None,
        }
    }
}

impl<R: Fn(&[f64], &mut [f64]), J: Fn(&[f64], &mut [f64])> FnProblem<R, J> {
    /// `m` residuals and their Jacobian `jacobian(params, out)` (row-major
    /// `m × n`, zeroed on entry, see [`Problem::jacobian`]).
    pub fn with_jacobian(m: usize, residuals: R, jacobian: J) -> Self {
        FnProblem {
            m,
            residuals,
            jacobian: Some(jacobian),
        }
    }
}

impl<R: Fn(&[f64], &mut [f64]), J: Fn(&[f64], &mut [f64])> Problem for FnProblem<R, J> {
    fn num_residuals(&self) -> usize {
        self.m
    }
    fn residuals(&self, params: &[f64], residuals: &mut [f64]) {
        (self.residuals)(params, residuals)
    }
    fn jacobian(&self, params: &[f64], jacobian: &mut [f64]) -> bool {
        match &self.jacobian {
            Some(j) => {
                j(params, jacobian);
                true
            }
            None => false,
        }
    }
}

/// Settings of [`least_squares`]; defaults as SciPy's `least_squares`
/// (`ftol = xtol = gtol = 1e-8`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeastSquares {
    /// Maximum number of accepted-or-rejected iterations (Jacobian
    /// evaluations). Default 200.
    pub max_iterations: usize,
    /// Stop when both the actual and the predicted relative reduction of the
    /// cost are <= `ftol`.
    pub ftol: f64,
    /// Stop when `|h| <= xtol · (|p| + xtol)` (Euclidean norms).
    pub xtol: f64,
    /// Stop when `max_j |J_jᵀ r| / (|J_j| |r|) <= gtol`.
    pub gtol: f64,
    /// Initial damping `λ₀` relative to the Marquardt scaling (> 0).
    /// Default 1e-3.
    pub initial_damping: f64,
}

impl Default for LeastSquares {
    fn default() -> Self {
        LeastSquares {
            max_iterations: 200,
            ftol: 1e-8,
            xtol: 1e-8,
            gtol: 1e-8,
            initial_damping: 1e-3,
        }
    }
}

/// Why [`least_squares`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Termination {
    /// The relative reduction of the cost fell below `ftol`.
    Ftol,
    /// The relative step fell below `xtol`.
    Xtol,
    /// The gradient is orthogonal to the residuals within `gtol` (includes
    /// a zero residual).
    Gtol,
    /// `max_iterations` reached.
    MaxIterations,
    /// No step reduced the cost even with very strong damping: the current
    /// point is a minimum to machine precision.
    NoProgress,
}

/// Result of [`least_squares`].
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// Parameters at the minimum.
    pub params: Vec<f64>,
    /// `0.5 · sum r²` there.
    pub cost: f64,
    /// `sqrt(sum r² / m)`.
    pub residual_rms: f64,
    /// Iterations done (Jacobian evaluations).
    pub iterations: usize,
    /// Why it stopped.
    pub termination: Termination,
    /// `s² (JᵀJ)⁻¹`, row-major `n × n`, with `s² = sum r² / (m - n)` (SciPy
    /// `curve_fit`'s scaling); `None` if `m == n` or `JᵀJ` is singular.
    pub covariance: Option<Vec<f64>>,
    /// Square roots of the covariance diagonal; `None` with it.
    pub std_errors: Option<Vec<f64>>,
}

/// Minimises `0.5 · sum r(p)²` from `initial`, by Levenberg–Marquardt.
///
/// # Errors
/// [`DspError::Empty`] for no parameters; [`DspError::TooShort`] for fewer
/// residuals than parameters; [`DspError::NonFinite`] for a non-finite
/// initial parameter, or residuals (or Jacobian) not finite at the initial
/// point; [`DspError::InvalidSetting`] for a tolerance that is negative or
/// NaN, all three tolerances zero, or `initial_damping <= 0`.
/// Non-finite residuals at a trial point only reject that step.
pub fn least_squares<P: Problem + ?Sized>(
    problem: &P,
    initial: &[f64],
    settings: &LeastSquares,
) -> Result<Fit> {
    let n = initial.len();
    let m = problem.num_residuals();
    if n == 0 {
        return Err(DspError::Empty { what: "params" });
    }
    if m < n {
        return Err(DspError::TooShort {
            what: "residuals (one per parameter at least)",
            needed: n,
            found: m,
        });
    }
    if let Some((index, &value)) = initial.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DspError::NonFinite {
            what: "initial params",
            index,
            value,
        });
    }
    for (name, tol) in [
        ("ftol", settings.ftol),
        ("xtol", settings.xtol),
        ("gtol", settings.gtol),
    ] {
        if tol.is_nan() || tol < 0.0 {
            return Err(invalid(name, format!("must be >= 0, was {tol}")));
        }
    }
    if settings.ftol == 0.0 && settings.xtol == 0.0 && settings.gtol == 0.0 {
        return Err(invalid("ftol", "ftol, xtol and gtol are all 0"));
    }
    if !(settings.initial_damping > 0.0 && settings.initial_damping.is_finite()) {
        return Err(invalid(
            "initial_damping",
            format!("must be finite and > 0, was {}", settings.initial_damping),
        ));
    }

    let mut ws = Workspace::new(m, n);
    let mut p = initial.to_vec();
    let mut r = vec![0.0; m];
    problem.residuals(&p, &mut r);
    check_all_finite("residuals at the initial params", &r)?;
    let mut cost = half_sum_sq(&r);

    let mut lambda = settings.initial_damping;
    let mut nu = 2.0;
    let mut iterations = 0;
    let mut p_new = vec![0.0; n];
    let mut r_new = vec![0.0; m];
    let mut h = vec![0.0; n];

    let termination = 'outer: loop {
        if iterations >= settings.max_iterations {
            break Termination::MaxIterations;
        }
        iterations += 1;
        ws.jacobian(problem, &p, &r, &mut r_new)?;
        ws.normal_equations(&r)?;

        // gtol: cosine between r and each Jacobian column.
        let rnorm = (2.0 * cost).sqrt();
        if rnorm == 0.0 {
            break Termination::Gtol;
        }
        let gmax = (0..n)
            .filter(|&j| ws.a[j * n + j] > 0.0)
            .map(|j| (ws.g[j] / (ws.a[j * n + j].sqrt() * rnorm)).abs())
            .fold(0.0, f64::max);
        if gmax <= settings.gtol {
            break Termination::Gtol;
        }

        // Inner loop: raise the damping until a step lowers the cost.
        loop {
            if !ws.solve_damped(lambda, &mut h) {
                lambda *= nu;
                nu *= 2.0;
                if !lambda.is_finite() || lambda > 1e300 {
                    break 'outer Termination::NoProgress;
                }
                continue;
            }
            for j in 0..n {
                p_new[j] = p[j] + h[j];
            }
            let pnorm = norm(&p);
            let hnorm = norm(&h);
            // Predicted reduction 0.5·hᵀ(λ·D·h - g) with g = Jᵀr.
            let predicted: f64 = 0.5
                * (0..n)
                    .map(|j| h[j] * (lambda * ws.d[j] * h[j] - ws.g[j]))
                    .sum::<f64>();
            problem.residuals(&p_new, &mut r_new);
            let new_cost = if r_new.iter().all(|v| v.is_finite()) {
                half_sum_sq(&r_new)
            } else {
                f64::INFINITY
            };
            let actual = cost - new_cost;
            if actual > 0.0 && predicted > 0.0 {
                let rho = actual / predicted;
                std::mem::swap(&mut p, &mut p_new);
                std::mem::swap(&mut r, &mut r_new);
                let old_cost = cost;
                cost = new_cost;
                lambda *= f64::max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                if actual <= settings.ftol * old_cost && predicted <= settings.ftol * old_cost {
                    break 'outer Termination::Ftol;
                }
                if hnorm <= settings.xtol * (pnorm + settings.xtol) {
                    break 'outer Termination::Xtol;
                }
                break;
            }
            // Rejected: a step this small that cannot lower the cost means
            // we sit at the minimum to rounding.
            if hnorm <= settings.xtol * (pnorm + settings.xtol) {
                break 'outer Termination::Xtol;
            }
            lambda *= nu;
            nu *= 2.0;
            if !lambda.is_finite() || lambda > 1e300 {
                break 'outer Termination::NoProgress;
            }
        }
    };

    // Covariance at the final parameters.
    ws.jacobian(problem, &p, &r, &mut r_new)?;
    ws.normal_equations(&r)?;
    let covariance = if m > n {
        let s2 = 2.0 * cost / (m - n) as f64;
        ws.inverse_normal()
            .map(|inv| inv.into_iter().map(|v| v * s2).collect::<Vec<f64>>())
    } else {
        None
    };
    let std_errors = covariance
        .as_ref()
        .map(|c| (0..n).map(|j| c[j * n + j].max(0.0).sqrt()).collect());
    Ok(Fit {
        params: p,
        cost,
        residual_rms: (2.0 * cost / m as f64).sqrt(),
        iterations,
        termination,
        covariance,
        std_errors,
    })
}

fn half_sum_sq(r: &[f64]) -> f64 {
    0.5 * r.iter().map(|v| v * v).sum::<f64>()
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn check_all_finite(what: &'static str, v: &[f64]) -> Result<()> {
    match crate::error::first_non_finite(v) {
        Some(index) => Err(DspError::NonFinite {
            what,
            index,
            value: v[index],
        }),
        None => Ok(()),
    }
}

/// Buffers reused across iterations.
struct Workspace {
    m: usize,
    n: usize,
    /// Jacobian, row-major m × n.
    jac: Vec<f64>,
    /// JᵀJ, row-major n × n.
    a: Vec<f64>,
    /// Jᵀr.
    g: Vec<f64>,
    /// Marquardt scaling: diag(JᵀJ), floored.
    d: Vec<f64>,
    /// Cholesky factor (lower, row-major n × n).
    l: Vec<f64>,
    nz: Vec<usize>,
}

impl Workspace {
    fn new(m: usize, n: usize) -> Self {
        Workspace {
            m,
            n,
            jac: vec![0.0; m * n],
            a: vec![0.0; n * n],
            g: vec![0.0; n],
            d: vec![0.0; n],
            l: vec![0.0; n * n],
            nz: Vec::with_capacity(n),
        }
    }

    /// Fills `jac` at `p` (analytic or forward differences); `scratch` is an
    /// m-vector.
    fn jacobian<P: Problem + ?Sized>(
        &mut self,
        problem: &P,
        p: &[f64],
        r: &[f64],
        scratch: &mut [f64],
    ) -> Result<()> {
        let (m, n) = (self.m, self.n);
        self.jac.fill(0.0);
        if !problem.jacobian(p, &mut self.jac) {
            let mut q = p.to_vec();
            for j in 0..n {
                let step = f64::EPSILON.sqrt() * p[j].abs().max(1.0);
                q[j] = p[j] + step;
                let step = q[j] - p[j]; // exactly representable step
                problem.residuals(&q, scratch);
                for i in 0..m {
                    self.jac[i * n + j] = (scratch[i] - r[i]) / step;
                }
                q[j] = p[j];
            }
        }
        // Checked for NaN and infinity row by row in `normal_equations`,
        // which reads the whole matrix anyway.
        Ok(())
    }

    /// `a = JᵀJ`, `g = Jᵀr`, skipping zero entries of each row.
    ///
    /// # Errors
    /// [`DspError::NonFinite`] (`"jacobian"`, row-major index) for the
    /// first NaN or infinity in the Jacobian.
    fn normal_equations(&mut self, r: &[f64]) -> Result<()> {
        const EXP: u64 = 0x7ff0_0000_0000_0000;
        let n = self.n;
        self.a.fill(0.0);
        self.g.fill(0.0);
        for (i, (row, &ri)) in self.jac.chunks_exact(n).zip(r).enumerate() {
            // Non-zero columns, 64 at a time into a bit mask (branch-free,
            // vectorises), then one step per set bit.
            self.nz.clear();
            for (base, block) in row.chunks(64).enumerate() {
                let (mut bits, bad) =
                    block
                        .iter()
                        .enumerate()
                        .fold((0u64, 0u64), |(m, b), (j, &v)| {
                            (
                                m | (u64::from(v != 0.0) << j),
                                b | (u64::from(v.to_bits() & EXP == EXP) << j),
                            )
                        });
                if bad != 0 {
                    let index = i * n + 64 * base + bad.trailing_zeros() as usize;
                    return Err(DspError::NonFinite {
                        what: "jacobian",
                        index,
                        value: self.jac[index],
                    });
                }
                while bits != 0 {
                    self.nz.push(64 * base + bits.trailing_zeros() as usize);
                    bits &= bits - 1;
                }
            }
            for (k, &a) in self.nz.iter().enumerate() {
                let ja = row[a];
                self.g[a] += ja * ri;
                let arow = &mut self.a[a * n..(a + 1) * n];
                for &b in &self.nz[k..] {
                    arow[b] += ja * row[b];
                }
            }
        }
        for a in 0..n {
            for b in 0..a {
                self.a[a * n + b] = self.a[b * n + a];
            }
        }
        let dmax = (0..n).map(|j| self.a[j * n + j]).fold(0.0, f64::max);
        for j in 0..n {
            // Floor keeps a parameter with a zero column from making the
            // damped system singular.
            self.d[j] = self.a[j * n + j].max(1e-12 * dmax).max(f64::MIN_POSITIVE);
        }
        Ok(())
    }

    /// Cholesky of `a + lambda·diag(d)` (or of `a` for lambda = 0) into `l`.
    fn factor(&mut self, lambda: f64) -> bool {
        let n = self.n;
        for i in 0..n {
            for j in 0..=i {
                let mut s = self.a[i * n + j];
                if i == j {
                    s += lambda * self.d[i];
                }
                for k in 0..j {
                    s -= self.l[i * n + k] * self.l[j * n + k];
                }
                if i == j {
                    if s.is_nan() || s <= 0.0 || !s.is_finite() {
                        return false;
                    }
                    self.l[i * n + i] = s.sqrt();
                } else {
                    self.l[i * n + j] = s / self.l[j * n + j];
                }
            }
        }
        true
    }

    /// Solves `l lᵀ x = b` in place.
    fn cho_solve(&self, x: &mut [f64]) {
        let n = self.n;
        for i in 0..n {
            let row = &self.l[i * n..i * n + i];
            let s = x[i] - row.iter().zip(&x[..i]).map(|(l, v)| l * v).sum::<f64>();
            x[i] = s / self.l[i * n + i];
        }
        for i in (0..n).rev() {
            let s = x[i]
                - (i + 1..n)
                    .zip(&x[i + 1..])
                    .map(|(k, v)| self.l[k * n + i] * v)
                    .sum::<f64>();
            x[i] = s / self.l[i * n + i];
        }
    }

    /// `h = -(a + lambda·D)⁻¹ g`; false if not positive definite.
    fn solve_damped(&mut self, lambda: f64, h: &mut [f64]) -> bool {
        if !self.factor(lambda) {
            return false;
        }
        for (hj, gj) in h.iter_mut().zip(&self.g) {
            *hj = -gj;
        }
        self.cho_solve(h);
        h.iter().all(|v| v.is_finite())
    }

    /// `(JᵀJ)⁻¹`, or `None` if singular to working precision.
    fn inverse_normal(&mut self) -> Option<Vec<f64>> {
        let n = self.n;
        if !self.factor(0.0) {
            return None;
        }
        // Reject a numerically singular factor (pivot ratio beyond 1/eps).
        let piv: Vec<f64> = (0..n).map(|i| self.l[i * n + i]).collect();
        let (pmin, pmax) = piv
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        if pmin * pmin <= f64::EPSILON * pmax * pmax {
            return None;
        }
        let mut inv = vec![0.0; n * n];
        let mut e = vec![0.0; n];
        for c in 0..n {
            e.fill(0.0);
            e[c] = 1.0;
            self.cho_solve(&mut e);
            for rr in 0..n {
                inv[rr * n + c] = e[rr];
            }
        }
        Some(inv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_problem_is_solved_and_covariance_matches_closed_form() {
        // y = a + b t: LM must land on the normal-equation solution, and the
        // covariance equals s²·(XᵀX)⁻¹ computed by hand.
        let t = [0.0, 1.0, 2.0, 3.0, 4.0];
        let y = [1.1, 2.9, 5.2, 6.8, 9.1];
        let prob = FnProblem::with_jacobian(
            5,
            |p: &[f64], r: &mut [f64]| {
                for i in 0..5 {
                    r[i] = p[0] + p[1] * t[i] - y[i];
                }
            },
            |_: &[f64], j: &mut [f64]| {
                for i in 0..5 {
                    j[2 * i] = 1.0;
                    j[2 * i + 1] = t[i];
                }
            },
        );
        let tight = LeastSquares {
            ftol: 1e-15,
            xtol: 1e-15,
            gtol: 1e-15,
            ..LeastSquares::default()
        };
        let fit = least_squares(&prob, &[0.0, 0.0], &tight).unwrap();
        // closed form: slope = Sxy/Sxx, intercept = ybar - slope·tbar
        let (tb, yb) = (2.0, y.iter().sum::<f64>() / 5.0);
        let sxx: f64 = t.iter().map(|t| (t - tb) * (t - tb)).sum();
        let sxy: f64 = t.iter().zip(&y).map(|(t, y)| (t - tb) * (y - yb)).sum();
        let b = sxy / sxx;
        let a = yb - b * tb;
        // 1e-12: exact Jacobian, so the fixed point Jᵀr = 0 is the normal
        // equations' solution; what is left is rounding in r and the solve.
        assert!(
            (fit.params[0] - a).abs() < 1e-12 && (fit.params[1] - b).abs() < 1e-12,
            "{fit:?} a={a} b={b}"
        );
        let s2 = 2.0 * fit.cost / 3.0;
        let cov = fit.covariance.unwrap();
        // var(b) = s²/Sxx; relative 1e-12 (a 2 x 2 Cholesky inverse).
        assert!((cov[3] - s2 / sxx).abs() <= 1e-12 * s2 / sxx);
        let se = fit.std_errors.unwrap()[1];
        assert!((se - (s2 / sxx).sqrt()).abs() <= 1e-12 * se);
    }

    #[test]
    fn bad_input_is_an_error() {
        let prob = FnProblem::new(1, |p: &[f64], r: &mut [f64]| r[0] = p[0] + p[1]);
        let s = LeastSquares::default();
        assert!(matches!(
            least_squares(&prob, &[1.0, 2.0], &s),
            Err(DspError::TooShort { .. })
        ));
        assert!(matches!(
            least_squares(&prob, &[], &s),
            Err(DspError::Empty { .. })
        ));
        let one = FnProblem::new(2, |p: &[f64], r: &mut [f64]| {
            r[0] = p[0];
            r[1] = p[0].sqrt();
        });
        assert!(matches!(
            least_squares(&one, &[f64::NAN], &s),
            Err(DspError::NonFinite { .. })
        ));
        assert!(matches!(
            least_squares(&one, &[-1.0], &s),
            Err(DspError::NonFinite { .. })
        ));
        let bad = LeastSquares {
            initial_damping: 0.0,
            ..s
        };
        assert!(least_squares(&one, &[1.0], &bad).is_err());
    }
}
