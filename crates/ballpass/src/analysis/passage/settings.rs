//! Settings of the ball-passage detection and their checks.

use serde::{Deserialize, Serialize};

use crate::bearing::{check_velocity, Geometry};
use crate::error::{Error, Result};

/// Settings of [`super::detect_passages`]; the defaults suit the thesis' bench.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PassageSettings {
    /// Tracking velocity, mm/s; `None`: the recording's metadata, else the
    /// velocity-free mode (period from the pulses themselves).
    pub velocity_mm_s: Option<f64>,
    /// Bearing geometry for predictions; `None`: no predicted `f_c`, no
    /// spacing limits (a velocity alone then only converts periods to spacings).
    pub geometry: Option<Geometry>,
    /// Smallest detection statistic, in standard deviations of its noise
    /// (the matched filter's output; see the module docs): a floor under
    /// the threshold that [`PassageSettings::false_detections_per_record`]
    /// sets.
    pub min_snr: f64,
    /// Smallest pulse amplitude relative to the 75th percentile of the
    /// amplitudes found.
    pub min_relative_prominence: f64,
    /// Smallest distance between passages, in predicted periods.
    pub min_distance_periods: f64,
    /// Length of the running-percentile baseline, in periods.
    pub baseline_periods: f64,
    /// Percentile of the running baseline, 0–100.
    pub baseline_percentile: f64,
    /// Most passages in the pulse-train fits, counted from the start of the
    /// record; 0: no fits. The default, 200, fits a whole 30 s record at any
    /// velocity up to 48 mm/s (the fit's dense Jacobian grows as the square
    /// of this number: 200 pulses is 30 000 samples × 204 parameters, 49 MB).
    pub fit_pulses: usize,
    /// Order N of the rectangular Fourier series fitted (thesis Fig. 47: 20).
    pub rectangular_order: usize,
    /// Expected false detections per record in white Gaussian noise: sets
    /// the detection threshold (Rice's formula, module docs).
    #[serde(default = "default_false_detections")]
    pub false_detections_per_record: f64,
    /// Undo an AC coupling of the photodetector when the record shows one
    /// (module docs, "AC coupling").
    #[serde(default = "default_true")]
    pub restore_ac_coupling: bool,
}

fn default_false_detections() -> f64 {
    0.01
}

fn default_true() -> bool {
    true
}

impl Default for PassageSettings {
    fn default() -> Self {
        Self {
            velocity_mm_s: None,
            geometry: None,
            min_snr: 5.0,
            min_relative_prominence: 0.25,
            min_distance_periods: 0.7,
            baseline_periods: 2.0,
            baseline_percentile: 10.0,
            fit_pulses: 200,
            rectangular_order: 20,
            false_detections_per_record: default_false_detections(),
            restore_ac_coupling: true,
        }
    }
}

impl PassageSettings {
    pub(super) fn validate(&self) -> Result<()> {
        if let Some(v) = self.velocity_mm_s {
            check_velocity(v)?;
        }
        if let Some(g) = &self.geometry {
            g.validate()?;
        }
        let pos = |name: &str, v: f64| -> Result<()> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::setting(
                    name,
                    format!("must be a positive number, got {v}"),
                ))
            }
        };
        pos("min_snr", self.min_snr)?;
        pos(
            "false_detections_per_record",
            self.false_detections_per_record,
        )?;
        pos("min_distance_periods", self.min_distance_periods)?;
        pos("baseline_periods", self.baseline_periods)?;
        if !(0.0..1.0).contains(&self.min_relative_prominence) {
            return Err(Error::setting(
                "min_relative_prominence",
                format!("must be in [0, 1), got {}", self.min_relative_prominence),
            ));
        }
        if !(0.0..=100.0).contains(&self.baseline_percentile) {
            return Err(Error::setting(
                "baseline_percentile",
                format!("must be in [0, 100], got {}", self.baseline_percentile),
            ));
        }
        if self.rectangular_order == 0 || self.rectangular_order > 10_000 {
            return Err(Error::setting(
                "rectangular_order",
                format!("must be 1 to 10000, got {}", self.rectangular_order),
            ));
        }
        Ok(())
    }
}
