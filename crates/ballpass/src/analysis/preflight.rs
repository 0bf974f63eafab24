//! Checks before any verdict: channels that carry nothing (dead or flat),
//! the velocity the encoder measures against the one stated, and a
//! ball-pass frequency that the sampling cannot show.
//!
//! [`check`] takes the loaded records and the stated velocity (if any) and
//! returns the records to analyse, the velocity to use and what the user
//! must be told:
//!
//! - **Dead or flat channel**: its samples span at most `flat_relative`
//!   times their magnitude (`max - min <= 1e-12 max(|max|, |min|)`, all
//!   zeros included). Float rounding of a constant (scales, offsets, text
//!   round trips) stays near `1e-16` relative; the finest converters
//!   (32 bits) resolve `2.3e-10` of full scale; `1e-12` lies between. Such a
//!   channel is left out of the analysis with a warning: its spectrum after
//!   filtering is rounding noise (PSD ~1e-28) that must not become a
//!   finding. A position that is an exact ramp (its sample-to-sample steps
//!   equal within `1e-6`, far below any encoder's quantisation or a stage's
//!   speed ripple) gives a velocity error of rounding noise and is left out
//!   of the findings too, after its slope has been measured.
//!   With every channel left out, the record is an error.
//! - **Velocity**: the encoder's velocity is the least-squares slope of
//!   the position over the record. With a stated velocity (flag, profile,
//!   file or manifest), a measured speed that differs by more than
//!   `velocity_tolerance` (5 %) is an error naming both numbers, unless
//!   `force_velocity` (then a warning). Without one, the measured speed is
//!   used (all records must agree within the tolerance) and the outputs say
//!   it was measured. A stage moving backward is noted.
//! - **Nyquist**: a predicted ball-pass frequency at or above `fs / 2` is an
//!   error whatever is forced: nothing can be measured there.

use serde::{Deserialize, Serialize};

use crate::bearing::Geometry;
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};

/// Thresholds of [`check`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PreflightSettings {
    /// A channel spanning at most this fraction of its magnitude is flat.
    pub flat_relative: f64,
    /// A position whose steps span at most this fraction of the largest
    /// step is an exact ramp.
    pub ramp_relative: f64,
    /// Largest relative difference between the measured and the stated speed.
    pub velocity_tolerance: f64,
    /// Analyse at the stated velocity even when the encoder contradicts it.
    pub force_velocity: bool,
}

impl Default for PreflightSettings {
    fn default() -> Self {
        Self {
            flat_relative: 1e-12,
            ramp_relative: 1e-6,
            velocity_tolerance: 0.05,
            force_velocity: false,
        }
    }
}

/// Where the velocity used came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VelocitySource {
    /// Given by the user, a profile, the file or a manifest.
    Stated,
    /// Measured from the encoder (none was given).
    Measured,
}

impl VelocitySource {
    /// `stated` or `measured from the encoder`.
    pub fn words(self) -> &'static str {
        match self {
            VelocitySource::Stated => "stated",
            VelocitySource::Measured => "measured from the encoder",
        }
    }
}

/// What [`check`] found.
#[derive(Debug, Clone)]
pub struct Checked {
    /// The records to analyse (dead channels left out).
    pub recordings: Vec<Recording>,
    /// The velocity to analyse at, mm/s (positive).
    pub velocity_mm_s: f64,
    /// Where it came from.
    pub velocity_source: VelocitySource,
    /// The encoder's velocity of each record, mm/s (signed; `None` without
    /// a usable position channel).
    pub measured_mm_s: Vec<Option<f64>>,
    /// Prominent warnings (dead channels, a forced velocity).
    pub warnings: Vec<String>,
    /// Things worth saying that do not question the result (measured
    /// velocity, backward motion).
    pub notes: Vec<String>,
}

/// Whether `x` spans at most `rel` of its magnitude (constant, or rounding
/// of a constant).
pub fn is_flat(x: &[f64], rel: f64) -> bool {
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    hi - lo <= rel * hi.abs().max(lo.abs())
}

/// The stage velocity from the position channel: least-squares slope,
/// mm/s, signed; `None` without a position channel.
pub fn measure_velocity(rec: &Recording) -> Option<f64> {
    let x = rec.channel(Channel::Position)?;
    Some(crate::recording::segment::slope(x) * rec.fs_hz())
}

/// Whether the position's sample-to-sample steps are all equal within
/// `rel` of the largest (an exact ramp).
fn is_exact_ramp(x: &[f64], rel: f64) -> bool {
    let (mut lo, mut hi, mut big) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for w in x.windows(2) {
        let d = w[1] - w[0];
        lo = lo.min(d);
        hi = hi.max(d);
        big = big.max(d.abs());
    }
    big > 0.0 && hi - lo <= rel * big
}

fn value_text(x: f64, c: Channel) -> String {
    format!("{x} {}", c.unit())
}

/// The channel checks alone (dead or flat channels, an exact-ramp
/// position; see the module docs), with each record's encoder velocity
/// measured before its position could be left out.
#[derive(Debug, Clone)]
pub struct CheckedChannels {
    /// The records with their dead channels left out.
    pub recordings: Vec<Recording>,
    /// The encoder's velocity of each record, mm/s (signed; `None` without
    /// a position channel or with a constant one).
    pub measured_mm_s: Vec<Option<f64>>,
    /// One warning per channel left out.
    pub warnings: Vec<String>,
}

/// Checks every record's channels (see the module docs).
///
/// # Errors
/// [`Error::InvalidRecording`] naming a record whose every channel is flat.
pub fn check_channels(recs: Vec<Recording>, s: &PreflightSettings) -> Result<CheckedChannels> {
    let mut warnings = Vec::new();
    let mut out = Vec::with_capacity(recs.len());
    let mut measured = Vec::with_capacity(recs.len());
    for mut rec in recs {
        let name = rec.source_name();
        let mut flat = Vec::new();
        for c in rec.channels() {
            let x = rec.channel(c).unwrap_or_default();
            if is_flat(x, s.flat_relative) {
                flat.push((c, x[0]));
            }
        }
        if flat.len() == rec.channels().len() {
            let list: Vec<String> = flat
                .iter()
                .map(|(c, v)| format!("{} = {}", c.column_name(), value_text(*v, *c)))
                .collect();
            return Err(Error::InvalidRecording {
                source_name: name,
                reason: format!(
                    "every channel is constant ({}): dead or disconnected inputs, nothing to \
                     analyse",
                    list.join(", ")
                ),
            });
        }
        for &(c, v) in &flat {
            warnings.push(format!(
                "{name}: channel {} is constant ({} in all {} samples): a dead or disconnected \
                 input; left out of the findings",
                c.column_name(),
                value_text(v, c),
                rec.len()
            ));
            rec = rec.without_channel(c)?;
        }
        let v = measure_velocity(&rec);
        if let Some(x) = rec.channel(Channel::Position) {
            if is_exact_ramp(x, s.ramp_relative) {
                warnings.push(format!(
                    "{name}: position_mm is an exact ramp (every step equal): its velocity error \
                     is rounding noise; left out of the findings"
                ));
                rec = rec.without_channel(Channel::Position)?;
            }
        }
        measured.push(v);
        out.push(rec);
    }
    Ok(CheckedChannels {
        recordings: out,
        measured_mm_s: measured,
        warnings,
    })
}

/// Runs the checks (see the module docs) on records to be analysed at
/// `stated` mm/s, or at the measured velocity when `None`. `geometry` gives
/// the ball-pass frequency for the Nyquist check.
///
/// # Errors
/// [`Error::InvalidRecording`] naming the record: every channel flat; a
/// stated velocity the encoder contradicts (both numbers; unless forced);
/// no velocity stated and none measurable, or records whose measured
/// velocities disagree; a ball-pass frequency at or above Nyquist.
pub fn check(
    recs: Vec<Recording>,
    stated: Option<f64>,
    geometry: &Geometry,
    s: &PreflightSettings,
) -> Result<Checked> {
    let CheckedChannels {
        recordings: out,
        measured_mm_s: measured,
        mut warnings,
    } = check_channels(recs, s)?;
    let mut notes = Vec::new();
    let (velocity, source) = match stated {
        Some(v) => {
            for (rec, m) in out.iter().zip(&measured) {
                let Some(m) = *m else { continue };
                let off = (m.abs() - v).abs() / v;
                if off > s.velocity_tolerance {
                    let text = format!(
                        "the encoder (position_mm) says the stage moves at {:.4} mm/s, but the \
                         stated velocity is {v} mm/s ({:.3} times that)",
                        m.abs(),
                        v / m.abs()
                    );
                    if !s.force_velocity {
                        return Err(Error::InvalidRecording {
                            source_name: rec.source_name(),
                            reason: format!(
                                "{text}; check the velocity, leave it out to use the measured \
                                 one, or force it with --force-velocity"
                            ),
                        });
                    }
                    warnings.push(format!(
                        "{}: {text}; analysed at {v} mm/s as forced",
                        rec.source_name()
                    ));
                }
            }
            (v, VelocitySource::Stated)
        }
        None => {
            let speeds: Vec<f64> = measured.iter().flatten().map(|m| m.abs()).collect();
            let missing: Vec<String> = out
                .iter()
                .zip(&measured)
                .filter(|(_, m)| m.is_none())
                .map(|(r, _)| r.source_name())
                .collect();
            if !missing.is_empty() || speeds.is_empty() {
                return Err(Error::InvalidRecording {
                    source_name: missing.first().cloned().unwrap_or_else(|| "analyze".into()),
                    reason: "no velocity: give --velocity V (mm/s); there is no position channel \
                             to measure it from"
                        .into(),
                });
            }
            let mean = speeds.iter().sum::<f64>() / speeds.len() as f64;
            if let Some((r, m)) = out
                .iter()
                .zip(&speeds)
                .find(|(_, m)| (*m - mean).abs() > s.velocity_tolerance * mean)
            {
                return Err(Error::InvalidRecording {
                    source_name: r.source_name(),
                    reason: format!(
                        "its encoder velocity {m:.4} mm/s differs from the others' (mean \
                         {mean:.4} mm/s) by more than {:.0} %: these are not repeats at one \
                         velocity; give --velocity or analyse them apart",
                        100.0 * s.velocity_tolerance
                    ),
                });
            }
            notes.push(format!(
                "velocity {mean:.4} mm/s measured from the encoder (position_mm slope{}); none \
                 was given",
                if speeds.len() > 1 {
                    format!(", mean of {} records", speeds.len())
                } else {
                    String::new()
                }
            ));
            (mean, VelocitySource::Measured)
        }
    };
    for (rec, m) in out.iter().zip(&measured) {
        if m.is_some_and(|m| m < 0.0) {
            notes.push(format!(
                "{}: the stage moves backward (position decreasing)",
                rec.source_name()
            ));
        }
    }
    let f_c = velocity / (2.0 * geometry.d_avg_mm());
    for rec in &out {
        let nyquist = rec.fs_hz() / 2.0;
        if f_c >= nyquist {
            return Err(Error::InvalidRecording {
                source_name: rec.source_name(),
                reason: format!(
                    "the ball-pass frequency at {velocity} mm/s, {f_c:.1} Hz, is at or above the \
                     Nyquist frequency {nyquist} Hz (fs = {} Hz): nothing can be measured there",
                    rec.fs_hz()
                ),
            });
        }
    }
    Ok(Checked {
        recordings: out,
        velocity_mm_s: velocity,
        velocity_source: source,
        measured_mm_s: measured,
        warnings,
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recording::{Channels, Metadata};

    fn sr25w() -> Geometry {
        crate::bearing::lookup("sr25w").unwrap().geometry
    }

    use crate::stats::test_noise::uniform as noise;

    fn rec(friction: Vec<f64>, v: f64, seed: u64) -> Recording {
        let n = friction.len();
        let e = noise(n, seed);
        Recording::new(
            1000.0,
            Channels {
                friction_n: Some(friction),
                // Encoder at v mm/s with 0.1 µm quantisation.
                position_mm: Some(
                    (0..n)
                        .map(|i| ((v * i as f64 / 1000.0 + 1e-3 * e[i]) * 1e4).round() / 1e4)
                        .collect(),
                ),
                optical_v: Some(noise(n, seed + 1)),
            },
            Metadata {
                source: Some(format!("r{seed}.csv").into()),
                ..Default::default()
            },
        )
        .unwrap()
    }

    /// Issue 18 item 4: a constant friction channel (3.0 N everywhere) is
    /// left out with a warning; every channel constant is an error.
    #[test]
    fn item4_dead_channels_are_left_out_and_all_dead_is_an_error() {
        let r = rec(vec![3.0; 10_000], 9.0, 1);
        let c = check(vec![r], Some(9.0), &sr25w(), &PreflightSettings::default()).unwrap();
        assert_eq!(
            c.recordings[0].channels(),
            [Channel::Position, Channel::Optical]
        );
        assert!(
            c.warnings[0].contains("friction_N is constant (3 N in all 10000 samples)"),
            "{:?}",
            c.warnings
        );
        // Rounding of a constant (a scale applied) is flat too.
        let f: Vec<f64> = (0..10_000).map(|i| 3.0 + 1e-15 * (i % 3) as f64).collect();
        assert!(is_flat(&f, 1e-12));
        let all = Recording::new(
            1000.0,
            Channels {
                friction_n: Some(vec![3.0; 100]),
                position_mm: Some(vec![12.5; 100]),
                optical_v: Some(vec![0.0; 100]),
            },
            Metadata::default(),
        )
        .unwrap();
        let e = check(
            vec![all],
            Some(9.0),
            &sr25w(),
            &PreflightSettings::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("every channel is constant"), "{e}");
        // A real signal, however small against its offset, is kept: 1 µN
        // of noise on 3 N (3e-7 relative, above any converter's step).
        let f: Vec<f64> = noise(10_000, 5).iter().map(|e| 3.0 + 1e-6 * e).collect();
        let c = check(
            vec![rec(f, 9.0, 2)],
            Some(9.0),
            &sr25w(),
            &PreflightSettings::default(),
        )
        .unwrap();
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    }

    /// Issue 18 item 5: a stated velocity the encoder contradicts is an
    /// error with both numbers, a warning when forced, and a ball-pass
    /// frequency above Nyquist is an error even when forced.
    #[test]
    fn item5_a_contradicted_velocity_is_refused_unless_forced() {
        let r = || rec(noise(10_000, 3), 9.0, 3);
        let s = PreflightSettings::default();
        let e = check(vec![r()], Some(200.0), &sr25w(), &s)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("r3.csv") && e.contains("9.0") && e.contains("200 mm/s"),
            "{e}"
        );
        let forced = PreflightSettings {
            force_velocity: true,
            ..s
        };
        let c = check(vec![r()], Some(200.0), &sr25w(), &forced).unwrap();
        assert!(c.warnings[0].contains("as forced"), "{:?}", c.warnings);
        // 5000 mm/s: f_c = 616.4 Hz above the 500 Hz Nyquist frequency.
        let e = check(vec![r()], Some(5000.0), &sr25w(), &forced)
            .unwrap_err()
            .to_string();
        assert!(e.contains("616.4 Hz") && e.contains("Nyquist"), "{e}");
        // Within 5 %: accepted as stated.
        let c = check(vec![r()], Some(9.3), &sr25w(), &s).unwrap();
        assert_eq!(c.velocity_source, VelocitySource::Stated);
    }

    /// Issue 15: without a stated velocity the encoder's is used and said
    /// to be measured; records that disagree are refused.
    #[test]
    fn the_velocity_is_measured_when_none_is_given() {
        let s = PreflightSettings::default();
        let c = check(
            vec![rec(noise(10_000, 4), 9.0, 4), rec(noise(10_000, 5), 9.0, 5)],
            None,
            &sr25w(),
            &s,
        )
        .unwrap();
        assert_eq!(c.velocity_source, VelocitySource::Measured);
        // 1e-3 mm of uniform noise and 0.1 µm steps over 10 s: the slope is
        // within 1e-4 mm/s of 9.
        assert!((c.velocity_mm_s - 9.0).abs() < 1e-4, "{}", c.velocity_mm_s);
        assert!(c.notes[0].contains("measured from the encoder"));
        let e = check(
            vec![
                rec(noise(10_000, 4), 9.0, 4),
                rec(noise(10_000, 5), 20.0, 5),
            ],
            None,
            &sr25w(),
            &s,
        )
        .unwrap_err();
        assert!(e.to_string().contains("not repeats at one velocity"), "{e}");
        // Backward motion: the speed is used, the direction noted.
        let c = check(vec![rec(noise(10_000, 6), -9.0, 6)], None, &sr25w(), &s).unwrap();
        assert!((c.velocity_mm_s - 9.0).abs() < 1e-4);
        assert!(
            c.notes.iter().any(|n| n.contains("backward")),
            "{:?}",
            c.notes
        );
    }

    /// An exact ramp's velocity error is rounding noise: measured, then
    /// left out of the findings.
    #[test]
    fn an_exact_ramp_is_measured_then_left_out() {
        let n = 5000;
        let r = Recording::new(
            1000.0,
            Channels {
                friction_n: Some(noise(n, 7)),
                position_mm: Some((0..n).map(|i| 9.0 * i as f64 / 1000.0).collect()),
                optical_v: None,
            },
            Metadata::default(),
        )
        .unwrap();
        let c = check(vec![r], None, &sr25w(), &PreflightSettings::default()).unwrap();
        assert!((c.velocity_mm_s - 9.0).abs() < 1e-9);
        assert_eq!(c.recordings[0].channels(), [Channel::Friction]);
        assert!(c.warnings[0].contains("exact ramp"), "{:?}", c.warnings);
    }
}
