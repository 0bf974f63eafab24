//! The synchronous average of a streamed record
//! ([`crate::analysis::sync`]'s method), accumulated in one pass as sums
//! once the passages are known.
//!
//! The in-memory average resamples every period into `B` bins and keeps
//! the rows; here each row is added to running sums as soon as its bins
//! are read: per bin `Σ (y − K)` and `Σ (y − K)²` (`K` the first period's
//! row, a shift that keeps the spread's sums from cancelling), and per
//! ball (passage index mod `N_B`) `Σ y`. The variance explained needs the
//! mean waveform `m`, known only at the end; its residual
//! `Σ (x − m(φ))²`, with `m(φ) = (1 − f) m_j + f m_{j+1}` between bins,
//! is a quadratic form in `m`:
//!
//! ```text
//! Σ x² − 2 Σ_j m_j W_j + Σ_j Q_j m_j² + 2 Σ_j C_j m_j m_{j+1}
//! W_j = Σ x (1 − f) [bin j] + Σ x f [bin j − 1],
//! Q_j = Σ (1 − f)² [bin j] + Σ f² [bin j − 1],  C_j = Σ f (1 − f) [bin j]
//! ```
//!
//! so its sums are gathered in the same pass. The same numbers as the
//! in-memory average to rounding (tested). Memory: the periods (24 bytes
//! each, about 4 MB at 24 hours at 9 mm/s) and `O(B N_B)` sums.

use super::super::sync::{
    ball_note, finish, periods, waveform, BallRow, SyncAverage, SyncKey, SyncSettings,
};
use crate::analysis::Signal;
use crate::stats::student_t_quantile;

/// Each ball's mean row.
type BallMeans = Vec<(usize, Vec<f64>)>;

/// Sums of one signal.
struct Acc {
    signal: Signal,
    unit: &'static str,
    scale: f64,
    /// Index of the signal among the analysis' signals.
    index: usize,
    shift: Option<Vec<f64>>,
    s1: Vec<f64>,
    s2: Vec<f64>,
    w: Vec<f64>,
    q: Vec<f64>,
    c: Vec<f64>,
    sum: f64,
    sq: f64,
    count: usize,
    balls: Vec<(usize, Vec<f64>)>,
    row: Vec<f64>,
}

/// The synchronous average fed the analysed samples in order.
pub(super) struct SyncStream {
    key: SyncKey,
    bins: usize,
    fs: f64,
    n: usize,
    settings: SyncSettings,
    per: Vec<(f64, f64, usize)>,
    rejected: usize,
    balls: Option<usize>,
    acc: Vec<Acc>,
    /// Next period and bin to read; next period for the explained sums.
    next: (usize, usize),
    ex: usize,
    /// The previous sample per signal, and the index of the next sample.
    prev: Vec<f64>,
    at: usize,
}

impl SyncStream {
    /// For `key_times_s` (s from the first analysed sample; optical
    /// passages or encoder keys, as `key` says) over `n` samples at `fs`;
    /// `signals` are the analysis' signals; `balls_in_circuit` is `N_B`
    /// when known (balls are told apart on optical passages only). `None`
    /// without friction and velocity error.
    pub(super) fn new(
        key: SyncKey,
        key_times_s: &[f64],
        n: usize,
        fs: f64,
        signals: &[Signal],
        balls_in_circuit: Option<u32>,
    ) -> Option<Self> {
        let settings = SyncSettings::default();
        let bins = settings.bins;
        let (per, rejected) = periods(key_times_s, n, fs);
        let acc: Vec<Acc> = [
            (Signal::Friction, "N", 1.0),
            (Signal::VelocityError, "µm/s", 1e3),
        ]
        .into_iter()
        .filter_map(|(signal, unit, scale)| {
            let index = signals.iter().position(|&s| s == signal)?;
            Some(Acc {
                signal,
                unit,
                scale,
                index,
                shift: None,
                s1: vec![0.0; bins],
                s2: vec![0.0; bins],
                w: vec![0.0; bins],
                q: vec![0.0; bins],
                c: vec![0.0; bins],
                sum: 0.0,
                sq: 0.0,
                count: 0,
                balls: Vec::new(),
                row: Vec::with_capacity(bins),
            })
        })
        .collect();
        if acc.is_empty() || n < 2 {
            return None;
        }
        let k = acc.len();
        let balls = match key {
            SyncKey::OpticalPassage => balls_in_circuit.map(|b| b as usize).filter(|&b| b > 0),
            SyncKey::EncoderPitch => None,
        };
        Some(SyncStream {
            key,
            bins,
            fs,
            n,
            settings,
            per,
            rejected,
            balls,
            acc,
            next: (0, 0),
            ex: 0,
            prev: vec![0.0; k],
            at: 0,
        })
    }

    /// The analysed samples from `at` on, of every signal (detrended,
    /// low-passed, as the analysis' signals).
    pub(super) fn push(&mut self, at: usize, signals: &[Vec<f64>]) {
        let len = signals.first().map_or(0, Vec::len);
        debug_assert_eq!(at, self.at);
        for (i, k) in (at..at + len).enumerate() {
            let x: Vec<f64> = self.acc.iter().map(|a| signals[a.index][i]).collect();
            self.explained(k, &x);
            if k >= 1 {
                self.bins_up_to(k, &x);
            }
            self.prev = x;
        }
        self.at += len;
    }

    /// Reads every bin whose interpolation needs samples `k − 1` and `k`.
    fn bins_up_to(&mut self, k: usize, x: &[f64]) {
        let b = self.bins;
        while let Some(&(a, e, key)) = self.per.get(self.next.0) {
            let j = self.next.1;
            let t = a + (e - a) * j as f64 / b as f64;
            let u = (t * self.fs).clamp(0.0, (self.n - 1) as f64);
            let i = (u as usize).min(self.n.saturating_sub(2));
            if i + 1 > k {
                return;
            }
            let f = u - i as f64;
            for (acc, (p, c)) in self.acc.iter_mut().zip(self.prev.iter().zip(x)) {
                acc.row.push(acc.scale * (p + f * (c - p)));
            }
            self.next.1 += 1;
            if self.next.1 == b {
                self.next = (self.next.0 + 1, 0);
                let ball = self.balls.map(|nb| key % nb);
                for acc in &mut self.acc {
                    let row = std::mem::take(&mut acc.row);
                    let shift = acc.shift.get_or_insert_with(|| row.clone());
                    for j in 0..b {
                        let d = row[j] - shift[j];
                        acc.s1[j] += d;
                        acc.s2[j] += d * d;
                    }
                    if let Some(ball) = ball {
                        match acc.balls.iter_mut().find(|(n, _)| *n == ball) {
                            Some((_, s)) => s.iter_mut().zip(&row).for_each(|(s, v)| *s += v),
                            None => acc.balls.push((ball, row)),
                        }
                    }
                }
            }
        }
    }

    /// Adds sample `k` to the explained-variance sums of its period.
    fn explained(&mut self, k: usize, x: &[f64]) {
        let fs = self.fs;
        while let Some(&(a, e, _)) = self.per.get(self.ex) {
            let i1 = ((e * fs).ceil() as usize).min(self.n);
            if k >= i1 {
                self.ex += 1;
                continue;
            }
            let i0 = (a * fs).ceil() as usize;
            if k < i0 {
                return;
            }
            let phi = (k as f64 / fs - a) / (e - a);
            let b = self.bins;
            let u = phi.rem_euclid(1.0) * b as f64;
            let j = (u as usize).min(b - 1);
            let f = u - j as f64;
            let j1 = (j + 1) % b;
            for (acc, &v) in self.acc.iter_mut().zip(x) {
                let v = acc.scale * v;
                acc.sum += v;
                acc.sq += v * v;
                acc.count += 1;
                acc.w[j] += v * (1.0 - f);
                acc.w[j1] += v * f;
                acc.q[j] += (1.0 - f) * (1.0 - f);
                acc.q[j1] += f * f;
                acc.c[j] += f * (1.0 - f);
            }
            // A sample ends no period but its own.
            return;
        }
    }

    /// The average, or in words why there is none.
    pub(super) fn finish(self, source: &str) -> Result<SyncAverage, String> {
        let p = self.per.len();
        if p < 2 {
            return Err(format!(
                "{source}: synchronous average: {p} whole period(s) between the keys; at least 2 \
                 are needed"
            ));
        }
        let b = self.bins;
        let pf = p as f64;
        let tq = student_t_quantile(0.5 + self.settings.confidence / 2.0, pf - 1.0);
        let mut waveforms = Vec::new();
        let mut ball_means: Vec<(Signal, BallMeans)> = Vec::new();
        for acc in &self.acc {
            let shift = acc.shift.as_ref().expect("two periods read");
            let mean: Vec<f64> = (0..b).map(|j| shift[j] + acc.s1[j] / pf).collect();
            let half: Vec<f64> = (0..b)
                .map(|j| {
                    let d = acc.s1[j] / pf;
                    let ss = (acc.s2[j] - pf * d * d).max(0.0);
                    tq * (ss / (pf - 1.0)).sqrt() / pf.sqrt()
                })
                .collect();
            let res = acc.sq - 2.0 * (0..b).map(|j| mean[j] * acc.w[j]).sum::<f64>()
                + (0..b).map(|j| acc.q[j] * mean[j] * mean[j]).sum::<f64>()
                + 2.0
                    * (0..b)
                        .map(|j| acc.c[j] * mean[j] * mean[(j + 1) % b])
                        .sum::<f64>();
            let nf = acc.count as f64;
            let tot = acc.sq - acc.sum * acc.sum / nf.max(1.0);
            let explained = if acc.count > 0 && tot > 0.0 {
                1.0 - res / tot
            } else {
                0.0
            };
            let low = mean.iter().zip(&half).map(|(m, h)| m - h).collect();
            let high = mean.iter().zip(&half).map(|(m, h)| m + h).collect();
            waveforms.push(waveform(
                acc.signal,
                acc.unit,
                [mean, low, high],
                explained,
                p,
            ));
            let per_ball = acc
                .balls
                .iter()
                .map(|(ball, s)| {
                    let count = self
                        .per
                        .iter()
                        .filter(|q| q.2 % self.balls.unwrap_or(1) == *ball);
                    let c = count.count() as f64;
                    (*ball, s.iter().map(|v| v / c).collect())
                })
                .collect();
            ball_means.push((acc.signal, per_ball));
        }
        let per_ball = match self.balls {
            None if self.key == SyncKey::EncoderPitch => (
                Vec::new(),
                "balls not told apart: no optical passages (keyed on the encoder)".to_string(),
            ),
            None => (
                Vec::new(),
                "balls not told apart: the number of balls in the circuit is unknown (bearing \
                 not in the catalog)"
                    .to_string(),
            ),
            Some(_) if self.rejected > 0 => (
                Vec::new(),
                format!(
                    "balls not told apart: {} period(s) rejected (a passage missed or spurious), \
                     so the count after it is not the ball's",
                    self.rejected
                ),
            ),
            Some(nb) => {
                let mut rows = Vec::new();
                for ball in 0..nb {
                    let periods = self.per.iter().filter(|q| q.2 % nb == ball).count();
                    if periods == 0 {
                        continue;
                    }
                    let of = |s: Signal| {
                        ball_means
                            .iter()
                            .find(|(t, _)| *t == s)
                            .and_then(|(_, m)| m.iter().find(|(k, _)| *k == ball))
                            .map(|(_, m)| m.as_slice())
                    };
                    let pp = |m: &[f64]| {
                        m.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                            - m.iter().copied().fold(f64::INFINITY, f64::min)
                    };
                    let f = of(Signal::Friction);
                    rows.push(BallRow {
                        ball,
                        periods,
                        friction_peak_to_peak_n: f.map(pp),
                        velocity_error_peak_to_peak_um_s: of(Signal::VelocityError).map(pp),
                        friction_max_n: f
                            .map(|m| m.iter().copied().fold(f64::NEG_INFINITY, f64::max)),
                    });
                }
                let note = ball_note(&rows, nb);
                (rows, note)
            }
        };
        let all: Vec<f64> = self.per.iter().map(|&(a, e, _)| e - a).collect();
        let mut avg = finish(
            self.key,
            &self.settings,
            self.rejected,
            &all,
            waveforms,
            per_ball,
        );
        avg.notes.push(
            "streamed: periods summed as they were read (per-bin sums; the variance explained \
             from sums of the interpolation weights)"
                .into(),
        );
        Ok(avg)
    }
}
