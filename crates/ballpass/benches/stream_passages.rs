//! The windowed passage detection of streamed records
//! ([`ballpass::analysis::stream::passages::WindowedPassages`]) scored on
//! the randomized benches of `validate_passages` (the same draw), beside
//! the whole-record detection on the same records.
//!
//! ```text
//! cargo bench -p ballpass --bench stream_passages -- [train|fresh] [N]
//! ```
//!
//! The benches' records last 10–120 s, shorter than a streamed analysis'
//! windows (300 s and more): to exercise the windows here, each record is
//! cut into windows of a quarter of its length (at least three overlaps),
//! overlapping by 5 predicted ball-pass periods: fewer periods per window
//! than a streamed analysis gives each window's template, noise and
//! baseline, so a harder case. Prints, for records with two windows or
//! more: counts exact against the truth (each method, with exact 95 %
//! binomial intervals), counts equal between the methods, and the mean
//! width's difference between them and against the truth.

use ballpass::analysis::stream::passages::WindowedPassages;
use ballpass::analysis::PassageSettings;
use ballpass::recording::Channel;
use ballpass::sim::simulate;
use ballpass::stats::binomial_interval;
use ballpass::validate::passages::{score_simulation, score_with, PassageScore};
use ballpass::validate::Domain;
use rayon::prelude::*;

/// Overlap of the windows here, predicted ball-pass periods.
const OVERLAP_PERIODS: f64 = 5.0;

struct Pair {
    whole: PassageScore,
    windowed: PassageScore,
    windows: usize,
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let set = args.first().map(String::as_str).unwrap_or("fresh");
    let n: u64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(200);
    let first = match set {
        "train" => 1,
        "fresh" => 1_000_001,
        other => {
            eprintln!("unknown set {other}: train or fresh");
            std::process::exit(2);
        }
    };
    let domain = Domain::default();
    let t0 = std::time::Instant::now();
    let pairs: Vec<Pair> = (first..first + n)
        .into_par_iter()
        .map(|seed| {
            let bench = domain.draw(seed);
            let sim = simulate(&bench.settings(&bench.bearing(0, false), seed))
                .expect("the default domain draws valid benches");
            let settings = PassageSettings {
                geometry: Some(bench.geometry),
                ..PassageSettings::default()
            };
            let whole = score_simulation(&sim, &settings);
            let rec = &sim.recording;
            let fs = rec.fs_hz();
            let len = rec.len();
            let overlap = OVERLAP_PERIODS * sim.truth.tau_c_s;
            let window = (len as f64 / fs / 4.0).max(3.0 * overlap);
            let mut windows = 0;
            let windowed = score_with(&sim, |r| {
                let mut w = WindowedPassages::new(
                    &r.source_name(),
                    fs,
                    r.meta.start_time_s,
                    len,
                    (window, overlap),
                    &settings,
                );
                let x = r.channel(Channel::Optical).unwrap_or(&[]);
                for c in x.chunks(4096) {
                    w.push(c)?;
                }
                let (a, win) = w.finish()?;
                windows = win.count;
                Ok(a)
            });
            Pair {
                whole,
                windowed,
                windows,
            }
        })
        .collect();
    let elapsed = t0.elapsed().as_secs_f64();
    let multi: Vec<&Pair> = pairs.iter().filter(|p| p.windows >= 2).collect();
    let m = multi.len();
    println!(
        "{set}: {n} benches (seeds {first}..={}), {m} cut into two windows or more, {elapsed:.1} s\n",
        first + n - 1
    );
    let ci = |k: usize| {
        let [lo, hi] = binomial_interval(k, m, 0.95);
        format!(
            "{k}/{m} ({:.1} %, 95 % CI {:.1}–{:.1} %)",
            100.0 * k as f64 / m.max(1) as f64,
            100.0 * lo,
            100.0 * hi
        )
    };
    let exact_whole = multi.iter().filter(|p| p.whole.count_exact).count();
    let exact_win = multi.iter().filter(|p| p.windowed.count_exact).count();
    let same_count = multi
        .iter()
        .filter(|p| p.whole.error.is_none() && p.whole.detected == p.windowed.detected)
        .count();
    println!("| | whole record | windowed |");
    println!("|---|---|---|");
    println!(
        "| count exact vs truth | {} | {} |",
        ci(exact_whole),
        ci(exact_win)
    );
    let sum = |f: fn(&PassageScore) -> usize, which: fn(&Pair) -> &PassageScore| -> usize {
        multi.iter().map(|p| f(which(p))).sum()
    };
    let (req, miss_w, miss_s, spur_w, spur_s) = (
        sum(|s| s.required, |p| &p.whole),
        sum(|s| s.missed, |p| &p.whole),
        sum(|s| s.missed, |p| &p.windowed),
        sum(|s| s.spurious, |p| &p.whole),
        sum(|s| s.spurious, |p| &p.windowed),
    );
    println!("| missed of {req} required | {miss_w} | {miss_s} |");
    println!("| spurious | {spur_w} | {spur_s} |");
    let q = |mut v: Vec<f64>, f: f64| -> f64 {
        if v.is_empty() {
            return f64::NAN;
        }
        v.sort_by(f64::total_cmp);
        v[((v.len() - 1) as f64 * f).round() as usize]
    };
    let err = |which: fn(&Pair) -> &PassageScore| -> Vec<f64> {
        multi
            .iter()
            .filter_map(|p| which(p).width_error.map(f64::abs))
            .collect()
    };
    for (name, e) in [
        ("whole record", err(|p| &p.whole)),
        ("windowed", err(|p| &p.windowed)),
    ] {
        println!(
            "| width error vs truth, {name}: median / 90 % / 95 % | {:.2} % / {:.2} % / {:.2} % | |",
            100.0 * q(e.clone(), 0.5),
            100.0 * q(e.clone(), 0.9),
            100.0 * q(e, 0.95)
        );
    }
    let between: Vec<f64> = multi
        .iter()
        .filter_map(|p| Some((p.windowed.width_s? / p.whole.width_s? - 1.0).abs()))
        .collect();
    println!(
        "\ncounts equal between the methods: {}\nmean width, windowed against whole record: |difference| median {:.3} %, 90 % {:.3} %, 95 % {:.3} %, max {:.3} % ({} records)",
        ci(same_count),
        100.0 * q(between.clone(), 0.5),
        100.0 * q(between.clone(), 0.9),
        100.0 * q(between.clone(), 0.95),
        100.0 * q(between.clone(), 1.0),
        between.len()
    );
}
