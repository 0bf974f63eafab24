//! The friction → optical lag at f_c, record by record, as `ballpass
//! validate`'s lag part scores it (one good-bearing record per bench of
//! the default domain, ≥ 10 periods, measurable), with the bench's
//! roughness and stage beside each error, so that the interval's coverage
//! can be read against them.
//!
//! ```text
//! cargo bench -p ballpass --bench lag_census -- FIRST_SEED N [--rough FRAC] [--len MM]
//!     [--stiff] [--quiet-sensors]
//! ```
//!
//! `--rough` / `--len` fix the domain's roughness (fraction of the Coulomb
//! level) or its correlation length; `--stiff` fixes the stage at 50 Hz,
//! ζ 0.7 (little velocity ripple); `--quiet-sensors` divides the load-cell
//! and optical noise by 1000. Every other draw of each bench is unchanged
//! (a fixed range still takes its draw). One CSV line per measurable
//! record, then the coverage.

use ballpass::analysis::load_cell::LoadCellCorrection;
use ballpass::analysis::{analyze, AnalyzeSettings};
use ballpass::sim::simulate;
use ballpass::validate::{Domain, Range};
use rayon::prelude::*;

fn wrap(x: f64) -> f64 {
    let y = x - x.round();
    if y <= -0.5 {
        y + 1.0
    } else {
        y
    }
}

/// `--mc SEED R SIGMA_SCALE [white]`: the bench simulated DC-coupled with
/// no roughness, then `R` records of it with an Ornstein–Uhlenbeck
/// roughness of its own (the bench's std times `SIGMA_SCALE`, correlation
/// time `len / v`; `white`: white noise of the same std instead) added to
/// friction: the error over the interval per realisation.
fn monte_carlo(args: &[String]) {
    use ballpass::recording::{Channel, Channels, Recording};
    let seed: u64 = args[0].parse().unwrap();
    let reps: u64 = args[1].parse().unwrap();
    let scale: f64 = args[2].parse().unwrap();
    let white = args.get(3).is_some_and(|a| a == "white");
    let d = Domain {
        load_cell_dc_probability: 1.0,
        ..Domain::default()
    };
    let b = d.draw(seed);
    let mut s = b.settings(&b.bearing(0, false), seed);
    let sigma = s.friction.roughness_n * scale;
    let len = s.friction.roughness_length_mm;
    s.friction.roughness_n = 0.0;
    let sim = simulate(&s).unwrap();
    let t = &sim.truth;
    let pred = b.geometry.predict(b.velocity_mm_s, 5).unwrap();
    let rec = &sim.recording;
    let fs = rec.fs_hz();
    let tc = len / b.velocity_mm_s;
    let rho = (-1.0 / (fs * tc)).exp();
    let errs: Vec<Option<(f64, f64)>> = (0..reps)
        .into_par_iter()
        .map(|r| {
            let mut g = ballpass::sim::rng::Rng::new(seed * 1000 + r);
            let mut x = sigma * g.normal();
            let fr: Vec<f64> = rec
                .channel(Channel::Friction)
                .unwrap()
                .iter()
                .map(|v| {
                    let out = v + if white { sigma * g.normal() } else { x };
                    x = rho * x + sigma * (1.0 - rho * rho).sqrt() * g.normal();
                    out
                })
                .collect();
            let rec2 = Recording::new(
                fs,
                Channels {
                    friction_n: Some(fr),
                    position_mm: rec.channel(Channel::Position).map(<[f64]>::to_vec),
                    optical_v: rec.channel(Channel::Optical).map(<[f64]>::to_vec),
                },
                rec.meta.clone(),
            )
            .unwrap();
            let a = analyze(
                std::slice::from_ref(&rec2),
                &pred,
                &AnalyzeSettings::default(),
            )
            .ok()?;
            let p = a.phases.iter().find(|p| p.pair == "friction__optical")?;
            let phase = p.phase_deg?;
            let ci = p.phase_ci95_deg.unwrap_or(0.0) / 360.0;
            Some((wrap(-phase / 360.0 - t.optical_lag_s / t.tau_c_s), ci))
        })
        .collect();
    let m: Vec<(f64, f64)> = errs.into_iter().flatten().collect();
    let inside = m.iter().filter(|(e, c)| e.abs() <= *c).count();
    let mean = m.iter().map(|r| r.0).sum::<f64>() / m.len() as f64;
    let sd = (m.iter().map(|r| (r.0 - mean).powi(2)).sum::<f64>() / m.len() as f64).sqrt();
    let ci_med = {
        let mut c: Vec<f64> = m.iter().map(|r| r.1).collect();
        c.sort_by(f64::total_cmp);
        c.get(c.len() / 2).copied().unwrap_or(f64::NAN)
    };
    println!(
        "seed {seed} scale {scale} white {white}: measurable {}/{reps}, inside {inside} ({:.3}), mean err {mean:+.5}, sd {sd:.5}, median ci {ci_med:.5}, sd*1.96/ci {:.3}; periods {:.1} f_c {:.3} d_avg {:.3} len {len:.3} v {:.2}",
        m.len(),
        inside as f64 / m.len() as f64,
        1.96 * sd / ci_med,
        s.duration_s / t.tau_c_s,
        t.f_c_hz,
        t.d_avg_mm,
        b.velocity_mm_s
    );
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if args[0] == "--mc" {
        monte_carlo(&args[1..]);
        return;
    }
    let first: u64 = args[0].parse().expect("FIRST_SEED");
    let n: u64 = args[1].parse().expect("N");
    let mut d = Domain::default();
    let mut quiet = false;
    let mut true_tau = false;
    let mut i = 2;
    while i < args.len() {
        match args[i].as_str() {
            "--rough" => {
                d.roughness_fraction = Range::fixed(args[i + 1].parse().unwrap());
                i += 1;
            }
            "--len" => {
                d.roughness_length_mm = Range::fixed(args[i + 1].parse().unwrap());
                i += 1;
            }
            "--stiff" => {
                d.stage_f_n_hz = Range::fixed(50.0);
                d.stage_zeta = Range::fixed(0.7);
            }
            "--quiet-sensors" => quiet = true,
            "--dc" => d.load_cell_dc_probability = 1.0,
            "--true-tau" => true_tau = true,
            a => panic!("unknown argument {a}"),
        }
        i += 1;
    }
    let rows: Vec<Option<String>> = (first..first + n)
        .into_par_iter()
        .map(|seed| {
            let b = d.draw(seed);
            let mut s = b.settings(&b.bearing(0, false), seed);
            if quiet {
                s.load_cell.noise_n /= 1000.0;
                s.optical.noise_v /= 1000.0;
            }
            let sim = simulate(&s).ok()?;
            let t = &sim.truth;
            let pred = b.geometry.predict(b.velocity_mm_s, 5).ok()?;
            let mut settings = AnalyzeSettings::default();
            if true_tau {
                settings.load_cell = match s.load_cell.time_constant_s {
                    Some(tau) => LoadCellCorrection::TimeConstant(tau),
                    None => LoadCellCorrection::Off,
                };
            }
            let a = analyze(std::slice::from_ref(&sim.recording), &pred, &settings).ok()?;
            let periods = s.duration_s / t.tau_c_s;
            if periods < 10.0 {
                return None;
            }
            let p = a.phases.iter().find(|p| p.pair == "friction__optical")?;
            let phase = p.phase_deg?;
            let ci = p.phase_ci95_deg.unwrap_or(0.0) / 360.0;
            let applied = a.load_cell.first().is_some_and(|d| d.applied);
            let truth = if applied {
                t.optical_lag_force_s
            } else {
                t.optical_lag_s
            };
            let err = wrap(-phase / 360.0 - truth / t.tau_c_s);
            let st = &s.stage;
            let f_n = (st.kkp_n_per_m / st.mass_kg).sqrt() / std::f64::consts::TAU;
            let zeta = st.kkd_n_s_per_m / (2.0 * (st.mass_kg * st.kkp_n_per_m).sqrt());
            Some(format!(
                "{seed},{periods:.1},{:.2},{:.0},{:.4},{:.3},{:.4},{:.3},{:.4},{:.3},{:.2},{:.2},{:.4},{:.4},{:.5},{:.5},{:.2},{},{:.3},{:.3}",
                b.velocity_mm_s,
                s.fs_hz,
                t.f_c_hz,
                t.d_avg_mm,
                s.friction.roughness_n,
                s.friction.roughness_length_mm,
                s.friction.pulse_amplitude_n,
                s.load_cell.noise_n,
                f_n,
                zeta,
                t.f_c_hz / f_n,
                p.coherence.unwrap_or(f64::NAN),
                err,
                ci,
                err.abs() / ci,
                u8::from(applied),
                s.load_cell.time_constant_s.unwrap_or(f64::INFINITY),
                a.load_cell.first().and_then(|d| d.tau_s).unwrap_or(f64::NAN)
            ))
        })
        .collect();
    println!("seed,periods,v,fs,f_c,d_avg,rough_n,rough_len,ripple_n,lc_noise,f_n,zeta,fc_over_fn,coh,err,ci,err_over_ci,applied,tau_true,tau_used");
    let (mut m, mut inside, mut within) = (0, 0, 0);
    for r in rows.iter().flatten() {
        println!("{r}");
        let f: Vec<f64> = r.split(',').map(|v| v.parse().unwrap()).collect();
        m += 1;
        inside += usize::from(f[14].abs() <= f[15]);
        within += usize::from(f[14].abs() <= 0.02);
    }
    eprintln!("measurable {m}; inside own interval {inside}; within 0.02 tau_c {within}");
}
