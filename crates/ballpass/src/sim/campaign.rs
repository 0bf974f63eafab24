//! The thesis' test campaign as a list of simulator runs.
//!
//! - Velocity sweep (thesis ch. 6.4 and 7): 1 to 20 mm/s in 1 mm/s steps,
//!   5 repeats each, one good SR25W.
//! - Bearing diagnosis (thesis ch. 8): 5 bearings x 10 repeats at 20 mm/s,
//!   bearing 4 sticking.
//!
//! Each run's seed is derived from the campaign seed and the run's index in
//! this list ([`super::rng::derive_seed`]), so a campaign is reproducible
//! as a whole and any one record can be regenerated alone.

use super::rng::derive_seed;
use super::{Condition, SimSettings};

/// Velocities of the sweep, mm/s.
pub const SWEEP_VELOCITIES_MM_S: std::ops::RangeInclusive<u32> = 1..=20;
/// Repeats per sweep velocity.
pub const SWEEP_REPEATS: u32 = 5;
/// Bearings in the diagnosis.
pub const DIAGNOSIS_BEARINGS: u32 = 5;
/// Repeats per bearing in the diagnosis.
pub const DIAGNOSIS_REPEATS: u32 = 10;
/// Velocity of the diagnosis runs, mm/s.
pub const DIAGNOSIS_VELOCITY_MM_S: f64 = 20.0;
/// The sticking bearing of the diagnosis (1-based, thesis "Bearing 4").
pub const STICKING_BEARING: u32 = 4;

/// One run of the campaign.
#[derive(Debug, Clone, PartialEq)]
pub struct CampaignEntry {
    /// Path relative to the campaign folder, `/`-separated, without extension
    /// (`sweep/v09_r3`, `diagnosis/bearing4_r07`).
    pub path: String,
    /// Bearing label (`sr25w` in the sweep, `bearing1`..`bearing5` in the diagnosis).
    pub bearing: String,
    /// Tracking velocity, mm/s.
    pub velocity_mm_s: f64,
    /// Repeat number, from 1.
    pub repeat: u32,
    /// Bearing condition.
    pub condition: Condition,
    /// The full settings of the run (seed included).
    pub settings: SimSettings,
}

/// Lists the campaign's runs: `base` with velocity, bearing label, condition,
/// test id and seed set per run.
pub fn plan(base: &SimSettings, campaign_seed: u64) -> Vec<CampaignEntry> {
    let mut out = Vec::new();
    let mut push = |path: String, bearing: String, v: f64, repeat: u32, condition: Condition| {
        let index = out.len() as u64;
        let settings = SimSettings {
            velocity_mm_s: v,
            bearing: bearing.clone(),
            condition,
            seed: derive_seed(campaign_seed, index),
            test_id: Some(path.clone()),
            ..base.clone()
        };
        out.push(CampaignEntry {
            path,
            bearing,
            velocity_mm_s: v,
            repeat,
            condition,
            settings,
        });
    };
    for v in SWEEP_VELOCITIES_MM_S {
        for r in 1..=SWEEP_REPEATS {
            push(
                format!("sweep/v{v:02}_r{r}"),
                base.bearing.clone(),
                f64::from(v),
                r,
                Condition::Good,
            );
        }
    }
    for b in 1..=DIAGNOSIS_BEARINGS {
        let condition = if b == STICKING_BEARING {
            Condition::Sticking
        } else {
            Condition::Good
        };
        for r in 1..=DIAGNOSIS_REPEATS {
            push(
                format!("diagnosis/bearing{b}_r{r:02}"),
                format!("bearing{b}"),
                DIAGNOSIS_VELOCITY_MM_S,
                r,
                condition,
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_has_the_thesis_campaign() {
        let p = plan(&SimSettings::default(), 42);
        assert_eq!(p.len(), 20 * 5 + 5 * 10);
        assert_eq!(p[0].path, "sweep/v01_r1");
        assert_eq!(p[99].path, "sweep/v20_r5");
        assert!(p[..100].iter().all(|e| e.condition == Condition::Good));
        let sticking: Vec<_> = p
            .iter()
            .filter(|e| e.condition == Condition::Sticking)
            .collect();
        assert_eq!(sticking.len(), 10);
        assert!(sticking
            .iter()
            .all(|e| e.bearing == "bearing4" && e.velocity_mm_s == 20.0));
        let mut seeds: Vec<u64> = p.iter().map(|e| e.settings.seed).collect();
        seeds.sort_unstable();
        seeds.dedup();
        assert_eq!(seeds.len(), p.len(), "seeds must differ per run");
        assert_eq!(plan(&SimSettings::default(), 42), p);
        assert_ne!(
            plan(&SimSettings::default(), 43)[0].settings.seed,
            p[0].settings.seed
        );
    }
}
