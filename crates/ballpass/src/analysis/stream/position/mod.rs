//! The position-domain spectra of a streamed record
//! ([`crate::analysis::position`]'s method, the same numbers), gathered
//! over the passes [`super::analyze_stream`] makes anyway.
//!
//! The in-memory method needs two things of the whole record before it
//! resamples: the median speed (its stop threshold and the fine grid
//! follow from it) and the longest run (the Welch segment length). Here:
//!
//! - **Median speed, exactly**, by selection on the bits of `|v|` over
//!   three passes: a non-negative `f64`'s bits order as integers, so
//!   each pass counts the values sharing the bits fixed so far in 2^21
//!   bins of the next 21 bits (one histogram, 16 MB, per middle value
//!   while the two middle values of an even count differ), and the
//!   middle values' ranks pick the bins. After three passes the 63 bits,
//!   so the values, are known: the median is the in-memory one for the
//!   same speeds.
//! - **Resampling** in the next pass, run by run as the runs end: each
//!   grid point is emitted at the sample where the in-memory walk takes
//!   it, each signal decimated through [`ZeroPhaseStream`]s of the same
//!   filters, the velocity's centred mean over one period run as the same
//!   running sum. The last grid point of a run is held until the run's
//!   end fixes their count.
//! - **Segment length**: the Welch segments of every candidate length
//!   (1024, 512, 256 points) are summed side by side; a candidate is
//!   dropped as soon as a run is long enough for a longer one, so in
//!   practice only the longest is kept after the first long run.
//! - **Lines between the bins**: instead of the segments, the sum of each
//!   windowed segment's autocorrelation ([`LineScan::from_autocorrelations`]).
//!
//! The velocity, friction and optical signals come from a [`Chain`] of
//! their own (the velocity as `gradient(position)` low-passed, as the
//! in-memory method takes it), so the results equal the in-memory ones
//! to the low-pass's 1e-12 and rounding (tested in `tests`).
//!
//! Memory: the histograms (16 or 32 MB) during the first three passes;
//! in the fourth, the filters' blocks and one segment per signal and
//! candidate.

mod median;
mod segments;
#[cfg(test)]
mod tests;

use std::collections::VecDeque;

use median::Median;
use segments::Candidate;

use ballpass_dsp::{DecimateSettings, Decimator, ZeroPhaseFilter, ZeroPhaseStream};

use super::chain::{Chain, Output};
use super::support::Progress;
use crate::analysis::position::{
    assemble, choose_nperseg, grid_step, Accumulated, DirectionRun, LineScan, PositionSpectra,
    POINTS_PER_PERIOD, SEGMENT_CHOICES,
};
use crate::analysis::{AnalyzeSettings, Signal};
use crate::error::{Error, Result};
use crate::recording::stream::{Block, RecordSource};
use crate::recording::Channel;
use crate::stats::welch_dof;

/// Shortest run (fine points) resampled, as in memory.
const MIN_FINE_POINTS: usize = 64;
/// Samples the per-run decimation filters settle at a time.
const DEC_BLOCK: usize = 4096;

/// The anti-alias filters of the decimation stages (factors 2, 4, 8).
pub(super) struct StageFilters {
    dec: Vec<(usize, Decimator)>,
}

impl StageFilters {
    pub(super) fn new() -> Result<Self> {
        let dec = [2usize, 4, 8]
            .into_iter()
            .map(|q| {
                Decimator::new(DecimateSettings {
                    q,
                    ..DecimateSettings::default()
                })
                .map(|d| (q, d))
                .map_err(|e| Error::dsp("position-domain decimator", e))
            })
            .collect::<Result<_>>()?;
        Ok(StageFilters { dec })
    }

    fn filter(&self, q: usize) -> &ZeroPhaseFilter {
        self.dec
            .iter()
            .find(|(k, _)| *k == q)
            .and_then(|(_, d)| d.zero_phase_filter())
            .expect("zero-phase decimators of 2, 4 and 8")
    }
}

/// One signal of a run on its way to the grid: the decimation stages.
struct Decimation<'f> {
    stages: Vec<(usize, ZeroPhaseStream<'f>, usize)>,
}

impl<'f> Decimation<'f> {
    fn new(filters: &'f StageFilters, mut q: usize) -> Self {
        let mut stages = Vec::new();
        while q > 1 {
            let step = q.min(8);
            stages.push((
                step,
                ZeroPhaseStream::new(filters.filter(step), DEC_BLOCK),
                0,
            ));
            q /= step;
        }
        Decimation { stages }
    }

    /// Runs `x` (fine points) through the stages; `out` gets the grid
    /// points settled. `last`: the run ends with `x`.
    fn push(&mut self, x: Vec<f64>, last: bool, out: &mut Vec<f64>) -> Result<()> {
        let mut cur = x;
        let stages = std::mem::take(&mut self.stages);
        let mut kept = Vec::new();
        for (step, mut f, mut at) in stages {
            let mut y = Vec::new();
            f.push(&cur, &mut y)
                .map_err(|e| Error::dsp("position-domain decimation", e))?;
            let f = if last {
                f.finish(&mut y)
                    .map_err(|e| Error::dsp("position-domain decimation", e))?;
                None
            } else {
                Some(f)
            };
            let mut next = Vec::with_capacity(y.len() / step + 1);
            for v in y {
                if at % step == 0 {
                    next.push(v);
                }
                at += 1;
            }
            cur = next;
            if let Some(f) = f {
                kept.push((step, f, at));
            }
        }
        self.stages = kept;
        out.extend_from_slice(&cur);
        Ok(())
    }
}

/// The run being resampled.
struct Run<'f> {
    start: usize,
    fwd: bool,
    sign: f64,
    count: usize,
    first: f64,
    x0: f64,
    prev: f64,
    cur: f64,
    y_prev: Vec<f64>,
    y_cur: Vec<f64>,
    /// Grid points emitted; the last ones, not yet decimated.
    emitted: usize,
    held: VecDeque<Vec<f64>>,
    dec: Vec<Decimation<'f>>,
    /// Decimated points waiting for the running mean, per signal (the
    /// last `POINTS_PER_PERIOD + 1` of each), the running sum and count.
    ring: Vec<VecDeque<f64>>,
    sum: f64,
    grid: usize,
    len: usize,
}

/// A run that ended: its listing, its length on the grid (0: not
/// resampled) and its segments per candidate length.
type RunSummary = (DirectionRun, usize, Vec<(usize, usize)>);

/// Resampling onto the grid, after the median (module docs).
struct Resampler<'f> {
    v_stop: f64,
    q: usize,
    fine: f64,
    fs: f64,
    dx: f64,
    /// Index of the velocity among the signals.
    vi: usize,
    filters: &'f StageFilters,
    run: Option<Run<'f>>,
    runs: Vec<RunSummary>,
    candidates: Vec<Candidate>,
    longest: usize,
}

impl<'f> Resampler<'f> {
    fn sample(&mut self, i: usize, v: f64, p: f64, ys: &[f64]) -> Result<()> {
        if let Some(run) = &self.run {
            if v.abs() >= self.v_stop && (v > 0.0) == run.fwd {
                return self.advance(p, ys);
            }
            self.close(i)?;
        }
        if v.abs() < self.v_stop {
            return Ok(());
        }
        let fwd = v > 0.0;
        let sign = if fwd { 1.0 } else { -1.0 };
        let first = f64::NEG_INFINITY.max(sign * p);
        let k = ys.len();
        self.run = Some(Run {
            start: i,
            fwd,
            sign,
            count: 1,
            first,
            x0: (first / self.fine).ceil() * self.fine,
            prev: first,
            cur: first,
            y_prev: vec![0.0; k],
            y_cur: ys.to_vec(),
            emitted: 0,
            held: VecDeque::new(),
            dec: (0..k)
                .map(|_| Decimation::new(self.filters, self.q))
                .collect(),
            ring: vec![VecDeque::new(); k],
            sum: 0.0,
            grid: 0,
            len: 0,
        });
        Ok(())
    }

    /// The grid point `j` of the run at its current sample.
    fn point(run: &Run<'_>, j: usize, fine: f64) -> Vec<f64> {
        let x = run.x0 + j as f64 * fine;
        let (a, b) = (run.prev, run.cur);
        let t = if b > a {
            ((x - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            1.0
        };
        run.y_prev
            .iter()
            .zip(&run.y_cur)
            .map(|(p, c)| p + t * (c - p))
            .collect()
    }

    fn advance(&mut self, p: f64, ys: &[f64]) -> Result<()> {
        let fine = self.fine;
        let run = self.run.as_mut().expect("a run");
        run.prev = run.cur;
        run.cur = run.cur.max(run.sign * p);
        std::mem::swap(&mut run.y_prev, &mut run.y_cur);
        run.y_cur.copy_from_slice(ys);
        run.count += 1;
        // (Finite values: `>=` is the in-memory walk's `!(cur < x)`.)
        while run.cur >= run.x0 + run.emitted as f64 * fine {
            let pt = Self::point(run, run.emitted, fine);
            run.held.push_back(pt);
            run.emitted += 1;
        }
        if run.held.len() > 2 {
            let pts: Vec<Vec<f64>> = run.held.drain(..run.held.len() - 2).collect();
            self.feed(pts, false)?;
        }
        Ok(())
    }

    /// Fine points of every signal into the decimation, the grid points
    /// into the running mean and the segments.
    fn feed(&mut self, pts: Vec<Vec<f64>>, last: bool) -> Result<()> {
        let run = self.run.as_mut().expect("a run");
        let k = run.dec.len();
        let mut grid: Vec<Vec<f64>> = vec![Vec::new(); k];
        for (s, (d, g)) in run.dec.iter_mut().zip(&mut grid).enumerate() {
            let x: Vec<f64> = pts.iter().map(|p| p[s]).collect();
            d.push(x, last, g)?;
        }
        let w = POINTS_PER_PERIOD | 1;
        let h = w / 2;
        for i in 0..grid[0].len() {
            for (r, g) in run.ring.iter_mut().zip(&grid) {
                r.push_back(g[i]);
            }
            run.grid += 1;
            let vr = &run.ring[self.vi];
            let mean = if run.grid < w {
                continue;
            } else if run.grid == w {
                run.sum = vr.iter().sum();
                run.sum / w as f64
            } else {
                run.sum += vr[w] - vr[0];
                run.sum / w as f64
            };
            if run.grid > w {
                for r in &mut run.ring {
                    r.pop_front();
                }
            }
            let xs: Vec<f64> = run
                .ring
                .iter()
                .enumerate()
                .map(|(s, r)| if s == self.vi { r[h] - mean } else { r[h] })
                .collect();
            run.len += 1;
            for c in &mut self.candidates {
                c.push(&xs, self.dx)?;
            }
            self.longest = self.longest.max(run.len);
            // A candidate shorter than one that fits is never chosen.
            if let Some(fit) = SEGMENT_CHOICES.iter().find(|&&n| n <= self.longest) {
                self.candidates.retain(|c| c.n >= *fit);
            }
        }
        Ok(())
    }

    /// Ends the run before sample `b`.
    fn close(&mut self, b: usize) -> Result<()> {
        let Some(run) = self.run.as_mut() else {
            return Ok(());
        };
        let (fine, q) = (self.fine, self.q);
        let last = run.cur;
        let travel = last - run.first;
        let duration = run.count as f64 / self.fs;
        let m = if travel > 0.0 {
            ((last - run.x0) / fine).floor() as usize + 1
        } else {
            0
        };
        let resampled = run.count >= 2 && m >= MIN_FINE_POINTS * q;
        if resampled {
            // Exactly m grid points: drop one taken past the last by
            // rounding, or add those the walk ends on.
            while run.emitted > m {
                run.held.pop_back();
                run.emitted -= 1;
            }
            while run.emitted < m {
                let pt = Self::point(run, run.emitted, fine);
                run.held.push_back(pt);
                run.emitted += 1;
            }
            let pts: Vec<Vec<f64>> = run.held.drain(..).collect();
            self.feed(pts, true)?;
        }
        let run = self.run.take().expect("a run");
        let segs = self
            .candidates
            .iter_mut()
            .map(|c| (c.n, c.end_run()))
            .collect();
        self.runs.push((
            DirectionRun {
                start_s: run.start as f64 / self.fs,
                end_s: (b - 1) as f64 / self.fs,
                direction: if run.fwd { "forward" } else { "backward" },
                travel_mm: travel,
                mean_speed_mm_s: travel / duration,
                segments: 0,
            },
            if resampled { run.len } else { 0 },
            segs,
        ));
        Ok(())
    }
}

/// What the position pass is doing.
enum Stage<'f> {
    Select(Median),
    Resample(Box<Resampler<'f>>),
    Done,
}

/// The position-domain spectra of a streamed record, fed the record's
/// blocks pass after pass ([`PositionPass::push`], [`PositionPass::end_pass`]).
pub(super) struct PositionPass<'f> {
    name: String,
    fs: f64,
    trim: usize,
    n: usize,
    d_avg: f64,
    filter: Option<&'f ZeroPhaseFilter>,
    filter_block: usize,
    filters: &'f StageFilters,
    settings: AnalyzeSettings,
    with: Vec<Signal>,
    stage: Stage<'f>,
    chain: Option<Chain<'f>>,
    out: Output,
    /// Record samples seen this pass, and the analysed positions not yet
    /// matched with their filtered samples.
    seen: usize,
    positions: VecDeque<f64>,
    at: usize,
    error: Option<Error>,
    result: Option<PositionSpectra>,
}

impl<'f> PositionPass<'f> {
    /// A pass over a record at `fs` analysed from `trim` for `n` samples,
    /// of the `signals` the analysis has (velocity error among them).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        name: &str,
        fs: f64,
        (trim, n): (usize, usize),
        signals: &[Signal],
        d_avg_mm: f64,
        filter: Option<&'f ZeroPhaseFilter>,
        filter_block: usize,
        filters: &'f StageFilters,
        settings: &AnalyzeSettings,
    ) -> Self {
        let with = [Signal::Friction, Signal::VelocityError, Signal::Optical]
            .into_iter()
            .filter(|s| signals.contains(s))
            .collect();
        PositionPass {
            name: name.into(),
            fs,
            trim,
            n,
            d_avg: d_avg_mm,
            filter,
            filter_block,
            filters,
            settings: settings.clone(),
            with,
            stage: Stage::Select(Median::new(n)),
            chain: None,
            out: Output::new(),
            seen: 0,
            positions: VecDeque::new(),
            at: 0,
            error: None,
            result: None,
        }
    }

    /// Whether every pass it needs has run (or it failed).
    pub(super) fn done(&self) -> bool {
        matches!(self.stage, Stage::Done) || self.error.is_some()
    }

    /// Starts a pass; `restore` is the load cell's `(τ, offset)` (known
    /// from the second pass on, needed only by the resampling).
    pub(super) fn begin_pass(&mut self, restore: Option<(f64, f64)>) {
        let signals = match self.stage {
            Stage::Select(_) => vec![Signal::VelocityError],
            Stage::Resample(_) => self.with.clone(),
            Stage::Done => return,
        };
        // Velocity 0: the chain's "velocity error" is the velocity itself.
        self.chain = Some(Chain::new(
            &signals,
            self.fs,
            0.0,
            (self.trim, self.n),
            restore,
            self.filter,
            self.filter_block,
        ));
        self.out = Output::new();
        self.seen = 0;
        self.at = 0;
        self.positions.clear();
    }

    /// One block of the record.
    pub(super) fn push(&mut self, b: Block<'_>) {
        if self.error.is_some() {
            return;
        }
        let Some(mut chain) = self.chain.take() else {
            return;
        };
        let r = self.take_positions(b).and_then(|()| {
            chain.push(b, &mut self.out)?;
            self.eat()
        });
        self.chain = Some(chain);
        if let Err(e) = r {
            self.error = Some(e);
        }
    }

    fn take_positions(&mut self, b: Block<'_>) -> Result<()> {
        if let Stage::Resample(_) = self.stage {
            let p = b.channel(Channel::Position).unwrap_or(&[]);
            let lo = self.trim.saturating_sub(self.seen).min(p.len());
            let hi = (self.trim + self.n).saturating_sub(self.seen).min(p.len());
            if lo < hi {
                self.positions.extend(&p[lo..hi]);
            }
        }
        self.seen += b.len();
        Ok(())
    }

    /// Takes what the chain handed out.
    fn eat(&mut self) -> Result<()> {
        let vi = self
            .with_of_stage()
            .iter()
            .position(|&s| s == Signal::VelocityError)
            .expect("velocity");
        match &mut self.stage {
            Stage::Select(m) => {
                if let Some(v) = self.out.filtered.get(vi) {
                    m.add(v);
                }
            }
            Stage::Resample(r) => {
                let len = self.out.filtered.first().map_or(0, Vec::len);
                let mut ys = vec![0.0; self.out.filtered.len()];
                for i in 0..len {
                    for (y, f) in ys.iter_mut().zip(&self.out.filtered) {
                        *y = f[i];
                    }
                    let p = self
                        .positions
                        .pop_front()
                        .ok_or_else(|| Error::InvalidRecording {
                            source_name: self.name.clone(),
                            reason: "position samples ran short while streaming".into(),
                        })?;
                    r.sample(self.at + i, ys[vi], p, &ys)?;
                }
                self.at += len;
            }
            Stage::Done => {}
        }
        self.out.advance();
        Ok(())
    }

    fn with_of_stage(&self) -> Vec<Signal> {
        match self.stage {
            Stage::Resample(_) => self.with.clone(),
            _ => vec![Signal::VelocityError],
        }
    }

    /// Ends a pass: the median's next bits, or the last run.
    ///
    /// # Errors
    /// Only what breaks the analysis as a whole (none yet: a failure of the
    /// spectra is kept for [`PositionPass::finish`]).
    pub(super) fn end_pass(&mut self) {
        let Some(chain) = self.chain.take() else {
            return;
        };
        if self.error.is_some() {
            return;
        }
        let r = chain
            .finish(&mut self.out)
            .and_then(|()| self.eat())
            .and_then(|()| self.next_stage());
        if let Err(e) = r {
            self.error = Some(e);
        }
    }

    fn next_stage(&mut self) -> Result<()> {
        let stage = std::mem::replace(&mut self.stage, Stage::Done);
        self.stage = match stage {
            Stage::Select(mut m) => match m.end_pass(&self.name)? {
                Some(med) => Stage::Resample(Box::new(self.resampler(med)?)),
                None => Stage::Select(m),
            },
            Stage::Resample(mut r) => {
                super::support::check_count(&self.name, self.at, self.n)?;
                r.close(self.n)?;
                self.result = Some(self.assemble(*r)?);
                Stage::Done
            }
            Stage::Done => Stage::Done,
        };
        Ok(())
    }

    /// The resampling, once the median speed `med` is known.
    fn resampler(&self, med: f64) -> Result<Resampler<'f>> {
        let dx = 2.0 * self.d_avg / POINTS_PER_PERIOD as f64;
        let (v_stop, q) = grid_step(&self.name, med, self.fs, &self.settings, dx)?;
        let k = self.with.len();
        let candidates = SEGMENT_CHOICES
            .iter()
            .map(|&n| Candidate::new(n, k, &self.settings))
            .collect::<Result<_>>()?;
        Ok(Resampler {
            v_stop,
            q,
            fine: dx / q as f64,
            fs: self.fs,
            dx,
            vi: self
                .with
                .iter()
                .position(|&s| s == Signal::VelocityError)
                .expect("velocity"),
            filters: self.filters,
            run: None,
            runs: Vec::new(),
            candidates,
            longest: 0,
        })
    }

    /// The spectra from what the runs gave (as [`crate::analysis::position`]
    /// sums them).
    fn assemble(&self, r: Resampler<'_>) -> Result<PositionSpectra> {
        let longest = r.runs.iter().map(|(_, len, _)| *len).max().unwrap_or(0);
        let nperseg = choose_nperseg(longest, &self.name, self.d_avg)?;
        let c = r
            .candidates
            .into_iter()
            .find(|c| c.n == nperseg)
            .expect("no candidate that fits is dropped");
        let mut acc = Accumulated {
            sums: Vec::new(),
            freq: c.freq,
            n_segments: 0,
            dof: 0.0,
            runs: Vec::new(),
            travel: 0.0,
            min_speed: f64::INFINITY,
        };
        for (mut run, len, segs) in r.runs {
            if len >= nperseg {
                let k = segs
                    .iter()
                    .find(|(n, _)| *n == nperseg)
                    .map_or(0, |(_, k)| *k);
                run.segments = k;
                acc.n_segments += k;
                acc.dof += welch_dof(&c.window, nperseg / 2, k);
                acc.travel += len as f64 * r.dx;
                acc.min_speed = acc.min_speed.min(run.mean_speed_mm_s);
            }
            acc.runs.push(run);
        }
        acc.sums = self.with.iter().copied().zip(c.psd).collect();
        let scan = LineScan::from_autocorrelations(
            r.dx,
            self.with
                .iter()
                .copied()
                .zip(c.acf)
                .map(|(s, a)| (s, a, c.segments))
                .collect(),
        );
        Ok(assemble(
            acc,
            self.d_avg,
            nperseg,
            1,
            &self.settings,
            Some(&scan),
        ))
    }

    /// The spectra, or why there are none; `None` if the passes it needs
    /// did not all run.
    pub(super) fn finish(self) -> Option<Result<PositionSpectra>> {
        match (self.error, self.result) {
            (Some(e), _) => Some(Err(e)),
            (None, r) => r.map(Ok),
        }
    }
}

/// [`PositionPass::begin_pass`] when there is a pass to make.
pub(super) fn begin(pos: &mut Option<PositionPass<'_>>, restore: Option<(f64, f64)>) {
    if let Some(p) = pos.as_mut() {
        p.begin_pass(restore);
    }
}

/// [`PositionPass::push`] when there is a pass to make.
pub(super) fn push(pos: &mut Option<PositionPass<'_>>, b: Block<'_>) {
    if let Some(p) = pos.as_mut() {
        p.push(b);
    }
}

/// [`PositionPass::end_pass`] when there is a pass to make.
pub(super) fn end(pos: &mut Option<PositionPass<'_>>) {
    if let Some(p) = pos.as_mut() {
        p.end_pass();
    }
}

/// A pass of its own, for a record without the load-cell pass; whether it
/// was made (not when the spectra had already failed).
///
/// # Errors
/// The source's read errors.
pub(super) fn extra_pass(
    pos: &mut Option<PositionPass<'_>>,
    src: &mut dyn RecordSource,
    restore: Option<(f64, f64)>,
    what: String,
    progress: &mut dyn FnMut(&str),
) -> Result<bool> {
    let Some(p) = pos.as_mut() else {
        return Ok(false);
    };
    if p.done() {
        return Ok(false);
    }
    p.begin_pass(restore);
    let mut prog = Progress {
        f: progress,
        what,
        total: src.len(),
        done: 0,
        shown: 0,
    };
    src.pass(&mut |b| {
        p.push(b);
        prog.add(b.len());
        Ok(())
    })?;
    p.end_pass();
    Ok(true)
}

/// The spectra, with the note or the warning the in-memory analysis
/// gives.
pub(super) fn finish(
    pos: Option<PositionPass<'_>>,
    notes: &mut Vec<String>,
    warnings: &mut Vec<String>,
) -> Option<PositionSpectra> {
    match pos?.finish()? {
        Ok(p) => {
            notes.push(crate::analysis::position::note(&p));
            Some(p)
        }
        Err(e) => {
            warnings.push(crate::analysis::position::failure(&e));
            None
        }
    }
}
