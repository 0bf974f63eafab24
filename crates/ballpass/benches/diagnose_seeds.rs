//! The diagnosis oracle on the simulated thesis batch over many campaign
//! seeds ([`ballpass::validate::thesis_batch`]): for each seed, bearing 4
//! and only bearing 4 must be bad (and ranked first), and the same batch
//! with every bearing good must have nothing bad.
//!
//! ```text
//! cargo bench -p ballpass --bench diagnose_seeds -- [N]
//! ```
//!
//! Seeds 1..=N (default 20) for the batch with bearing 4 sticking, seeds
//! 101..=100+N/5 for the all-good batch. Prints one line per seed and exits
//! with status 1 if any seed fails.

use ballpass::validate::thesis_batch::{batch, outcome};

fn main() {
    let n: u64 = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(20);
    let mut failed = 0;
    for seed in 1..=n {
        let o = match batch(seed, false) {
            Ok(recs) => outcome(&recs),
            Err(e) => {
                println!("seed {seed}: error {e}");
                failed += 1;
                continue;
            }
        };
        let ok = o.finds_bearing_4();
        failed += usize::from(!ok);
        println!(
            "seed {seed:>4}  first {}  bad {:?}  {}",
            o.first,
            o.bad,
            if ok { "ok" } else { "FAIL" }
        );
    }
    for seed in 101..=100 + (n / 5).max(1) {
        let bad = match batch(seed, true) {
            Ok(recs) => outcome(&recs).bad,
            Err(e) => {
                println!("all-good seed {seed}: error {e}");
                failed += 1;
                continue;
            }
        };
        failed += usize::from(!bad.is_empty());
        println!(
            "all-good seed {seed:>4}  bad {bad:?}  {}",
            if bad.is_empty() { "ok" } else { "FAIL" }
        );
    }
    println!("{failed} failed");
    if failed > 0 {
        std::process::exit(1);
    }
}
