#![doc = include_str!("../README.md")]

pub mod error;
pub mod lsq;
pub mod peaks;

pub use error::{check_finite, invalid, DspError, Result};
pub use lsq::{least_squares, Fit, FnProblem, LeastSquares, Problem, Termination};
pub use peaks::{
    find_peaks, peak_prominences, peak_widths, peak_widths_with_prominences, Bound,
    FindPeaksSettings, PeakProperties, PeakWidthsSettings, Peaks, Prominences, Widths,
};
