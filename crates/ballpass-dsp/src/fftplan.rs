//! FFT plans shared within a thread.
//!
//! A real FFT plan of length `n` holds its twiddle factors (`n` sines and
//! cosines) and its algorithm choice; building one costs about as much as a
//! few transforms. The plans are immutable and the planner picks the same
//! algorithm for a length every time, so a thread keeps one planner and
//! every Welch engine and correlator of that thread reuses its plans (a
//! campaign's worker threads plan each length once, not once per record).
//! The transforms are bit for bit those of a fresh plan.

use std::cell::RefCell;
use std::sync::Arc;

use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

thread_local! {
    static PLANNER: RefCell<RealFftPlanner<f64>> = RefCell::new(RealFftPlanner::new());
    static COMPLEX_PLANNER: RefCell<FftPlanner<f64>> = RefCell::new(FftPlanner::new());
}

/// The forward real FFT of length `len` (cached per thread).
pub(crate) fn forward(len: usize) -> Arc<dyn RealToComplex<f64>> {
    PLANNER.with(|p| p.borrow_mut().plan_fft_forward(len))
}

/// The inverse real FFT of length `len` (cached per thread).
pub(crate) fn inverse(len: usize) -> Arc<dyn ComplexToReal<f64>> {
    PLANNER.with(|p| p.borrow_mut().plan_fft_inverse(len))
}

/// The forward complex FFT of length `len` (cached per thread).
pub(crate) fn complex_forward(len: usize) -> Arc<dyn Fft<f64>> {
    COMPLEX_PLANNER.with(|p| p.borrow_mut().plan_fft_forward(len))
}
