//! The stage identification of a streamed record: the spectra
//! [`StageSpectra::of_signals`] takes from the whole record, gathered in
//! two readings of it.
//!
//! In memory the restored friction and the velocity error (m/s) of the
//! whole, untrimmed record are each detrended by their least-squares line
//! and go into a Welch estimate with their cross spectrum. Here the chain
//! hands over the same samples block by block (to the bit:
//! [`super::chain`]); pass 2 sums each one's line ([`TrendSums`], the
//! same closed form as `detrend` with compensated sums), pass 3 feeds
//! them, detrended, to a [`WelchStream`] of the same settings. The fit
//! then runs on the spectra as in memory.

use ballpass_dsp::WelchStream;

use super::chain::{Output, Trend, TrendSums};
use crate::analysis::load_cell::DcRestoration;
use crate::analysis::{Detrend, Signal};
use crate::error::{Error, Result};
use crate::model::identify::{
    grouped_welch, identify, nperseg_for, Lattice, StageIdentification, StageSpectra,
};

/// Samples detrended and fed to the Welch estimate at a time.
const CHUNK: usize = 1 << 14;

/// Friction and velocity error, a chunk of each.
type Pair = [Vec<f64>; 2];

/// The friction → velocity-error spectra of a record, gathered block by block.
pub(super) struct StageStream {
    /// Indices of the friction and the velocity error among the signals.
    of: [usize; 2],
    /// Whether the record is trimmed: the chain then hands these two out
    /// untrimmed too ([`StageStream::untrimmed`]); else its raw output is
    /// the whole record already.
    trimmed: bool,
    nperseg: usize,
    lines: [TrendSums; 2],
    trends: Option<[Trend; 2]>,
    /// The estimate, with the jackknife's groups of its segments.
    welch: WelchStream,
    /// Scratch: a chunk of each signal, scaled or detrended.
    buf: Pair,
    /// The velocity error as it comes, for the check of the encoder's
    /// quantisation.
    lattice: Lattice,
}

impl StageStream {
    /// For a record of `len` samples at `fs` with `signals`, analysed from
    /// sample `trim`; `None` without both friction and velocity error (as
    /// in memory).
    pub(super) fn new(
        signals: &[Signal],
        len: usize,
        fs: f64,
        trim: usize,
    ) -> Result<Option<Self>> {
        let at = |s: Signal| signals.iter().position(|&x| x == s);
        let (Some(f), Some(v)) = (at(Signal::Friction), at(Signal::VelocityError)) else {
            return Ok(None);
        };
        let nperseg = nperseg_for(len, fs);
        let welch = grouped_welch(nperseg)?;
        Ok(Some(StageStream {
            of: [f, v],
            trimmed: trim > 0,
            nperseg,
            lines: [TrendSums::new(len); 2],
            trends: None,
            welch,
            buf: [Vec::new(), Vec::new()],
            lattice: Lattice::new(len),
        }))
    }

    /// The signals a chain must hand out untrimmed (as
    /// [`super::chain::Chain::with_untrimmed`] takes them).
    pub(super) fn untrimmed(&self) -> Vec<usize> {
        if self.trimmed {
            self.of.to_vec()
        } else {
            Vec::new()
        }
    }

    /// Where the record's friction and velocity error are in `out`, and
    /// the index of their first sample.
    fn source<'o>(&self, out: &'o Output) -> Source<'o> {
        let (at, fr, ve) = if self.trimmed {
            (
                out.untrimmed_at,
                out.untrimmed.first(),
                out.untrimmed.get(1),
            )
        } else {
            (out.raw_at, out.raw.get(self.of[0]), out.raw.get(self.of[1]))
        };
        (
            at,
            fr.map_or(&[][..], Vec::as_slice),
            ve.map_or(&[][..], Vec::as_slice),
        )
    }

    /// Pass 2: the lines.
    pub(super) fn add_lines(&mut self, out: &Output) {
        let src = self.source(out);
        let lines = &mut self.lines;
        // Adding to sums cannot fail.
        let _ = for_chunks(src, &mut self.buf, &mut |at, xs| {
            for (t, x) in lines.iter_mut().zip(xs.iter()) {
                t.add(at, x);
            }
            Ok(())
        });
    }

    /// Pass 3: the spectra of the detrended signals.
    ///
    /// # Errors
    /// The Welch estimate's.
    pub(super) fn push(&mut self, out: &Output) -> Result<()> {
        let trends = *self
            .trends
            .get_or_insert_with(|| self.lines.map(|t| t.trend(Detrend::Linear)));
        let src = self.source(out);
        let welch = &mut self.welch;
        let lattice = &mut self.lattice;
        for_chunks(src, &mut self.buf, &mut |at, xs| {
            lattice.push(&xs[1]);
            for (x, t) in xs.iter_mut().zip(&trends) {
                for (i, y) in x.iter_mut().enumerate() {
                    *y -= t.at(at + i);
                }
            }
            welch
                .push(&[&xs[0], &xs[1]])
                .map_err(|e| Error::dsp("stage identification spectra", e))
        })
    }

    /// The spectra and the stage fitted to them; `velocity_mm_s` the
    /// commanded speed, `dc` the load cell's restoration of the friction.
    ///
    /// # Errors
    /// The Welch estimate's.
    pub(super) fn finish(
        self,
        fs: f64,
        velocity_mm_s: f64,
        dc: &DcRestoration,
    ) -> Result<(StageIdentification, StageSpectra)> {
        let mut sp = StageSpectra::of_grouped(self.welch, fs, self.nperseg)?.restored_with(dc);
        sp.encoder = self.lattice.phases(velocity_mm_s * 1e-3);
        Ok((identify(&sp), sp))
    }
}

/// The index of the first sample, the friction and the velocity error.
type Source<'o> = (usize, &'o [f64], &'o [f64]);

/// Calls `f(at, [friction N, velocity error m/s])` on chunks of `src`
/// (the velocity error scaled as [`StageSpectra::of`] scales it).
fn for_chunks(
    (at, fr, ve): Source<'_>,
    buf: &mut Pair,
    f: &mut dyn FnMut(usize, &mut Pair) -> Result<()>,
) -> Result<()> {
    for (k, (a, b)) in fr.chunks(CHUNK).zip(ve.chunks(CHUNK)).enumerate() {
        buf[0].clear();
        buf[0].extend_from_slice(a);
        buf[1].clear();
        buf[1].extend(b.iter().map(|x| x * 1e-3));
        f(at + k * CHUNK, buf)?;
    }
    Ok(())
}
