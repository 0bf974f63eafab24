//! Long signals in the report: each trace drawn as its envelope, and a
//! detail of a few ball periods at full resolution beside it.
//!
//! A record of hours holds millions of samples per channel and thousands
//! of ball periods: drawn sample by sample it is a solid band, and the
//! figure (and its copy in the interactive page) holds every sample. Above
//! [`ENVELOPE_ABOVE_SAMPLES`] the signals figure keeps, of each of
//! [`ENVELOPE_BUCKETS`] equal stretches of samples, its first, last,
//! smallest and largest sample in time order (the M4 aggregation the
//! renderer applies per pixel column anyway, so the picture is the same),
//! and a second figure shows [`DETAIL_PERIODS`] ball periods from the
//! middle of the record sample by sample.

use crate::recording::{Channel, Recording};
use crate::report::kinds::{self, fmt_sig, Trace};
use crate::report::{Axis, Figure, Panel, Rgb, Series};

/// Records longer than this many samples (2^20, 17 minutes at 1 kHz) are
/// drawn as envelopes with a detail figure; shorter ones sample by sample.
pub const ENVELOPE_ABOVE_SAMPLES: usize = 1 << 20;
/// Stretches of an envelope (each up to 4 points).
pub const ENVELOPE_BUCKETS: usize = 2000;
/// Ball periods in the detail figure.
pub const DETAIL_PERIODS: f64 = 5.0;

/// Indices of the first, smallest, largest and last sample of each of
/// `buckets` stretches of `y` (as equal as integer division makes them),
/// in increasing order without repeats; every index when `y` is no longer
/// than `4 * buckets`. A NaN is never chosen as the smallest or largest.
pub fn envelope_indices(y: &[f64], buckets: usize) -> Vec<usize> {
    let n = y.len();
    if n <= 4 * buckets.max(1) {
        return (0..n).collect();
    }
    let mut out = Vec::with_capacity(4 * buckets);
    for b in 0..buckets {
        let (lo, hi) = (b * n / buckets, (b + 1) * n / buckets);
        let (mut imin, mut imax) = (lo, lo);
        for i in lo..hi {
            if y[i] < y[imin] || y[imin].is_nan() {
                imin = i;
            }
            if y[i] > y[imax] || y[imax].is_nan() {
                imax = i;
            }
        }
        let mut four = [lo, imin, imax, hi - 1];
        four.sort_unstable();
        for i in four {
            if out.last() != Some(&i) {
                out.push(i);
            }
        }
    }
    out
}

/// The channels of `rec` as the signals figure labels them.
fn traces(rec: &Recording) -> Vec<Trace<'_>> {
    Channel::ALL
        .iter()
        .filter_map(|&c| {
            rec.channel(c).map(|v| Trace {
                label: match c {
                    Channel::Friction => "Friction force",
                    Channel::Position => "Position",
                    Channel::Optical => "Optical sensor",
                },
                unit: c.unit(),
                values: v,
            })
        })
        .collect()
}

/// The signals figure of a record: every sample up to
/// [`ENVELOPE_ABOVE_SAMPLES`], else each channel's envelope (module docs).
pub fn signals(id: &str, title: &str, rec: &Recording) -> Figure {
    let traces = traces(rec);
    if rec.len() <= ENVELOPE_ABOVE_SAMPLES {
        let t: Vec<f64> = (0..rec.len()).map(|i| rec.time_s(i)).collect();
        return kinds::time_series_stack(id, title, &t, &traces);
    }
    let mut fig = Figure::new(id, title);
    for (k, tr) in traces.iter().enumerate() {
        let idx = envelope_indices(tr.values, ENVELOPE_BUCKETS);
        let t = idx.iter().map(|&i| rec.time_s(i)).collect();
        let y = idx.iter().map(|&i| tr.values[i]).collect();
        fig.panels.push(
            Panel::new(Axis::linear("Time", "s"), Axis::linear(tr.label, tr.unit))
                .with_series(Series::line(tr.label, t, y).with_color(Rgb::palette(k))),
        );
    }
    fig.panel_height_px = 220;
    fig.interactive()
}

/// Words for the caption of [`signals`] on `rec` (empty when it is drawn
/// sample by sample).
pub fn envelope_words(rec: &Recording) -> String {
    if rec.len() <= ENVELOPE_ABOVE_SAMPLES {
        return String::new();
    }
    format!(
        " Each trace is drawn as its envelope: the first, last, smallest and largest sample of \
         each of {ENVELOPE_BUCKETS} stretches of {} samples ({} s).",
        rec.len() / ENVELOPE_BUCKETS,
        fmt_sig(rec.len() as f64 / ENVELOPE_BUCKETS as f64 / rec.fs_hz(), 3)
    )
}

/// [`DETAIL_PERIODS`] periods `tau_c_s` of `rec` from its middle, sample
/// by sample; `None` for a record drawn sample by sample anyway, or a
/// period that is not a positive number.
pub fn detail(id: &str, title: &str, rec: &Recording, tau_c_s: f64) -> Option<Figure> {
    if rec.len() <= ENVELOPE_ABOVE_SAMPLES || !(tau_c_s.is_finite() && tau_c_s > 0.0) {
        return None;
    }
    let len = ((DETAIL_PERIODS * tau_c_s * rec.fs_hz()).ceil() as usize).clamp(2, rec.len());
    let start = (rec.len() - len) / 2;
    let t: Vec<f64> = (start..start + len).map(|i| rec.time_s(i)).collect();
    let traces: Vec<Trace<'_>> = traces(rec)
        .into_iter()
        .map(|tr| Trace {
            values: &tr.values[start..start + len],
            ..tr
        })
        .collect();
    Some(kinds::time_series_stack(id, title, &t, &traces))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_envelope_keeps_each_stretchs_first_last_and_extremes_in_order() {
        // Two stretches of 20 samples.
        let y: Vec<f64> = (0..40)
            .map(|i| match i {
                3 => 9.0,
                7 => -5.0,
                25 => -8.0,
                33 => 7.0,
                _ => (i % 3) as f64,
            })
            .collect();
        let idx = envelope_indices(&y, 2);
        // Stretch 0 = 0..20: first 0, max 3, min 7, last 19; stretch 1 =
        // 20..40: first 20, min 25, max 33, last 39.
        assert_eq!(idx, vec![0, 3, 7, 19, 20, 25, 33, 39]);
        // Short signals keep every sample.
        assert_eq!(envelope_indices(&y, 10), (0..40).collect::<Vec<_>>());
    }

    #[test]
    fn an_envelope_has_the_extremes_of_the_signal_and_never_a_nan() {
        let mut y: Vec<f64> = (0..100_000)
            .map(|i| (i as f64 * 0.001).sin() * (1.0 + (i % 97) as f64 * 0.01))
            .collect();
        y[0] = f64::NAN;
        y[50_000] = f64::NAN;
        let idx = envelope_indices(&y, 100);
        assert!(idx.len() <= 400 && idx.windows(2).all(|w| w[0] < w[1]));
        let kept: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
        let finite = |v: &[f64], f: fn(f64, f64) -> f64, init: f64| {
            v.iter().copied().filter(|x| !x.is_nan()).fold(init, f)
        };
        assert_eq!(
            finite(&kept, f64::max, f64::NEG_INFINITY),
            finite(&y, f64::max, f64::NEG_INFINITY)
        );
        assert_eq!(
            finite(&kept, f64::min, f64::INFINITY),
            finite(&y, f64::min, f64::INFINITY)
        );
        // Only a stretch's first sample can be a NaN (it is kept as its
        // start, never as an extreme): here samples 0 and 50 000.
        let nans: Vec<usize> = idx.iter().copied().filter(|&i| y[i].is_nan()).collect();
        assert_eq!(nans, vec![0, 50_000]);
    }
}
