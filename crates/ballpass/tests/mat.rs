//! MAT-file loading against the committed fixtures of
//! `tools/make_mat_fixtures.py` (scipy 1.17.1), and the MAT writer.

use std::path::PathBuf;

use ballpass::recording::{
    load, write_mat, Channel, Channels, Format, LoadOptions, Metadata, Recording,
};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// The fixtures' values exactly as Python printed them (`repr`, which
/// round-trips), read from the CSV text that `csv_renamed.mat` holds.
fn reference() -> Recording {
    let opts = LoadOptions {
        format: Some(Format::Csv),
        ..Default::default()
    };
    load(&data("csv_renamed.mat"), &opts).expect("reference CSV")
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn plain_variables_load_bit_exact_uncompressed_and_compressed() {
    let want = reference();
    for name in ["plain_v5.mat", "plain_v7.mat"] {
        let r = load(&data(name), &LoadOptions::default()).unwrap();
        assert_eq!(r.fs_hz(), 1000.0, "{name}");
        assert_eq!(r.len(), 200);
        assert_eq!(r.channels(), Channel::ALL.to_vec());
        for c in Channel::ALL {
            assert_eq!(
                bits(r.channel(c).unwrap()),
                bits(want.channel(c).unwrap()),
                "{name} {c}"
            );
        }
        assert_eq!(r.meta.test_id.as_deref(), Some(&name[..name.len() - 4]));
    }
}

#[test]
fn controldesk_struct_layout_with_mapped_signal_names() {
    let path = data("controldesk.mat");
    // Without a mapping the block-path names match no channel: the error lists them.
    let e = load(&path, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("controldesk.mat") && e.contains("'Model Root/Load cell/Force'"),
        "{e}"
    );
    let mut o = LoadOptions::default();
    o.friction.name = Some("force".into()); // last part of the block path
    o.position.name = Some("Counts".into());
    o.position.scale = 1e-4; // encoder counts of 0.1 um
    o.optical.name = Some("Model Root/Photodetector/Voltage".into()); // whole path
    let r = load(&path, &o).unwrap();
    let want = reference();
    assert_eq!(r.fs_hz(), 1000.0);
    assert_eq!(
        bits(r.channel(Channel::Friction).unwrap()),
        bits(want.channel(Channel::Friction).unwrap())
    );
    assert_eq!(
        bits(r.channel(Channel::Optical).unwrap()),
        bits(want.channel(Channel::Optical).unwrap())
    );
    // Counts are 9 t rounded to 1e-4 mm, stored as int32: within half a count
    // plus the rounding of the product counts * 1e-4 (far below 1e-12 mm).
    for (p, q) in r
        .channel(Channel::Position)
        .unwrap()
        .iter()
        .zip(want.channel(Channel::Position).unwrap())
    {
        assert!((p - q).abs() <= 0.5e-4 + 1e-12, "{p} vs {q}");
    }
    // A mapped name that is not there is named, with what is there.
    o.friction.name = Some("Torque".into());
    let e = load(&path, &o).unwrap_err().to_string();
    assert!(e.contains("no signal 'Torque' for friction_N"), "{e}");
}

#[test]
fn bad_mat_files_are_one_line_errors_naming_the_file() {
    for (name, expect) in [
        ("truncated.mat", "truncated MAT-file"),
        ("truncated_v7.mat", "truncated MAT-file"),
        ("garbage.mat", "malformed MAT-file"),
        ("csv_renamed.mat", "looks like a CSV file"),
        ("v73_header.mat", "v7.3 (HDF5)"),
        ("matrix.mat", "'friction_N' is a 200x2 matrix"),
    ] {
        let e = load(&data(name), &LoadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(name) && e.contains(expect), "{name}: {e}");
        assert!(!e.contains('\n'), "{name}: message spans lines: {e}");
    }
}

/// Every prefix (in steps of 23 bytes) and single-byte corruptions of the
/// fixtures: loading returns Ok or Err and never panics or aborts.
#[test]
fn damaged_mat_files_never_panic() {
    let dir = std::env::temp_dir().join(format!("ballpass-mat-damage-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("d.mat");
    let mut errors = 0;
    for name in ["plain_v5.mat", "plain_v7.mat", "controldesk.mat"] {
        let orig = std::fs::read(data(name)).unwrap();
        let mut variants: Vec<Vec<u8>> = (0..orig.len())
            .step_by(23)
            .map(|n| orig[..n].to_vec())
            .collect();
        for at in (0..orig.len()).step_by(29) {
            let mut v = orig.clone();
            v[at] ^= 0xA5;
            variants.push(v);
        }
        for v in variants {
            std::fs::write(&p, &v).unwrap();
            if load(&p, &LoadOptions::default()).is_err() {
                errors += 1;
            }
        }
    }
    // Every prefix shorter than the file must fail (about 610 of the ~1090
    // variants are prefixes); at the time of writing ~540 corruptions made the
    // third-party reader panic, which must have been contained.
    assert!(errors > 450, "{errors}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn write_mat_round_trip_is_bit_exact() {
    let n = 500;
    let mut s: u64 = 42;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let x = f64::from_bits(s);
        if x.is_finite() && x.abs() <= Recording::MAX_ABS {
            x
        } else {
            -0.0
        }
    };
    let friction: Vec<f64> = (0..n).map(|_| next()).collect();
    let optical: Vec<f64> = (0..n).map(|_| next()).collect();
    let rec = Recording::new(
        2500.0,
        Channels {
            friction_n: Some(friction),
            optical_v: Some(optical),
            ..Default::default()
        },
        Metadata {
            start_time_s: 1.5,
            ..Default::default()
        },
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("ballpass-mat-write-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("w.mat");
    write_mat(&rec, &p).unwrap();
    let back = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(back.fs_hz(), 2500.0);
    assert_eq!(back.meta.start_time_s, 1.5);
    assert_eq!(back.channels(), vec![Channel::Friction, Channel::Optical]);
    for c in [Channel::Friction, Channel::Optical] {
        assert_eq!(
            bits(back.channel(c).unwrap()),
            bits(rec.channel(c).unwrap())
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
