//! Each pulse's amplitude, centre and width fitted against the template
//! (Levenberg–Marquardt on four parameters), with the neighbours' modelled
//! pulses removed from the data: a pulse's width measured as if it stood alone.

use super::lsq::dense_solve;
use super::template::{Pulse, Template};

/// One pulse fitted against the template.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PulseFit {
    pub pulse: Pulse,
    /// Local offset fitted with it.
    pub offset: f64,
    /// Standard error of the stretch.
    pub s_se: f64,
    /// Samples in the fit window.
    pub samples: usize,
    /// The window was cut by the record's start or end.
    pub cut: bool,
    /// The fit converged to a sensible pulse.
    pub ok: bool,
}

/// Fits `o + a h((i − c)/s)` to `data(i)`, `i < n` (the signal with the
/// baseline and the neighbours' pulses removed) over the template support
/// around `p`, by Levenberg–Marquardt on `(a, c, s, o)`; the window is the
/// support at the starting stretch, widened by 10 %.
pub(super) fn fit_pulse(
    data: &dyn Fn(usize) -> f64,
    n: usize,
    p: Pulse,
    t: &Template,
    (left, right): (f64, f64),
) -> PulseFit {
    let lo_f = p.c + 1.1 * p.s * left;
    let hi_f = p.c + 1.1 * p.s * right;
    let cut = lo_f < 0.0 || hi_f > (n - 1) as f64;
    let lo = lo_f.ceil().max(0.0) as usize;
    let hi = (hi_f.floor().max(0.0) as usize).min(n - 1);
    let samples = (hi + 1).saturating_sub(lo);
    let mut fit = PulseFit {
        pulse: p,
        offset: 0.0,
        s_se: f64::INFINITY,
        samples,
        cut,
        ok: false,
    };
    if samples < 8 {
        return fit;
    }
    let xs: Vec<f64> = (lo..=hi).map(|i| i as f64).collect();
    let ys: Vec<f64> = (lo..=hi).map(data).collect();
    let ys = &ys[..];
    let mut pts = Points::new(samples);
    let mut cost = |th: &[f64; 4]| -> f64 {
        pts.fill(&xs, th, t, false);
        pts.p0
            .iter()
            .zip(ys)
            .map(|(&p, y)| {
                // y − o − a·t.value((x − c) / s)
                let r = y - th[3] - th[0] * t.at_point(p);
                r * r
            })
            .sum()
    };
    let mut th = [p.a, p.c, p.s, 0.0];
    let mut c0 = cost(&th);
    let mut lambda = 1e-3;
    let mut jtj = [[0.0; 4]; 4];
    let mut jac = Points::new(samples);
    for _ in 0..30 {
        let mut g = [0.0; 4];
        jtj = [[0.0; 4]; 4];
        jac.fill(&xs, &th, t, true);
        for (k, y) in ys.iter().enumerate() {
            let u = jac.u[k];
            // t.value(u), t.slope(u)
            let hv = t.at_point(jac.p0[k]);
            let hs = (t.at_point(jac.p1[k]) - t.at_point(jac.p2[k])) / t.dx;
            let jr = [hv, -th[0] * hs / th[2], -th[0] * hs * u / th[2], 1.0];
            let r = y - th[3] - th[0] * hv;
            for a in 0..4 {
                g[a] += jr[a] * r;
                for b in 0..=a {
                    jtj[a][b] += jr[a] * jr[b];
                }
            }
        }
        let mut improved = false;
        let mut converged = false;
        for _ in 0..8 {
            let mut m = [0.0; 16];
            for a in 0..4 {
                for b in 0..=a {
                    m[a * 4 + b] = jtj[a][b];
                    m[b * 4 + a] = jtj[a][b];
                }
                m[a * 4 + a] += lambda * jtj[a][a].max(1e-300);
            }
            let mut step = vec![g.to_vec()];
            if !dense_solve(&mut m, 4, &mut step) {
                lambda *= 10.0;
                continue;
            }
            let st = &step[0];
            let trial = [th[0] + st[0], th[1] + st[1], th[2] + st[2], th[3] + st[3]];
            if !(trial[2] > 0.2 * p.s && trial[2] < 5.0 * p.s) {
                lambda *= 10.0;
                continue;
            }
            let c1 = cost(&trial);
            if c1 < c0 {
                converged = st[1].abs() < 1e-4 * th[2] && (st[2] / th[2]).abs() < 1e-6;
                th = trial;
                c0 = c1;
                lambda = (lambda * 0.3).max(1e-9);
                improved = true;
                break;
            }
            lambda *= 10.0;
        }
        if !improved || converged {
            break;
        }
    }
    fit.pulse = Pulse {
        a: th[0],
        c: th[1],
        s: th[2],
    };
    fit.offset = th[3];
    // Standard error of s: σ² (JᵀJ)⁻¹ at the solution.
    let dof = samples.saturating_sub(4).max(1) as f64;
    let s2 = c0 / dof;
    let mut m = [0.0; 16];
    for a in 0..4 {
        for b in 0..=a {
            m[a * 4 + b] = jtj[a][b];
            m[b * 4 + a] = jtj[a][b];
        }
    }
    let mut e = vec![vec![0.0, 0.0, 1.0, 0.0]];
    if dense_solve(&mut m, 4, &mut e) {
        fit.s_se = (s2 * e[0][2]).max(0.0).sqrt();
    }
    let support = right - left;
    fit.ok = th.iter().all(|v| v.is_finite())
        && (th[1] - p.c).abs() < 0.25 * support * p.s
        && th[2] > 0.3 * p.s
        && th[2] < 3.0 * p.s;
    fit
}

/// Per sample of a fit window, `u = (x − c) / s` and the template's grid
/// positions of `t.value(u)` (`p0`) and of the two values of `t.slope(u)`
/// (`p1`, `p2`), computed over the whole window at once with exactly the
/// operations of [`Template::value`] and `Template::slope` (the centred
/// difference of two values over one grid step): one loop per
/// quantity, so the divisions run side by side in vector registers.
struct Points {
    u: Vec<f64>,
    p0: Vec<f64>,
    p1: Vec<f64>,
    p2: Vec<f64>,
}

impl Points {
    fn new(n: usize) -> Self {
        Self {
            u: vec![0.0; n],
            p0: vec![0.0; n],
            p1: vec![0.0; n],
            p2: vec![0.0; n],
        }
    }

    /// The positions for parameters `th = (a, c, s, o)` at samples `xs`;
    /// `p1`, `p2` only with `slope`.
    fn fill(&mut self, xs: &[f64], th: &[f64; 4], t: &Template, slope: bool) {
        let (dx, origin) = (t.dx, t.origin as f64);
        for (u, x) in self.u.iter_mut().zip(xs) {
            *u = (x - th[1]) / th[2];
        }
        for (p, u) in self.p0.iter_mut().zip(&self.u) {
            *p = u / dx + origin;
        }
        if slope {
            for (p, u) in self.p1.iter_mut().zip(&self.u) {
                *p = (u + 0.5 * dx) / dx + origin;
            }
            for (p, u) in self.p2.iter_mut().zip(&self.u) {
                *p = (u - 0.5 * dx) / dx + origin;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gauss(sigma: f64) -> impl Fn(f64) -> f64 {
        move |u: f64| (-0.5 * (u / sigma).powi(2)).exp()
    }

    /// The positions computed side by side give `Template::value` and
    /// `Template::slope` bit for bit.
    #[test]
    fn points_give_value_and_slope_bitwise() {
        let t = Template::from_fn(30.0, 25.0, 0.37, gauss(6.0));
        let xs: Vec<f64> = (0..400).map(|i| i as f64).collect();
        for th in [
            [1.5, 199.3, 1.07, 0.1],
            [-0.7, 12.0, 0.31, 0.0],
            [2.0, 390.5, 3.3, -1.0],
        ] {
            let mut pts = Points::new(xs.len());
            pts.fill(&xs, &th, &t, true);
            for (k, x) in xs.iter().enumerate() {
                let u = (x - th[1]) / th[2];
                assert_eq!(pts.u[k].to_bits(), u.to_bits());
                assert_eq!(t.at_point(pts.p0[k]).to_bits(), t.value(u).to_bits());
                let hs = (t.at_point(pts.p1[k]) - t.at_point(pts.p2[k])) / t.dx;
                assert_eq!(hs.to_bits(), t.slope(u).to_bits(), "{th:?} {k}");
            }
        }
    }

    #[test]
    fn pulse_fit_recovers_amplitude_centre_and_stretch() {
        let t = Template::from_fn(30.0, 30.0, 0.5, gauss(6.0));
        let n = 200;
        let truth = Pulse {
            c: 101.3,
            a: 2.0,
            s: 1.07,
        };
        let d: Vec<f64> = (0..n)
            .map(|i| 0.1 + truth.a * t.value((i as f64 - truth.c) / truth.s))
            .collect();
        let f = fit_pulse(
            &|i| d[i],
            n,
            Pulse {
                c: 99.0,
                a: 1.5,
                s: 1.0,
            },
            &t,
            (t.left(), t.right()),
        );
        assert!(f.ok && !f.cut);
        assert!((f.pulse.c - truth.c).abs() < 1e-3, "{:?}", f);
        assert!((f.pulse.s - truth.s).abs() < 1e-4, "{:?}", f);
        assert!((f.pulse.a - truth.a).abs() < 1e-3, "{:?}", f);
        assert!((f.offset - 0.1).abs() < 1e-3, "{:?}", f);
    }
}
