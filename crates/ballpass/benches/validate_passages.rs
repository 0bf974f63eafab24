//! Ball-passage detection scored on randomized benches
//! ([`ballpass::validate::passages`]): every bench drawn from the default
//! domain, one record each, scored against the simulator's truth.
//!
//! ```text
//! cargo bench -p ballpass --bench validate_passages -- [train|fresh|fresh2|fresh3|fresh4] [N] [--list]
//! ```
//!
//! `train` draws bench seeds 1..=N (the seeds the rules were designed on),
//! `fresh` seeds 1_000_001..=1_000_000+N (never looked at before the rules
//! were first frozen), `fresh2` seeds 8_000_001..=8_000_000+N (never looked
//! at before the edge search and the AC-coupling step of the second
//! revision were frozen), `fresh3` seeds 11_000_001..=11_000_000+N (never
//! looked at before the AC coupling's plausibility check was frozen),
//! `fresh4` seeds 14_000_001..=14_000_000+N (never looked at before the
//! gap-following baseline and the overlap flag were frozen). Prints the
//! Markdown tables of the report; `--list` also
//! prints one line per record that is not exact or whose width is off by
//! more than 3 %.

use ballpass::validate::passages::{score, summarize, PassageScore};
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
        other => {
            eprintln!("unknown set {other}: train, fresh, fresh2, fresh3 or fresh4");
            std::process::exit(2);
        }
    };
    let domain = Domain::default();
    let t0 = std::time::Instant::now();
    let scores: Vec<PassageScore> = (first..first + n)
        .into_par_iter()
        .map(|seed| {
            score(&domain.draw(seed), seed).expect("the default domain draws valid benches")
        })
        .collect();
    let elapsed = t0.elapsed().as_secs_f64();
    if list {
        for s in &scores {
            let off = s.width_error.is_none_or(|e| e.abs() > 0.03);
            if !s.count_exact || off {
                println!(
                    "seed {:>8} v {:5.2} fs {:5} T {:5.1} snr {:5.1} fwhm {:.3} ({:7.1} smp) {:<13} ac {:<5} {:?} drift {:.2} intf {:<5} | req {:3} miss {:2} spur {:2} (inv {:2}) pol {:2} width {:+.3} (stated {:+.3}) used {:?} {:?}",
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
                    s.width_error_stated.unwrap_or(f64::NAN),
                    s.widths_used,
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
        "{set}: {n} benches (seeds {first}..={}), {elapsed:.1} s\n",
        first + n - 1
    );
    print!("{}", summarize(&scores).to_markdown());
}
