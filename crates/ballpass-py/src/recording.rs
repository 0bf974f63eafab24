//! `Recording`, `load` and `simulate`: the one way data enters an analysis,
//! from numpy arrays, from a file with the command line's mapping options,
//! or from the testbed simulator.

use std::path::PathBuf;

use ballpass::bearing::{self, Geometry};
use ballpass::recording::profile::{parse_delimiter, GeometryOverride};
use ballpass::recording::{self as rec, Channel, Channels, LoadOptions, Metadata, Profile};
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
/// flags, by their Python names); `None` or absent: the profile's value,
/// else the default.
#[derive(Debug, Default, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LoadArgs {
    profile: Option<PathBuf>,
    format: Option<serde_json::Value>,
    delimiter: Option<String>,
    fs_hz: Option<f64>,
    time_col: Option<String>,
    ignore_time: bool,
    friction_col: Option<String>,
    position_col: Option<String>,
    optical_col: Option<String>,
    friction_scale: Option<f64>,
    friction_offset: Option<f64>,
    position_scale: Option<f64>,
    position_offset: Option<f64>,
    optical_scale: Option<f64>,
    optical_offset: Option<f64>,
    velocity_mm_s: Option<f64>,
    test_id: Option<String>,
    min_periods: Option<f64>,
    #[serde(flatten)]
    pub bearing: BearingArgs,
}

/// Which bearing: a catalog key, a custom geometry over it, or both.
#[derive(Debug, Default, Clone, Deserialize)]
#[serde(default)]
pub struct BearingArgs {
    pub bearing: Option<String>,
    pub ball_diameter_mm: Option<f64>,
    pub free_space_mm: Option<f64>,
    pub balls_in_race: Option<u32>,
}

/// The catalog key used when neither an argument nor a profile names a
/// bearing (as on the command line).
pub const DEFAULT_BEARING: &str = "sr25w";

impl BearingArgs {
    /// `(name, geometry)`: the catalog entry of `bearing`, else `fallback`,
    /// else sr25w; with the given fields overriding its geometry (the name
    /// then says `(custom geometry)`).
    pub fn resolve(&self, fallback: Option<(String, Geometry)>) -> PyResult<(String, Geometry)> {
        let from_catalog = |key: &str| -> PyResult<(String, Geometry)> {
            let e = bearing::lookup(key).ok_or_else(|| {
                let keys: Vec<_> = bearing::CATALOG.iter().map(|e| e.key).collect();
                errors::value(format!(
                    "unknown bearing {key:?} (catalog: {})",
                    keys.join(", ")
                ))
            })?;
            Ok((e.name.to_string(), e.geometry))
        };
        let (name, base) = match (&self.bearing, fallback) {
            (Some(key), _) => from_catalog(key)?,
            (None, Some(f)) => f,
            (None, None) => from_catalog(DEFAULT_BEARING)?,
        };
        let over = GeometryOverride {
            ball_diameter_mm: self.ball_diameter_mm,
            free_space_mm: self.free_space_mm,
            balls_in_race: self.balls_in_race,
        };
        let g = over.apply(base).map_err(errors::domain)?;
        let custom = !over.is_empty() && !name.ends_with("(custom geometry)");
        Ok((
            if custom {
                format!("{name} (custom geometry)")
            } else {
                name
            },
            g,
        ))
    }
}

impl LoadArgs {
    /// Parses the JSON of the keyword arguments.
    pub fn parse(json: Option<&str>) -> PyResult<Self> {
        match json {
            None => Ok(Self::default()),
            Some(t) => {
                serde_json::from_str(t).map_err(|e| errors::value(format!("load options: {e}")))
            }
        }
    }

    /// Load options: defaults, then the profile, then the arguments given;
    /// the bearing resolved (argument, profile, sr25w) and validated.
    pub fn options(&self) -> PyResult<LoadOptions> {
        let mut o = match &self.profile {
            Some(p) => Profile::read(p)
                .and_then(|p| p.load_options())
                .map_err(errors::domain)?,
            None => LoadOptions::default(),
        };
        if let Some(f) = &self.format {
            o.format = Some(
                serde_json::from_value(f.clone())
                    .map_err(|e| errors::value(format!("invalid format {f}: {e}")))?,
            );
        }
        if let Some(d) = &self.delimiter {
            o.delimiter = Some(parse_delimiter(d).map_err(errors::domain)?);
        }
        rec::LoadOverrides {
            fs_hz: self.fs_hz,
            time: self.time_col.clone(),
            ignore_time: self.ignore_time,
            sources: [
                (
                    &self.friction_col,
                    self.friction_scale,
                    self.friction_offset,
                ),
                (
                    &self.position_col,
                    self.position_scale,
                    self.position_offset,
                ),
                (&self.optical_col, self.optical_scale, self.optical_offset),
            ]
            .map(|(name, scale, offset)| rec::SourceOverride {
                name: name.clone(),
                scale,
                offset,
            }),
            velocity_mm_s: self.velocity_mm_s,
            test_id: self.test_id.clone(),
            min_periods: self.min_periods,
        }
        .apply(&mut o);
        let (name, g) = self.bearing.resolve(o.bearing_fallback())?;
        o.bearing = Some(name);
        o.geometry = Some(g);
        o.validate().map_err(errors::domain)?;
        Ok(o)
    }

    /// The velocity given as an argument (not the profile's or the file's).
    pub fn velocity_mm_s(&self) -> Option<f64> {
        self.velocity_mm_s
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
