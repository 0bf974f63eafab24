//! The whole thesis on simulated data, in one call: the built-in data source
//! of `ballpass demo`.
//!
//! 1. Simulates the thesis' campaign with [`crate::sim`]: the 1–20 mm/s sweep
//!    (five repeats each; its 9 mm/s set is the thesis' chapter 7 test) and
//!    five bearings × ten repeats at 20 mm/s with bearing 4 sticking.
//! 2. `analyze` on the five 9 mm/s repeats (correlations, spectra,
//!    harmonics, phases, averaged as in the thesis).
//! 3. `passage` on the first 9 mm/s record (ball passages, pulse-train fits).
//! 4. `model`: the simulator's PD stage (Bode plots, finite differences,
//!    velocity response to the friction pulses) and the Gaussian pulse-train
//!    coefficients.
//! 5. `sweep` over the sweep records and `diagnose` over the batch.
//!
//! Everything is computed in memory; the result carries the report, the
//! tables and the headline findings, and the caller writes them.

use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::analysis::{self, analyze, detect_passages, Analysis, PassageAnalysis, PassageSettings};
use crate::bearing::lookup;
use crate::campaign::diagnose::{diagnose, Condition as Verdict, DiagnoseSettings, Diagnosis};
use crate::campaign::export;
use crate::campaign::record::RecordResult;
use crate::campaign::run::{entry_of_simulation, process_simulation, CampaignSettings};
use crate::campaign::sweep::{sweep, Sweep};
use crate::campaign::{BatchOutcome, RecordOutcome};
use crate::error::{Error, Result};
use crate::model::stage::{BodeRow, DifferenceRow, VelocityResponse};
use crate::model::{
    difference_responses, velocity_response, FrequencyAxis, GaussianTrain, PdLoop,
    VelocityResponseSettings,
};
use crate::recording::Recording;
use crate::report::analysis::AnalysisLinks;
use crate::report::campaign::{diagnosis_parts, friction_examples, sweep_parts};
use crate::report::{
    self, Block, Level, Report, ReportFiles, ReportOptions, Section, Verdict as Badge,
};
use crate::sim::{campaign::plan, SimSettings};

/// Settings of the demo.
#[derive(Debug, Clone, PartialEq)]
pub struct DemoSettings {
    /// Campaign seed (every record's seed derives from it).
    pub seed: u64,
    /// Velocity of the chapter 7 analysis, mm/s (must be one of the sweep's).
    pub analysis_velocity_mm_s: f64,
}

impl Default for DemoSettings {
    fn default() -> Self {
        Self {
            seed: 2011,
            analysis_velocity_mm_s: 9.0,
        }
    }
}

/// Everything the demo produced.
#[derive(Debug)]
pub struct Demo {
    /// The one report (summary, then every figure).
    pub report: Report,
    /// The chapter 7 analysis of the 9 mm/s repeats.
    pub analysis: Analysis,
    /// The ball passages of the first 9 mm/s record.
    pub passages: PassageAnalysis,
    /// The velocity sweep.
    pub sweep: Sweep,
    /// Per-record results of the sweep.
    pub sweep_records: BatchOutcome<RecordResult>,
    /// The bearing diagnosis.
    pub diagnosis: Diagnosis,
    /// Per-record results of the batch.
    pub diagnosis_records: BatchOutcome<RecordResult>,
    /// The sweep's 9 mm/s recordings (for exports).
    pub analysis_recordings: Vec<Recording>,
    /// The model tables behind the model figures.
    pub model: ModelTables,
    /// Headline findings, one sentence each, with how good each is.
    pub headlines: Vec<Finding>,
    /// Wall time of each stage, s.
    pub timings: Vec<(String, f64)>,
}

/// One headline finding of the demo: a sentence and how good it is (a bad
/// bearing is a [`Level::Fail`]; facts are [`Level::Info`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    /// Badge.
    pub level: Level,
    /// The sentence.
    pub text: String,
}

impl Finding {
    fn info(text: impl Into<String>) -> Self {
        Finding {
            level: Level::Info,
            text: text.into(),
        }
    }
}

impl fmt::Display for Finding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// The model tables the demo's model figures are drawn from.
#[derive(Debug, Clone)]
pub struct ModelTables {
    /// Bode table of the simulator's PD stage.
    pub bode: Vec<BodeRow>,
    /// Centred and forward differences against `jω`.
    pub difference: Vec<DifferenceRow>,
    /// `|C_n| / P` of the Gaussian train, corrected and as printed.
    pub gaussian: Vec<GaussianRow>,
    /// The stage's velocity response to one period of friction pulses.
    pub response: VelocityResponse,
}

/// One coefficient of the Gaussian pulse train (`gaussian_coefficients.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GaussianRow {
    /// Harmonic number.
    pub n: usize,
    /// `|C_n| / P` (the thesis' Eq. 6.28 corrected).
    pub c_over_p: f64,
    /// The value the thesis' printed formula gives.
    pub thesis_printed_c_over_p: f64,
}

/// Runs the demo.
///
/// # Errors
/// Any stage's error (none is expected on the built-in data; a failure is a
/// bug worth reporting, and the message names the stage).
pub fn run_demo(settings: &DemoSettings) -> Result<Demo> {
    let sr25w = lookup("sr25w")
        .ok_or_else(|| Error::setting("bearing", "sr25w missing from the catalog"))?
        .geometry;
    let base = SimSettings::default();
    let mut timings = Vec::new();
    let mut clock = Instant::now();
    let mut lap = |name: &str, timings: &mut Vec<(String, f64)>| {
        timings.push((name.to_string(), clock.elapsed().as_secs_f64()));
        clock = Instant::now();
    };

    // 1–2. Simulate and process every record in parallel.
    let campaign = CampaignSettings::default();
    let planned = plan(&base, settings.seed);
    let v_an = settings.analysis_velocity_mm_s;
    let processed: Vec<(bool, RecordOutcome<RecordResult>, Option<Recording>)> = planned
        .par_iter()
        .map(|c| {
            let is_sweep = c.path.starts_with("sweep/");
            let keep = (is_sweep && c.velocity_mm_s == v_an) || (!is_sweep && c.repeat == 1);
            let (rec, result) = match process_simulation(c, sr25w, &campaign) {
                Ok((rec, r)) => (keep.then_some(rec), Ok(r)),
                Err(e) => (None, Err(e.to_string())),
            };
            (
                is_sweep,
                RecordOutcome {
                    entry: entry_of_simulation(c),
                    result,
                },
                rec,
            )
        })
        .collect();
    lap("simulate and process 150 records", &mut timings);

    let mut sweep_records = Vec::new();
    let mut diag_records = Vec::new();
    let mut analysis_recordings = Vec::new();
    let mut examples: Vec<(String, Recording)> = Vec::new();
    for (is_sweep, outcome, rec) in processed {
        if let Some(rec) = rec {
            if is_sweep {
                analysis_recordings.push(rec);
            } else {
                examples.push((outcome.entry.bearing.clone(), rec));
            }
        }
        if is_sweep {
            sweep_records.push(outcome);
        } else {
            diag_records.push(outcome);
        }
    }
    let sweep_records = BatchOutcome {
        records: sweep_records,
    };
    let diagnosis_records = BatchOutcome {
        records: diag_records,
    };

    // Chapter 7: analyze the repeats at the analysis velocity.
    let prediction = sr25w.predict(v_an, 5)?;
    let analysis = analyze(
        &analysis_recordings,
        &prediction,
        &analysis::AnalyzeSettings::default(),
    )?;
    lap("analyze the 9 mm/s repeats", &mut timings);

    // Chapter 5–6: passages and fits of the first record.
    let first = analysis_recordings.first().ok_or_else(|| {
        Error::setting(
            "analysis velocity",
            format!("{v_an} mm/s is not a sweep velocity"),
        )
    })?;
    let passages = detect_passages(
        first,
        &PassageSettings {
            velocity_mm_s: Some(v_an),
            geometry: Some(sr25w),
            ..PassageSettings::default()
        },
    )?;
    lap("ball passages and pulse-train fits", &mut timings);

    // Campaigns.
    let ok_sweep: Vec<&RecordResult> = sweep_records.ok().map(|(_, r)| r).collect();
    let the_sweep = sweep(&ok_sweep, Some(sr25w.d_avg_mm()));
    let ok_diag: Vec<&RecordResult> = diagnosis_records.ok().map(|(_, r)| r).collect();
    let diagnosis = diagnose(&ok_diag, &DiagnoseSettings::default());
    lap("sweep and diagnosis tables", &mut timings);

    // Report.
    let mut report = Report::new("ballpass demo: the thesis campaign on simulated data")
        .with_command(format!("ballpass demo --seed {}", settings.seed));
    let headlines = headlines(
        &analysis,
        &passages,
        &the_sweep,
        &diagnosis,
        &sweep_records,
        &diagnosis_records,
    );
    let (model_section, model) = model_part(&base, &prediction)?;
    report = report.with_section(
        Section::new("What this is")
            .with(Block::Paragraph(format!(
                "The built-in testbed simulator (air-bearing stage under PD control, {} balls of a THK SR25W, \
                 quartz load cell, 0.1 µm encoder, optical fibre sensor) produced the thesis' campaign: \
                 1–20 mm/s × 5 repeats and 5 bearings × 10 repeats at 20 mm/s with bearing 4 sticking \
                 (150 records of 30 s at 1 kHz, campaign seed {}). ballpass then ran analyze (the five \
                 {v_an} mm/s repeats), passage, model, sweep and diagnose on them; each has a part \
                 below, with its figures and links to the tables they are drawn from (analyze/, \
                 passage/, model/, sweep/, diagnose/ beside this page). The simulator's numbers \
                 that are not from the thesis are assumptions, listed in its documentation.",
                sr25w.balls_in_race, settings.seed
            )))
            .with(Block::Verdicts(
                headlines
                    .iter()
                    .map(|h| Badge::new(h.level, "finding", h.text.clone()))
                    .collect(),
            )),
    );
    let an = report::analysis::sections(
        &analysis,
        Some(first),
        &AnalysisLinks {
            tables_dir: "analyze/".into(),
            recording: None,
            id_prefix: String::new(),
        },
    )?;
    report = report.with_section(part(
        &format!("Chapter 7 — analyze: five repeats at {v_an} mm/s"),
        an,
    ));
    let ps = report::passage::record_sections(1, first, &passages, "passage/passage.json", "")?;
    report = report.with_section(part(
        &format!("Chapters 5–6 — ball passages of the first {v_an} mm/s record"),
        ps,
    ));
    report = report.with_section(model_section);
    let sp = sweep_parts(&the_sweep, "sweep_", "sweep/")?;
    report = report.with_section(part("Velocity sweep — 1 to 20 mm/s", sp.sections));
    let traces = friction_examples(&diagnosis, |bearing| {
        examples
            .iter()
            .find(|(name, _)| name == bearing)
            .map(|(_, r)| r.clone())
    });
    let dp = diagnosis_parts(
        &diagnosis,
        ok_diag.first().map(|r| r.f_c_predicted_hz),
        &traces,
        "diagnose_",
        "diagnose/",
    )?;
    report = report.with_section(part(
        "Chapter 8 — bearing diagnosis at 20 mm/s",
        dp.sections,
    ));
    lap("report", &mut timings);

    Ok(Demo {
        report,
        analysis,
        passages,
        sweep: the_sweep,
        sweep_records,
        diagnosis,
        diagnosis_records,
        analysis_recordings,
        model,
        headlines,
        timings,
    })
}

/// A part of the demo report: a heading over a command's sections.
fn part(heading: &str, sections: Vec<Section>) -> Section {
    sections
        .into_iter()
        .fold(Section::new(heading), Section::with_subsection)
}

/// The stage and pulse-train models with the simulator's parameters: the
/// demo's model part and the tables behind its figures.
fn model_part(
    base: &SimSettings,
    prediction: &crate::bearing::Prediction,
) -> Result<(Section, ModelTables)> {
    let st = &base.stage;
    let stage = PdLoop::from_products(st.mass_kg, st.kkp_n_per_m, st.kkd_n_s_per_m)?;
    let f_n = stage.omega_n_rad_s() / (2.0 * std::f64::consts::PI);
    let bode = stage.bode(&FrequencyAxis::default())?;
    let diff = difference_responses(base.fs_hz, 500)?;
    let tau_c = prediction.tau_c_s;
    let sigma_ratio = 0.155 / (2.0 * (2.0 * std::f64::consts::LN_2).sqrt());
    let friction = GaussianTrain::new(tau_c, sigma_ratio, 0.2, 0.0, 0.5 * tau_c)?;
    let resp = velocity_response(&stage, &friction, &VelocityResponseSettings::default())?;
    let unit = GaussianTrain::new(1.0, sigma_ratio, 1.0, 0.0, 0.0)?;
    let gaussian: Vec<GaussianRow> = (0..=8)
        .map(|n| GaussianRow {
            n,
            c_over_p: unit.coefficient(n as i64).norm(),
            thesis_printed_c_over_p: unit.thesis_printed_coefficient(n as i64),
        })
        .collect();
    let ns: Vec<f64> = gaussian.iter().map(|g| g.n as f64).collect();
    let cn: Vec<f64> = gaussian.iter().map(|g| g.c_over_p).collect();
    let printed: Vec<f64> = gaussian.iter().map(|g| g.thesis_printed_c_over_p).collect();
    let mut bode_figs = report::model::stage_bode_figures(&bode, f_n, Some(prediction.f_c_hz));
    for f in &mut bode_figs {
        f.data.push(report::DataFile {
            path: "model/bode.csv".into(),
            what: "f_hz and the gain (dB) and phase (deg) of each transfer function".into(),
        });
    }
    let diff_fig = report::model::difference_figure(&diff, base.fs_hz).with_data(
        "model/difference.csv",
        "gain ratios and absolute phases (deg)",
    );
    let coef_fig =
        report::model::gaussian_coefficients_figure(&ns, &cn, Some(&printed), sigma_ratio)
            .with_data(
                "model/gaussian_coefficients.csv",
                "n, |C_n|/P corrected and as printed",
            );
    let resp_fig = report::model::velocity_response_figure(&resp).with_data(
        "model/velocity_response.csv",
        "t_s, friction_n, velocity_mm_s",
    );
    let refs = |figs: &[&report::Figure]| {
        figs.iter()
            .map(|f| format!("{{fig:{}}}", f.id))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut section = Section::new("Chapter 6 — models: the simulated stage and the pulse trains")
        .with(Block::KeyValues(vec![
            ("stage natural frequency f_n".into(), format!("{f_n:.4} Hz")),
            ("damping ratio".into(), format!("{:.3}", stage.damping_ratio())),
            (
                format!("f_c at {} mm/s", prediction.velocity_mm_s),
                format!(
                    "{:.4} Hz (f_c / f_n = {:.3})",
                    prediction.f_c_hz,
                    prediction.f_c_hz / f_n
                ),
            ),
            (
                "friction pulse σ / τc".into(),
                format!("{sigma_ratio:.4} (width at half maximum 0.155 τc)"),
            ),
            (
                "velocity response to 0.2 N pulses".into(),
                format!(
                    "{:.4} mm/s peak to peak; the thesis' magnitude-only sum (Eq. 6.29 as printed) errs by {:.0} % of the peak",
                    resp.velocity_peak_to_peak_mm_s,
                    100.0 * resp.magnitude_only_error_of_peak
                ),
            ),
        ]))
        .with(Block::Paragraph(format!(
            "The stage's responses to the reference and to friction are in {} (thesis Figs. \
             41–42); the differentiators that turn position into velocity in {{fig:{}}} (Fig. \
             28); the Fourier coefficients of the Gaussian friction pulses in {{fig:{}}} (Fig. \
             49); and the velocity error those pulses cause over one period in {{fig:{}}} (Fig. \
             51). The formulas are the thesis' as corrected in the method notes of the user \
             guide.",
            refs(&bode_figs.iter().collect::<Vec<_>>()),
            diff_fig.id,
            coef_fig.id,
            resp_fig.id
        )));
    for f in bode_figs {
        section = section.with_figure(f);
    }
    section = section
        .with_figure(diff_fig)
        .with_figure(coef_fig)
        .with_figure(resp_fig);
    Ok((
        section,
        ModelTables {
            bode,
            difference: diff,
            gaussian,
            response: resp,
        },
    ))
}

fn headlines(
    a: &Analysis,
    p: &PassageAnalysis,
    s: &Sweep,
    d: &Diagnosis,
    sr: &BatchOutcome<RecordResult>,
    dr: &BatchOutcome<RecordResult>,
) -> Vec<Finding> {
    let mut h = Vec::new();
    h.push(Finding::info(format!(
        "at 9 mm/s the predicted ball-pass frequency is {:.4} Hz; the correlations measure {}",
        a.prediction.f_c_hz,
        a.measured_period
            .f_c_hz
            .map(|f| format!(
                "{f:.4} Hz ({:+.2} %)",
                100.0 * (f - a.prediction.f_c_hz) / a.prediction.f_c_hz
            ))
            .unwrap_or_else(|| "no period".into())
    )));
    if let Some(ph) = a.phases.iter().find(|p| {
        p.x == crate::analysis::Signal::Friction && p.y == crate::analysis::Signal::Optical
    }) {
        h.push(Finding::info(report::analysis::humanize(&ph.words)));
    }
    h.push(Finding::info(format!(
        "{} ball passages in the first record, τp/τc = {} (mean ± standard deviation over the passages; thesis 0.155)",
        p.count,
        report::passage::width_pm(&p.tau_p_over_tau_c, 4)
    )));
    h.extend(s.findings.iter().cloned().map(Finding::info));
    let bad: Vec<&str> = d
        .bearings
        .iter()
        .filter(|b| b.verdict == Verdict::Bad)
        .map(|b| b.bearing.as_str())
        .collect();
    h.push(if bad.is_empty() {
        Finding {
            level: Level::Pass,
            text: "no bearing of the batch is bad".to_string(),
        }
    } else {
        Finding {
            level: Level::Fail,
            text: format!(
                "bad: {} — {}",
                bad.join(", "),
                d.bearings[0].evidence.first().cloned().unwrap_or_default()
            ),
        }
    });
    let failed = sr.n_failed() + dr.n_failed();
    if failed > 0 {
        h.push(Finding {
            level: Level::Warn,
            text: format!("{failed} simulated records failed to analyse (see the tables)"),
        });
    }
    h
}

/// What [`write_outputs`] wrote.
#[derive(Debug, Clone)]
pub struct DemoFiles {
    /// The data files (CSV, JSON), in the order written.
    pub data: Vec<PathBuf>,
    /// The report, its figures and drawing notes.
    pub report: ReportFiles,
    /// Figures in the report.
    pub figures: usize,
    /// Tables in the report.
    pub tables: usize,
}

/// Rows as CSV with a header from their field names.
fn rows_csv<T: Serialize>(path: &Path, rows: impl IntoIterator<Item = T>) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(|e| Error::Format {
            path: path.to_path_buf(),
            reason: format!("cannot format a row: {e}"),
        })?;
    }
    let bytes = w.into_inner().map_err(|e| Error::Format {
        path: path.to_path_buf(),
        reason: format!("cannot format: {e}"),
    })?;
    String::from_utf8(bytes).map_err(|e| Error::Format {
        path: path.to_path_buf(),
        reason: format!("not UTF-8: {e}"),
    })
}

/// One sample of the velocity response (`model/velocity_response.csv`).
#[derive(Serialize)]
struct ResponseRow {
    t_s: f64,
    friction_n: f64,
    velocity_mm_s: f64,
    velocity_magnitude_only_mm_s: f64,
}

/// Writes everything the demo produced under `dir`: `analyze/` (the
/// analysis tables), `passage/passage.json`, `model/` (the model tables),
/// `sweep/` and `diagnose/` (records, campaign tables and JSON),
/// `recordings/v09_r<k>.csv` when `recordings`, then `report.html` with
/// `figures/` (and the signals figure linked to its recording when written).
///
/// # Errors
/// [`Error::Io`] naming the folder or file that could not be written.
pub fn write_outputs(
    demo: &Demo,
    dir: &Path,
    options: ReportOptions,
    recordings: bool,
) -> Result<DemoFiles> {
    let mkdir = |d: &Path| {
        std::fs::create_dir_all(d).map_err(|source| Error::Io {
            path: d.to_path_buf(),
            source,
        })
    };
    let mut data = Vec::new();
    let paths = crate::analysis::write_outputs(&demo.analysis, &dir.join("analyze"))?;
    data.extend([
        paths.json,
        paths.correlations,
        paths.spectra,
        paths.spectra_hires,
        paths.spectra_unfiltered,
    ]);
    let k = demo.analysis.settings.harmonics;
    let (sweep_dir, diag_dir, passage_dir, model_dir) = (
        dir.join("sweep"),
        dir.join("diagnose"),
        dir.join("passage"),
        dir.join("model"),
    );
    for d in [&sweep_dir, &diag_dir, &passage_dir, &model_dir] {
        mkdir(d)?;
    }
    data.push(export::write_text(
        &sweep_dir,
        "records.csv",
        &export::records_csv(&demo.sweep_records, k),
    )?);
    data.push(export::write_text(
        &sweep_dir,
        "sweep.csv",
        &export::sweep_csv(&demo.sweep),
    )?);
    data.push(export::write_json(&sweep_dir, "sweep.json", &demo.sweep)?);
    data.push(export::write_text(
        &diag_dir,
        "records.csv",
        &export::records_csv(&demo.diagnosis_records, k),
    )?);
    data.push(export::write_text(
        &diag_dir,
        "diagnosis.csv",
        &export::diagnosis_csv(&demo.diagnosis),
    )?);
    data.push(export::write_text(
        &diag_dir,
        "friction_spectra.csv",
        &export::friction_spectra_csv(&demo.diagnosis),
    )?);
    data.push(export::write_json(
        &diag_dir,
        "diagnosis.json",
        &demo.diagnosis,
    )?);
    data.push(export::write_json(
        &passage_dir,
        "passage.json",
        &demo.passages,
    )?);
    let m = &demo.model;
    let r = &m.response;
    for (name, text) in [
        ("bode.csv", rows_csv(&model_dir.join("bode.csv"), &m.bode)?),
        (
            "difference.csv",
            rows_csv(&model_dir.join("difference.csv"), &m.difference)?,
        ),
        (
            "gaussian_coefficients.csv",
            rows_csv(&model_dir.join("gaussian_coefficients.csv"), &m.gaussian)?,
        ),
        (
            "velocity_response.csv",
            rows_csv(
                &model_dir.join("velocity_response.csv"),
                (0..r.time_s.len()).map(|i| ResponseRow {
                    t_s: r.time_s[i],
                    friction_n: r.friction_n[i],
                    velocity_mm_s: r.velocity_mm_s[i],
                    velocity_magnitude_only_mm_s: r.velocity_magnitude_only_mm_s[i],
                }),
            )?,
        ),
    ] {
        data.push(export::write_text(&model_dir, name, &text)?);
    }
    let mut report = demo.report.clone();
    if recordings {
        let rec_dir = dir.join("recordings");
        mkdir(&rec_dir)?;
        for (i, r) in demo.analysis_recordings.iter().enumerate() {
            let p = rec_dir.join(format!("v09_r{}.csv", i + 1));
            crate::recording::write_csv(r, &p)?;
            data.push(p);
        }
        if let Some(f) = report.figure_mut("signals") {
            f.data.push(report::DataFile {
                path: "recordings/v09_r1.csv".into(),
                what: "the recording".into(),
            });
        }
    }
    let files = report::write_report(&report, dir, options)?;
    Ok(DemoFiles {
        data,
        figures: files.svgs.len(),
        tables: report.table_count(),
        report: files,
    })
}
