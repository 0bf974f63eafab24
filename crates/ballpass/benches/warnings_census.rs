//! How often `analyze` warns on a good bearing, and about what: every
//! bench drawn from the default validation domain, one record of its good
//! bearing each (as `ballpass validate`'s lag/stage part draws them), the
//! analysis run with default settings, and its warnings counted by kind
//! (the message with its numbers blanked). A warning a lab sees on most
//! healthy records teaches it to ignore warnings; this measures that.
//!
//! On the records of ten periods or more it also counts, per signal,
//! whether the line at `f_c` could be tested against its floor and was
//! significant, and how often "friction shows f_c" was claimed (every
//! such record has a friction ripple): a line that cannot be tested is a
//! verdict the record could have given and did not.
//!
//! ```text
//! cargo bench -p ballpass --bench warnings_census -- FIRST_SEED [N] [--list]
//! cargo bench -p ballpass --bench warnings_census -- --write SEED FILE.csv
//! ```
//!
//! Prints, for each kind, how many records carried it (exact 95 %
//! binomial interval) and one example; `--list` adds one line per record
//! with a warning. It ends with the load cell's high-pass: the phase
//! advance left at `f_c` on the records warned of an unknown high-pass and
//! on the others (does the warning mean something, and is it missing
//! anywhere?). `--write` writes one bench's record and its truth
//! (`FILE.truth.json`) for a closer look with `ballpass analyze`.

use std::collections::BTreeMap;

use ballpass::analysis::{analyze, AnalyzeSettings, Signal};
use ballpass::sim::simulate;
use ballpass::validate::{Domain, Rate};
use rayon::prelude::*;

/// A warning's kind: its words with every number replaced by `#`.
fn kind(w: &str) -> String {
    let mut out = String::with_capacity(w.len());
    let mut in_number = false;
    let chars: Vec<char> = w.chars().collect();
    for (i, &c) in chars.iter().enumerate() {
        // A minus sign belongs to the number after it, a hyphen to words.
        let sign = c == '-' && !in_number && chars.get(i + 1).is_some_and(char::is_ascii_digit);
        let numeric = c.is_ascii_digit() || (in_number && (c == '.' || c == ',')) || sign;
        if numeric {
            if !in_number {
                out.push('#');
            }
            in_number = true;
        } else {
            in_number = false;
            out.push(c);
        }
    }
    out
}

/// One record: its bench in a few words, its warnings, and (with ten
/// periods or more) the `k = 1` outcome of each signal and whether
/// friction periodicity was claimed.
struct Record {
    bench: String,
    warnings: Vec<String>,
    lines: Option<([Option<bool>; 3], bool)>,
    high_pass: HighPass,
}

/// The load cell's high-pass at `f_c` on one record: what the simulator
/// put in, and what the analysis did about it.
struct HighPass {
    /// Phase advance of the simulated high-pass at `f_c`, degrees (0 for a
    /// DC-coupled sensor).
    true_deg: f64,
    /// Advance left after the analysis' restoration (the true advance less
    /// the one it undid), degrees.
    left_deg: f64,
    /// The analysis warned of an unknown high-pass.
    warned: bool,
}

/// Phase advance of a first-order high-pass of time constant `tau_s` at
/// `f_hz`, degrees.
fn advance_deg(tau_s: Option<f64>, f_hz: f64) -> f64 {
    tau_s.map_or(0.0, |t| {
        (1.0 / (std::f64::consts::TAU * f_hz * t))
            .atan()
            .to_degrees()
    })
}

/// The signals whose `k = 1` line is counted.
const SIGNALS: [Signal; 3] = [Signal::Optical, Signal::Friction, Signal::VelocityError];

/// One record (`Err`: the bench could not be simulated or analysed, with
/// the reason).
fn one(domain: &Domain, seed: u64) -> Result<Record, String> {
    let b = domain.draw(seed);
    let s = b.settings(&b.bearing(0, false), seed);
    let sim = simulate(&s).map_err(|e| e.to_string())?;
    let pred = b
        .geometry
        .predict(b.velocity_mm_s, 5)
        .map_err(|e| e.to_string())?;
    let a = analyze(
        std::slice::from_ref(&sim.recording),
        &pred,
        &AnalyzeSettings::default(),
    )
    .map_err(|e| e.to_string())?;
    let bench = format!(
        "{:.0} Hz, {:.1} s, {:.2} mm/s, {:.1} periods",
        b.fs_hz,
        b.duration_s,
        b.velocity_mm_s,
        b.duration_s / sim.truth.tau_c_s
    );
    let lines = (b.duration_s / sim.truth.tau_c_s >= 10.0).then(|| {
        let k1 = SIGNALS.map(|sig| {
            a.harmonics
                .iter()
                .find(|h| h.k == 1 && h.signal == sig)
                .and_then(|h| h.significant)
        });
        (k1, !a.verdict.friction_harmonics_flagged.is_empty())
    });
    let f_c = sim.truth.f_c_hz;
    let true_deg = advance_deg(s.load_cell.time_constant_s, f_c);
    let dc = a.load_cell.first();
    let undone = dc
        .filter(|d| d.applied)
        .map_or(0.0, |d| advance_deg(d.tau_s, f_c));
    let high_pass = HighPass {
        true_deg,
        left_deg: true_deg - undone,
        warned: dc.is_some_and(|d| d.unknown_high_pass),
    };
    Ok(Record {
        bench,
        warnings: a.warnings,
        lines,
        high_pass,
    })
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    if let [flag, seed, path] = args.as_slice() {
        if flag == "--write" {
            let seed: u64 = seed
                .parse()
                .expect("--write SEED FILE.csv: SEED is a number");
            let domain = Domain::default();
            let b = domain.draw(seed);
            let sim = simulate(&b.settings(&b.bearing(0, false), seed)).expect("simulate");
            let path = std::path::Path::new(path);
            ballpass::recording::write_csv(&sim.recording, path).expect("write the record");
            sim.truth
                .write_json(&ballpass::sim::truth_path(path))
                .expect("write the truth");
            return;
        }
    }
    let Some(first) = args.first().and_then(|a| a.parse::<u64>().ok()) else {
        eprintln!("usage: warnings_census FIRST_SEED [N] [--list]");
        std::process::exit(2);
    };
    let n: u64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(200);
    let list = args.iter().any(|a| a == "--list");
    let domain = Domain::default();
    let rows: Vec<(u64, Result<Record, String>)> = (first..first + n)
        .into_par_iter()
        .map(|seed| (seed, one(&domain, seed)))
        .collect();
    let mut kinds: BTreeMap<String, (usize, String)> = BTreeMap::new();
    let (mut analysed, mut warned) = (0usize, 0usize);
    for (seed, r) in &rows {
        match r {
            Ok(Record {
                bench, warnings: w, ..
            }) => {
                analysed += 1;
                if !w.is_empty() {
                    warned += 1;
                    if list {
                        println!("{seed} ({bench}): {}", w.join(" | "));
                    }
                }
                // Each kind once per record, with its first message.
                let seen: BTreeMap<String, &String> =
                    w.iter().rev().map(|x| (kind(x), x)).collect();
                for (k, ex) in seen {
                    kinds.entry(k).or_insert((0, ex.clone())).0 += 1;
                }
            }
            Err(e) => println!("{seed}: not analysed: {e}"),
        }
    }
    println!(
        "good-bearing records (seeds {first}..{}): analysed {analysed}/{n}; with any warning {}",
        first + n - 1,
        Rate::of(warned, analysed)
    );
    let mut by_count: Vec<(&String, &(usize, String))> = kinds.iter().collect();
    by_count.sort_by_key(|b| std::cmp::Reverse(b.1 .0));
    for (k, (c, ex)) in by_count {
        println!("  {}  {k}\n      e.g. {ex}", Rate::of(*c, analysed));
    }
    let long: Vec<&([Option<bool>; 3], bool)> = rows
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok()?.lines.as_ref())
        .collect();
    println!("records of ten periods or more: {}", long.len());
    for (i, sig) in SIGNALS.iter().enumerate() {
        let untested = long.iter().filter(|l| l.0[i].is_none()).count();
        let significant = long.iter().filter(|l| l.0[i] == Some(true)).count();
        println!(
            "  {:<15} line at f_c not tested {}; significant {}",
            sig.words(),
            Rate::of(untested, long.len()),
            Rate::of(significant, long.len())
        );
    }
    println!(
        "  friction shows f_c (claimed; every record has a ripple) {}",
        Rate::of(long.iter().filter(|l| l.1).count(), long.len())
    );
    high_pass_census(&rows);
}

/// Whether the unknown-high-pass warning means something: the advance the
/// load cell left in the friction's phase at `f_c`, on the records it was
/// raised on and on those it was not.
fn high_pass_census(rows: &[(u64, Result<Record, String>)]) {
    let hp: Vec<&HighPass> = rows
        .iter()
        .filter_map(|(_, r)| Some(&r.as_ref().ok()?.high_pass))
        .collect();
    let band = |warned: bool, lo: f64, hi: f64| {
        hp.iter()
            .filter(|h| h.warned == warned && h.left_deg.abs() >= lo && h.left_deg.abs() < hi)
            .count()
    };
    for warned in [true, false] {
        let n = hp.iter().filter(|h| h.warned == warned).count();
        println!(
            "{} the unknown-high-pass warning: {n}; advance left at f_c ≥ 10° {}, 2–10° {}, < 2° {}",
            if warned { "records with" } else { "records without" },
            Rate::of(band(warned, 10.0, f64::INFINITY), n),
            Rate::of(band(warned, 2.0, 10.0), n),
            Rate::of(band(warned, 0.0, 2.0), n),
        );
    }
    let ac = hp.iter().filter(|h| h.true_deg > 0.0).count();
    println!(
        "  AC-coupled load cells: {ac}; restored (advance left < 2° where the true one was ≥ 2°) {}",
        Rate::of(
            hp.iter()
                .filter(|h| h.true_deg >= 2.0 && h.left_deg.abs() < 2.0)
                .count(),
            hp.iter().filter(|h| h.true_deg >= 2.0).count()
        )
    );
}
