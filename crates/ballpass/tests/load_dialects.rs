//! Text recordings as labs write them (decimal commas, units rows, time in
//! ms or µs, metadata lines before the header), gaps refused, filled or
//! split at, and the messages of bad cells (issue 15; issue 18 items 10, 11).

use std::path::{Path, PathBuf};

use ballpass::recording::io::csv::check_fast_path_agrees;
use ballpass::recording::{load, load_all, Channel, GapPolicy, LoadOptions, TimeUnit};

#[path = "common/scratch.rs"]
mod scratch_dir;

fn scratch(name: &str) -> scratch_dir::Scratch {
    scratch_dir::scratch_in("dialects", name)
}

fn write(dir: &Path, name: &str, text: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// `header` then `n` rows from `row(i)`, `\n`-ended.
fn table(header: &str, n: usize, row: impl Fn(usize) -> String) -> String {
    let mut s = format!("{header}\n");
    for i in 0..n {
        s.push_str(&row(i));
        s.push('\n');
    }
    s
}

/// Issue 18, item 10: a last line `# end` without a line end is a comment
/// for both CSV readers (the general one took it for a one-field row).
#[test]
fn csv_readers_agree_on_a_last_comment_line_without_newline() {
    let dir = scratch("endcomment");
    let text = table("time_s,friction_N", 40, |i| {
        format!("{},{}", i as f64 / 1000.0, i)
    }) + "# end";
    assert_eq!(check_fast_path_agrees(text.as_bytes()), Ok(()));
    let r = load(
        &write(&dir, "a.csv", text.as_bytes()),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(r.len(), 40);
    // The same file with a quote (general reader only) reads the same.
    let quoted = text.replacen("time_s", "\"time_s\"", 1);
    let q = load(
        &write(&dir, "q.csv", quoted.as_bytes()),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(q.channel(Channel::Friction), r.channel(Channel::Friction));
    for end in ["#", "# end\r", "#x,y", "# end\n\n"] {
        let t = table("time_s,friction_N", 20, |i| {
            format!("{},{}", i as f64 / 1000.0, i)
        }) + end;
        assert_eq!(check_fast_path_agrees(t.as_bytes()), Ok(()), "{end:?}");
        assert!(
            load(&write(&dir, "e.csv", t.as_bytes()), &LoadOptions::default()).is_ok(),
            "{end:?}"
        );
    }
}

#[test]
fn decimal_comma_is_detected_or_set() {
    let dir = scratch("comma");
    let text = table("time_s;friction_N;optical_V", 40, |i| {
        format!(
            "{};{},5;0,{}",
            (i as f64 / 1000.0).to_string().replace('.', ","),
            i,
            i % 10
        )
    });
    let r = load(
        &write(&dir, "de.csv", text.as_bytes()),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(r.fs_hz(), 1000.0);
    assert_eq!(r.channel(Channel::Friction).unwrap()[3], 3.5);
    assert_eq!(r.channel(Channel::Optical).unwrap()[7], 0.7);
    assert!(r.meta.notes.iter().any(|n| n.contains("decimal comma")));
    // Tab-separated, set explicitly.
    let tsv = text.replace(';', "\t");
    let o = LoadOptions {
        decimal_comma: Some(true),
        ..Default::default()
    };
    let t = load(&write(&dir, "de.tsv", tsv.as_bytes()), &o).unwrap();
    assert_eq!(t.channel(Channel::Friction), r.channel(Channel::Friction));
    // A ','-separated file cannot have a decimal comma.
    let o = LoadOptions {
        decimal_comma: Some(true),
        delimiter: Some(b','),
        ..Default::default()
    };
    let e = load(&write(&dir, "x.csv", b"a\n"), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("decimal-comma"), "{e}");
    // Without detection (a '.' somewhere), '1,5' says what it may be.
    let mixed = text.replacen("0,003;", "0.003;", 1);
    let e = load(
        &write(&dir, "m.csv", mixed.as_bytes()),
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("decimal comma?"), "{e}");
}

#[test]
fn units_row_is_read_as_units() {
    let dir = scratch("units");
    let text = table("Zeit;Kraft;Weg\n[ms];[kN];[µm]", 40, |i| {
        format!("{};{};{}", i, 0.002 + i as f64 * 1e-6, 9.0 * i as f64)
    });
    let mut o = LoadOptions {
        time: Some("Zeit".into()),
        ..Default::default()
    };
    o.friction.name = Some("Kraft".into());
    o.position.name = Some("Weg".into());
    let r = load(&write(&dir, "u.csv", text.as_bytes()), &o).unwrap();
    // ms time: 1 kHz, never read as seconds (1 Hz).
    assert_eq!(r.fs_hz(), 1000.0);
    // kN → N, µm → mm.
    assert_eq!(r.channel(Channel::Friction).unwrap()[0], 2.0);
    assert!((r.channel(Channel::Position).unwrap()[10] - 0.09).abs() < 1e-15);
    assert!(r
        .meta
        .notes
        .iter()
        .any(|n| n.contains("in kN") && n.contains("x1000")));
    // A unit ballpass cannot convert needs a scale.
    let counts = text.replace("[µm]", "counts");
    let e = load(&write(&dir, "c.csv", counts.as_bytes()), &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'counts'") && e.contains("units row, line 2") && e.contains("position scale"),
        "{e}"
    );
    o.position.scale = 1e-4;
    assert!(load(&write(&dir, "c.csv", counts.as_bytes()), &o).is_ok());
}

#[test]
fn time_in_ms_or_us_from_the_header_or_a_setting() {
    let dir = scratch("timeunit");
    for (header, step) in [("time_ms", 1.0), ("t [ms]", 1.0), ("Zeit (µs)", 1000.0)] {
        let text = table(&format!("{header},friction_N"), 40, |i| {
            format!("{},{}", i as f64 * step, i)
        });
        let r = load(
            &write(&dir, "t.csv", text.as_bytes()),
            &LoadOptions::default(),
        )
        .unwrap();
        assert_eq!(r.fs_hz(), 1000.0, "{header}");
    }
    // A bare 'time' column in ms needs the unit said.
    let text = table("time,friction_N", 40, |i| format!("{i},{i}"));
    let p = write(&dir, "bare.csv", text.as_bytes());
    let o = LoadOptions {
        time: Some("time".into()),
        time_unit: Some(TimeUnit::Ms),
        ..Default::default()
    };
    assert_eq!(load(&p, &o).unwrap().fs_hz(), 1000.0);
    // A setting that contradicts the file is an error, not a guess.
    let text = table("time_ms,friction_N", 40, |i| format!("{i},{i}"));
    let o = LoadOptions {
        time_unit: Some(TimeUnit::S),
        ..Default::default()
    };
    let e = load(&write(&dir, "c.csv", text.as_bytes()), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("s given") && e.contains("says ms"), "{e}");
}

#[test]
fn metadata_lines_before_the_header() {
    let dir = scratch("preamble");
    let body = table("time_s;friction_N", 40, |i| {
        format!("{};{}", i as f64 / 1000.0, i)
    });
    let text = format!("LabVIEW export\nDate: 2024-01-02\nOperator;Jane Doe\n\n{body}");
    let r = load(
        &write(&dir, "p.csv", text.as_bytes()),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(r.len(), 40);
    assert!(
        r.meta
            .notes
            .iter()
            .any(|n| n.contains("3 metadata line(s)")),
        "{:?}",
        r.meta.notes
    );
    // Errors count lines from the top of the file.
    let bad = text.replacen("0.003;3", "0.003;x", 1);
    let e = load(
        &write(&dir, "b.csv", bad.as_bytes()),
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("b.csv:9 column 'friction_N'"), "{e}");
    // Given explicitly.
    let o = LoadOptions {
        skip_lines: Some(4),
        ..Default::default()
    };
    assert_eq!(
        load(&write(&dir, "p.csv", text.as_bytes()), &o)
            .unwrap()
            .len(),
        40
    );
}

/// Issue 18, item 11: a bad cell is quoted bounded and escaped.
#[test]
fn bad_cells_are_quoted_bounded_and_escaped() {
    let dir = scratch("badcell");
    let huge = "x".repeat(1_000_000);
    let text = table("time_s,friction_N", 30, |i| {
        if i == 5 {
            format!("{},{huge}", i as f64 / 1000.0)
        } else {
            format!("{},{i}", i as f64 / 1000.0)
        }
    });
    let e = load(
        &write(&dir, "h.csv", text.as_bytes()),
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.len() < 400 && e.contains("… (1000000 characters)"),
        "{}",
        &e[..e.len().min(400)]
    );
    let text = table("time_s,friction_N", 30, |i| {
        if i == 5 {
            format!("{},\"1\r\n\x1b[31mred\"", i as f64 / 1000.0)
        } else {
            format!("{},{i}", i as f64 / 1000.0)
        }
    });
    let e = load(
        &write(&dir, "esc.csv", text.as_bytes()),
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        !e.contains('\r')
            && !e.contains('\n')
            && !e.contains('\x1b')
            && e.contains("\\r\\n\\x1b[31m"),
        "{e:?}"
    );
    // A file name with a line end is shown escaped too.
    let p = write(&dir, "a\nb.csv", b"nothing here\n");
    let e = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    assert!(!e.contains('\n') && e.contains("a\\nb.csv"), "{e:?}");
}

/// Issue 18, item 11: values near 1e307 are refused naming the channel and
/// the line, not passed on to overflow an analysis ("non-finite value (NaN)
/// at index 0").
#[test]
fn values_near_1e307_name_the_channel() {
    let dir = scratch("huge");
    let text = table("time_s,friction_N,optical_V", 30, |i| {
        format!(
            "{},1,{}",
            i as f64 / 1000.0,
            if i == 7 { 1.5e307 } else { 0.5 }
        )
    });
    let e = load(
        &write(&dir, "v.csv", text.as_bytes()),
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("v.csv:9 column 'optical_V'") && e.contains("optical_V: value 1.5e307"),
        "{e}"
    );
    // A scale that takes sane numbers there is refused the same way.
    let text = table("time_s,friction_N", 30, |i| {
        format!("{},1e90", i as f64 / 1000.0)
    });
    let mut o = LoadOptions::default();
    o.friction.scale = 1e20;
    let e = load(&write(&dir, "s.csv", text.as_bytes()), &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("after scaling") && e.contains("friction_N"),
        "{e}"
    );
}

fn gappy(dir: &Path) -> PathBuf {
    // 1 kHz; samples 100-102 missing from the time column; friction NaN at
    // 300 (one sample) and 600-899 (0.3 s).
    let mut s = String::from("time_s,friction_N,optical_V\n");
    for i in 0..1000 {
        if (100..103).contains(&i) {
            continue;
        }
        let f = if i == 300 || (600..900).contains(&i) {
            "NaN".to_string()
        } else {
            format!("{}", i as f64 * 0.5)
        };
        s.push_str(&format!("{},{f},{}\n", i as f64 / 1000.0, i % 7));
    }
    write(dir, "gappy.csv", s.as_bytes())
}

#[test]
fn gaps_are_refused_with_their_position_by_default() {
    let dir = scratch("gaps");
    let p = gappy(&dir);
    let e = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    assert!(
        e.contains("gappy.csv:102 column 'time'")
            && e.contains("3 sample(s) missing from the time column at t = 0.100000 s")
            && e.contains("3 gaps")
            && e.contains("fill-gaps"),
        "{e}"
    );
}

#[test]
fn short_gaps_are_filled_and_long_ones_split_on_request() {
    let dir = scratch("fill");
    let p = gappy(&dir);
    // Fill up to 5 ms: the 3 missing samples and the single NaN; the 0.3 s
    // gap remains and is refused.
    let fill = LoadOptions {
        gaps: GapPolicy {
            fill_max_s: Some(0.005),
            split: false,
        },
        ..Default::default()
    };
    let e = load(&p, &fill).unwrap_err().to_string();
    assert!(
        e.contains("for 300 sample(s)") && e.contains("0.300000 s long"),
        "{e}"
    );
    // And split: two pieces, the gaps filled in the first.
    let both = LoadOptions {
        gaps: GapPolicy {
            fill_max_s: Some(0.005),
            split: true,
        },
        ..Default::default()
    };
    let pieces = load_all(&p, &both).unwrap();
    assert_eq!(pieces.len(), 2);
    let (a, b) = (&pieces[0], &pieces[1]);
    assert_eq!((a.len(), b.len()), (600, 100));
    assert_eq!(a.fs_hz(), 1000.0);
    assert_eq!(b.meta.start_time_s, 0.9);
    assert_eq!(a.meta.test_id.as_deref(), Some("gappy_part1"));
    // Linear through the filled samples (friction is 0.5 i there).
    let f = a.channel(Channel::Friction).unwrap();
    for i in [100, 101, 102, 300] {
        assert!((f[i] - 0.5 * i as f64).abs() < 1e-12, "{i}: {}", f[i]);
    }
    assert!(
        a.meta.notes.iter().any(|n| n.contains("filled 2 gap(s)")),
        "{:?}",
        a.meta.notes
    );
    assert!(b.meta.notes.iter().any(|n| n.contains("piece 2 of 2")));
    // load() wants one recording per file.
    let e = load(&p, &both).unwrap_err().to_string();
    assert!(e.contains("2 pieces"), "{e}");
}

#[test]
fn edge_gaps_are_cut_when_repairs_are_asked_for() {
    let dir = scratch("edges");
    let text = table("time_s,friction_N", 50, |i| {
        let v = if !(3..47).contains(&i) {
            "nan".to_string()
        } else {
            i.to_string()
        };
        format!("{},{v}", i as f64 / 1000.0)
    });
    let p = write(&dir, "e.csv", text.as_bytes());
    assert!(load(&p, &LoadOptions::default()).is_err());
    let o = LoadOptions {
        gaps: GapPolicy {
            fill_max_s: Some(0.001),
            split: false,
        },
        ..Default::default()
    };
    let r = load(&p, &o).unwrap();
    assert_eq!(r.len(), 44);
    assert_eq!(r.meta.start_time_s, 0.003);
    assert_eq!(r.channel(Channel::Friction).unwrap()[0], 3.0);
}
