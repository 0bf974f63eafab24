//! Time and peak memory of `ballpass analyze` on hour-long records, beside
//! the SciPy script doing the same steps (`tools/bench_scipy_long.py`).
//!
//! ```text
//! cargo bench -p ballpass-cli --bench long_record -- [HOURS ...] [--no-scipy] [--report] [--stream-on|--stream-off] [--tdms|--mf4|--mat73|--mat73-deflate]
//! ```
//!
//! With `--tdms` the record is written as an NI TDMS file instead
//! (`ballpass::recording::io::tdms::write_tdms`: float64 channels with
//! waveform timing, segments of 1000 samples, as DAQmx logging writes
//! them) and `analyze` is measured streamed (`--stream on`) and read whole
//! (`--stream off`), side by side. With `--mat73` it is written as a MATLAB
//! v7.3 file instead (contiguous doubles; `--mat73-deflate`: chunks of 65536
//! values, deflate level 4 with shuffle, as MATLAB compresses by default),
//! by `tools/make_long_v73.py` with h5py from the channels' raw doubles
//! (`$PYTHON`, else `python3`, with tools/requirements-formats.txt). With
//! `--stream-on` these two measure the streamed run alone (a 24-hour
//! record read whole needs several times its 2.8 GB).
//! With `--mf4`, the same with an ASAM MDF 4 file written by asammdf
//! (`tools/write_long_mf4.py`: float64 channels on a float64 time master,
//! 4 MB data blocks), with the Python of `BALLPASS_FORMATS_PYTHON`
//! (default `python3`; tools/requirements-formats.txt).
//!
//! For each duration (default 2 h) it simulates a record at 1 kHz
//! (`ballpass simulate`, good bearing, 9 mm/s) into a temporary folder,
//! runs `ballpass analyze --no-report` (with `--report`: the report too;
//! `--stream-on`/`--stream-off` force the streamed or in-memory analysis,
//! else a file of 1 GiB or more, 4.5 hours and longer, is streamed)
//! and the SciPy script under `/usr/bin/time -v`, and prints the wall time
//! and peak resident memory of each. Every generated file is removed at the
//! end (a 24-hour CSV is 5.3 GB). Needs `/usr/bin/time` (GNU time) and,
//! for the SciPy column, `python3` with tools/requirements.txt. A bench,
//! not a test: CI builds it and never runs it.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Wall time, CPU time and peak resident memory of one process.
struct Run {
    seconds: f64,
    cpu_seconds: f64,
    peak_mb: f64,
}

/// Runs `cmd` under GNU time and reads its wall time and peak RSS.
fn measured(cmd: Command) -> Result<Run, String> {
    let program = cmd.get_program().to_owned();
    let args: Vec<_> = cmd.get_args().map(|a| a.to_owned()).collect();
    let out = Command::new("/usr/bin/time")
        .arg("-v")
        .arg(&program)
        .args(&args)
        .output()
        .map_err(|e| format!("cannot run /usr/bin/time: {e}"))?;
    let err = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        return Err(format!("{program:?} failed: {err}"));
    }
    let field = |name: &str| -> Option<&str> {
        err.lines()
            .find_map(|l| l.trim().strip_prefix(name))
            .map(str::trim)
    };
    let peak_kb: f64 = field("Maximum resident set size (kbytes):")
        .and_then(|v| v.parse().ok())
        .ok_or("no peak RSS in /usr/bin/time's output")?;
    let wall = field("Elapsed (wall clock) time (h:mm:ss or m:ss):")
        .ok_or("no wall time in /usr/bin/time's output")?;
    let seconds = wall
        .split(':')
        .try_fold(0.0, |acc, part| part.parse::<f64>().map(|v| acc * 60.0 + v))
        .map_err(|e| format!("wall time '{wall}': {e}"))?;
    let cpu = |name: &str| -> Result<f64, String> {
        field(name)
            .and_then(|v| v.parse::<f64>().ok())
            .ok_or_else(|| format!("no '{name}' in /usr/bin/time's output"))
    };
    Ok(Run {
        seconds,
        cpu_seconds: cpu("User time (seconds):")? + cpu("System time (seconds):")?,
        peak_mb: peak_kb / 1024.0,
    })
}

/// Longest record simulated in one piece (the simulator's 50 million
/// samples at 1 kHz are 13.9 h).
const MAX_SIMULATED_HOURS: f64 = 12.0;

/// `ballpass simulate` of `hours` at 1 kHz, 9 mm/s into `out`.
fn simulate(bin: &Path, hours: f64, out: &Path) -> Result<(), String> {
    let o = Command::new(bin)
        .args(["simulate", "--velocity", "9", "--duration"])
        .arg(format!("{}", hours * 3600.0))
        .arg("--out")
        .arg(out)
        .output()
        .map_err(|e| format!("simulate: {e}"))?;
    if o.status.success() {
        Ok(())
    } else {
        Err(format!("simulate: {}", String::from_utf8_lossy(&o.stderr)))
    }
}

/// Writes `times` copies of the CSV record `piece` end to end into `out`:
/// copy `k` has its time shifted by `k` times the piece's duration plus
/// one sample, and its position by `k` times the piece's travel plus one
/// sample's, so that time and position run on without a jump.
fn tile(piece: &Path, out: &Path, times: usize) -> Result<(), String> {
    use std::io::{BufWriter, Write};
    let text = std::fs::read_to_string(piece).map_err(|e| format!("{piece:?}: {e}"))?;
    let mut lines = text.lines();
    let header = lines.next().ok_or("empty piece")?;
    let rows: Vec<[f64; 4]> = lines
        .map(|l| {
            let mut v = [0.0; 4];
            for (slot, cell) in v.iter_mut().zip(l.split(',')) {
                *slot = cell.parse().unwrap_or(f64::NAN);
            }
            v
        })
        .collect();
    let (first, last) = (rows[0], rows[rows.len() - 1]);
    let dt = rows[1][0] - rows[0][0];
    let step_t = last[0] - first[0] + dt;
    let step_p = last[2] - first[2] + (rows[1][2] - rows[0][2]);
    let f = std::fs::File::create(out).map_err(|e| format!("{out:?}: {e}"))?;
    let mut w = BufWriter::with_capacity(1 << 20, f);
    let io = |e: std::io::Error| format!("{out:?}: {e}");
    writeln!(w, "{header}").map_err(io)?;
    for k in 0..times {
        let (ot, op) = (k as f64 * step_t, k as f64 * step_p);
        for r in &rows {
            writeln!(w, "{},{},{},{}", r[0] + ot, r[1], r[2] + op, r[3]).map_err(io)?;
        }
    }
    w.flush().map_err(io)?;
    Ok(())
}

fn main() {
    let mut hours: Vec<f64> = Vec::new();
    let mut scipy = true;
    let mut report = false;
    let mut stream = None;
    let mut binary = None;
    for a in std::env::args().skip(1) {
        match a.as_str() {
            "--no-scipy" => scipy = false,
            "--report" => report = true,
            "--stream-on" => stream = Some("on"),
            "--stream-off" => stream = Some("off"),
            "--tdms" => binary = Some(Binary::Tdms),
            "--mat73" => binary = Some(Binary::Mat73 { deflate: false }),
            "--mat73-deflate" => binary = Some(Binary::Mat73 { deflate: true }),
            "--mf4" => binary = Some(Binary::Mf4),
            "--bench" => {}
            _ => match a.parse::<f64>() {
                Ok(h) if h > 0.0 => hours.push(h),
                _ => {
                    eprintln!(
                        "long_record: unknown argument '{a}' (hours, --no-scipy, --report, \
                         --stream-on, --stream-off, --tdms, --mf4, --mat73, --mat73-deflate)"
                    );
                    std::process::exit(2);
                }
            },
        }
    }
    if hours.is_empty() {
        hours.push(2.0);
    }
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_ballpass"));
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools");
    let dir = std::env::temp_dir().join(format!("ballpass-long-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary folder");
    let result = match binary {
        Some(kind) => run_binary(&bin, &tools, &dir, &hours, (report, stream), kind),
        None => run_all(&bin, &tools, &dir, &hours, (scipy, report, stream)),
    };
    let _ = std::fs::remove_dir_all(&dir);
    if let Err(e) = result {
        eprintln!("long_record: {e}");
        std::process::exit(1);
    }
}

/// The simulated CSV record of `hours` at `rec` (tiled past what the
/// simulator holds).
fn record(bin: &Path, dir: &Path, h: f64, rec: &Path) -> Result<(), String> {
    if h <= MAX_SIMULATED_HOURS {
        simulate(bin, h, rec)
    } else {
        // The simulator holds at most 50 million samples: a longer
        // record is a 2-hour one repeated end to end.
        let piece = dir.join("piece_2h.csv");
        simulate(bin, 2.0, &piece)?;
        tile(&piece, rec, (h / 2.0).ceil() as usize)?;
        let _ = std::fs::remove_file(&piece);
        Ok(())
    }
}

/// A binary format the record is written in (`--tdms`, `--mat73`).
#[derive(Debug, Clone, Copy)]
enum Binary {
    /// NI TDMS (`write_tdms`).
    Tdms,
    /// ASAM MDF 4 (asammdf, `tools/write_long_mf4.py`).
    Mf4,
    /// MATLAB v7.3 (h5py, `tools/make_long_v73.py`).
    Mat73 { deflate: bool },
}

/// Writes the record of `csv` as an MF4 file at `out` through
/// `tools/write_long_mf4.py` (asammdf).
fn write_mf4(tools: &Path, csv: &Path, out: &Path) -> Result<(), String> {
    let python = std::env::var_os("BALLPASS_FORMATS_PYTHON").unwrap_or_else(|| "python3".into());
    let o = Command::new(python)
        .arg(tools.join("write_long_mf4.py"))
        .arg(csv)
        .arg(out)
        .output()
        .map_err(|e| format!("write_long_mf4.py: {e}"))?;
    if o.status.success() {
        Ok(())
    } else {
        Err(format!(
            "write_long_mf4.py: {}",
            String::from_utf8_lossy(&o.stderr)
        ))
    }
}

/// Writes `rec` as a MATLAB v7.3 file at `out` through
/// `tools/make_long_v73.py` (its raw doubles first, removed after).
fn write_mat73(
    rec: &ballpass::recording::Recording,
    tools: &Path,
    out: &Path,
    deflate: bool,
) -> Result<(), String> {
    use ballpass::recording::Channel;
    use std::io::{BufWriter, Write};
    let raw = out.with_extension("raw");
    std::fs::create_dir_all(&raw).map_err(|e| format!("{raw:?}: {e}"))?;
    let t0 = rec.meta.start_time_s;
    let fs = rec.fs_hz();
    let time: Vec<f64> = (0..rec.len()).map(|i| t0 + i as f64 / fs).collect();
    let columns = [
        ("time_s", Some(&time[..])),
        ("friction_N", rec.channel(Channel::Friction)),
        ("position_mm", rec.channel(Channel::Position)),
        ("optical_V", rec.channel(Channel::Optical)),
    ];
    for (name, values) in columns {
        let values = values.ok_or_else(|| format!("no {name} in the record"))?;
        let p = raw.join(format!("{name}.f64"));
        let f = std::fs::File::create(&p).map_err(|e| format!("{p:?}: {e}"))?;
        let mut w = BufWriter::with_capacity(1 << 20, f);
        for v in values {
            w.write_all(&v.to_le_bytes())
                .map_err(|e| format!("{p:?}: {e}"))?;
        }
        w.flush().map_err(|e| format!("{p:?}: {e}"))?;
    }
    let python = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());
    let mut cmd = Command::new(python);
    cmd.arg(tools.join("make_long_v73.py")).arg(&raw).arg(out);
    if deflate {
        cmd.arg("--deflate");
    }
    let o = cmd.output().map_err(|e| format!("make_long_v73.py: {e}"));
    let _ = std::fs::remove_dir_all(&raw);
    let o = o?;
    if o.status.success() {
        Ok(())
    } else {
        Err(format!(
            "make_long_v73.py: {}",
            String::from_utf8_lossy(&o.stderr)
        ))
    }
}

/// `analyze` of a TDMS, MF4 or MATLAB v7.3 record streamed and read whole
/// (`--tdms`, `--mf4`, `--mat73`; with `--stream-on` streamed only).
fn run_binary(
    bin: &Path,
    tools: &Path,
    dir: &Path,
    hours: &[f64],
    (report, stream): (bool, Option<&str>),
    kind: Binary,
) -> Result<(), String> {
    let (label, ext) = match kind {
        Binary::Tdms => ("TDMS record", "tdms"),
        Binary::Mf4 => ("MF4 record", "mf4"),
        Binary::Mat73 { deflate: false } => ("MATLAB v7.3 record", "mat"),
        Binary::Mat73 { deflate: true } => ("MATLAB v7.3 record (deflate)", "mat"),
    };
    println!(
        "| {label} | file | streamed: wall (CPU) | peak RSS | read whole: wall (CPU) | peak RSS |"
    );
    println!("|---|---|---|---|---|---|");
    let modes: &[&str] = if stream == Some("on") {
        &["on"]
    } else {
        &["on", "off"]
    };
    for &h in hours {
        let csv = dir.join(format!("rec_{h}h.csv"));
        record(bin, dir, h, &csv)?;
        let rec = dir.join(format!("rec_{h}h.{ext}"));
        let whole =
            ballpass::recording::io::load(&csv, &Default::default()).map_err(|e| e.to_string())?;
        match kind {
            Binary::Tdms => ballpass::recording::io::tdms::write_tdms(&whole, &rec, 1000, false)
                .map_err(|e| e.to_string())?,
            Binary::Mf4 => write_mf4(tools, &csv, &rec)?,
            Binary::Mat73 { deflate } => write_mat73(&whole, tools, &rec, deflate)?,
        }
        let _ = std::fs::remove_file(&csv);
        drop(whole);
        let size = std::fs::metadata(&rec).map_err(|e| e.to_string())?.len();
        let mut runs = Vec::new();
        for mode in modes {
            let mut cmd = Command::new(bin);
            cmd.arg("analyze")
                .arg(&rec)
                .args(["--velocity", "9", "--stream", mode, "--out"])
                .arg(dir.join("bp"));
            if !report {
                cmd.arg("--no-report");
            }
            runs.push(measured(cmd)?);
            let _ = std::fs::remove_dir_all(dir.join("bp"));
        }
        let _ = std::fs::remove_file(&rec);
        let whole = match runs.get(1) {
            Some(r) => format!(
                "{:.1} s ({:.1} s) | {:.0} MB",
                r.seconds, r.cpu_seconds, r.peak_mb
            ),
            None => "not run | -".into(),
        };
        println!(
            "| {h} h at 1 kHz | {:.2} GB | {:.1} s ({:.1} s) | {:.0} MB | {whole} |",
            size as f64 / 1e9,
            runs[0].seconds,
            runs[0].cpu_seconds,
            runs[0].peak_mb,
        );
    }
    Ok(())
}

fn run_all(
    bin: &Path,
    tools: &Path,
    dir: &Path,
    hours: &[f64],
    (scipy, report, stream): (bool, bool, Option<&str>),
) -> Result<(), String> {
    println!(
        "| record | ballpass analyze: wall (CPU) | peak RSS | SciPy script: wall (CPU) | peak RSS | speed-up (wall) |"
    );
    println!("|---|---|---|---|---|---|");
    for &h in hours {
        let rec = dir.join(format!("rec_{h}h.csv"));
        record(bin, dir, h, &rec)?;
        let mut ours = Command::new(bin);
        ours.arg("analyze")
            .arg(&rec)
            .args(["--velocity", "9", "--out"])
            .arg(dir.join("bp"));
        if !report {
            ours.arg("--no-report");
        }
        if let Some(s) = stream {
            ours.args(["--stream", s]);
        }
        let ours = measured(ours)?;
        let theirs = if scipy {
            let mut py = Command::new("python3");
            py.arg(tools.join("bench_scipy_long.py"))
                .arg(&rec)
                .args(["--velocity", "9", "--max-lag", "90.124", "--out"])
                .arg(dir.join("scipy"));
            Some(measured(py)?)
        } else {
            None
        };
        let _ = std::fs::remove_file(&rec);
        let _ = std::fs::remove_dir_all(dir.join("bp"));
        let _ = std::fs::remove_dir_all(dir.join("scipy"));
        match theirs {
            Some(t) => println!(
                "| {h} h at 1 kHz | {:.1} s ({:.1} s) | {:.0} MB | {:.1} s ({:.1} s) | {:.0} MB | {:.1}x |",
                ours.seconds,
                ours.cpu_seconds,
                ours.peak_mb,
                t.seconds,
                t.cpu_seconds,
                t.peak_mb,
                t.seconds / ours.seconds
            ),
            None => println!(
                "| {h} h at 1 kHz | {:.1} s ({:.1} s) | {:.0} MB | - | - | - |",
                ours.seconds, ours.cpu_seconds, ours.peak_mb
            ),
        }
    }
    Ok(())
}
