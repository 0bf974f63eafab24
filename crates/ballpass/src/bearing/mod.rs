//! Bearing geometry, the catalog, and the ball-pass predictions of thesis
//! Eqs. 1.1–1.4 (checked in docs/methods.md §1).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

pub mod catalog;

pub use catalog::{find, lookup, CatalogEntry, CATALOG};

/// Geometry of one ball circuit of a linear guide.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// Ball diameter `d`, mm.
    pub ball_diameter_mm: f64,
    /// Total free space between the balls of one circuit `d_ext`, mm.
    pub free_space_mm: f64,
    /// Number of balls in the circuit `N_B`.
    pub balls_in_race: u32,
}

impl Geometry {
    /// Builds and validates a geometry.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when `d` is not positive, `d_ext` negative, or `N_B` zero.
    pub fn new(ball_diameter_mm: f64, free_space_mm: f64, balls_in_race: u32) -> Result<Self> {
        let g = Self {
            ball_diameter_mm,
            free_space_mm,
            balls_in_race,
        };
        g.validate()?;
        Ok(g)
    }

    /// Checks the ranges of the fields.
    ///
    /// # Errors
    /// As [`Geometry::new`].
    pub fn validate(&self) -> Result<()> {
        if !(self.ball_diameter_mm.is_finite() && self.ball_diameter_mm > 0.0) {
            return Err(Error::setting(
                "ball diameter",
                format!(
                    "must be a positive number of mm, got {}",
                    self.ball_diameter_mm
                ),
            ));
        }
        if !(self.free_space_mm.is_finite() && self.free_space_mm >= 0.0) {
            return Err(Error::setting(
                "free space",
                format!(
                    "must be zero or a positive number of mm, got {}",
                    self.free_space_mm
                ),
            ));
        }
        if self.balls_in_race == 0 {
            return Err(Error::setting("balls in race", "must be at least 1, got 0"));
        }
        Ok(())
    }

    /// Mean ball spacing `d_avg = d + d_ext / N_B`, mm (Eq. 1.3).
    pub fn d_avg_mm(&self) -> f64 {
        self.ball_diameter_mm + self.free_space_mm / f64::from(self.balls_in_race)
    }

    /// Spacing variation `d_var = d_ext / N_B`, mm: the surface-to-surface gap
    /// of evenly spaced balls (Eq. 1.4; 0.0556 mm for SR25W).
    pub fn d_var_mm(&self) -> f64 {
        self.free_space_mm / f64::from(self.balls_in_race)
    }

    /// Predictions at one tracking velocity.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] when the velocity is not positive and finite,
    /// or `harmonics` is zero.
    pub fn predict(&self, velocity_mm_s: f64, harmonics: usize) -> Result<Prediction> {
        self.validate()?;
        check_velocity(velocity_mm_s)?;
        if harmonics == 0 {
            return Err(Error::setting("harmonics", "must be at least 1"));
        }
        let d_avg = self.d_avg_mm();
        let d_var = self.d_var_mm();
        let f_c = velocity_mm_s / (2.0 * d_avg);
        let lo = velocity_mm_s / 2.0 / (d_avg + d_var);
        let hi = velocity_mm_s / 2.0 / (d_avg - d_var);
        // A single gap can range from 0 to d_ext (docs/methods.md §1): spacing d ..= d + d_ext.
        let min_single = velocity_mm_s / 2.0 / (self.ball_diameter_mm + self.free_space_mm);
        let max_single = velocity_mm_s / 2.0 / self.ball_diameter_mm;
        Ok(Prediction {
            velocity_mm_s,
            d_avg_mm: d_avg,
            d_var_mm: d_var,
            f_c_hz: f_c,
            tau_c_s: 1.0 / f_c,
            f_band_low_hz: lo,
            f_band_high_hz: hi,
            f_single_spacing_low_hz: min_single,
            f_single_spacing_high_hz: max_single,
            harmonics_hz: (1..=harmonics).map(|k| k as f64 * f_c).collect(),
            balls_in_race: Some(self.balls_in_race),
        })
    }
}

/// Checks that a tracking velocity is a positive finite number of mm/s.
///
/// # Errors
/// [`Error::InvalidSetting`] naming `velocity`.
pub fn check_velocity(velocity_mm_s: f64) -> Result<()> {
    if velocity_mm_s.is_finite() && velocity_mm_s > 0.0 {
        Ok(())
    } else {
        Err(Error::setting(
            "velocity",
            format!("must be a positive number of mm/s, got {velocity_mm_s}"),
        ))
    }
}

/// What the geometry predicts at one velocity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Prediction {
    /// Tracking velocity `v`, mm/s.
    pub velocity_mm_s: f64,
    /// Mean ball spacing, mm.
    pub d_avg_mm: f64,
    /// Spacing variation used for the band, mm.
    pub d_var_mm: f64,
    /// Ball-pass frequency `f_c = v / (2 d_avg)`, Hz (Eq. 1.2).
    pub f_c_hz: f64,
    /// Ball-pass period `tau_c = 1 / f_c`, s.
    pub tau_c_s: f64,
    /// Lower edge of the band `v/2 / (d_avg + d_var)`, Hz (Eq. 1.4).
    pub f_band_low_hz: f64,
    /// Upper edge of the band `v/2 / (d_avg - d_var)`, Hz (Eq. 1.4).
    pub f_band_high_hz: f64,
    /// Passage rate of one pair of balls at the widest spacing `d + d_ext`, Hz.
    pub f_single_spacing_low_hz: f64,
    /// Passage rate of one pair of touching balls (spacing `d`), Hz.
    pub f_single_spacing_high_hz: f64,
    /// `k f_c` for k = 1..=K, Hz.
    pub harmonics_hz: Vec<f64>,
    /// Balls in the circuit `N_B` of the geometry (`None` when read from a
    /// file written before it was recorded); the synchronous average tells
    /// the balls apart with it.
    #[serde(default)]
    pub balls_in_race: Option<u32>,
}

/// Predictions of one bearing over several velocities: what
/// `ballpass predict --json` prints (schema `ballpass.predict/1`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PredictionTable {
    /// `ballpass.predict/1`.
    pub schema: &'static str,
    /// ballpass version.
    pub version: &'static str,
    /// Bearing name (catalog name, `(custom geometry)` when overridden).
    pub bearing: String,
    /// The geometry predicted from.
    pub geometry: Geometry,
    /// One prediction per velocity, in the order given.
    pub predictions: Vec<Prediction>,
}

/// Predicts `bearing`'s ball-pass frequencies at each velocity (mm/s), with
/// `harmonics` multiples `k f_c` each.
///
/// # Errors
/// As [`Geometry::predict`], for the first bad velocity.
pub fn prediction_table(
    bearing: impl Into<String>,
    geometry: Geometry,
    velocities_mm_s: &[f64],
    harmonics: usize,
) -> Result<PredictionTable> {
    Ok(PredictionTable {
        schema: "ballpass.predict/1",
        version: crate::VERSION,
        bearing: bearing.into(),
        geometry,
        predictions: velocities_mm_s
            .iter()
            .map(|&v| geometry.predict(v, harmonics))
            .collect::<Result<_>>()?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference values from docs/methods.md §1 (5–6 significant digits as printed there).
    #[test]
    fn sr25w_matches_errata_reference_values() {
        let g = lookup("sr25w").unwrap().geometry;
        assert!((g.d_avg_mm() - 4.05556).abs() < 5e-6);
        for (v, f, tau) in [
            (0.5, 0.061644, 16.222),
            (1.0, 0.12329, 8.111),
            (9.0, 1.10959, 0.90123),
            (10.0, 1.23288, 0.81111),
            (20.0, 2.46575, 0.40556),
        ] {
            let p = g.predict(v, 3).unwrap();
            // The references are printed to 5 significant digits: half a unit in
            // the fifth digit is at most 5e-5 relative.
            assert!((p.f_c_hz - f).abs() / f < 5e-5, "f_c at {v}: {}", p.f_c_hz);
            assert!(
                (p.tau_c_s - tau).abs() / tau < 5e-5,
                "tau_c at {v}: {}",
                p.tau_c_s
            );
        }
        let p = g.predict(1.0, 1).unwrap();
        // docs/methods.md §1: f_d/v from 0.12162 to 0.12500.
        assert!(
            (p.f_band_low_hz - 0.12162).abs() < 5e-6,
            "{}",
            p.f_band_low_hz
        );
        assert!(
            (p.f_band_high_hz - 0.12500).abs() < 5e-6,
            "{}",
            p.f_band_high_hz
        );
        // docs/methods.md §1: a single spacing of 4–6 mm gives f/v from 0.0833 to 0.125.
        assert!((p.f_single_spacing_low_hz - 1.0 / 12.0).abs() < 1e-12);
        assert!((p.f_single_spacing_high_hz - 0.125).abs() < 1e-12);
    }

    #[test]
    fn bad_velocity_and_geometry_are_errors() {
        let g = lookup("sr25w").unwrap().geometry;
        for v in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(g.predict(v, 1).is_err(), "velocity {v}");
        }
        assert!(Geometry::new(0.0, 2.0, 36).is_err());
        assert!(Geometry::new(4.0, -1.0, 36).is_err());
        assert!(Geometry::new(4.0, 2.0, 0).is_err());
    }
}
