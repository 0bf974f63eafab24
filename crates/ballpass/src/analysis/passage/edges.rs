//! The record's ends in the measurement loop: the ghost pulses one period
//! beyond the outermost pulses, and the search's view of the ends.

use super::template::{Pulse, Template};

/// The pulses one period (the median spacing of the pulses found) before
/// the first and after the last, when their core support reaches into the
/// record. Outside the record, their tails are in it; left out, the
/// baseline and the template would take them. Inside (close to the start
/// or end), they hold the baseline's free end off a pulse not yet found,
/// which the search then finds. Amplitudes: `amps` (the last fit), or 0
/// before the first fit (a pulse assumed where the record holds none
/// would bend the baseline at the record's end).
pub(super) fn ghosts(
    pulses: &[Pulse],
    nd: usize,
    grid: &Template,
    amps: [f64; 2],
) -> [Option<Pulse>; 2] {
    if pulses.is_empty() {
        return [None, None];
    }
    let gaps: Vec<f64> = pulses.windows(2).map(|w| w[1].c - w[0].c).collect();
    if gaps.is_empty() {
        return [None, None];
    }
    let spacing = super::signal::median(&gaps);
    let amp = |k: usize| if amps[k].is_finite() { amps[k] } else { 0.0 };
    let first = pulses[0].c - spacing;
    let last = pulses[pulses.len() - 1].c + spacing;
    let end = (nd - 1) as f64;
    [
        (first + grid.right() > 0.0).then(|| Pulse {
            c: first,
            a: amp(0),
            s: 1.0,
        }),
        (last + grid.left() < end).then(|| Pulse {
            c: last,
            a: amp(1),
            s: 1.0,
        }),
    ]
}

/// Periods from the outermost pulse to the record's end within which that
/// end is searched as in [`EdgeSearch`].
const EDGE_PERIODS: f64 = 1.5;

/// The search's view of the record's ends. Past the outermost pulses'
/// support the baseline splines are held by nothing but the data, and bend
/// to take a pulse the search has not found yet (one cut by the record's
/// start or end, with the ghost there too weak to hold them off). There
/// the search sees the signal against the baseline continued in a straight
/// line from the half period before, and keeps a pulse only where the next
/// one is due: within a quarter period of the ghost's centre, which must
/// lie inside the record.
pub(super) struct EdgeSearch {
    /// The baseline-removed signal, the ends against the straight baseline.
    pub(super) signal: Vec<f64>,
    /// Blocks before `lo` and after `hi` are the ends.
    lo: f64,
    hi: f64,
    /// Where a pulse is due at each end (`None`: no ghost inside the record).
    due: [Option<f64>; 2],
    /// Tolerance on `due`, blocks.
    tol: f64,
}

impl EdgeSearch {
    pub(super) fn new(
        d: &[f64],
        baseline: &[f64],
        pulses: &[Pulse],
        ghosts: &[Option<Pulse>],
        core: (f64, f64),
        pd: f64,
    ) -> Self {
        let nd = d.len();
        let end = nd.saturating_sub(1) as f64;
        let mut signal = d.to_vec();
        let (Some(first), Some(last)) = (pulses.first(), pulses.last()) else {
            return Self {
                signal,
                lo: f64::NEG_INFINITY,
                hi: f64::INFINITY,
                due: [None, None],
                tol: 0.0,
            };
        };
        let lo = first.c + core.0;
        let hi = last.c + core.1;
        let inside = |g: &Option<Pulse>| g.map(|g| g.c).filter(|c| (0.0..=end).contains(c));
        // Only where the record ends within one and a half periods of the
        // outermost pulse: further out, pulses are missing (the seeds found
        // part of the record), and the search is left as it is.
        let due = [
            ghosts
                .first()
                .and_then(inside)
                .filter(|c| *c < first.c && first.c <= EDGE_PERIODS * pd),
            ghosts
                .get(1)
                .and_then(inside)
                .filter(|c| *c > last.c && end - last.c <= EDGE_PERIODS * pd),
        ];
        let span = (0.5 * pd).max(4.0);
        // Least-squares line through the baseline over `a..=b` (blocks).
        let line = |a: f64, b: f64| -> Option<(f64, f64)> {
            let a = a.max(0.0).ceil() as usize;
            let b = (b.min(end).floor().max(0.0)) as usize;
            if b < a + 2 || b >= nd {
                return None;
            }
            let xs: Vec<f64> = (a..=b).map(|i| i as f64).collect();
            let fit = crate::stats::linear_fit(&xs, &baseline[a..=b])?;
            Some((fit.intercept, fit.slope))
        };
        if due[1].is_some() {
            if let Some((c0, c1)) = line(hi - span, hi) {
                let from = hi.max(0.0).ceil() as usize;
                for i in from.min(nd)..nd {
                    signal[i] = d[i] + baseline[i] - (c0 + c1 * i as f64);
                }
            }
        }
        if due[0].is_some() {
            if let Some((c0, c1)) = line(lo, lo + span) {
                let to = (lo.floor().max(-1.0) + 1.0) as usize;
                for i in 0..to.min(nd) {
                    signal[i] = d[i] + baseline[i] - (c0 + c1 * i as f64);
                }
            }
        }
        Self {
            signal,
            lo,
            hi,
            due,
            tol: 0.25 * pd,
        }
    }

    /// Whether a pulse found at `c` is kept.
    pub(super) fn keeps(&self, c: f64) -> bool {
        let near = |g: f64| (c - g).abs() <= self.tol;
        match (c < self.lo, c > self.hi) {
            (true, _) => self.due[0].is_none_or(near),
            (_, true) => self.due[1].is_none_or(near),
            _ => true,
        }
    }
}
