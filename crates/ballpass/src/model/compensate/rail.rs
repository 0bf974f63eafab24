//! The table against rail position: the rail grid fitted to the optical
//! passages, and when the table is also given against it (the passages
//! lock to the grid, and the records share one encoder frame).

use serde::Serialize;

use super::travel;
use crate::analysis::Analysis;
/// Largest rms distance of the passages from their rail grid, as a fraction
/// of the pitch, for the rail-position table.
pub const RAIL_LOCK_FRACTION: f64 = 0.05;

/// Largest spread of the records' mean distances from the rail grid, as a
/// fraction of the pitch, for the rail-position table from several
/// records (records of one encoder frame agree; a record re-zeroed in
/// between sits apart). Set on training benches (docs/methods.md §14).
pub const RECORD_OFFSET_LIMIT: f64 = 0.05;

/// The table against rail position.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RailTable {
    /// Encoder position of phase 0 (an optical passage), mm.
    pub x0_mm: f64,
    /// Travel per period fitted to the passages, mm.
    pub pitch_mm: f64,
    /// Spacing of the table's positions, mm (`pitch / B`).
    pub spacing_mm: f64,
    /// Rms distance of the passages from the grid, mm.
    pub lock_rms_mm: f64,
}

/// The rail grid fitted to the optical passages, whether or not they lock
/// to it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RailGrid {
    /// Encoder position of phase 0 (an optical passage), mm.
    pub x0_mm: f64,
    /// Travel per period fitted to the passages, mm.
    pub pitch_mm: f64,
    /// Rms distance of the passages from the grid, mm.
    pub lock_rms_mm: f64,
    /// The same as a fraction of the pitch (locked when ≤
    /// [`RAIL_LOCK_FRACTION`]).
    pub lock_fraction: f64,
    /// Each record's phase on the grid relative to the first record's
    /// (one intercept per record on a common pitch), fraction of the
    /// pitch, within ±1/2 (records of one encoder frame agree).
    pub record_offsets: Vec<f64>,
    /// Largest minus smallest of `record_offsets` (0 for one record;
    /// locked only when ≤ [`RECORD_OFFSET_LIMIT`]).
    pub offset_spread: f64,
}

/// The rail grid of the optical passages of every record, with the table
/// when they lock to it and the records share one encoder frame.
pub(super) fn rail_table(
    keys: &std::result::Result<Vec<travel::RecordKeys>, String>,
    a: &Analysis,
    bins: usize,
) -> (Option<RailTable>, String, Option<RailGrid>) {
    let grid = match keys {
        Ok(k) => rail_grid(k, 2.0 * a.prediction.d_avg_mm),
        Err(why) => Err(format!("no rail table: {why}")),
    };
    match grid {
        Err(why) => (None, why, None),
        Ok(g) if g.lock_fraction > RAIL_LOCK_FRACTION => (
            None,
            format!(
                "no rail table: the passages wander {:.1} % of a pitch (rms) from a rail grid \
                 (limit {:.0} %); use the table keyed on the passages",
                100.0 * g.lock_fraction,
                100.0 * RAIL_LOCK_FRACTION
            ),
            Some(g),
        ),
        Ok(g) if g.offset_spread > RECORD_OFFSET_LIMIT => (
            None,
            format!(
                "no rail table: the records' passages sit {:.1} % of a pitch apart on the rail grid \
                 (limit {:.0} %): the records do not share one encoder frame (re-homed or \
                 re-zeroed between them?); use the table keyed on the passages, or records of \
                 one frame",
                100.0 * g.offset_spread,
                100.0 * RECORD_OFFSET_LIMIT
            ),
            Some(g),
        ),
        Ok(g) => (
            Some(RailTable {
                x0_mm: g.x0_mm,
                pitch_mm: g.pitch_mm,
                spacing_mm: g.pitch_mm / bins as f64,
                lock_rms_mm: g.lock_rms_mm,
            }),
            format!(
                "the passages lock to the rail: rms {:.1} % of the pitch from x0 + k·{:.4} mm \
                 (limit {:.0} %){}",
                100.0 * g.lock_fraction,
                g.pitch_mm,
                100.0 * RAIL_LOCK_FRACTION,
                if g.record_offsets.len() > 1 {
                    format!(
                        ", the records within {:.1} % of a pitch of each other (limit {:.0} %)",
                        100.0 * g.offset_spread,
                        100.0 * RECORD_OFFSET_LIMIT
                    )
                } else {
                    String::new()
                }
            ),
            Some(g),
        ),
    }
}

/// The rail grid fitted to the optical passages of every record (`pitch0`
/// the predicted travel per period), or why there is none.
pub(super) fn rail_grid(
    keys: &[travel::RecordKeys],
    pitch0: f64,
) -> std::result::Result<RailGrid, String> {
    let pos: Vec<f64> = keys
        .iter()
        .flat_map(|k| k.passage_mm.iter().copied())
        .collect();
    if pos.len() < 3 {
        return Err("no rail table: fewer than 3 passages".into());
    }
    // Grid index of each passage from the predicted pitch, then a line.
    let x_first = pos[0];
    let k: Vec<f64> = pos
        .iter()
        .map(|x| ((x - x_first) / pitch0).round())
        .collect();
    let Some(fit) = crate::stats::linear_fit(&k, &pos) else {
        return Err("no rail table: the passage positions do not fit a line".into());
    };
    let (pitch, x0) = (fit.slope, fit.intercept);
    let resid: Vec<f64> = k
        .iter()
        .zip(&pos)
        .map(|(k, x)| x - x0 - k * pitch)
        .collect();
    let rms = (resid.iter().map(|r| r * r).sum::<f64>() / pos.len() as f64).sqrt();
    // Each record's own phase on a common pitch: x = x0_r + k·p with one
    // intercept per record (a step between records is not absorbed by the
    // slope, as it is in the single line), offsets relative to the first
    // record, wrapped to ±p/2, fraction of the pitch.
    let mut spans = Vec::with_capacity(keys.len());
    let mut at = 0;
    for kk in keys {
        let n = kk.passage_mm.len();
        if n >= 2 {
            spans.push(at..at + n);
        }
        at += n;
    }
    let (mut sxy, mut sxx) = (0.0, 0.0);
    let means: Vec<(f64, f64)> = spans
        .iter()
        .map(|r| {
            let n = r.len() as f64;
            let km = k[r.clone()].iter().sum::<f64>() / n;
            let xm = pos[r.clone()].iter().sum::<f64>() / n;
            for i in r.clone() {
                sxy += (k[i] - km) * (pos[i] - xm);
                sxx += (k[i] - km).powi(2);
            }
            (km, xm)
        })
        .collect();
    let p_common = if sxx > 0.0 { sxy / sxx } else { pitch };
    let x0s: Vec<f64> = means.iter().map(|(km, xm)| xm - p_common * km).collect();
    let record_offsets: Vec<f64> = x0s
        .iter()
        .map(|x| {
            let d = (x - x0s[0]) / p_common.abs();
            d - d.round()
        })
        .collect();
    let spread = record_offsets
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max)
        - record_offsets.iter().copied().fold(f64::INFINITY, f64::min);
    Ok(RailGrid {
        x0_mm: x0,
        pitch_mm: pitch,
        lock_rms_mm: rms,
        lock_fraction: rms / pitch.abs(),
        record_offsets,
        offset_spread: if spread.is_finite() { spread } else { 0.0 },
    })
}
