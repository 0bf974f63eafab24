//! The sweep's ripple in the position domain held to the simulator's truth
//! (issue 17: "the sweep shows the ripple amplitude against speed in that
//! domain"). The randomized measurement over speeds and seeds, with the
//! rail roughness on, is the bench `position_line -- --amplitude`.

use std::path::Path;

use ballpass::analysis::Signal;
use ballpass::bearing::lookup;
use ballpass::campaign::record::RecordResult;
use ballpass::campaign::run::{entry_for, process_recording, CampaignSettings};
use ballpass::campaign::sweep::sweep;
use ballpass::sim::Simulation;

#[path = "common/ripple.rs"]
mod ripple;
use ripple::ripple_only;

fn process(sim: &Simulation, v: f64, repeat: u32) -> RecordResult {
    let g = lookup("sr25w").unwrap().geometry;
    let e = entry_for(Path::new("sim"), "sr25w", v, repeat);
    process_recording(&sim.recording, &e, g, &CampaignSettings::default()).unwrap()
}

/// Per record and pooled per velocity, the k = 1 line's amplitude matches
/// the simulated ripple and the truth lies inside its interval.
#[test]
fn the_ripple_amplitude_matches_the_simulated_one_at_each_speed() {
    for (v, seed) in [(6.0, 21), (20.0, 22)] {
        let sims = [ripple_only(v, seed), ripple_only(v, seed + 100)];
        let recs: Vec<RecordResult> = sims
            .iter()
            .zip(1..)
            .map(|(s, r)| process(s, v, r))
            .collect();
        let t = &sims[0].truth;
        // Friction: the Gaussian pulse train's fundamental (truth), read
        // through the restored load cell (|H| ≥ 0.99 at f_c) and the 20 Hz
        // low-pass (≥ 0.99), resampled onto the travel; the line's power is
        // summed over Hann's main lobe (≥ 99 % of it off-bin). 5 % covers
        // those and the load-cell noise in the bins (the line is > 25 dB
        // over it without roughness).
        let f_truth = t.friction_fundamental_n;
        // Velocity error: the stage's response |G_vf(f_c)| to that line, in
        // µm/s. 10 %: the encoder's quantisation noise in the bins (the line
        // is ~15 dB over it at 6 mm/s) and the central difference's gain at
        // f_c (> 0.99).
        let ve_truth = t.g_vf_gain_mm_s_per_n * 1e3 * f_truth;
        for r in &recs {
            for (sig, truth, tol) in [
                (Signal::Friction, f_truth, 0.05),
                (Signal::VelocityError, ve_truth, 0.10),
            ] {
                let l = r
                    .position_ripple
                    .iter()
                    .find(|l| l.signal == sig && l.k == 1)
                    .unwrap_or_else(|| panic!("v {v}: no {sig:?} line: {:?}", r.warnings));
                let rel = l.amplitude / truth - 1.0;
                assert!(
                    rel.abs() < tol,
                    "v {v} {sig:?}: amplitude {} vs truth {truth} ({:+.1} %)",
                    l.amplitude,
                    100.0 * rel
                );
                let (lo, hi) = (l.amplitude_lower.unwrap(), l.amplitude_upper.unwrap());
                assert!(lo < l.amplitude && l.amplitude < hi, "{l:?}");
            }
        }
        let refs: Vec<&RecordResult> = recs.iter().collect();
        let s = sweep(&refs, Some(t.d_avg_mm));
        let row = &s.velocities[0];
        for (sig, truth, tol) in [
            (Signal::Friction, f_truth, 0.05),
            (Signal::VelocityError, ve_truth, 0.10),
        ] {
            let l = row
                .ripple
                .iter()
                .find(|l| l.signal == sig && l.k == 1)
                .unwrap();
            assert_eq!(l.records, 2);
            assert!(
                (l.amplitude / truth - 1.0).abs() < tol,
                "v {v} {sig:?}: pooled {} vs {truth}",
                l.amplitude
            );
            let (lo, hi) = (l.amplitude_lower.unwrap(), l.amplitude_upper.unwrap());
            assert!(
                lo < truth && truth < hi,
                "v {v} {sig:?}: {lo}..{hi} vs {truth}"
            );
        }
    }
}

/// A record with too little travel for the line (1 mm/s for 30 s: 30 mm,
/// under four ball-pass periods) gets no ripple and says why; the sweep
/// names the velocity.
#[test]
fn too_little_travel_gives_no_ripple_and_says_so() {
    let slow = ripple_only(1.0, 31);
    let fast = ripple_only(9.0, 32);
    let recs = [process(&slow, 1.0, 1), process(&fast, 9.0, 1)];
    assert!(recs[0].position_ripple.is_empty());
    assert!(
        recs[0]
            .warnings
            .iter()
            .any(|w| w.starts_with("no position-domain ripple")),
        "{:?}",
        recs[0].warnings
    );
    let refs: Vec<&RecordResult> = recs.iter().collect();
    let s = sweep(&refs, None);
    assert!(s.velocities[0].ripple.is_empty() && !s.velocities[1].ripple.is_empty());
    assert!(
        s.findings
            .iter()
            .any(|f| f.starts_with("no position-domain line at 1 mm/s")),
        "{:?}",
        s.findings
    );
}
