//! `Recording`, `load` and `simulate`: the one way data enters an analysis,
//! from numpy arrays, from a file with the command line's mapping options,
//! or from the testbed simulator.

use std::path::PathBuf;

use ballpass::bearing::Geometry;
use ballpass::recording::{self as rec, Channel, Channels, LoadOptions, Metadata};
use ballpass::recording::{BearingRequest, LoadRequest};
use ballpass::sim::{self, SimSettings};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::Deserialize;

use crate::convert;
use crate::errors;

/// One bench recording: uniformly sampled channels (float64 arrays) and
/// metadata. Built from arrays (`Recording(fs_hz, friction_n=...)`), by
/// `ballpass.load` or by `ballpass.simulate`.
#[pyclass(module = "ballpass._native", name = "Recording")]
pub struct PyRecording {
    pub rec: rec::Recording,
}

/// `numpy.asarray(x, dtype=float64)` flattened to a vector; `None` stays
/// `None`. A 2-D or complex array is a `ValueError` naming `what`.
fn samples(py: Python<'_>, x: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Option<Vec<f64>>> {
    let Some(x) = x.filter(|x| !x.is_none()) else {
        return Ok(None);
    };
    let np = py.import("numpy")?;
    if np.call_method1("iscomplexobj", (x,))?.extract::<bool>()? {
        return Err(errors::value(format!(
            "{what}: complex samples; expected real numbers"
        )));
    }
    let kw = PyDict::new(py);
    kw.set_item("dtype", np.getattr("float64")?)?;
    let a = np.call_method("asarray", (x,), Some(&kw))?;
    let a = a
        .cast_into::<PyArray1<f64>>()
        .map_err(|_| errors::value(format!("{what}: expected a 1-D sequence of numbers")))?;
    Ok(Some(a.readonly().as_array().to_vec()))
}

fn channel_array<'py>(
    py: Python<'py>,
    r: &rec::Recording,
    c: Channel,
) -> Option<Bound<'py, PyArray1<f64>>> {
    r.channel(c).map(|v| PyArray1::from_slice(py, v))
}

#[pymethods]
impl PyRecording {
    /// A validated recording from arrays: `fs_hz` in Hz, `friction_n` in N,
    /// `position_mm` in mm, `optical_v` in V (any may be `None`, not all).
    #[new]
    #[pyo3(signature = (fs_hz, friction_n=None, position_mm=None, optical_v=None, *, velocity_mm_s=None, bearing=None, test_id=None, source=None, start_time_s=0.0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        fs_hz: f64,
        friction_n: Option<&Bound<'_, PyAny>>,
        position_mm: Option<&Bound<'_, PyAny>>,
        optical_v: Option<&Bound<'_, PyAny>>,
        velocity_mm_s: Option<f64>,
        bearing: Option<String>,
        test_id: Option<String>,
        source: Option<PathBuf>,
        start_time_s: f64,
    ) -> PyResult<Self> {
        let channels = Channels {
            friction_n: samples(py, friction_n, "friction_n")?,
            position_mm: samples(py, position_mm, "position_mm")?,
            optical_v: samples(py, optical_v, "optical_v")?,
        };
        let meta = Metadata {
            velocity_mm_s,
            bearing,
            test_id,
            source,
            start_time_s,
            notes: Vec::new(),
        };
        let rec = rec::Recording::new(fs_hz, channels, meta).map_err(errors::domain)?;
        Ok(Self { rec })
    }

    /// Sampling rate, Hz.
    #[getter]
    fn fs_hz(&self) -> f64 {
        self.rec.fs_hz()
    }

    /// Friction force, N (a copy), or `None`.
    #[getter]
    fn friction_n<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        channel_array(py, &self.rec, Channel::Friction)
    }

    /// Stage position, mm (a copy), or `None`.
    #[getter]
    fn position_mm<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        channel_array(py, &self.rec, Channel::Position)
    }

    /// Optical sensor, V (a copy), or `None`.
    #[getter]
    fn optical_v<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        channel_array(py, &self.rec, Channel::Optical)
    }

    /// Sample times, s: `start_time_s + i / fs_hz`.
    #[getter]
    fn time_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let t: Vec<f64> = (0..self.rec.len()).map(|i| self.rec.time_s(i)).collect();
        convert::array(py, t)
    }

    /// Duration, `len / fs_hz`, s.
    #[getter]
    fn duration_s(&self) -> f64 {
        self.rec.duration_s()
    }

    /// Channels present, by column name (`friction_N`, `position_mm`, `optical_V`).
    #[getter]
    fn channels(&self) -> Vec<&'static str> {
        self.rec
            .channels()
            .into_iter()
            .map(Channel::column_name)
            .collect()
    }

    /// Commanded tracking velocity, mm/s, when known.
    #[getter]
    fn velocity_mm_s(&self) -> Option<f64> {
        self.rec.meta.velocity_mm_s
    }

    #[setter]
    fn set_velocity_mm_s(&mut self, v: Option<f64>) {
        self.rec.meta.velocity_mm_s = v;
    }

    /// Bearing name, when known.
    #[getter]
    fn bearing(&self) -> Option<String> {
        self.rec.meta.bearing.clone()
    }

    #[setter]
    fn set_bearing(&mut self, v: Option<String>) {
        self.rec.meta.bearing = v;
    }

    /// Test identifier, when known.
    #[getter]
    fn test_id(&self) -> Option<String> {
        self.rec.meta.test_id.clone()
    }

    #[setter]
    fn set_test_id(&mut self, v: Option<String>) {
        self.rec.meta.test_id = v;
    }

    /// File the recording was read from, when any.
    #[getter]
    fn source(&self) -> Option<String> {
        self.rec
            .meta
            .source
            .as_ref()
            .map(|p| p.display().to_string())
    }

    /// Time of the first sample, s.
    #[getter]
    fn start_time_s(&self) -> f64 {
        self.rec.meta.start_time_s
    }

    /// The name used in messages and results: the source file, else the
    /// test id, else `recording`.
    #[getter]
    fn name(&self) -> String {
        self.rec.source_name()
    }

    fn __len__(&self) -> usize {
        self.rec.len()
    }

    fn __repr__(&self) -> String {
        let channels: Vec<String> = self.channels().iter().map(|c| format!("'{c}'")).collect();
        let velocity = self
            .rec
            .meta
            .velocity_mm_s
            .map_or("None".to_string(), |v| format!("{v:?}"));
        format!(
            "Recording('{}', fs_hz={:?}, samples={}, channels=[{}], velocity_mm_s={velocity})",
            self.rec.source_name(),
            self.rec.fs_hz(),
            self.rec.len(),
            channels.join(", "),
        )
    }

    /// Writes the recording as canonical CSV (`time_s, friction_N,
    /// position_mm, optical_V`), atomically.
    fn to_csv(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let r = &self.rec;
        py.detach(|| rec::write_csv(r, &path))
            .map_err(errors::domain)
    }

    /// Writes the recording as a MATLAB level-5 MAT-file, atomically.
    fn to_mat(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let r = &self.rec;
        py.detach(|| rec::write_mat(r, &path))
            .map_err(errors::domain)
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let this = slf.borrow();
        let r = &this.rec;
        let m = &r.meta;
        let ctor = py.import("ballpass._native")?.getattr("Recording")?;
        let kwargs = PyDict::new(py);
        kwargs.set_item("velocity_mm_s", m.velocity_mm_s)?;
        kwargs.set_item("bearing", m.bearing.clone())?;
        kwargs.set_item("test_id", m.test_id.clone())?;
        kwargs.set_item("source", m.source.clone())?;
        kwargs.set_item("start_time_s", m.start_time_s)?;
        let args = (
            r.fs_hz(),
            channel_array(py, r, Channel::Friction),
            channel_array(py, r, Channel::Position),
            channel_array(py, r, Channel::Optical),
        );
        let partial = py.import("functools")?.getattr("partial")?;
        let f = partial.call((ctor,), Some(&kwargs))?;
        (f, args).into_pyobject(py).map(|t| t.into_any())
    }
}

/// The keyword arguments of `ballpass.load` (the command line's input
/// flags, by their Python names: the library's [`LoadRequest`]); `None` or
/// absent: the profile's value, else the default.
#[derive(Debug, Default)]
pub struct LoadArgs(LoadRequest);

/// Which bearing: a catalog key, a custom geometry over it, or both.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(transparent)]
pub struct BearingArgs(BearingRequest);

impl BearingArgs {
    /// `(name, geometry)`: the catalog entry of `bearing`, else `fallback`,
    /// else sr25w; with the given fields overriding its geometry (the name
    /// then says `(custom geometry)`).
    pub fn resolve(&self, fallback: Option<(String, Geometry)>) -> PyResult<(String, Geometry)> {
        self.0.resolve(fallback).map_err(errors::domain)
    }
}

impl LoadArgs {
    /// Parses the JSON of the keyword arguments.
    pub fn parse(json: Option<&str>) -> PyResult<Self> {
        match json {
            None => Ok(Self::default()),
            Some(t) => serde_json::from_str(t)
                .map(Self)
                .map_err(|e| errors::value(format!("load options: {e}"))),
        }
    }

    /// Load options: defaults, then the profile, then the arguments given;
    /// the bearing resolved (argument, profile, sr25w) and validated.
    pub fn options(&self) -> PyResult<LoadOptions> {
        self.0.options().map_err(errors::domain)
    }

    /// The velocity given as an argument (not the profile's or the file's).
    pub fn velocity_mm_s(&self) -> Option<f64> {
        self.0.velocity_mm_s
    }
}

/// `ballpass.load(path, **options)`: one recording file (CSV/TSV/MAT) read
/// with the command line's mapping options.
#[pyfunction]
#[pyo3(signature = (path, options=None))]
fn load(py: Python<'_>, path: PathBuf, options: Option<&str>) -> PyResult<PyRecording> {
    let o = LoadArgs::parse(options)?.options()?;
    let r = py.detach(|| rec::load(&path, &o)).map_err(errors::domain)?;
    Ok(PyRecording { rec: r })
}

/// `ballpass.simulate`: a bench recording from the testbed simulator and
/// its truth (as the truth file's JSON). `settings` is merged onto the
/// simulator's defaults; the other arguments override it as the command
/// line's flags do.
#[pyfunction]
#[pyo3(signature = (settings=None, velocity_mm_s=None, bearing=None, condition=None, seed=None))]
fn simulate<'py>(
    py: Python<'py>,
    settings: Option<&str>,
    velocity_mm_s: Option<f64>,
    bearing: Option<&str>,
    condition: Option<&str>,
    seed: Option<u64>,
) -> PyResult<(PyRecording, Bound<'py, PyAny>)> {
    let mut s: SimSettings =
        convert::settings(&SimSettings::default(), settings, "simulator settings")?;
    if let Some(key) = bearing {
        let b = SimSettings::for_bearing(key, s.velocity_mm_s).map_err(errors::domain)?;
        s.bearing = b.bearing;
        s.geometry = b.geometry;
    }
    if let Some(v) = velocity_mm_s {
        s.velocity_mm_s = v;
    }
    if let Some(c) = condition {
        s.condition = serde_json::from_value(serde_json::Value::String(c.to_string()))
            .map_err(|e| errors::value(format!("invalid condition {c:?}: {e}")))?;
    }
    if let Some(seed) = seed {
        s.seed = seed;
    }
    let sim = py.detach(|| sim::simulate(&s)).map_err(errors::domain)?;
    let truth = convert::serialize(py, &sim.truth)?;
    Ok((PyRecording { rec: sim.recording }, truth))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRecording>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    Ok(())
}
