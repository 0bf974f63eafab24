//! Steps 1–2 of the analysis on a record read block by block: load-cell
//! restoration, velocity error, trim, low-pass, detrend.
//!
//! - Restoration is the recursion of [`load_cell::restore`] with its state
//!   (running integral, previous sample) carried from block to block:
//!   the same values to the bit.
//! - The velocity `gradient(position, 1/fs)` is taken over the position
//!   held with one sample before and after each value, so each value is
//!   the same centred (or, at the record's ends, one-sided) difference as
//!   on the whole record: the same to the bit.
//! - The low-pass is [`ZeroPhaseStream`] (to 1e-12 of the whole-record
//!   filter, see its docs).
//! - The detrend subtracts the line fitted in an earlier pass from the
//!   compensated sums `Σ y` and `Σ (i − c) y` ([`TrendSums`]).
//!
//! [`load_cell::restore`]: crate::analysis::load_cell::restore

use ballpass_dsp::{gradient, Spacing, ZeroPhaseFilter, ZeroPhaseStream};

use crate::analysis::Signal;
use crate::error::{Error, Result};
use crate::recording::stream::Block;
use crate::recording::Channel;

/// Compensated (Neumaier) sum.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Sum {
    s: f64,
    c: f64,
}

impl Sum {
    pub(crate) fn add(&mut self, v: f64) {
        let t = self.s + v;
        if self.s.abs() >= v.abs() {
            self.c += (self.s - t) + v;
        } else {
            self.c += (v - t) + self.s;
        }
        self.s = t;
    }

    pub(crate) fn value(&self) -> f64 {
        self.s + self.c
    }
}

/// The sums a least-squares line through `y[0..n]` needs.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TrendSums {
    n: usize,
    center: f64,
    sum: Sum,
    moment: Sum,
}

impl TrendSums {
    pub(crate) fn new(n: usize) -> Self {
        TrendSums {
            n,
            center: (n as f64 - 1.0) / 2.0,
            sum: Sum::default(),
            moment: Sum::default(),
        }
    }

    /// Adds `y[at .. at + ys.len()]`.
    pub(crate) fn add(&mut self, at: usize, ys: &[f64]) {
        for (i, &y) in ys.iter().enumerate() {
            self.sum.add(y);
            self.moment.add(((at + i) as f64 - self.center) * y);
        }
    }

    /// The trend `kind` removes: `(offset, slope, center)`.
    pub(crate) fn trend(&self, kind: crate::analysis::Detrend) -> Trend {
        let nf = self.n as f64;
        let mean = self.sum.value() / nf;
        match kind {
            crate::analysis::Detrend::None => Trend::default(),
            crate::analysis::Detrend::Constant => Trend {
                offset: mean,
                ..Trend::default()
            },
            crate::analysis::Detrend::Linear if self.n < 2 => Trend {
                offset: mean,
                ..Trend::default()
            },
            crate::analysis::Detrend::Linear => Trend {
                offset: mean,
                slope: self.moment.value() / (nf * (nf * nf - 1.0) / 12.0),
                center: self.center,
            },
        }
    }
}

/// A line `offset + slope (i − center)`.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Trend {
    offset: f64,
    slope: f64,
    center: f64,
}

impl Trend {
    pub(crate) fn at(&self, i: usize) -> f64 {
        self.offset + self.slope * (i as f64 - self.center)
    }
}

/// The velocity of a position given in pieces (module docs).
#[derive(Debug, Default)]
struct Gradient {
    /// Position samples from the one before the next value to emit.
    held: Vec<f64>,
    /// Whether `held[0]` is the sample before the next value (not the
    /// record's first sample).
    primed: bool,
}

impl Gradient {
    fn push(&mut self, p: &[f64], dt: f64, out: &mut Vec<f64>) -> Result<()> {
        self.held.extend_from_slice(p);
        if self.held.len() < 3 {
            return Ok(());
        }
        let v = gradient(&self.held, Spacing::Uniform(dt))
            .map_err(|e| Error::dsp("velocity (gradient)", e))?;
        // Every value but the last (which needs the next sample); after
        // the first block the first value belongs to the previous block.
        let from = usize::from(self.primed);
        out.extend_from_slice(&v[from..v.len() - 1]);
        let keep = self.held.len() - 2;
        self.held.drain(..keep);
        self.primed = true;
        Ok(())
    }

    fn finish(self, dt: f64, out: &mut Vec<f64>) -> Result<()> {
        if self.held.len() < 2 {
            return Err(Error::dsp(
                "velocity (gradient)",
                ballpass_dsp::DspError::TooShort {
                    what: "position",
                    needed: 2,
                    found: self.held.len(),
                },
            ));
        }
        let v = gradient(&self.held, Spacing::Uniform(dt))
            .map_err(|e| Error::dsp("velocity (gradient)", e))?;
        out.extend_from_slice(&v[usize::from(self.primed)..]);
        Ok(())
    }
}

/// One pass of steps 1–2 over a record given in blocks.
pub(crate) struct Chain<'f> {
    signals: Vec<Signal>,
    dt: f64,
    velocity: f64,
    /// Samples dropped at the start, samples kept.
    trim: usize,
    n: usize,
    /// Load-cell restoration `(k = 1/(2 fs τ), offset)` and its state.
    restore: Option<(f64, f64)>,
    integral: f64,
    prev: Option<f64>,
    grad: Option<Gradient>,
    /// Record samples seen per signal (before the trim).
    seen: Vec<usize>,
    filters: Vec<Option<ZeroPhaseStream<'f>>>,
    /// Settled filtered samples not yet handed out, per signal.
    settled: Vec<Vec<f64>>,
    /// Raw (trimmed) samples not yet handed out, per signal.
    raw: Vec<Vec<f64>>,
    /// Which signals are handed out untrimmed ([`Chain::with_untrimmed`]),
    /// and their samples not yet handed out.
    untrimmed_of: Vec<usize>,
    untrimmed: Vec<Vec<f64>>,
}

/// What one block of input gave: the next raw (trimmed, unfiltered)
/// samples and the next low-passed samples of every signal, each with the
/// index (in the analysed record) of its first sample.
pub(crate) struct Output {
    pub raw_at: usize,
    pub raw: Vec<Vec<f64>>,
    pub filtered_at: usize,
    pub filtered: Vec<Vec<f64>>,
    /// The next samples before the trim of the signals a chain was asked
    /// for ([`Chain::with_untrimmed`]), in that order, from the record's
    /// sample `untrimmed_at`.
    pub untrimmed_at: usize,
    pub untrimmed: Vec<Vec<f64>>,
}

impl<'f> Chain<'f> {
    /// A chain for `signals` of a record at `fs` analysed from sample
    /// `trim` for `n` samples; `restore` is `(τ, offset)` to undo.
    pub(crate) fn new(
        signals: &[Signal],
        fs: f64,
        velocity: f64,
        (trim, n): (usize, usize),
        restore: Option<(f64, f64)>,
        filter: Option<&'f ZeroPhaseFilter>,
        filter_block: usize,
    ) -> Self {
        Chain {
            signals: signals.to_vec(),
            dt: 1.0 / fs,
            velocity,
            trim,
            n,
            restore: restore.map(|(tau, off)| (0.5 / (fs * tau), off)),
            integral: 0.0,
            prev: None,
            grad: signals
                .contains(&Signal::VelocityError)
                .then(Gradient::default),
            seen: vec![0; signals.len()],
            filters: signals
                .iter()
                .map(|_| filter.map(|f| ZeroPhaseStream::new(f, filter_block)))
                .collect(),
            settled: vec![Vec::new(); signals.len()],
            raw: vec![Vec::new(); signals.len()],
            untrimmed_of: Vec::new(),
            untrimmed: Vec::new(),
        }
    }

    /// The chain also hands out the signals at indices `of` before the
    /// trim ([`Output::untrimmed`]).
    pub(crate) fn with_untrimmed(mut self, of: &[usize]) -> Self {
        self.untrimmed_of = of.to_vec();
        self.untrimmed = vec![Vec::new(); of.len()];
        self
    }

    /// Feeds one block; `out` gets what is ready.
    pub(crate) fn push(&mut self, b: Block<'_>, out: &mut Output) -> Result<()> {
        let mut fresh: Vec<Vec<f64>> = Vec::with_capacity(self.signals.len());
        for s in self.signals.clone() {
            let mut v = Vec::new();
            match s {
                Signal::Friction => {
                    let x = b.channel(Channel::Friction).unwrap_or(&[]);
                    match self.restore {
                        Some((k, off)) => {
                            v.reserve(x.len());
                            for &y in x {
                                let u = y - off;
                                if let Some(p) = self.prev {
                                    self.integral += k * (p + u);
                                }
                                v.push(u + self.integral);
                                self.prev = Some(u);
                            }
                        }
                        None => v.extend_from_slice(x),
                    }
                }
                Signal::Optical => v.extend_from_slice(b.channel(Channel::Optical).unwrap_or(&[])),
                Signal::VelocityError => {
                    let p = b.channel(Channel::Position).unwrap_or(&[]);
                    let g = self.grad.as_mut().expect("velocity signal has a gradient");
                    g.push(p, self.dt, &mut v)?;
                    v.iter_mut().for_each(|x| *x -= self.velocity);
                }
            }
            fresh.push(v);
        }
        self.take(fresh, out)
    }

    /// Ends the record; `out` gets the rest.
    pub(crate) fn finish(mut self, out: &mut Output) -> Result<()> {
        let mut fresh = vec![Vec::new(); self.signals.len()];
        if let Some(g) = self.grad.take() {
            let k = self
                .signals
                .iter()
                .position(|&s| s == Signal::VelocityError)
                .expect("velocity signal");
            g.finish(self.dt, &mut fresh[k])?;
            fresh[k].iter_mut().for_each(|x| *x -= self.velocity);
        }
        self.keep(fresh)?;
        for (k, f) in self.filters.iter_mut().enumerate() {
            if let Some(f) = f.take() {
                f.finish(&mut self.settled[k]).map_err(|e| {
                    Error::dsp(format!("low-pass of {}", self.signals[k].name()), e)
                })?;
            }
        }
        Self::hand_out(&mut self.raw, &mut out.raw);
        Self::hand_out(&mut self.settled, &mut out.filtered);
        if !self.untrimmed_of.is_empty() {
            Self::hand_out(&mut self.untrimmed, &mut out.untrimmed);
        }
        Ok(())
    }

    /// Trims the record samples `fresh` of each signal, passes them on and
    /// hands out what is ready.
    fn take(&mut self, fresh: Vec<Vec<f64>>, out: &mut Output) -> Result<()> {
        self.keep(fresh)?;
        Self::hand_out(&mut self.raw, &mut out.raw);
        Self::hand_out(&mut self.settled, &mut out.filtered);
        if !self.untrimmed_of.is_empty() {
            Self::hand_out(&mut self.untrimmed, &mut out.untrimmed);
        }
        Ok(())
    }

    /// Trims the record samples `fresh` of each signal and passes them to
    /// the raw and filtered queues.
    fn keep(&mut self, fresh: Vec<Vec<f64>>) -> Result<()> {
        for (k, v) in fresh.into_iter().enumerate() {
            if let Some(j) = self.untrimmed_of.iter().position(|&i| i == k) {
                self.untrimmed[j].extend_from_slice(&v);
            }
            let start = self.seen[k];
            self.seen[k] += v.len();
            let lo = self.trim.saturating_sub(start).min(v.len());
            let hi = (self.trim + self.n).saturating_sub(start).min(v.len());
            if lo >= hi {
                continue;
            }
            let kept = &v[lo..hi];
            self.raw[k].extend_from_slice(kept);
            match &mut self.filters[k] {
                Some(f) => f.push(kept, &mut self.settled[k]).map_err(|e| {
                    Error::dsp(format!("low-pass of {}", self.signals[k].name()), e)
                })?,
                None => self.settled[k].extend_from_slice(kept),
            }
        }
        Ok(())
    }

    /// Moves the samples every signal has out of `held` into `out`.
    fn hand_out(held: &mut [Vec<f64>], out: &mut Vec<Vec<f64>>) {
        let m = held.iter().map(Vec::len).min().unwrap_or(0);
        out.clear();
        for h in held.iter_mut() {
            out.push(h.drain(..m).collect());
        }
    }
}

impl Output {
    pub(crate) fn new() -> Self {
        Output {
            raw_at: 0,
            raw: Vec::new(),
            filtered_at: 0,
            filtered: Vec::new(),
            untrimmed_at: 0,
            untrimmed: Vec::new(),
        }
    }

    /// Advances the indices past what was handed out.
    pub(crate) fn advance(&mut self) {
        self.raw_at += self.raw.first().map_or(0, Vec::len);
        self.filtered_at += self.filtered.first().map_or(0, Vec::len);
        self.untrimmed_at += self.untrimmed.first().map_or(0, Vec::len);
    }
}
