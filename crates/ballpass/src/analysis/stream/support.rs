//! The pass runner and the load-cell pass of [`super::analyze_stream`],
//! and small helpers.

use super::chain::{Chain, Output, Sum};
use crate::analysis::load_cell::{self, Decision};
use crate::analysis::{AnalyzeSettings, Signal};
use crate::bearing::Prediction;
use crate::error::{Error, Result};
use crate::recording::stream::{Block, RecordSource};
use crate::recording::Channel;

/// Running sums of one pass, reported as a percentage.
pub(super) struct Progress<'p> {
    pub(super) f: &'p mut dyn FnMut(&str),
    pub(super) what: String,
    pub(super) total: usize,
    pub(super) done: usize,
    pub(super) shown: usize,
}

impl Progress<'_> {
    pub(super) fn add(&mut self, k: usize) {
        self.done += k;
        let pct = (100 * self.done / self.total.max(1)).min(100);
        if pct != self.shown {
            self.shown = pct;
            (self.f)(&format!("{} {pct:>3} %", self.what));
        }
    }
}

pub(super) fn channel_of(s: Signal) -> Channel {
    match s {
        Signal::Friction => Channel::Friction,
        Signal::VelocityError => Channel::Position,
        Signal::Optical => Channel::Optical,
    }
}

/// A source that handed over a different number of samples than it said.
pub(super) fn check_count(name: &str, got: usize, want: usize) -> Result<()> {
    if got == want {
        Ok(())
    } else {
        Err(Error::InvalidRecording {
            source_name: name.into(),
            reason: format!("read {got} samples where {want} were expected (the file changed while it was read?)"),
        })
    }
}

/// The restoration `(τ, offset)` to undo, what was done, and the
/// friction's mean.
pub(super) type LoadCellPass = (Option<(f64, f64)>, load_cell::DcRestoration, f64);

/// Pass 1: the friction's mean and the discharge fit's sums (`on_block`
/// sees each block as read); the
/// restoration to undo and what was done (its `level_over_spread` is
/// filled in after pass 2, which has the friction's spread).
pub(super) fn load_cell_pass(
    src: &mut dyn RecordSource,
    pred: &Prediction,
    settings: &AnalyzeSettings,
    what: &str,
    progress: &mut dyn FnMut(&str),
    on_block: &mut dyn FnMut(Block<'_>),
) -> Result<LoadCellPass> {
    let (fs, len) = (src.fs_hz(), src.len());
    let w = load_cell::block_width(len, fs);
    let mut sum = -0.0;
    let mut means = Vec::new();
    let mut block = -0.0;
    let mut in_block = 0usize;
    // Offset fit of a given τ on every 10th sample (one-pass sums).
    let tau = match settings.load_cell {
        load_cell::LoadCellCorrection::TimeConstant(t) => Some(t),
        _ => None,
    };
    let (mut sb, mut ss, mut sbb, mut sbs, mut m) = (
        Sum::default(),
        Sum::default(),
        Sum::default(),
        Sum::default(),
        0usize,
    );
    let mut i = 0usize;
    let mut prog = Progress {
        f: progress,
        what: what.into(),
        total: len,
        done: 0,
        shown: 0,
    };
    src.pass(&mut |b| {
        on_block(b);
        let f = b.friction_n.unwrap_or(&[]);
        for &y in f {
            sum += y;
            block += y;
            in_block += 1;
            if in_block == w {
                means.push(block / w as f64);
                block = -0.0;
                in_block = 0;
            }
            if let Some(t) = tau {
                if i % 10 == 0 {
                    let e = (-(i as f64) / (fs * t)).exp();
                    sb.add(e);
                    ss.add(y);
                    sbb.add(e * e);
                    sbs.add(e * y);
                    m += 1;
                }
            }
            i += 1;
        }
        prog.add(b.len());
        Ok(())
    })?;
    check_count(&src.source_name(), i, len)?;
    let mean = sum / len as f64;
    let decision = match settings.load_cell {
        load_cell::LoadCellCorrection::Off => Decision::Off,
        load_cell::LoadCellCorrection::TimeConstant(t) => {
            let mf = m as f64;
            let (mb, ms) = (sb.value() / mf, ss.value() / mf);
            let cbb = sbb.value() - mf * mb * mb;
            let cbs = sbs.value() - mf * mb * ms;
            let a = if cbb > 0.0 { cbs / cbb } else { 0.0 };
            Decision::Given {
                tau: t,
                offset: ms - a * mb,
            }
        }
        load_cell::LoadCellCorrection::Auto => {
            Decision::Auto(load_cell::fit_discharge_means(means, len, fs, pred.tau_c_s))
        }
    };
    // The spread is not known yet: a placeholder the caller replaces.
    let (undo, dc) = load_cell::decide(decision, 0.0);
    Ok((undo, dc, mean))
}

/// What every pass of the chain over the record shares.
pub(super) struct PassKit<'a> {
    pub(super) signals: &'a [Signal],
    pub(super) fs: f64,
    pub(super) velocity: f64,
    pub(super) trim_n: (usize, usize),
    pub(super) len: usize,
    pub(super) restore: Option<(f64, f64)>,
    pub(super) filter: Option<&'a ballpass_dsp::ZeroPhaseFilter>,
    pub(super) filter_block: usize,
    pub(super) name: &'a str,
    /// Signals the chain hands out untrimmed too (the stage's).
    pub(super) untrimmed: &'a [usize],
}

impl PassKit<'_> {
    /// Reads the record through a new chain: `on_block` sees each block
    /// as read, `eat` what the chain gives for it (`true` at the end);
    /// checks that the whole analysed span came through.
    pub(super) fn run(
        &self,
        src: &mut dyn RecordSource,
        what: String,
        progress: &mut dyn FnMut(&str),
        on_block: &mut dyn FnMut(Block<'_>),
        eat: &mut dyn FnMut(&mut Output, bool) -> Result<()>,
    ) -> Result<()> {
        let mut chain = Chain::new(
            self.signals,
            self.fs,
            self.velocity,
            self.trim_n,
            self.restore,
            self.filter,
            self.filter_block,
        )
        .with_untrimmed(self.untrimmed);
        let mut out = Output::new();
        let mut prog = Progress {
            f: progress,
            what,
            total: self.len,
            done: 0,
            shown: 0,
        };
        src.pass(&mut |b| {
            on_block(b);
            chain.push(b, &mut out)?;
            eat(&mut out, false)?;
            out.advance();
            prog.add(b.len());
            Ok(())
        })?;
        chain.finish(&mut out)?;
        eat(&mut out, true)?;
        out.advance();
        check_count(self.name, out.raw_at, self.trim_n.1)?;
        check_count(self.name, out.filtered_at, self.trim_n.1)
    }
}

/// The sums of the velocity error's statistics (as `prepare_raw_keeping` takes
/// them, in the same order).
#[derive(Default)]
pub(super) struct Moments {
    pub(super) sum: f64,
    pub(super) sq: f64,
    pub(super) dev: f64,
}

impl Moments {
    pub(super) fn new() -> Self {
        Moments {
            sum: -0.0,
            sq: -0.0,
            dev: -0.0,
        }
    }
}
