//! The diagnosis oracle of the campaign issue on the simulated thesis batch
//! ([`ballpass::validate::thesis_batch`]): bearing 4 and only bearing 4 is
//! bad, and an all-good batch has nothing bad. A fast subset of seeds; the
//! 20-seed run is the bench binary
//! `cargo bench -p ballpass --bench diagnose_seeds`.

use ballpass::validate::thesis_batch::{batch, outcome};

#[test]
fn bearing_4_and_only_bearing_4_is_bad() {
    for seed in 1..=3u64 {
        let recs = batch(seed, false).unwrap();
        assert_eq!(recs.len(), 50);
        let o = outcome(&recs);
        assert!(o.finds_bearing_4(), "seed {seed}: {o:?}");
    }
}

#[test]
fn an_all_good_batch_has_no_bad_bearing() {
    let recs = batch(101, true).unwrap();
    let o = outcome(&recs);
    assert!(o.bad.is_empty(), "{o:?}");
}
