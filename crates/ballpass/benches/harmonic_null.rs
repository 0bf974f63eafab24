//! Calibration of the friction harmonic test under no ripple: which part of
//! the p-value makes it conservative (a measurement, not a product path).
//!
//! ```text
//! cargo bench -p ballpass --bench harmonic_null -- FIRST_SEED N DURATION_S [--ripple] [--all] [--dump FILE]
//! ```
//!
//! The variants are the session-21 candidates for the floor-misfit term;
//! `--all` gives the session-20 list instead (each part of the test
//! switched off in turn). `--dump FILE` writes every p-value as CSV
//! (`seed,variant,test,p`; `test` counts the record's tests that have one).
//!
//! `--ripple` keeps the domain's friction ripple (0–10 % of the Coulomb
//! level) instead of switching it off: the fractions at small `p` and `u`
//! are then each variant's detection of a real ripple, not its false-alarm
//! rate.
//!
//! Seeds `FIRST_SEED..FIRST_SEED + N`, each a bench of `Domain::default()`
//! with the ripple off and the duration fixed, drawn, simulated and
//! analysed as the periodicity part of `ballpass validate` does
//! (`validate/suite/null_record.rs`). For every friction harmonic test at
//! the predicted `f_c` it recomputes the p-value with one part of the test
//! switched off at a time ([`ballpass::analysis::harmonics::Variant`]) and
//! prints, per variant, the fraction of p-values at most 0.01, 0.05, 0.1,
//! 0.5 with exact 95 % intervals, the same for the record statistic
//! `u = 1 − (1 − p_min)^m` over the record's predicted tests, and
//! diagnostics of the floor fit. The default variant is checked equal, bit
//! for bit, to the analysis's own predicted p-values. Cores:
//! `RAYON_NUM_THREADS`.

use ballpass::analysis::harmonics::{predicted_tests_with, Variant, VariantDiag};
use ballpass::analysis::{analyze, AnalyzeSettings, Signal};
use ballpass::sim::simulate;
use ballpass::stats::binomial_interval;
use ballpass::validate::bench::Range;
use ballpass::validate::Domain;
use rayon::prelude::*;

const LEVELS: [f64; 4] = [0.01, 0.05, 0.1, 0.5];

/// The session-21 candidates for the misfit term (the default list).
fn candidates() -> Vec<(&'static str, Variant)> {
    let v = Variant::default;
    vec![
        ("today", v()),
        (
            "a: no misfit",
            Variant {
                no_misfit: true,
                ..v()
            },
        ),
        (
            "a4: misfit gated 0.99",
            Variant {
                misfit_gate: Some(0.99),
                ..v()
            },
        ),
        (
            "f1: pooled misfit",
            Variant {
                misfit_pooled: true,
                ..v()
            },
        ),
        (
            "h1: pooled predictive",
            Variant {
                misfit_pooled: true,
                misfit_predictive: Some(1.0),
                ..v()
            },
        ),
        (
            "p1: pooled gate .99",
            Variant {
                misfit_pooled_gate: Some(0.99),
                ..v()
            },
        ),
        (
            "p2: pooled gate .95",
            Variant {
                misfit_pooled_gate: Some(0.95),
                ..v()
            },
        ),
        (
            "p3: pooled gate .99, D/2",
            Variant {
                misfit_pooled_gate: Some(0.99),
                pooled_dof_scale: Some(0.5),
                ..v()
            },
        ),
        (
            "p4: pooled gate .9",
            Variant {
                misfit_pooled_gate: Some(0.9),
                ..v()
            },
        ),
        (
            "p5: p1, pooled amount",
            Variant {
                misfit_pooled_gate: Some(0.99),
                misfit_pooled: true,
                ..v()
            },
        ),
        (
            "u1: a4 or p2",
            Variant {
                misfit_gate: Some(0.99),
                misfit_pooled_gate: Some(0.95),
                gate_union: true,
                ..v()
            },
        ),
        (
            "u2: a4 or p1",
            Variant {
                misfit_gate: Some(0.99),
                misfit_pooled_gate: Some(0.99),
                gate_union: true,
                ..v()
            },
        ),
        (
            "u3: a3 or p2",
            Variant {
                misfit_gate: Some(0.95),
                misfit_pooled_gate: Some(0.95),
                gate_union: true,
                ..v()
            },
        ),
        (
            "u4: a4 or p4",
            Variant {
                misfit_gate: Some(0.99),
                misfit_pooled_gate: Some(0.9),
                gate_union: true,
                ..v()
            },
        ),
        (
            "s1: soft 1 s.e.",
            Variant {
                misfit_soft: Some(1.0),
                ..v()
            },
        ),
        (
            "s2: soft 2 s.e.",
            Variant {
                misfit_soft: Some(2.0),
                ..v()
            },
        ),
        (
            "s3: soft 1 s.e. pooled",
            Variant {
                misfit_soft: Some(1.0),
                misfit_pooled: true,
                ..v()
            },
        ),
        (
            "s4: soft 0.5 s.e.",
            Variant {
                misfit_soft: Some(0.5),
                ..v()
            },
        ),
        (
            "g1: floor guard 1",
            Variant {
                floor_guard: Some(1),
                ..v()
            },
        ),
        (
            "g1n: floor guard 1, no misfit",
            Variant {
                floor_guard: Some(1),
                no_misfit: true,
                ..v()
            },
        ),
    ]
}

/// Every part of the test switched off at a time (session 20; `--all`).
fn variants() -> Vec<(&'static str, Variant)> {
    let v = Variant::default;
    vec![
        ("today", v()),
        (
            "a: no misfit",
            Variant {
                no_misfit: true,
                ..v()
            },
        ),
        (
            "a2: misfit x leverage only",
            Variant {
                misfit_leverage_only: true,
                ..v()
            },
        ),
        (
            "a3: misfit gated 0.95",
            Variant {
                misfit_gate: Some(0.95),
                ..v()
            },
        ),
        (
            "a4: misfit gated 0.99",
            Variant {
                misfit_gate: Some(0.99),
                ..v()
            },
        ),
        (
            "b1: centre bin only",
            Variant {
                centre_bin_only: true,
                ..v()
            },
        ),
        (
            "b2: max of 3, tail n_b=2",
            Variant {
                n_b_tail: Some(2),
                ..v()
            },
        ),
        (
            "b3: max of 3, tail n_b=1",
            Variant {
                n_b_tail: Some(1),
                ..v()
            },
        ),
        (
            "c: no inflation",
            Variant {
                no_inflation: true,
                ..v()
            },
        ),
        (
            "d: floor exact (var 0)",
            Variant {
                exact_floor: true,
                ..v()
            },
        ),
        (
            "e1: degree 1",
            Variant {
                degree: Some(1),
                ..v()
            },
        ),
        (
            "e2: degree 2",
            Variant {
                degree: Some(2),
                ..v()
            },
        ),
        (
            "a+c",
            Variant {
                no_misfit: true,
                no_inflation: true,
                ..v()
            },
        ),
        (
            "a2+c",
            Variant {
                misfit_leverage_only: true,
                no_inflation: true,
                ..v()
            },
        ),
        (
            "a4+c",
            Variant {
                misfit_gate: Some(0.99),
                no_inflation: true,
                ..v()
            },
        ),
        (
            "a+b2",
            Variant {
                no_misfit: true,
                n_b_tail: Some(2),
                ..v()
            },
        ),
    ]
}

/// One record: per variant, its predicted tests' p-values; and today's
/// diagnostics.
struct Rec {
    seed: u64,
    p: Vec<Vec<f64>>,
    diag: Vec<VariantDiag>,
}

fn record(d: &Domain, seed: u64, vs: &[(&str, Variant)]) -> Option<Rec> {
    let b = d.draw(seed);
    let s = b.settings(&b.bearing(0, false), seed);
    let sim = simulate(&s).ok()?;
    let pred = b.geometry.predict(b.velocity_mm_s, 5).ok()?;
    if s.duration_s < 2.0 * pred.tau_c_s {
        return None;
    }
    let settings = AnalyzeSettings::default();
    let a = analyze(std::slice::from_ref(&sim.recording), &pred, &settings).ok()?;
    let product: Vec<Option<f64>> = a
        .harmonics
        .iter()
        .filter(|r| r.signal == Signal::Friction)
        .map(|r| r.predicted.as_ref().and_then(|v| v.p_value))
        .collect();
    let mut p = Vec::new();
    let mut diag = Vec::new();
    for (i, (_, v)) in vs.iter().enumerate() {
        let rows = predicted_tests_with(
            &a.spectra_hires,
            Signal::Friction,
            pred.f_c_hz,
            &settings,
            *v,
        );
        if i == 0 {
            let mine: Vec<Option<f64>> = rows.iter().map(|r| r.1.p_value).collect();
            let theirs: Vec<Option<f64>> =
                product.iter().copied().filter(Option::is_some).collect();
            let mine_some: Vec<Option<f64>> =
                mine.iter().copied().filter(Option::is_some).collect();
            assert_eq!(mine_some, theirs, "seed {seed}: default variant differs");
            diag = rows.iter().filter_map(|r| r.2).collect();
        }
        p.push(rows.iter().filter_map(|r| r.1.p_value).collect());
    }
    Some(Rec { seed, p, diag })
}

fn frac(k: usize, n: usize) -> String {
    let [lo, hi] = binomial_interval(k, n, 0.95);
    format!(
        "{:5.1} % [{:4.1}, {:4.1}]",
        100.0 * k as f64 / n.max(1) as f64,
        100.0 * lo,
        100.0 * hi
    )
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let num = |i: usize| args.get(i).and_then(|a| a.parse::<f64>().ok());
    let (Some(first), Some(n), Some(duration)) = (num(0), num(1), num(2)) else {
        eprintln!("usage: harmonic_null FIRST_SEED N DURATION_S [--ripple] [--all] [--dump FILE]");
        std::process::exit(2);
    };
    let ripple = args.iter().any(|a| a == "--ripple");
    let base = Domain::default();
    let d = Domain {
        duration_s: Range::fixed(duration),
        ripple_fraction: if ripple {
            base.ripple_fraction
        } else {
            Range::fixed(0.0)
        },
        ..base
    };
    let vs = if args.iter().any(|a| a == "--all") {
        variants()
    } else {
        candidates()
    };
    let recs: Vec<Rec> = (0..n as u64)
        .into_par_iter()
        .filter_map(|k| record(&d, first as u64 + k, &vs))
        .collect();
    println!(
        "seeds {}..{} at {duration} s{}: {} records analysed",
        first as u64,
        first as u64 + n as u64,
        if ripple {
            ", with the domain's ripple"
        } else {
            ", no ripple"
        },
        recs.len()
    );
    println!(
        "{:<26} {:>6}  {:>24} {:>24} {:>24} {:>24}",
        "variant (single tests)", "n", "p<=0.01", "p<=0.05", "p<=0.1", "p<=0.5"
    );
    for (i, (name, _)) in vs.iter().enumerate() {
        let all: Vec<f64> = recs.iter().flat_map(|r| r.p[i].iter().copied()).collect();
        let cells: Vec<String> = LEVELS
            .iter()
            .map(|&l| frac(all.iter().filter(|&&p| p <= l).count(), all.len()))
            .collect();
        println!("{:<26} {:>6}  {}", name, all.len(), cells.join(" "));
    }
    println!(
        "{:<26} {:>6}  {:>24} {:>24} {:>24} {:>24}",
        "variant (record u)", "n", "u<=0.01", "u<=0.05", "u<=0.1", "u<=0.5"
    );
    for (i, (name, _)) in vs.iter().enumerate() {
        let u: Vec<f64> = recs
            .iter()
            .filter(|r| !r.p[i].is_empty())
            .map(|r| {
                let m = r.p[i].len() as i32;
                let pmin = r.p[i].iter().copied().fold(1.0, f64::min);
                1.0 - (1.0 - pmin).powi(m)
            })
            .collect();
        let cells: Vec<String> = LEVELS
            .iter()
            .map(|&l| frac(u.iter().filter(|&&p| p <= l).count(), u.len()))
            .collect();
        println!("{:<26} {:>6}  {}", name, u.len(), cells.join(" "));
    }
    // Every p-value, for other statistics of the same records.
    if let Some(path) = args
        .iter()
        .position(|a| a == "--dump")
        .and_then(|i| args.get(i + 1))
    {
        let mut out = String::from("seed,variant,test,p\n");
        for r in &recs {
            for (i, (name, _)) in vs.iter().enumerate() {
                for (k, p) in r.p[i].iter().enumerate() {
                    out.push_str(&format!("{},\"{}\",{},{:e}\n", r.seed, name, k + 1, p));
                }
            }
        }
        // Written beside and renamed, so an interrupted run leaves no
        // half-written file.
        if let Err(e) = ballpass::fsutil::write_atomic(std::path::Path::new(path), out.as_bytes()) {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
    // Diagnostics of today's floor fits.
    let diag: Vec<&VariantDiag> = recs.iter().flat_map(|r| r.diag.iter()).collect();
    let nd = diag.len().max(1) as f64;
    let mean = |f: &dyn Fn(&VariantDiag) -> f64| diag.iter().map(|d| f(d)).sum::<f64>() / nd;
    let med = |f: &dyn Fn(&VariantDiag) -> f64| {
        let mut v: Vec<f64> = diag.iter().map(|d| f(d)).collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    println!(
        "diagnostics over {} tests: floor bins mean {:.1} median {:.0}; degree 2 share {:.2}; \
         nu mean {:.1} median {:.1}; s2/psi' mean {:.3} median {:.3}; misfit > 0 share {:.2}, \
         mean misfit {:.4}; psi'(nu/2) mean {:.4}; leverage mean {:.3}; inflation {:.3}; \
         var mean {:.4} median {:.4}",
        diag.len(),
        mean(&|d| d.floor_bins as f64),
        med(&|d| d.floor_bins as f64),
        mean(&|d| (d.degree == 2) as u8 as f64),
        mean(&|d| d.nu),
        med(&|d| d.nu),
        mean(&|d| d.s2_over_vchi),
        med(&|d| d.s2_over_vchi),
        mean(&|d| (d.misfit > 0.0) as u8 as f64),
        mean(&|d| d.misfit),
        mean(&|d| ballpass::stats::trigamma(0.5 * d.nu)),
        mean(&|d| d.leverage),
        mean(&|d| d.inflation),
        mean(&|d| d.var),
        med(&|d| d.var),
    );
}
