#![doc = include_str!("../README.md")]

mod biquad;
pub mod correlate;
pub mod correlate_window;
pub mod decimate;
pub mod detrend;
pub mod error;
mod fftplan;
pub mod filtfilt_stream;
pub mod fir;
pub mod gradient;
pub mod iir;
pub mod lfilter_fast;
pub mod lsq;
pub mod lti;
mod npcomplex;
pub mod peaks;
pub mod segment_power;
mod simd;
mod sincos;
pub mod sos;
pub mod spectral;
#[cfg(test)]
mod test_noise;
pub mod welch_stream;
pub mod window;
pub mod zoom;

pub use correlate::{
    correlate, correlation_lags, CorrelateSettings, Correlation, Correlator, Normalization,
};
pub use correlate_window::{correlate_pairs_window, WindowCorrelation};
pub use decimate::{decimate, DecimateSettings, Decimator};
pub use detrend::{detrend, detrend_in_place, DetrendType};
pub use error::{check_finite, invalid, DspError, Result};
pub use filtfilt_stream::ZeroPhaseStream;
pub use fir::correlate_valid;
pub use gradient::{gradient, gradient_with_edge_order, EdgeOrder, Spacing};
pub use iir::{
    butter, butter_zpk, cheby1, cheby1_zpk, zpk2sos, ButterSettings, Cheby1Settings, FilterBand,
    Zpk,
};
pub use lfilter_fast::lfilter_fast;
pub use lsq::{least_squares, Fit, FnProblem, LeastSquares, Problem, Termination};
pub use lti::{
    bode, freqs, freqs_values, freqz, freqz_values, freqz_values_scipy_grid, sosfreqz,
    sosfreqz_values, unwrap, AnalogResponse, Bode, DigitalResponse,
};
pub use peaks::{
    find_peaks, peak_prominences, peak_widths, peak_widths_with_prominences, Bound,
    FindPeaksSettings, PeakProperties, PeakWidthsSettings, Peaks, Prominences, Widths,
};
/// Complex numbers used in spectra, frequency responses and pole-zero lists
/// (re-exported from `num_complex` via `rustfft`).
pub use rustfft::num_complex::Complex64;
pub use segment_power::segment_powers;
pub use sos::{
    lfilter, lfilter_with_state, lfilter_zi, sosfilt, sosfilt_fast, sosfilt_fast_with_state,
    sosfilt_with_state, sosfilt_zi, sosfiltfilt, FiltFiltSettings, LfilterOutput, PadLen, PadType,
    Sos, SosOutput, ZeroPhaseFilter,
};
pub use spectral::{
    coherence, csd, periodogram, welch, Average, Coherence, Csd, PeriodogramSettings, Psd, Scaling,
    SpectralSet, Welch, WelchSettings,
};
pub use welch_stream::WelchStream;
pub use window::Window;
pub use zoom::{polyphase_average_csd, polyphase_average_psd};
