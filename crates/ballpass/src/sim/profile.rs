//! Multi-speed runs: a reference that holds constant-velocity plateaus
//! (forward or backward) joined by constant-acceleration ramps, as a lab's
//! benchmark run of a linear axis does ("42, 83 and 125 mm/s back and forth
//! in one 25 s file").
//!
//! With [`SimSettings::profile`](super::SimSettings::profile) set, the
//! stage is settled at the first plateau's velocity before the first sample
//! (as [`Start::Settled`](super::Start::Settled)), then the reference
//! follows the profile from `t = 0`; the last plateau lasts to the end of
//! the record. The reference velocity, from `t = 0`:
//!
//! ```text
//! plateau 0: V_0 for D_0 s, ramp to V_1 at +-a (|V_1 - V_0| / a s),
//! plateau 1: V_1 for D_1 s, ramp, ...
//! ```
//!
//! The truth lists each plateau's commanded interval and velocity
//! ([`PlateauTruth`]) and the stage's mean velocity over it; the interval
//! is the reference's, so the stage's settling after a ramp lies inside it.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// One constant-velocity part of a [`SpeedProfile`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProfilePlateau {
    /// Commanded velocity, mm/s (negative: backward).
    pub velocity_mm_s: f64,
    /// How long the reference holds it, s (the last plateau: at least).
    pub duration_s: f64,
}

/// Plateaus joined by ramps of one acceleration (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpeedProfile {
    /// The plateaus, in order.
    pub plateaus: Vec<ProfilePlateau>,
    /// Acceleration of the ramps between plateaus, mm/s².
    pub acceleration_mm_s2: f64,
}

/// A plateau as simulated (times from the first sample).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlateauTruth {
    /// When the reference reaches the plateau's velocity, s.
    pub start_s: f64,
    /// When the reference leaves it (or the record ends), s.
    pub end_s: f64,
    /// Commanded velocity, mm/s (signed).
    pub velocity_mm_s: f64,
    /// The stage's mean velocity over `[start_s, end_s)` from the encoder,
    /// mm/s (signed; includes the settling after the ramp).
    pub mean_velocity_mm_s: f64,
}

/// One piece of the reference: from `t0`, position `x0` (mm), velocity
/// `v0` (mm/s), acceleration `a` (mm/s²).
#[derive(Debug, Clone, Copy)]
struct Piece {
    t0: f64,
    x0: f64,
    v0: f64,
    a: f64,
}

impl SpeedProfile {
    /// The benchmark run of issue 15: 42, 83 and 125 mm/s, each forward
    /// then backward, 3.5 s per plateau, ramps at 400 mm/s² (about 25 s in
    /// all; the stage model settles within about 1.5 s after each ramp).
    pub fn lab_run() -> Self {
        let plateaus = [42.0, -42.0, 83.0, -83.0, 125.0, -125.0]
            .into_iter()
            .map(|v| ProfilePlateau {
                velocity_mm_s: v,
                duration_s: 3.5,
            })
            .collect();
        Self {
            plateaus,
            acceleration_mm_s2: 400.0,
        }
    }

    /// Checks the profile.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] (`profile ...`): no plateau, a velocity
    /// that is zero, not finite or slower than `min_speed_mm_s`, a
    /// duration or acceleration that is not positive.
    pub fn validate(&self, min_speed_mm_s: f64) -> Result<()> {
        if self.plateaus.is_empty() {
            return Err(Error::setting("profile", "has no plateau"));
        }
        if !(self.acceleration_mm_s2.is_finite() && self.acceleration_mm_s2 > 0.0) {
            return Err(Error::setting(
                "profile acceleration",
                format!(
                    "must be a positive number of mm/s², got {}",
                    self.acceleration_mm_s2
                ),
            ));
        }
        for (k, p) in self.plateaus.iter().enumerate() {
            if !(p.velocity_mm_s.is_finite() && p.velocity_mm_s.abs() >= min_speed_mm_s) {
                return Err(Error::setting(
                    "profile velocity",
                    format!(
                        "plateau {}: {} mm/s; expected a speed of at least {min_speed_mm_s} mm/s \
                         (negative for backward)",
                        k + 1,
                        p.velocity_mm_s
                    ),
                ));
            }
            if !(p.duration_s.is_finite() && p.duration_s > 0.0) {
                return Err(Error::setting(
                    "profile duration",
                    format!(
                        "plateau {}: must be a positive number of s, got {}",
                        k + 1,
                        p.duration_s
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Velocity of the first plateau, mm/s (signed).
    pub fn first_velocity_mm_s(&self) -> f64 {
        self.plateaus[0].velocity_mm_s
    }

    /// Largest speed of the profile, mm/s.
    pub fn max_speed_mm_s(&self) -> f64 {
        self.plateaus
            .iter()
            .map(|p| p.velocity_mm_s.abs())
            .fold(0.0, f64::max)
    }

    /// The reference's pieces from `t = 0`: plateau, ramp, plateau, ...
    fn pieces(&self) -> Vec<Piece> {
        let mut out = Vec::new();
        let (mut t, mut x) = (0.0, 0.0);
        for (k, p) in self.plateaus.iter().enumerate() {
            let v = p.velocity_mm_s;
            out.push(Piece {
                t0: t,
                x0: x,
                v0: v,
                a: 0.0,
            });
            if let Some(next) = self.plateaus.get(k + 1) {
                t += p.duration_s;
                x += v * p.duration_s;
                let dv = next.velocity_mm_s - v;
                let a = self.acceleration_mm_s2.copysign(dv);
                let tr = dv.abs() / self.acceleration_mm_s2;
                out.push(Piece {
                    t0: t,
                    x0: x,
                    v0: v,
                    a,
                });
                x += v * tr + 0.5 * a * tr * tr;
                t += tr;
            }
        }
        out
    }

    /// Reference position (mm, 0 at `t = 0`) and velocity (mm/s) at `t`
    /// seconds from the first sample; before it, the first plateau's
    /// velocity.
    pub fn reference(&self, t: f64) -> (f64, f64) {
        let pieces = self.pieces();
        let p = pieces
            .iter()
            .rev()
            .find(|p| p.t0 <= t)
            .copied()
            .unwrap_or(pieces[0]);
        let dt = t - p.t0;
        (p.x0 + p.v0 * dt + 0.5 * p.a * dt * dt, p.v0 + p.a * dt)
    }

    /// A sampler of [`SpeedProfile::reference`] for increasing times
    /// (constant time per call).
    pub(crate) fn sampler(&self) -> ProfileSampler {
        ProfileSampler {
            pieces: self.pieces(),
            k: 0,
        }
    }

    /// Lowest and highest reference position from `t = -pre_s` to
    /// `duration_s`, mm (0 at `t = 0`).
    pub fn position_range_mm(&self, pre_s: f64, duration_s: f64) -> (f64, f64) {
        let v0 = self.first_velocity_mm_s();
        let mut lo = (-v0 * pre_s).min(0.0);
        let mut hi = (-v0 * pre_s).max(0.0);
        // Extremes are at piece ends (velocity changes sign only inside a
        // ramp, where the extreme is at v = 0).
        for p in self.pieces() {
            let mut check = |t: f64| {
                if (0.0..=duration_s).contains(&t) {
                    let (x, _) = self.reference(t);
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            };
            check(p.t0);
            if p.a != 0.0 {
                check(p.t0 - p.v0 / p.a);
            }
        }
        let (x, _) = self.reference(duration_s);
        (lo.min(x), hi.max(x))
    }

    /// The plateaus' commanded intervals within `[0, duration_s)` with
    /// their velocities: `(start_s, end_s, velocity_mm_s)`.
    pub fn intervals(&self, duration_s: f64) -> Vec<(f64, f64, f64)> {
        let pieces = self.pieces();
        pieces
            .iter()
            .enumerate()
            .filter(|(_, p)| p.a == 0.0)
            .filter_map(|(i, p)| {
                let end = pieces.get(i + 1).map_or(duration_s, |q| q.t0);
                let (a, b) = (p.t0, end.min(duration_s));
                (b > a).then_some((a, b, p.v0))
            })
            .collect()
    }
}

/// Walks the pieces of a profile forward in time.
pub(crate) struct ProfileSampler {
    pieces: Vec<Piece>,
    k: usize,
}

impl ProfileSampler {
    /// Reference position (m) and velocity (m/s) at `t` s from the first
    /// sample; `t` must not decrease between calls (negative before it).
    pub(crate) fn at(&mut self, t: f64) -> (f64, f64) {
        while self.k + 1 < self.pieces.len() && self.pieces[self.k + 1].t0 <= t {
            self.k += 1;
        }
        // Before t = 0 the first piece (a plateau) extends backward.
        let p = self.pieces[self.k];
        let dt = t - p.t0;
        let x = p.x0 + p.v0 * dt + 0.5 * p.a * dt * dt;
        let v = p.v0 + p.a * dt;
        (x * 1e-3, v * 1e-3)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_is_continuous_and_holds_each_plateau() {
        let p = SpeedProfile::lab_run();
        p.validate(0.01).unwrap();
        let iv = p.intervals(100.0);
        assert_eq!(iv.len(), 6);
        // 42 → -42 at 400 mm/s²: 0.21 s of ramp after 3.5 s.
        assert!((iv[1].0 - 3.71).abs() < 1e-12, "{iv:?}");
        for w in iv.windows(2) {
            let ramp = (w[1].2 - w[0].2).abs() / 400.0;
            assert!((w[1].0 - w[0].1 - ramp).abs() < 1e-12);
        }
        // Position continuous and its difference quotient the velocity.
        let mut s = p.sampler();
        let h = 1e-4;
        let mut t = -1.0;
        let mut prev = s.at(t);
        while t < 26.0 {
            t += h;
            let cur = s.at(t);
            let mid_v = 0.5 * (prev.1 + cur.1);
            // Exact for piecewise quadratics away from breakpoints; at a
            // breakpoint the error is at most a h / 2 (0.02 mm/s).
            assert!(((cur.0 - prev.0) / h - mid_v).abs() < 3e-5, "t {t}");
            let (x, v) = p.reference(t);
            assert!((x * 1e-3 - cur.0).abs() < 1e-12 && (v * 1e-3 - cur.1).abs() < 1e-12);
            prev = cur;
        }
        let (lo, hi) = p.position_range_mm(1.0, 26.0);
        assert!(lo <= -42.0 + 1e-9 && hi > 0.0, "{lo} {hi}");
    }

    #[test]
    fn bad_profiles_are_refused() {
        let mut p = SpeedProfile::lab_run();
        p.plateaus[2].velocity_mm_s = 0.0;
        assert!(p.validate(0.01).is_err());
        let mut p = SpeedProfile::lab_run();
        p.acceleration_mm_s2 = -1.0;
        assert!(p.validate(0.01).is_err());
        assert!(SpeedProfile {
            plateaus: vec![],
            acceleration_mm_s2: 1.0
        }
        .validate(0.01)
        .is_err());
    }
}
