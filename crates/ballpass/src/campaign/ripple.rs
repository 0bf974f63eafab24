//! The ball-pass ripple in the position domain, per record and per
//! velocity of a sweep: the amplitude of the friction's and the velocity
//! error's lines at `k / (2 d_avg)` cycles/mm ([`crate::analysis::position`])
//! with their confidence intervals.
//!
//! In the position domain the line sits at the same place at every speed,
//! so the records of one velocity are pooled as Welch pools segments: the
//! mean of their line powers and floors, the sum of their degrees of
//! freedom, and the interval of [`line_amplitude_band`] on the pooled
//! numbers.

use serde::{Deserialize, Serialize};

use super::record::RecordResult;
use crate::analysis::confidence::psd_band_factors;
use crate::analysis::position::{line_amplitude_band, PositionSpectra};
use crate::analysis::Signal;

/// The signals whose ripple a sweep reports, with their unit and the factor
/// from the position spectra's unit (N, mm/s) to it.
pub const RIPPLE_SIGNALS: [(Signal, &str, f64); 2] = [
    (Signal::Friction, "N", 1.0),
    (Signal::VelocityError, "µm/s", 1e3),
];

/// Column-name token of a ripple unit (`n`, `um_s`).
pub fn unit_token(unit: &str) -> &'static str {
    if unit == "N" {
        "n"
    } else {
        "um_s"
    }
}

/// One line of one record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RippleLine {
    /// Signal (friction or velocity error).
    pub signal: Signal,
    /// Harmonic `k` of `1 / (2 d_avg)`.
    pub k: usize,
    /// Unit of the amplitudes: `N` or `µm/s`.
    pub unit: String,
    /// Amplitude of the line as a sinusoid.
    pub amplitude: f64,
    /// Lower end of its confidence interval.
    pub amplitude_lower: Option<f64>,
    /// Upper end of its confidence interval.
    pub amplitude_upper: Option<f64>,
    /// Line power above the floor, unit².
    pub power: f64,
    /// The floor's share of the bins summed, unit².
    pub floor_power: f64,
    /// Equivalent degrees of freedom of a bin.
    pub dof: f64,
    /// Confidence of the interval (the analysis' `band_confidence`).
    pub confidence: f64,
}

/// Fewest bins a line's floor must be measured over for the sweep to
/// report the line: the median of fewer scatters as much as the line's own
/// bins (a record with 8 periods per segment has 4 at k = 1; one with 4
/// periods has none or one or two, and its lines are left out).
pub const MIN_FLOOR_BINS: usize = 4;

/// The lines of a record's position spectra that can be told from their
/// floor (at least [`MIN_FLOOR_BINS`] bins of it), in the sweep's units.
pub fn record_lines(p: &PositionSpectra) -> Vec<RippleLine> {
    let mut out = Vec::new();
    for (signal, unit, scale) in RIPPLE_SIGNALS {
        for l in p
            .lines
            .iter()
            .filter(|l| l.signal == signal && l.floor_bins >= MIN_FLOOR_BINS)
        {
            out.push(RippleLine {
                signal,
                k: l.k,
                unit: unit.to_string(),
                amplitude: l.amplitude * scale,
                amplitude_lower: l.amplitude_lower.map(|a| a * scale),
                amplitude_upper: l.amplitude_upper.map(|a| a * scale),
                power: l.power * scale * scale,
                floor_power: l.floor_power * scale * scale,
                dof: p.dof,
                confidence: p.band.map_or(0.95, |b| b.confidence),
            });
        }
    }
    out
}

/// One line at one velocity, pooled over its records.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VelocityRipple {
    /// Signal.
    pub signal: Signal,
    /// Harmonic `k`.
    pub k: usize,
    /// Unit of the amplitudes: `N` or `µm/s`.
    pub unit: String,
    /// Records pooled.
    pub records: usize,
    /// Amplitude of the pooled line, `sqrt(2 · mean power)`.
    pub amplitude: f64,
    /// Lower end of its confidence interval.
    pub amplitude_lower: Option<f64>,
    /// Upper end of its confidence interval.
    pub amplitude_upper: Option<f64>,
    /// Degrees of freedom pooled (sum over the records).
    pub dof: f64,
    /// Confidence of the interval.
    pub confidence: f64,
}

/// Pools the lines of the records of one velocity (module docs), at the
/// confidence of their bands.
pub fn pool(records: &[&RecordResult]) -> Vec<VelocityRipple> {
    let mut keys: Vec<(Signal, usize)> = records
        .iter()
        .flat_map(|r| r.position_ripple.iter().map(|l| (l.signal, l.k)))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.into_iter()
        .filter_map(|(signal, k)| {
            let lines: Vec<&RippleLine> = records
                .iter()
                .filter_map(|r| {
                    r.position_ripple
                        .iter()
                        .find(|l| l.signal == signal && l.k == k)
                })
                .collect();
            let n = lines.len() as f64;
            let first = lines.first()?;
            let power = lines.iter().map(|l| l.power).sum::<f64>() / n;
            let floor = lines.iter().map(|l| l.floor_power).sum::<f64>() / n;
            let dof: f64 = lines.iter().map(|l| l.dof).sum();
            let band = psd_band_factors(dof, first.confidence)
                .map(|f| line_amplitude_band(power, floor, f));
            Some(VelocityRipple {
                signal,
                k,
                unit: first.unit.clone(),
                records: lines.len(),
                amplitude: (2.0 * power).sqrt(),
                amplitude_lower: band.map(|b| b[0]),
                amplitude_upper: band.map(|b| b[1]),
                dof,
                confidence: first.confidence,
            })
        })
        .collect()
}

/// A sentence on the fundamental's ripple across the sweep, per signal:
/// its range over the velocities and where it is largest; and the
/// velocities without a position-domain line.
pub fn finding(rows: &[(f64, &[VelocityRipple])]) -> Vec<String> {
    let mut out = Vec::new();
    for (signal, unit, _) in RIPPLE_SIGNALS {
        let pts: Vec<(f64, &VelocityRipple)> = rows
            .iter()
            .filter_map(|(v, r)| {
                r.iter()
                    .find(|l| l.signal == signal && l.k == 1)
                    .map(|l| (*v, l))
            })
            .collect();
        let Some((v_max, l_max)) = pts
            .iter()
            .max_by(|a, b| a.1.amplitude.total_cmp(&b.1.amplitude))
        else {
            continue;
        };
        let (_, l_min) = pts
            .iter()
            .min_by(|a, b| a.1.amplitude.total_cmp(&b.1.amplitude))
            .expect("non-empty");
        let sig = 3;
        out.push(format!(
            "{} ripple at 1/(2 d_avg) in the position domain: amplitude {}–{} {unit} over {} \
             velocities, largest at {v_max} mm/s",
            signal.words(),
            crate::report::kinds::fmt_sig(l_min.amplitude, sig),
            crate::report::kinds::fmt_sig(l_max.amplitude, sig),
            pts.len()
        ));
    }
    let missing: Vec<String> = rows
        .iter()
        .filter(|(_, r)| !r.iter().any(|l| l.k == 1))
        .map(|(v, _)| format!("{v}"))
        .collect();
    if !missing.is_empty() && missing.len() < rows.len() {
        out.push(format!(
            "no position-domain line at {} mm/s: too little travel in one direction to tell \
             the line from its floor",
            missing.join(", ")
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::sweep::tests::record;

    fn line(signal: Signal, power: f64, floor: f64, dof: f64) -> RippleLine {
        RippleLine {
            signal,
            k: 1,
            unit: "N".into(),
            amplitude: (2.0 * power).sqrt(),
            amplitude_lower: None,
            amplitude_upper: None,
            power,
            floor_power: floor,
            dof,
            confidence: 0.95,
        }
    }

    /// Pooling averages the powers and floors and adds the degrees of
    /// freedom: the pooled interval is the one of the averaged numbers, and
    /// narrower than one record's.
    #[test]
    fn pooling_averages_powers_and_adds_dof() {
        let mut a = record(9.0, 1);
        let mut b = record(9.0, 2);
        a.position_ripple = vec![line(Signal::Friction, 0.002, 0.0004, 20.0)];
        b.position_ripple = vec![line(Signal::Friction, 0.004, 0.0002, 20.0)];
        let p = pool(&[&a, &b]);
        assert_eq!(p.len(), 1);
        let l = &p[0];
        assert_eq!((l.records, l.dof), (2, 40.0));
        assert!((l.amplitude - (2.0f64 * 0.003).sqrt()).abs() < 1e-15);
        let f = psd_band_factors(40.0, 0.95).unwrap();
        let want = line_amplitude_band(0.003, 0.0003, f);
        assert_eq!(
            [l.amplitude_lower.unwrap(), l.amplitude_upper.unwrap()],
            want
        );
        let one = line_amplitude_band(0.003, 0.0003, psd_band_factors(20.0, 0.95).unwrap());
        assert!(want[0] > one[0] && want[1] < one[1], "{want:?} {one:?}");
        assert!(want[0] < l.amplitude && l.amplitude < want[1]);
    }

    /// A line no stronger than the noise on its floor has a lower bound of 0.
    #[test]
    fn a_weak_line_has_a_lower_bound_of_zero() {
        let f = psd_band_factors(10.0, 0.95).unwrap();
        let [lo, hi] = line_amplitude_band(1e-6, 1e-3, f);
        assert_eq!(lo, 0.0);
        assert!(hi > (2.0f64 * 1e-6).sqrt());
    }
}
