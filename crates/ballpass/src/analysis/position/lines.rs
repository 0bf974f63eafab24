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
pub(super) struct LineScan {
    window: Vec<f64>,
    dx: f64,
    segments: Vec<(Signal, Vec<f64>)>,
}

impl LineScan {
    pub(super) fn new(window: &[f64], dx: f64) -> Self {
        LineScan {
            window: window.to_vec(),
            dx,
            segments: Vec::new(),
        }
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

    /// Mean power of the segments of `s` at each frequency of `freqs`
    /// (cycles/mm), `L` frequencies in lock step.
    ///
    /// Per frequency, exactly the arithmetic of one frequency alone
    /// ([`tests::power_alone`] is the reference, checked bit for bit): a
    /// phasor `e^{−i step n}` rotated sample by sample and renormalised
    /// every 256 points, and per segment `Σ v·pr`, `−Σ v·pi` in sample
    /// order. The phasor does not depend on the segment, so it is made
    /// once for all of them, and `L` independent frequencies keep the
    /// processor busy where one is a chain of dependent multiplications.
    fn powers<const L: usize>(&self, s: Signal, freqs: &[f64]) -> Vec<f64> {
        let n = self.window.len();
        let segs: Vec<&[f64]> = self
            .segments
            .iter()
            .filter(|(t, _)| *t == s)
            .map(|(_, v)| v.as_slice())
            .collect();
        let count = segs.len().max(1) as f64;
        let mut table = vec![([0.0f64; L], [0.0f64; L]); n];
        let mut out = Vec::with_capacity(freqs.len());
        for chunk in freqs.chunks(L) {
            // Unused lanes rotate by zero (cos 1, sin 0) and are dropped.
            let (mut c, mut sn) = ([1.0f64; L], [0.0f64; L]);
            for (j, f) in chunk.iter().enumerate() {
                let step = std::f64::consts::TAU * f * self.dx;
                (c[j], sn[j]) = (step.cos(), step.sin());
            }
            let (mut pr, mut pi) = ([1.0f64; L], [0.0f64; L]);
            for (k, slot) in table.iter_mut().enumerate() {
                *slot = (pr, pi);
                for j in 0..L {
                    let t = pr[j] * c[j] - pi[j] * sn[j];
                    pi[j] = pr[j] * sn[j] + pi[j] * c[j];
                    pr[j] = t;
                }
                if k % 256 == 255 {
                    for j in 0..L {
                        let a = (pr[j] * pr[j] + pi[j] * pi[j]).sqrt();
                        pr[j] /= a;
                        pi[j] /= a;
                    }
                }
            }
            let mut total = [0.0f64; L];
            for seg in &segs {
                let (mut re, mut im) = ([0.0f64; L], [0.0f64; L]);
                for (v, (pr, pi)) in seg.iter().zip(&table) {
                    for j in 0..L {
                        re[j] += v * pr[j];
                        im[j] -= v * pi[j];
                    }
                }
                for j in 0..L {
                    total[j] += re[j] * re[j] + im[j] * im[j];
                }
            }
            out.extend(total[..chunk.len()].iter().map(|t| t / count));
        }
        out
    }

    /// Frequency of the largest mean power in `[lo, hi]`: a grid of 64
    /// steps, then golden-section refinement of the best step to 1e-4 of
    /// a step.
    fn peak(&self, s: Signal, lo: f64, hi: f64) -> f64 {
        let n = 64;
        let h = (hi - lo) / n as f64;
        let grid: Vec<f64> = (0..=n).map(|j| lo + j as f64 * h).collect();
        let p = self.powers::<8>(s, &grid);
        // The last of equal maxima, as `Iterator::max_by` picks.
        let best = (0..=n)
            .max_by(|&a, &b| p[a].total_cmp(&p[b]))
            .map(|j| grid[j])
            .expect("grid");
        let (mut a, mut b) = ((best - h).max(lo), (best + h).min(hi));
        let g = 0.5 * (5f64.sqrt() - 1.0);
        while b - a > 1e-4 * h {
            let (c, d) = (b - g * (b - a), a + g * (b - a));
            let p = self.powers::<2>(s, &[c, d]);
            if p[0] >= p[1] {
                b = d;
            } else {
                a = c;
            }
        }
        0.5 * (a + b)
    }
}

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
    let wanted: Vec<(Signal, &[f64], usize)> = p
        .auto
        .iter()
        .flat_map(|(s, psd)| (1..=harmonics).map(move |k| (*s, psd.as_slice(), k)))
        .collect();
    wanted
        .into_par_iter()
        .filter_map(|(s, psd, k)| {
            let s = &s;
            let f = k as f64 * p.line_per_mm;
            let lo = ((0.75 * f / df).ceil() as usize).max(1);
            let hi = ((1.25 * f / df).floor() as usize).min(psd.len().saturating_sub(3));
            if lo + 2 > hi {
                return None;
            }
            let i = (lo..=hi)
                .max_by(|&a, &b| psd[a].total_cmp(&psd[b]))
                .expect("non-empty");
            if psd[i] <= 0.0 {
                return None;
            }
            let measured = match scan {
                Some(scan) => scan.peak(*s, (i as f64 - 1.0) * df, (i as f64 + 1.0) * df),
                None => i as f64 * df,
            };
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
            Some(PositionLine {
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
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean power of the segments of `s` at `f`, one frequency and one
    /// segment at a time: the reference [`LineScan::powers`] must equal
    /// bit for bit.
    pub(super) fn power_alone(scan: &LineScan, s: Signal, f: f64) -> f64 {
        let step = std::f64::consts::TAU * f * scan.dx;
        let (c, sn) = (step.cos(), step.sin());
        let mut total = 0.0;
        let mut count = 0usize;
        for (_, seg) in scan.segments.iter().filter(|(t, _)| *t == s) {
            let (mut re, mut im) = (0.0, 0.0);
            let (mut pr, mut pi) = (1.0f64, 0.0f64);
            for (n, v) in seg.iter().enumerate() {
                re += v * pr;
                im -= v * pi;
                let t = pr * c - pi * sn;
                pi = pr * sn + pi * c;
                pr = t;
                if n % 256 == 255 {
                    let a = (pr * pr + pi * pi).sqrt();
                    pr /= a;
                    pi /= a;
                }
            }
            total += re * re + im * im;
            count += 1;
        }
        total / count.max(1) as f64
    }

    #[test]
    fn powers_in_lock_step_equal_one_frequency_at_a_time_bit_for_bit() {
        // Two signals, runs of 2600 and 1100 points (several segments of
        // 1024, one run with one): a line near 0.123 cycles/mm plus
        // deterministic noise.
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
                .map(|i| (std::f64::consts::TAU * 0.123 * i as f64 * dx).sin() + 0.3 * noise())
                .collect();
            scan.add(s, &x);
        }
        let freqs: Vec<f64> = (0..37).map(|j| 0.05 + 0.0071 * j as f64).collect();
        for s in [Signal::Friction, Signal::VelocityError, Signal::Optical] {
            let alone: Vec<u64> = freqs
                .iter()
                .map(|&f| power_alone(&scan, s, f).to_bits())
                .collect();
            let eight: Vec<u64> = scan
                .powers::<8>(s, &freqs)
                .iter()
                .map(|p| p.to_bits())
                .collect();
            let two: Vec<u64> = scan
                .powers::<2>(s, &freqs)
                .iter()
                .map(|p| p.to_bits())
                .collect();
            assert_eq!(eight, alone, "{s:?}");
            assert_eq!(two, alone, "{s:?}");
        }
        // The peak search finds the line (the grid is 1/(1024 dx) wide per bin).
        let f = scan.peak(Signal::Friction, 0.11, 0.135);
        assert!((f - 0.123).abs() < 0.1 / (1024.0 * dx), "{f}");
    }
}
