//! Stage identification scored on randomized benches
//! ([`ballpass::model::identify`]): every bench drawn from the default
//! validation domain, one record each (the good bearing of
//! `ballpass validate`'s lag/stage part), the friction → velocity-error
//! spectra fitted, and each identified stage scored against the simulated
//! stage: within the ±5 % (f_n) / ±20 % (ζ) bar, and whether the stated
//! 95 % intervals of f_n, ζ and the peak gain hold the truth (coverage,
//! with exact binomial intervals).
//!
//! ```text
//! cargo bench -p ballpass --bench validate_stage -- [train|fresh|fresh2|SEED] [N] [--list] [--dump DIR] [--domain FILE]
//! ```
//!
//! `train` draws bench seeds 3_000_001..=3_000_000+N (the seeds the interval
//! was designed on), `fresh` seeds 9_100_001..=9_100_000+N (never looked at
//! before the first estimator was frozen; seen since), `fresh2` seeds
//! 9_200_001..=9_200_000+N (never looked at before the load-cell, chain and
//! residual-correlation terms were frozen); a number starts there. `--list` prints one
//! line per identified stage; `--dump DIR` writes each bench's spectra up to
//! a quarter of the rate (`seed.bin`: little-endian f64 rows of frequency,
//! P_ff, P_vv, Re P_fv, Im P_fv) and `index.jsonl` (the truth, the load
//! cell's time constant and the one the analysis undid, and the estimate)
//! for offline study. `--domain FILE` draws the benches from a domain file
//! (the JSON of `ballpass validate --domain`, e.g. one lab's bench) instead
//! of the default domain.

use std::io::Write;

use ballpass::analysis::AnalyzeSettings;
use ballpass::model::identify::{identify, StageIdentification, StageSpectra};
use ballpass::sim::simulate;
use ballpass::validate::{Domain, Rate};
use rayon::prelude::*;

/// One bench's outcome.
struct Row {
    seed: u64,
    fs_hz: f64,
    duration_s: f64,
    noise_n: f64,
    truth: [f64; 3],
    id: Option<StageIdentification>,
    n_d: f64,
    load_cell_tau_s: Option<f64>,
    restored_tau_s: Option<f64>,
    spectra: Option<StageSpectra>,
    error: Option<String>,
}

fn truth_of(st: &ballpass::sim::StageSettings) -> [f64; 3] {
    let f_n = (st.kkp_n_per_m / st.mass_kg).sqrt() / std::f64::consts::TAU;
    let zeta = st.kkd_n_s_per_m / (2.0 * (st.mass_kg * st.kkp_n_per_m).sqrt());
    [f_n, zeta, 1e3 / st.kkd_n_s_per_m]
}

fn one(domain: &Domain, seed: u64, keep: bool) -> Row {
    let b = domain.draw(seed);
    let s = b.settings(&b.bearing(0, false), seed);
    let mut row = Row {
        seed,
        fs_hz: b.fs_hz,
        duration_s: b.duration_s,
        noise_n: s.load_cell.noise_n,
        truth: truth_of(&s.stage),
        id: None,
        n_d: 0.0,
        load_cell_tau_s: s.load_cell.time_constant_s,
        restored_tau_s: None,
        spectra: None,
        error: None,
    };
    let run = || -> Result<Option<StageSpectra>, String> {
        let sim = simulate(&s).map_err(|e| e.to_string())?;
        let pred = b
            .geometry
            .predict(b.velocity_mm_s, 5)
            .map_err(|e| e.to_string())?;
        StageSpectra::of_recording(
            &sim.recording,
            b.velocity_mm_s,
            pred.tau_c_s,
            AnalyzeSettings::default().load_cell,
        )
        .map_err(|e| e.to_string())
    };
    match run() {
        Ok(Some(sp)) => {
            row.id = Some(identify(&sp));
            row.n_d = sp.n_d;
            row.restored_tau_s = sp.restored_tau_s;
            if keep {
                row.spectra = Some(sp);
            }
        }
        Ok(None) => row.error = Some("no friction or position channel".into()),
        Err(e) => row.error = Some(e),
    }
    row
}

fn dump(dir: &std::path::Path, r: &Row) -> std::io::Result<()> {
    let Some(sp) = &r.spectra else {
        return Ok(());
    };
    let mut bytes = Vec::new();
    for (i, &f) in sp.freq_hz.iter().enumerate() {
        if f > 0.25 * sp.fs_hz {
            break;
        }
        for v in [f, sp.p_ff[i], sp.p_vv[i], sp.p_fv[i].re, sp.p_fv[i].im] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(dir.join(format!("{}.bin", r.seed)), bytes)
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let set = args.first().map(String::as_str).unwrap_or("fresh");
    let n: u64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(400);
    let list = args.iter().any(|a| a == "--list");
    let dump_dir = args
        .iter()
        .position(|a| a == "--dump")
        .and_then(|i| args.get(i + 1))
        .map(std::path::PathBuf::from);
    let first = match set {
        "train" => 3_000_001,
        "fresh" => 9_100_001,
        "fresh2" => 9_200_001,
        other => match other.parse::<u64>() {
            Ok(s) => s,
            Err(_) => {
                eprintln!("unknown set {other}: train, fresh, fresh2 or a first seed");
                std::process::exit(2);
            }
        },
    };
    if let Some(d) = &dump_dir {
        if let Err(e) = std::fs::create_dir_all(d) {
            eprintln!("{}: {e}", d.display());
            std::process::exit(1);
        }
    }
    let domain = match args
        .iter()
        .position(|a| a == "--domain")
        .and_then(|i| args.get(i + 1))
    {
        Some(p) => {
            let d = std::fs::read_to_string(p)
                .map_err(|e| e.to_string())
                .and_then(|t| serde_json::from_str::<Domain>(&t).map_err(|e| e.to_string()))
                .and_then(|d| d.validate().map(|()| d).map_err(|e| e.to_string()));
            match d {
                Ok(d) => d,
                Err(e) => {
                    eprintln!("{p}: not a domain: {e}");
                    std::process::exit(2);
                }
            }
        }
        None => Domain::default(),
    };
    let t0 = std::time::Instant::now();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let rows: Vec<Row> = (first..first + n)
        .into_par_iter()
        .map(|seed| {
            let mut r = one(&domain, seed, dump_dir.is_some());
            if let Some(d) = &dump_dir {
                if let Err(e) = dump(d, &r) {
                    eprintln!("{}: {e}", d.display());
                }
                r.spectra = None;
            }
            let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if k % 50 == 0 {
                eprintln!("{k}/{n} ({:.0} s)", t0.elapsed().as_secs_f64());
            }
            r
        })
        .collect();
    let elapsed = t0.elapsed().as_secs_f64();
    if let Some(d) = &dump_dir {
        let mut idx = std::fs::File::create(d.join("index.jsonl")).expect("index file");
        for r in &rows {
            let id = r.id.as_ref();
            let est = |e: Option<ballpass::model::identify::Estimate>| {
                e.map_or(serde_json::Value::Null, |e| {
                    serde_json::json!([e.value, e.ci95])
                })
            };
            let line = serde_json::json!({
                "seed": r.seed, "fs": r.fs_hz, "tau": r.load_cell_tau_s, "tau_hat": r.restored_tau_s, "T": r.duration_s, "noise": r.noise_n, "n_d": r.n_d,
                "truth": r.truth,
                "identified": id.is_some_and(|i| i.identified),
                "f_n": est(id.and_then(|i| i.natural_frequency_hz)),
                "zeta": est(id.and_then(|i| i.damping_ratio)),
                "gain": est(id.and_then(|i| i.peak_gain_mm_s_per_n)),
                "chi2": id.and_then(|i| i.reduced_chi2),
                "bins": id.map(|i| i.bins_used),
                "band": id.and_then(|i| i.band_hz),
                "error": r.error,
            });
            writeln!(idx, "{line}").expect("index file");
        }
    }
    let failed: Vec<&Row> = rows.iter().filter(|r| r.error.is_some()).collect();
    let ok = rows.len() - failed.len();
    let ids: Vec<(&Row, &StageIdentification)> = rows
        .iter()
        .filter_map(|r| r.id.as_ref().filter(|i| i.identified).map(|i| (r, i)))
        .collect();
    let mut within = 0;
    let mut cover = [0usize; 3];
    let mut both = 0;
    for (r, id) in &ids {
        let est = [
            id.natural_frequency_hz,
            id.damping_ratio,
            id.peak_gain_mm_s_per_n,
        ];
        let inside: Vec<bool> = est
            .iter()
            .zip(r.truth)
            .map(|(e, t)| e.is_some_and(|e| (e.value - t).abs() <= e.ci95))
            .collect();
        for (c, &i) in cover.iter_mut().zip(&inside) {
            *c += usize::from(i);
        }
        both += usize::from(inside[0] && inside[1]);
        let rel = |k: usize| est[k].map_or(f64::NAN, |e| e.value / r.truth[k] - 1.0);
        within += usize::from(rel(0).abs() <= 0.05 && rel(1).abs() <= 0.2);
        if list {
            let z =
                |k: usize| est[k].map_or(f64::NAN, |e| (e.value - r.truth[k]) / (e.ci95 / 1.96));
            println!(
                "seed {:>8} fs {:5} T {:5.1} noise {:.3} | f_n {:6.2} ζ {:.2} | f_n {:+.3} (±{:.3}) z {:+5.1} | ζ {:+.3} (±{:.3}) z {:+5.1} | gain {:+.3} z {:+5.1} | χ² {:.2} bins {}",
                r.seed,
                r.fs_hz,
                r.duration_s,
                r.noise_n,
                r.truth[0],
                r.truth[1],
                rel(0),
                est[0].map_or(f64::NAN, |e| e.ci95 / r.truth[0]),
                z(0),
                rel(1),
                est[1].map_or(f64::NAN, |e| e.ci95 / r.truth[1]),
                z(1),
                rel(2),
                z(2),
                id.reduced_chi2.unwrap_or(f64::NAN),
                id.bins_used
            );
        }
    }
    for r in &failed {
        println!(
            "seed {} failed: {}",
            r.seed,
            r.error.as_deref().unwrap_or("")
        );
    }
    let m = ids.len();
    println!(
        "{set}: {n} benches (seeds {first}..={}), {elapsed:.1} s\n",
        first + n - 1
    );
    println!("| score | k/n (95 % interval) |");
    println!("|---|---|");
    println!("| stage identified | {} |", Rate::of(m, ok));
    println!(
        "| identified within ±5 % f_n, ±20 % ζ | {} |",
        Rate::of(within, m)
    );
    println!(
        "| f_n inside its 95 % interval | {} |",
        Rate::of(cover[0], m)
    );
    println!("| ζ inside its 95 % interval | {} |", Rate::of(cover[1], m));
    println!(
        "| peak gain inside its 95 % interval | {} |",
        Rate::of(cover[2], m)
    );
    println!("| f_n and ζ both inside | {} |", Rate::of(both, m));
    if !failed.is_empty() {
        println!("| benches not simulated/analysed | {} |", failed.len());
    }
}
