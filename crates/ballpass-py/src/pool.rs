//! Worker threads: a [`ThreadPool`] object owns a rayon pool of a fixed
//! size, and every domain function runs its parallel work in the pool it is
//! given, else in rayon's default pool (one thread per core, or
//! `RAYON_NUM_THREADS`). Nothing global is set: the Python layer passes the
//! pool of the call (`threads=`) or of the enclosing `ballpass.threads(n)`
//! block, so many worker processes on one machine need not oversubscribe.

use std::sync::Arc;

use pyo3::prelude::*;

use crate::errors;

/// A pool of worker threads for ballpass' parallel work.
#[pyclass(module = "ballpass._native", frozen)]
pub struct ThreadPool {
    pool: Arc<rayon::ThreadPool>,
    threads: usize,
}

#[pymethods]
impl ThreadPool {
    /// A pool of `threads` worker threads (at least 1).
    #[new]
    fn new(threads: usize) -> PyResult<Self> {
        if threads == 0 {
            return Err(errors::value("threads must be at least 1, got 0"));
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("ballpass-{i}"))
            .build()
            .map_err(|e| errors::value(format!("cannot start {threads} threads: {e}")))?;
        Ok(Self {
            pool: Arc::new(pool),
            threads,
        })
    }

    /// Number of worker threads.
    #[getter]
    fn threads(&self) -> usize {
        self.threads
    }

    fn __repr__(&self) -> String {
        format!("ThreadPool(threads={})", self.threads)
    }
}

/// Runs `work` without the GIL, in `pool` when one is given.
pub fn run<T: Send>(
    py: Python<'_>,
    pool: Option<&Bound<'_, ThreadPool>>,
    work: impl FnOnce() -> T + Send,
) -> T {
    match pool {
        Some(p) => {
            let p = Arc::clone(&p.get().pool);
            py.detach(move || p.install(work))
        }
        None => py.detach(work),
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<ThreadPool>()
}
