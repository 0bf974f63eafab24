//! `ballpass compensate`: a feedforward compensation table from the
//! synchronous average of recordings, and its predicted benefit; with
//! `--applied`, the second round from records taken with a table applied
//! (glue over [`ballpass::model::compensate`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use ballpass::analysis::load_cell::LoadCellCorrection;
use ballpass::analysis::preflight;
use ballpass::analysis::AnalyzeSettings;
use ballpass::model::compensate::second::{second_from_records, AppliedTable, SecondCompensation};
use ballpass::model::compensate::{compensate, StageSource};
use ballpass::model::stage::PdLoop;
use clap::Args;

use crate::args::LoadArgs;
use crate::records::{self, CheckArgs};
use crate::{output, text};

/// Arguments of `ballpass compensate`.
#[derive(Debug, Args)]
pub struct CompensateArgs {
    /// Recording files: CSV/TSV, MATLAB .mat (v5/v7/v7.3), NI .tdms or MDF
    /// .mf4, at one velocity (repeats are averaged); they need friction,
    /// encoder position and the optical sensor.
    #[arg(required = true, value_name = "REC")]
    recs: Vec<PathBuf>,
    #[command(flatten)]
    load: LoadArgs,
    /// Output folder for compensation.json, compensation_phase.csv and
    /// (when the passages lock to the rail) compensation_rail.csv.
    #[arg(long, short = 'o', value_name = "DIR")]
    out: PathBuf,
    /// Moving mass m, kg: with --kkp and --kkd, the stage used when it
    /// cannot be identified from the records.
    #[arg(long, value_name = "KG", requires_all = ["kkp", "kkd"])]
    mass: Option<f64>,
    /// Loop stiffness K·K_P, N/m (with --mass).
    #[arg(long, value_name = "N/M", requires = "mass")]
    kkp: Option<f64>,
    /// Loop damping K·K_D, N·s/m (with --mass).
    #[arg(long, value_name = "N·S/M", requires = "mass")]
    kkd: Option<f64>,
    /// The quartz load cell's discharge time constant in seconds, undone
    /// before the analysis; `auto` (default) takes the τ with which the
    /// replay through the stage gives the records' velocity error best
    /// (compensation.json `load_cell` says which), `off` leaves the
    /// friction as recorded (a DC-coupled sensor). Near stall the records
    /// do not decide τ: a known τ makes the table better there
    /// (docs/methods.md §14).
    #[arg(long, value_name = "S|auto|off", value_parser = super::analyze::parse_load_cell)]
    load_cell_tau: Option<LoadCellCorrection>,
    /// A second round: REC... were taken with the table of this
    /// compensation.json applied on the machine; the table's fundamental is
    /// corrected from what they still show (the stage and the std before any
    /// table are taken from the file).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["mass", "kkp", "kkd"])]
    applied: Option<PathBuf>,
    /// Print compensation.json to stdout instead of the summary.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    check: CheckArgs,
}

/// Runs `ballpass compensate`.
pub fn run(a: &CompensateArgs) -> Result<()> {
    let mut opts = a.load.options()?;
    if a.load.min_periods.is_none() {
        opts.min_periods = opts.min_periods.min(2.0);
    }
    let geometry = opts.geometry.expect("options() resolves the bearing");
    let gains = match (a.mass, a.kkp, a.kkd) {
        (Some(m), Some(kp), Some(kd)) => Some(PdLoop::from_products(m, kp, kd)?),
        (None, None, None) => None,
        _ => bail!("give --mass, --kkp and --kkd together"),
    };
    let applied = a.applied.as_deref().map(AppliedTable::read).transpose()?;
    let out = output::open_dir(&a.out, "compensate")?;
    let recs = records::load_all(&a.recs, &opts, &a.load.window)?;
    let stated = super::analyze::stated_velocity(a.load.velocity, &recs)?;
    let checked = preflight::check(recs, stated, &geometry, &a.check.preflight())?;
    let mut settings = AnalyzeSettings::default();
    if let Some(t) = a.load_cell_tau {
        settings.load_cell = t;
    }
    let prediction = geometry.predict(checked.velocity_mm_s, settings.harmonics)?;
    if let Some(applied) = applied {
        let second = second_from_records(&checked.recordings, &prediction, &settings, &applied)?;
        return finish_second(a, out, &checked.warnings, &second);
    }
    let comp = compensate(&checked.recordings, &prediction, &settings, gains)?;
    {
        let mut err = std::io::stderr().lock();
        for w in checked.warnings.iter().chain(&comp.warnings) {
            writeln!(err, "warning: {}", text::line(w))?;
        }
    }
    comp.write(out.path())?;
    let dir = output::commit(out)?;
    let mut so = output::stdout();
    if a.json {
        serde_json::to_writer_pretty(&mut so, &comp)?;
        writeln!(so)?;
    } else {
        let p = &comp.prediction;
        let range = |v: &[f64]| {
            v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - v.iter().copied().fold(f64::INFINITY, f64::min)
        };
        match &comp.table_refused {
            Some(why) => writeln!(
                so,
                "table: none given (the force written is all zeros): {}",
                text::line(why)
            )?,
            None => writeln!(
                so,
                "table: {} bins per ball-pass period ({:.4} s, {} periods averaged), {:.4} N peak to peak",
                comp.bins,
                comp.period_s,
                comp.periods_used,
                range(&comp.force_n)
            )?,
        }
        writeln!(so, "phase 0: {}", comp.phase_reference)?;
        writeln!(so, "load cell: {}", text::line(&comp.load_cell.note))?;
        writeln!(so, "table from: {}", comp.table_text)?;
        writeln!(so, "rail: {}", comp.rail_note)?;
        writeln!(
            so,
            "stage: {}",
            match comp.stage_source {
                StageSource::Identified => "identified from the records",
                StageSource::GivenGains => "the gains given (not identified from the records)",
            }
        )?;
        writeln!(
            so,
            "predicted: f_c component {:.2} -> {:.2} µm/s, velocity-error std (low-passed) {:.1} -> {:.1} µm/s",
            p.f_c_before_um_s, p.f_c_after_um_s, p.std_before_um_s, p.std_after_um_s
        )?;
        if let (Some(lo), Some(hi)) = (p.f_c_after_low_um_s, p.f_c_after_high_um_s) {
            writeln!(
                so,
                "f_c component after: 80 % of simulated tables left {lo:.2}-{hi:.2} µm/s at this \
                 replay error ({:.2} µm/s)",
                p.f_c_model_error_um_s
            )?;
        }
        writeln!(so, "wrote {}", text::path(&dir))?;
    }
    so.flush()?;
    Ok(())
}

/// Writes and prints a second round (`--applied`).
fn finish_second(
    a: &CompensateArgs,
    out: ballpass::outdir::OutputDir,
    checks: &[String],
    second: &SecondCompensation,
) -> Result<()> {
    {
        let mut err = std::io::stderr().lock();
        for w in checks.iter().chain(&second.warnings) {
            writeln!(err, "warning: {}", text::line(w))?;
        }
    }
    second.write(out.path())?;
    let dir = output::commit(out)?;
    let mut so = output::stdout();
    if a.json {
        serde_json::to_writer_pretty(&mut so, second)?;
        writeln!(so)?;
    } else {
        let r = &second.round;
        writeln!(
            so,
            "second round: {} bins per ball-pass period ({:.4} s, {} periods averaged), \
             fundamental changed by {:.4} N",
            second.bins, second.period_s, second.periods_used, r.change_n
        )?;
        writeln!(
            so,
            "applied table: {}",
            text::path(Path::new(&second.applied_from))
        )?;
        writeln!(
            so,
            "with the applied table: f_c component {:.2} µm/s, velocity-error std (low-passed) {:.1} µm/s",
            r.f_c_with_table_um_s, r.std_with_table_um_s
        )?;
        writeln!(
            so,
            "predicted after this round: f_c component {:.2} µm/s (80 % of simulated second rounds \
             {:.2}-{:.2}), std {:.1} µm/s",
            r.f_c_after_um_s[1], r.f_c_after_um_s[0], r.f_c_after_um_s[2], r.std_after_um_s
        )?;
        writeln!(so, "wrote {}", text::path(&dir))?;
    }
    so.flush()?;
    Ok(())
}
