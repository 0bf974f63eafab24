//! The streamed position-domain spectra against the in-memory ones, on
//! simulated records forced through small blocks.

use crate::analysis::position::PositionSpectra;
use crate::analysis::stream::analyze_stream_blocks;
use crate::analysis::{analyze, AnalyzeSettings, MaxLag};
use crate::bearing::lookup;
use crate::recording::stream::RecordingSource;
use crate::recording::{Channels, Recording};
use crate::sim::{simulate, ProfilePlateau, SimSettings, SpeedProfile};

/// PSDs relative to each one's peak: the low-pass and the decimation
/// filters each differ from the whole-record filter by < 1e-12 of the
/// signal (ZeroPhaseStream's test), the segments' sums by rounding.
/// Measured: 6.7e-14 (constant speed), 2.1e-13 (back and forth).
const TOL: f64 = 1e-10;

fn rel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let top = a.iter().chain(b).fold(0.0_f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
        / top.max(f64::MIN_POSITIVE)
}

fn compare(m: &PositionSpectra, s: &PositionSpectra) {
    // The runs, the grid and the segment length: the same values (the runs
    // come from the same comparisons with the same median).
    assert_eq!(m.runs, s.runs);
    assert_eq!(
        (m.dx_mm, m.nperseg, m.n_segments, m.n_records, m.dof),
        (s.dx_mm, s.nperseg, s.n_segments, s.n_records, s.dof)
    );
    assert_eq!(
        (m.travel_used_mm, m.min_speed_mm_s),
        (s.travel_used_mm, s.min_speed_mm_s)
    );
    assert_eq!(m.freq_per_mm, s.freq_per_mm);
    assert_eq!(m.band, s.band);
    let mut worst = 0.0_f64;
    for ((a, x), (b, y)) in m.auto.iter().zip(&s.auto) {
        assert_eq!(a, b);
        worst = worst.max(rel(x, y));
    }
    eprintln!("position PSDs: largest difference {worst:e} of the peak");
    assert!(worst < TOL, "{worst:e}");
    assert_eq!(m.lines.len(), s.lines.len());
    let mut worst_line = 0.0_f64;
    for (a, b) in m.lines.iter().zip(&s.lines) {
        assert_eq!((a.signal, a.k, a.floor_bins), (b.signal, b.k, b.floor_bins));
        // The line between the bins: a golden section stopped at 1e-4 of
        // its step (a sixty-fourth of a bin, a sixteenth of the line): the
        // two searches agree to that, 2e-7 of the line; 1e-6 allows
        // a last comparison decided by rounding.
        let d = (a.measured_per_mm - b.measured_per_mm).abs() / a.measured_per_mm;
        worst_line = worst_line.max(d);
        assert!(
            d < 1e-6,
            "{:?} {} {} vs {}",
            a.signal,
            a.k,
            a.measured_per_mm,
            b.measured_per_mm
        );
        // Powers are sums of PSD bins (TOL of the peak).
        let top = m
            .auto_of(a.signal)
            .unwrap()
            .iter()
            .fold(0.0_f64, |x, v| x.max(*v))
            * m.resolution_per_mm
            * 5.0;
        assert!((a.power - b.power).abs() <= TOL * top, "{a:?} {b:?}");
    }
    eprintln!("position lines: largest relative difference {worst_line:e}");
}

fn both(rec: &Recording, velocity: f64, passes: usize) -> (PositionSpectra, PositionSpectra) {
    let settings = AnalyzeSettings {
        max_lag: MaxLag::Seconds(5.0),
        ..Default::default()
    };
    let pred = lookup("sr25w")
        .expect("catalog")
        .geometry
        .predict(velocity, settings.harmonics)
        .expect("predicts");
    let mem = analyze(std::slice::from_ref(rec), &pred, &settings).expect("in memory");
    let mut src = RecordingSource::new(rec, 1013);
    let st =
        analyze_stream_blocks(&mut src, &pred, &settings, &mut |_| {}, 3000).expect("streamed");
    let info = st.stream.as_ref().expect("streamed");
    assert_eq!(info.passes, passes);
    assert!(!info.not_computed.iter().any(|s| s.contains("position")));
    (
        mem.position.expect("in-memory position spectra"),
        st.position.expect("streamed position spectra"),
    )
}

#[test]
fn streamed_position_spectra_equal_the_in_memory_ones() {
    let rec = simulate(&SimSettings {
        velocity_mm_s: 9.0,
        duration_s: 50.0,
        seed: 21,
        ..Default::default()
    })
    .expect("simulates")
    .recording;
    let (m, s) = both(&rec, 9.0, 4);
    assert!(m.n_segments > 2, "{}", m.n_segments);
    compare(&m, &s);
}

#[test]
fn streamed_position_spectra_of_a_back_and_forth_run_without_friction() {
    // Plateaus both ways at three speeds; the friction channel dropped, so
    // the median takes passes 1–3 of the analysis and the resampling a
    // pass of its own.
    let plateaus = [9.0, -14.0, 5.0, -9.0]
        .map(|v| ProfilePlateau {
            velocity_mm_s: v,
            duration_s: 12.0,
        })
        .to_vec();
    let sim = simulate(&SimSettings {
        velocity_mm_s: 9.0,
        duration_s: 48.0,
        seed: 8,
        profile: Some(SpeedProfile {
            plateaus,
            acceleration_mm_s2: 50.0,
        }),
        ..Default::default()
    })
    .expect("simulates")
    .recording;
    let rec = Recording::new(
        sim.fs_hz(),
        Channels {
            friction_n: None,
            position_mm: sim
                .channel(crate::recording::Channel::Position)
                .map(<[f64]>::to_vec),
            optical_v: sim
                .channel(crate::recording::Channel::Optical)
                .map(<[f64]>::to_vec),
        },
        sim.meta.clone(),
    )
    .expect("valid");
    let (m, s) = both(&rec, 9.0, 4);
    assert!(m.runs.len() >= 4, "{:?}", m.runs);
    assert!(m
        .runs
        .iter()
        .any(|r| r.direction == "backward" && r.segments > 0));
    compare(&m, &s);
}
