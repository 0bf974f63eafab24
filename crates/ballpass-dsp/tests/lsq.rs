//! `ballpass_dsp::lsq` against SciPy's `least_squares(method='lm')` fixtures
//! (`tools/scipy_fixtures/lsq.py`) and on noise-free problems.

mod common;

use ballpass_dsp::{least_squares, DspError, FnProblem, LeastSquares, Problem};
use common::{assert_close, f64s, fixture, fixture_names};

/// Tight stops for the comparisons: both solvers are then limited by
/// rounding near the minimum, not by their (different) stopping rules.
fn tight() -> LeastSquares {
    LeastSquares {
        ftol: 1e-15,
        xtol: 1e-15,
        gtol: 1e-15,
        max_iterations: 1000,
        ..LeastSquares::default()
    }
}

/// A curve model `y(t; p)` with its analytic Jacobian, as the fixtures.
#[derive(Clone, Copy)]
enum Model {
    ExpDecay,
    Gaussians,
}

impl Model {
    fn parse(name: &str) -> Self {
        match name {
            "exp_decay" => Model::ExpDecay,
            "gaussians" => Model::Gaussians,
            other => panic!("unknown model {other}"),
        }
    }

    /// `y` at `t`, and if `jac` is given, `∂y/∂p` into the row (len n).
    fn eval(self, p: &[f64], t: f64, jac: Option<&mut [f64]>) -> f64 {
        match self {
            Model::ExpDecay => {
                let e = (-p[1] * t).exp();
                if let Some(j) = jac {
                    j[0] = e;
                    j[1] = -p[0] * t * e;
                    j[2] = 1.0;
                }
                p[0] * e + p[2]
            }
            Model::Gaussians => {
                let mut y = p[0];
                let mut jac = jac;
                if let Some(j) = jac.as_deref_mut() {
                    j[0] = 1.0;
                }
                for (k, g3) in p[1..].chunks_exact(3).enumerate() {
                    let (a, c, s) = (g3[0], g3[1], g3[2]);
                    let u = (t - c) / s;
                    let g = (-0.5 * u * u).exp();
                    y += a * g;
                    // Far from a pulse g underflows to 0: those entries stay
                    // zero and the solver skips them (sparse rows).
                    if let (Some(j), true) = (jac.as_deref_mut(), g != 0.0) {
                        j[1 + 3 * k] = g;
                        j[2 + 3 * k] = a * g * u / s;
                        j[3 + 3 * k] = a * g * u * u / s;
                    }
                }
                y
            }
        }
    }
}

struct Curve {
    model: Model,
    t: Vec<f64>,
    y: Vec<f64>,
    analytic: bool,
}

impl Problem for Curve {
    fn num_residuals(&self) -> usize {
        self.t.len()
    }
    fn residuals(&self, p: &[f64], r: &mut [f64]) {
        for ((ri, &t), &y) in r.iter_mut().zip(&self.t).zip(&self.y) {
            *ri = self.model.eval(p, t, None) - y;
        }
    }
    fn jacobian(&self, p: &[f64], jac: &mut [f64]) -> bool {
        if !self.analytic {
            return false;
        }
        for (row, &t) in jac.chunks_exact_mut(p.len()).zip(&self.t) {
            self.model.eval(p, t, Some(row));
        }
        true
    }
}

#[test]
fn agrees_with_scipy_lm_on_noisy_fits() {
    let names = fixture_names("lsq");
    assert_eq!(names.len(), 5);
    for name in names {
        let fx = fixture("lsq", &name);
        let x0 = f64s(&fx["x0"]);
        for analytic in [true, false] {
            let problem = Curve {
                model: Model::parse(fx["model"].as_str().unwrap()),
                t: f64s(&fx["t"]),
                y: f64s(&fx["y"]),
                analytic,
            };
            let what = format!("{name} (analytic jacobian: {analytic})");
            let fit = least_squares(&problem, &x0, &tight()).unwrap();
            // Parameters: 1e-7 relative. Both solvers stop at the same
            // minimum only to within their tolerances and rounding: near the
            // minimum the cost is flat (a parameter error δ changes it by
            // ~δ²), so the last digits are set by the gradient test; with a
            // forward-difference Jacobian the fixed point Jᵀr = 0 also moves
            // by the ~1e-8 relative error of J times the small residuals.
            assert_close(
                &format!("{what} params"),
                &fit.params,
                &f64s(&fx["params"]),
                1e-7,
            );
            // Cost: second order in the parameter error, so 1e-12 relative.
            let cost = fx["cost"].as_f64().unwrap();
            assert!(
                (fit.cost - cost).abs() <= 1e-12 * cost,
                "{what}: cost {} vs {cost}",
                fit.cost
            );
            // Covariance: inv(JᵀJ)·s², compared entry by entry relative to
            // sqrt(C_ii·C_jj) (the scale of a correlation: entries near zero
            // are meaningless relative to themselves). A smooth function of
            // the parameters and of J: the analytic J gives ~1e-9, the
            // forward-difference J (error ~1e-8 relative, amplified by the
            // conditioning of JᵀJ) ~1e-6; tolerance 1e-5 for both.
            let cov = fit.covariance.expect("full rank");
            let want = f64s(&fx["covariance"]);
            let n = x0.len();
            let err = (0..n * n)
                .map(|k| {
                    let (i, j) = (k / n, k % n);
                    (cov[k] - want[k]).abs() / (want[i * n + i] * want[j * n + j]).sqrt()
                })
                .fold(0.0, f64::max);
            assert!(err <= 1e-5, "{what}: covariance error {err:e}");
            let se = fit.std_errors.expect("with the covariance");
            for j in 0..n {
                assert_eq!(se[j], cov[j * n + j].sqrt());
            }
        }
    }
}

#[test]
fn recovers_noise_free_parameters_exactly() {
    let t: Vec<f64> = (0..1500).map(|i| i as f64 / 1000.0).collect();
    // (model, truth, initial guess, sample times)
    type Case<'a> = (Model, Vec<f64>, Vec<f64>, &'a [f64]);
    let cases: [Case; 3] = [
        (
            Model::ExpDecay,
            vec![2.5, 0.7, 0.3],
            vec![1.0, 1.0, 0.0],
            &t[..200],
        ),
        (
            Model::Gaussians,
            vec![0.5, 3.0, 0.42, 0.08],
            vec![0.0, 2.0, 0.4, 0.1],
            &t[..1000],
        ),
        (
            Model::Gaussians,
            vec![
                0.1, 1.0, 0.30, 0.012, 0.8, 0.33, 0.015, 1.2, 0.60, 0.010, 0.9, 1.1, 0.02,
            ],
            vec![
                0.0, 0.8, 0.305, 0.010, 1.0, 0.325, 0.012, 1.0, 0.598, 0.012, 1.0, 1.09, 0.018,
            ],
            &t,
        ),
    ];
    for (model, truth, x0, t) in cases {
        let y: Vec<f64> = t.iter().map(|&t| model.eval(&truth, t, None)).collect();
        for analytic in [true, false] {
            let problem = Curve {
                model,
                t: t.to_vec(),
                y: y.clone(),
                analytic,
            };
            let fit = least_squares(&problem, &x0, &tight()).unwrap();
            // Zero residual at the truth: the solver must land on it to
            // rounding, 1e-9 relative (the data themselves carry ~1e-16
            // relative rounding, amplified by the conditioning).
            assert_close(
                &format!("{} params", truth.len()),
                &fit.params,
                &truth,
                1e-9,
            );
            assert!(fit.residual_rms < 1e-12, "rms {}", fit.residual_rms);
        }
    }
}

#[test]
fn bad_problems_are_errors() {
    let s = LeastSquares::default();
    let under = FnProblem::new(2, |p: &[f64], r: &mut [f64]| {
        r[0] = p[0] - p[1];
        r[1] = p[1] - p[2];
    });
    assert!(matches!(
        least_squares(&under, &[1.0, 2.0, 3.0], &s),
        Err(DspError::TooShort {
            needed: 3,
            found: 2,
            ..
        })
    ));
    let nan = FnProblem::new(2, |_: &[f64], r: &mut [f64]| r.fill(f64::NAN));
    assert!(matches!(
        least_squares(&nan, &[1.0], &s),
        Err(DspError::NonFinite { .. })
    ));
    assert!(matches!(
        least_squares(&nan, &[], &s),
        Err(DspError::Empty { .. })
    ));
    // A non-finite Jacobian entry is reported at its row-major index, also
    // past the first 64 columns (the check runs in blocks of 64).
    for (n, row, col) in [(2, 1, 1), (70, 2, 66)] {
        let bad_jac = FnProblem::with_jacobian(
            n + 3,
            |p: &[f64], r: &mut [f64]| {
                r.iter_mut()
                    .zip(p.iter().cycle())
                    .for_each(|(r, p)| *r = *p)
            },
            move |_: &[f64], j: &mut [f64]| {
                j.fill(1.0);
                j[row * n + col] = f64::INFINITY;
            },
        );
        let err = least_squares(&bad_jac, &vec![1.0; n], &s).unwrap_err();
        assert!(
            matches!(err, DspError::NonFinite { what: "jacobian", index, .. } if index == row * n + col),
            "{err:?}"
        );
    }
    let empty = FnProblem::new(0, |_: &[f64], _: &mut [f64]| {});
    assert!(least_squares(&empty, &[1.0], &s).is_err());
    let neg = LeastSquares { ftol: -1.0, ..s };
    let ok = FnProblem::new(2, |p: &[f64], r: &mut [f64]| r.fill(p[0]));
    assert!(matches!(
        least_squares(&ok, &[1.0], &neg),
        Err(DspError::InvalidSetting { name: "ftol", .. })
    ));
}
