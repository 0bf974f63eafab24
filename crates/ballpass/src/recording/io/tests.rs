//! Round trip and bad-input tests of the CSV reader and writer.

use std::path::{Path, PathBuf};

use super::*;
use crate::recording::{Channels, Metadata};

/// A fresh empty folder under the system temp dir, unique per test,
/// removed when the test ends.
fn scratch(name: &str) -> crate::test_scratch::Scratch {
    crate::test_scratch::scratch_in("io", name)
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Deterministic awkward values: a linear congruential generator over bit
/// patterns plus the edge cases of float formatting.
fn awkward(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    let specials = [
        -0.0,
        0.0,
        5e-324,
        -2.2250738585072014e-308,
        1e100,
        -9.999999999999999e99,
        0.1,
        1.0 / 3.0,
        -1e-7,
        123456789012345680.0,
    ];
    (0..n)
        .map(|i| {
            if i < specials.len() {
                return specials[i];
            }
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let x = f64::from_bits(s);
            if x.is_finite() && x.abs() <= Recording::MAX_ABS {
                x
            } else {
                (s >> 11) as f64 * 1e-3
            }
        })
        .collect()
}

fn rec(fs: f64, start: f64, n: usize, channels: Channels) -> Recording {
    let _ = n;
    Recording::new(
        fs,
        channels,
        Metadata {
            start_time_s: start,
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn csv_round_trip_is_bit_exact() {
    let dir = scratch("roundtrip");
    for (k, (fs, start)) in [
        (1000.0, 0.0),
        (1234.5, 12.5),
        (2500.0, -3.0),
        (48000.0, 1e-3),
    ]
    .into_iter()
    .enumerate()
    {
        let n = 3000;
        let r = rec(
            fs,
            start,
            n,
            Channels {
                friction_n: Some(awkward(n, 1 + k as u64)),
                position_mm: Some(awkward(n, 100 + k as u64)),
                optical_v: Some(awkward(n, 200 + k as u64)),
            },
        );
        let p = dir.join(format!("r{k}.csv"));
        write_csv(&r, &p).unwrap();
        let back = load(&p, &LoadOptions::default()).unwrap();
        assert_eq!(back.fs_hz().to_bits(), fs.to_bits(), "fs {fs}");
        assert_eq!(back.meta.start_time_s.to_bits(), start.to_bits());
        assert_eq!(back.len(), n);
        for c in Channel::ALL {
            let a: Vec<u64> = r.channel(c).unwrap().iter().map(|x| x.to_bits()).collect();
            let b: Vec<u64> = back
                .channel(c)
                .unwrap()
                .iter()
                .map(|x| x.to_bits())
                .collect();
            assert_eq!(a, b, "channel {c} at fs {fs}");
        }
    }
    // A subset of channels keeps its subset, and no temporary file is left over.
    let r = rec(
        1000.0,
        0.0,
        100,
        Channels {
            optical_v: Some(awkward(100, 7)),
            ..Default::default()
        },
    );
    let p = dir.join("optical.csv");
    write_csv(&r, &p).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.starts_with("time_s,optical_V\n"), "{}", &text[..40]);
    let back = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(back.channels(), vec![Channel::Optical]);
    assert_eq!(back.channel(Channel::Optical), r.channel(Channel::Optical));
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn write_to_a_missing_folder_is_an_io_error_naming_the_file() {
    let r = rec(
        1000.0,
        0.0,
        20,
        Channels {
            optical_v: Some(vec![1.0; 20]),
            ..Default::default()
        },
    );
    let p = std::env::temp_dir().join("ballpass-no-such-dir-xyz/r.csv");
    let e = write_csv(&r, &p).unwrap_err().to_string();
    assert!(e.contains("ballpass-no-such-dir-xyz/r.csv"), "{e}");
}

/// A valid 1 kHz file of `n` rows with the given header and a row formatter.
fn table(header: &str, n: usize, row: impl Fn(usize) -> String) -> String {
    let mut s = String::from(header);
    s.push('\n');
    for i in 0..n {
        s.push_str(&row(i));
        s.push('\n');
    }
    s
}

fn err_of(dir: &Path, name: &str, text: &str, opts: &LoadOptions) -> String {
    let p = write(dir, name, text);
    load(&p, opts).unwrap_err().to_string()
}

#[test]
fn comments_blank_lines_bom_case_and_mapping() {
    let dir = scratch("mapping");
    let mut text = String::from("\u{feff}# bench 2, run 7\n\n");
    text.push_str(&table("Zeit;Kraft;Enc;OPTICAL_v", 50, |i| {
        format!("{};{};{};{}", i as f64 * 0.001, i, 10 * i, 0.5)
    }));
    text.push_str("# trailing comment\n");
    let p = write(&dir, "bench.csv", &text);
    let mut o = LoadOptions {
        time: Some("zeit".into()),
        ..Default::default()
    };
    o.friction.name = Some("kraft".into());
    o.position = ChannelSource {
        name: Some("Enc".into()),
        scale: 1e-4,
        offset: 1.0,
    };
    let r = load(&p, &o).unwrap();
    assert_eq!(r.fs_hz(), 1000.0);
    assert_eq!(r.len(), 50);
    assert_eq!(r.channel(Channel::Friction).unwrap()[3], 3.0);
    // 30 counts * 1e-4 + 1 mm: one rounding each for the product and the sum.
    assert!((r.channel(Channel::Position).unwrap()[3] - 1.003).abs() < 1e-15);
    assert_eq!(r.channel(Channel::Optical).unwrap()[0], 0.5);
    assert_eq!(r.meta.test_id.as_deref(), Some("bench"));
}

#[test]
fn tsv_and_fs_without_time_column() {
    let dir = scratch("tsv");
    let text = table("friction_N\toptical_V", 40, |i| format!("{i}\t1"));
    let p = write(&dir, "a.tsv", &text);
    let e = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("no time column") && e.contains("a.tsv"), "{e}");
    let r = load(
        &p,
        &LoadOptions {
            fs_hz: Some(500.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(r.fs_hz(), 500.0);
    assert_eq!(r.channels(), vec![Channel::Friction, Channel::Optical]);
}

#[test]
fn empty_file_and_header_only_are_errors() {
    let dir = scratch("empty");
    let o = LoadOptions::default();
    let e = err_of(&dir, "e.csv", "", &o);
    assert!(e.contains("e.csv") && e.contains("empty"), "{e}");
    let e = err_of(&dir, "c.csv", "# only a comment\n\n", &o);
    assert!(e.contains("c.csv") && e.contains("no header"), "{e}");
    let e = err_of(&dir, "h.csv", "time_s,friction_N\n", &o);
    assert!(e.contains("h.csv") && e.contains("no data rows"), "{e}");
}

#[test]
fn text_cell_names_file_line_and_column() {
    let dir = scratch("textcell");
    let text = table("time_s,friction_N,optical_V", 30, |i| {
        if i == 12 {
            format!("{},oops,1", i as f64 / 1000.0)
        } else {
            format!("{},1,1", i as f64 / 1000.0)
        }
    });
    let e = err_of(&dir, "t.csv", &text, &LoadOptions::default());
    assert_eq!(
        e,
        "t.csv:14 column 'friction_N': 'oops' is not a number"
            .replace("t.csv", &dir.join("t.csv").display().to_string())
    );
    let text = table("time_s,friction_N", 30, |i| {
        if i == 3 {
            format!("{},", i as f64 / 1000.0)
        } else if i == 5 {
            format!("{},nan", i as f64 / 1000.0)
        } else {
            format!("{},1", i as f64 / 1000.0)
        }
    });
    // An empty cell and `nan` are gaps: refused by default, naming the first.
    let e = err_of(&dir, "c.csv", &text, &LoadOptions::default());
    assert!(
        e.contains("c.csv:5 column 'friction_N': no finite value in friction_N for 1 sample(s)")
            && e.contains("2 gaps")
            && e.contains("fill-gaps"),
        "{e}"
    );
    let text = text.replace("0.003,\n", "0.003,2\n");
    let e = err_of(&dir, "n.csv", &text, &LoadOptions::default());
    assert!(
        e.contains("n.csv:7 column 'friction_N': no finite value"),
        "{e}"
    );
}

#[test]
fn ragged_row_names_the_line() {
    let dir = scratch("ragged");
    let text = table("time_s,friction_N,optical_V", 30, |i| {
        if i == 20 {
            format!("{},1", i as f64 / 1000.0)
        } else {
            format!("{},1,2", i as f64 / 1000.0)
        }
    });
    let e = err_of(&dir, "r.csv", &text, &LoadOptions::default());
    assert!(
        e.contains("r.csv:22: 2 field(s), but the header (line 1) has 3"),
        "{e}"
    );
}

#[test]
fn bad_time_columns_name_the_line() {
    let dir = scratch("time");
    let o = LoadOptions::default();
    let mk = |f: &dyn Fn(usize) -> f64| table("time_s,friction_N", 40, |i| format!("{},1", f(i)));
    // Decreasing at data row 10 (line 12: the header is line 1).
    let e = err_of(
        &dir,
        "d.csv",
        &mk(&|i| if i == 10 { 0.0005 } else { i as f64 / 1000.0 }),
        &o,
    );
    assert!(
        e.contains("d.csv:12 column 'time_s'") && e.contains("backwards"),
        "{e}"
    );
    // Duplicate at data row 20 (line 22).
    let e = err_of(
        &dir,
        "u.csv",
        &mk(&|i| if i == 20 { 0.019 } else { i as f64 / 1000.0 }),
        &o,
    );
    assert!(
        e.contains("u.csv:22 column 'time_s'") && e.contains("duplicate"),
        "{e}"
    );
    // Non-uniform: the step doubles from row 30 on.
    let e = err_of(
        &dir,
        "n.csv",
        &mk(&|i| {
            if i < 30 {
                i as f64 / 1000.0
            } else {
                0.029 + (i - 29) as f64 * 0.0015
            }
        }),
        &o,
    );
    assert!(
        e.contains("n.csv:32 column 'time_s'") && e.contains("not uniform"),
        "{e}"
    );
    // A missing sample is named as such.
    let e = err_of(
        &dir,
        "m.csv",
        &mk(&|i| {
            if i < 25 {
                i as f64 / 1000.0
            } else {
                (i + 1) as f64 / 1000.0
            }
        }),
        &o,
    );
    assert!(
        e.contains("m.csv:27") && e.contains("1 sample(s) missing"),
        "{e}"
    );
}

#[test]
fn given_rate_is_checked_against_the_time_column() {
    let dir = scratch("fs");
    let text = table("time_s,optical_V", 1000, |i| {
        format!("{},1", i as f64 / 1000.0)
    });
    let p = write(&dir, "f.csv", &text);
    let ok = LoadOptions {
        fs_hz: Some(1000.0),
        ..Default::default()
    };
    assert_eq!(load(&p, &ok).unwrap().fs_hz(), 1000.0);
    let bad = LoadOptions {
        fs_hz: Some(2000.0),
        ..Default::default()
    };
    let e = load(&p, &bad).unwrap_err().to_string();
    assert!(
        e.contains("f.csv") && e.contains("2000 Hz") && e.contains("disagrees"),
        "{e}"
    );
    let ignore = LoadOptions {
        fs_hz: Some(2000.0),
        ignore_time: true,
        ..Default::default()
    };
    assert_eq!(load(&p, &ignore).unwrap().fs_hz(), 2000.0);
}

#[test]
fn missing_and_unknown_columns_are_named() {
    let dir = scratch("missing");
    let text = table("time_s,force,optical_V", 30, |i| {
        format!("{},1,1", i as f64 / 1000.0)
    });
    let p = write(&dir, "m.csv", &text);
    let mut o = LoadOptions::default();
    o.friction.name = Some("Friction".into());
    let e = load(&p, &o).unwrap_err().to_string();
    assert!(
        e.contains("m.csv:1")
            && e.contains("no column 'Friction'")
            && e.contains("'time_s', 'force', 'optical_V'"),
        "{e}"
    );
    // Without a mapping the file loads with the optical channel only, and an
    // analysis asking for friction is told it is missing.
    let r = load(&p, &LoadOptions::default()).unwrap();
    let e = r
        .require(Channel::Friction, "correlation")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("friction_N is missing") && e.contains("m.csv"),
        "{e}"
    );
    let text = table("time_s,a,b", 30, |i| format!("{},1,1", i as f64 / 1000.0));
    let e = err_of(&dir, "none.csv", &text, &LoadOptions::default());
    assert!(
        e.contains("none.csv:1") && e.contains("no channel column"),
        "{e}"
    );
}

#[test]
fn too_few_periods_is_an_error_when_velocity_and_bearing_are_known() {
    let dir = scratch("periods");
    // 2 s at 1 mm/s with SR25W: tau_c = 8.11 s, 0.25 periods.
    let text = table("time_s,optical_V", 2000, |i| {
        format!("{},1", i as f64 / 1000.0)
    });
    let p = write(&dir, "s.csv", &text);
    let o = LoadOptions {
        velocity_mm_s: Some(1.0),
        geometry: Some(crate::bearing::lookup("sr25w").unwrap().geometry),
        ..Default::default()
    };
    let e = load(&p, &o).unwrap_err().to_string();
    assert!(
        e.contains("s.csv") && e.contains("0.25 ball-pass periods"),
        "{e}"
    );
    let o = LoadOptions {
        min_periods: 0.2,
        ..o
    };
    assert!(load(&p, &o).is_ok());
}

#[test]
fn bad_options_are_rejected() {
    let p = Path::new("unused.csv");
    for o in [
        LoadOptions {
            fs_hz: Some(0.0),
            ..Default::default()
        },
        LoadOptions {
            velocity_mm_s: Some(-1.0),
            ..Default::default()
        },
        LoadOptions {
            ignore_time: true,
            ..Default::default()
        },
        LoadOptions {
            friction: ChannelSource {
                scale: 0.0,
                ..Default::default()
            },
            ..Default::default()
        },
    ] {
        assert!(
            matches!(load(p, &o), Err(Error::InvalidSetting { .. })),
            "{o:?}"
        );
    }
}
