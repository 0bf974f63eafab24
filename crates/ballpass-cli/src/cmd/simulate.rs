//! `ballpass simulate` and `ballpass simulate-campaign`: recordings from the
//! built-in testbed simulator, each with its truth file beside it.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use ballpass::fsutil::{commit_all, Pending};
use ballpass::model::compensate::second::AppliedTable;
use ballpass::recording::{write_csv, write_mat};
use ballpass::sim::{self, campaign, Condition, SimSettings, Simulation, Start};
use clap::{Args, ValueEnum};
use rayon::prelude::*;

use crate::{output, text};

/// Bearing condition on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ConditionArg {
    /// Small periodic friction content.
    Good,
    /// Sporadic friction spikes at ball passages.
    Sticking,
}

impl From<ConditionArg> for Condition {
    fn from(c: ConditionArg) -> Self {
        match c {
            ConditionArg::Good => Condition::Good,
            ConditionArg::Sticking => Condition::Sticking,
        }
    }
}

/// How the recording starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StartArg {
    /// Stage already tracking the velocity.
    Settled,
    /// Stage accelerates from rest; recording triggers after a distance.
    FromRest,
}

/// Simulator options shared by both subcommands. Each flag, when given,
/// overrides the settings file (if any), which overrides the defaults.
#[derive(Debug, Clone, Args)]
pub struct SimFlags {
    /// Settings file (JSON): the simulator's settings, as in the `settings` of
    /// a truth file (or a whole truth file, whose settings are reused). Flags
    /// given as well override it.
    #[arg(long, value_name = "FILE")]
    settings: Option<PathBuf>,
    /// Recorded duration, s [default: 30].
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    /// Sampling rate, Hz [default: 1000].
    #[arg(long, value_name = "HZ")]
    fs: Option<f64>,
    /// Internal steps per sample [default: 20].
    #[arg(long, value_name = "N")]
    oversample: Option<u32>,
    /// Start settled or from rest [default: settled].
    #[arg(long, value_enum)]
    start: Option<StartArg>,
    /// Acceleration from rest, mm/s² [default: 100].
    #[arg(long, value_name = "MM_S2")]
    acceleration: Option<f64>,
    /// Stage travel that triggers the recording from rest, mm [default: V²/2a + V t_settle].
    #[arg(long, value_name = "MM")]
    trigger_distance: Option<f64>,
    /// Coulomb friction level, N [default: 3].
    #[arg(long, value_name = "N")]
    coulomb: Option<f64>,
    /// Load-cell discharge time constant, s [default: 10].
    #[arg(long, value_name = "S")]
    load_cell_tau: Option<f64>,
    /// AC-couple the photodetector (thesis Fig. 38).
    #[arg(long)]
    ac_coupling: bool,
    /// AC-coupling time constant, s [default: 1].
    #[arg(long, value_name = "S")]
    ac_tau: Option<f64>,
    /// Add the coherent-source interference drift to the photodetector (thesis Fig. 32).
    #[arg(long)]
    interference_drift: bool,
    /// Period of the interference drift, s [default: 5].
    #[arg(long, value_name = "S")]
    interference_period: Option<f64>,
    /// A multi-speed run instead of one velocity: the lab's benchmark run,
    /// plateaus of 3.5 s at 42, 83 and 125 mm/s, each forward then
    /// backward, ramps at 400 mm/s² (the truth lists the plateaus; any
    /// profile can be given in the --settings file's `profile`).
    #[arg(long)]
    multi_speed: bool,
    /// Apply a compensation table as a feedforward force, keyed on the
    /// optical passages: the compensation.json of `ballpass compensate`
    /// (first or second round). The closed loop a machine would run with it.
    #[arg(long, value_name = "FILE")]
    feedforward: Option<PathBuf>,
}

impl SimFlags {
    /// The base settings: the file if given, else the defaults; then the flags.
    fn settings(&self) -> Result<SimSettings> {
        let mut s = match &self.settings {
            Some(p) => read_settings(p)?,
            None => SimSettings::default(),
        };
        if let Some(v) = self.duration {
            s.duration_s = v;
        }
        if let Some(v) = self.fs {
            s.fs_hz = v;
        }
        if let Some(v) = self.oversample {
            s.oversample = v;
        }
        if let Some(v) = self.start {
            s.start = match v {
                StartArg::Settled => Start::Settled,
                StartArg::FromRest => Start::FromRest,
            };
        }
        if let Some(v) = self.acceleration {
            s.motion.acceleration_mm_s2 = v;
        }
        if self.trigger_distance.is_some() {
            s.motion.trigger_distance_mm = self.trigger_distance;
        }
        if let Some(v) = self.coulomb {
            s.friction.coulomb_n = v;
        }
        if let Some(v) = self.load_cell_tau {
            s.load_cell.time_constant_s = Some(v);
        }
        if self.ac_coupling {
            s.optical.ac_coupling = true;
        }
        if let Some(v) = self.ac_tau {
            s.optical.ac_time_constant_s = v;
        }
        if self.interference_drift {
            s.optical.interference_drift = true;
        }
        if let Some(v) = self.interference_period {
            s.optical.interference_period_s = v;
        }
        if self.multi_speed {
            s.profile = Some(sim::SpeedProfile::lab_run());
        }
        if let Some(p) = &self.feedforward {
            let ff = AppliedTable::read(p)?.feedforward();
            ff.validate()
                .with_context(|| format!("{}: the table as a feedforward", p.display()))?;
            s.feedforward = Some(ff);
        }
        Ok(s)
    }
}

fn read_settings(path: &Path) -> Result<SimSettings> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read settings file {}", path.display()))?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not valid JSON", path.display()))?;
    let is_truth = value.get("schema").and_then(|s| s.as_str()) == Some(sim::TRUTH_SCHEMA);
    let obj = if is_truth {
        value
            .get("settings")
            .cloned()
            .with_context(|| format!("{}: truth file without settings", path.display()))?
    } else {
        value
    };
    serde_json::from_value(obj)
        .with_context(|| format!("{}: not simulator settings", path.display()))
}

/// Arguments of `ballpass simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Tracking velocity, mm/s [default with --settings: the file's; not
    /// needed with --multi-speed].
    #[arg(
        long,
        short = 'v',
        required_unless_present_any = ["settings", "multi_speed"],
        allow_hyphen_values = true,
        value_name = "MM/S"
    )]
    velocity: Option<f64>,
    /// Bearing from the catalog [default: sr25w].
    #[arg(long)]
    bearing: Option<String>,
    /// Bearing condition [default: good].
    #[arg(long, value_enum)]
    condition: Option<ConditionArg>,
    /// Random seed; the same seed gives the same bytes [default: 0].
    #[arg(long)]
    seed: Option<u64>,
    /// Output recording (`.csv` or `.mat`); the truth goes beside it as
    /// `NAME.truth.json`.
    #[arg(
        long = "out",
        short = 'o',
        visible_alias = "output",
        value_name = "FILE"
    )]
    output: PathBuf,
    #[command(flatten)]
    flags: SimFlags,
}

/// Runs `ballpass simulate`.
pub fn run(a: &SimulateArgs) -> Result<()> {
    let mut s = a.flags.settings()?;
    if let Some(key) = &a.bearing {
        let b = SimSettings::for_bearing(key, s.velocity_mm_s)?;
        s.bearing = b.bearing;
        s.geometry = b.geometry;
    }
    if let Some(v) = a.velocity {
        s.velocity_mm_s = v;
    }
    if let Some(c) = a.condition {
        s.condition = c.into();
    }
    if let Some(seed) = a.seed {
        s.seed = seed;
    }
    check_output(&a.output)?;
    let sim = sim::simulate(&s)?;
    let truth_file = sim::truth_path(&a.output);
    // Temporary files of a killed earlier run of these two targets.
    if let (Some(dir), Some(n1), Some(n2)) = (
        a.output.parent(),
        a.output.file_name(),
        truth_file.file_name(),
    ) {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        ballpass::fsutil::remove_stale_temps(dir, Some(&[n1, n2]))?;
    }
    write_pair(&sim, &a.output)?;
    let t = &sim.truth;
    let mut out = output::stdout();
    let speed = if t.plateaus.is_empty() {
        format!("{} mm/s", t.velocity_mm_s)
    } else {
        format!("{} plateaus", t.plateaus.len())
    };
    writeln!(
        out,
        "wrote {} ({} samples at {} Hz, {} bearing, {speed}) and {}",
        text::path(&a.output),
        t.n_samples,
        t.fs_hz,
        t.condition.name(),
        text::path(&truth_file)
    )?;
    writeln!(
        out,
        "f_c = {:.6} Hz, tau_c = {:.5} s, {} optical passages; optical lags friction by {:.3} s ({:.3} tau_c)",
        t.f_c_hz,
        t.tau_c_s,
        t.optical_passage_times_s.len(),
        t.optical_lag_s,
        t.optical_lag_tau_c
    )?;
    Ok(())
}

/// Output formats: canonical CSV (`.csv`) or MATLAB level 5 (`.mat`).
fn check_output(path: &Path) -> Result<()> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("csv" | "mat") => Ok(()),
        _ => bail!(
            "{}: unknown output format; expected a .csv or .mat file name",
            path.display()
        ),
    }
}

/// Writes the recording and its truth together: both go to temporary
/// names beside their targets first and are put in place only when both
/// are whole ([`ballpass::fsutil::commit_all`]), so a failure or an
/// interrupt never leaves a recording without its truth. Returns the
/// truth file's path.
fn write_pair(sim: &Simulation, path: &Path) -> Result<PathBuf> {
    let is_mat = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mat"));
    let truth_file = sim::truth_path(path);
    let rec = Pending::new(path)?;
    let truth = Pending::new(&truth_file)?;
    if is_mat {
        write_mat(&sim.recording, rec.path())
    } else {
        write_csv(&sim.recording, rec.path())
    }
    .with_context(|| format!("writing {}", path.display()))?;
    sim.truth
        .write_json(truth.path())
        .with_context(|| format!("writing {}", truth_file.display()))?;
    commit_all(vec![rec, truth])?;
    Ok(truth_file)
}

/// Arguments of `ballpass simulate-campaign`.
#[derive(Debug, Args)]
pub struct CampaignArgs {
    /// Output folder (created if missing): recordings, truth files and `manifest.csv`.
    #[arg(long, short = 'o', value_name = "DIR")]
    out: PathBuf,
    /// Campaign seed; each record's seed is derived from it and the record's index.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads [default: all cores].
    #[arg(long, value_name = "N")]
    jobs: Option<usize>,
    #[command(flatten)]
    flags: SimFlags,
}

/// Runs `ballpass simulate-campaign`.
pub fn run_campaign(a: &CampaignArgs) -> Result<()> {
    let base = a.flags.settings()?;
    base.validate()?;
    if base.profile.is_some() {
        bail!("--multi-speed (a speed profile) does not apply to the thesis campaign, whose records each have one velocity");
    }
    let plan = campaign::plan(&base, a.seed);
    let out = output::open_dir(&a.out, "simulate-campaign")?;
    let staged = out.path().to_path_buf();
    for sub in ["sweep", "diagnosis"] {
        let d = staged.join(sub);
        std::fs::create_dir_all(&d)
            .with_context(|| format!("cannot create folder {}", d.display()))?;
    }
    // A progress bar on a terminal (the campaign takes a while), nothing
    // when stderr is a file or a pipe.
    let bar = crate::output::progress(plan.len(), "recordings");
    let work = || -> Result<()> {
        plan.par_iter().try_for_each(|e| -> Result<()> {
            let path = staged.join(format!("{}.csv", e.path));
            let sim =
                sim::simulate(&e.settings).with_context(|| format!("simulating {}", e.path))?;
            write_pair(&sim, &path)?;
            if let Some(b) = &bar {
                b.inc(1);
            }
            Ok(())
        })
    };
    match a.jobs {
        Some(0) => bail!("--jobs must be at least 1"),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start worker threads")?
            .install(work)?,
        None => work()?,
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let mut manifest = String::from("path,bearing,velocity_mm_s,repeat,condition\n");
    for e in &plan {
        manifest.push_str(&format!(
            "{}.csv,{},{},{},{}\n",
            e.path,
            e.bearing,
            e.velocity_mm_s,
            e.repeat,
            e.condition.name()
        ));
    }
    ballpass::fsutil::write_atomic(&staged.join("manifest.csv"), manifest.as_bytes())?;
    let dir = output::commit(out)?;
    let mut o = output::stdout();
    writeln!(
        o,
        "wrote {} recordings with truth files and {}",
        plan.len(),
        text::path(&dir.join("manifest.csv"))
    )?;
    o.flush()?;
    Ok(())
}
