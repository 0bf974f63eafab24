//! Zero-phase filtering of a signal that arrives in pieces, in memory that
//! does not grow with its length.
//!
//! [`ZeroPhaseFilter::apply`] runs the backward pass from the last sample
//! of the whole signal, so it needs the whole signal. [`ZeroPhaseStream`]
//! runs the forward pass exactly as it does (the same left extension and
//! initial state, its state carried from piece to piece) and the backward
//! pass block by block: the forward output `y[a .. a + B + P]` is filtered
//! backward from the steady state of its last value, and only
//! `y[a .. a + B]` is kept. The backward pass started `P` samples late
//! differs from the whole-signal one by a transient that decays as the
//! slowest pole, `r^P`; `P` is chosen from the filter's poles so that
//! `r^P <= 1e-16` twice over ([`ZeroPhaseStream::overlap_for`]). The last
//! block runs from the right extension, exactly as the whole-signal filter.
//!
//! So the output equals [`ZeroPhaseFilter::apply`]'s to within rounding
//! and that decayed transient: tested below on noise with steps and a
//! ramp at `1e-12` of the signal's largest value.
//!
//! Memory: `B + P` samples of forward output plus the extension length.

use crate::error::{check_finite, DspError, Result};
use crate::sos::{PadType, ZeroPhaseFilter};

/// Backward decay required of the transient of a late-started block.
const DECAY: f64 = 1e-16;

/// A [`ZeroPhaseFilter`] run on a signal given in pieces
/// ([`ZeroPhaseStream::push`]), which returns the filtered samples in
/// order as they are settled, and the rest at [`ZeroPhaseStream::finish`].
#[derive(Debug)]
pub struct ZeroPhaseStream<'f> {
    f: &'f ZeroPhaseFilter,
    overlap: usize,
    block: usize,
    /// Raw samples held until the left extension can be made.
    head: Vec<f64>,
    started: bool,
    /// Forward DF-II-T state.
    z: Vec<[f64; 2]>,
    /// The last `pad_len + 1` raw samples (the right extension's source).
    tail: Vec<f64>,
    /// Forward output not yet settled.
    pending: Vec<f64>,
}

impl<'f> ZeroPhaseStream<'f> {
    /// A stream through `filter`, settling at least `min_block` samples at
    /// a time (the backward pass reruns `overlap` samples per block, so a
    /// block several times the overlap keeps the extra work small).
    pub fn new(filter: &'f ZeroPhaseFilter, min_block: usize) -> ZeroPhaseStream<'f> {
        let overlap = Self::overlap_for(filter);
        ZeroPhaseStream {
            f: filter,
            overlap,
            block: min_block.max(1),
            head: Vec::new(),
            started: false,
            z: Vec::new(),
            tail: Vec::new(),
            pending: Vec::new(),
        }
    }

    /// Samples the backward pass of a block runs past its end: twice the
    /// number after which the slowest pole's transient has decayed to
    /// `1e-16` (so also a double pole's `k r^k`), at least 64.
    pub fn overlap_for(filter: &ZeroPhaseFilter) -> usize {
        let r = filter
            .sos()
            .sections()
            .iter()
            .map(|s| {
                let (a1, a2) = (s[4] / s[3], s[5] / s[3]);
                let disc = a1 * a1 - 4.0 * a2;
                if disc < 0.0 {
                    a2.abs().sqrt()
                } else {
                    let q = disc.sqrt();
                    ((-a1 + q) / 2.0).abs().max(((-a1 - q) / 2.0).abs())
                }
            })
            .fold(0.0_f64, f64::max);
        if !(r > 0.0 && r < 1.0) {
            // FIR sections (no transient) or an unstable filter (whose
            // whole-signal result is meaningless anyway): the minimum.
            return 64;
        }
        let k = (DECAY.ln() / r.ln()).ceil();
        (2.0 * k).clamp(64.0, 1e9) as usize
    }

    /// The overlap in use, samples.
    pub fn overlap(&self) -> usize {
        self.overlap
    }

    /// Feeds the next samples; appends the samples settled so far to `out`.
    ///
    /// # Errors
    /// [`DspError::NonFinite`] for a non-finite sample.
    pub fn push(&mut self, x: &[f64], out: &mut Vec<f64>) -> Result<()> {
        if x.is_empty() {
            return Ok(());
        }
        check_finite("x", x)?;
        if self.started {
            self.forward(x, out);
            return Ok(());
        }
        self.head.extend_from_slice(x);
        if self.head.len() > self.f.pad_len {
            self.start(out);
        }
        Ok(())
    }

    /// Ends the signal: appends the remaining filtered samples to `out`.
    ///
    /// # Errors
    /// [`DspError::Empty`] for no samples, [`DspError::TooShort`] for a
    /// signal not longer than the padding (as [`ZeroPhaseFilter::apply`]).
    pub fn finish(mut self, out: &mut Vec<f64>) -> Result<()> {
        if !self.started {
            let edge = self.f.pad_len;
            if self.head.is_empty() {
                return Err(DspError::Empty { what: "x" });
            }
            if self.head.len() <= edge {
                return Err(DspError::TooShort {
                    what: "x (sosfiltfilt needs more samples than padlen)",
                    needed: edge + 1,
                    found: self.head.len(),
                });
            }
            self.start(out);
        }
        let edge = self.f.pad_len;
        let t = &self.tail;
        let last = t[t.len() - 1];
        let mut ext: Vec<f64> = match self.f.pad_type {
            PadType::Odd => (0..edge).map(|i| 2.0 * last - t[t.len() - 2 - i]).collect(),
            PadType::Even => (0..edge).map(|i| t[t.len() - 2 - i]).collect(),
            PadType::Constant => vec![last; edge],
            PadType::None => Vec::new(),
        };
        self.f.cascade.filter(&mut ext, &mut self.z, false);
        self.pending.extend_from_slice(&ext);
        let z = self.f.steady(self.pending[self.pending.len() - 1]);
        self.f.cascade.filter_from(&mut self.pending, &z, true);
        out.extend_from_slice(&self.pending[..self.pending.len() - edge]);
        Ok(())
    }

    /// The left extension and the forward state it leaves, then the held
    /// samples forward.
    fn start(&mut self, out: &mut Vec<f64>) {
        let edge = self.f.pad_len;
        let head = std::mem::take(&mut self.head);
        let first = head[0];
        let mut left: Vec<f64> = match self.f.pad_type {
            PadType::Odd => (0..edge).map(|i| 2.0 * first - head[edge - i]).collect(),
            PadType::Even => (0..edge).map(|i| head[edge - i]).collect(),
            PadType::Constant => vec![first; edge],
            PadType::None => Vec::new(),
        };
        let x0 = left.first().copied().unwrap_or(first);
        self.z = self.f.steady(x0);
        self.f.cascade.filter(&mut left, &mut self.z, false);
        self.started = true;
        self.forward(&head, out);
    }

    /// The forward pass over `x`, then every block that can be settled.
    fn forward(&mut self, x: &[f64], out: &mut Vec<f64>) {
        let keep = self.f.pad_len + 1;
        self.tail
            .extend_from_slice(&x[x.len().saturating_sub(keep)..]);
        if self.tail.len() > keep {
            self.tail.drain(..self.tail.len() - keep);
        }
        let at = self.pending.len();
        self.pending.extend_from_slice(x);
        self.f
            .cascade
            .filter(&mut self.pending[at..], &mut self.z, false);
        let span = self.block + self.overlap;
        let mut done = 0;
        let mut buf = Vec::new();
        while self.pending.len() - done >= span {
            buf.clear();
            buf.extend_from_slice(&self.pending[done..done + span]);
            let z = self.f.steady(buf[span - 1]);
            self.f.cascade.filter_from(&mut buf, &z, true);
            out.extend_from_slice(&buf[..self.block]);
            done += self.block;
        }
        self.pending.drain(..done);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::iir::{butter, cheby1, FilterBand};
    use crate::sos::{FiltFiltSettings, PadLen};

    /// Seeded noise with two steps and a ramp (xorshift), no dependency.
    fn signal(n: usize, mut s: u64) -> Vec<f64> {
        (0..n)
            .map(|i| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let u = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                let step =
                    if i > n / 3 { 5.0 } else { 0.0 } - if i > 2 * n / 3 { 7.0 } else { 0.0 };
                u + step + 1e-3 * i as f64
            })
            .collect()
    }

    fn streamed(f: &ZeroPhaseFilter, x: &[f64], piece: usize, block: usize) -> Vec<f64> {
        let mut s = ZeroPhaseStream::new(f, block);
        let mut out = Vec::new();
        for c in x.chunks(piece) {
            s.push(c, &mut out).unwrap();
        }
        s.finish(&mut out).unwrap();
        out
    }

    #[test]
    fn streamed_equals_whole_signal_filter() {
        let bw = butter(5, FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0).unwrap();
        let ch = cheby1(8, 0.05, FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0).unwrap();
        for (sos, pad) in [
            (bw.clone(), PadType::Odd),
            (ch, PadType::Odd),
            (bw.clone(), PadType::Even),
            (bw.clone(), PadType::Constant),
            (bw, PadType::None),
        ] {
            let f = ZeroPhaseFilter::new(
                sos,
                FiltFiltSettings {
                    pad_type: pad,
                    pad_len: PadLen::Auto,
                },
            )
            .unwrap();
            let x = signal(60_000, 7);
            let whole = f.apply(&x).unwrap();
            let top = whole.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            // Pieces smaller and larger than the block, and blocks of one
            // overlap: many block joins, each a late-started backward pass.
            for (piece, block) in [(1000, 1), (7, 5000), (33_333, 2000)] {
                let s = streamed(&f, &x, piece, block);
                assert_eq!(s.len(), x.len());
                let err = s
                    .iter()
                    .zip(&whole)
                    .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
                // Rounding (1e-16 per operation, a few thousand operations
                // deep) plus the decayed transient (1e-16): far below 1e-12.
                assert!(err <= 1e-12 * top, "{pad:?} {piece}/{block}: {err:e}");
            }
        }
    }

    #[test]
    fn short_and_empty_signals_are_refused_as_the_whole_filter_does() {
        let sos = butter(5, FilterBand::LowPass { cutoff_hz: 20.0 }, 1000.0).unwrap();
        let f = ZeroPhaseFilter::new(sos, FiltFiltSettings::default()).unwrap();
        let mut out = Vec::new();
        let s = ZeroPhaseStream::new(&f, 100);
        assert!(matches!(s.finish(&mut out), Err(DspError::Empty { .. })));
        let mut s = ZeroPhaseStream::new(&f, 100);
        s.push(&[1.0; 10], &mut out).unwrap();
        assert!(matches!(s.finish(&mut out), Err(DspError::TooShort { .. })));
        let mut s = ZeroPhaseStream::new(&f, 100);
        assert!(s.push(&[1.0, f64::NAN], &mut out).is_err());
        // A 5th-order Butterworth at 20/1000 Hz: slowest pole radius
        // exp(-2 pi 20 sin(pi/10) / 1000) ~ 0.962, so ~950 samples to 1e-16.
        let p = ZeroPhaseStream::overlap_for(&f);
        assert!((1800..2100).contains(&p), "{p}");
    }
}
