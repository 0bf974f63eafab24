//! The ball-pass lines of the position-domain spectra (module docs of
//! [`super`], "line k"): each located between the bins on the
//! segment-averaged power, its power over the floor and its amplitude band.

use ballpass_dsp::DetrendType;
use rayon::prelude::*;

use super::{line_amplitude_band, PositionLine, PositionSpectra};
use crate::analysis::Signal;
use crate::stats::median;

/// The windowed, detrended Welch segments of every signal, for locating a
/// line between the bins: the mean of `|Σ w[n] x[n] e^{−2πi f n dx}|²` over
/// the segments is the Welch PSD at any `f` (up to its scale), so its
/// maximum near a peak bin is the zero-padded Welch peak, free of an
/// interpolation formula's bias.
///
/// A streamed record gives instead, per signal, the sum over its segments
/// of each windowed segment's autocorrelation `R[l] = Σ s[i] s[i+l]`
/// ([`LineScan::from_autocorrelations`]): the same mean power is then
/// `(R[0] + 2 Σ_{l≥1} R[l] cos(2π f l dx)) / segments`, equal to the sum
/// over the segments up to rounding, in memory of one segment per signal.
pub(crate) struct LineScan {
    window: Vec<f64>,
    dx: f64,
    segments: Vec<(Signal, Vec<f64>)>,
    /// Per signal, summed autocorrelations (lags `0..n`) and segments.
    acf: Vec<(Signal, Vec<f64>, usize)>,
}

impl LineScan {
    pub(super) fn new(window: &[f64], dx: f64) -> Self {
        LineScan {
            window: window.to_vec(),
            dx,
            segments: Vec::new(),
            acf: Vec::new(),
        }
    }

    /// A scan from the summed autocorrelations of the windowed, detrended
    /// segments of each signal (lags `0..n`) and their numbers of
    /// segments.
    pub(crate) fn from_autocorrelations(dx: f64, acf: Vec<(Signal, Vec<f64>, usize)>) -> Self {
        LineScan {
            window: Vec::new(),
            dx,
            segments: Vec::new(),
            acf,
        }
    }

    /// Mean segment power of `s` at each of `freqs` from its summed
    /// autocorrelation (struct docs); `None` when there is none.
    fn acf_powers(&self, s: Signal, freqs: &[f64]) -> Option<Vec<f64>> {
        let (_, r, count) = self.acf.iter().find(|(t, _, c)| *t == s && *c > 0)?;
        let tau = std::f64::consts::TAU;
        Some(
            freqs
                .iter()
                .map(|&f| {
                    let w = tau * f * self.dx;
                    let tail: f64 = r[1..]
                        .iter()
                        .enumerate()
                        .map(|(l, v)| v * (w * (l + 1) as f64).cos())
                        .sum();
                    (r[0] + 2.0 * tail) / *count as f64
                })
                .collect(),
        )
    }

    /// Adds the segments of `x` as Welch cuts them (step `n/2`, linear
    /// detrend, window).
    pub(super) fn add(&mut self, s: Signal, x: &[f64]) {
        let n = self.window.len();
        let mut start = 0;
        while start + n <= x.len() {
            let mut seg = x[start..start + n].to_vec();
            ballpass_dsp::detrend_in_place(&mut seg, DetrendType::Linear)
                .expect("a finite segment detrends");
            seg.iter_mut().zip(&self.window).for_each(|(v, w)| *v *= w);
            self.segments.push((s, seg));
            start += n / 2;
        }
    }

    /// The segments of `s`.
    fn segments_of(&self, s: Signal) -> Vec<&[f64]> {
        self.segments
            .iter()
            .filter(|(t, _)| *t == s)
            .map(|(_, v)| v.as_slice())
            .collect()
    }

    /// Frequency of the largest mean power of the segments of `s` in each
    /// `[lo, hi]` of `ranges`: a grid of 64 steps, then golden-section
    /// refinement of the best step to 1e-4 of a step. The ranges are
    /// searched side by side (their grids in one call, their golden
    /// sections in lock step), each exactly as alone ([`tests::peak_alone`]
    /// is the reference, checked bit for bit). `None` without segments.
    fn peaks(&self, s: Signal, ranges: &[(f64, f64)]) -> Option<Vec<f64>> {
        let segs = self.segments_of(s);
        let by_acf = self.acf_powers(s, &[]).is_some();
        let powers = |f: &[f64]| match self.acf_powers(s, f) {
            Some(p) => p,
            None => ballpass_dsp::segment_powers(&segs, self.dx, f)
                .expect("Welch segments of one length, finite frequencies"),
        };
        let any = by_acf || !segs.is_empty();
        if !any || ranges.is_empty() {
            return any.then(Vec::new);
        }
        let n = 64;
        let grid: Vec<f64> = ranges
            .iter()
            .flat_map(|&(lo, hi)| {
                let h = (hi - lo) / n as f64;
                (0..=n).map(move |j| lo + j as f64 * h)
            })
            .collect();
        let p = powers(&grid);
        // Per range: the bracket, its interior points and their powers
        // (`c < d`; `None` until measured), and the grid step.
        let mut state: Vec<Golden> = ranges
            .iter()
            .enumerate()
            .map(|(r, &(lo, hi))| {
                let h = (hi - lo) / n as f64;
                let (p, grid) = (&p[r * (n + 1)..][..=n], &grid[r * (n + 1)..][..=n]);
                // The last of equal maxima, as `Iterator::max_by` picks.
                let best = (0..=n)
                    .max_by(|&a, &b| p[a].total_cmp(&p[b]))
                    .map(|j| grid[j])
                    .expect("grid");
                Golden::new((best - h).max(lo), (best + h).min(hi), h)
            })
            .collect();
        loop {
            // The points to measure: both interior points of a new
            // bracket, then the one new point per step.
            let wanted: Vec<(usize, bool, f64)> = state
                .iter()
                .enumerate()
                .filter(|(_, st)| st.active())
                .flat_map(|(r, st)| {
                    let c = st.pc.is_none().then_some((r, false, st.c));
                    let d = st.pd.is_none().then_some((r, true, st.d));
                    c.into_iter().chain(d)
                })
                .collect();
            if wanted.is_empty() {
                break;
            }
            let freqs: Vec<f64> = wanted.iter().map(|w| w.2).collect();
            let p = powers(&freqs);
            for (&(r, is_d, _), &v) in wanted.iter().zip(&p) {
                if is_d {
                    state[r].pd = Some(v);
                } else {
                    state[r].pc = Some(v);
                }
            }
            for st in state.iter_mut().filter(|st| st.active()) {
                st.step();
            }
        }
        Some(state.iter().map(|st| 0.5 * (st.a + st.b)).collect())
    }
}

/// The golden ratio's conjugate, `(√5 − 1) / 2`.
fn golden_ratio() -> f64 {
    0.5 * (5f64.sqrt() - 1.0)
}

/// One golden-section search for a maximum: the bracket `[a, b]`, its
/// interior points `c = b − g (b − a)` and `d = a + g (b − a)` and their
/// powers once measured. Each step keeps the side of the larger power
/// (`c` on ties) and reuses the kept interior point and its power, so one
/// new point is measured per step; it stops when the bracket is at most
/// `1e-4 h` wide.
#[derive(Debug, Clone, Copy)]
struct Golden {
    a: f64,
    b: f64,
    h: f64,
    c: f64,
    d: f64,
    pc: Option<f64>,
    pd: Option<f64>,
}

impl Golden {
    fn new(a: f64, b: f64, h: f64) -> Self {
        let g = golden_ratio();
        Golden {
            a,
            b,
            h,
            c: b - g * (b - a),
            d: a + g * (b - a),
            pc: None,
            pd: None,
        }
    }

    fn active(&self) -> bool {
        self.b - self.a > 1e-4 * self.h
    }

    /// Narrows the bracket once both interior powers are known.
    fn step(&mut self) {
        let (Some(pc), Some(pd)) = (self.pc, self.pd) else {
            return;
        };
        let g = golden_ratio();
        if pc >= pd {
            (self.b, self.d, self.pd) = (self.d, self.c, Some(pc));
            self.c = self.b - g * (self.b - self.a);
            self.pc = None;
        } else {
            (self.a, self.c, self.pc) = (self.c, self.d, Some(pd));
            self.d = self.a + g * (self.b - self.a);
            self.pd = None;
        }
    }
}

/// A line whose search holds a positive bin: its signal and PSD, the
/// harmonic `k`, the searched bins `lo..=hi` and the largest one.
type Found<'a> = (Signal, &'a [f64], usize, usize, usize, usize);

/// Median of `χ²_ν / ν` (0.693 at ν = 2, 0.934 at 10, → 1); 1 without
/// degrees of freedom.
fn chi2_median_over_nu(nu: f64) -> f64 {
    let m = crate::stats::chi2_ppf(0.5, nu) / nu;
    if nu > 0.0 && m.is_finite() && m > 0.0 {
        m
    } else {
        1.0
    }
}

/// The line and harmonics of every signal (module docs), each line in
/// parallel (rayon; the order is that of a sequential pass). Without
/// `scan`, each line's frequency is its largest bin's.
pub(super) fn lines(
    p: &PositionSpectra,
    harmonics: usize,
    scan: Option<&LineScan>,
) -> Vec<PositionLine> {
    let df = p.resolution_per_mm;
    // Each line's search range and largest bin.
    let found: Vec<Found<'_>> = p
        .auto
        .iter()
        .flat_map(|(s, psd)| (1..=harmonics).map(move |k| (*s, psd.as_slice(), k)))
        .filter_map(|(s, psd, k)| {
            let f = k as f64 * p.line_per_mm;
            let lo = ((0.75 * f / df).ceil() as usize).max(1);
            let hi = ((1.25 * f / df).floor() as usize).min(psd.len().saturating_sub(3));
            if lo + 2 > hi {
                return None;
            }
            let i = (lo..=hi)
                .max_by(|&a, &b| psd[a].total_cmp(&psd[b]))
                .expect("non-empty");
            (psd[i] > 0.0).then_some((s, psd, k, lo, hi, i))
        })
        .collect();
    // Each line located between the bins around its largest one, the lines
    // of one signal searched together, the signals in parallel (rayon).
    let measured: Vec<f64> = p
        .auto
        .par_iter()
        .map(|(s, _)| {
            let bins: Vec<usize> = found.iter().filter(|l| l.0 == *s).map(|l| l.5).collect();
            let ranges: Vec<(f64, f64)> = bins
                .iter()
                .map(|&i| ((i as f64 - 1.0) * df, (i as f64 + 1.0) * df))
                .collect();
            scan.and_then(|scan| scan.peaks(*s, &ranges))
                .unwrap_or_else(|| bins.iter().map(|&i| i as f64 * df).collect())
        })
        .collect::<Vec<Vec<f64>>>()
        .concat();
    found
        .into_iter()
        .zip(measured)
        .map(|((s, psd, k, lo, hi, i), measured)| {
            let s = &s;
            let f = k as f64 * p.line_per_mm;
            // The power is summed around the predicted line's bin, not the
            // largest one: where the line is weak, the largest bin of a
            // ±25 % search is often a peak of the floor's scatter, and
            // summing around it would bias the power up.
            let i0 = ((f / df).round() as usize).clamp(lo, hi);
            // Floor: the bins within ±50 % of k·f_line, more than 2 bins
            // from the line and from the neighbouring harmonics.
            let flo = ((0.5 * f / df).ceil() as usize).max(1);
            let fhi = ((1.5 * f / df).floor() as usize).min(psd.len() - 1);
            let rest: Vec<f64> = (flo..=fhi)
                .filter(|&j| {
                    let h = (j as f64 * df / p.line_per_mm).round();
                    j.abs_diff(i0) > 2 && (j as f64 * df - h * p.line_per_mm).abs() > 2.0 * df
                })
                .map(|j| psd[j])
                .collect();
            // The median of bins distributed S·χ²_ν/ν is S times the median
            // of χ²_ν/ν: divided by it, the floor is the mean level S the
            // line's bins carry too.
            let floor = median(&rest).unwrap_or(0.0) / chi2_median_over_nu(p.dof);
            let summed = i0.saturating_sub(2)..=(i0 + 2).min(psd.len() - 1);
            let floor_power = floor * summed.clone().count() as f64 * df;
            // Unclamped per bin (a bin below the floor is the floor's
            // scatter, and clamping it would bias the power up).
            let power = summed.map(|j| (psd[j] - floor) * df).sum::<f64>().max(0.0);
            let band = p
                .band
                .map(|b| line_amplitude_band(power, floor_power, [b.lower_factor, b.upper_factor]));
            PositionLine {
                signal: *s,
                k,
                predicted_per_mm: f,
                measured_per_mm: measured,
                deviation_percent: 100.0 * (measured - f) / f,
                power,
                rms: power.sqrt(),
                unit: s.unit(),
                ratio_db: if floor > 0.0 {
                    10.0 * (psd[i] / floor).log10()
                } else {
                    f64::INFINITY
                },
                floor_power,
                floor_bins: rest.len(),
                amplitude: (2.0 * power).sqrt(),
                amplitude_lower: band.map(|b| b[0]),
                amplitude_upper: band.map(|b| b[1]),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean power of the segments of `s` at `f`, one frequency at a
    /// time (the kernel is itself held bit for bit to a one-frequency,
    /// one-segment loop in `ballpass_dsp::segment_power`'s tests).
    fn power_alone(scan: &LineScan, s: Signal, f: f64) -> f64 {
        let segs: Vec<&[f64]> = scan
            .segments
            .iter()
            .filter(|(t, _)| *t == s)
            .map(|(_, seg)| seg.as_slice())
            .collect();
        ballpass_dsp::segment_powers(&segs, scan.dx, &[f]).expect("the scan's segments are valid")
            [0]
    }

    /// One range searched alone, one frequency at a time: the reference
    /// [`LineScan::peaks`] must equal bit for bit.
    pub(super) fn peak_alone(scan: &LineScan, s: Signal, lo: f64, hi: f64) -> f64 {
        let n = 64;
        let h = (hi - lo) / n as f64;
        let grid: Vec<f64> = (0..=n).map(|j| lo + j as f64 * h).collect();
        let p: Vec<f64> = grid.iter().map(|&f| power_alone(scan, s, f)).collect();
        let best = (0..=n)
            .max_by(|&a, &b| p[a].total_cmp(&p[b]))
            .map(|j| grid[j])
            .expect("grid");
        // Golden section, each step measuring the one new interior point.
        let (mut a, mut b) = ((best - h).max(lo), (best + h).min(hi));
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
        let (mut pc, mut pd) = (power_alone(scan, s, c), power_alone(scan, s, d));
        while b - a > 1e-4 * h {
            if pc >= pd {
                (b, d, pd) = (d, c, pc);
                c = b - g * (b - a);
                pc = power_alone(scan, s, c);
            } else {
                (a, c, pc) = (c, d, pd);
                d = a + g * (b - a);
                pd = power_alone(scan, s, d);
            }
        }
        0.5 * (a + b)
    }

    #[test]
    fn ranges_searched_together_equal_each_alone_bit_for_bit() {
        // Two signals, runs of 2600 and 1100 points (several segments of
        // 1024, one run with one): lines near 0.123 and 0.246 cycles/mm
        // plus deterministic noise.
        let dx = 0.127;
        let w = ballpass_dsp::Window::Hann.values(1024).unwrap();
        let mut scan = LineScan::new(&w, dx);
        let mut state = 7u64;
        let mut noise = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for (s, len) in [
            (Signal::Friction, 2600),
            (Signal::VelocityError, 2600),
            (Signal::Friction, 1100),
        ] {
            let x: Vec<f64> = (0..len)
                .map(|i| {
                    let t = std::f64::consts::TAU * i as f64 * dx;
                    (0.123 * t).sin() + 0.4 * (0.246 * t).sin() + 0.3 * noise()
                })
                .collect();
            scan.add(s, &x);
        }
        let bin = 1.0 / (1024.0 * dx);
        // Ranges of different widths, so that the golden sections stop
        // after different numbers of steps.
        let ranges = [
            (0.123 - bin, 0.123 + bin),
            (0.246 - 1.3 * bin, 0.246 + 0.7 * bin),
            (0.05, 0.05 + 0.2 * bin),
            (0.3, 0.3 + 3.0 * bin),
        ];
        for s in [Signal::Friction, Signal::VelocityError] {
            let together: Vec<u64> = scan
                .peaks(s, &ranges)
                .unwrap()
                .iter()
                .map(|f| f.to_bits())
                .collect();
            let alone: Vec<u64> = ranges
                .iter()
                .map(|&(lo, hi)| peak_alone(&scan, s, lo, hi).to_bits())
                .collect();
            assert_eq!(together, alone, "{s:?}");
            let one: Vec<u64> = ranges
                .iter()
                .map(|&r| scan.peaks(s, &[r]).unwrap()[0].to_bits())
                .collect();
            assert_eq!(one, alone, "{s:?}");
        }
        // The search finds the lines (the grid is 1/(1024 dx) wide per bin).
        let f = scan.peaks(Signal::Friction, &ranges[..2]).unwrap();
        assert!((f[0] - 0.123).abs() < 0.1 * bin, "{f:?}");
        assert!((f[1] - 0.246).abs() < 0.1 * bin, "{f:?}");
        // No segments of a signal: nothing to search.
        assert_eq!(scan.peaks(Signal::Optical, &ranges), None);
    }
}
