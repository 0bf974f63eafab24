//! A compensation table applied by the simulated controller: a force
//! against the ball-pass phase added to the stage loop as feedforward.
//!
//! ```text
//! stage   m y'' = −K K_P y − K K_D y' − (f − u) − m r''
//! u       = table(φ), linear interpolation between the bins, periodic
//! φ       OpticalPassage: (s − s_last) / d_avg, s the ball travel and s_last
//!         the last optical passage's (an ideal real-time detector: known the
//!         instant the ball centre crosses the sensor); RailPosition:
//!         (x − x0) / pitch, x the encoder position in the recording's frame
//! ```
//!
//! `u` acts in the direction of motion (it cancels a friction `f` read
//! `+` by the load cell), so a table equal to the periodic part of the
//! friction leaves only the rest of the friction for the stage to reject.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// What the controller measures the phase from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "key", deny_unknown_fields)]
pub enum FeedforwardKey {
    /// Ball travel since the last optical passage over the mean ball pitch.
    OpticalPassage,
    /// Encoder position: phase `(x − x0_mm) / pitch_mm`.
    RailPosition {
        /// Position of phase 0, mm (recording frame).
        x0_mm: f64,
        /// Travel per period, mm.
        pitch_mm: f64,
    },
}

/// A compensation table and its key.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Feedforward {
    /// Force of bin `j` at phase `j / B`, N (`+` along the motion).
    pub force_n: Vec<f64>,
    /// Phase reference.
    pub key: FeedforwardKey,
}

impl Feedforward {
    /// Checks the table.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for an empty table, a non-finite force or
    /// a pitch that is not positive.
    pub fn validate(&self) -> Result<()> {
        if self.force_n.len() < 2 {
            return Err(Error::setting(
                "feedforward",
                format!("table needs at least 2 bins, got {}", self.force_n.len()),
            ));
        }
        if let Some(j) = self.force_n.iter().position(|v| !v.is_finite()) {
            return Err(Error::setting(
                "feedforward",
                format!("force of bin {j} is not a finite number"),
            ));
        }
        if let FeedforwardKey::RailPosition { x0_mm, pitch_mm } = self.key {
            if !(x0_mm.is_finite() && pitch_mm.is_finite() && pitch_mm > 0.0) {
                return Err(Error::setting(
                    "feedforward",
                    format!(
                        "rail key needs a finite x0 and a positive pitch, got {x0_mm}, {pitch_mm}"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The force at phase `phi` (periods; any real), N.
    pub fn force_at(&self, phi: f64) -> f64 {
        crate::analysis::sync::at_phase(&self.force_n, phi)
    }
}
