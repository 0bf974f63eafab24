//! The streamed TDMS reader against the whole-file one: every sample to
//! the bit, on the npTDMS-written and byte-laid fixtures (contiguous,
//! interleaved, big-endian, DAQmx, NI scaling, several groups) and on
//! records of many segments, read in tiny pieces.

use std::path::PathBuf;

use super::*;
use crate::recording::io::tdms::write_tdms;
use crate::recording::io::{load, GapPolicy};
use crate::recording::stream::{assert_streams_as, collect};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn scratch(test: &str) -> crate::test_scratch::Scratch {
    crate::test_scratch::scratch_in("tdms", test)
}

fn record(duration_s: f64) -> Recording {
    crate::sim::test_record(7, duration_s)
}

/// Streams `path` under `opts` in blocks of `sizes` and asserts rate,
/// length, channels, metadata and (twice, pass after pass) every sample
/// equal to the whole-file read's bits.
fn same_as_whole(path: &Path, opts: &LoadOptions, sizes: (usize, usize)) {
    let whole = load(path, opts).unwrap();
    let mut src = open_sized(path, opts, sizes)
        .unwrap()
        .unwrap_or_else(|why| panic!("{}: declined: {why}", path.display()));
    assert_streams_as(&mut src, &whole, &path.display().to_string());
    assert_eq!(check_stream_agrees(path), Ok(()));
}

#[test]
fn fixtures_stream_to_the_bit_in_tiny_pieces() {
    let opts = LoadOptions::default();
    for name in [
        "tdms_plain.tdms",
        "tdms_interleaved.tdms",
        "tdms_bigendian.tdms",
        "tdms_daqmx.tdms",
    ] {
        for sizes in [(16, 64), (17, 8), (50, 1000), (BLOCK_SAMPLES, WINDOW_BYTES)] {
            same_as_whole(&data(name), &opts, sizes);
        }
    }
    let mut o = LoadOptions::default();
    o.friction.name = Some("Force".into());
    o.position.name = Some("Bench 1/Position".into());
    o.optical.name = Some("bench 1/voltage".into());
    same_as_whole(&data("tdms_scaled.tdms"), &o, (16, 64));
    for k in 1..=3 {
        let spec = PathBuf::from(format!("{}#Run {k}", data("tdms_runs.tdms").display()));
        same_as_whole(&spec, &opts, (16, 64));
    }
}

/// A time channel and no waveform timing (npTDMS-written, float64 seconds
/// and TDMS timestamps, `tdms_timed`/`tdms_stamps`): its steps scanned in pieces, the same rate,
/// start, notes and samples as the whole column's check; with a rate
/// given beside it, read whole, saying why.
#[test]
fn a_time_channel_is_scanned_in_pieces() {
    let file = data("tdms_timed.tdms");
    for name in ["tdms_timed.tdms", "tdms_stamps.tdms"] {
        for sizes in [(16, 64), (17, 8), (BLOCK_SAMPLES, WINDOW_BYTES)] {
            same_as_whole(&data(name), &LoadOptions::default(), sizes);
        }
    }
    // Seconds read as milliseconds: the unit's note, a rate of 1 MHz.
    let ms = LoadOptions {
        time_unit: Some(crate::recording::io::TimeUnit::Ms),
        ..LoadOptions::default()
    };
    same_as_whole(&file, &ms, (16, 64));
    let src = open_sized(&file, &ms, (16, 64)).unwrap().unwrap();
    assert_eq!(src.fs_hz(), 1e6);
    assert!(src.meta().notes.iter().any(|n| n.contains("read in ms")));
    // A rate given beside the time channel: read whole, the reason said.
    let given = LoadOptions {
        fs_hz: Some(1000.0),
        ..LoadOptions::default()
    };
    let why = open_sized(&file, &given, (16, 64)).unwrap().unwrap_err();
    assert!(
        why.contains("time channel ('Log/time_s')") && why.contains("rate"),
        "{why}"
    );
    // One stamp moved by 0.4 of a step: the scan declines, the whole
    // column's check refuses it at its sample.
    let dir = scratch("timed");
    let p = dir.join("jitter.tdms");
    let mut bytes = std::fs::read(&file).unwrap();
    let stamp = (3.25 + 50.0 / 1000.0_f64).to_le_bytes();
    let at = bytes
        .windows(8)
        .position(|w| w == stamp)
        .expect("the stamp of sample 50");
    bytes[at..at + 8].copy_from_slice(&(3.25 + 50.4 / 1000.0_f64).to_le_bytes());
    std::fs::write(&p, &bytes).unwrap();
    let why = open_sized(&p, &LoadOptions::default(), (16, 64))
        .unwrap()
        .unwrap_err();
    assert!(why.contains("uniformly"), "{why}");
    let whole = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    assert!(whole.contains("sampling is not uniform"), "{whole}");
    assert_eq!(check_stream_agrees(&p), Ok(()));
}

/// A record of many segments (the last one shorter, its own index),
/// contiguous and interleaved, in blocks that straddle segments.
#[test]
fn records_of_many_segments_stream_to_the_bit() {
    let dir = scratch("segments");
    let rec = record(6.0);
    for interleaved in [false, true] {
        let p = dir.join(format!("rec{interleaved}.tdms"));
        write_tdms(&rec, &p, 997, interleaved).unwrap();
        let back = load(&p, &LoadOptions::default()).unwrap();
        assert_eq!(back.fs_hz(), rec.fs_hz());
        for c in Channel::ALL {
            assert_eq!(back.channel(c), rec.channel(c), "{c:?}");
        }
        for sizes in [(1000, 4096), (333, 100), (4096, 1 << 20)] {
            same_as_whole(&p, &LoadOptions::default(), sizes);
        }
    }
}

/// A value that is not finite is refused as the whole-file reader refuses
/// it, naming the same sample; gap filling is read whole.
#[test]
fn gaps_are_refused_at_their_sample_or_read_whole() {
    let dir = scratch("gaps");
    let p = dir.join("nan.tdms");
    write_tdms(&record(3.0), &p, 1000, false).unwrap();
    // Put the NaN into the file's bytes: friction is the first channel of
    // the third segment (1000 samples of 3 channels per segment).
    let mut bytes = std::fs::read(&p).unwrap();
    let nan_at = bytes.len() - 3 * 8 * 1000 + 500 * 8;
    bytes[nan_at..nan_at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    std::fs::write(&p, &bytes).unwrap();
    let whole = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    let mut src = open_sized(&p, &LoadOptions::default(), (300, 256))
        .unwrap()
        .unwrap();
    let streamed = collect(&mut src).unwrap_err().to_string();
    assert!(whole.contains("sample 2501"), "{whole}");
    assert!(streamed.contains("sample 2501"), "{streamed}");
    assert_eq!(check_stream_agrees(&p), Ok(()));
    let fill = LoadOptions {
        gaps: GapPolicy {
            fill_max_s: Some(0.1),
            ..GapPolicy::default()
        },
        ..LoadOptions::default()
    };
    assert!(open_sized(&p, &fill, (300, 256)).unwrap().is_err());
}

/// A file that changes between passes is an error, not a wrong sample.
#[test]
fn a_file_changed_after_the_scan_is_an_error() {
    let dir = scratch("changed");
    let p = dir.join("rec.tdms");
    write_tdms(&record(2.0), &p, 500, false).unwrap();
    let mut src = open_sized(&p, &LoadOptions::default(), (300, 256))
        .unwrap()
        .unwrap();
    let mut bytes = std::fs::read(&p).unwrap();
    bytes.truncate(bytes.len() - 100);
    std::fs::write(&p, &bytes).unwrap();
    let e = collect(&mut src).unwrap_err().to_string();
    assert!(e.contains("rec.tdms") && e.contains("changed"), "{e}");
}
