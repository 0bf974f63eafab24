//! Signal and stage models of thesis chapter 6, with the corrections of docs/methods.md
//! §2–7: the sinusoid model signals and their analytic correlations and
//! spectra ([`signals`]), rectangular and Gaussian pulse trains with their
//! exact Fourier coefficients ([`pulse_train`]), and the PD-controlled stage
//! with its frequency responses and predicted velocity ([`stage`]); and
//! all three evaluated on grids as the tables `ballpass model` writes
//! ([`tables`]).

pub mod compensate;
pub mod identify;
pub mod pulse_train;
pub mod signals;
pub mod stage;
pub mod tables;

pub use pulse_train::{GaussianTrain, RectangularCoefficients, RectangularTrain};
pub use signals::{LagConvention, ModelSignal, SinusoidModel};
pub use stage::{
    difference_responses, velocity_response, BodeRow, DifferenceRow, FrequencyAxis, HarmonicRow,
    LoopFeatures, PdLoop, VelocityResponse, VelocityResponseSettings,
};
pub use tables::{
    pulses_tables, signals_tables, stage_tables, PulsesTableSettings, PulsesTables, RatioKind,
    SignalsTableSettings, SignalsTables, StageTableSettings, StageTables,
};
