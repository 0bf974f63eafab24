//! The `ballpass` command-line tool: argument parsing and glue only.

use std::io::Write;
use std::process::ExitCode;

use anyhow::Context;
use clap::{Parser, Subcommand};

mod args;
mod cmd;
mod malloc;
mod output;
mod records;
mod text;

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
    /// Feedforward compensation table (force against ball-pass phase) and its predicted benefit.
    Compensate(Box<cmd::compensate::CompensateArgs>),
    /// Signal and stage models of thesis chapter 6, with its formulas corrected (docs/methods.md), as tables.
    Model(cmd::model::ModelArgs),
    /// Ball passages seen by the optical sensor: periods, widths, artefacts, fits.
    Passage(Box<cmd::passage::PassageArgs>),
    /// Simulate a bench recording with the built-in testbed simulator (writes NAME.truth.json beside it).
    Simulate(cmd::simulate::SimulateArgs),
    /// Simulate the thesis' test campaign: velocity sweep and bearing diagnosis, with a manifest.
    SimulateCampaign(cmd::simulate::CampaignArgs),
    /// How far to trust each verdict on a bench: simulate many seeded records and fleets of it and measure false-alarm and detection rates.
    Validate(Box<cmd::validate::ValidateArgs>),
}

/// Exit code after SIGINT/SIGTERM/SIGHUP (128 + SIGINT, as shells report
/// an interrupted command).
const EXIT_INTERRUPTED: u8 = 130;

/// On SIGINT, SIGTERM or SIGHUP: stop writing, remove this run's temporary
/// files and staging folders (a commit in progress is let finish), say so,
/// and exit.
fn install_interrupt_handler() {
    let result = ctrlc::set_handler(|| {
        let n = ballpass::fsutil::interrupt();
        let _ = writeln!(
            std::io::stderr(),
            "interrupted: nothing written{}",
            if n > 0 {
                format!(" ({n} temporary file(s) and folder(s) removed)")
            } else {
                String::new()
            }
        );
        std::process::exit(i32::from(EXIT_INTERRUPTED));
    });
    if let Err(e) = result {
        // Without the handler an interrupt leaves temporary files, which
        // the next run into the same folder removes.
        let _ = writeln!(
            std::io::stderr(),
            "note: cannot catch interrupts ({e}); an interrupted run leaves temporary files"
        );
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // Before any other thread exists (the interrupt handler starts one).
    match cli.command {
        Command::Analyze(_) => malloc::return_freed_memory(),
        _ => malloc::keep_freed_memory(),
    }
    install_interrupt_handler();
    let result = match cli.command {
        Command::Demo(a) => cmd::demo::run(&a),
        Command::Predict(a) => cmd::predict::run(&a),
        Command::Analyze(a) => cmd::analyze::run(&a),
        Command::Sweep(a) => cmd::campaign::run_sweep(&a),
        Command::Diagnose(a) => cmd::campaign::run_diagnose(&a),
        Command::Inspect(a) => cmd::inspect::run(&a),
        Command::Compensate(a) => cmd::compensate::run(&a),
        Command::Model(a) => cmd::model::run(&a),
        Command::Passage(a) => cmd::passage::run(&a),
        Command::Simulate(a) => cmd::simulate::run(&a),
        Command::SimulateCampaign(a) => cmd::simulate::run_campaign(&a),
        Command::Validate(a) => cmd::validate::run(&a),
    };
    let result = result.and_then(|()| {
        std::io::stdout()
            .flush()
            .context("writing to standard output")
    });
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
            let _ = writeln!(std::io::stderr(), "{}", text::line(&msg));
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
