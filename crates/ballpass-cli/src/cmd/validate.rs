//! `ballpass validate`: how far to trust each verdict on a bench, measured
//! by simulating many seeded records and fleets of it.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};
use ballpass::analysis::preflight::{self, PreflightSettings};
use ballpass::validate::{estimate_domain, Domain, SuiteSettings};

use crate::args::LoadArgs;
use clap::Args;

/// Arguments of `ballpass validate`.
#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// The bench as a JSON object of domain keys (each a range
    /// `{"lo": .., "hi": .., "log": false}`, or a list for `fs_hz` and the
    /// shapes); keys left out take the full randomized grid's ranges. See
    /// docs/verdicts.md.
    #[arg(long, value_name = "FILE")]
    domain: Option<PathBuf>,
    /// The full grid: 100 fleets, 200 records per part, record lengths
    /// 10 s, 30 s, 2 min and 10 min (about an hour on two cores). Without
    /// it: 20 fleets, 40 records, 10 s and 30 s.
    #[arg(long)]
    grid: bool,
    /// Fleets to run (overrides the count of --grid).
    #[arg(long, value_name = "N")]
    fleets: Option<usize>,
    /// Records per part (overrides the count of --grid).
    #[arg(long, value_name = "N")]
    records: Option<usize>,
    /// Record lengths of the periodicity part, s, comma-separated.
    #[arg(long, value_name = "S,S,..", value_delimiter = ',')]
    durations: Option<Vec<f64>>,
    /// First seed of the benches.
    #[arg(long, default_value_t = 1_000_000, value_name = "SEED")]
    seed: u64,
    /// Also write the full report as JSON to this file.
    #[arg(long, short = 'o', value_name = "FILE")]
    out: Option<PathBuf>,
    /// Recordings of your bench: the domain is narrowed to what they show
    /// (rate, length, velocity, the bearing's geometry, the load cell's
    /// discharge, the stage, the optical pulse width; the rest keeps the
    /// grid's ranges or --domain's). Read with the input flags below.
    #[arg(long = "from", value_name = "REC", num_args = 1..)]
    from: Vec<PathBuf>,
    /// Write the domain validated on as JSON (edit it and pass it back with
    /// --domain).
    #[arg(long, value_name = "FILE")]
    write_domain: Option<PathBuf>,
    #[command(flatten)]
    load: LoadArgs,
}

/// The domain estimated from `--from`'s recordings on top of `base`, and
/// the notes saying what came from where.
fn from_recordings(a: &ValidateArgs, base: &Domain) -> Result<(Domain, Vec<String>)> {
    let opts = a.load.options()?;
    let geometry = opts.geometry.expect("options() resolves the bearing");
    let recs = crate::records::load_all(&a.from, &opts, &a.load.window)?;
    let mut with_speed = Vec::with_capacity(recs.len());
    for rec in recs {
        let name = rec.source_name();
        let stated = a.load.velocity.or(rec.meta.velocity_mm_s);
        let checked = preflight::check(vec![rec], stated, &geometry, &PreflightSettings::default())
            .with_context(|| format!("{name}: cannot take the bench from it"))?;
        let v = checked.velocity_mm_s;
        with_speed.extend(checked.recordings.into_iter().map(|r| (r, v)));
    }
    let est = estimate_domain(&with_speed, &geometry, base)
        .with_context(|| "estimating the bench from the recordings".to_string())?;
    Ok((est.domain, est.notes))
}

/// Runs `ballpass validate`.
pub fn run(a: &ValidateArgs) -> Result<()> {
    let domain = match &a.domain {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("{}: cannot read the domain file", p.display()))?;
            serde_json::from_str::<Domain>(&text).with_context(|| {
                format!(
                    "{}: not a domain (a JSON object of domain keys, see docs/verdicts.md)",
                    p.display()
                )
            })?
        }
        None => Domain::default(),
    };
    domain
        .validate()
        .with_context(|| "the validation domain".to_string())?;
    let (domain, notes) = if a.from.is_empty() {
        (domain, Vec::new())
    } else {
        from_recordings(a, &domain)?
    };
    if let Some(p) = &a.write_domain {
        ballpass::fsutil::write_json_pretty(p, &domain)?;
    }
    let mut s = if a.grid {
        SuiteSettings::default()
    } else {
        SuiteSettings {
            fleets: 20,
            records: 40,
            durations_s: vec![10.0, 30.0],
            ..SuiteSettings::default()
        }
    };
    if let Some(n) = a.fleets {
        s.fleets = n;
    }
    if let Some(n) = a.records {
        s.records = n;
    }
    if let Some(d) = &a.durations {
        if d.iter().any(|t| !(t.is_finite() && *t >= 10.0)) {
            anyhow::bail!("--durations: each record length must be at least 10 s, got {d:?}");
        }
        s.durations_s.clone_from(d);
    }
    s.seed = a.seed;
    let total = s.fleets + s.records * (1 + s.durations_s.len());
    let bar = crate::output::progress(total, "benches");
    let done = std::sync::atomic::AtomicUsize::new(0);
    let report = ballpass::validate::run(&domain, &s, &|_, _, _| {
        let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if let Some(b) = &bar {
            b.set_position(d as u64);
        }
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    if let Some(p) = &a.out {
        ballpass::fsutil::write_json_pretty(p, &report)?;
    }
    let mut out = crate::output::stdout();
    if !notes.is_empty() {
        writeln!(out, "bench estimated from {} recording(s):", a.from.len())?;
        for n in &notes {
            writeln!(out, "  {n}")?;
        }
    }
    write!(out, "{}", report.text())?;
    Ok(())
}
