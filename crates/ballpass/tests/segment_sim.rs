//! Plateau segmentation of multi-speed runs held to the simulator's truth
//! (issue 15): the plateaus found from the encoder against the profile the
//! simulator followed, on the lab's benchmark run and on randomized
//! profiles and seeds.

use ballpass::recording::segment::{plateaus, split, Direction, SegmentSettings};
use ballpass::recording::Channel;
use ballpass::sim::{simulate, ProfilePlateau, SimSettings, SpeedProfile, StageSettings};

/// Simple seeded generator for the randomized profiles.
struct Lcg(u64);

impl Lcg {
    fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn settings(profile: SpeedProfile, duration_s: f64, seed: u64) -> SimSettings {
    SimSettings {
        duration_s,
        seed,
        profile: Some(profile),
        ..Default::default()
    }
}

/// Latest start of a found plateau after its commanded start, s.
///
/// The velocity error of the PD stage after the ramp into a plateau is a
/// damped oscillation with envelope `A exp(-zeta w_n t)` from the ramp's
/// end. The ramp's end is an acceleration step `a`, whose velocity-error
/// response `a / w_d exp(-zeta w_n t) sin(w_d t)` has envelope `a / w_d`;
/// its start adds at most as much again, and a short ramp is at most a
/// velocity step of `|dV|`, envelope `|dV| / sqrt(1 - zeta^2)`; so
/// `A = min(2 a / w_d, |dV| / sqrt(1 - zeta^2))`. A block is kept once
/// the envelope is below the 2 % tolerance of the speed `V`:
/// `t = ln(A / (0.02 |V|)) / (zeta w_n)`, plus two 0.1 s blocks of
/// granularity. The first plateau starts settled: only the blocks.
fn settling_bound_s(s: &SimSettings, start_s: f64) -> f64 {
    let p = s.profile.as_ref().unwrap();
    let k = p
        .intervals(s.duration_s)
        .iter()
        .position(|iv| (iv.0 - start_s).abs() < 1e-12)
        .unwrap();
    if k == 0 {
        return 0.2;
    }
    let st = StageSettings::default();
    let (zeta, wn) = (st.damping_ratio(), st.omega_n_rad_s());
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let v = p.plateaus[k].velocity_mm_s;
    let dv = (v - p.plateaus[k - 1].velocity_mm_s).abs();
    let a = (2.0 * p.acceleration_mm_s2 / wd).min(dv / (1.0 - zeta * zeta).sqrt());
    (a / (0.02 * v.abs())).ln().max(0.0) / (zeta * wn) + 0.2
}

/// Runs the simulation and the segmentation and checks every plateau
/// against the truth; returns the largest velocity error (relative) and
/// the largest start delay after the commanded start, s.
fn check(s: &SimSettings) -> (f64, f64) {
    let sim = simulate(s).unwrap();
    let truth = &sim.truth.plateaus;
    let found = plateaus(&sim.recording, &SegmentSettings::default()).unwrap();
    // Plateaus shorter than the settling time plus the shortest plateau
    // kept (1 s) cannot be found; the profiles below have none.
    assert_eq!(
        found.len(),
        truth.len(),
        "seed {}: found {found:#?}\ntruth {truth:#?}",
        s.seed
    );
    let mut worst_v = 0.0f64;
    let mut worst_delay = 0.0f64;
    for (f, t) in found.iter().zip(truth) {
        let want_dir = if t.velocity_mm_s > 0.0 {
            Direction::Forward
        } else {
            Direction::Backward
        };
        assert_eq!(f.direction, want_dir, "seed {}: {f:?} vs {t:?}", s.seed);
        let rel = (f.velocity_mm_s - t.velocity_mm_s).abs() / t.velocity_mm_s.abs();
        worst_v = worst_v.max(rel);
        // The stage tracks the commanded velocity on a plateau: its mean
        // velocity error there is the friction ripple's, well under 1 %.
        assert!(rel < 0.01, "seed {}: {f:?} vs {t:?}", s.seed);
        // The plateau starts after the reference reaches the velocity (the
        // settling is a transient and is dropped) but no later than the
        // settling allows (see `settling_bound_s`).
        let delay = f.start_s - t.start_s;
        worst_delay = worst_delay.max(delay);
        let bound = settling_bound_s(s, t.start_s);
        assert!(
            (-1e-9..bound).contains(&delay),
            "seed {}: start {f:?} vs {t:?}, bound {bound:.2} s",
            s.seed
        );
        // It ends before the stage leaves the velocity: the stage follows
        // the ramp within a fraction of a second, one block (0.1 s) of
        // granularity on either side.
        assert!(
            f.end_s <= t.end_s + 0.3 && f.end_s >= t.end_s - 0.3,
            "seed {}: end {f:?} vs {t:?}",
            s.seed
        );
    }
    // Each plateau as a recording: forward, at its speed.
    let parts = split(&sim.recording, &found).unwrap();
    for (p, f) in parts.iter().zip(&found) {
        assert_eq!(p.meta.velocity_mm_s, Some(f.speed_mm_s));
        let x = p.channel(Channel::Position).unwrap();
        assert!(x[x.len() - 1] > x[0], "{}", p.source_name());
    }
    (worst_v, worst_delay)
}

/// The lab's benchmark run: 42, 83 and 125 mm/s back and forth in 25 s,
/// on several seeds.
#[test]
fn the_benchmark_run_splits_into_its_six_plateaus() {
    for seed in 0..4 {
        let (v, d) = check(&settings(SpeedProfile::lab_run(), 25.0, seed));
        eprintln!("lab run seed {seed}: velocity error {v:.2e}, start delay {d:.2} s");
    }
}

/// Random profiles: 3 to 6 plateaus at 5–150 mm/s in either direction,
/// ramps at 100–800 mm/s², random seeds; each plateau lasts 2–5 s beyond
/// its settling bound (a plateau shorter than its settling plus the 1 s
/// kept at least cannot be found, by design).
#[test]
fn randomized_profiles_split_into_their_plateaus() {
    let mut g = Lcg(2026);
    let mut worst = (0.0f64, 0.0f64);
    for case in 0..40 {
        let n = 3 + (g.uniform() * 4.0) as usize;
        let mut plateaus = Vec::new();
        let mut last: f64 = 0.0;
        for _ in 0..n {
            // Neighbours differ by at least 10 % (else they are one plateau).
            let v = loop {
                let speed = 5.0 + 145.0 * g.uniform();
                let v = if g.uniform() < 0.5 { speed } else { -speed };
                if (v - last).abs() > 0.1 * v.abs().max(last.abs()) {
                    break v;
                }
            };
            last = v;
            plateaus.push(ProfilePlateau {
                velocity_mm_s: v,
                duration_s: 2.0 + 3.0 * g.uniform(),
            });
        }
        let mut p = SpeedProfile {
            acceleration_mm_s2: 100.0 + 700.0 * g.uniform(),
            plateaus,
        };
        // Lengthen each plateau by its settling bound.
        let probe = settings(p.clone(), 1e4, 0);
        let bounds: Vec<f64> = p
            .intervals(1e4)
            .iter()
            .map(|iv| settling_bound_s(&probe, iv.0))
            .collect();
        for (pl, b) in p.plateaus.iter_mut().zip(bounds) {
            pl.duration_s += b;
        }
        let last = p.intervals(1e9).last().unwrap().0;
        let total = last + p.plateaus.last().unwrap().duration_s;
        let seed = (g.uniform() * 1e6) as u64;
        let s = SimSettings {
            oversample: 10,
            ..settings(p, total, seed)
        };
        let (v, d) = check(&s);
        eprintln!("case {case}: velocity error {v:.2e}, start delay {d:.2} s");
        worst = (worst.0.max(v), worst.1.max(d));
    }
    eprintln!(
        "worst: velocity error {:.2e}, start delay {:.2} s",
        worst.0, worst.1
    );
}
