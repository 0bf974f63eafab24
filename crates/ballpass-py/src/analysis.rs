//! `predict`, `analyze` and `passages`: what the command line's `predict`,
//! `analyze` and `passage` compute, on recordings already in memory.

use ballpass::analysis::passage_table::{
    checked_passages, passage_rows, PassageFailure, PassageOutput,
};
use ballpass::analysis::preflight::{self, PreflightSettings};
use ballpass::analysis::stream::file::{self as stream_file, Choice, Naming, StreamMode};
use ballpass::analysis::{self, export, AnalyzeSettings, PassageSettings};
use ballpass::bearing;
use ballpass::recording::segment::{self, Window};
use ballpass::recording::Recording;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert;
use crate::errors;
use crate::pool::{self, ThreadPool};
use crate::recording::{BearingArgs, LoadArgs, PyRecording};

pub(crate) fn bearing_args(json: Option<&str>) -> PyResult<BearingArgs> {
    match json {
        None => Ok(BearingArgs::default()),
        Some(t) => serde_json::from_str(t).map_err(|e| errors::value(format!("bearing: {e}"))),
    }
}

/// `ballpass.predict`: the ball-pass frequency, period and band at each
/// velocity, as `ballpass predict --json` prints them.
#[pyfunction]
#[pyo3(signature = (velocities_mm_s, harmonics, bearing=None))]
fn predict<'py>(
    py: Python<'py>,
    velocities_mm_s: Vec<f64>,
    harmonics: usize,
    bearing: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let (name, g) = bearing_args(bearing)?.resolve(None)?;
    let t =
        bearing::prediction_table(name, g, &velocities_mm_s, harmonics).map_err(errors::domain)?;
    convert::serialize(py, &t)
}

/// The velocity stated for an analysis, as `ballpass analyze` takes it: the
/// argument, else the one all recordings' metadata agree on, else none (the
/// checks then measure it from the encoder).
pub(crate) fn stated_velocity(recs: &[Recording], given: Option<f64>) -> PyResult<Option<f64>> {
    if given.is_some() {
        return Ok(given);
    }
    let vs: Vec<f64> = recs.iter().filter_map(|r| r.meta.velocity_mm_s).collect();
    match vs.first() {
        None => Ok(None),
        Some(&v) if vs.len() == recs.len() && vs.iter().all(|&w| w == v) => Ok(Some(v)),
        Some(_) => Err(errors::value(
            "the recordings' metadata disagree on the velocity or lack it; give velocity_mm_s",
        )),
    }
}

/// Columns of a spectra table: `freq_hz`, then the library's columns.
fn spectra_columns<'py>(py: Python<'py>, s: &analysis::Spectra) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("freq_hz", convert::array(py, s.freq_hz.clone()))?;
    for (name, v) in export::spectrum_columns(s) {
        d.set_item(name, convert::array(py, v))?;
    }
    Ok(d)
}

/// A table as `{column: array}`: the index column, then the others.
pub(crate) fn table<'py>(
    py: Python<'py>,
    index_name: &str,
    index: &[f64],
    columns: Vec<(String, Vec<f64>)>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item(index_name, convert::array(py, index.to_vec()))?;
    for (name, v) in columns {
        d.set_item(name, convert::array(py, v))?;
    }
    Ok(d)
}

/// `ballpass.analyze`: the analysis of one recording or several repeats at
/// one velocity. Returns `(analysis.json as a dict, correlations,
/// spectra, spectra_hires, spectra_unfiltered, spectra_position,
/// sync_average)`, the tables as `{column: array}` with the CSV files'
/// columns (units in their names); the last two are `None` when the
/// command line writes no such file.
/// The checks before the analysis are the command line's (dead channels
/// left out, the velocity checked against the encoder or measured from it
/// when none is stated, Nyquist); their warnings and notes join the
/// analysis' as there.
#[pyfunction]
#[pyo3(signature = (recordings, velocity_mm_s=None, bearing=None, settings=None, pool=None, force_velocity=false))]
fn analyze<'py>(
    py: Python<'py>,
    recordings: Vec<PyRef<'py, PyRecording>>,
    velocity_mm_s: Option<f64>,
    bearing: Option<&str>,
    settings: Option<&str>,
    pool: Option<Bound<'py, ThreadPool>>,
    force_velocity: bool,
) -> PyResult<Tables<'py>> {
    let s: AnalyzeSettings =
        convert::settings(&AnalyzeSettings::default(), settings, "analysis settings")?;
    s.validate().map_err(errors::domain)?;
    let (mut a, checked) = checked_run(
        py,
        &recordings,
        velocity_mm_s,
        bearing,
        pool.as_ref(),
        force_velocity,
        s.harmonics,
        |recs, prediction| analysis::analyze(recs, prediction, &s),
    )?;
    a.warnings.splice(0..0, checked.warnings);
    a.method_notes.extend(checked.notes);
    results(py, a)
}

/// What the command line's checks said of the records: prominent warnings
/// and notes.
pub(crate) struct CheckNotes {
    pub warnings: Vec<String>,
    pub notes: Vec<String>,
}

/// The command line's checks on `recordings` (the velocity given, else
/// the recordings' own, against the encoder; dead channels left out), then
/// `work` on the records they pass and the prediction at their velocity
/// with `harmonics` harmonics, in `pool` with the GIL released: `work`'s
/// answer and what the checks said.
#[allow(clippy::too_many_arguments)]
pub(crate) fn checked_run<'py, T: Send>(
    py: Python<'py>,
    recordings: &[PyRef<'py, PyRecording>],
    velocity_mm_s: Option<f64>,
    bearing: Option<&str>,
    pool: Option<&Bound<'py, ThreadPool>>,
    force_velocity: bool,
    harmonics: usize,
    work: impl FnOnce(&[Recording], &bearing::Prediction) -> ballpass::Result<T> + Send,
) -> PyResult<(T, CheckNotes)> {
    let (_, g) = bearing_args(bearing)?.resolve(None)?;
    let recs: Vec<Recording> = recordings.iter().map(|r| r.rec.clone()).collect();
    let stated = stated_velocity(&recs, velocity_mm_s)?;
    let pre = PreflightSettings {
        force_velocity,
        ..PreflightSettings::default()
    };
    pool::run(py, pool, || {
        let checked = preflight::check(recs, stated, &g, &pre)?;
        let prediction = g.predict(checked.velocity_mm_s, harmonics)?;
        let out = work(&checked.recordings, &prediction)?;
        Ok::<_, ballpass::Error>((
            out,
            CheckNotes {
                warnings: checked.warnings,
                notes: checked.notes,
            },
        ))
    })
    .map_err(errors::domain)
}

/// `analyze`'s results: `(analysis.json as a dict, correlations, spectra,
/// spectra_hires, spectra_unfiltered, spectra_position, sync_average)`.
type Tables<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyDict>,
    Bound<'py, PyDict>,
    Bound<'py, PyDict>,
    Bound<'py, PyDict>,
    Option<Bound<'py, PyDict>>,
    Option<Bound<'py, PyDict>>,
);

/// An analysis as [`Tables`].
fn results<'py>(py: Python<'py>, mut a: analysis::Analysis) -> PyResult<Tables<'py>> {
    let json = convert::serialize(py, &a)?;
    let spectra = spectra_columns(py, &a.spectra)?;
    let hires = spectra_columns(py, &a.spectra_hires)?;
    let unfiltered = spectra_columns(py, &a.spectra_unfiltered)?;
    let position = a
        .position
        .as_ref()
        .map(|p| {
            table(
                py,
                "freq_per_mm",
                &p.freq_per_mm,
                analysis::position::position_columns(p),
            )
        })
        .transpose()?;
    let sync = a
        .sync
        .as_ref()
        .map(|s| table(py, "phase", &s.phases(), s.csv_columns()))
        .transpose()?;
    // The correlations (the largest series, 2N - 1 points each) become the
    // arrays without a copy: the analysis is not used after this.
    let names: Vec<String> = export::correlation_columns(&a.correlations, a.settings.corr_norm)
        .into_iter()
        .map(|(name, _)| name)
        .collect();
    let corr = PyDict::new(py);
    corr.set_item(
        "lag_s",
        convert::array(py, std::mem::take(&mut a.correlations.lag_s)),
    )?;
    for (name, (_, v)) in names
        .into_iter()
        .zip(std::mem::take(&mut a.correlations.series))
    {
        corr.set_item(name, convert::array(py, v))?;
    }
    Ok((json, corr, spectra, hires, unfiltered, position, sync))
}

/// `ballpass.analyze` of one record file under `stream` (`auto`, `on`,
/// `off`), the command line's `--stream`: `(tables, None)` when the
/// record was analysed streamed (block by block, in memory that does not
/// grow with its length), `(None, warning)` when it is to be read whole
/// (the warning, if any, says why a long file could not be streamed).
/// The velocity is the one given, else the file's; a streamed record
/// cannot have it measured from the encoder.
#[pyfunction]
#[pyo3(signature = (path, stream, load=None, velocity_mm_s=None, settings=None, pool=None))]
fn analyze_file<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    stream: &str,
    load: Option<&str>,
    velocity_mm_s: Option<f64>,
    settings: Option<&str>,
    pool: Option<Bound<'py, ThreadPool>>,
) -> PyResult<(Option<Tables<'py>>, Option<String>)> {
    let s: AnalyzeSettings =
        convert::settings(&AnalyzeSettings::default(), settings, "analysis settings")?;
    s.validate().map_err(errors::domain)?;
    let mode = StreamMode::parse("stream", stream).map_err(errors::domain)?;
    let opts = LoadArgs::parse(load)?.options()?;
    let geometry = opts
        .geometry
        .ok_or_else(|| errors::value("load options: no bearing geometry"))?;
    const NAMING: Naming = Naming {
        stream: "stream",
        velocity: "velocity_mm_s",
    };
    let files = [path];
    let analysis = pool::run(py, pool.as_ref(), || {
        match stream_file::choose(&files, &opts, mode, None, NAMING)? {
            Choice::Whole(warning) => Ok(Err(warning)),
            Choice::Stream(mut src) => stream_file::analyze_streamed(
                &mut src,
                velocity_mm_s,
                &geometry,
                &s,
                NAMING,
                &mut |_| {},
            )
            .map(Ok),
        }
    })
    .map_err(errors::domain)?;
    match analysis {
        Ok(a) => Ok((Some(results(py, a)?), None)),
        Err(warning) => Ok((None, warning)),
    }
}

/// `ballpass.passages`: the optical ball passages of each recording, as
/// `ballpass passage` measures them: each recording cut to `window`
/// (`"T0:T1"`, seconds on its time axis, as `--window`), then the checks
/// before the analysis (dead channels left out; a velocity, given or the
/// recording's, checked against the encoder, or measured from it when none
/// is stated; `force_velocity` as `--force-velocity`), then the detection.
/// Returns `(passage.json as a dict, [passages.csv columns of each measured
/// record])`; a record that fails is listed in `failed`, and when all fail
/// the first failure is raised.
#[pyfunction]
#[pyo3(signature = (recordings, bearing=None, settings=None, pool=None, window=None, force_velocity=false))]
fn passages<'py>(
    py: Python<'py>,
    recordings: Vec<PyRef<'py, PyRecording>>,
    bearing: Option<&str>,
    settings: Option<&str>,
    pool: Option<Bound<'py, ThreadPool>>,
    window: Option<&str>,
    force_velocity: bool,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyList>)> {
    let (name, g) = bearing_args(bearing)?.resolve(None)?;
    let mut s: PassageSettings =
        convert::settings(&PassageSettings::default(), settings, "passage settings")?;
    s.geometry = Some(g);
    let window = window
        .map(Window::parse)
        .transpose()
        .map_err(errors::domain)?;
    let pre = PreflightSettings {
        force_velocity,
        ..PreflightSettings::default()
    };
    // The velocity given to this call guides the detection, as --velocity
    // does; a recording's own is stated to the checks.
    let explicit = s.velocity_mm_s;
    let recs: Vec<&Recording> = recordings.iter().map(|r| &r.rec).collect();
    let results = pool::run(py, pool.as_ref(), || {
        recs.iter()
            .map(|r| {
                let rec = match &window {
                    Some(w) => segment::window(r, w),
                    None => Ok((*r).clone()),
                };
                rec.and_then(|rec| {
                    let stated = explicit.or(rec.meta.velocity_mm_s);
                    checked_passages(rec, stated, explicit, &s, &g, &pre)
                })
                .map_err(|e| (r.source_name(), e))
            })
            .collect::<Vec<_>>()
    });
    let (mut done, mut failed, mut warnings) = (Vec::new(), Vec::new(), Vec::new());
    let mut first_error = None;
    for r in results {
        match r {
            Ok(c) => {
                warnings.extend(c.warnings);
                done.push(c.passages);
            }
            Err((record, e)) => {
                failed.push(PassageFailure {
                    record,
                    error: e.to_string(),
                });
                first_error.get_or_insert(e);
            }
        }
    }
    if done.is_empty() {
        return Err(match first_error {
            Some(e) => errors::domain(e),
            None => errors::value("no recordings given"),
        });
    }
    let tables = PyList::empty(py);
    for r in &done {
        tables.append(convert::columns(py, &passage_rows(r))?)?;
    }
    let out = PassageOutput {
        window,
        warnings,
        ..PassageOutput::new(name, done, failed)
    };
    Ok((convert::serialize(py, &out)?, tables))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(predict, m)?)?;
    m.add_function(wrap_pyfunction!(analyze, m)?)?;
    m.add_function(wrap_pyfunction!(analyze_file, m)?)?;
    m.add_function(wrap_pyfunction!(passages, m)?)?;
    Ok(())
}
