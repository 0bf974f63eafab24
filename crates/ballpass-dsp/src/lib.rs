#![doc = include_str!("../README.md")]

pub mod correlate;
pub mod detrend;
pub mod error;
pub mod spectral;
pub mod window;
pub mod zoom;

pub use correlate::{
    correlate, correlation_lags, CorrelateSettings, Correlation, Correlator, Normalization,
};
pub use detrend::{detrend, detrend_in_place, DetrendType};
pub use error::{check_finite, invalid, DspError, Result};
pub use spectral::{
    coherence, csd, periodogram, welch, Average, Coherence, Complex64, Csd, PeriodogramSettings,
    Psd, Scaling, Welch, WelchSettings,
};
pub use window::Window;
pub use zoom::{polyphase_average_csd, polyphase_average_psd};
