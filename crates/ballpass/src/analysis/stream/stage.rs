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

/// The friction → velocity-error spectra of a record, gathered block by block.
pub(super) struct StageStream {
    /// Indices of the friction and the velocity error among the signals.
    of: [usize; 2],
    nperseg: usize,
    lines: [TrendSums; 2],
    trends: Option<[Trend; 2]>,
    welch: WelchStream,
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
        }))
    }

    /// The friction (N) and velocity error (m/s, as
    /// [`StageSpectra::of`] scales it) of what `out` holds untrimmed.
    fn signals(&self, out: &Output) -> [Vec<f64>; 2] {
        let [f, v] = self.of;
        [
            out.untrimmed.get(f).cloned().unwrap_or_default(),
            out.untrimmed
                .get(v)
                .map(|x| x.iter().map(|x| x * 1e-3).collect())
                .unwrap_or_default(),
        ]
    }

    /// Pass 2: the lines.
    pub(super) fn add_lines(&mut self, out: &Output) {
        let xs = self.signals(out);
        for (t, x) in self.lines.iter_mut().zip(&xs) {
            t.add(out.untrimmed_at, x);
        }
    }

    /// Pass 3: the spectra of the detrended signals.
    ///
    /// # Errors
    /// The Welch estimate's.
    pub(super) fn push(&mut self, out: &Output) -> Result<()> {
        let trends = *self
            .trends
            .get_or_insert_with(|| self.lines.map(|t| t.trend(Detrend::Linear)));
        let mut xs = self.signals(out);
        if xs[0].is_empty() {
            return Ok(());
        }
        for (x, t) in xs.iter_mut().zip(&trends) {
            for (i, y) in x.iter_mut().enumerate() {
                *y -= t.at(out.untrimmed_at + i);
            }
        }
        self.welch
            .push(&[&xs[0], &xs[1]])
            .map_err(|e| Error::dsp("stage identification spectra", e))
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
