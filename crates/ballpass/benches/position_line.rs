//! Seeded randomized measurement of the position-domain ball-pass line
//! against the simulator's truth `1 / (2 d_avg)` (issue 17): for each speed
//! 1–20 mm/s, `--seeds` benches (random circuit, random seed) of a
//! constant-speed run and of a varying-speed run around that speed
//! (plateaus at 0.6, 1.0 and 1.4 times it, then back at 0.8 times it), each
//! `--travel` mm forward. Prints, per speed and kind, the largest and the
//! rms deviation of the friction's and the velocity error's first line, and
//! how many benches fall outside 0.5 %.
//!
//! `cargo bench -p ballpass --bench position_line -- [--seeds N] [--travel MM]`

use ballpass::analysis::position::position_spectra;
use ballpass::analysis::{AnalyzeSettings, Signal};
use ballpass::sim::{simulate, ProfilePlateau, SimSettings, SpeedProfile};

fn arg(name: &str, default: f64) -> f64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let seeds = arg("--seeds", 20.0) as u64;
    let travel = arg("--travel", 320.0);
    let speeds = [1.0, 2.0, 5.0, 10.0, 15.0, 20.0];
    println!(
        "position-domain line vs truth 1/(2 d_avg): {seeds} seeds per row, {travel} mm forward"
    );
    println!(
        "{:>6} {:>9} | {:>9} {:>9} {:>5} | {:>9} {:>9} {:>5} | {:>9} {:>9} {:>5}",
        "v mm/s",
        "kind",
        "fr max %",
        "fr rms %",
        ">0.5",
        "ve max %",
        "ve rms %",
        ">0.5",
        "op max %",
        "op rms %",
        ">0.5"
    );
    let t0 = std::time::Instant::now();
    for (si, &v) in speeds.iter().enumerate() {
        for kind in ["constant", "varying"] {
            let mut dev: [Vec<f64>; 3] = [Vec::new(), Vec::new(), Vec::new()];
            for seed in 0..seeds {
                let seed =
                    1_000_000 + 1000 * si as u64 + seed + if kind == "varying" { 500 } else { 0 };
                let mut s = SimSettings {
                    velocity_mm_s: v,
                    duration_s: travel / v + 2.0,
                    seed,
                    ..Default::default()
                };
                if kind == "varying" {
                    let factors = [0.6, 1.0, 1.4];
                    let each = travel / factors.len() as f64;
                    let mut plateaus: Vec<ProfilePlateau> = factors
                        .iter()
                        .map(|f| ProfilePlateau {
                            velocity_mm_s: f * v,
                            duration_s: each / (f * v),
                        })
                        .collect();
                    plateaus.push(ProfilePlateau {
                        velocity_mm_s: -0.8 * v,
                        duration_s: 60.0 / (0.8 * v),
                    });
                    s.duration_s = plateaus.iter().map(|p| p.duration_s).sum::<f64>() + 3.0;
                    s.profile = Some(SpeedProfile {
                        plateaus,
                        acceleration_mm_s2: 50.0,
                    });
                }
                let sim = simulate(&s).expect("simulation");
                let d = sim.truth.d_avg_mm;
                let truth = 1.0 / (2.0 * d);
                let p = position_spectra(&[sim.recording], d, &AnalyzeSettings::default())
                    .expect("position spectra");
                if std::env::args().any(|a| a == "--debug") {
                    let f = p.auto_of(Signal::Friction).unwrap();
                    let k0 = (0.5 * truth / p.resolution_per_mm) as usize;
                    let k1 = (1.5 * truth / p.resolution_per_mm) as usize;
                    eprintln!("v {v} {kind} seed {seed}: df {} line {truth} nperseg {} segs {} lines {:?}", p.resolution_per_mm, p.nperseg, p.n_segments, p.lines.iter().filter(|l| l.k == 1).map(|l| (l.signal, l.measured_per_mm, l.ratio_db)).collect::<Vec<_>>());
                    eprintln!(
                        "  fr psd {:?}",
                        &f[k0..k1]
                            .iter()
                            .map(|x| format!("{x:.2e}"))
                            .collect::<Vec<_>>()
                    );
                }
                for (i, sig) in [Signal::Friction, Signal::VelocityError, Signal::Optical]
                    .into_iter()
                    .enumerate()
                {
                    let m = p.line(sig, 1).map_or(f64::NAN, |l| l.measured_per_mm);
                    dev[i].push(100.0 * (m - truth) / truth);
                }
            }
            let stats = |x: &[f64]| {
                let max = x.iter().fold(0.0f64, |a, b| {
                    if b.is_nan() {
                        f64::INFINITY
                    } else {
                        a.max(b.abs())
                    }
                });
                let rms = (x.iter().map(|d| d * d).sum::<f64>() / x.len() as f64).sqrt();
                let out = x.iter().filter(|d| d.is_nan() || d.abs() >= 0.5).count();
                (max, rms, out)
            };
            let (fm, fr, fo) = stats(&dev[0]);
            let (vm, vr, vo) = stats(&dev[1]);
            let (om, or, oo) = stats(&dev[2]);
            println!(
                "{v:>6} {kind:>9} | {fm:>9.3} {fr:>9.3} {fo:>5} | {vm:>9.3} {vr:>9.3} {vo:>5} | {om:>9.3} {or:>9.3} {oo:>5}"
            );
        }
    }
    println!("{:.1} s", t0.elapsed().as_secs_f64());
}
