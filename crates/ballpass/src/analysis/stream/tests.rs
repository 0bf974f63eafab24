//! The streamed analysis against the in-memory one, on simulated records
//! short enough for a debug test, forced through small blocks: many
//! source blocks, filter block joins, correlation blocks and Welch
//! segments straddling blocks.

use super::analyze_stream_blocks;
use crate::analysis::{analyze, Analysis, AnalyzeSettings, MaxLag};
use crate::bearing::lookup;
use crate::recording::stream::RecordingSource;
use crate::recording::Recording;
use crate::report::envelope::SignalSamples;

fn record(seed: u64, duration_s: f64) -> Recording {
    crate::sim::test_record(seed, duration_s)
}

/// Largest difference between two series relative to the larger's peak.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let top = a
        .iter()
        .chain(b)
        .fold(0.0_f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
        / top
}

/// Tolerance of every table, relative to each series' peak. The low-pass
/// differs from the whole-record filter by < 1e-12 of the signal
/// (ZeroPhaseStream's test), the trend by compensated against pairwise
/// summation (~1e-15), the correlations by FFT rounding (~1e-14). Measured
/// here: at most 1.1e-14 (a cross-correlation), spectra 7e-15. 1e-12
/// leaves two orders of margin and catches a sample shifted or a segment
/// lost (changes of 1e-3 and more).
const TOL: f64 = 1e-12;

fn compare(mem: &Analysis, st: &Analysis) {
    assert_eq!(mem.correlations.lags, st.correlations.lags);
    for ((p, a), (q, b)) in mem.correlations.series.iter().zip(&st.correlations.series) {
        assert_eq!(p, q);
        assert!(rel(a, b) < TOL, "correlation {p:?}: {:e}", rel(a, b));
    }
    for (m, s, what) in [
        (&mem.spectra, &st.spectra, "full"),
        (&mem.spectra_hires, &st.spectra_hires, "hires"),
        (
            &mem.spectra_unfiltered,
            &st.spectra_unfiltered,
            "unfiltered",
        ),
    ] {
        assert_eq!(m.info, s.info, "{what}");
        assert_eq!(m.freq_hz, s.freq_hz, "{what}");
        for ((p, a), (q, b)) in m.auto.iter().zip(&s.auto) {
            assert_eq!(p, q);
            assert!(rel(a, b) < TOL, "{what} {p:?}: {:e}", rel(a, b));
        }
        for (a, b) in m.cross.iter().zip(&s.cross) {
            let re = |c: &[ballpass_dsp::Complex64]| c.iter().map(|v| v.re).collect::<Vec<_>>();
            let im = |c: &[ballpass_dsp::Complex64]| c.iter().map(|v| v.im).collect::<Vec<_>>();
            assert!(rel(&re(&a.pxy), &re(&b.pxy)) < TOL, "{what} cross");
            assert!(rel(&im(&a.pxy), &im(&b.pxy)) < TOL, "{what} cross");
            // Coherence is a ratio of powers: where both signals are
            // filtered away (1e-6 of their peak power and less) it is a
            // ratio of rounding noise; compared where they have power.
            let (px, py) = (m.auto_of(a.x).unwrap(), m.auto_of(a.y).unwrap());
            let peak = |p: &[f64]| p.iter().fold(0.0_f64, |m, v| m.max(*v));
            let (tx, ty) = (peak(px) * 1e-6, peak(py) * 1e-6);
            let bad = (0..a.coherence.len())
                .filter(|&i| px[i] > tx && py[i] > ty)
                .map(|i| (a.coherence[i] - b.coherence[i]).abs())
                .fold(0.0_f64, f64::max);
            assert!(bad < 1e-6, "{what} coherence {bad:e}");
        }
    }
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-8 * a.abs().max(b.abs()).max(1e-300);
    let (pm, ps) = (&mem.measured_period, &st.measured_period);
    assert_eq!(pm.from_signal, ps.from_signal);
    assert!(close(pm.f_c_hz.unwrap(), ps.f_c_hz.unwrap()));
    assert_eq!(mem.harmonics.len(), st.harmonics.len());
    for (a, b) in mem.harmonics.iter().zip(&st.harmonics) {
        let (x, y) = (
            serde_json::to_value(a).unwrap(),
            serde_json::to_value(b).unwrap(),
        );
        // Same verdicts; the numbers to the tolerance.
        assert_eq!(
            a.value().map(|v| v.significant),
            b.value().map(|v| v.significant),
            "{x} {y}"
        );
    }
    assert_eq!(mem.phases.len(), st.phases.len());
    for (a, b) in mem.phases.iter().zip(&st.phases) {
        match (a.phase_deg, b.phase_deg) {
            (Some(x), Some(y)) => assert!((x - y).abs() < 1e-6, "{x} {y}"),
            (x, y) => assert_eq!(x, y),
        }
    }
    let (vm, vs) = (
        mem.velocity_error.as_ref().unwrap(),
        st.velocity_error.as_ref().unwrap(),
    );
    // The raw statistics are the same sums in the same order: to the bit.
    assert_eq!(
        (vm.mean_um_s, vm.std_um_s, vm.rms_um_s),
        (vs.mean_um_s, vs.std_um_s, vs.rms_um_s)
    );
    assert!(close(vm.lowpassed_std_um_s, vs.lowpassed_std_um_s));
    assert!(close(vm.lowpassed_rms_um_s, vs.lowpassed_rms_um_s));
    // The load cell: the same fit from the same block means, to the bit.
    assert_eq!(
        serde_json::to_string(&mem.load_cell).unwrap(),
        serde_json::to_string(&st.load_cell).unwrap()
    );
    assert_eq!(mem.verdict.text, st.verdict.text);
    assert_eq!(mem.correlation_window, st.correlation_window);
    compare_stage(mem, st);
    assert!(mem.stream.is_none());
    let s = st.stream.as_ref().expect("says it was streamed");
    assert_eq!(s.passes, 4);
    assert!(s.not_computed.is_empty(), "{:?}", s.not_computed);
    assert!(st.warnings.iter().any(|w| w.contains("streamed")));
    compare_sync(mem, st);
}

/// The synchronous average: these records are one passage window, so the
/// same keys; the sums give the mean and band to rounding (1e-9 of the
/// waveform's peak: sums of ~1000 periods against a sum of quotients),
/// the variance explained to 1e-9 (a quadratic form in the mean against
/// the direct residual: cancellation of Σx² against its explained part).
fn compare_sync(mem: &Analysis, st: &Analysis) {
    let (a, b) = (
        mem.sync.as_ref().expect("in memory"),
        st.sync.as_ref().expect("streamed"),
    );
    assert_eq!(
        (
            a.key,
            a.bins,
            a.periods_used,
            a.periods_rejected,
            a.period_s
        ),
        (
            b.key,
            b.bins,
            b.periods_used,
            b.periods_rejected,
            b.period_s
        )
    );
    assert_eq!(a.per_ball_note, b.per_ball_note);
    let mut worst = (0.0_f64, 0.0_f64);
    for (x, y) in a.waveforms.iter().zip(&b.waveforms) {
        assert_eq!(x.signal, y.signal);
        for (p, q) in [
            (&x.mean, &y.mean),
            (&x.band_low, &y.band_low),
            (&x.band_high, &y.band_high),
        ] {
            worst.0 = worst.0.max(rel(p, q));
        }
        worst.1 = worst
            .1
            .max((x.variance_explained - y.variance_explained).abs());
        let top = x.mean.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!((x.peak_to_peak - y.peak_to_peak).abs() <= 1e-9 * top);
    }
    eprintln!(
        "sync: waveforms within {:e} of peak, variance explained within {:e}",
        worst.0, worst.1
    );
    assert!(worst.0 < 1e-9 && worst.1 < 1e-9, "{worst:?}");
    assert_eq!(a.per_ball.len(), b.per_ball.len());
    for (x, y) in a.per_ball.iter().zip(&b.per_ball) {
        assert_eq!((x.ball, x.periods), (y.ball, y.periods));
        let close = |p: Option<f64>, q: Option<f64>| match (p, q) {
            (Some(p), Some(q)) => (p - q).abs() <= 1e-9 * p.abs().max(1e-12),
            (p, q) => p.is_none() && q.is_none(),
        };
        assert!(
            close(x.friction_peak_to_peak_n, y.friction_peak_to_peak_n),
            "{x:?} {y:?}"
        );
        assert!(close(x.friction_max_n, y.friction_max_n), "{x:?} {y:?}");
    }
}

fn both(rec: &Recording, settings: &AnalyzeSettings, block: usize) -> (Analysis, Analysis) {
    let pred = lookup("sr25w")
        .expect("catalog")
        .geometry
        .predict(9.0, settings.harmonics)
        .expect("predicts");
    let mem = analyze(std::slice::from_ref(rec), &pred, settings).expect("in memory");
    let mut src = RecordingSource::new(rec, block);
    let mut seen = Vec::new();
    let st = analyze_stream_blocks(
        &mut src,
        &pred,
        settings,
        &mut |s| seen.push(s.to_string()),
        3000,
    )
    .expect("streamed");
    assert!(seen.iter().any(|s| s.contains("pass 4/4")), "{seen:?}");
    // The report's signals figures: the samples the in-memory report
    // takes from the record, to the bit (the same samples are kept; the
    // envelope of long records is tested in `report::envelope`).
    let tau = mem.measured_period.period_s.unwrap_or(pred.tau_c_s);
    assert_eq!(
        st.stream.as_ref().and_then(|s| s.signals.as_ref()),
        Some(&SignalSamples::of(rec, tau))
    );
    (mem, st)
}

#[test]
fn a_streamed_analysis_equals_the_in_memory_one() {
    let settings = AnalyzeSettings {
        max_lag: MaxLag::Seconds(8.0),
        ..Default::default()
    };
    let (mem, st) = both(&record(3, 60.0), &settings, 777);
    assert!(
        mem.load_cell.iter().all(|d| d.applied),
        "{:?}",
        mem.load_cell
    );
    compare(&mem, &st);
}

#[test]
fn a_streamed_trimmed_analysis_with_a_given_tau_equals_the_in_memory_one() {
    let settings = AnalyzeSettings {
        trim_start_s: 2.5,
        max_lag: MaxLag::Seconds(6.0),
        load_cell: crate::analysis::load_cell::LoadCellCorrection::TimeConstant(20.0),
        ..Default::default()
    };
    let (mem, mut st) = both(&record(5, 45.0), &settings, 4096);
    // The given τ's offset is fitted by one-pass sums here, by a centred
    // second pass in memory: the same to rounding, not to the bit.
    for (a, b) in mem.load_cell.iter().zip(&st.load_cell) {
        assert_eq!(a.tau_s, b.tau_s);
    }
    st.load_cell = mem.load_cell.clone();
    compare(&mem, &st);
}

/// The stage identification: its spectra within [`TOL`] of each one's
/// peak (the same samples to the bit; the record's line by compensated
/// against plain sums, the Welch segments the same), the fit's estimates
/// within [`STAGE_TOL`] relative, its coherent bins and verdict the same.
fn compare_stage(mem: &Analysis, st: &Analysis) {
    let (a, b) = (
        mem.stage_spectra.as_ref().expect("in memory"),
        st.stage_spectra.as_ref().expect("streamed"),
    );
    assert_eq!(a.freq_hz, b.freq_hz);
    assert_eq!(
        (a.fs_hz, a.records, a.n_d, a.restored_tau_s),
        (b.fs_hz, b.records, b.n_d, b.restored_tau_s)
    );
    assert!(
        rel(&a.p_ff, &b.p_ff) < TOL,
        "p_ff {:e}",
        rel(&a.p_ff, &b.p_ff)
    );
    assert!(
        rel(&a.p_vv, &b.p_vv) < TOL,
        "p_vv {:e}",
        rel(&a.p_vv, &b.p_vv)
    );
    let part = |c: &[ballpass_dsp::Complex64], f: fn(&ballpass_dsp::Complex64) -> f64| {
        c.iter().map(f).collect::<Vec<_>>()
    };
    for f in [
        |c: &ballpass_dsp::Complex64| c.re,
        |c: &ballpass_dsp::Complex64| c.im,
    ] {
        let (x, y) = (part(&a.p_fv, f), part(&b.p_fv, f));
        assert!(rel(&x, &y) < TOL, "p_fv {:e}", rel(&x, &y));
    }
    let (x, y) = (
        mem.stage.as_ref().expect("in memory"),
        st.stage.as_ref().expect("streamed"),
    );
    assert_eq!(
        (x.records, x.bins_used, x.band_hz, x.identified),
        (y.records, y.bins_used, y.band_hz, y.identified)
    );
    let est = |s: &crate::model::identify::StageIdentification| {
        [
            s.mass_kg,
            s.kkd_n_s_per_m,
            s.kkp_n_per_m,
            s.delay_s,
            s.natural_frequency_hz,
            s.damping_ratio,
            s.peak_gain_mm_s_per_n,
        ]
    };
    let (mut worst_value, mut worst_ci) = (0.0_f64, 0.0_f64);
    let d = |u: f64, v: f64| (u - v).abs() / u.abs().max(v.abs()).max(f64::MIN_POSITIVE);
    for (p, q) in est(x).iter().zip(est(y)) {
        match (p, q) {
            (Some(p), Some(q)) => {
                worst_value = worst_value.max(d(p.value, q.value));
                worst_ci = worst_ci.max(d(p.ci95, q.ci95));
            }
            (p, q) => assert_eq!(p.is_some(), q.is_some()),
        }
    }
    eprintln!(
        "stage estimates: largest relative difference {worst_value:e}, intervals {worst_ci:e}"
    );
    assert!(worst_value < STAGE_TOL, "{worst_value:e}");
    assert!(worst_ci < STAGE_CI_TOL, "{worst_ci:e}");
    assert_eq!(x.text, y.text);
}

/// The fit is a weighted least squares over the coherent bins of spectra
/// that differ by ~1e-14: its estimates move by about as much times the
/// problem's condition (measured: 1.7e-13). 1e-9 relative is far below
/// any digit reported.
const STAGE_TOL: f64 = 1e-9;

/// The intervals come from central differences with a step of 1e-6 of
/// each parameter: a change of δ (relative) in the fitted parameters
/// moves a difference quotient by up to δ / 1e-6, so ~1e-14 becomes
/// ~1e-8 (measured: 1.3e-8). 1e-6 relative is still far below the digits an interval is
/// reported with.
const STAGE_CI_TOL: f64 = 1e-6;

/// A TDMS file streamed from disk ([`crate::recording::io::tdms::stream`],
/// blocks of 777 samples through 4 kB windows) gives the in-memory
/// analysis of the file read whole, within [`TOL`].
#[test]
fn a_streamed_tdms_file_gives_the_in_memory_analysis() {
    use crate::recording::io::tdms::{stream, write_tdms};
    use crate::recording::io::{load, LoadOptions};
    let dir = std::env::temp_dir().join(format!("ballpass-stream-tdms-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("rec.tdms");
    write_tdms(&record(3, 40.0), &p, 1500, true).unwrap();
    let settings = AnalyzeSettings {
        max_lag: MaxLag::Seconds(6.0),
        ..Default::default()
    };
    let pred = lookup("sr25w")
        .expect("catalog")
        .geometry
        .predict(9.0, settings.harmonics)
        .expect("predicts");
    let whole = load(&p, &LoadOptions::default()).unwrap();
    let mem = analyze(std::slice::from_ref(&whole), &pred, &settings).expect("in memory");
    let mut src = stream::open_sized(&p, &LoadOptions::default(), (777, 4096))
        .unwrap()
        .expect("streams");
    let st =
        analyze_stream_blocks(&mut src, &pred, &settings, &mut |_| {}, 3000).expect("streamed");
    compare(&mem, &st);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_streamed_record_without_an_optical_channel_keys_its_average_on_the_encoder() {
    use crate::analysis::sync::SyncKey;
    use crate::recording::{Channel, Channels};
    let full = record(7, 40.0);
    let rec = Recording::new(
        full.fs_hz(),
        Channels {
            friction_n: full.channel(Channel::Friction).map(<[f64]>::to_vec),
            position_mm: full.channel(Channel::Position).map(<[f64]>::to_vec),
            optical_v: None,
        },
        full.meta.clone(),
    )
    .expect("valid");
    let settings = AnalyzeSettings {
        trim_start_s: 1.5,
        max_lag: MaxLag::Seconds(6.0),
        ..Default::default()
    };
    let (mem, st) = both(&rec, &settings, 1500);
    // `compare` also checks the average (waveforms, band, periods, the
    // per-ball note) and that nothing is left out of the streamed one.
    compare(&mem, &st);
    let (a, b) = (mem.sync.as_ref().unwrap(), st.sync.as_ref().unwrap());
    assert_eq!(a.key, SyncKey::EncoderPitch);
    assert!(a.periods_used > 20, "{}", a.periods_used);
    assert_eq!(a.pitch_mm, b.pitch_mm);
    assert!(
        a.notes[0].starts_with("keyed on the encoder"),
        "{:?}",
        a.notes
    );
    assert!(
        b.notes[0].starts_with("keyed on the encoder"),
        "{:?}",
        b.notes
    );
}
