//! Ripple-free records of one length, one line per record: the periodicity
//! part of `ballpass validate` (no lag or stage records), with each
//! record's friction periodicity claim and its statistic and every
//! friction–optical coherence row, so the false alarms can be counted per
//! record as well as per row (rows of one record are not independent).
//!
//! ```text
//! cargo bench -p ballpass --bench coherence_long -- FIRST_SEED N DURATION_S [--domain FILE.json] [--json OUT.json]
//! ```
//!
//! Seeds `FIRST_SEED..FIRST_SEED + N`, each a bench of the domain (default:
//! `ballpass validate`'s) with the ripple off and the duration fixed;
//! above 300 s the suite takes the domain's lowest rate. Cores:
//! `RAYON_NUM_THREADS`. Prints one line per record (seed, rate, periods,
//! high-resolution segments, load-cell τ simulated and undone, the claim,
//! `p_min · m`, then each friction–optical row as `k:bins:coherence/level`
//! with `*` where significant) and the totals with exact 95 % intervals.

use ballpass::validate::suite::{periodicity_score, NullRecord};
use ballpass::validate::Domain;

fn line(r: &NullRecord) -> String {
    let tau = |t: Option<f64>| t.map_or("-".to_string(), |t| format!("{t:.2}"));
    let rows: Vec<String> = r
        .rows
        .iter()
        .filter(|x| x.pair == "friction__optical")
        .map(|x| {
            format!(
                "{}:{:.3}:{:.5}/{:.5}{}",
                x.k,
                x.bins,
                x.coherence,
                x.threshold,
                if x.significant { "*" } else { "" }
            )
        })
        .collect();
    format!(
        "{} fs {} T {} periods {:.0} nperseg {} K {} tau {} undone {} claimed {} p_min*m {} | {}",
        r.seed,
        r.fs_hz,
        r.duration_s,
        r.periods,
        r.hires_nperseg,
        r.hires_segments,
        tau(r.load_cell_tau_s),
        tau(r.load_cell_restored_tau_s),
        r.friction_claimed,
        r.friction_p_min.map_or("-".into(), |p| format!(
            "{:.4}",
            p * r.friction_tests as f64
        )),
        rows.join(" ")
    )
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let num = |i: usize| args.get(i).and_then(|a| a.parse::<f64>().ok());
    let (Some(first), Some(n), Some(duration)) = (num(0), num(1), num(2)) else {
        eprintln!(
            "usage: coherence_long FIRST_SEED N DURATION_S [--domain FILE.json] [--json OUT.json]"
        );
        std::process::exit(2);
    };
    let opt = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
    };
    let domain: Domain = match opt("--domain") {
        Some(p) => {
            let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{p}: {e}"));
            serde_json::from_str(&text).unwrap_or_else(|e| panic!("{p}: {e}"))
        }
        None => Domain::default(),
    };
    let progress = |part: &str, done: usize, total: usize| {
        eprintln!("{part}: {done}/{total}");
    };
    let score = periodicity_score(&domain, duration, first as u64, n as usize, &progress);
    for r in &score.records {
        println!("{}", line(r));
    }
    for f in &score.failed {
        println!("failed: {f}");
    }
    println!(
        "records {} (too short {}, failed {})",
        score.records.len(),
        score.too_short,
        score.failed.len()
    );
    println!(
        "friction periodicity claimed {} (nominal {:.0} %, at most {} expected)",
        score.false_claims,
        100.0 * score.nominal,
        score.allowed
    );
    println!(
        "friction–optical rows significant {} (nominal {:.3} % per row); records with one {}",
        score.coherence_friction_optical,
        100.0 * score.coherence_nominal,
        score.coherence_friction_optical_records
    );
    println!(
        "friction–velocity error rows significant {}",
        score.coherence_friction_velocity_error
    );
    if let Some(p) = opt("--json") {
        let text = serde_json::to_string_pretty(&score).expect("serialise");
        std::fs::write(p, text).unwrap_or_else(|e| panic!("{p}: {e}"));
    }
}
