//! The friction → velocity-error spectra the stage is identified from:
//! one record's Welch auto- and cross-spectra (friction with its load-cell
//! discharge undone, velocity error from the encoder), their jackknife
//! groups and encoder check, and the pooling of several records.

use ballpass_dsp::{Complex64, WelchSettings};

use super::encoder::{self, EncoderPhases, Lattice};
use super::jackknife::{self, SegmentGroup};
use crate::analysis::load_cell::{restore_friction, DcRestoration, LoadCellCorrection};
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};

/// The friction → velocity-error spectra of one or more records, to be
/// pooled and fitted.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageSpectra {
    /// Sampling rate, Hz.
    pub fs_hz: f64,
    /// Bin frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Friction auto-spectrum (sum over records), N²/Hz.
    pub p_ff: Vec<f64>,
    /// Velocity-error auto-spectrum (sum), (m/s)²/Hz.
    pub p_vv: Vec<f64>,
    /// Cross spectrum `conj(F) V` (sum), N·(m/s)/Hz.
    pub p_fv: Vec<Complex64>,
    /// Records summed.
    pub records: usize,
    /// Equivalent segments (all records), for the error of `H1`.
    pub n_d: f64,
    /// Time constant of the load-cell discharge undone in the friction
    /// before these spectra were taken, s (`None`: friction as recorded).
    /// Pooled records with different ones keep the mean of `1/τ` (the
    /// restoration's deviation from 1 is linear in it).
    pub restored_tau_s: Option<f64>,
    /// The same spectra in [`GROUPS`](super::GROUPS) parts (segment `j` of each record
    /// into part `j mod GROUPS`; bins up to a quarter of the rate), for the
    /// jackknife that checks the fit's intervals (module `jackknife`);
    /// empty: no check.
    pub groups: Vec<SegmentGroup>,
    /// The check of the encoder's quantisation (module `encoder`): of the
    /// record whose quantisation is least spread by its motion; `None`
    /// when no counting encoder was found in the velocity error.
    pub encoder: Option<EncoderPhases>,
}

/// Segment length of the identification spectra for a record of `n`
/// samples: 16 s (a 1/16 Hz resolution for the slowest stages), at most a
/// quarter of the record, a power of two.
pub fn nperseg_for(n: usize, fs_hz: f64) -> usize {
    let want = (16.0 * fs_hz).min(n as f64 / 4.0).max(16.0);
    let mut p = 16usize;
    while (p * 2) as f64 <= want {
        p *= 2;
    }
    p
}

impl StageSpectra {
    /// The spectra of one record: `friction_n` (discharge undone),
    /// `velocity_error_mm_s` (centred difference of the encoder), both
    /// linearly detrended here, Hann segments of `nperseg` with half overlap.
    ///
    /// # Errors
    /// [`Error::Dsp`] if the Welch estimate rejects the signals.
    pub fn of(
        friction_n: &[f64],
        velocity_error_mm_s: &[f64],
        fs_hz: f64,
        nperseg: usize,
    ) -> Result<StageSpectra> {
        let mut f = friction_n.to_vec();
        let mut v: Vec<f64> = velocity_error_mm_s.iter().map(|x| x * 1e-3).collect();
        for s in [&mut f, &mut v] {
            ballpass_dsp::detrend_in_place(s, ballpass_dsp::DetrendType::Linear)
                .map_err(|e| Error::dsp("stage identification detrend", e))?;
        }
        // A segment no longer than the record, as the Welch estimate takes it.
        let nperseg = nperseg.min(f.len());
        let mut welch = jackknife::grouped_welch(nperseg)?;
        welch
            .push(&[&f, &v])
            .map_err(|e| Error::dsp("stage identification spectra", e))?;
        let out = StageSpectra::of_grouped(welch, fs_hz, nperseg)?;
        Ok(out)
    }

    /// The spectra and the jackknife's groups from a stream made by
    /// `jackknife::grouped_welch` and fed the detrended friction and
    /// velocity error (m/s).
    ///
    /// # Errors
    /// [`Error::Dsp`] if the stream has no complete segment.
    pub(crate) fn of_grouped(
        welch: ballpass_dsp::WelchStream,
        fs_hz: f64,
        nperseg: usize,
    ) -> Result<StageSpectra> {
        let (set, groups) = welch
            .finish_with_groups(fs_hz)
            .map_err(|e| Error::dsp("stage identification spectra", e))?;
        let mut out = StageSpectra::of_set(set, fs_hz, nperseg);
        out.groups = groups.into_iter().map(SegmentGroup::from_part).collect();
        Ok(out)
    }

    /// The Welch estimate of [`StageSpectra::of`]: Hann segments of
    /// `nperseg`, half overlap.
    pub(crate) fn welch_settings(nperseg: usize) -> WelchSettings {
        WelchSettings {
            nperseg,
            ..WelchSettings::default()
        }
    }

    /// The spectra of one record from the Welch estimate `set` of its
    /// detrended friction and velocity error (m/s), in that order, with
    /// their cross spectrum ([`StageSpectra::welch_settings`]).
    pub(crate) fn of_set(set: ballpass_dsp::SpectralSet, fs_hz: f64, nperseg: usize) -> Self {
        let w: Vec<f64> = (0..nperseg)
            .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / nperseg as f64).cos())
            .collect();
        let nu = crate::stats::welch_dof(&w, nperseg / 2, set.n_segments);
        let mut auto = set.auto.into_iter();
        StageSpectra {
            fs_hz,
            freq_hz: set.freq_hz,
            p_ff: auto.next().unwrap_or_default(),
            p_vv: auto.next().unwrap_or_default(),
            p_fv: set.cross.into_iter().next().unwrap_or_default(),
            records: 1,
            n_d: nu / 2.0,
            restored_tau_s: None,
            groups: Vec::new(),
            encoder: None,
        }
    }

    /// The spectra of a recording with friction and position channels
    /// (`None` without either): the friction with the load cell's discharge
    /// undone as `correction` says (`period_s` the predicted ball-pass
    /// period, for its estimate), the velocity error from the encoder by the
    /// centred difference.
    ///
    /// # Errors
    /// As [`StageSpectra::of`] and [`restore_friction`].
    pub fn of_recording(
        rec: &Recording,
        velocity_mm_s: f64,
        period_s: f64,
        correction: LoadCellCorrection,
    ) -> Result<Option<StageSpectra>> {
        let (Some(f), Some(p)) = (
            rec.channel(Channel::Friction),
            rec.channel(Channel::Position),
        ) else {
            return Ok(None);
        };
        let fs = rec.fs_hz();
        let (friction, dc) = restore_friction(f, fs, period_s, correction)?;
        let nperseg = nperseg_for(friction.len(), fs);
        StageSpectra::of_signals(&friction, p, fs, velocity_mm_s, nperseg)
            .map(|sp| Some(sp.restored_with(&dc)))
    }

    /// These spectra with the load cell's restoration `dc` recorded (the
    /// fit models what it did to the friction: module docs).
    #[must_use]
    pub fn restored_with(mut self, dc: &DcRestoration) -> StageSpectra {
        self.restored_tau_s = dc.tau_s.filter(|t| dc.applied && *t > 0.0);
        self
    }

    /// The spectra from a friction channel (discharge already undone) and
    /// the encoder position (mm): the velocity error by the centred
    /// difference.
    ///
    /// # Errors
    /// As [`StageSpectra::of`].
    pub fn of_signals(
        friction_n: &[f64],
        position_mm: &[f64],
        fs_hz: f64,
        velocity_mm_s: f64,
        nperseg: usize,
    ) -> Result<StageSpectra> {
        let v: Vec<f64> =
            ballpass_dsp::gradient(position_mm, ballpass_dsp::Spacing::Uniform(1.0 / fs_hz))
                .map_err(|e| Error::dsp("stage identification velocity", e))?
                .into_iter()
                .map(|x| x - velocity_mm_s)
                .collect();
        // The check takes m/s: scaled a block at a time, not copied whole.
        let mut lattice = Lattice::new(v.len());
        let mut block = Vec::with_capacity(4096);
        for part in v.chunks(4096) {
            block.clear();
            block.extend(part.iter().map(|x| x * 1e-3));
            lattice.push(&block);
        }
        let mut out = StageSpectra::of(friction_n, &v, fs_hz, nperseg)?;
        out.encoder = lattice.phases(velocity_mm_s * 1e-3);
        Ok(out)
    }

    /// Adds another record's spectra on the same grid; `false` (nothing
    /// added) when the grid differs.
    pub fn add(&mut self, other: &StageSpectra) -> bool {
        if self.records == 0 {
            *self = other.clone();
            return true;
        }
        if other.fs_hz != self.fs_hz || other.freq_hz != self.freq_hz {
            return false;
        }
        for (a, b) in self.p_ff.iter_mut().zip(&other.p_ff) {
            *a += b;
        }
        for (a, b) in self.p_vv.iter_mut().zip(&other.p_vv) {
            *a += b;
        }
        for (a, b) in self.p_fv.iter_mut().zip(&other.p_fv) {
            *a += b;
        }
        jackknife::add_groups(&mut self.groups, &other.groups);
        self.encoder = encoder::worse(self.encoder, other.encoder);
        let rate = |s: &StageSpectra| s.restored_tau_s.map_or(0.0, |t| 1.0 / t);
        let (a, b) = (self.records as f64, other.records as f64);
        let mean_rate = (rate(self) * a + rate(other) * b) / (a + b);
        self.restored_tau_s = (mean_rate > 0.0).then(|| 1.0 / mean_rate);
        self.records += other.records;
        self.n_d += other.n_d;
        true
    }
}
