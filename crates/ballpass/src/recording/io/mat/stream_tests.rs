//! The streamed v7.3 reader against the whole-file one: every sample to
//! the bit, on the h5py-written fixtures (plain variables, ControlDesk,
//! struct fields and a rate field, deflate and shuffle chunks, a row
//! vector, integer counts), read in blocks that cross their chunks.

use std::path::PathBuf;

use super::*;
use crate::recording::io::{load, GapPolicy};
use crate::recording::stream::{assert_streams_as, collect};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn scratch(test: &str) -> crate::test_scratch::Scratch {
    crate::test_scratch::scratch_in("mat73", test)
}

/// Streams `path` under `opts` in blocks of `block` samples and asserts
/// rate, length, channels, metadata and (twice, pass after pass) every
/// sample equal to the whole-file read's bits.
fn same_as_whole(path: &Path, opts: &LoadOptions, block: usize) {
    let whole = load(path, opts).unwrap();
    let mut src = open_sized(path, opts, block)
        .unwrap()
        .unwrap_or_else(|why| panic!("{}: declined: {why}", path.display()));
    assert_streams_as(&mut src, &whole, &path.display().to_string());
}

fn controldesk_options() -> LoadOptions {
    let mut o = LoadOptions::default();
    o.friction.name = Some("force".into());
    o.position.name = Some("Counts".into());
    o.position.scale = 1e-4;
    o.optical.name = Some("Model Root/Photodetector/Voltage".into());
    o
}

fn struct_options() -> LoadOptions {
    let mut o = LoadOptions::default();
    o.friction.name = Some("bearing.gs".into());
    o.optical.name = Some("signals{1}".into());
    o.fs_from = Some("bearing.sr".into());
    o
}

/// Blocks of 16, 17, 50, 64, 299 and 300 samples cross the fixtures'
/// chunks of 50, 64, 77, 128 and 300 values at every offset pattern; the
/// default block reads each file in one.
#[test]
fn fixtures_stream_to_the_bit_across_chunks() {
    let plain = LoadOptions::default();
    let cases = [
        ("v73_plain.mat", plain.clone()),
        ("v73_chunked.mat", plain),
        ("v73_controldesk.mat", controldesk_options()),
        ("v73_struct.mat", struct_options()),
    ];
    for (name, opts) in &cases {
        for block in [16, 17, 50, 64, 299, 300, BLOCK_SAMPLES] {
            same_as_whole(&data(name), opts, block);
        }
        assert_eq!(check_stream_agrees(&data(name)), Ok(()), "{name}");
    }
    // Optical counts (int16) and a row vector are in the chunked fixture.
    let whole = load(&data("v73_chunked.mat"), &LoadOptions::default()).unwrap();
    assert_eq!(whole.len(), 2000);
    assert_eq!(whole.channel(Channel::Optical).unwrap()[0], 375.0);
}

/// What is read whole says why: a level-5 file, gap filling, a rate given
/// beside the time.
#[test]
fn what_is_not_streamed_says_why() {
    let why = open(&data("plain_v7.mat"), &LoadOptions::default())
        .unwrap()
        .unwrap_err();
    assert!(why.contains("level-5"), "{why}");
    let fill = LoadOptions {
        gaps: GapPolicy {
            fill_max_s: Some(0.1),
            ..GapPolicy::default()
        },
        ..LoadOptions::default()
    };
    let why = open(&data("v73_plain.mat"), &fill).unwrap().unwrap_err();
    assert!(why.contains("gaps"), "{why}");
    let rate = LoadOptions {
        fs_hz: Some(1000.0),
        ..LoadOptions::default()
    };
    let why = open(&data("v73_plain.mat"), &rate).unwrap().unwrap_err();
    assert!(why.contains("time_s"), "{why}");
    // Ignoring the time, the given rate streams.
    let ignore = LoadOptions {
        ignore_time: true,
        ..rate
    };
    same_as_whole(&data("v73_chunked.mat"), &ignore, 100);
}

/// A time variable with a gap is read whole (the whole-file reader names
/// the sample); a value that is not finite is refused as the whole-file
/// reader refuses it, naming the same sample.
#[test]
fn gaps_and_bad_values_agree_with_the_whole_read() {
    let dir = scratch("gaps");
    let src = std::fs::read(data("v73_plain.mat")).unwrap();
    // The contiguous time_s and friction_N vectors of the fixture, found by
    // their first values' bytes (0.000, 0.001, ... and 2.0, 2.0157...).
    let find = |needle: &[u8]| src.windows(needle.len()).position(|w| w == needle).unwrap();
    let mut t = Vec::new();
    for i in 0..3 {
        t.extend_from_slice(&(f64::from(i) / 1000.0).to_le_bytes());
    }
    let t_at = find(&t);
    let mut gap = src.clone();
    gap[t_at + 100 * 8..t_at + 101 * 8].copy_from_slice(&5.0f64.to_le_bytes());
    let p = dir.join("gap.mat");
    std::fs::write(&p, &gap).unwrap();
    assert!(load(&p, &LoadOptions::default()).is_err());
    let why = open_sized(&p, &LoadOptions::default(), 16)
        .unwrap()
        .unwrap_err();
    assert!(why.contains("not uniform"), "{why}");
    assert_eq!(check_stream_agrees(&p), Ok(()));

    // friction_N's first two values, as the whole-file reader reads them.
    let friction = load(&data("v73_plain.mat"), &LoadOptions::default())
        .unwrap()
        .channel(Channel::Friction)
        .unwrap()[..2]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect::<Vec<u8>>();
    let w = find(&friction);
    let mut nan = src;
    nan[w + 150 * 8..w + 151 * 8].copy_from_slice(&f64::NAN.to_le_bytes());
    let p = dir.join("nan.mat");
    std::fs::write(&p, &nan).unwrap();
    let whole = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    let mut s = open_sized(&p, &LoadOptions::default(), 16)
        .unwrap()
        .unwrap();
    let streamed = collect(&mut s).unwrap_err().to_string();
    assert!(whole.contains("sample 151"), "{whole}");
    assert!(streamed.contains("sample 151"), "{streamed}");
    assert_eq!(check_stream_agrees(&p), Ok(()));
}

/// A file that changes between passes is an error, not a wrong sample;
/// truncated copies never panic and agree with the whole-file read.
#[test]
fn changed_and_truncated_files_are_errors() {
    let dir = scratch("changed");
    let p = dir.join("rec.mat");
    let bytes = std::fs::read(data("v73_chunked.mat")).unwrap();
    std::fs::write(&p, &bytes).unwrap();
    let mut src = open_sized(&p, &LoadOptions::default(), 100)
        .unwrap()
        .unwrap();
    std::fs::write(&p, &bytes[..bytes.len() - 100]).unwrap();
    let e = collect(&mut src).unwrap_err().to_string();
    assert!(e.contains("rec.mat") && e.contains("changed"), "{e}");
    for cut in (0..bytes.len()).step_by(997) {
        std::fs::write(&p, &bytes[..cut]).unwrap();
        assert_eq!(check_stream_agrees(&p), Ok(()), "cut at {cut}");
    }
}

/// A chunk index entry damaged outside every range read (found by the fuzz
/// harness, seed 73, execution 43362, a mutation of v73_plain.mat): the
/// whole-file reader refuses the file, and so does the streamed one.
#[test]
fn a_damaged_chunk_index_is_refused_as_whole() {
    let p = data("fuzzed_v73_chunk_index.mat");
    let whole = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    assert!(whole.contains("optical_V"), "{whole}");
    let e = open_sized(&p, &LoadOptions::default(), 16)
        .unwrap_err()
        .to_string();
    assert!(e.contains("optical_V") && e.contains("chunk"), "{e}");
    assert_eq!(check_stream_agrees(&p), Ok(()));
}
