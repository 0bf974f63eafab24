//! Ball-passage detection scored on randomized benches
//! ([`ballpass::validate::passages`]): every bench drawn from the default
//! domain, one record each, scored against the simulator's truth.
//!
//! ```text
//! cargo bench -p ballpass --bench validate_passages -- [train|fresh|fresh2|fresh3|fresh4|fresh5|fresh6|fresh7|fresh8|fresh9|fresh10|fresh11|fresh12] [N] [--list] [--json] [--clean] [--fwhm R] [--seeds a,b,...] [--recorded-width] [--velocity-factor K]
//! ```
//!
//! `train` draws bench seeds 1..=N (the seeds the rules were designed on),
//! `fresh` seeds 1_000_001..=1_000_000+N (never looked at before the rules
//! were first frozen), `fresh2` seeds 8_000_001..=8_000_000+N (never looked
//! at before the edge search and the AC-coupling step of the second
//! revision were frozen), `fresh3` seeds 11_000_001..=11_000_000+N (never
//! looked at before the AC coupling's plausibility check was frozen),
//! `fresh4` seeds 14_000_001..=14_000_000+N (never looked at before the
//! gap-following baseline and the overlap flag were frozen), `fresh5` seeds
//! 15_000_001..=15_000_000+N (never looked at before session 12's passage
//! rule was frozen; `fresh6`, 15_100_001+, kept for a rule changed after
//! that; `fresh7`, 15_200_001+, never looked at before session 14's rule
//! was frozen; `fresh8`, 15_300_001+, never looked at before session 15's
//! rule was frozen; `fresh9`, 15_400_001+, never looked at before session
//! 16, which scored session 15's rule on it again, unchanged; `fresh10`,
//! 15_500_001+, never looked at before session 17's rule was frozen;
//! `fresh12`, 37_100_001+, never looked at before session 20's missed-gap
//! rule was frozen; `fresh11`, 15_600_001+, kept unused until session 21,
//! which scored the release's rules on it once, unchanged since session 20). Prints the
//! Markdown tables of the report; `--list` also
//! prints one line per record that is not exact or whose width is off by
//! more than 3 %; `--json` prints every record's score instead of the
//! tables. `--clean` scores the same benches without noise, drift, AC
//! coupling or interference, `--fwhm R` with every pulse `R τ_c` wide
//! (what the detector does where nothing but the pulses' shape and
//! overlap is in the way). `--seeds a,b,...` scores only those bench
//! seeds (to look at single records of a design set). The headline width
//! truth is the width at half prominence of the pulses as recorded (SciPy's
//! `peak_widths` on the same bench without noise, drift, coupling or
//! interference; one pulse's FWHM where that record holds fewer than three
//! pulses), the FWHM of one pulse the second column. `--recorded-width`
//! prints, per record, the analysis' width error against the FWHM of one
//! pulse and against the width at half prominence, and the ratio of the two
//! truths. `--velocity-factor K` gives the analysis a tracking velocity
//! `K` times the record's (a real period mismatch: a wrong velocity, or
//! equally a wrong `d_avg`, since `f_c = v / (2 d_avg)`), to score the
//! period-mismatch and missed-passage conditions where the prediction is
//! wrong.

use ballpass::analysis::PassageSettings;
use ballpass::sim::simulate;
use ballpass::validate::passages::{
    score_and_recorded_width, score_simulation, summarize, PassageScore,
};
use ballpass::validate::Domain;
use rayon::prelude::*;

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let set = args.first().map(String::as_str).unwrap_or("fresh");
    let n: u64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(500);
    let list = args.iter().any(|a| a == "--list");
    let json = args.iter().any(|a| a == "--json");
    let first = match set {
        "train" => 1,
        "fresh" => 1_000_001,
        "fresh2" => 8_000_001,
        "fresh3" => 11_000_001,
        "fresh4" => 14_000_001,
        "fresh5" => 15_000_001,
        "fresh6" => 15_100_001,
        "fresh7" => 15_200_001,
        "fresh8" => 15_300_001,
        "fresh9" => 15_400_001,
        "fresh10" => 15_500_001,
        "fresh11" => 15_600_001,
        "fresh12" => 37_100_001,
        other => {
            eprintln!(
                "unknown set {other}: train, fresh, fresh2, fresh3, fresh4, fresh5, fresh6, fresh7, fresh8, fresh9, fresh10, fresh11 or fresh12"
            );
            std::process::exit(2);
        }
    };
    // `--clean`: the same benches without noise (pulse SNR 10⁵), drift,
    // AC coupling or interference; `--fwhm R`: every pulse R τ_c wide.
    let clean = args.iter().any(|a| a == "--clean");
    let fwhm: Option<f64> = args
        .iter()
        .position(|a| a == "--fwhm")
        .and_then(|i| args.get(i + 1))
        .and_then(|a| a.parse().ok());
    // `--seeds a,b,...`: only these bench seeds of the set (looking at
    // single records of a design set; the set's range is not checked).
    let only: Option<Vec<u64>> = args
        .iter()
        .position(|a| a == "--seeds")
        .and_then(|i| args.get(i + 1))
        .map(|a| a.split(',').filter_map(|v| v.trim().parse().ok()).collect());
    let domain = Domain::default();
    let t0 = std::time::Instant::now();
    let seeds: Vec<u64> = only.unwrap_or_else(|| (first..first + n).collect());
    // `--recorded-width`: one line per record with the analysis' width error
    // against the truth's FWHM of one pulse and against the width at half
    // prominence of the same pulses (SciPy's `peak_widths` on the bench
    // simulated again without noise, drift, coupling or interference).
    let recorded = args.iter().any(|a| a == "--recorded-width");
    let velocity_factor: Option<f64> = args
        .iter()
        .position(|a| a == "--velocity-factor")
        .and_then(|i| args.get(i + 1))
        .and_then(|a| a.parse().ok());
    let scored: Vec<(PassageScore, Option<f64>)> = seeds
        .into_par_iter()
        .map(|seed| {
            let mut bench = domain.draw(seed);
            if clean {
                let o = &mut bench.optical;
                o.noise_v = 1e-5 * o.pulse_amplitude_v;
                o.ac_coupling = false;
                o.baseline_drift_v = 0.0;
                o.interference_drift = false;
            }
            if let Some(r) = fwhm {
                bench.optical.width_ratio = r;
            }
            if let Some(k) = velocity_factor {
                // The analysis told a wrong velocity (no recorded-width ratio).
                let sim = simulate(&bench.settings(&bench.bearing(0, false), seed))
                    .expect("the default domain draws valid benches");
                let settings = PassageSettings {
                    geometry: Some(bench.geometry),
                    velocity_mm_s: sim.recording.meta.velocity_mm_s.map(|v| k * v),
                    ..PassageSettings::default()
                };
                let mut s = score_simulation(&sim, &settings);
                s.bench.bench_seed = bench.seed;
                return (s, None);
            }
            score_and_recorded_width(&bench, seed).expect("the default domain draws valid benches")
        })
        .collect();
    if recorded {
        for (s, w) in &scored {
            println!(
                "seed {:>8} {:<13} fwhm {:.3} τc snr {:8.1} interference {:<5} widths {:?} | analysis {:+.4} | half prominence / FWHM {:.4} | analysis vs half prominence {:+.4}",
                s.bench.bench_seed,
                s.bench.shape.name(),
                s.bench.fwhm_tau_c,
                s.bench.snr,
                s.truth.interference,
                s.widths_used,
                s.width_error_fwhm.unwrap_or(f64::NAN),
                w.unwrap_or(f64::NAN),
                match (s.width_error_fwhm, w) {
                    (Some(e), Some(r)) => (1.0 + e) / r - 1.0,
                    _ => f64::NAN,
                }
            );
        }
        return;
    }
    let scores: Vec<PassageScore> = scored.into_iter().map(|(s, _)| s).collect();
    let elapsed = t0.elapsed().as_secs_f64();
    if list {
        for s in &scores {
            let off = s.width_error.is_none_or(|e| e.abs() > 0.03)
                || s.width_error_fwhm.is_some_and(|e| e.abs() > 0.03);
            if !s.count_exact || off {
                println!(
                    "seed {:>8} v {:5.2} fs {:5} T {:5.1} snr {:5.1} fwhm {:.3} ({:7.1} smp) {:<13} ac {:<5} {:?} drift {:.2} intf {:<5} | req {:3} miss {:2} spur {:2} (inv {:2}) pol {:2} width {:+.3} (FWHM {:+.3}, stated {:+.3}) used {:?} withheld {} {:?}",
                    s.bench.seed,
                    s.bench.velocity_mm_s,
                    s.bench.fs_hz,
                    s.bench.duration_s,
                    s.bench.snr,
                    s.bench.fwhm_tau_c,
                    s.bench.fwhm_samples,
                    s.bench.shape.name(),
                    s.truth.ac_coupling,
                    s.truth.ac_time_constant_s.map(|t| (t * 100.0).round() / 100.0),
                    s.truth.drift_fraction,
                    s.truth.interference,
                    s.required,
                    s.missed,
                    s.spurious,
                    s.spurious_inverted,
                    s.polarity_errors,
                    s.width_error.unwrap_or(f64::NAN),
                    s.width_error_fwhm.unwrap_or(f64::NAN),
                    s.width_error_stated.unwrap_or(f64::NAN),
                    s.widths_used,
                    s.width_withheld,
                    s.error
                );
            }
        }
    }
    if json {
        for s in &scores {
            println!("{}", serde_json::to_string(s).expect("scores serialise"));
        }
        return;
    }
    println!(
        "{set}: {} benches (seeds {first}..={}), {elapsed:.1} s\n",
        scores.len(),
        first + n - 1
    );
    print!("{}", summarize(&scores).to_markdown());
}
