//! The least-squares core: the record's template found together with a
//! smooth baseline, every pulse's overlap with its neighbours accounted for.
//!
//! # The model
//!
//! ```text
//! z[n] = Σ_j β_j B_j(n) + Σ_k a_k h((n − c_k) / s_k) + noise
//! ```
//!
//! - `B_j`: uniform cubic B-splines with knots one ball-pass period apart:
//!   the baseline. Its spectrum is `sinc⁴(f τ_c)`, zero at the ball-pass
//!   frequency and its harmonics, so it follows drifts slower than a few
//!   periods and cannot take the pulse train's shape.
//! - `h`: the template, on a grid of `dx` samples, linear between grid
//!   points, over a support shorter than a period (see
//!   [`Template::with_tails`] for why and for the tails past it), with a
//!   small penalty on its second differences (it only decides directions
//!   the data leave free).
//! - `a_k, c_k, s_k`: each pulse's amplitude, centre and stretch, held fixed
//!   while the template is solved for, then fitted pulse by pulse
//!   ([`fit_pulse`]) against the template with the neighbours' modelled
//!   pulses subtracted: a pulse's width is measured as if it stood alone.
//!
//! Given the pulses, the model is linear in `β, h`. The normal equations
//! have a banded block (the splines, bandwidth 3) and a small dense block
//! (the template); they are solved by the Schur complement of the banded
//! block, so the cost is linear in the record length.

use super::template::{Pulse, Template};

/// Uniform cubic B-spline weights at fraction `f` of a knot interval.
#[inline]
fn bspline_weights(f: f64) -> [f64; 4] {
    let f2 = f * f;
    let f3 = f2 * f;
    let g = 1.0 - f;
    [
        g * g * g / 6.0,
        (3.0 * f3 - 6.0 * f2 + 4.0) / 6.0,
        (-3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0) / 6.0,
        f3 / 6.0,
    ]
}

/// The baseline's cubic B-splines over `n` samples, knots `knot` samples apart.
#[derive(Debug, Clone, Copy)]
pub(super) struct Splines {
    pub knot: f64,
    pub count: usize,
}

impl Splines {
    pub fn new(n: usize, knot: f64) -> Self {
        let knot = knot.max(1.0);
        let count = ((n.saturating_sub(1)) as f64 / knot).floor() as usize + 4;
        Self { knot, count }
    }

    /// First basis index and the four weights at sample `i`.
    #[inline]
    fn at(&self, i: usize) -> (usize, [f64; 4]) {
        let t = i as f64 / self.knot;
        // `t >= 0`: the cast is the floor, without the library call
        // `floor` is on the x86_64 baseline (the same `j`).
        let j = (t as usize).min(self.count - 4);
        (j, bspline_weights(t - j as f64))
    }

    /// The spline with coefficients `beta` at fractional samples `at`
    /// (clamped to the range the splines cover).
    pub fn eval_at(&self, beta: &[f64], at: &[f64]) -> Vec<f64> {
        let top = (self.count - 3) as f64;
        at.iter()
            .map(|&x| {
                let t = (x / self.knot).clamp(0.0, top);
                // `t >= 0` (or NaN): the cast is the floor, as in `at`.
                let j = (t as usize).min(self.count - 4);
                let w = bspline_weights(t - j as f64);
                w.iter().zip(&beta[j..j + 4]).map(|(w, b)| w * b).sum()
            })
            .collect()
    }

    /// The spline with coefficients `beta` at every sample `0..n`.
    pub fn eval(&self, beta: &[f64], n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let (j, w) = self.at(i);
                w.iter().zip(&beta[j..j + 4]).map(|(w, b)| w * b).sum()
            })
            .collect()
    }
}

/// For each sample, the pulses whose template support covers it: a sweep
/// over pulses sorted by centre.
struct Cover<'a> {
    pulses: &'a [Pulse],
    left: f64,
    right: f64,
    lo: usize,
}

impl<'a> Cover<'a> {
    fn new(pulses: &'a [Pulse], t: &Template) -> Self {
        Self {
            pulses,
            left: t.left(),
            right: t.right(),
            lo: 0,
        }
    }

    /// Calls `f(k, u)` for every pulse `k` covering sample `i`
    /// (`u` = template coordinate). Samples must come in increasing order.
    #[inline]
    fn each(&mut self, i: usize, mut f: impl FnMut(usize, f64)) {
        let x = i as f64;
        // Stretches differ little between pulses; a pulse whose support
        // ended before `x` (with the widest stretch) is done for good.
        while self.lo < self.pulses.len() {
            let p = self.pulses[self.lo];
            if p.c + p.s.max(1.0) * 2.0 * self.right < x {
                self.lo += 1;
            } else {
                break;
            }
        }
        for (k, p) in self.pulses.iter().enumerate().skip(self.lo) {
            if p.c + p.s.max(1.0) * 2.0 * self.left > x {
                break;
            }
            let u = (x - p.c) / p.s;
            if u > self.left && u < self.right {
                f(k, u);
            }
        }
    }
}

/// Least-squares solution of the model for one right-hand side.
#[derive(Debug, Clone)]
pub(super) struct Solution {
    /// Spline coefficients of the baseline.
    pub beta: Vec<f64>,
    /// The template.
    pub template: Template,
}

/// The linear least-squares problem of the module docs, for fixed pulses.
pub(super) struct Problem<'a> {
    /// Samples in the signal.
    pub n: usize,
    /// Baseline splines.
    pub splines: Splines,
    /// The pulses (sorted by centre).
    pub pulses: &'a [Pulse],
    /// Grid and support of the template to solve for (values ignored).
    pub grid: &'a Template,
    /// Penalty on the template's second differences, relative to the mean
    /// data weight of a template value.
    pub smoothness: f64,
    /// Hold the template at zero at both ends of its support.
    pub pin_ends: bool,
}

/// Banded symmetric positive-definite matrix (lower bandwidth `BW`),
/// Cholesky-factorised in place.
const BW: usize = 3;

struct Band {
    /// `a[i][d]` = `G[i][i − d]` for `d = 0..=BW`.
    a: Vec<[f64; BW + 1]>,
}

impl Band {
    fn new(n: usize) -> Self {
        Self {
            a: vec![[0.0; BW + 1]; n],
        }
    }

    /// (The assembly in [`Problem::solve`] adds to `a` directly, a knot
    /// interval's rows at a time.)
    #[cfg(test)]
    fn add(&mut self, i: usize, j: usize, v: f64) {
        // i >= j, i - j <= BW.
        self.a[i][i - j] += v;
    }

    /// In-place Cholesky `G = L Lᵀ`; false if not positive definite.
    fn factor(&mut self) -> bool {
        let n = self.a.len();
        for i in 0..n {
            for d in (0..=BW.min(i)).rev() {
                let j = i - d;
                let mut s = self.a[i][d];
                for e in 1..=BW {
                    if d + e > BW || e > j {
                        break;
                    }
                    // L[i][j − e] L[j][j − e]
                    s -= self.a[i][d + e] * self.a[j][e];
                }
                if d == 0 {
                    if s.is_nan() || s <= 0.0 {
                        return false;
                    }
                    self.a[i][0] = s.sqrt();
                } else {
                    self.a[i][d] = s / self.a[j][0];
                }
            }
        }
        true
    }

    /// Solves `L Lᵀ x = b` in place.
    fn solve(&self, b: &mut [f64]) {
        let n = self.a.len();
        for i in 0..n {
            let mut s = b[i];
            for d in 1..=BW.min(i) {
                s -= self.a[i][d] * b[i - d];
            }
            b[i] = s / self.a[i][0];
        }
        for i in (0..n).rev() {
            let mut s = b[i];
            for d in 1..=BW {
                if i + d >= n {
                    break;
                }
                s -= self.a[i + d][d] * b[i + d];
            }
            b[i] = s / self.a[i][0];
        }
    }
}

/// Dense Cholesky solve of `a x = b` (`a` row-major `m × m`, overwritten),
/// for several right-hand sides; false if not positive definite.
pub(super) fn dense_solve(a: &mut [f64], m: usize, rhs: &mut [Vec<f64>]) -> bool {
    for i in 0..m {
        for j in 0..=i {
            let mut s = a[i * m + j];
            for k in 0..j {
                s -= a[i * m + k] * a[j * m + k];
            }
            if i == j {
                if s.is_nan() || s <= 0.0 {
                    return false;
                }
                a[i * m + i] = s.sqrt();
            } else {
                a[i * m + j] = s / a[j * m + j];
            }
        }
    }
    for b in rhs.iter_mut() {
        for i in 0..m {
            let mut s = b[i];
            for k in 0..i {
                s -= a[i * m + k] * b[k];
            }
            b[i] = s / a[i * m + i];
        }
        for i in (0..m).rev() {
            let mut s = b[i];
            for k in i + 1..m {
                s -= a[k * m + i] * b[k];
            }
            b[i] = s / a[i * m + i];
        }
    }
    true
}

/// `D −= Cᵀ X` (`C`, `X`: `nb × m` row-major; `D`: `m × m`), computed on
/// the lower triangle and mirrored. Each entry is the plain loop's sum
/// `Σ_j C[j][r] X[j][c]`, added from `-0.0` in `j` order, so the bits are
/// those of `(0..nb).map(..).sum()`; [`SCHUR_LANES`] entries of a row run
/// side by side so that their serial sums interleave instead of waiting on
/// each other (tested bit for bit).
fn subtract_schur(dense: &mut [f64], cross: &[f64], x: &[f64], m: usize, nb: usize) {
    const L: usize = SCHUR_LANES;
    // X with its rows padded to whole groups of lanes (zeros).
    let mp = m.div_ceil(L) * L;
    let mut xp = vec![0.0; nb * mp];
    for (dst, src) in xp.chunks_exact_mut(mp).zip(x.chunks_exact(m)) {
        dst[..m].copy_from_slice(src);
    }
    for r in 0..m {
        for c0 in (0..=r).step_by(L) {
            let mut s = [-0.0f64; L];
            for (j, xr) in xp.chunks_exact(mp).enumerate() {
                let cr = cross[j * m + r];
                let xs = &xr[c0..c0 + L];
                for (acc, v) in s.iter_mut().zip(xs) {
                    *acc += cr * v;
                }
            }
            for (l, s) in s.iter().enumerate().take(r + 1 - c0) {
                let c = c0 + l;
                dense[r * m + c] -= s;
                if c != r {
                    dense[c * m + r] -= s;
                }
            }
        }
    }
}

/// Writes back the band rows `j0..j0 + 4` and the `rb` entries of knot
/// interval `j0` that [`Problem::solve`] accumulated in locals.
fn store_interval(
    band: &mut Band,
    rb: &mut [Vec<f64>],
    j0: usize,
    local: &[[f64; BW + 1]; 4],
    local_rb: &[[f64; 4]],
) {
    band.a[j0..j0 + 4].copy_from_slice(local);
    for (rb, l) in rb.iter_mut().zip(local_rb) {
        rb[j0..j0 + 4].copy_from_slice(l);
    }
}

/// Entries of [`subtract_schur`] summed side by side.
const SCHUR_LANES: usize = 8;

/// The normal equations of [`Problem::solve`] as summed over the samples:
/// the spline block (lower band), the spline-template block `C` (`nb × m`),
/// the template block's lower triangle `D` (`m × m`) and the right-hand
/// sides' spline and template parts.
struct Assembly {
    band: Band,
    cross: Vec<f64>,
    dense: Vec<f64>,
    rb: Vec<Vec<f64>>,
    rd: Vec<Vec<f64>>,
}

impl Problem<'_> {
    /// Sums the normal equations over the samples ([`Assembly`]), for the
    /// `nt` unknown grid points from `first`.
    fn assemble(&self, rhs: &[&[f64]], first: usize, nt: usize) -> Assembly {
        let nb = self.splines.count;
        let m = nt;
        let unknown =
            |j: usize| -> Option<usize> { (j >= first && j < first + nt).then(|| j - first) };
        let nr = rhs.len();
        let mut band = Band::new(nb);
        let mut cross = vec![0.0; nb * m];
        let mut dense = vec![0.0; m * m];
        let mut rb = vec![vec![0.0; nb]; nr];
        let mut rd = vec![vec![0.0; m]; nr];
        let mut cover = Cover::new(self.pulses, self.grid);
        let mut idx: Vec<usize> = Vec::with_capacity(16);
        let mut val: Vec<f64> = Vec::with_capacity(16);
        let inv_dx = 1.0 / self.grid.dx;
        let origin = self.grid.origin as f64;
        // The band's and `rb`'s entries of the current knot interval `j0`,
        // held in locals while `j0` stays (it never decreases): each entry
        // still gets its terms one by one in sample order, so the sums are
        // those of adding straight into `band` and `rb`, without a store
        // and a reload between samples (`local` is `band.a[j0 + p][d]`).
        let mut cur = None::<usize>;
        let mut local = [[0.0f64; BW + 1]; 4];
        let mut local_rb = vec![[0.0f64; 4]; nr];
        for i in 0..self.n {
            idx.clear();
            val.clear();
            cover.each(i, |k, u| {
                let a = self.pulses[k].a;
                let p = u * inv_dx + origin;
                let j = p as usize;
                let f = p - j as f64;
                if let Some(d) = unknown(j) {
                    idx.push(d);
                    val.push(a * (1.0 - f));
                }
                if let Some(d) = unknown(j + 1) {
                    idx.push(d);
                    val.push(a * f);
                }
            });
            let (j0, w) = self.splines.at(i);
            if cur != Some(j0) {
                if let Some(c) = cur {
                    store_interval(&mut band, &mut rb, c, &local, &local_rb);
                }
                for (p, l) in local.iter_mut().enumerate() {
                    *l = band.a[j0 + p];
                }
                for (l, rb) in local_rb.iter_mut().zip(&rb) {
                    l.copy_from_slice(&rb[j0..j0 + 4]);
                }
                cur = Some(j0);
            }
            for p in 0..4 {
                for q in 0..=p {
                    // band.add(j0 + p, j0 + q, ..)
                    local[p][p - q] += w[p] * w[q];
                }
                let row = &mut cross[(j0 + p) * m..(j0 + p + 1) * m];
                for (&d, &v) in idx.iter().zip(&val) {
                    row[d] += w[p] * v;
                }
            }
            // Lower triangle of v vᵀ, v sparse with repeated indices (two
            // pulses on one grid point): an unordered pair a ≠ b on the
            // diagonal stands for both of its ordered pairs.
            for (a, (&da, &va)) in idx.iter().zip(&val).enumerate() {
                for (b, (&db, &vb)) in idx[..=a].iter().zip(&val[..=a]).enumerate() {
                    let (r, c) = if da >= db { (da, db) } else { (db, da) };
                    let k = if r == c && a != b { 2.0 } else { 1.0 };
                    dense[r * m + c] += k * va * vb;
                }
            }
            for (r, z) in rhs.iter().enumerate() {
                let zi = z[i];
                for p in 0..4 {
                    // rb[r][j0 + p]
                    local_rb[r][p] += w[p] * zi;
                }
                for (&d, &v) in idx.iter().zip(&val) {
                    rd[r][d] += v * zi;
                }
            }
        }
        if let Some(c) = cur {
            store_interval(&mut band, &mut rb, c, &local, &local_rb);
        }
        Assembly {
            band,
            cross,
            dense,
            rb,
            rd,
        }
    }
}

impl Problem<'_> {
    /// Solves for each right-hand side (each `n` long). `None` when the
    /// system is singular (no pulse covers the template, say).
    pub fn solve(&self, rhs: &[&[f64]]) -> Option<Vec<Solution>> {
        let nb = self.splines.count;
        let g = self.grid.h.len();
        // Unknown grid points: all, or the interior ones when the ends are pinned.
        let first = usize::from(self.pin_ends);
        let nt = g.saturating_sub(2 * first);
        let unknown =
            |j: usize| -> Option<usize> { (j >= first && j < first + nt).then(|| j - first) };
        let m = nt;
        if nt == 0 || self.pulses.is_empty() {
            return None;
        }
        let nr = rhs.len();
        let Assembly {
            mut band,
            cross,
            mut dense,
            rb,
            rd,
        } = self.assemble(rhs, first, nt);
        // Symmetrise the dense block (only the lower triangle was summed,
        // with the diagonal counted once).
        for r in 0..m {
            for c in 0..r {
                dense[c * m + r] = dense[r * m + c];
            }
        }
        // Second-difference penalty on the template (pinned ends are 0).
        let mean_diag = (0..nt).map(|i| dense[i * m + i]).sum::<f64>() / nt as f64;
        if mean_diag.is_nan() || mean_diag <= 0.0 {
            return None;
        }
        let lam = self.smoothness * mean_diag;
        for centre in 1..g - 1 {
            // Row e_{centre−1} − 2 e_centre + e_{centre+1} on grid points.
            let pts = [(centre - 1, 1.0), (centre, -2.0), (centre + 1, 1.0)];
            for &(pa, va) in &pts {
                let Some(da) = unknown(pa) else { continue };
                for &(pb, vb) in &pts {
                    let Some(db) = unknown(pb) else { continue };
                    dense[da * m + db] += lam * va * vb;
                }
            }
        }
        // Tiny ridges keep the blocks definite where the data are silent
        // (a knot interval without samples).
        let band_ridge = 1e-10 * band.a.iter().map(|r| r[0]).fold(0.0, f64::max);
        for r in band.a.iter_mut() {
            r[0] += band_ridge.max(1e-300);
        }
        let dense_ridge = 1e-10 * (0..m).map(|i| dense[i * m + i]).fold(0.0, f64::max);
        for i in 0..m {
            dense[i * m + i] += dense_ridge.max(1e-300);
        }
        if !band.factor() {
            return None;
        }
        // X = B⁻¹ C (column by column), S = D − Cᵀ X, rhs' = rd − Xᵀ rb.
        let mut x = vec![0.0; nb * m];
        let mut col = vec![0.0; nb];
        for c in 0..m {
            for (j, v) in col.iter_mut().enumerate() {
                *v = cross[j * m + c];
            }
            band.solve(&mut col);
            for (j, v) in col.iter().enumerate() {
                x[j * m + c] = *v;
            }
        }
        subtract_schur(&mut dense, &cross, &x, m, nb);
        let mut rdp: Vec<Vec<f64>> = (0..nr)
            .map(|r| {
                (0..m)
                    .map(|c| rd[r][c] - (0..nb).map(|j| x[j * m + c] * rb[r][j]).sum::<f64>())
                    .collect()
            })
            .collect();
        if !dense_solve(&mut dense, m, &mut rdp) {
            return None;
        }
        let out = (0..nr)
            .map(|r| {
                let theta = &rdp[r];
                let mut beta: Vec<f64> = (0..nb)
                    .map(|j| rb[r][j] - (0..m).map(|c| cross[j * m + c] * theta[c]).sum::<f64>())
                    .collect();
                band.solve(&mut beta);
                let mut h = vec![0.0; g];
                h[first..first + nt].copy_from_slice(&theta[..nt]);
                Solution {
                    beta,
                    template: Template {
                        dx: self.grid.dx,
                        origin: self.grid.origin,
                        h,
                    },
                }
            })
            .collect();
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::super::template::pulse_model;
    use super::*;

    /// The lock-step Schur update equals the plain loop bit for bit, for
    /// sizes below, at and past whole groups of lanes.
    #[test]
    fn schur_update_equals_the_plain_loop_bitwise() {
        for (m, nb) in [(1, 5), (7, 40), (8, 33), (13, 90), (17, 301)] {
            let val = |i: usize, a: usize| ((i * a % 97) as f64 - 48.0) / 7.0 + 1e-3 * i as f64;
            let cross: Vec<f64> = (0..nb * m).map(|i| val(i, 31)).collect();
            let x: Vec<f64> = (0..nb * m).map(|i| val(i, 17)).collect();
            let d0: Vec<f64> = (0..m * m).map(|i| val(i, 5)).collect();
            let mut want = d0.clone();
            for r in 0..m {
                for c in 0..=r {
                    let s: f64 = (0..nb).map(|j| cross[j * m + r] * x[j * m + c]).sum();
                    want[r * m + c] -= s;
                    if c != r {
                        want[c * m + r] -= s;
                    }
                }
            }
            let mut got = d0;
            subtract_schur(&mut got, &cross, &x, m, nb);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&want), "m {m} nb {nb}");
        }
    }

    /// The assembly's spline block and spline right-hand sides, summed in
    /// locals a knot interval at a time, equal adding every sample's terms
    /// straight into them (the plain loop) bit for bit; the other blocks
    /// are summed as before.
    #[test]
    fn interval_sums_equal_the_plain_loop_bitwise() {
        let n = 1234;
        let pulses: Vec<Pulse> = (0..13)
            .map(|k| Pulse {
                c: 40.0 + 93.7 * k as f64,
                a: 1.0 + 0.1 * (k % 3) as f64,
                s: 1.0 + 0.01 * (k % 4) as f64,
            })
            .collect();
        let grid = Template::from_fn(40.0, 40.0, 2.5, |_| 0.0);
        let z1: Vec<f64> = (0..n)
            .map(|i| (0.37 * i as f64).sin() + 1e-3 * i as f64)
            .collect();
        let z2: Vec<f64> = (0..n).map(|i| (i % 17) as f64 - 8.3).collect();
        for knot in [93.7, 7.0, 1.0, 5000.0] {
            let p = Problem {
                n,
                splines: Splines::new(n, knot),
                pulses: &pulses,
                grid: &grid,
                smoothness: 1e-2,
                pin_ends: true,
            };
            let got = p.assemble(&[&z1, &z2], 1, grid.h.len() - 2);
            let nb = p.splines.count;
            let mut band = Band::new(nb);
            let mut rb = vec![vec![0.0; nb]; 2];
            for i in 0..n {
                let (j0, w) = p.splines.at(i);
                for a in 0..4 {
                    for b in 0..=a {
                        band.add(j0 + a, j0 + b, w[a] * w[b]);
                    }
                    rb[0][j0 + a] += w[a] * z1[i];
                    rb[1][j0 + a] += w[a] * z2[i];
                }
            }
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&got.band.a.concat()),
                bits(&band.a.concat()),
                "knot {knot}"
            );
            assert_eq!(bits(&got.rb.concat()), bits(&rb.concat()), "knot {knot}");
        }
    }

    fn gauss(sigma: f64) -> impl Fn(f64) -> f64 {
        move |u: f64| (-0.5 * (u / sigma).powi(2)).exp()
    }

    #[test]
    fn band_cholesky_solves_a_banded_system() {
        // G = tridiagonal-plus (bandwidth 3), against a dense solve.
        let n = 9;
        let mut band = Band::new(n);
        let mut dense = vec![0.0; n * n];
        for i in 0..n {
            for d in 0..=BW.min(i) {
                let v = if d == 0 {
                    10.0 + i as f64
                } else {
                    1.0 / (1.0 + d as f64 + i as f64)
                };
                band.add(i, i - d, v);
                dense[i * n + i - d] = v;
                dense[(i - d) * n + i] = v;
            }
        }
        let b: Vec<f64> = (0..n).map(|i| (i as f64).sin() + 1.0).collect();
        let mut xb = b.clone();
        assert!(band.factor());
        band.solve(&mut xb);
        let mut xd = vec![b];
        assert!(dense_solve(&mut dense, n, &mut xd));
        for (a, c) in xb.iter().zip(&xd[0]) {
            assert!((a - c).abs() < 1e-12, "{a} vs {c}");
        }
    }

    /// Overlapping Gaussian pulses (FWHM 0.45 of the spacing) on a sloping
    /// baseline: the least-squares template is the isolated pulse, and its
    /// FWHM the pulse's, although the half-prominence width of the sum is not.
    #[test]
    fn template_of_overlapping_pulses_is_the_isolated_pulse() {
        let period = 100.0;
        let fwhm = 0.45 * period;
        let sigma = fwhm / 2.354_820_045;
        let n = 3000;
        let mut pulses = Vec::new();
        let mut c = 37.0;
        let mut k = 0;
        while c < n as f64 {
            pulses.push(Pulse {
                c,
                a: 1.0 + 0.05 * ((k * 7 % 5) as f64 - 2.0),
                s: 1.0,
            });
            c += period * (1.0 + 0.03 * ((k * 3 % 7) as f64 - 3.0) / 3.0);
            k += 1;
        }
        let truth = Template::from_fn(2.5 * fwhm, 2.5 * fwhm, 1.0, gauss(sigma));
        let mut z = pulse_model(n, &pulses, &truth);
        for (i, v) in z.iter_mut().enumerate() {
            *v += 0.3 + 2e-4 * i as f64;
        }
        let grid = Template::from_fn(0.9 * period, 0.9 * period, fwhm / 16.0, |_| 0.0);
        let p = Problem {
            n,
            splines: Splines::new(n, period),
            pulses: &pulses,
            grid: &grid,
            smoothness: 1e-2,
            pin_ends: true,
        };
        let sol = p.solve(&[&z]).unwrap().remove(0);
        let s = sol.template.shape().unwrap();
        assert!(
            (s.fwhm() / fwhm - 1.0).abs() < 2e-3,
            "{} vs {fwhm}",
            s.fwhm()
        );
        assert!((s.peak - 1.0).abs() < 5e-3, "{}", s.peak);
        let b = Splines::new(n, period).eval(&sol.beta, n);
        for (i, v) in b.iter().enumerate().step_by(97) {
            assert!((v - 0.3 - 2e-4 * i as f64).abs() < 5e-3, "{i}: {v}");
        }
    }
}
