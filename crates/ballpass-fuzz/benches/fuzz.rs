//! The long fuzz run (see the crate doc): `cargo bench -p ballpass-fuzz
//! --bench fuzz -- [--execs N] [--seed S] [--seconds T] [--out DIR]`.
//! Prints the report; exits 1 when anything failed.

use std::time::Duration;

use ballpass_fuzz::alloc::Counting;
use ballpass_fuzz::harness::{run, Config};

#[global_allocator]
static ALLOC: Counting = Counting;

fn main() {
    let mut config = Config {
        seed: 1,
        execs: 1_000_000,
        max_time: None,
        save_dir: std::path::PathBuf::from("target/fuzz-failures"),
        progress_every: 100_000,
        time_slack: 1.0,
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        let value = args.get(i + 1).cloned().unwrap_or_default();
        match args[i].as_str() {
            "--execs" => config.execs = value.parse().unwrap_or(config.execs),
            "--seed" => config.seed = value.parse().unwrap_or(config.seed),
            "--seconds" => {
                config.max_time = value.parse().ok().map(Duration::from_secs_f64);
            }
            "--out" => config.save_dir = value.into(),
            // `cargo bench` passes --bench; anything else is ignored.
            _ => {
                i += 1;
                continue;
            }
        }
        i += 2;
    }
    let seeds = ballpass_fuzz::corpus::all();
    eprintln!(
        "{} seeds; seed {}, {} executions",
        seeds.len(),
        config.seed,
        config.execs
    );
    let report = run(&seeds, &config);
    println!("{report}");
    if report.failure_count > 0 {
        std::process::exit(1);
    }
}
