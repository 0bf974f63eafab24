//! The stage fit's intervals checked against the data themselves: a
//! jackknife over groups of Welch segments.
//!
//! The fit's covariance rests on a model of the error of `H1` (its
//! variance from the coherence, the Hann window's correlation of
//! neighbouring bins, the residuals' own correlation). Where that model
//! misses something, the interval is too narrow and says so nowhere: on a
//! stiff stage excited mostly by the sharp harmonics of the ball-pass
//! ripple (lines about a bin apart, little random friction between them)
//! the errors of `H1` stay correlated over four bins and the load cell's
//! noise biases it by 12–18 % near the resonance; there the stated
//! standard error of `f_n` was about 3.5 times too small and most stages
//! claimed identified were more than 5 % off.
//!
//! So each record's segments are also summed into [`GROUPS`] slots
//! (segment `j` into slot `j mod 16`, pooled records slot by slot), and the
//! whole identification (band, bins, fit) is repeated with one slot left
//! out at a time. The spread of those fits is the delete-a-group
//! jackknife's variance (unequal groups: Busing, Meijer & van der Leeden,
//! *Statistics and Computing* 9, 1999), which carries whatever the error
//! model misses: bias that moves with the data, correlation, the selection
//! of bins, the non-linearity of the fit. For f_n and ζ (the values a
//! stage is claimed identified by) it replaces the stated variance where
//! it is larger at the 1 % level of a χ² test with one degree of freedom
//! fewer than groups; on a well-specified fit the two agree and the stated
//! one, less noisy, is kept (the jackknife's own variance is biased up a
//! little, Efron–Stein). A fit that fails when one group is left out has
//! no jackknife interval: the stage is then not claimed identified. The
//! check runs only where the fit would claim the stage: it can only widen
//! the intervals, so elsewhere it could not change the verdict. The groups
//! are summed on every record (a sweep pools them) from the estimate's own
//! segment transforms ([`ballpass_dsp::WelchStream::with_groups`]): a few
//! additions per segment.

use ballpass_dsp::{Complex64, SpectralSet, WelchStream};

use super::StageSpectra;
use crate::error::{Error, Result};

/// Slots the segments are summed into (segment `j` into `j mod GROUPS`).
pub const GROUPS: usize = 16;

/// Fewest non-empty groups for a jackknife (a single record has at least
/// seven segments: [`super::nperseg_for`]).
const MIN_GROUPS: usize = 3;

/// Bins kept in the groups beyond a quarter of the rate (the highest the
/// fit uses): the neighbourhood of the coherence's running mean.
const EXTRA_BINS: usize = 2 * super::SMOOTH_HALF_BINS;

/// The part of a Welch estimate that one group of segments contributes:
/// the sum of their spectra over the record's segment count (so that the
/// groups add up to the estimate), bins up to a quarter of the rate.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SegmentGroup {
    /// Friction auto-spectrum part, N²/Hz.
    pub p_ff: Vec<f64>,
    /// Velocity-error auto-spectrum part, (m/s)²/Hz.
    pub p_vv: Vec<f64>,
    /// Cross-spectrum part, N·(m/s)/Hz.
    pub p_fv: Vec<Complex64>,
    /// Segments summed.
    pub segments: usize,
}

impl SegmentGroup {
    /// A group from its part of the friction, velocity-error estimate
    /// (auto spectra in that order, their cross spectrum); an empty group
    /// without segments.
    pub(super) fn from_part(part: SpectralSet) -> SegmentGroup {
        if part.n_segments == 0 {
            return SegmentGroup::default();
        }
        let mut auto = part.auto.into_iter();
        SegmentGroup {
            p_ff: auto.next().unwrap_or_default(),
            p_vv: auto.next().unwrap_or_default(),
            p_fv: part.cross.into_iter().next().unwrap_or_default(),
            segments: part.n_segments,
        }
    }

    fn add(&mut self, other: &SegmentGroup) {
        if self.p_ff.is_empty() {
            *self = other.clone();
            return;
        }
        for (a, b) in self.p_ff.iter_mut().zip(&other.p_ff) {
            *a += b;
        }
        for (a, b) in self.p_vv.iter_mut().zip(&other.p_vv) {
            *a += b;
        }
        for (a, b) in self.p_fv.iter_mut().zip(&other.p_fv) {
            *a += b;
        }
        self.segments += other.segments;
    }
}

/// Adds `other`'s groups to `mine` slot by slot (pooled records).
pub(super) fn add_groups(mine: &mut Vec<SegmentGroup>, other: &[SegmentGroup]) {
    if mine.len() < other.len() {
        mine.resize(other.len(), SegmentGroup::default());
    }
    for (a, b) in mine.iter_mut().zip(other) {
        a.add(b);
    }
}

/// The Welch stream of the identification spectra ([`StageSpectra::welch_settings`])
/// that also sums its segments into [`GROUPS`] groups over the bins the
/// fit can use (up to a quarter of the rate, plus [`EXTRA_BINS`]).
///
/// # Errors
/// [`Error::Dsp`] if the Welch settings are rejected.
pub(crate) fn grouped_welch(nperseg: usize) -> Result<WelchStream> {
    let keep = nperseg / 4 + 1 + EXTRA_BINS;
    WelchStream::new(StageSpectra::welch_settings(nperseg), 2, &[(0, 1)])
        .and_then(|w| w.with_groups(GROUPS, keep))
        .map_err(|e| Error::dsp("stage identification Welch", e))
}

/// The spectra with group `g` left out, as a Welch average of the rest;
/// `None` when the group is empty or holds every segment.
fn leave_out(s: &StageSpectra, g: usize) -> Option<StageSpectra> {
    let grp = s.groups.get(g)?;
    let total: usize = s.groups.iter().map(|x| x.segments).sum();
    if grp.segments == 0 || grp.segments >= total {
        return None;
    }
    let k = grp.p_ff.len().min(s.freq_hz.len());
    let scale = total as f64 / (total - grp.segments) as f64;
    let sub = |a: &[f64], b: &[f64]| -> Vec<f64> {
        a[..k]
            .iter()
            .zip(&b[..k])
            .map(|(x, y)| (x - y) * scale)
            .collect()
    };
    Some(StageSpectra {
        fs_hz: s.fs_hz,
        freq_hz: s.freq_hz[..k].to_vec(),
        p_ff: sub(&s.p_ff, &grp.p_ff),
        p_vv: sub(&s.p_vv, &grp.p_vv),
        p_fv: s.p_fv[..k]
            .iter()
            .zip(&grp.p_fv[..k])
            .map(|(x, y)| (x - y) * scale)
            .collect(),
        records: s.records,
        n_d: s.n_d * (total - grp.segments) as f64 / total as f64,
        restored_tau_s: s.restored_tau_s,
        groups: Vec::new(),
        encoder: s.encoder,
    })
}

/// The jackknife standard errors of the values `values` picks from a fit
/// (`None` for a failed fit), given the full fit's values `full`: one
/// entry per value, infinite when a leave-one-out fit failed; `None` when
/// the spectra carry fewer than three non-empty groups.
pub(super) fn standard_errors<const K: usize>(
    s: &StageSpectra,
    full: [f64; K],
    fit: impl Fn(&StageSpectra) -> Option<[f64; K]> + Sync,
) -> Option<[f64; K]> {
    use rayon::prelude::*;
    let total: usize = s.groups.iter().map(|x| x.segments).sum();
    let used: Vec<usize> = (0..s.groups.len())
        .filter(|&g| s.groups[g].segments > 0)
        .collect();
    if used.len() < MIN_GROUPS || total == 0 {
        return None;
    }
    let fits: Vec<Option<[f64; K]>> = used
        .par_iter()
        .map(|&g| leave_out(s, g).and_then(|sp| fit(&sp)))
        .collect();
    if fits.iter().any(Option::is_none) {
        return Some([f64::INFINITY; K]);
    }
    // Delete-m_h jackknife (module docs): h = n / m_h, pseudo-values
    // h θ̂ − (h − 1) θ_(−h), their weighted mean, and the variance.
    let n = total as f64;
    let gcount = used.len() as f64;
    Some(std::array::from_fn(|k| {
        let parts: Vec<(f64, f64)> = used
            .iter()
            .zip(&fits)
            .map(|(&g, f)| {
                let h = n / s.groups[g].segments as f64;
                (h, f.map_or(f64::NAN, |v| v[k]))
            })
            .collect();
        let theta_j =
            gcount * full[k] - parts.iter().map(|&(h, t)| (1.0 - 1.0 / h) * t).sum::<f64>();
        let var = parts
            .iter()
            .map(|&(h, t)| {
                let pseudo = h * full[k] - (h - 1.0) * t;
                (pseudo - theta_j).powi(2) / (h - 1.0)
            })
            .sum::<f64>()
            / gcount;
        if var.is_finite() {
            var.max(0.0).sqrt()
        } else {
            f64::INFINITY
        }
    }))
}
