//! The `ballpass` command-line tool: argument parsing and glue only.

use std::io::Write;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod args;
mod cmd;
mod malloc;
mod output;

/// Finds and characterises the periodic disturbances that balls cause in
/// linear ball bearings.
#[derive(Debug, Parser)]
#[command(name = "ballpass", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the whole thesis on built-in simulated data into one report (start here).
    Demo(cmd::demo::DemoArgs),
    /// Predict the ball-pass frequency, period and band of a bearing at a velocity.
    Predict(cmd::predict::PredictArgs),
    /// Correlations, spectra, measured period, phases and harmonics of recordings.
    Analyze(Box<cmd::analyze::AnalyzeArgs>),
    /// Velocity sweep over a campaign: velocity-error trend, tau_c and tau_p against velocity, d_avg.
    Sweep(Box<cmd::campaign::CampaignArgs>),
    /// Bearing diagnosis over a batch: friction spectra, harmonics, sticking events, verdicts.
    Diagnose(Box<cmd::campaign::DiagnoseArgs>),
    /// Show what a recording holds before analysing it: duration, rate,
    /// channels, ranges, clipping, dropouts, load-cell drift.
    Inspect(Box<cmd::inspect::InspectArgs>),
    /// Signal and stage models of thesis chapter 6, with its formulas corrected (docs/methods.md), as tables.
    Model(cmd::model::ModelArgs),
    /// Ball passages seen by the optical sensor: periods, widths, artefacts, fits.
    Passage(cmd::passage::PassageArgs),
    /// Simulate a bench recording with the built-in testbed simulator (writes NAME.truth.json beside it).
    Simulate(cmd::simulate::SimulateArgs),
    /// Simulate the thesis' test campaign: velocity sweep and bearing diagnosis, with a manifest.
    SimulateCampaign(cmd::simulate::CampaignArgs),
}

fn main() -> ExitCode {
    malloc::keep_freed_memory();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(a) => cmd::demo::run(&a),
        Command::Predict(a) => cmd::predict::run(&a),
        Command::Analyze(a) => cmd::analyze::run(&a),
        Command::Sweep(a) => cmd::campaign::run_sweep(&a),
        Command::Diagnose(a) => cmd::campaign::run_diagnose(&a),
        Command::Inspect(a) => cmd::inspect::run(&a),
        Command::Model(a) => cmd::model::run(&a),
        Command::Passage(a) => cmd::passage::run(&a),
        Command::Simulate(a) => cmd::simulate::run(&a),
        Command::SimulateCampaign(a) => cmd::simulate::run_campaign(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            if is_broken_pipe(&err) {
                return ExitCode::SUCCESS;
            }
            let mut msg = format!("error: {err}");
            for cause in err.chain().skip(1) {
                let c = cause.to_string();
                if !msg.contains(&c) {
                    msg.push_str(": ");
                    msg.push_str(&c);
                }
            }
            let _ = writeln!(std::io::stderr(), "{msg}");
            ExitCode::from(1)
        }
    }
}

fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
