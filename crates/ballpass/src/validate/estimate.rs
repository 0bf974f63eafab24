//! A lab's own validation domain, estimated from its recordings.
//!
//! `ballpass validate --from REC...` analyses each recording as `analyze`
//! would and narrows the randomized grid to what the records show; what
//! they cannot show keeps the grid's range, and the notes say which is
//! which:
//!
//! | key | from |
//! |---|---|
//! | `fs_hz` | the records' rates |
//! | `duration_s` | the records' lengths (shortest to longest) |
//! | `velocity_mm_s` | the records' velocities |
//! | geometry | the bearing given (fixed) |
//! | `load_cell_tau_s`, `load_cell_dc_probability` | the discharge identified in the records (× / ÷ 1.5 around the estimates, never DC coupled); DC coupled when every record shows a DC level and no discharge |
//! | `stage_f_n_hz`, `stage_zeta` | the stage identified from the records: its 95 % interval, at least ±5 % / ±20 % |
//! | `optical_width_ratio` | the optical pulses' mean width at half prominence over `τc` (× / ÷ 1.25, within 0.02–0.6) |
//! | everything else | the full grid (noise, ripple, roughness, optical SNR, coupling and drift, sticking) |
//!
//! The margins are not fitted to anything: they keep the estimates'
//! own scatter (a discharge time constant from one record is good to tens of
//! per cent, a pulse width to a few) inside the range drawn from, so that
//! the rates measured there are the bench's and not one point's.

use serde::Serialize;

use super::bench::{Domain, Range};
use crate::analysis::{analyze, AnalyzeSettings};
use crate::bearing::Geometry;
use crate::error::Result;
use crate::recording::Recording;

/// The domain estimated from recordings, with what was estimated and what
/// kept the grid's range.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DomainEstimate {
    /// The domain to validate on.
    pub domain: Domain,
    /// One line per key: the estimate and where it came from, or why the
    /// grid's range was kept.
    pub notes: Vec<String>,
}

/// The smallest and largest of `v` as a range (`None` if empty).
fn span(v: &[f64], log: bool) -> Option<Range> {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (lo.is_finite() && hi.is_finite()).then_some(Range { lo, hi, log })
}

/// Estimates a validation domain from `records` (each with its velocity,
/// mm/s) of one bearing `geometry`; `base` gives the ranges of what the
/// records cannot show (module docs).
///
/// # Errors
/// The first record the analysis refuses, with its error.
pub fn estimate_domain(
    records: &[(Recording, f64)],
    geometry: &Geometry,
    base: &Domain,
) -> Result<DomainEstimate> {
    let mut d = base.clone();
    let mut notes = Vec::new();
    let settings = AnalyzeSettings::default();
    let mut taus = Vec::new();
    let mut dc_coupled = 0usize;
    let mut with_friction = 0usize;
    let mut widths = Vec::new();
    let mut stages = Vec::new();
    for (rec, v) in records {
        let pred = geometry.predict(*v, settings.harmonics)?;
        let a = analyze(std::slice::from_ref(rec), &pred, &settings)?;
        if let Some(lc) = a.load_cell.first() {
            with_friction += 1;
            match (lc.applied, lc.tau_s) {
                (true, Some(t)) => taus.push(t),
                (false, _) if !lc.unknown_high_pass => dc_coupled += 1,
                _ => {}
            }
        }
        widths.extend(
            a.passages
                .iter()
                .filter_map(|p| p.tau_p_over_tau_c.map(|m| m.mean)),
        );
        if let Some(st) = a.stage.as_ref().filter(|s| s.identified) {
            if let (Some(f), Some(z)) = (st.natural_frequency_hz, st.damping_ratio) {
                stages.push((f, z));
            }
        }
    }
    let n = records.len();
    let mut fs: Vec<f64> = records.iter().map(|(r, _)| r.fs_hz()).collect();
    fs.sort_by(f64::total_cmp);
    fs.dedup();
    if !fs.is_empty() {
        notes.push(format!("fs_hz {fs:?}: the records' sampling rates"));
        d.fs_hz = fs;
    }
    let lengths: Vec<f64> = records.iter().map(|(r, _)| r.duration_s()).collect();
    if let Some(r) = span(&lengths, true) {
        d.duration_s = Range {
            lo: r.lo.max(10.0),
            hi: r.hi.max(10.0),
            log: true,
        };
        notes.push(format!(
            "duration_s {:.1}–{:.1} s: the records' lengths (at least 10 s, the shortest the suite simulates)",
            d.duration_s.lo, d.duration_s.hi
        ));
    }
    let speeds: Vec<f64> = records.iter().map(|(_, v)| *v).collect();
    if let Some(r) = span(&speeds, false) {
        notes.push(format!(
            "velocity_mm_s {:.3}–{:.3} mm/s: the records' velocities",
            r.lo, r.hi
        ));
        d.velocity_mm_s = r;
    }
    let dia = geometry.ball_diameter_mm;
    d.ball_diameter_mm = Range::fixed(dia);
    d.balls_in_race = Range::fixed(f64::from(geometry.balls_in_race));
    d.free_space_per_ball = Range::fixed(geometry.free_space_mm / dia);
    notes.push(format!(
        "geometry fixed: ball {dia:.3} mm, {} balls, free space {:.3} mm (the bearing given)",
        geometry.balls_in_race, geometry.free_space_mm
    ));
    if let Some(r) = span(&taus, true) {
        d.load_cell_tau_s = Range::log(r.lo / 1.5, r.hi * 1.5);
        d.load_cell_dc_probability = 0.0;
        notes.push(format!(
            "load_cell_tau_s {:.3}–{:.3} s: the discharge identified in {} of {with_friction} records ({:.3}–{:.3} s), × / ÷ 1.5",
            d.load_cell_tau_s.lo,
            d.load_cell_tau_s.hi,
            taus.len(),
            r.lo,
            r.hi
        ));
    } else if with_friction > 0 && dc_coupled == with_friction {
        d.load_cell_dc_probability = 1.0;
        notes.push(format!(
            "load cell DC coupled: none of the {with_friction} records shows a discharge"
        ));
    } else {
        notes.push(
            "load-cell discharge kept at the grid's range: the records do not identify it"
                .to_string(),
        );
    }
    if stages.is_empty() {
        notes.push(
            "stage kept at the grid's range: not identifiable from these records".to_string(),
        );
    } else {
        let f_lo = stages
            .iter()
            .map(|(f, _)| (f.value - f.ci95).min(0.95 * f.value))
            .fold(f64::INFINITY, f64::min);
        let f_hi = stages
            .iter()
            .map(|(f, _)| (f.value + f.ci95).max(1.05 * f.value))
            .fold(f64::NEG_INFINITY, f64::max);
        let z_lo = stages
            .iter()
            .map(|(_, z)| (z.value - z.ci95).min(0.8 * z.value))
            .fold(f64::INFINITY, f64::min);
        let z_hi = stages
            .iter()
            .map(|(_, z)| (z.value + z.ci95).max(1.2 * z.value))
            .fold(f64::NEG_INFINITY, f64::max);
        d.stage_f_n_hz = Range::log(f_lo.max(1e-3), f_hi);
        d.stage_zeta = Range::lin(z_lo.max(0.01), z_hi);
        notes.push(format!(
            "stage f_n {f_lo:.2}–{f_hi:.2} Hz, ζ {:.2}–{z_hi:.2}: identified in {} of {n} records (95 % intervals, at least ±5 % / ±20 %)",
            z_lo.max(0.01),
            stages.len()
        ));
    }
    if let Some(r) = span(&widths, false) {
        d.optical_width_ratio = Range::lin(
            (r.lo / 1.25).clamp(0.02, 0.6),
            (r.hi * 1.25).clamp(0.02, 0.6),
        );
        notes.push(format!(
            "optical_width_ratio {:.3}–{:.3} τc: the pulses' width at half prominence ({:.3}–{:.3} τc), × / ÷ 1.25",
            d.optical_width_ratio.lo, d.optical_width_ratio.hi, r.lo, r.hi
        ));
    } else {
        notes.push(
            "optical pulse width kept at the grid's range: no optical passages measured"
                .to_string(),
        );
    }
    notes.push(
        "kept at the grid's ranges (not estimated): friction noise, ripple and pulse shapes, rail roughness, Coulomb level, optical SNR, coupling, drift and interference, sticking"
            .to_string(),
    );
    d.validate()?;
    Ok(DomainEstimate { domain: d, notes })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::simulate;

    /// Records simulated on one known bench: the estimated domain must hold
    /// that bench's rate, length, velocity, geometry and (where the records
    /// identify them) its discharge time constant and optical pulse width.
    #[test]
    fn the_domain_holds_the_bench_the_records_came_from() {
        let grid = Domain::default();
        for seed in 9_100_000..9_100_006u64 {
            let mut b = grid.draw(seed);
            // Short records keep the test fast; the duration is checked as given.
            b.duration_s = b.duration_s.min(30.0);
            let s = b.settings(&b.bearing(0, false), seed);
            let sim = simulate(&s).unwrap();
            let est =
                estimate_domain(&[(sim.recording, b.velocity_mm_s)], &b.geometry, &grid).unwrap();
            let d = &est.domain;
            assert_eq!(d.fs_hz, vec![b.fs_hz]);
            let inside = |r: &Range, x: f64| r.lo * (1.0 - 1e-9) <= x && x <= r.hi * (1.0 + 1e-9);
            assert!(inside(&d.velocity_mm_s, b.velocity_mm_s));
            assert!(
                (d.duration_s.lo - b.duration_s.max(10.0)).abs() < 0.01,
                "{:?} {}",
                d.duration_s,
                b.duration_s
            );
            assert_eq!(
                d.ball_diameter_mm,
                Range::fixed(b.geometry.ball_diameter_mm)
            );
            if d.load_cell_dc_probability == 0.0 {
                let tau = s
                    .load_cell
                    .time_constant_s
                    .expect("a discharge was identified");
                assert!(
                    inside(&d.load_cell_tau_s, tau),
                    "{:?} {tau}",
                    d.load_cell_tau_s
                );
            }
            if d.load_cell_dc_probability == 1.0 {
                // DC coupled, or a discharge too slow for the record to show.
                let t = s.load_cell.time_constant_s.unwrap_or(f64::INFINITY);
                assert!(t >= b.duration_s, "seed {seed}: τ {t} called DC coupled");
            }
            if d.optical_width_ratio != grid.optical_width_ratio {
                assert!(
                    inside(&d.optical_width_ratio, s.optical.width_ratio),
                    "seed {seed}: {:?} {}",
                    d.optical_width_ratio,
                    s.optical.width_ratio
                );
            }
        }
    }
}
