//! Shared argument groups and parsers.

use anyhow::{bail, Context, Result};
use ballpass::bearing::{self, Geometry};
use clap::Args;

/// Which bearing: a catalog key or a custom geometry.
#[derive(Debug, Clone, Args)]
pub struct BearingArgs {
    /// Bearing from the catalog (see `ballpass predict --list-bearings`).
    #[arg(long, default_value = "sr25w")]
    pub bearing: String,
    /// Custom geometry: ball diameter d, mm (overrides the catalog entry's).
    #[arg(long, value_name = "MM")]
    pub ball_diameter: Option<f64>,
    /// Custom geometry: total free space in the race d_ext, mm.
    #[arg(long, value_name = "MM")]
    pub free_space: Option<f64>,
    /// Custom geometry: number of balls in the race N_B.
    #[arg(long, value_name = "N")]
    pub balls: Option<u32>,
}

impl BearingArgs {
    /// The geometry selected, catalog entry with any flag overriding its field.
    pub fn geometry(&self) -> Result<(String, Geometry)> {
        let entry = bearing::lookup(&self.bearing).with_context(|| {
            let keys: Vec<_> = bearing::CATALOG.iter().map(|e| e.key).collect();
            format!(
                "unknown bearing '{}' (catalog: {})",
                self.bearing,
                keys.join(", ")
            )
        })?;
        let mut g = entry.geometry;
        let custom =
            self.ball_diameter.is_some() || self.free_space.is_some() || self.balls.is_some();
        if let Some(d) = self.ball_diameter {
            g.ball_diameter_mm = d;
        }
        if let Some(d) = self.free_space {
            g.free_space_mm = d;
        }
        if let Some(n) = self.balls {
            g.balls_in_race = n;
        }
        g.validate()?;
        let name = if custom {
            format!("{} (custom geometry)", entry.name)
        } else {
            entry.name.to_string()
        };
        Ok((name, g))
    }
}

/// Parses `V` or `START:STOP:STEP` (inclusive) into a list of velocities, mm/s.
pub fn parse_velocities(s: &str) -> Result<Vec<f64>> {
    let parts: Vec<&str> = s.split(':').collect();
    let num = |p: &str| -> Result<f64> {
        p.trim()
            .parse::<f64>()
            .with_context(|| format!("velocity '{s}': '{p}' is not a number"))
    };
    match parts.as_slice() {
        [v] => Ok(vec![num(v)?]),
        [a, b, step] => {
            let (a, b, step) = (num(a)?, num(b)?, num(step)?);
            if !(step.is_finite() && step > 0.0 && a.is_finite() && b.is_finite()) || b < a {
                bail!("velocity range '{s}': expected START:STOP:STEP with STOP >= START and STEP > 0");
            }
            let n = ((b - a) / step + 1e-9).floor() as usize + 1;
            if n > 100_000 {
                bail!("velocity range '{s}' has {n} values; at most 100000");
            }
            Ok((0..n).map(|i| a + i as f64 * step).collect())
        }
        _ => bail!("velocity '{s}': expected a number or START:STOP:STEP"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_ranges_are_inclusive() {
        assert_eq!(parse_velocities("9").unwrap(), vec![9.0]);
        assert_eq!(parse_velocities("1:3:1").unwrap(), vec![1.0, 2.0, 3.0]);
        assert_eq!(parse_velocities("1:2:0.5").unwrap(), vec![1.0, 1.5, 2.0]);
        assert!(parse_velocities("3:1:1").is_err());
        assert!(parse_velocities("1:2:0").is_err());
        assert!(parse_velocities("fast").is_err());
    }
}
