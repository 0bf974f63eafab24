//! One record's runs on the position grid: the runs of one direction, the
//! fine grid's step, the resampling of the signals onto it and the
//! decimation to `2 d_avg / 64` (the module docs' steps before Welch).

use ballpass_dsp::{gradient, DecimateSettings, Decimator, Spacing, ZeroPhaseFilter};

use super::walk::{resample, Walk, SHARED_WALK_MAX_SAMPLES};
use super::{AnalyzeSettings, DirectionRun, Signal, POINTS_PER_PERIOD, STOP_FRACTION};
use crate::error::{Error, Result};
use crate::recording::{Channel, Recording};
use crate::stats::median;

/// One record's runs resampled on the common grid.
pub(super) struct Resampled {
    /// Each run, with its friction (if any) and velocity error on the grid
    /// when it was long enough to resample.
    pub runs: Vec<(DirectionRun, Option<Series>)>,
}

/// Signals on the position grid.
pub(super) type Series = Vec<(Signal, Vec<f64>)>;

/// Index ranges of the runs of one direction above `v_stop`.
pub(super) fn direction_runs(v: &[f64], v_stop: f64) -> Vec<(usize, usize, bool)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < v.len() {
        if v[i].abs() < v_stop {
            i += 1;
            continue;
        }
        let fwd = v[i] > 0.0;
        let start = i;
        while i < v.len() && v[i].abs() >= v_stop && (v[i] > 0.0) == fwd {
            i += 1;
        }
        out.push((start, i, fwd));
    }
    out
}

/// Centred moving average over `w` points (odd); the ends, where the
/// window is not full, are dropped: the output is `len − w + 1` long.
pub(super) fn moving_average_valid(x: &[f64], w: usize) -> Vec<f64> {
    if x.len() < w {
        return Vec::new();
    }
    let mut s: f64 = x[..w].iter().sum();
    let mut out = Vec::with_capacity(x.len() - w + 1);
    out.push(s / w as f64);
    for i in w..x.len() {
        s += x[i] - x[i - w];
        out.push(s / w as f64);
    }
    out
}

/// Decimates by `q` (a power of two) in stages of at most 8.
fn decimate_pow2(mut x: Vec<f64>, mut q: usize, what: &str) -> Result<Vec<f64>> {
    while q > 1 {
        let step = q.min(8);
        let d = Decimator::new(DecimateSettings {
            q: step,
            ..DecimateSettings::default()
        })
        .map_err(|e| Error::dsp(format!("{what}: position-domain decimator"), e))?;
        x = d
            .apply(&x)
            .map_err(|e| Error::dsp(format!("{what}: position-domain decimation"), e))?;
        q /= step;
    }
    Ok(x)
}

/// The stop speed `STOP_FRACTION · median|v|` and the fine grid's factor
/// `q` (module docs) from the median speed `med` of a record at `fs`.
///
/// # Errors
/// [`Error::InvalidRecording`] when the median speed is not positive.
pub(crate) fn grid_step(
    name: &str,
    med: f64,
    fs: f64,
    settings: &AnalyzeSettings,
    dx: f64,
) -> Result<(f64, usize)> {
    if med.is_nan() || med <= 0.0 {
        return Err(Error::InvalidRecording {
            source_name: name.into(),
            reason: "the stage does not move (median speed 0): no position-domain spectrum".into(),
        });
    }
    let v_stop = STOP_FRACTION * med;
    let f_b = settings.lowpass_hz.unwrap_or(fs / 2.0).min(fs / 2.0);
    // Fine spacing dx/q ≤ v_stop / (2 f_b): alias-free at every kept speed.
    let mut q = 1usize;
    while dx / q as f64 > v_stop / (2.0 * f_b) {
        q *= 2;
    }
    Ok((v_stop, q))
}

/// Shortest stretch (fine points) the zero-phase decimation stages take:
/// SciPy's `padlen` of an order-8 Chebyshev in 4 sections is 27 per stage.
const MIN_FINE_POINTS: usize = 64;

/// Signals of one record over the samples analysed, already low-passed
/// with the analysis' filter (before any detrend): what the analysis'
/// own preparation made of the friction and optical channels, so that
/// they are not filtered twice ([`super::compute_lowpassed`]).
pub(crate) type Lowpassed = [(Signal, Vec<f64>)];

/// Resamples one record's friction and velocity on the grid `dx` (module
/// docs); `given`: signals already low-passed (the others are low-passed
/// here).
#[allow(clippy::too_many_arguments)]
pub(super) fn resample_record(
    rec: &Recording,
    range: std::ops::Range<usize>,
    friction: Option<&[f64]>,
    given: Option<&Lowpassed>,
    filter: Option<&ZeroPhaseFilter>,
    settings: &AnalyzeSettings,
    dx: f64,
    with_optical: bool,
) -> Result<Resampled> {
    let name = rec.source_name();
    let fs = rec.fs_hz();
    let Some(pos) = rec.channel(Channel::Position) else {
        return Err(Error::MissingChannel {
            channel: "position_mm",
            source_name: name,
            needed_for: "position-domain spectra",
        });
    };
    let lowpass = |x: &[f64], what: &str| -> Result<Vec<f64>> {
        match filter {
            Some(f) => f
                .apply(x)
                .map_err(|e| Error::dsp(format!("{name}: low-pass of {what}"), e)),
            None => Ok(x.to_vec()),
        }
    };
    // One record-length buffer at a time beside the record: the velocity,
    // then each signal low-passed, resampled run by run and decimated.
    let v = {
        let v_all = gradient(pos, Spacing::Uniform(1.0 / fs))
            .map_err(|e| Error::dsp(format!("{name}: velocity (gradient)"), e))?;
        lowpass(&v_all[range.clone()], "velocity")?
    };
    let p = &pos[range.clone()];
    let med = {
        let speeds: Vec<f64> = v.iter().map(|x| x.abs()).collect();
        median(&speeds).unwrap_or(0.0)
    };
    let (v_stop, q) = grid_step(&name, med, fs, settings, dx)?;
    let fine = dx / q as f64;
    // Odd window for a centred mean.
    let period_pts = POINTS_PER_PERIOD | 1;
    // Each run, with where it lies on the fine grid when it is long enough
    // to resample: (samples a..b, sign, first grid point, grid points).
    type Grid = (std::ops::Range<usize>, f64, f64, usize);
    let mut planned: Vec<(DirectionRun, Option<Grid>)> = Vec::new();
    for (a, b, fwd) in direction_runs(&v, v_stop) {
        let sign = if fwd { 1.0 } else { -1.0 };
        // Running maximum of the mirrored position: a monotone travel axis
        // from its first value to its largest.
        let first = f64::NEG_INFINITY.max(sign * p[a]);
        let last = p[a..b]
            .iter()
            .fold(f64::NEG_INFINITY, |m, x| m.max(sign * x));
        let travel = last - first;
        let duration = (b - a) as f64 / fs;
        let run = DirectionRun {
            start_s: a as f64 / fs,
            end_s: (b - 1) as f64 / fs,
            direction: if fwd { "forward" } else { "backward" },
            travel_mm: travel,
            mean_speed_mm_s: travel / duration,
            segments: 0,
        };
        let x0 = (first / fine).ceil() * fine;
        let m = if travel > 0.0 {
            ((last - x0) / fine).floor() as usize + 1
        } else {
            0
        };
        if b - a < 2 || m < MIN_FINE_POINTS * q {
            planned.push((run, None));
        } else {
            planned.push((run, Some((a..b, sign, x0, m))));
        }
    }
    // Each run's walk, made once for the signals (a short record's).
    let walks: Option<Vec<Option<Walk>>> = (p.len() <= SHARED_WALK_MAX_SAMPLES).then(|| {
        planned
            .iter()
            .map(|(_, g)| {
                g.as_ref()
                    .map(|(r, sign, x0, m)| Walk::new(&p[r.clone()], *sign, *x0, fine, *m))
            })
            .collect()
    });
    // One signal on the grid, run by run (`None` for a run not resampled).
    let on_grid = |y: &[f64]| -> Result<Vec<Option<Vec<f64>>>> {
        planned
            .iter()
            .enumerate()
            .map(|(k, (_, g))| {
                g.as_ref()
                    .map(|(r, sign, x0, m)| {
                        let walk = walks.as_ref().and_then(|w| w[k].as_ref());
                        let fine_y = match walk {
                            Some(w) => w.apply(&y[r.clone()]),
                            None => resample(&p[r.clone()], *sign, &y[r.clone()], *x0, fine, *m),
                        };
                        decimate_pow2(fine_y, q, &name)
                    })
                    .transpose()
            })
            .collect()
    };
    let vel = on_grid(&v)?;
    drop(v);
    // A signal low-passed already (the same filter on the same samples:
    // the same values), else low-passed here.
    let given_of = |s: Signal| {
        given
            .and_then(|g| g.iter().find(|(t, _)| *t == s))
            .map(|(_, y)| y.as_slice())
    };
    let fr = match friction.or_else(|| rec.channel(Channel::Friction)) {
        Some(x) => Some(match given_of(Signal::Friction) {
            Some(y) => on_grid(y)?,
            None => on_grid(&lowpass(&x[range.clone()], "friction")?)?,
        }),
        None => None,
    };
    let op = match rec.channel(Channel::Optical).filter(|_| with_optical) {
        Some(x) => Some(match given_of(Signal::Optical) {
            Some(y) => on_grid(y)?,
            None => on_grid(&lowpass(&x[range.clone()], "optical")?)?,
        }),
        None => None,
    };
    let mut fr = fr.map(Vec::into_iter);
    let mut op = op.map(Vec::into_iter);
    let mut runs = Vec::new();
    for ((run, _), vel) in planned.into_iter().zip(vel) {
        let (fr, op) = (
            fr.as_mut().and_then(Iterator::next).flatten(),
            op.as_mut().and_then(Iterator::next).flatten(),
        );
        let Some(vel) = vel else {
            runs.push((run, None));
            continue;
        };
        // Velocity error: v minus its mean over one period, centred.
        let mean = moving_average_valid(&vel, period_pts);
        let h = period_pts / 2;
        let mut sigs = Vec::new();
        if mean.is_empty() {
            runs.push((run, None));
            continue;
        }
        if let Some(fr) = fr {
            sigs.push((Signal::Friction, fr[h..h + mean.len()].to_vec()));
        }
        let ve: Vec<f64> = vel[h..h + mean.len()]
            .iter()
            .zip(&mean)
            .map(|(x, m)| x - m)
            .collect();
        sigs.push((Signal::VelocityError, ve));
        if let Some(op) = op {
            sigs.push((Signal::Optical, op[h..h + mean.len()].to_vec()));
        }
        runs.push((run, Some(sigs)));
    }
    Ok(Resampled { runs })
}
