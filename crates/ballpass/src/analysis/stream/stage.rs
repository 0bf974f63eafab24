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
use crate::model::identify::{identify, nperseg_for, StageIdentification, StageSpectra};

/// Samples detrended and fed to the Welch estimate at a time.
const CHUNK: usize = 1 << 14;

/// Friction and velocity error, a chunk of each.
type Pair = [Vec<f64>; 2];

/// The friction → velocity-error spectra of a record, gathered block by block.
pub(super) struct StageStream {
    /// Indices of the friction and the velocity error among the signals
    /// (the chain hands them out untrimmed in this order).
    pub(super) of: [usize; 2],
    nperseg: usize,
    lines: [TrendSums; 2],
    trends: Option<[Trend; 2]>,
    welch: WelchStream,
    /// Scratch: a chunk of each signal, scaled or detrended.
    buf: Pair,
}

impl StageStream {
    /// For a record of `len` samples at `fs` with `signals`; `None` without
    /// both friction and velocity error (as in memory).
    pub(super) fn new(signals: &[Signal], len: usize, fs: f64) -> Result<Option<Self>> {
        let at = |s: Signal| signals.iter().position(|&x| x == s);
        let (Some(f), Some(v)) = (at(Signal::Friction), at(Signal::VelocityError)) else {
            return Ok(None);
        };
        let nperseg = nperseg_for(len, fs);
        let welch = WelchStream::new(StageSpectra::welch_settings(nperseg), 2, &[(0, 1)])
            .map_err(|e| Error::dsp("stage identification Welch", e))?;
        Ok(Some(StageStream {
            of: [f, v],
            nperseg,
            lines: [TrendSums::new(len); 2],
            trends: None,
            welch,
            buf: [Vec::new(), Vec::new()],
        }))
    }

    /// Calls `f(at, [friction N, velocity error m/s])` on chunks of what
    /// `out` holds untrimmed (the velocity error scaled as
    /// [`StageSpectra::of`] scales it).
    fn chunks(
        out: &Output,
        buf: &mut Pair,
        f: &mut dyn FnMut(usize, &mut Pair) -> Result<()>,
    ) -> Result<()> {
        let (Some(fr), Some(ve)) = (out.untrimmed.first(), out.untrimmed.get(1)) else {
            return Ok(());
        };
        for (k, (a, b)) in fr.chunks(CHUNK).zip(ve.chunks(CHUNK)).enumerate() {
            buf[0].clear();
            buf[0].extend_from_slice(a);
            buf[1].clear();
            buf[1].extend(b.iter().map(|x| x * 1e-3));
            f(out.untrimmed_at + k * CHUNK, buf)?;
        }
        Ok(())
    }

    /// Pass 2: the lines.
    pub(super) fn add_lines(&mut self, out: &Output) {
        let lines = &mut self.lines;
        // Adding to sums cannot fail.
        let _ = Self::chunks(out, &mut self.buf, &mut |at, xs| {
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
        let welch = &mut self.welch;
        Self::chunks(out, &mut self.buf, &mut |at, xs| {
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

    /// The spectra and the stage fitted to them; `dc` the load cell's
    /// restoration of the friction.
    ///
    /// # Errors
    /// The Welch estimate's.
    pub(super) fn finish(
        self,
        fs: f64,
        dc: &DcRestoration,
    ) -> Result<(StageIdentification, StageSpectra)> {
        let set = self
            .welch
            .finish(fs)
            .map_err(|e| Error::dsp("stage identification spectra", e))?;
        let sp = StageSpectra::of_set(set, fs, self.nperseg).restored_with(dc);
        Ok((identify(&sp), sp))
    }
}
