//! The diagnosis oracle of the campaign issue on the simulated thesis batch
//! (5 bearings × 10 repeats at 20 mm/s, bearing 4 sticking): for a campaign
//! seed, bearing 4 and only bearing 4 must be bad, and a batch in which every
//! bearing is good must have nothing bad. Each seed re-draws every record
//! (ball spacings, noise, spikes), so every seed is 50 independent records.
//!
//! Used by the fast test (`tests/diagnose_seeds.rs`, a few seeds) and by the
//! bench binary (`cargo bench -p ballpass --bench diagnose_seeds -- [N]`,
//! 20 seeds by default).

use rayon::prelude::*;

use crate::bearing::lookup;
use crate::campaign::diagnose::{diagnose, Condition, DiagnoseSettings};
use crate::campaign::record::RecordResult;
use crate::campaign::run::{process_simulation, CampaignSettings};
use crate::sim::{self, campaign::plan, SimSettings};

/// The 50 diagnosis records of the simulated thesis batch for `seed`, with
/// every bearing good when `all_good`.
pub fn batch(seed: u64, all_good: bool) -> crate::Result<Vec<RecordResult>> {
    let base = SimSettings::default();
    let g = lookup("sr25w")
        .ok_or_else(|| crate::Error::setting("bearing", "sr25w is not in the catalog"))?
        .geometry;
    let settings = CampaignSettings::default();
    plan(&base, seed)
        .into_par_iter()
        .filter(|c| c.path.starts_with("diagnosis/"))
        .map(|mut c| {
            if all_good {
                c.settings.condition = sim::Condition::Good;
            }
            process_simulation(&c, g, &settings).map(|r| r.1)
        })
        .collect()
}

/// What `diagnose` makes of a batch: the bearing it ranks first and the
/// bearings it calls bad, in its order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Outcome {
    /// The bearing ranked most suspect.
    pub first: String,
    /// The bearings called bad.
    pub bad: Vec<String>,
}

impl Outcome {
    /// Bearing 4, and only bearing 4, is bad, and it is ranked first.
    pub fn finds_bearing_4(&self) -> bool {
        self.bad == ["bearing4"] && self.first == "bearing4"
    }
}

/// Diagnoses `records` with the default settings.
pub fn outcome(records: &[RecordResult]) -> Outcome {
    let refs: Vec<&RecordResult> = records.iter().collect();
    let d = diagnose(&refs, &DiagnoseSettings::default());
    Outcome {
        first: d
            .bearings
            .first()
            .map(|b| b.bearing.clone())
            .unwrap_or_default(),
        bad: d
            .bearings
            .iter()
            .filter(|b| b.verdict == Condition::Bad)
            .map(|b| b.bearing.clone())
            .collect(),
    }
}
