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

use crate::recording::stream::Block;
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

/// The label of a channel in the signals figure.
fn label(c: Channel) -> &'static str {
    match c {
        Channel::Friction => "Friction force",
        Channel::Position => "Position",
        Channel::Optical => "Optical sensor",
    }
}

/// The samples one channel adds to the signals figures.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelSamples {
    /// The channel.
    pub channel: Channel,
    /// Indices of the samples drawn in the signals figure (every one, or
    /// the envelope's), increasing.
    pub index: Vec<usize>,
    /// The samples at [`ChannelSamples::index`].
    pub values: Vec<f64>,
    /// The samples of the detail figure (empty without one).
    pub detail: Vec<f64>,
}

/// The samples the signals figures of one record draw, gathered from the
/// record whole ([`SignalSamples::of`]) or block by block
/// ([`SignalGatherer`], for a streamed record): the same samples either
/// way, a few thousand per channel for a long record.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalSamples {
    /// The record's name.
    pub source_name: String,
    /// Samples per channel in the record.
    pub len: usize,
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Time of the first sample, s.
    pub start_time_s: f64,
    /// Index of the detail figure's first sample (`None` without one).
    pub detail_start: Option<usize>,
    /// Each channel present, in canonical order.
    pub channels: Vec<ChannelSamples>,
}

/// Where the detail figure of a record of `len` samples at `fs` starts
/// and how long it is: [`DETAIL_PERIODS`] periods `tau_c_s` from its
/// middle; `None` for a record drawn sample by sample anyway, or a period
/// that is not a positive number.
fn detail_span(len: usize, fs: f64, tau_c_s: f64) -> Option<(usize, usize)> {
    if len <= ENVELOPE_ABOVE_SAMPLES || !(tau_c_s.is_finite() && tau_c_s > 0.0) {
        return None;
    }
    let n = ((DETAIL_PERIODS * tau_c_s * fs).ceil() as usize).clamp(2, len);
    Some(((len - n) / 2, n))
}

impl SignalSamples {
    /// The samples of `rec`'s figures, the detail at the period `tau_c_s`.
    pub fn of(rec: &Recording, tau_c_s: f64) -> Self {
        let span = detail_span(rec.len(), rec.fs_hz(), tau_c_s);
        let channels = Channel::ALL
            .iter()
            .filter_map(|&c| {
                let v = rec.channel(c)?;
                let index = if rec.len() <= ENVELOPE_ABOVE_SAMPLES {
                    (0..v.len()).collect()
                } else {
                    envelope_indices(v, ENVELOPE_BUCKETS)
                };
                Some(ChannelSamples {
                    channel: c,
                    values: index.iter().map(|&i| v[i]).collect(),
                    index,
                    detail: span.map_or_else(Vec::new, |(s, n)| v[s..s + n].to_vec()),
                })
            })
            .collect();
        SignalSamples {
            source_name: rec.source_name(),
            len: rec.len(),
            fs_hz: rec.fs_hz(),
            start_time_s: rec.meta.start_time_s,
            detail_start: span.map(|(s, _)| s),
            channels,
        }
    }

    fn time_s(&self, i: usize) -> f64 {
        self.start_time_s + i as f64 / self.fs_hz
    }

    /// Drawn as envelopes (not sample by sample).
    fn enveloped(&self) -> bool {
        self.len > ENVELOPE_ABOVE_SAMPLES
    }
}

/// Per channel: the running envelope of the current stretch.
#[derive(Debug, Clone)]
struct Stretch {
    out: ChannelSamples,
    /// Current stretch and its bounds.
    bucket: usize,
    lo: usize,
    hi: usize,
    first: f64,
    min: (usize, f64),
    max: (usize, f64),
    last: f64,
}

/// [`SignalSamples`] gathered block by block: the envelopes (or every
/// sample of a record drawn sample by sample) from one reading of the
/// record ([`SignalGatherer::push`]), the detail from another once the
/// period is known ([`SignalGatherer::detail_at`],
/// [`SignalGatherer::push_detail`]). Keeps what
/// [`envelope_indices`] keeps, chosen by the same comparisons in the same
/// order, so the samples equal [`SignalSamples::of`]'s.
#[derive(Debug, Clone)]
pub struct SignalGatherer {
    samples: SignalSamples,
    stretches: Vec<Stretch>,
    at: usize,
    detail: Option<(usize, usize)>,
    detail_at: usize,
}

impl SignalGatherer {
    /// A record `source_name` of `len` samples at `fs_hz` from
    /// `start_time_s`, with `channels`.
    pub fn new(
        source_name: String,
        len: usize,
        fs_hz: f64,
        start_time_s: f64,
        channels: &[Channel],
    ) -> Self {
        let stretches = Channel::ALL
            .iter()
            .filter(|c| channels.contains(c))
            .map(|&channel| Stretch {
                out: ChannelSamples {
                    channel,
                    index: Vec::new(),
                    values: Vec::new(),
                    detail: Vec::new(),
                },
                bucket: 0,
                lo: 0,
                hi: 0,
                first: f64::NAN,
                min: (0, f64::NAN),
                max: (0, f64::NAN),
                last: f64::NAN,
            })
            .collect();
        SignalGatherer {
            samples: SignalSamples {
                source_name,
                len,
                fs_hz,
                start_time_s,
                detail_start: None,
                channels: Vec::new(),
            },
            stretches,
            at: 0,
            detail: None,
            detail_at: 0,
        }
    }

    /// The next samples of the record, in order from its start.
    pub fn push(&mut self, b: Block<'_>) {
        let (len, all) = (self.samples.len, !self.samples.enveloped());
        for st in &mut self.stretches {
            let Some(y) = b.channel(st.out.channel) else {
                continue;
            };
            for (k, &v) in y.iter().enumerate() {
                let i = self.at + k;
                if all {
                    st.out.index.push(i);
                    st.out.values.push(v);
                    continue;
                }
                if i == st.hi {
                    // A new stretch (stretches are never empty here: the
                    // record has more than 4 per stretch).
                    st.lo = st.bucket * len / ENVELOPE_BUCKETS;
                    st.hi = (st.bucket + 1) * len / ENVELOPE_BUCKETS;
                    st.bucket += 1;
                    st.first = v;
                    st.min = (i, v);
                    st.max = (i, v);
                }
                // The comparisons of `envelope_indices`, in its order.
                if v < st.min.1 || st.min.1.is_nan() {
                    st.min = (i, v);
                }
                if v > st.max.1 || st.max.1.is_nan() {
                    st.max = (i, v);
                }
                st.last = v;
                if i + 1 == st.hi {
                    let mut four = [(st.lo, st.first), st.min, st.max, (st.hi - 1, st.last)];
                    four.sort_unstable_by_key(|p| p.0);
                    for (j, x) in four {
                        if st.out.index.last() != Some(&j) {
                            st.out.index.push(j);
                            st.out.values.push(x);
                        }
                    }
                }
            }
        }
        self.at += b.len();
    }

    /// The detail figure at the period `tau_c_s`; its samples come from
    /// a new reading of the record through [`SignalGatherer::push_detail`].
    pub fn detail_at(&mut self, tau_c_s: f64) {
        let s = &self.samples;
        self.detail = detail_span(s.len, s.fs_hz, tau_c_s);
        self.detail_at = 0;
        for st in &mut self.stretches {
            st.out.detail.clear();
        }
    }

    /// The next samples of the record for the detail, in order from its start.
    pub fn push_detail(&mut self, b: Block<'_>) {
        let n = b.len();
        if let Some((start, len)) = self.detail {
            let (lo, hi) = (
                start.max(self.detail_at),
                (start + len).min(self.detail_at + n),
            );
            if lo < hi {
                for st in &mut self.stretches {
                    if let Some(y) = b.channel(st.out.channel) {
                        st.out
                            .detail
                            .extend_from_slice(&y[lo - self.detail_at..hi - self.detail_at]);
                    }
                }
            }
        }
        self.detail_at += n;
    }

    /// The samples gathered.
    pub fn finish(self) -> SignalSamples {
        SignalSamples {
            detail_start: self.detail.map(|(s, _)| s),
            channels: self.stretches.into_iter().map(|s| s.out).collect(),
            ..self.samples
        }
    }
}

/// The signals figure of a record: every sample up to
/// [`ENVELOPE_ABOVE_SAMPLES`], else each channel's envelope (module docs).
pub fn signals(id: &str, title: &str, s: &SignalSamples) -> Figure {
    let mut fig = Figure::new(id, title);
    for (k, c) in s.channels.iter().enumerate() {
        let (label, unit) = (label(c.channel), c.channel.unit());
        let t = c.index.iter().map(|&i| s.time_s(i)).collect();
        fig.panels.push(
            Panel::new(Axis::linear("Time", "s"), Axis::linear(label, unit))
                .with_series(Series::line(label, t, c.values.clone()).with_color(Rgb::palette(k))),
        );
    }
    fig.panel_height_px = 220;
    fig.interactive()
}

/// Words for the caption of [`signals`] (empty when it is drawn sample by
/// sample).
pub fn envelope_words(s: &SignalSamples) -> String {
    if !s.enveloped() {
        return String::new();
    }
    format!(
        " Each trace is drawn as its envelope: the first, last, smallest and largest sample of \
         each of {ENVELOPE_BUCKETS} stretches of {} samples ({} s).",
        s.len / ENVELOPE_BUCKETS,
        fmt_sig(s.len as f64 / ENVELOPE_BUCKETS as f64 / s.fs_hz, 3)
    )
}

/// [`DETAIL_PERIODS`] ball periods from the record's middle, sample by
/// sample (`None` when the samples have no detail).
pub fn detail(id: &str, title: &str, s: &SignalSamples) -> Option<Figure> {
    let start = s.detail_start?;
    let n = s.channels.first().map_or(0, |c| c.detail.len());
    let t: Vec<f64> = (start..start + n).map(|i| s.time_s(i)).collect();
    let traces: Vec<Trace<'_>> = s
        .channels
        .iter()
        .map(|c| Trace {
            label: label(c.channel),
            unit: c.channel.unit(),
            values: &c.detail,
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

    /// A long record (enveloped, with a detail) gathered block by block in
    /// uneven blocks gives exactly the samples taken from it whole: the
    /// same stretches, the same comparisons in the same order. Quantised
    /// values make many ties, where the first extreme must win.
    #[test]
    fn gathered_block_by_block_the_samples_equal_the_whole_records() {
        use crate::recording::stream::{RecordSource, RecordingSource};
        use crate::recording::{Channels, Metadata};
        let n = ENVELOPE_ABOVE_SAMPLES + 12_345;
        let wave = |k: f64| -> Vec<f64> {
            (0..n)
                .map(|i| ((i as f64 * k).sin() * 7.0 + (i % 13) as f64 * 0.5).round())
                .collect()
        };
        let rec = Recording::new(
            1000.0,
            Channels {
                friction_n: Some(wave(0.0013)),
                position_mm: None,
                optical_v: Some(wave(0.0101)),
            },
            Metadata {
                start_time_s: 2.5,
                ..Default::default()
            },
        )
        .expect("valid");
        let tau = 0.61;
        let whole = SignalSamples::of(&rec, tau);
        assert_eq!(whole.channels.len(), 2);
        assert!(whole.detail_start.is_some());
        assert!(whole.channels[0].index.len() > 3 * ENVELOPE_BUCKETS);
        for block in [1 << 16, 4099, 999_983] {
            let mut src = RecordingSource::new(&rec, block);
            let mut g = SignalGatherer::new(
                src.source_name(),
                src.len(),
                src.fs_hz(),
                src.meta().start_time_s,
                &src.channels(),
            );
            src.pass(&mut |b| {
                g.push(b);
                Ok(())
            })
            .expect("reads");
            g.detail_at(tau);
            src.pass(&mut |b| {
                g.push_detail(b);
                Ok(())
            })
            .expect("reads");
            assert_eq!(g.finish(), whole, "blocks of {block}");
        }
    }
}
