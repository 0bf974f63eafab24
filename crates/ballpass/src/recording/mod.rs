//! The one way data enters an analysis: [`Recording`], validated on the way in.
//!
//! Loaders for the bench file formats live in [`io`] and all produce a
//! [`Recording`]; [`io::write_csv`] writes one back.

use std::fmt;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

pub mod inspect;
pub mod io;
pub mod profile;
pub mod request;
pub mod segment;
pub mod stream;

pub use io::{
    load, load_all, write_csv, write_mat, ChannelSource, Format, GapPolicy, LoadOptions,
    LoadOverrides, SourceOverride, TimeUnit,
};
pub use profile::Profile;
pub use request::{BearingRequest, LoadRequest};

/// The three measured channels of the testbed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Channel {
    /// Friction force from the quartz load cell, N.
    Friction,
    /// Stage position from the optical encoder, mm.
    Position,
    /// Photodetector voltage of the optical ball sensor, V.
    Optical,
}

impl Channel {
    /// All channels, in file-column order.
    pub const ALL: [Channel; 3] = [Channel::Friction, Channel::Position, Channel::Optical];

    /// Canonical column name with its unit (`friction_N`, `position_mm`, `optical_V`).
    pub fn column_name(self) -> &'static str {
        match self {
            Channel::Friction => "friction_N",
            Channel::Position => "position_mm",
            Channel::Optical => "optical_V",
        }
    }

    /// Unit symbol.
    pub fn unit(self) -> &'static str {
        match self {
            Channel::Friction => "N",
            Channel::Position => "mm",
            Channel::Optical => "V",
        }
    }

    /// Short name used in result tables (`friction`, `position`, `optical`).
    pub fn short_name(self) -> &'static str {
        match self {
            Channel::Friction => "friction",
            Channel::Position => "position",
            Channel::Optical => "optical",
        }
    }
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.column_name())
    }
}

/// What is known about a recording besides its samples.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Metadata {
    /// Commanded tracking velocity, mm/s, when known.
    pub velocity_mm_s: Option<f64>,
    /// Bearing name or catalog key, when known.
    pub bearing: Option<String>,
    /// Test identifier (e.g. repeat number or bench run id).
    pub test_id: Option<String>,
    /// File the recording was read from.
    pub source: Option<PathBuf>,
    /// Time of the first sample, s (from the time column; 0 when unknown).
    pub start_time_s: f64,
    /// What loading did to the numbers, in words: units converted, gaps
    /// filled, the record split (empty when it read them as they are).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// One bench recording: uniformly sampled channels plus metadata.
///
/// Any channel may be absent; analyses ask for what they need with
/// [`Recording::require`] and get an error that names the channel otherwise.
/// A `Recording` is only built through [`Recording::new`], which validates:
/// positive finite sampling rate, at least one channel, equal channel lengths,
/// at least [`Recording::MIN_SAMPLES`] samples, finite values within
/// ±[`Recording::MAX_ABS`].
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    fs_hz: f64,
    friction_n: Option<Vec<f64>>,
    position_mm: Option<Vec<f64>>,
    optical_v: Option<Vec<f64>>,
    len: usize,
    /// Metadata; free to edit after construction.
    pub meta: Metadata,
}

/// The channels to build a [`Recording`] from.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Channels {
    /// Friction force, N.
    pub friction_n: Option<Vec<f64>>,
    /// Stage position, mm.
    pub position_mm: Option<Vec<f64>>,
    /// Optical sensor, V.
    pub optical_v: Option<Vec<f64>>,
}

impl Recording {
    /// Fewest samples a recording may hold.
    pub const MIN_SAMPLES: usize = 16;

    /// Largest magnitude of a sample: far beyond any force in N, position in
    /// mm or voltage, and small enough that the analyses' sums of squares of
    /// a billion samples stay finite (a value near 1e307 would overflow them).
    pub const MAX_ABS: f64 = 1e100;

    /// Builds a validated recording.
    ///
    /// # Errors
    /// [`Error::InvalidSetting`] for a bad `fs_hz`; [`Error::InvalidChannel`]
    /// for no channels, unequal lengths, too few samples or a non-finite or
    /// out-of-range sample (naming the channel and the sample index).
    pub fn new(fs_hz: f64, channels: Channels, meta: Metadata) -> Result<Self> {
        let source_name = source_name(&meta);
        if !(fs_hz.is_finite() && fs_hz > 0.0) {
            return Err(Error::setting(
                "fs",
                format!(
                    "{source_name}: sampling rate must be a positive number of Hz, got {fs_hz}"
                ),
            ));
        }
        let present: Vec<(Channel, &Vec<f64>)> = [
            (Channel::Friction, &channels.friction_n),
            (Channel::Position, &channels.position_mm),
            (Channel::Optical, &channels.optical_v),
        ]
        .into_iter()
        .filter_map(|(c, v)| v.as_ref().map(|v| (c, v)))
        .collect();
        let Some(&(first, first_data)) = present.first() else {
            return Err(Error::InvalidChannel {
                channel: "any".into(),
                source_name,
                reason: "no channel found (expected friction_N, position_mm or optical_V)".into(),
            });
        };
        let len = first_data.len();
        for &(c, v) in &present {
            if v.len() != len {
                return Err(Error::InvalidChannel {
                    channel: c.column_name().into(),
                    source_name,
                    reason: format!(
                        "has {} samples but {} has {len}",
                        v.len(),
                        first.column_name()
                    ),
                });
            }
            // One pass in the common case: NaN fails the comparison too.
            if v.iter().fold(true, |ok, x| ok & (x.abs() <= Self::MAX_ABS)) {
                continue;
            }
            if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err(Error::InvalidChannel {
                    channel: c.column_name().into(),
                    source_name,
                    reason: format!("sample {i} is {x}; expected a finite number"),
                });
            }
            if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| x.abs() > Self::MAX_ABS) {
                return Err(Error::InvalidChannel {
                    channel: c.column_name().into(),
                    source_name,
                    reason: format!(
                        "sample {i} is {x:e}, beyond ±{:e}: far outside any measurement",
                        Self::MAX_ABS
                    ),
                });
            }
        }
        if len < Self::MIN_SAMPLES {
            return Err(Error::InvalidChannel {
                channel: first.column_name().into(),
                source_name,
                reason: format!("only {len} samples; at least {} needed", Self::MIN_SAMPLES),
            });
        }
        Ok(Self {
            fs_hz,
            friction_n: channels.friction_n,
            position_mm: channels.position_mm,
            optical_v: channels.optical_v,
            len,
            meta,
        })
    }

    /// Sampling rate, Hz.
    pub fn fs_hz(&self) -> f64 {
        self.fs_hz
    }

    /// Number of samples per channel.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Always false: a recording holds at least [`Recording::MIN_SAMPLES`] samples.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Duration covered, `len / fs`, s.
    pub fn duration_s(&self) -> f64 {
        self.len as f64 / self.fs_hz
    }

    /// Time of sample `i`, s.
    pub fn time_s(&self, i: usize) -> f64 {
        self.meta.start_time_s + i as f64 / self.fs_hz
    }

    /// The samples of one channel, if present.
    pub fn channel(&self, c: Channel) -> Option<&[f64]> {
        match c {
            Channel::Friction => self.friction_n.as_deref(),
            Channel::Position => self.position_mm.as_deref(),
            Channel::Optical => self.optical_v.as_deref(),
        }
    }

    /// The samples of one channel, or an error naming what needed it.
    ///
    /// # Errors
    /// [`Error::MissingChannel`] when the channel is absent.
    pub fn require(&self, c: Channel, needed_for: &'static str) -> Result<&[f64]> {
        self.channel(c).ok_or_else(|| Error::MissingChannel {
            channel: c.column_name(),
            source_name: self.source_name(),
            needed_for,
        })
    }

    /// Channels present, in canonical order.
    pub fn channels(&self) -> Vec<Channel> {
        Channel::ALL
            .into_iter()
            .filter(|&c| self.channel(c).is_some())
            .collect()
    }

    /// A name for messages: the source file, else the test id, else `recording`.
    pub fn source_name(&self) -> String {
        source_name(&self.meta)
    }
}

fn source_name(meta: &Metadata) -> String {
    if let Some(p) = &meta.source {
        crate::error::shown_path(p)
    } else if let Some(t) = &meta.test_id {
        crate::error::excerpt(t)
    } else {
        "recording".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ch(n: usize) -> Option<Vec<f64>> {
        Some((0..n).map(|i| i as f64).collect())
    }

    #[test]
    fn valid_recording_reports_its_shape() {
        let r = Recording::new(
            1000.0,
            Channels {
                friction_n: ch(100),
                optical_v: ch(100),
                ..Default::default()
            },
            Metadata::default(),
        )
        .unwrap();
        assert_eq!(r.len(), 100);
        assert!((r.duration_s() - 0.1).abs() < 1e-15);
        assert_eq!(r.channels(), vec![Channel::Friction, Channel::Optical]);
        let err = r.require(Channel::Position, "velocity error").unwrap_err();
        assert!(err.to_string().contains("position_mm is missing"), "{err}");
    }

    #[test]
    fn unequal_lengths_name_the_channel() {
        let err = Recording::new(
            1000.0,
            Channels {
                friction_n: ch(100),
                position_mm: ch(99),
                ..Default::default()
            },
            Metadata {
                source: Some("a.csv".into()),
                ..Default::default()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("a.csv") && err.contains("position_mm") && err.contains("99"),
            "{err}"
        );
    }

    #[test]
    fn non_finite_sample_is_rejected_with_index() {
        let mut v = ch(50).unwrap();
        v[7] = f64::NAN;
        let err = Recording::new(
            1000.0,
            Channels {
                optical_v: Some(v),
                ..Default::default()
            },
            Metadata::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("optical_V") && err.contains("sample 7"),
            "{err}"
        );
    }

    #[test]
    fn bad_rate_and_empty_are_rejected() {
        assert!(Recording::new(
            0.0,
            Channels {
                optical_v: ch(50),
                ..Default::default()
            },
            Metadata::default()
        )
        .is_err());
        assert!(Recording::new(1000.0, Channels::default(), Metadata::default()).is_err());
        assert!(Recording::new(
            1000.0,
            Channels {
                optical_v: ch(3),
                ..Default::default()
            },
            Metadata::default()
        )
        .is_err());
    }
}
