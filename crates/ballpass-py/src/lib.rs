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

/// The extension's own allocations (kernel scratch, result arrays handed to
/// numpy) come from mimalloc, which keeps freed pages for reuse. With the
/// host's glibc malloc every block above its mmap threshold (the
/// correlation and spectrum buffers, 0.5-1 MB each) is mapped and zeroed
/// by the kernel anew on every call: measured, a full 30 000-sample
/// correlation took 3.9 ms that way and 0.9 ms with reuse. The command
/// line gets the same reuse from `mallopt` (ballpass-cli's `malloc`
/// module); an extension must not change its host's malloc, so it brings
/// its own allocator for its own blocks only (numpy's and Python's
/// allocations are untouched).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod analysis;
mod campaign;
mod compensate;
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
    compensate::register(m)?;
    model::register(m)?;
    pool::register(m)?;
    Ok(())
}
