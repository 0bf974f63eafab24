//! The simulated record the ripple tests hold to the truth, shared by
//! `sync.rs` and `sweep_ripple.rs`.

use ballpass::sim::{simulate, SimSettings, Simulation};

/// A good bearing at `v` mm/s whose only periodic force is the ball-pass
/// ripple: no rail roughness (its random content at f_c would be ~45 % of
/// the 0.06 N fundamental in a 30 s record, see docs/methods.md; the
/// randomized measurement with roughness on is the bench
/// `position_line -- --amplitude`), load-cell and encoder noise kept,
/// the default 30 s.
pub fn ripple_only(v: f64, seed: u64) -> Simulation {
    let mut s = SimSettings {
        velocity_mm_s: v,
        seed,
        ..Default::default()
    };
    s.friction.roughness_n = 0.0;
    simulate(&s).expect("the default bench with the roughness off simulates")
}
