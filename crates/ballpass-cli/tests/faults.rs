//! Hostile files and faults through the real binary (issue 18): each test
//! is named after the item it guards.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ballpass::outdir::{RunManifest, LOCK_FILE, RUN_FILE};
use common::{bin, library_test_file, output, run, scratch, scratch_path};

fn fixture() -> PathBuf {
    library_test_file("fixtures/analyze/input.csv")
}

/// The fixture (8 s at 200 Hz, 18 mm/s) with column `col` (0-based, time
/// first) replaced by `value` in every row.
fn fixture_with(col: usize, value: &str) -> String {
    let text = std::fs::read_to_string(fixture()).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        if i == 0 {
            out.push_str(line);
        } else {
            let mut cells: Vec<&str> = line.split(',').collect();
            cells[col] = value;
            out.push_str(&cells.join(","));
        }
        out.push('\n');
    }
    out
}

/// Every entry under `d`, relative, sorted (hidden ones included).
fn tree(d: &Path) -> Vec<String> {
    fn walk(root: &Path, d: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(d).unwrap() {
            let e = e.unwrap();
            let p = e.path();
            out.push(p.strip_prefix(root).unwrap().to_string_lossy().into_owned());
            if e.file_type().unwrap().is_dir() {
                walk(root, &p, out);
            }
        }
    }
    let mut v = Vec::new();
    if d.exists() {
        walk(d, d, &mut v);
    }
    v.sort();
    v
}

/// The folder holds exactly one complete run: its manifest lists every file
/// there with its size, and nothing of ours is left beside them.
fn assert_complete_run(d: &Path) {
    let m = RunManifest::read(d).expect("ballpass-run.json");
    for f in &m.files {
        let len = std::fs::metadata(d.join(&f.path)).unwrap().len();
        assert_eq!(len, f.bytes, "{}", f.path);
    }
    for name in tree(d) {
        let base = name.rsplit('/').next().unwrap();
        assert!(
            !base.starts_with('.') && !base.ends_with(".tmp"),
            "leftover {name}"
        );
    }
}

fn analyze_args<'a>(rec: &'a str, out: &'a str) -> Vec<&'a str> {
    vec![
        "analyze",
        rec,
        "--velocity",
        "18",
        "--out",
        out,
        "--no-report",
    ]
}

/// Item 4: a constant friction channel (3.0 N in every sample) is left out
/// of the findings with a warning; it no longer "shows f_c".
#[test]
fn item4_a_dead_friction_channel_is_left_out_of_the_findings() {
    let d = scratch("item4");
    let rec = d.join("dead.csv");
    std::fs::write(&rec, fixture_with(1, "3.0")).unwrap();
    let out = d.join("out");
    let (ok, stdout, stderr) = run(&analyze_args(rec.to_str().unwrap(), out.to_str().unwrap()));
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("friction_N is constant (3 N in all 1600 samples)"),
        "{stderr}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("analysis.json")).unwrap()).unwrap();
    let showing = json["verdict"]["signals_showing_f_c"].as_array().unwrap();
    assert!(!showing.iter().any(|s| s == "friction"), "{showing:?}");
    assert!(json["verdict"]["friction_harmonics_flagged"]
        .as_array()
        .unwrap()
        .is_empty());
    assert!(json["warnings"][0]
        .as_str()
        .unwrap()
        .contains("dead or disconnected"));
    assert!(!stdout.contains("friction stands above"), "{stdout}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 4: every channel constant is an error, and nothing is written.
#[test]
fn item4_all_channels_constant_is_an_error() {
    let d = scratch("item4all");
    let mut text = fixture_with(1, "3.0");
    for col in [2, 3] {
        let tmp = d.join("t.csv");
        std::fs::write(&tmp, &text).unwrap();
        text = std::fs::read_to_string(&tmp)
            .unwrap()
            .lines()
            .enumerate()
            .map(|(i, l)| {
                if i == 0 {
                    return l.to_string() + "\n";
                }
                let mut c: Vec<&str> = l.split(',').collect();
                c[col] = "1.5";
                c.join(",") + "\n"
            })
            .collect();
    }
    let rec = d.join("all.csv");
    std::fs::write(&rec, text).unwrap();
    let out = d.join("out");
    let (ok, _, stderr) = run(&analyze_args(rec.to_str().unwrap(), out.to_str().unwrap()));
    assert!(!ok);
    assert!(
        stderr.contains("every channel is constant") && stderr.lines().count() == 1,
        "{stderr}"
    );
    assert!(!out.exists(), "{:?}", tree(&out));
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 5: `passage` and `sweep` check a stated velocity against the
/// encoder as `analyze` does (analyze: tests/analyze.rs).
#[test]
fn item5_passage_and_sweep_refuse_a_velocity_the_encoder_contradicts() {
    let d = scratch("item5");
    let rec = fixture();
    let out = d.join("p");
    let (ok, _, stderr) = run(&[
        "passage",
        rec.to_str().unwrap(),
        "--velocity",
        "200",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        stderr.contains("says the stage moves at 18.0000 mm/s")
            && stderr.contains("stated velocity is 200 mm/s"),
        "{stderr}"
    );
    // A manifest that states the wrong velocity: the record fails with
    // both numbers; the batch says so.
    std::fs::copy(&rec, d.join("r.csv")).unwrap();
    std::fs::write(
        d.join("m.csv"),
        "path,bearing,velocity_mm_s,repeat\nr.csv,sr25w,9,1\n",
    )
    .unwrap();
    let r = common::run_in(
        &d,
        &["sweep", "m.csv", "--out", "s", "--no-report", "--jobs", "1"],
    );
    assert_eq!(r.code, 1, "{}", r.stdout);
    assert!(
        r.stdout.contains("says the stage moves at 18.0000 mm/s"),
        "{}",
        r.stdout
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 6: a non-UTF-8 argument neither panics nor loses its bytes: the
/// report's command line shows it escaped.
#[cfg(unix)]
#[test]
fn item6_a_non_utf8_argument_is_recorded_escaped() {
    use std::os::unix::ffi::OsStrExt;
    let d = scratch("item6");
    let name = std::ffi::OsStr::from_bytes(b"caf\xe9.csv");
    std::fs::copy(fixture(), d.join(name)).unwrap();
    let out = d.join(std::ffi::OsStr::from_bytes(b"out\xff"));
    let r = output(
        bin()
            .arg("analyze")
            .arg(d.join(name))
            .args(["--velocity", "18", "--out"])
            .arg(&out),
    );
    assert!(r.ok(), "{}", r.stderr);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        html.contains(r"caf\xe9.csv"),
        "command line not in the report"
    );
    assert!(html.contains(r"out\xff"), "command line not in the report");
    // model and passage record the command line too.
    let r = output(bin().args(["model", "pulses", "--out"]).arg(&out));
    assert!(r.ok(), "{}", r.stderr);
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 7: the folder-mode pattern that took minutes (backtracking) ends
/// at once with a clear "no match".
#[test]
fn item7_a_pathological_pattern_finishes() {
    let d = scratch("item7");
    std::fs::write(d.join("a".repeat(200)), "").unwrap();
    let r = common::run_in(
        &d,
        &[
            "sweep",
            ".",
            "--pattern",
            "*a*a*a*a*a*a*a*a*b.csv",
            "--velocity",
            "9",
            "--out",
            "o",
        ],
    );
    assert_eq!(r.code, 1);
    assert!(r.stderr.contains("matches"), "{}", r.stderr);
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 8: while another process holds the folder's lock, a run is refused
/// with the holder named; a lock file left by a dead process is no
/// obstacle.
#[test]
fn item8_one_run_per_output_folder() {
    let d = scratch("item8lock");
    let out = d.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let lock = std::fs::File::options()
        .read(true)
        .write(true)
        .create(true)
        .truncate(true)
        .open(out.join(LOCK_FILE))
        .unwrap();
    lock.try_lock().unwrap();
    std::fs::write(out.join(LOCK_FILE), "4242").unwrap();
    let rec = fixture();
    let args = analyze_args(rec.to_str().unwrap(), out.to_str().unwrap());
    let (ok, _, stderr) = run(&args);
    assert!(!ok);
    assert!(
        stderr.contains("in use by another ballpass run (pid 4242)"),
        "{stderr}"
    );
    drop(lock);
    // The lock file stays (as after SIGKILL), unlocked: the next run goes.
    let (ok, _, stderr) = run(&args);
    assert!(ok, "{stderr}");
    assert_complete_run(&out);
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 8: two runs started together into one folder never leave a mixed
/// tree: one writes, the other is refused (or runs after it), and the
/// folder holds exactly one complete run.
#[test]
fn item8_two_runs_at_once_leave_one_complete_run() {
    let d = scratch("item8race");
    let out = d.join("out");
    let rec = fixture();
    for _ in 0..3 {
        let spawn = |nperseg: &str| {
            bin()
                .args([
                    "analyze",
                    rec.to_str().unwrap(),
                    "--velocity",
                    "18",
                    "--nperseg",
                    nperseg,
                    "--out",
                ])
                .arg(&out)
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        };
        let (a, b) = (spawn("256"), spawn("512"));
        for child in [a, b] {
            let o = child.wait_with_output().unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(
                o.status.success() || err.contains("in use by another ballpass run"),
                "{err}"
            );
        }
        assert_complete_run(&out);
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("analysis.json")).unwrap())
                .unwrap();
        // The report and the tables are of one run: the report's settings
        // table names the same segment length as analysis.json.
        let n = json["settings"]["nperseg"].as_u64().unwrap();
        let html = std::fs::read_to_string(out.join("report.html")).unwrap();
        let cell = |k: u64| format!("<code>nperseg</code></th><td>{k}</td>");
        let other = if n == 256 { 512 } else { 256 };
        assert!(html.contains(&cell(n)), "report of another run");
        assert!(!html.contains(&cell(other)), "mixed run");
        assert!(html.contains(&format!("--nperseg {n}")), "command line");
    }
    let _ = std::fs::remove_dir_all(&d);
}

fn wait_for(mut cond: impl FnMut() -> bool, what: &str) {
    let t0 = Instant::now();
    while !cond() {
        assert!(t0.elapsed() < Duration::from_secs(120), "{what}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn staged_files(d: &Path) -> usize {
    tree(d)
        .iter()
        .filter(|n| n.starts_with(".ballpass-staging.") && n.ends_with(".csv"))
        .count()
}

fn signal(pid: u32, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &pid.to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill {sig} {pid}");
}

/// Item 8 and issue 15: SIGTERM or SIGINT during `simulate-campaign`
/// leaves no temporary file, no staging folder and no lock; the folder's
/// earlier contents are untouched.
#[cfg(unix)]
#[test]
fn item8_an_interrupted_run_leaves_no_temporary_files() {
    for sig in ["-TERM", "-INT"] {
        let d = scratch_path(&format!("item8int{sig}"));
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("notes.txt"), "mine").unwrap();
        let child = bin()
            .args(["simulate-campaign", "--jobs", "2", "--out"])
            .arg(&d)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        wait_for(|| staged_files(&d) >= 4, "the campaign to start writing");
        signal(child.id(), sig);
        let o = child.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(130), "{sig}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("interrupted: nothing written"), "{err}");
        assert_eq!(tree(&d), ["notes.txt"], "{sig}");
        let _ = std::fs::remove_dir_all(&d);
    }
}

/// Item 8: a run killed outright (SIGKILL: no handler runs) leaves its
/// staging folder and lock; the next run into the folder removes them and
/// completes.
#[cfg(unix)]
#[test]
fn item8_leftovers_of_a_killed_run_are_removed_by_the_next() {
    let d = scratch_path("item8kill");
    let child = bin()
        .args(["simulate-campaign", "--jobs", "2", "--out"])
        .arg(&d)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(|| staged_files(&d) >= 4, "the campaign to start writing");
    signal(child.id(), "-KILL");
    let _ = child.wait_with_output();
    assert!(
        tree(&d).iter().any(|n| n.starts_with(".ballpass-staging.")),
        "{:?}",
        tree(&d)
    );
    assert!(!d.join("manifest.csv").exists());
    let r = output(
        bin()
            .args([
                "simulate-campaign",
                "--duration",
                "0.5",
                "--fs",
                "200",
                "--oversample",
                "4",
                "--out",
            ])
            .arg(&d),
    );
    assert!(r.ok(), "{}", r.stderr);
    assert_complete_run(&d);
    assert!(d.join("manifest.csv").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 8: `simulate -o` with a long legal name writes both files (the
/// temporary name used to exceed NAME_MAX for the truth file).
#[test]
fn item8_a_long_output_name_writes_recording_and_truth() {
    let d = scratch("item8long");
    // 240 bytes + ".truth.json" = 251 <= 255.
    let name = format!("{}.csv", "r".repeat(236));
    let p = d.join(&name);
    let (ok, _, stderr) = run(&[
        "simulate",
        "-v",
        "9",
        "--duration",
        "1",
        "-o",
        p.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    assert!(p.exists() && d.join(name.replace(".csv", ".truth.json")).exists());
    assert_eq!(tree(&d).len(), 2, "{:?}", tree(&d));
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 11: a full disk behind standard output is named as such.
#[cfg(target_os = "linux")]
#[test]
fn item11_a_full_standard_output_is_named() {
    let d = scratch("item11full");
    let full = std::fs::File::options()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = bin()
        .args(["predict", "--velocity", "1:20:1"])
        .stdout(full)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("writing to standard output") && err.contains("No space left"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 11: a huge bad cell with a carriage return and a terminal escape
/// gives one bounded, escaped error line.
#[test]
fn item11_error_lines_are_bounded_and_escaped() {
    let d = scratch("item11cell");
    let mut text = std::fs::read_to_string(fixture()).unwrap();
    let bad = format!("\x1b[2J\r{}", "9x".repeat(200_000));
    text = text.replacen("0.005,", &format!("0.005{bad},"), 1);
    let rec = d.join("bad.csv");
    std::fs::write(&rec, text).unwrap();
    let r = output(bin().args(["inspect", rec.to_str().unwrap()]));
    assert_eq!(r.code, 1);
    assert_eq!(r.stderr.lines().count(), 1, "{}", r.stderr.len());
    assert!(r.stderr.len() < 3000, "{} bytes", r.stderr.len());
    assert!(!r.stderr.contains('\x1b') && !r.stderr.contains('\r'));
    assert!(r.stderr.contains("bad.csv"), "{}", &r.stderr[..200]);
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 14: an analysis that would not fit in memory is refused before
/// any work with the estimate and a hint, and leaves no output.
#[test]
fn item14_an_analysis_too_big_for_memory_is_refused_with_a_message() {
    let d = scratch("item14");
    let out = d.join("out");
    let rec = fixture();
    let r = output(
        bin()
            .env("BALLPASS_MEMORY_GB", "0.0001")
            .args(analyze_args(rec.to_str().unwrap(), out.to_str().unwrap())),
    );
    assert_eq!(r.code, 1);
    assert!(
        r.stderr.contains("needs about")
            && r.stderr.contains("--window")
            && r.stderr.contains("nothing written"),
        "{}",
        r.stderr
    );
    assert!(!out.exists(), "{:?}", tree(&out));
    let _ = std::fs::remove_dir_all(&d);
}

/// Item 8: the previous run's outputs stay whole when a later run into the
/// same folder fails, and the manifest still describes them.
#[test]
fn item8_a_failed_run_keeps_the_previous_outputs() {
    let d = scratch("item8keep");
    let out = d.join("out");
    let rec = fixture();
    let (ok, _, stderr) = run(&analyze_args(rec.to_str().unwrap(), out.to_str().unwrap()));
    assert!(ok, "{stderr}");
    let before = std::fs::read(out.join("analysis.json")).unwrap();
    let (ok, _, _) = run(&[
        "analyze",
        rec.to_str().unwrap(),
        "--velocity",
        "200",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert_eq!(std::fs::read(out.join("analysis.json")).unwrap(), before);
    assert_complete_run(&out);
    assert!(out.join(RUN_FILE).exists());
    let _ = std::fs::remove_dir_all(&d);
}
