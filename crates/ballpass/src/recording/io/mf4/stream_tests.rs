//! The streamed MF4 reader against the whole-file one: every sample to the
//! bit, on the asammdf-written fixtures (one DT block, DZ blocks,
//! invalidation bits, a data list of 81 DT or DZ blocks with integer
//! channels and linear conversions), read in blocks of many sizes so that
//! blocks of samples and the file's data blocks cut each other everywhere.

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
    crate::test_scratch::scratch_in("mf4", test)
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

#[test]
fn fixtures_stream_to_the_bit_in_blocks_of_any_size() {
    let opts = LoadOptions::default();
    for name in ["mf4_plain.mf4", "mf4_compressed.mf4"] {
        for block in [16, 17, 50, 199, BLOCK_SAMPLES] {
            same_as_whole(&data(name), &opts, block);
        }
        assert_eq!(check_stream_agrees(&data(name)), Ok(()));
    }
}

/// 81 data blocks of 62 records (about 1000 bytes each), raw or deflated:
/// blocks of 16, 61, 63 and 1000 samples straddle them everywhere; the
/// integer channels go through the file's linear conversions. The values
/// are also asammdf's own reading of the file (`.expected.csv`, printed
/// to round-trip) to the bit.
#[test]
fn data_lists_of_many_blocks_stream_to_the_bit() {
    let opts = LoadOptions::default();
    // Friction holds 5 samples the file marks invalid: filled when read
    // whole, and a fill is not streamed; read with the gaps refused they
    // stop both readers at the same sample.
    for name in ["mf4_blocks.mf4", "mf4_blocks_dz.mf4"] {
        let p = data(name);
        let whole = load(&p, &opts).unwrap_err().to_string();
        assert!(whole.contains("sample 8"), "{whole}");
        // In the first block: refused when the file is opened, at the same
        // sample (the count of gaps in the record is the whole read's).
        let at_open = open_sized(&p, &opts, 61).unwrap_err().to_string();
        assert!(at_open.contains("sample 8"), "{at_open}");
        // Past the first block, a pass refuses it: see
        // `invalid_samples_are_refused_at_their_sample_or_read_whole`.
        assert_eq!(check_stream_agrees(&p), Ok(()));
    }
    // Position and optical only (no invalid sample): streamed to the bit,
    // and equal to asammdf's reading.
    let mut o = LoadOptions::default();
    o.position.name = Some("position_mm".into());
    o.optical.name = Some("optical_V".into());
    // Friction read from position too, with a scale (its unit is then not
    // converted, and a note says so): a channel of the file feeding two.
    o.friction.name = Some("position_mm".into());
    o.friction.scale = 2.0;
    for name in ["mf4_blocks.mf4", "mf4_blocks_dz.mf4"] {
        for block in [16, 61, 63, 1000, BLOCK_SAMPLES] {
            same_as_whole(&data(name), &o, block);
        }
        let text = std::fs::read_to_string(data(&format!("{name}.expected.csv"))).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        let mut src = open_sized(&data(name), &o, 63).unwrap().unwrap();
        let got = collect(&mut src).unwrap();
        assert_eq!(got[1].len(), 5000);
        for (i, r) in rows.iter().enumerate() {
            assert_eq!(got[1][i].to_bits(), r[2].to_bits(), "{name} position {i}");
            assert_eq!(got[2][i].to_bits(), r[3].to_bits(), "{name} optical {i}");
        }
        assert_eq!(src.fs_hz(), 1000.0);
    }
}

/// The invalid samples of `mf4_invalid.mf4` are refused by both readers at
/// the same sample; filling them is read whole.
#[test]
fn invalid_samples_are_refused_at_their_sample_or_read_whole() {
    let p = data("mf4_invalid.mf4");
    let whole = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    let mut src = open_sized(&p, &LoadOptions::default(), 16)
        .unwrap()
        .unwrap();
    let streamed = collect(&mut src).unwrap_err().to_string();
    assert!(whole.contains("sample 51"), "{whole}");
    assert!(streamed.contains("sample 51"), "{streamed}");
    assert_eq!(check_stream_agrees(&p), Ok(()));
    let fill = LoadOptions {
        gaps: GapPolicy {
            fill_max_s: Some(0.1),
            ..GapPolicy::default()
        },
        ..LoadOptions::default()
    };
    let why = open_sized(&p, &fill, 16).unwrap().unwrap_err();
    assert!(why.contains("gaps"), "{why}");
}

/// Channels of two channel groups are read whole (their time axes are
/// compared there), with the reason; a given rate is checked against the
/// time channel as the whole-file reader checks it.
#[test]
fn other_groups_are_read_whole_and_a_given_rate_is_checked() {
    let mut o = LoadOptions::default();
    o.optical.name = Some("optical_V".into());
    let why = open_sized(&data("mf4_two_rates.mf4"), &o, 16)
        .unwrap()
        .unwrap_err();
    assert!(why.contains("channel groups"), "{why}");
    let p = data("mf4_plain.mf4");
    let given = LoadOptions {
        fs_hz: Some(1000.0),
        ..LoadOptions::default()
    };
    same_as_whole(&p, &given, 50);
    let wrong = LoadOptions {
        fs_hz: Some(1010.0),
        ..LoadOptions::default()
    };
    let whole = load(&p, &wrong).unwrap_err().to_string();
    let streamed = open_sized(&p, &wrong, 50).unwrap_err().to_string();
    assert_eq!(whole, streamed);
    // The time ignored: the given rate, no time channel read.
    let ignored = LoadOptions {
        fs_hz: Some(500.0),
        ignore_time: true,
        ..LoadOptions::default()
    };
    same_as_whole(&p, &ignored, 17);
}

/// A time channel with a step off the grid is read whole (its steps are
/// judged against the median there); truncated and damaged files are
/// errors or declined, never a panic, and agree with the whole-file
/// reader.
#[test]
fn uneven_time_and_damaged_files_are_read_whole_or_refused() {
    let dir = scratch("damaged");
    // Sample 100 late by 0.9e-3 of a step: two steps 1.8e-3 apart, each
    // within the 1e-3 tolerance of the median step (accepted whole), not
    // of the smallest (declined here). The time master is the first 8
    // bytes of each 32-byte record of the one DT block.
    let mut plain = std::fs::read(data("mf4_plain.mf4")).unwrap();
    let dt = plain.windows(4).position(|w| w == b"##DT").unwrap() + 24;
    let at = dt + 100 * 32;
    let t = f64::from_le_bytes(plain[at..at + 8].try_into().unwrap());
    assert_eq!(t, 0.1);
    plain[at..at + 8].copy_from_slice(&(t + 0.9e-6).to_le_bytes());
    let p = dir.join("late.mf4");
    std::fs::write(&p, &plain).unwrap();
    assert_eq!(load(&p, &LoadOptions::default()).unwrap().fs_hz(), 1000.0);
    let why = open_sized(&p, &LoadOptions::default(), 16)
        .unwrap()
        .unwrap_err();
    assert!(why.contains("median"), "{why}");
    let bytes = std::fs::read(data("mf4_blocks.mf4")).unwrap();
    // Truncated anywhere: both readers refuse, or agree to the bit.
    for cut in [
        10,
        64,
        100,
        1000,
        5000,
        40_000,
        bytes.len() - 500,
        bytes.len() - 1,
    ] {
        let p = dir.join(format!("cut{cut}.mf4"));
        std::fs::write(&p, &bytes[..cut]).unwrap();
        assert_eq!(check_stream_agrees(&p), Ok(()), "cut at {cut}");
    }
    // A damaged data block: one byte of every 997 flipped.
    let mut hit = bytes.clone();
    for i in (3000..hit.len()).step_by(997) {
        hit[i] ^= 0x5a;
    }
    let p = dir.join("flipped.mf4");
    std::fs::write(&p, &hit).unwrap();
    assert_eq!(check_stream_agrees(&p), Ok(()));
    // Not an MDF file at all, or empty: the whole-file reader's errors.
    for (name, b) in [
        ("text.mf4", &b"time_s,x\n0,1\n"[..]),
        ("empty.mf4", &b""[..]),
    ] {
        let p = dir.join(name);
        std::fs::write(&p, b).unwrap();
        let whole = load(&p, &LoadOptions::default()).unwrap_err().to_string();
        let streamed = open(&p, &LoadOptions::default()).unwrap_err().to_string();
        assert_eq!(whole, streamed);
    }
}

/// A file that changes between passes is an error, not a wrong sample.
#[test]
fn a_file_changed_after_it_was_opened_is_an_error() {
    let dir = scratch("changed");
    let p = dir.join("rec.mf4");
    std::fs::copy(data("mf4_plain.mf4"), &p).unwrap();
    let mut src = open_sized(&p, &LoadOptions::default(), 50)
        .unwrap()
        .unwrap();
    let mut bytes = std::fs::read(&p).unwrap();
    bytes.truncate(bytes.len() - 100);
    std::fs::write(&p, &bytes).unwrap();
    let e = collect(&mut src).unwrap_err().to_string();
    assert!(e.contains("rec.mf4") && e.contains("changed"), "{e}");
}
