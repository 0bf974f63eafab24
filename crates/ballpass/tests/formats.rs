//! TDMS, MF4, MATLAB v7.3 and MATLAB struct recordings against the values
//! their own ecosystem's readers (npTDMS, asammdf, h5py, scipy.io) read from
//! the same committed files: `tools/make_format_fixtures.py` writes each
//! fixture with the format's writer and `FILE.expected.csv` with the
//! reference reader's values printed by `repr` (which round-trips), so the
//! comparison is bit for bit.

use std::path::PathBuf;

use ballpass::recording::io::contents;
use ballpass::recording::{load, Channel, GapPolicy, LoadOptions, Recording};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// The columns of `FILE.expected.csv` by name.
fn expected(name: &str) -> Vec<(String, Vec<f64>)> {
    let text = std::fs::read_to_string(data(&format!("{name}.expected.csv"))).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); header.len()];
    for line in lines {
        for (c, cell) in cols.iter_mut().zip(line.split(',')) {
            c.push(cell.parse().unwrap());
        }
    }
    header.into_iter().zip(cols).collect()
}

fn column(cols: &[(String, Vec<f64>)], name: &str) -> Vec<f64> {
    cols.iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no column {name}"))
        .1
        .clone()
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// Every channel of `rec` equals the reference reader's column bit for bit;
/// the time axis (when the reference has one) agrees with `time_s(i)`.
fn assert_matches(name: &str, rec: &Recording) {
    let cols = expected(name);
    for c in rec.channels() {
        assert_eq!(
            bits(rec.channel(c).unwrap()),
            bits(&column(&cols, c.column_name())),
            "{name} {c}"
        );
    }
    if let Some((_, t)) = cols.iter().find(|(n, _)| n == "time_s") {
        assert_eq!(t.len(), rec.len(), "{name}");
        // The references compute t0 + i * increment (npTDMS) or store the
        // times (asammdf, h5py); ballpass computes t0 + i / fs. The two
        // agree to the rounding of one product: 4 ulp of the largest time.
        let tol = 4.0 * f64::EPSILON * t.last().unwrap().abs().max(1.0);
        for (i, &ti) in t.iter().enumerate() {
            assert!((rec.time_s(i) - ti).abs() <= tol, "{name} t[{i}]");
        }
    }
}

#[test]
fn tdms_plain_two_segments_with_waveform_timing() {
    let r = load(&data("tdms_plain.tdms"), &LoadOptions::default()).unwrap();
    assert_eq!(r.fs_hz(), 1000.0);
    assert_eq!(r.len(), 200);
    assert_eq!(r.channels(), Channel::ALL.to_vec());
    assert_matches("tdms_plain.tdms", &r);
}

#[test]
fn tdms_time_channel_without_waveform_timing() {
    for name in ["tdms_timed.tdms", "tdms_stamps.tdms"] {
        let r = load(&data(name), &LoadOptions::default()).unwrap();
        assert_eq!(r.fs_hz(), 1000.0, "{name}");
        assert_eq!(r.len(), 200);
        assert_eq!(r.channels(), Channel::ALL.to_vec());
        // npTDMS's channels, and its float seconds.
        assert_matches(name, &r);
    }
    let r = load(&data("tdms_timed.tdms"), &LoadOptions::default()).unwrap();
    assert_eq!(r.meta.start_time_s, 3.25);
}

#[test]
fn tdms_ni_scaling_and_group_channel_paths() {
    let path = data("tdms_scaled.tdms");
    let mut o = LoadOptions::default();
    o.friction.name = Some("Force".into());
    o.position.name = Some("Bench 1/Position".into());
    // 'Voltage' is in both groups: named alone, it is an error listing both.
    o.optical.name = Some("Voltage".into());
    let e = load(&path, &o).unwrap_err().to_string();
    assert!(
        e.contains("'Bench 1/Voltage', 'Bench 2/Voltage'") && e.contains("full name"),
        "{e}"
    );
    o.optical.name = Some("bench 1/voltage".into());
    let r = load(&path, &o).unwrap();
    assert_eq!(r.fs_hz(), 1000.0);
    assert_matches("tdms_scaled.tdms", &r);
}

#[test]
fn tdms_interleaved_big_endian_and_daqmx_raw_data() {
    for name in [
        "tdms_interleaved.tdms",
        "tdms_bigendian.tdms",
        "tdms_daqmx.tdms",
    ] {
        let r = load(&data(name), &LoadOptions::default()).unwrap();
        assert_eq!(r.fs_hz(), 1000.0, "{name}");
        assert_eq!(r.len(), 200, "{name}");
        assert_matches(name, &r);
    }
}

#[test]
fn mf4_with_master_time_channel_plain_and_compressed() {
    for name in ["mf4_plain.mf4", "mf4_compressed.mf4"] {
        let r = load(&data(name), &LoadOptions::default()).unwrap();
        assert_eq!(r.fs_hz(), 1000.0, "{name}");
        assert_eq!(r.channels(), Channel::ALL.to_vec(), "{name}");
        assert_matches(name, &r);
    }
}

#[test]
fn mf4_invalid_samples_are_gaps() {
    let path = data("mf4_invalid.mf4");
    let e = load(&path, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("mf4_invalid.mf4")
            && e.contains("sample 51")
            && e.contains("no finite value in friction_N for 2 sample(s)")
            && e.contains("2 gaps"),
        "{e}"
    );
    let o = LoadOptions {
        gaps: GapPolicy {
            fill_max_s: Some(0.005),
            split: false,
        },
        ..Default::default()
    };
    let r = load(&path, &o).unwrap();
    let want = column(&expected("mf4_invalid.mf4"), "friction_N");
    let got = r.channel(Channel::Friction).unwrap();
    for (i, (&g, &w)) in got.iter().zip(&want).enumerate() {
        if w.is_nan() {
            // Linear between the neighbours, as the notes say.
            let (l, h) = match i {
                50 => (49, 52),
                51 => (49, 52),
                _ => (119, 121),
            };
            let f = (i - l) as f64 / (h - l) as f64;
            let lin = want[l] + (want[h] - want[l]) * f;
            assert!((g - lin).abs() <= 1e-15, "{i}: {g} vs {lin}");
        } else {
            assert_eq!(g.to_bits(), w.to_bits(), "{i}");
        }
    }
    assert!(
        r.meta.notes.iter().any(|n| n.contains("filled 2 gap(s)")),
        "{:?}",
        r.meta.notes
    );
}

#[test]
fn mf4_channels_of_different_rates_are_not_one_recording() {
    let e = load(&data("mf4_two_rates.mf4"), &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("different time axes"), "{e}");
    // Either alone loads, at its own rate.
    let mut o = LoadOptions::default();
    o.optical.name = Some("slow/optical_V".into());
    o.friction.name = None;
    let r = load(&data("mf4_two_rates.mf4"), &o);
    // friction_N is still found by its default name: the pair is refused.
    assert!(r.is_err());
}

#[test]
fn matlab_v73_plain_variables_read_like_v5() {
    let r = load(&data("v73_plain.mat"), &LoadOptions::default()).unwrap();
    assert_eq!(r.fs_hz(), 1000.0);
    assert_eq!(r.channels(), Channel::ALL.to_vec());
    assert_matches("v73_plain.mat", &r);
    // The same numbers as the level-5 fixture.
    let v5 = load(&data("plain_v5.mat"), &LoadOptions::default()).unwrap();
    for c in Channel::ALL {
        assert_eq!(bits(r.channel(c).unwrap()), bits(v5.channel(c).unwrap()));
    }
}

/// Many chunks (deflate, shuffle, a row vector, int16 counts) read as h5py
/// reads them.
#[test]
fn matlab_v73_chunked_variables_read_as_h5py_reads_them() {
    let r = load(&data("v73_chunked.mat"), &LoadOptions::default()).unwrap();
    assert_eq!(r.fs_hz(), 1000.0);
    assert_eq!(r.len(), 2000);
    assert_matches("v73_chunked.mat", &r);
}

#[test]
fn matlab_v73_controldesk_layout() {
    let mut o = LoadOptions::default();
    o.friction.name = Some("force".into());
    o.position.name = Some("Counts".into());
    o.position.scale = 1e-4;
    o.optical.name = Some("Model Root/Photodetector/Voltage".into());
    let r = load(&data("v73_controldesk.mat"), &o).unwrap();
    assert_eq!(r.fs_hz(), 1000.0);
    assert_matches("v73_controldesk.mat", &r);
}

fn struct_options() -> LoadOptions {
    let mut o = LoadOptions::default();
    o.friction.name = Some("bearing.gs".into());
    o.optical.name = Some("signals{1}".into());
    o.fs_from = Some("bearing.sr".into());
    o
}

#[test]
fn struct_fields_by_path_and_the_rate_from_a_field() {
    let mut o = struct_options();
    o.position.name = Some("nested.inner.data".into());
    let r = load(&data("struct_v5.mat"), &o).unwrap();
    assert_eq!(r.fs_hz(), 1000.0);
    assert_eq!(r.channels(), Channel::ALL.to_vec());
    assert_matches("struct_v5.mat", &r);
    let r73 = load(&data("v73_struct.mat"), &struct_options()).unwrap();
    assert_eq!(r73.fs_hz(), 1000.0);
    assert_matches("v73_struct.mat", &r73);
    for c in [Channel::Friction, Channel::Optical] {
        assert_eq!(bits(r.channel(c).unwrap()), bits(r73.channel(c).unwrap()));
    }
    // Paths that lead nowhere say what is there.
    let mut bad = struct_options();
    bad.friction.name = Some("bearing.gz".into());
    let e = load(&data("struct_v5.mat"), &bad).unwrap_err().to_string();
    assert!(
        e.contains("no field 'gz'") && e.contains("gs, sr, load, rate"),
        "{e}"
    );
    bad.friction.name = Some("signals{2}".into());
    let e = load(&data("struct_v5.mat"), &bad).unwrap_err().to_string();
    assert!(e.contains("'signals{2}' is text"), "{e}");
    bad.friction.name = Some("bearing".into());
    let e = load(&data("struct_v5.mat"), &bad).unwrap_err().to_string();
    assert!(
        e.contains("is a struct; name a field, as in 'bearing.gs'"),
        "{e}"
    );
}

#[test]
fn inspect_lists_what_each_format_holds() {
    let o = LoadOptions::default();
    let has = |name: &str, item: &str, what: &str| {
        let c = contents(&data(name), &o, 500).unwrap();
        assert!(
            c.iter().any(|(n, w)| n == item && w.contains(what)),
            "{name}: {item} {what} not in {c:?}"
        );
    };
    has("struct_v5.mat", "bearing.gs", "double 200x1");
    has("struct_v5.mat", "bearing.sr", "double 1x1");
    has("struct_v5.mat", "nested.inner.data", "double 200x1");
    has("struct_v5.mat", "signals{2}", "char 'label'");
    has("v73_struct.mat", "bearing.gs", "double 200x1");
    has("v73_controldesk.mat", "rec_9mm_s.Y(2).Data", "int32 200x1");
    has("tdms_scaled.tdms", "Bench 1/Force", "int16, 200 values");
    has("tdms_scaled.tdms", "Bench 2", "group of 1 channel");
    has("tdms_plain.tdms", "Measurements/friction_N", "1000 Hz");
    has("mf4_plain.mf4", "bench/friction_N", "200 samples");
    has("mf4_plain.mf4", "bench/time", "master");
}

/// One run per group, as LabVIEW logs them: `FILE#GROUP` reads that run,
/// bit for bit as npTDMS reads the group; the record is named after it.
#[test]
fn tdms_runs_one_per_group_are_named_file_hash_group() {
    for k in 1..=3 {
        let spec = PathBuf::from(format!("{}#Run {k}", data("tdms_runs.tdms").display()));
        let r = load(&spec, &LoadOptions::default()).unwrap();
        assert_eq!(r.fs_hz(), 1000.0);
        assert_eq!(r.len(), 200 - 20 * (k - 1));
        assert_eq!(r.channels(), Channel::ALL.to_vec());
        assert_matches(&format!("tdms_runs.tdms.run{k}"), &r);
        assert!(r
            .source_name()
            .ends_with(&format!("tdms_runs.tdms#Run {k}")));
        assert_eq!(
            r.meta.test_id.as_deref(),
            Some(&*format!("tdms_runs#Run {k}"))
        );
    }
    // The group's name ignoring case, as channel names.
    let spec = PathBuf::from(format!("{}#run 2", data("tdms_runs.tdms").display()));
    assert_eq!(load(&spec, &LoadOptions::default()).unwrap().len(), 180);
    // Only that group's contents.
    let c = contents(&spec, &LoadOptions::default(), 100).unwrap();
    assert!(c.iter().all(|(n, _)| n.starts_with("Run 2")), "{c:?}");
    assert_eq!(c.len(), 4, "{c:?}");
}

#[test]
fn tdms_runs_wrong_or_missing_names_say_what_the_file_holds() {
    let file = data("tdms_runs.tdms");
    let holds = "'Run 1' (3 channels), 'Run 2' (3 channels), 'Run 3' (3 channels)";
    // No group named: the channel names are in every group.
    let e = load(&file, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(holds) && e.contains("FILE#GROUP") && !e.contains('\n'),
        "{e}"
    );
    let spec = PathBuf::from(format!("{}#Run 9", file.display()));
    let e = load(&spec, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no group 'Run 9'") && e.contains(holds) && e.contains("tdms_runs.tdms"),
        "{e}"
    );
    let spec = PathBuf::from(format!("{}#", file.display()));
    assert!(load(&spec, &LoadOptions::default()).is_err());
    // A record name on a format that holds one record.
    let spec = PathBuf::from(format!("{}#rec", data("plain_v5.mat").display()));
    let e = load(&spec, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("only TDMS files") && e.contains("mat"), "{e}");
}

/// A file whose name holds `#` is that file.
#[test]
fn a_file_named_with_a_hash_is_read_as_it_is() {
    let d = std::env::temp_dir().join(format!("ballpass-hash-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let p = d.join("run#1.csv");
    std::fs::write(
        &p,
        (0..100).fold("time_s,friction_N\n".to_string(), |s, i| {
            s + &format!("{},{}\n", i as f64 / 100.0, i)
        }),
    )
    .unwrap();
    let r = load(&p, &LoadOptions::default()).unwrap();
    assert_eq!(r.len(), 100);
    std::fs::remove_dir_all(&d).unwrap();
}
