//! `ballpass._native`: the compiled half of the Python package `ballpass`.
//!
//! Glue only, like the command-line tool: every number comes from the
//! `ballpass` and `ballpass-dsp` crates. The Python modules
//! (`python/ballpass/`) give the public API: SciPy's signatures and argument
//! checks in `ballpass.signal`, keyword arguments and result objects in
//! `ballpass`. The functions here take resolved arguments and contiguous
//! float64 arrays, release the GIL while they compute, and return numpy
//! arrays and plain Python objects (results as their serde JSON values).

use pyo3::prelude::*;

mod analysis;
mod campaign;
mod convert;
mod errors;
mod model;
mod pool;
mod recording;
mod signal;

/// The compiled module `ballpass._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", ballpass::VERSION)?;
    signal::register(m)?;
    recording::register(m)?;
    analysis::register(m)?;
    campaign::register(m)?;
    model::register(m)?;
    pool::register(m)?;
    Ok(())
}
