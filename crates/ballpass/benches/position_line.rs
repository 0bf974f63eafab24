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
//!
//! With `--amplitude`, measures instead the sweep's ripple amplitude
//! (`campaign::ripple`): for each speed 2–20 mm/s, `--seeds` benches of 30 s
//! (the campaign's records, rail roughness on) processed as a sweep
//! processes them; per record and pooled over groups of 5 repeats, the k = 1
//! amplitude of friction and velocity error against the truth (the pulse
//! train's fundamental and |G_vf(f_c)| times it): median and 90th
//! percentile of the relative error, and how often the truth lies inside
//! the 95 % interval.

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
    if std::env::args().any(|a| a == "--amplitude") {
        amplitude(arg("--seeds", 20.0) as u64);
        return;
    }
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

/// Median of x (signed), 90th percentile of |x|, and the fraction of
/// `inside`.
fn summary(rel: &[f64], inside: &[bool]) -> (f64, f64, f64) {
    let mut a: Vec<f64> = rel.iter().map(|x| x.abs()).collect();
    a.sort_by(f64::total_cmp);
    let mut m = rel.to_vec();
    m.sort_by(f64::total_cmp);
    let q = |a: &[f64], p: f64| a[((p * (a.len() - 1) as f64).round() as usize).min(a.len() - 1)];
    let cover = inside.iter().filter(|b| **b).count() as f64 / inside.len().max(1) as f64;
    (100.0 * q(&m, 0.5), 100.0 * q(&a, 0.9), 100.0 * cover)
}

/// The `--amplitude` measurement (module docs).
fn amplitude(seeds: u64) {
    use ballpass::bearing::lookup;
    use ballpass::campaign::record::RecordResult;
    use ballpass::campaign::ripple::pool;
    use ballpass::campaign::run::{entry_for, process_recording, CampaignSettings};
    let g = lookup("sr25w").expect("sr25w").geometry;
    let settings = CampaignSettings::default();
    println!(
        "ripple amplitude (k = 1) vs truth, 30 s records, roughness on: {seeds} seeds per speed; \
         rel. error median (signed) / |rel. error| p90 %, truth inside the 95 % interval %"
    );
    println!(
        "{:>6} | {:>22} {:>22} | {:>22} {:>22}",
        "v mm/s",
        "friction per record",
        "friction pooled by 5",
        "v_e per record",
        "v_e pooled by 5"
    );
    let t0 = std::time::Instant::now();
    let mut all: [[(Vec<f64>, Vec<bool>); 2]; 2] = Default::default();
    for (si, v) in [2.0, 3.0, 5.0, 9.0, 15.0, 20.0].into_iter().enumerate() {
        // [signal][per record, pooled]: relative errors and coverage.
        let mut acc: [[(Vec<f64>, Vec<bool>); 2]; 2] = Default::default();
        let mut group: Vec<(RecordResult, [f64; 2])> = Vec::new();
        for i in 0..seeds {
            let s = SimSettings {
                velocity_mm_s: v,
                seed: 2_000_000 + 1000 * si as u64 + i,
                ..Default::default()
            };
            let sim = simulate(&s).expect("simulation");
            let t = &sim.truth;
            let truth = [
                t.friction_fundamental_n,
                t.g_vf_gain_mm_s_per_n * 1e3 * t.friction_fundamental_n,
            ];
            let e = entry_for(std::path::Path::new("sim"), "sr25w", v, i as u32 + 1);
            let r = process_recording(&sim.recording, &e, g, &settings).expect("processing");
            for (j, sig) in [Signal::Friction, Signal::VelocityError]
                .into_iter()
                .enumerate()
            {
                if let Some(l) = r
                    .position_ripple
                    .iter()
                    .find(|l| l.signal == sig && l.k == 1)
                {
                    acc[j][0].0.push(l.amplitude / truth[j] - 1.0);
                    acc[j][0].1.push(
                        l.amplitude_lower.unwrap_or(0.0) <= truth[j]
                            && truth[j] <= l.amplitude_upper.unwrap_or(f64::INFINITY),
                    );
                }
            }
            group.push((r, truth));
            if group.len() == 5 {
                let refs: Vec<&RecordResult> = group.iter().map(|(r, _)| r).collect();
                let pooled = pool(&refs);
                for (j, sig) in [Signal::Friction, Signal::VelocityError]
                    .into_iter()
                    .enumerate()
                {
                    // The truth of the group: the mean of its benches'.
                    let truth = group.iter().map(|(_, t)| t[j]).sum::<f64>() / 5.0;
                    if let Some(l) = pooled.iter().find(|l| l.signal == sig && l.k == 1) {
                        acc[j][1].0.push(l.amplitude / truth - 1.0);
                        acc[j][1].1.push(
                            l.amplitude_lower.unwrap_or(0.0) <= truth
                                && truth <= l.amplitude_upper.unwrap_or(f64::INFINITY),
                        );
                    }
                }
                group.clear();
            }
        }
        let cell = |x: &(Vec<f64>, Vec<bool>)| {
            if x.0.is_empty() {
                format!("{:>22}", "none")
            } else {
                let (m, p, c) = summary(&x.0, &x.1);
                format!("{:>+6.1} {:>6.1} {:>5.0}({:>2})", m, p, c, x.0.len())
            }
        };
        println!(
            "{v:>6} | {} {} | {} {}",
            cell(&acc[0][0]),
            cell(&acc[0][1]),
            cell(&acc[1][0]),
            cell(&acc[1][1])
        );
        for j in 0..2 {
            for k in 0..2 {
                all[j][k].0.extend(acc[j][k].0.iter());
                all[j][k].1.extend(acc[j][k].1.iter());
            }
        }
    }
    let cell = |x: &(Vec<f64>, Vec<bool>)| {
        let (m, p, c) = summary(&x.0, &x.1);
        format!("{:>+6.1} {:>6.1} {:>5.0}({:>2})", m, p, c, x.0.len())
    };
    println!(
        "{:>6} | {} {} | {} {}",
        "all",
        cell(&all[0][0]),
        cell(&all[0][1]),
        cell(&all[1][0]),
        cell(&all[1][1])
    );
    println!("{:.1} s", t0.elapsed().as_secs_f64());
}
