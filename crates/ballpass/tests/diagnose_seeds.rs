//! The diagnosis oracle of the campaign issue: on the simulated thesis batch
//! (5 bearings × 10 repeats at 20 mm/s, bearing 4 sticking) bearing 4 and
//! only bearing 4 is bad, for each of 20 campaign seeds; and a batch in which
//! every bearing is good has nothing bad.
//!
//! Each seed re-draws every record (ball spacings, noise, spikes), so the 20
//! seeds are 1000 independent simulated records.

use ballpass::bearing::lookup;
use ballpass::campaign::diagnose::{diagnose, Condition, DiagnoseSettings};
use ballpass::campaign::record::RecordResult;
use ballpass::campaign::run::{process_simulation, CampaignSettings};
use ballpass::sim::{self, campaign::plan, SimSettings};
use rayon::prelude::*;

fn batch(seed: u64, all_good: bool) -> Vec<RecordResult> {
    let base = SimSettings::default();
    let g = lookup("sr25w").unwrap().geometry;
    let settings = CampaignSettings::default();
    plan(&base, seed)
        .into_par_iter()
        .filter(|c| c.path.starts_with("diagnosis/"))
        .map(|mut c| {
            if all_good {
                c.settings.condition = sim::Condition::Good;
            }
            process_simulation(&c, g, &settings).unwrap().1
        })
        .collect()
}

#[test]
fn bearing_4_and_only_bearing_4_is_bad_for_20_seeds() {
    for seed in 1..=20u64 {
        let recs = batch(seed, false);
        assert_eq!(recs.len(), 50);
        let refs: Vec<&RecordResult> = recs.iter().collect();
        let d = diagnose(&refs, &DiagnoseSettings::default());
        let bad: Vec<&str> = d
            .bearings
            .iter()
            .filter(|b| b.verdict == Condition::Bad)
            .map(|b| b.bearing.as_str())
            .collect();
        assert_eq!(bad, vec!["bearing4"], "seed {seed}: {:#?}", d.bearings);
        assert_eq!(
            d.bearings[0].bearing, "bearing4",
            "seed {seed}: ranked first"
        );
    }
}

#[test]
fn an_all_good_batch_has_no_bad_bearing() {
    for seed in [101u64, 102, 103] {
        let recs = batch(seed, true);
        let refs: Vec<&RecordResult> = recs.iter().collect();
        let d = diagnose(&refs, &DiagnoseSettings::default());
        assert!(
            d.bearings.iter().all(|b| b.verdict != Condition::Bad),
            "seed {seed}: {:#?}",
            d.bearings
        );
    }
}
