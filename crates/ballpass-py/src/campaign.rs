//! Campaigns: a manifest's records processed one by one (`process_record`,
//! what a Spark executor runs) or as a whole (`campaign`, what `ballpass
//! sweep` and `ballpass diagnose` run), and a diagnosis of records already
//! processed (`diagnose_records`, the last step of a fleet on Spark).

use std::path::{Path, PathBuf};

use ballpass::campaign::diagnose::{diagnose, DiagnoseSettings};
use ballpass::campaign::output::{CampaignOutput, DIAGNOSIS_SCHEMA, SWEEP_SCHEMA};
use ballpass::campaign::record::RecordResult;
use ballpass::campaign::run::{geometry_for, process_entry, CampaignSettings};
use ballpass::campaign::segments::plan;
use ballpass::campaign::sweep::sweep;
use ballpass::campaign::{
    export, from_directory, read_manifest, run_batch, select, BatchOutcome, CampaignKind, Manifest,
    ManifestEntry, RecordOutcome, Selection,
};
use ballpass::recording::segment::Window;
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert;
use crate::errors;
use crate::pool::{self, ThreadPool};
use crate::recording::LoadArgs;

/// The manifest CSV at `source`, or the recordings of the folder `source`
/// matching `pattern` (bearing from `load`'s arguments when the pattern has
/// no `{bearing}`).
fn read_source(
    source: &Path,
    pattern: Option<&str>,
    load: &LoadArgs,
    segment: bool,
) -> PyResult<Manifest> {
    if source.is_dir() {
        let Some(p) = pattern else {
            return Err(errors::value(format!(
                "{} is a folder: give pattern= (e.g. 'v{{velocity}}_r{{repeat}}.csv') or a manifest CSV",
                source.display()
            )));
        };
        let bearing = load.options()?.bearing;
        // Segmented runs measure their speeds: none needs to be given (NaN:
        // "measured", as an empty manifest cell).
        let velocity = load.velocity_mm_s().or(segment.then_some(f64::NAN));
        from_directory(source, p, bearing.as_deref(), velocity).map_err(errors::domain)
    } else {
        if pattern.is_some() {
            return Err(errors::value(format!(
                "pattern= goes with a folder, but {} is a file",
                source.display()
            )));
        }
        read_manifest(source).map_err(errors::domain)
    }
}

/// `ballpass.read_manifest`: the entries of a manifest CSV or of a folder
/// with a file-name pattern, as dicts.
#[pyfunction]
#[pyo3(signature = (source, pattern=None, load=None))]
fn manifest<'py>(
    py: Python<'py>,
    source: PathBuf,
    pattern: Option<&str>,
    load: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let m = read_source(&source, pattern, &LoadArgs::parse(load)?, false)?;
    convert::serialize(py, &m)
}

/// `ballpass.select`: the records of a manifest (or folder) that `ballpass
/// sweep` or `ballpass diagnose` would use: `{"source", "entries",
/// "notes"}`.
#[pyfunction]
#[pyo3(signature = (kind, source, pattern=None, only_bearings=Vec::new(), only_velocities=Vec::new(), load=None))]
fn selection<'py>(
    py: Python<'py>,
    kind: &str,
    source: PathBuf,
    pattern: Option<&str>,
    only_bearings: Vec<String>,
    only_velocities: Vec<f64>,
    load: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let kind = campaign_kind(kind)?;
    let m = read_source(&source, pattern, &LoadArgs::parse(load)?, false)?;
    let Selection { entries, notes } =
        select(&m, kind, &only_bearings, &only_velocities).map_err(errors::domain)?;
    let d = PyDict::new(py);
    d.set_item("source", m.source.display().to_string())?;
    d.set_item("entries", convert::serialize(py, &entries)?)?;
    d.set_item("notes", notes)?;
    Ok(d.into_any())
}

fn campaign_kind(kind: &str) -> PyResult<CampaignKind> {
    match kind {
        "sweep" => Ok(CampaignKind::Sweep),
        "diagnose" => Ok(CampaignKind::Diagnose),
        other => Err(errors::value(format!(
            "unknown campaign {other:?}; expected 'sweep' or 'diagnose'"
        ))),
    }
}

/// Per-record settings of a campaign: the library's defaults with the
/// command line's flags (`lowpass_hz`, `harmonics`) and, for a diagnosis,
/// its band edge and sticking settings.
fn campaign_settings(
    lowpass_hz: f64,
    harmonics: usize,
    diagnosis: Option<&DiagnoseSettings>,
    window: Option<&str>,
    force_velocity: bool,
) -> PyResult<CampaignSettings> {
    let mut s = CampaignSettings::default();
    s.analyze.lowpass_hz = Some(lowpass_hz);
    s.analyze.harmonics = harmonics;
    if let Some(d) = diagnosis {
        s.low_band_hz = d.low_band_hz;
        s.sticking = d.sticking.clone();
    }
    // `--window T0:T1` and `--force-velocity`: each record is cut to the
    // window before the checks, which refuse a stated velocity the encoder
    // contradicts unless forced.
    s.window = window
        .map(Window::parse)
        .transpose()
        .map_err(errors::domain)?;
    s.preflight.force_velocity = force_velocity;
    Ok(s)
}

fn diagnose_settings(json: Option<&str>) -> PyResult<DiagnoseSettings> {
    convert::settings(&DiagnoseSettings::default(), json, "diagnosis settings")
}

/// A record's result as `(dict, friction_psd_freq_hz, friction_psd,
/// sticking_heights_n)`: the JSON leaves the spectrum and the per-period
/// heights out (the diagnosis pools the heights), so they travel beside it.
fn record_to_py<'py>(py: Python<'py>, r: &RecordResult) -> PyResult<Bound<'py, PyAny>> {
    let heights = r
        .sticking
        .as_ref()
        .map(|s| s.heights_n.clone())
        .unwrap_or_default();
    (
        convert::serialize(py, r)?,
        convert::array(py, r.friction_psd_freq_hz.clone()),
        convert::array(py, r.friction_psd.clone()),
        convert::array(py, heights),
    )
        .into_pyobject(py)
        .map(|t| t.into_any())
}

/// `ballpass.process_record`: one recording file of a campaign, loaded and
/// processed as `ballpass diagnose` processes each record.
#[pyfunction]
#[pyo3(signature = (path, bearing, velocity_mm_s, repeat, condition=None, lowpass_hz=20.0, harmonics=5, diagnosis=None, load=None, window=None, force_velocity=false))]
#[allow(clippy::too_many_arguments)]
fn process_record<'py>(
    py: Python<'py>,
    path: PathBuf,
    bearing: String,
    velocity_mm_s: f64,
    repeat: u32,
    condition: Option<String>,
    lowpass_hz: f64,
    harmonics: usize,
    diagnosis: Option<&str>,
    load: Option<&str>,
    window: Option<&str>,
    force_velocity: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let ds = diagnose_settings(diagnosis)?;
    let settings = campaign_settings(lowpass_hz, harmonics, Some(&ds), window, force_velocity)?;
    let opts = LoadArgs::parse(load)?.options()?;
    let fallback = opts
        .geometry
        .ok_or_else(|| errors::value("no bearing geometry"))?;
    let entry = ManifestEntry {
        path,
        bearing,
        velocity_mm_s,
        repeat,
        condition,
        notes: None,
        plateau: None,
    };
    let r = py
        .detach(|| process_entry(&entry, &opts, fallback, &settings))
        .map_err(errors::domain)?;
    record_to_py(py, &r)
}

/// A record's result back from `(json, friction_psd_freq_hz, friction_psd,
/// sticking_heights_n)`.
fn record_from_py(t: &Bound<'_, PyAny>) -> PyResult<RecordResult> {
    type State<'a> = (
        String,
        PyReadonlyArray1<'a, f64>,
        PyReadonlyArray1<'a, f64>,
        PyReadonlyArray1<'a, f64>,
    );
    let (json, freq, psd, heights): State<'_> = t.extract()?;
    let mut r: RecordResult = serde_json::from_str(&json)
        .map_err(|e| errors::value(format!("not a ballpass record result: {e}")))?;
    r.friction_psd_freq_hz = freq.as_array().to_vec();
    r.friction_psd = psd.as_array().to_vec();
    let heights = heights.as_array().to_vec();
    match r.sticking.as_mut() {
        Some(s) => {
            if heights.len() != s.periods {
                return Err(errors::value(format!(
                    "record {}: sticking_heights_n has {} values but the result counts {} periods",
                    r.path,
                    heights.len(),
                    s.periods
                )));
            }
            s.heights_n = heights;
        }
        None if !heights.is_empty() => {
            return Err(errors::value(format!(
                "record {}: sticking_heights_n given but the result has no sticking",
                r.path
            )));
        }
        None => {}
    }
    Ok(r)
}

fn entry_of(r: &RecordResult) -> ManifestEntry {
    ManifestEntry {
        path: PathBuf::from(&r.path),
        bearing: r.bearing.clone(),
        velocity_mm_s: r.velocity_mm_s,
        repeat: r.repeat,
        condition: r.condition.clone(),
        notes: None,
        plateau: r.plateau.clone(),
    }
}

/// The diagnosis envelope (`diagnosis.json`) and its friction spectra table.
fn diagnosis_output<'py>(
    py: Python<'py>,
    source: String,
    outcome: &BatchOutcome<RecordResult>,
    notes: &[String],
    settings: &CampaignSettings,
    ds: &DiagnoseSettings,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    let ok: Vec<&RecordResult> = outcome.ok().map(|(_, r)| r).collect();
    let d = diagnose(&ok, ds);
    let out = CampaignOutput::new(DIAGNOSIS_SCHEMA, source, outcome, notes, settings, &d);
    let spectra = PyDict::new(py);
    spectra.set_item("freq_hz", convert::array(py, d.freq_hz.clone()))?;
    for (b, p) in d.bearings.iter().zip(&d.friction_psd) {
        spectra.set_item(
            export::friction_psd_column(&b.bearing),
            convert::array(py, p.clone()),
        )?;
    }
    Ok((convert::serialize(py, &out)?, spectra))
}

/// `ballpass.diagnose_records`: the diagnosis of records processed
/// elsewhere (by `process_record`, e.g. on Spark executors), as
/// `diagnosis.json`. `failures` are `(path, bearing, velocity_mm_s, repeat,
/// reason)` of records that could not be processed.
#[pyfunction]
#[pyo3(signature = (records, failures, source, selection, lowpass_hz=20.0, harmonics=5, diagnosis=None, window=None, force_velocity=false))]
#[allow(clippy::too_many_arguments)]
fn diagnose_records<'py>(
    py: Python<'py>,
    records: Vec<Bound<'py, PyAny>>,
    failures: Vec<(String, String, f64, u32, String)>,
    source: String,
    selection: Vec<String>,
    lowpass_hz: f64,
    harmonics: usize,
    diagnosis: Option<&str>,
    window: Option<&str>,
    force_velocity: bool,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    let ds = diagnose_settings(diagnosis)?;
    // The per-record settings are part of diagnosis.json: the window and
    // the checks the records were processed with.
    let settings = campaign_settings(lowpass_hz, harmonics, Some(&ds), window, force_velocity)?;
    let mut outcome = BatchOutcome {
        records: Vec::new(),
    };
    for t in &records {
        let r = record_from_py(t)?;
        outcome.records.push(RecordOutcome {
            entry: entry_of(&r),
            result: Ok(r),
        });
    }
    for (path, bearing, velocity_mm_s, repeat, reason) in failures {
        outcome.records.push(RecordOutcome {
            entry: ManifestEntry {
                path: path.into(),
                bearing,
                velocity_mm_s,
                repeat,
                condition: None,
                notes: None,
                plateau: None,
            },
            result: Err(reason),
        });
    }
    diagnosis_output(py, source, &outcome, &selection, &settings, &ds)
}

/// `ballpass.sweep` / `ballpass.diagnose`: a whole campaign as the command
/// line runs it (source, selection, every record in parallel, the
/// campaign's answer). Returns `(sweep.json or diagnosis.json as a dict,
/// extra tables)`.
#[pyfunction]
#[pyo3(signature = (kind, source, pattern=None, only_bearings=Vec::new(), only_velocities=Vec::new(), lowpass_hz=20.0, harmonics=5, diagnosis=None, load=None, pool=None, window=None, force_velocity=false, segment=false))]
#[allow(clippy::too_many_arguments)]
fn campaign<'py>(
    py: Python<'py>,
    kind: &str,
    source: PathBuf,
    pattern: Option<&str>,
    only_bearings: Vec<String>,
    only_velocities: Vec<f64>,
    lowpass_hz: f64,
    harmonics: usize,
    diagnosis: Option<&str>,
    load: Option<&str>,
    pool: Option<Bound<'py, ThreadPool>>,
    window: Option<&str>,
    force_velocity: bool,
    segment: bool,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    let kind = campaign_kind(kind)?;
    let load = LoadArgs::parse(load)?;
    let ds = diagnose_settings(diagnosis)?;
    let diagnosis = match kind {
        CampaignKind::Sweep => None,
        CampaignKind::Diagnose => Some(&ds),
    };
    let mut settings = campaign_settings(lowpass_hz, harmonics, diagnosis, window, force_velocity)?;
    // `--segment`: each file split into its constant-velocity plateaus.
    settings.segment = segment.then(Default::default);
    let manifest = read_source(&source, pattern, &load, segment)?;
    let opts = load.options()?;
    let fallback = opts
        .geometry
        .ok_or_else(|| errors::value("no bearing geometry"))?;
    let (outcome, planned) = pool::run(py, pool.as_ref(), || {
        let mut planned = plan(
            manifest,
            kind,
            &only_bearings,
            &only_velocities,
            &opts,
            fallback,
            &settings,
        )?;
        let outcome = run_batch(
            &planned.selection.entries,
            |e| process_entry(e, &opts, fallback, &settings),
            |_, _| {},
        );
        Ok::<_, ballpass::Error>((planned.finish(outcome), planned))
    })
    .map_err(errors::domain)?;
    let (manifest, notes) = (planned.manifest, planned.selection.notes);
    let src = manifest.source.display().to_string();
    match kind {
        CampaignKind::Diagnose => diagnosis_output(py, src, &outcome, &notes, &settings, &ds),
        CampaignKind::Sweep => {
            let ok: Vec<&RecordResult> = outcome.ok().map(|(_, r)| r).collect();
            let g = geometry_for(ok.first().map_or("", |r| r.bearing.as_str()), fallback);
            let s = sweep(&ok, Some(g.d_avg_mm()));
            let out = CampaignOutput::new(SWEEP_SCHEMA, src, &outcome, &notes, &settings, &s);
            Ok((convert::serialize(py, &out)?, PyDict::new(py)))
        }
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(manifest, m)?)?;
    m.add_function(wrap_pyfunction!(selection, m)?)?;
    m.add_function(wrap_pyfunction!(process_record, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose_records, m)?)?;
    m.add_function(wrap_pyfunction!(campaign, m)?)?;
    Ok(())
}
