//! The record's own pulse shape (the *template*): a function sampled on a
//! grid, its peak and half-maximum crossings, its Gaussian tails, and the
//! pulses it models (`a_k h((n − c_k) / s_k)`). How it is found is in
//! [`super::lsq`]; how each pulse is fitted against it, [`super::pulse_fit`].

/// One pulse: centre `c` (samples), amplitude `a` (signal units, signed),
/// stretch `s` of the template.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Pulse {
    pub c: f64,
    pub a: f64,
    pub s: f64,
}

/// The mean pulse shape: `h(u)` at `u = (i − origin) dx` samples,
/// `i = 0..h.len()`, zero at both ends and outside.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Template {
    pub dx: f64,
    pub origin: usize,
    pub h: Vec<f64>,
}

/// Points where the template crosses half its peak, and its peak.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Shape {
    /// Position of the maximum, samples from the origin.
    pub peak_u: f64,
    /// Value at the maximum.
    pub peak: f64,
    /// Half-maximum crossing before the peak.
    pub left_u: f64,
    /// Half-maximum crossing after the peak.
    pub right_u: f64,
}

impl Shape {
    /// Full width at half maximum, samples.
    pub fn fwhm(&self) -> f64 {
        self.right_u - self.left_u
    }

    /// Midpoint of the two half-maximum crossings.
    pub fn mid_u(&self) -> f64 {
        0.5 * (self.left_u + self.right_u)
    }
}

impl Template {
    /// A template of `left` and `right` samples either side of the origin on
    /// a grid of `dx`, filled by `f`.
    pub fn from_fn(left: f64, right: f64, dx: f64, f: impl Fn(f64) -> f64) -> Self {
        let origin = (left / dx).ceil().max(1.0) as usize;
        let after = (right / dx).ceil().max(1.0) as usize;
        let mut h: Vec<f64> = (0..=origin + after)
            .map(|i| f((i as f64 - origin as f64) * dx))
            .collect();
        h[0] = 0.0;
        let last = h.len() - 1;
        h[last] = 0.0;
        Self { dx, origin, h }
    }

    /// First point of the support, samples from the origin (negative).
    pub fn left(&self) -> f64 {
        -(self.origin as f64) * self.dx
    }

    /// Last point of the support, samples from the origin.
    pub fn right(&self) -> f64 {
        (self.h.len() - 1 - self.origin) as f64 * self.dx
    }

    /// `h(u)`, linear between grid points, 0 outside.
    #[inline]
    pub fn value(&self, u: f64) -> f64 {
        self.at_point(u / self.dx + self.origin as f64)
    }

    /// [`Template::value`] at grid position `p = u / dx + origin`
    /// (computed by the caller, with the same operations, so that many
    /// positions can be computed side by side).
    #[inline]
    pub fn at_point(&self, p: f64) -> f64 {
        if !(p > 0.0 && p < (self.h.len() - 1) as f64) {
            return 0.0;
        }
        let i = p as usize;
        let f = p - i as f64;
        self.h[i] + f * (self.h[i + 1] - self.h[i])
    }

    /// `h'(u)` as the centred difference of [`Template::value`] over one grid
    /// step (continuous, unlike the slope of the linear pieces). The fits
    /// compute it over a window at once (`pulse_fit::Points`); this is
    /// their reference in the tests.
    #[cfg(test)]
    pub fn slope(&self, u: f64) -> f64 {
        (self.value(u + 0.5 * self.dx) - self.value(u - 0.5 * self.dx)) / self.dx
    }

    /// Peak and half-maximum crossings: the largest grid value (refined by
    /// a parabola through it and its neighbours), and the first points below
    /// half of it walking out from there, linearly interpolated. `None` when
    /// the template has no positive peak.
    pub fn shape(&self) -> Option<Shape> {
        let (imax, &hmax) = self
            .h
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))?;
        if hmax <= 0.0 || imax == 0 || imax + 1 >= self.h.len() {
            return None;
        }
        let (a, b, c) = (self.h[imax - 1], hmax, self.h[imax + 1]);
        let den = a - 2.0 * b + c;
        let (off, peak) = if den < 0.0 {
            let off = (0.5 * (a - c) / den).clamp(-0.5, 0.5);
            (off, b - 0.25 * (a - c) * off)
        } else {
            (0.0, b)
        };
        let half = 0.5 * peak;
        let u = |i: f64| (i - self.origin as f64) * self.dx;
        let mut left = None;
        for i in (0..imax).rev() {
            if self.h[i] <= half {
                let f = (half - self.h[i]) / (self.h[i + 1] - self.h[i]);
                left = Some(u(i as f64 + f));
                break;
            }
        }
        let mut right = None;
        for i in imax + 1..self.h.len() {
            if self.h[i] <= half {
                let f = (self.h[i - 1] - half) / (self.h[i - 1] - self.h[i]);
                right = Some(u(i as f64 - 1.0 + f));
                break;
            }
        }
        Some(Shape {
            peak_u: u(imax as f64 + off),
            peak,
            left_u: left?,
            right_u: right?,
        })
    }

    /// The template continued past both ends of its support by Gaussian
    /// tails, and those tails alone (zero on the support).
    ///
    /// Each side's tail is `h(u) = h_end exp(−((u − u_p)² − (u_end − u_p)²) / (2 s²))`,
    /// with `u_p` the peak and `s` from a straight line through
    /// `ln h` against `(u − u_p)²` over the grid points where `h` falls from
    /// half the peak to a tenth of it (the strong part of the pulse's
    /// decay, which a pedestal under the pulse barely moves);
    /// continued until it falls to 0.1 % of the peak, or `reach` samples
    /// from the peak. No tail where the end value is below 1 % of the peak
    /// or the line does not fall.
    ///
    /// Pulses that overlap leave the level under them undetermined by the
    /// data alone (a pedestal added to the pulse and taken from the baseline
    /// gives the same signal); the support is kept shorter than a period so
    /// that the least squares cannot trade the two, and the tails past it,
    /// which the neighbours' supports would otherwise leave unexplained, are
    /// continued from the pulse's own decay.
    pub fn with_tails(&self, reach: f64) -> Option<(Template, Template)> {
        let sh = self.shape()?;
        let peak = sh.peak;
        let g = self.h.len();
        let u = |i: usize| (i as f64 - self.origin as f64) * self.dx;
        let fit_side = |range: Vec<usize>, end: usize| -> Option<f64> {
            let he = self.h[end];
            if he < 0.01 * peak {
                return None;
            }
            let pts: Vec<(f64, f64)> = range
                .into_iter()
                .filter(|&i| self.h[i] > 0.1 * peak && self.h[i] <= 0.5 * peak)
                .map(|i| ((u(i) - sh.peak_u).powi(2), self.h[i].ln()))
                .collect();
            if pts.len() < 3 {
                return None;
            }
            let fit = crate::stats::linear_fit(
                &pts.iter().map(|p| p.0).collect::<Vec<_>>(),
                &pts.iter().map(|p| p.1).collect::<Vec<_>>(),
            )?;
            (fit.slope < 0.0).then(|| (-0.5 / fit.slope).sqrt())
        };
        let left_start = ((sh.left_u / self.dx) + self.origin as f64)
            .floor()
            .max(0.0) as usize;
        let right_start = ((sh.right_u / self.dx) + self.origin as f64).ceil() as usize;
        let s_l = fit_side((0..=left_start.min(g - 1)).collect(), 0);
        let s_r = fit_side((right_start.min(g - 1)..g).collect(), g - 1);
        // Grid points beyond each end until 0.1 % of the peak or `reach`.
        let extent = |s: Option<f64>, end: usize| -> usize {
            match s {
                Some(s) => {
                    let he = self.h[end];
                    let d_end = (u(end) - sh.peak_u).abs();
                    let d = (d_end * d_end + 2.0 * s * s * (he / (1e-3 * peak)).ln().max(0.0))
                        .sqrt()
                        .min(reach);
                    ((d - d_end) / self.dx).ceil().max(0.0) as usize
                }
                None => 0,
            }
        };
        let (el, er) = (extent(s_l, 0), extent(s_r, g - 1));
        let tail = |s: Option<f64>, end: usize, k: usize, dir: f64| -> f64 {
            let Some(s) = s else { return 0.0 };
            let d_end = u(end) - sh.peak_u;
            let d = d_end + dir * k as f64 * self.dx;
            self.h[end] * (-(d * d - d_end * d_end) / (2.0 * s * s)).exp()
        };
        let mut full = Vec::with_capacity(g + el + er + 2);
        let mut tails = Vec::with_capacity(g + el + er + 2);
        // A zero at each far end keeps the linear interpolation inside.
        full.push(0.0);
        tails.push(0.0);
        for k in (1..=el).rev() {
            let v = tail(s_l, 0, k, -1.0);
            full.push(v);
            tails.push(v);
        }
        full.extend_from_slice(&self.h);
        tails.extend(std::iter::repeat_n(0.0, g));
        for k in 1..=er {
            let v = tail(s_r, g - 1, k, 1.0);
            full.push(v);
            tails.push(v);
        }
        full.push(0.0);
        tails.push(0.0);
        let origin = self.origin + el + 1;
        Some((
            Template {
                dx: self.dx,
                origin,
                h: full,
            },
            Template {
                dx: self.dx,
                origin,
                h: tails,
            },
        ))
    }

    /// The template on `[left, right]` only (same grid step; zero at both
    /// new ends).
    pub fn restricted(&self, left: f64, right: f64) -> Template {
        let left = left.max(self.left());
        let right = right.min(self.right());
        Template::from_fn(-left, right, self.dx, |u| self.value(u))
    }

    /// Scales the values by `k`.
    pub fn scale(&mut self, k: f64) {
        self.h.iter_mut().for_each(|v| *v *= k);
    }

    /// The same function on a grid stretched by `k` (values unchanged):
    /// `h_new(u) = h(u / k)`.
    pub fn stretch(&mut self, k: f64) {
        self.dx *= k;
    }
}

/// The modelled pulses `Σ_k a_k h((n − c_k)/s_k)` at every sample `0..n`.
pub(super) fn pulse_model(n: usize, pulses: &[Pulse], t: &Template) -> Vec<f64> {
    let mut out = vec![0.0; n];
    add_pulses(&mut out, pulses, t, 1.0);
    out
}

/// Adds `sign × a_k h((i − c_k)/s_k)` of every pulse to `out`.
pub(super) fn add_pulses(out: &mut [f64], pulses: &[Pulse], t: &Template, sign: f64) {
    let n = out.len();
    for p in pulses {
        let lo = (p.c + p.s * t.left()).ceil().max(0.0) as usize;
        let hi = ((p.c + p.s * t.right()).floor().max(-1.0) as isize).min(n as isize - 1);
        if hi < lo as isize {
            continue;
        }
        for (i, o) in out.iter_mut().enumerate().take(hi as usize + 1).skip(lo) {
            *o += sign * p.a * t.value((i as f64 - p.c) / p.s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gauss(sigma: f64) -> impl Fn(f64) -> f64 {
        move |u: f64| (-0.5 * (u / sigma).powi(2)).exp()
    }

    #[test]
    fn template_shape_of_a_gaussian() {
        let sigma = 10.0;
        let t = Template::from_fn(40.0, 40.0, 0.5, gauss(sigma));
        let s = t.shape().unwrap();
        // FWHM = 2√(2 ln 2) σ = 23.548; linear interpolation on a 0.5-sample
        // grid errs by < (dx²/8) |h''| / |h'| at the crossing ≈ 1e-3 samples.
        assert!((s.fwhm() - 23.548_2).abs() < 5e-3, "{}", s.fwhm());
        assert!(s.mid_u().abs() < 1e-9 && s.peak_u.abs() < 1e-9);
        assert!((s.peak - 1.0).abs() < 1e-12);
    }
}
