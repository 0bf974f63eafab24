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

use std::time::Instant;

use rayon::prelude::*;

use crate::analysis::{self, analyze, detect_passages, Analysis, PassageAnalysis, PassageSettings};
use crate::bearing::lookup;
use crate::campaign::diagnose::{diagnose, Condition as Verdict, DiagnoseSettings, Diagnosis};
use crate::campaign::record::RecordResult;
use crate::campaign::run::{entry_of_simulation, process_simulation, CampaignSettings};
use crate::campaign::sweep::{sweep, Sweep};
use crate::campaign::{BatchOutcome, RecordOutcome};
use crate::error::{Error, Result};
use crate::model::{
    difference_responses, velocity_response, FrequencyAxis, GaussianTrain, PdLoop,
    VelocityResponseSettings,
};
use crate::recording::Recording;
use crate::report::campaign::{diagnosis_parts, friction_examples, sweep_parts};
use crate::report::{self, Block, Level, Report, Section, Verdict as Badge};
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
    /// Headline findings, one sentence each.
    pub headlines: Vec<String>,
    /// Wall time of each stage, s.
    pub timings: Vec<(String, f64)>,
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
    report = report.with_section(
        Section::new("What this is")
            .with(Block::Paragraph(format!(
                "The built-in testbed simulator (air-bearing stage under PD control, {} balls of a THK SR25W, \
                 quartz load cell, 0.1 µm encoder, optical fibre sensor) produced the thesis' campaign: \
                 1–20 mm/s × 5 repeats and 5 bearings × 10 repeats at 20 mm/s with bearing 4 sticking \
                 (150 records of 30 s at 1 kHz, campaign seed {}). ballpass then ran analyze (the five \
                 {v_an} mm/s repeats), passage, model, sweep and diagnose on them. The simulator's numbers \
                 that are not from the thesis are assumptions, listed in its documentation.",
                sr25w.balls_in_race, settings.seed
            )))
            .with(Block::Verdicts(
                headlines.iter().map(|h| Badge::new(Level::Info, "finding", h.clone())).collect(),
            )),
    );
    // analyze
    let an = report::analysis::report(&analysis, Some(first))?;
    report = append(report, "Chapter 7 — analyze: five repeats at 9 mm/s", an);
    // passage
    let mut pr = Report::new("passage");
    for s in report::passage::passage_sections(&passages) {
        pr = pr.with_section(s);
    }
    for f in report::passage::passage_figures(1, first, &passages)? {
        pr = pr.with_figure(f);
    }
    report = append(
        report,
        "Chapters 5–6 — ball passages of the first 9 mm/s record",
        pr,
    );
    // model
    report = append(
        report,
        "Chapter 6 — models: the simulated stage and the pulse trains",
        model_report(&base, &prediction)?,
    );
    // sweep
    let sp = sweep_parts(&the_sweep, "sweep_")?;
    report = append_parts(
        report,
        "Velocity sweep — 1 to 20 mm/s",
        sp.sections,
        sp.figures,
    );
    // diagnose
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
    )?;
    report = append_parts(
        report,
        "Chapter 8 — bearing diagnosis at 20 mm/s",
        dp.sections,
        dp.figures,
    );
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
        headlines,
        timings,
    })
}

/// Appends another report's sections (under a heading) and figures.
fn append(report: Report, heading: &str, other: Report) -> Report {
    append_parts(report, heading, other.summary, other.figures)
}

fn append_parts(
    mut report: Report,
    heading: &str,
    sections: Vec<Section>,
    figures: Vec<report::Figure>,
) -> Report {
    for mut s in sections {
        s.heading = format!("{heading}: {}", s.heading);
        report = report.with_section(s);
    }
    for f in figures {
        report = report.with_figure(f);
    }
    report
}

/// The stage and pulse-train models with the simulator's parameters.
fn model_report(base: &SimSettings, prediction: &crate::bearing::Prediction) -> Result<Report> {
    let st = &base.stage;
    let stage = PdLoop::from_products(st.mass_kg, st.kkp_n_per_m, st.kkd_n_s_per_m)?;
    let f_n = stage.omega_n_rad_s() / (2.0 * std::f64::consts::PI);
    let bode = stage.bode(&FrequencyAxis::default())?;
    let diff = difference_responses(base.fs_hz, 500)?;
    let tau_c = prediction.tau_c_s;
    let sigma_ratio = 0.155 / (2.0 * (2.0 * std::f64::consts::LN_2).sqrt());
    let friction = GaussianTrain::new(tau_c, sigma_ratio, 0.2, 0.0, 0.5 * tau_c)?;
    let resp = velocity_response(&stage, &friction, &VelocityResponseSettings::default())?;
    let ns: Vec<f64> = (0..=8).map(f64::from).collect();
    let unit = GaussianTrain::new(1.0, sigma_ratio, 1.0, 0.0, 0.0)?;
    let cn: Vec<f64> = (0..=8).map(|n| unit.coefficient(n).norm()).collect();
    let printed: Vec<f64> = (0..=8)
        .map(|n| unit.thesis_printed_coefficient(n))
        .collect();
    let mut r = Report::new("model").with_section(Section::new("Stage and pulse trains").with(Block::KeyValues(vec![
        ("stage natural frequency f_n".into(), format!("{f_n:.4} Hz")),
        ("damping ratio".into(), format!("{:.3}", stage.damping_ratio())),
        ("f_c at 9 mm/s".into(), format!("{:.4} Hz (f_c / f_n = {:.3})", prediction.f_c_hz, prediction.f_c_hz / f_n)),
        ("friction pulse σ / τc".into(), format!("{sigma_ratio:.4} (half-prominence width 0.155 τc)")),
        (
            "velocity response to 0.2 N pulses".into(),
            format!(
                "{:.4} mm/s peak to peak; the thesis' magnitude-only sum errs by {:.0} % of the peak (ERRATA §7)",
                resp.velocity_peak_to_peak_mm_s,
                100.0 * resp.magnitude_only_error_of_peak
            ),
        ),
    ])));
    for f in report::model::stage_bode_figures(&bode, f_n, Some(prediction.f_c_hz)) {
        r = r.with_figure(f);
    }
    r = r
        .with_figure(report::model::difference_figure(&diff, base.fs_hz))
        .with_figure(report::model::gaussian_coefficients_figure(
            &ns,
            &cn,
            Some(&printed),
            sigma_ratio,
        ))
        .with_figure(report::model::velocity_response_figure(&resp));
    Ok(r)
}

fn headlines(
    a: &Analysis,
    p: &PassageAnalysis,
    s: &Sweep,
    d: &Diagnosis,
    sr: &BatchOutcome<RecordResult>,
    dr: &BatchOutcome<RecordResult>,
) -> Vec<String> {
    let mut h = Vec::new();
    h.push(format!(
        "at 9 mm/s the predicted ball-pass frequency is {:.4} Hz; the correlations measure {}",
        a.prediction.f_c_hz,
        a.measured_period
            .f_c_hz
            .map(|f| format!(
                "{f:.4} Hz ({:+.2} %)",
                100.0 * (f - a.prediction.f_c_hz) / a.prediction.f_c_hz
            ))
            .unwrap_or_else(|| "no period".into())
    ));
    if let Some(ph) = a.phases.iter().find(|p| p.pair == "friction__optical") {
        h.push(ph.words.clone());
    }
    h.push(format!(
        "{} ball passages in the first record, τp/τc = {:.4} ± {:.4} (thesis 0.155)",
        p.count, p.tau_p_over_tau_c.mean, p.tau_p_over_tau_c.std
    ));
    h.extend(s.findings.iter().cloned());
    let bad: Vec<&str> = d
        .bearings
        .iter()
        .filter(|b| b.verdict == Verdict::Bad)
        .map(|b| b.bearing.as_str())
        .collect();
    h.push(if bad.is_empty() {
        "no bearing of the batch is bad".to_string()
    } else {
        format!(
            "bad: {} — {}",
            bad.join(", "),
            d.bearings[0].evidence.first().cloned().unwrap_or_default()
        )
    });
    let failed = sr.n_failed() + dr.n_failed();
    if failed > 0 {
        h.push(format!(
            "{failed} simulated records failed to analyse (see the tables)"
        ));
    }
    h
}
