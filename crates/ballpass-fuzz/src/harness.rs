//! The run: seeds mutated by a seeded generator, each input given to every
//! loader of its kind, under a panic catcher, a watchdog and the counting
//! allocator; failures saved with the seed and execution number that
//! reproduce them.
//!
//! What counts as a failure:
//!
//! - **panic**: a loader panicked (its own code; third-party panics must
//!   have been contained into errors);
//! - **hang**: a call took longer than [`time_limit`] (1 s per MB, at least
//!   [`MIN_LIMIT_MS`]), twice in a row (the machine is shared, so one slow
//!   call is measured again before it counts). The watchdog ends the run
//!   with the input saved when a call takes 100 times that;
//! - **memory**: the peak of live bytes during a call, or one request,
//!   beyond [`memory_bound`] (what the input can really hold: its size
//!   times deflate's 1032:1 expansion times the 8 bytes of an `f64` per
//!   byte, for the formats that compress; 64 times its size otherwise);
//! - **message**: an error that spans lines, holds control characters, is
//!   longer than [`MAX_MESSAGE`] characters, or shows a third party's words
//!   (`panicked`, `unwrap`, `binrw`);
//! - **disagreement**: the CSV fast path read a file differently from the
//!   general reader, or the streamed reader (`analyze --stream`, the file
//!   read in 1 kB pieces; a TDMS or MF4 file in blocks of 16 samples)
//!   differently from the whole-file reader.
//!
//! An abort (stack overflow, refused allocation above
//! [`crate::alloc::HARD_CAP`]) ends the process: the run's exit status
//! says so, and `--seed`/`--execs` reproduce it.

use std::collections::BTreeMap;
use std::fmt;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use ballpass::campaign::manifest::parse_manifest;
use ballpass::recording::inspect::{inspect_bytes, InspectSettings};
use ballpass::recording::io::csv::blocks::check_stream_agrees;
use ballpass::recording::io::csv::check_fast_path_agrees;
use ballpass::recording::io::mat::stream::check_stream_agrees as check_mat_stream_agrees;
use ballpass::recording::io::mf4::stream::check_stream_agrees as check_mf4_stream_agrees;
use ballpass::recording::io::tdms::stream::check_stream_agrees as check_tdms_stream_agrees;
use ballpass::recording::io::{contents_of_bytes, load_all_bytes};
use ballpass::recording::{GapPolicy, LoadOptions, Profile, TimeUnit};

use crate::alloc;
use crate::corpus::{Kind, Seed};
use crate::mutate::mutate;
use crate::rng::Rng;

/// Shortest time limit of one call, ms (fixed costs dominate small inputs).
pub const MIN_LIMIT_MS: u64 = 10;
/// Longest error message accepted, characters.
pub const MAX_MESSAGE: usize = 2000;

/// Time one call on `len` bytes may take: 1 s per MB, at least [`MIN_LIMIT_MS`].
pub fn time_limit(len: usize) -> Duration {
    Duration::from_millis(MIN_LIMIT_MS.max(len as u64 / 1000))
}

/// Memory one call on `len` bytes of `kind` may use (see the module doc).
pub fn memory_bound(kind: Kind, len: usize) -> usize {
    match kind {
        Kind::Mat | Kind::Mf4 => (64 << 20) + len.saturating_mul(1032 * 8),
        _ => (16 << 20) + len.saturating_mul(64),
    }
}

/// How to run.
#[derive(Debug, Clone)]
pub struct Config {
    /// Seed of the generator.
    pub seed: u64,
    /// Executions (inputs) to run.
    pub execs: u64,
    /// Stop after this long even if `execs` are not done.
    pub max_time: Option<Duration>,
    /// Folder for failing inputs (created on the first one).
    pub save_dir: PathBuf,
    /// Print progress to stderr every this many executions (0: never).
    pub progress_every: u64,
    /// Multiplier of [`time_limit`]: 1 for the long run; more in `cargo
    /// test`, whose other test binaries share the machine's cores.
    pub time_slack: f64,
}

/// One failure.
#[derive(Debug, Clone)]
pub struct Failure {
    /// panic, hang, memory, message or disagreement.
    pub what: &'static str,
    /// Loader call.
    pub call: &'static str,
    /// Input kind.
    pub kind: Kind,
    /// Execution number (with the seed, reproduces it).
    pub exec: u64,
    /// Detail.
    pub detail: String,
    /// Where the input was saved.
    pub saved: Option<PathBuf>,
}

/// What a run did.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// Seed.
    pub seed: u64,
    /// Inputs run.
    pub execs: u64,
    /// Loader calls by (kind, call).
    pub calls: BTreeMap<(String, &'static str), u64>,
    /// Calls that returned an error (a clean refusal).
    pub errors: u64,
    /// Calls that succeeded.
    pub oks: u64,
    /// Failures (at most 100 kept; `failure_count` has them all).
    pub failures: Vec<Failure>,
    /// Number of failures.
    pub failure_count: u64,
    /// Longest call, and its input's size.
    pub slowest: (Duration, usize),
    /// Largest call time relative to its limit, and that call (kind, call,
    /// input size, time).
    pub worst_time_ratio: f64,
    /// The call of `worst_time_ratio`.
    pub worst_time_call: String,
    /// Largest peak of live bytes of one call, and its input's size.
    pub peak_bytes: (usize, usize),
    /// Largest peak relative to its bound.
    pub worst_memory_ratio: f64,
    /// Wall time.
    pub elapsed: Duration,
}

impl Report {
    /// Loader calls in all.
    pub fn total_calls(&self) -> u64 {
        self.calls.values().sum()
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "seed {}: {} inputs, {} loader calls in {:.1} s ({:.0} calls/s); {} ok, {} refused",
            self.seed,
            self.execs,
            self.total_calls(),
            self.elapsed.as_secs_f64(),
            self.total_calls() as f64 / self.elapsed.as_secs_f64().max(1e-9),
            self.oks,
            self.errors
        )?;
        for ((kind, call), n) in &self.calls {
            writeln!(f, "  {kind:<8} {call:<12} {n:>10}")?;
        }
        writeln!(
            f,
            "slowest call {:.2} ms ({} bytes), worst time/limit {:.3} ({}); \
             largest peak {:.1} MB ({} bytes in), worst memory/bound {:.4}",
            self.slowest.0.as_secs_f64() * 1e3,
            self.slowest.1,
            self.worst_time_ratio,
            self.worst_time_call,
            self.peak_bytes.0 as f64 / 1e6,
            self.peak_bytes.1,
            self.worst_memory_ratio
        )?;
        writeln!(f, "failures: {}", self.failure_count)?;
        for x in &self.failures {
            writeln!(
                f,
                "  {} in {} {} (exec {}): {}{}",
                x.what,
                x.kind.name(),
                x.call,
                x.exec,
                x.detail,
                x.saved
                    .as_ref()
                    .map(|p| format!(" [{}]", p.display()))
                    .unwrap_or_default()
            )?;
        }
        Ok(())
    }
}

/// The watchdog's view of the call in progress.
struct Watch {
    /// Start of the call, ns since the run began (0: idle).
    started_ns: AtomicU64,
    /// The call's limit, ns.
    limit_ns: AtomicU64,
    /// The input of the call in progress, and its description.
    input: Mutex<(Vec<u8>, String)>,
    done: AtomicBool,
}

/// The options a call loads with: defaults, or those that take the
/// loaders down their other paths (names by path, dialects, gaps).
fn options(rng: &mut Rng, kind: Kind) -> LoadOptions {
    let mut o = LoadOptions::default();
    match (kind, rng.below(4)) {
        (_, 0) => {}
        (Kind::Csv, 1) => {
            o.decimal_comma = Some(true);
            o.delimiter = Some(b';');
            o.time_unit = Some(TimeUnit::Ms);
        }
        (Kind::Csv, 2) => {
            o.friction.name = Some("Kraft".into());
            o.time = Some("Zeit".into());
            o.friction.scale = 1e-3;
        }
        (Kind::Mat, 1) => {
            o.friction.name = Some("bearing.gs".into());
            o.fs_from = Some("bearing.sr".into());
            o.optical.name = Some("signals{1}".into());
        }
        (Kind::Mat, 2) => {
            o.friction.name = Some("force".into());
            o.position.name = Some("Counts".into());
            o.position.scale = 1e-4;
        }
        (Kind::Tdms, 1) => {
            o.friction.name = Some("Force".into());
            o.optical.name = Some("Bench 1/Voltage".into());
        }
        (Kind::Tdms, 2) => {
            // One run per group (`FILE#GROUP`).
            o.record = Some("Run 2".into());
        }
        _ => {
            o.gaps = GapPolicy {
                fill_max_s: Some(0.01),
                split: true,
            };
            o.fs_hz = Some(1000.0);
        }
    }
    o
}

/// A message's problem, if any.
fn bad_message(m: &str) -> Option<String> {
    if m.chars().count() > MAX_MESSAGE {
        return Some(format!("{} characters", m.chars().count()));
    }
    if m.chars().any(char::is_control) {
        return Some("control characters".into());
    }
    for w in ["panicked", "unwrap()", "binrw", "called `"] {
        if m.contains(w) {
            return Some(format!("third-party words '{w}'"));
        }
    }
    None
}

/// Runs the harness.
pub fn run(seeds: &[Seed], config: &Config) -> Report {
    let mut rng = Rng::new(config.seed);
    let mut report = Report {
        seed: config.seed,
        ..Report::default()
    };
    let begin = Instant::now();
    let watch = Arc::new(Watch {
        started_ns: AtomicU64::new(0),
        limit_ns: AtomicU64::new(0),
        input: Mutex::new((Vec::new(), String::new())),
        done: AtomicBool::new(false),
    });
    let dog = {
        let watch = Arc::clone(&watch);
        let dir = config.save_dir.clone();
        let seed = config.seed;
        std::thread::spawn(move || watchdog(&watch, begin, &dir, seed))
    };
    let settings = InspectSettings::default();
    // The streamed CSV reader reads from disk: each CSV input is written
    // here first (removed at the end of the run).
    let stream_dir = std::env::temp_dir().join(format!(
        "ballpass-fuzz-stream-{}-{}",
        std::process::id(),
        config.seed
    ));
    let stream_file = stream_dir.join("fuzz.csv");
    let stream_tdms = stream_dir.join("fuzz.tdms");
    let stream_mat = stream_dir.join("fuzz.mat");
    let stream_mf4 = stream_dir.join("fuzz.mf4");
    let have_stream_dir = std::fs::create_dir_all(&stream_dir).is_ok();
    // Seeds by kind, each kind drawn with its weight (so that the many MAT
    // stress files do not crowd out the other formats).
    let weights = [
        (Kind::Csv, 25),
        (Kind::Mat, 30),
        (Kind::Tdms, 15),
        (Kind::Mf4, 15),
        (Kind::Profile, 8),
        (Kind::Manifest, 7),
    ];
    let by_kind: Vec<(Kind, usize, Vec<&Seed>)> = weights
        .iter()
        .map(|&(k, w)| {
            (
                k,
                w,
                seeds.iter().filter(|s| s.kind == k).collect::<Vec<_>>(),
            )
        })
        .filter(|(_, _, v)| !v.is_empty())
        .collect();
    let total_weight: usize = by_kind.iter().map(|(_, w, _)| w).sum();
    for exec in 0..config.execs {
        if config.max_time.is_some_and(|t| begin.elapsed() >= t) {
            break;
        }
        if config.progress_every > 0 && exec > 0 && exec % config.progress_every == 0 {
            eprintln!(
                "exec {exec}: {} calls, {} failures, {:.0} s",
                report.total_calls(),
                report.failure_count,
                begin.elapsed().as_secs_f64()
            );
        }
        let mut pick = rng.below(total_weight);
        let group = by_kind
            .iter()
            .find(|(_, w, _)| {
                let hit = pick < *w;
                pick = pick.saturating_sub(*w);
                hit
            })
            .unwrap_or(&by_kind[0]);
        let seed = group.2[rng.below(group.2.len())];
        let other = &group.2[rng.below(group.2.len())].bytes;
        let input = if rng.one_in(10) {
            seed.bytes.clone()
        } else {
            mutate(&mut rng, &seed.bytes, other, seed.kind.is_text())
        };
        let kind = seed.kind;
        let opts = options(&mut rng, kind);
        let path = PathBuf::from(kind.file_name());
        if let Ok(mut slot) = watch.input.lock() {
            slot.0.clear();
            slot.0.extend_from_slice(&input);
            slot.1 = format!("{} exec {exec}", kind.name());
        }
        report.execs += 1;
        let mut call = |name: &'static str, f: &dyn Fn() -> Result<(), String>| {
            let limit = time_limit(input.len()).mul_f64(config.time_slack.max(1.0));
            let bound = memory_bound(kind, input.len());
            let attempt = || {
                alloc::reset();
                let base = alloc::current();
                watch.limit_ns.store(limit.as_nanos() as u64, Relaxed);
                watch
                    .started_ns
                    .store(begin.elapsed().as_nanos() as u64 + 1, Relaxed);
                let t0 = Instant::now();
                let r = catch_unwind(AssertUnwindSafe(f));
                let dt = t0.elapsed();
                watch.started_ns.store(0, Relaxed);
                (r, dt, alloc::usage(base))
            };
            let (mut r, mut dt, mut mem) = attempt();
            if dt > limit {
                // Measured again: one slow call on a shared machine is not a hang.
                (r, dt, mem) = attempt();
            }
            *report
                .calls
                .entry((kind.name().to_string(), name))
                .or_insert(0) += 1;
            if dt > report.slowest.0 {
                report.slowest = (dt, input.len());
            }
            let ratio = dt.as_secs_f64() / limit.as_secs_f64();
            if ratio > report.worst_time_ratio {
                report.worst_time_ratio = ratio;
                report.worst_time_call = format!(
                    "{} {name}, {} bytes, {:.2} ms, exec {exec}",
                    kind.name(),
                    input.len(),
                    dt.as_secs_f64() * 1e3
                );
            }
            if mem.peak_bytes > report.peak_bytes.0 {
                report.peak_bytes = (mem.peak_bytes, input.len());
            }
            let used = mem.peak_bytes.max(mem.largest_bytes);
            report.worst_memory_ratio = report.worst_memory_ratio.max(used as f64 / bound as f64);
            let mut fail = |what: &'static str, detail: String| {
                report.failure_count += 1;
                if report.failures.len() < 100 {
                    let saved = save(&config.save_dir, config.seed, exec, kind, name, &input);
                    report.failures.push(Failure {
                        what,
                        call: name,
                        kind,
                        exec,
                        detail,
                        saved,
                    });
                }
            };
            match r {
                Err(_) => fail("panic", "the loader panicked".into()),
                Ok(Ok(())) => report.oks += 1,
                Ok(Err(m)) => {
                    report.errors += 1;
                    if let Some(why) = bad_message(&m) {
                        let shown: String = m.chars().take(300).collect();
                        fail("message", format!("{why}: {shown:?}"));
                    }
                }
            }
            if dt > limit {
                fail(
                    "hang",
                    format!("{:.1} ms for {} bytes", dt.as_secs_f64() * 1e3, input.len()),
                );
            }
            if used > bound {
                fail(
                    "memory",
                    format!("{used} bytes for {} bytes (bound {bound})", input.len()),
                );
            }
        };
        let err = |e: ballpass::Error| e.to_string();
        match kind {
            Kind::Csv | Kind::Mat | Kind::Tdms | Kind::Mf4 => {
                call("load", &|| {
                    load_all_bytes(&path, &input, &opts)
                        .map(|_| ())
                        .map_err(err)
                });
                call("contents", &|| {
                    contents_of_bytes(&path, &input, &opts, 500)
                        .map(|_| ())
                        .map_err(err)
                });
                call("inspect", &|| {
                    inspect_bytes(&path, &input, &opts, &settings)
                        .map(|_| ())
                        .map_err(err)
                });
                if kind == Kind::Csv {
                    call("agree", &|| match check_fast_path_agrees(&input) {
                        Ok(()) => Ok(()),
                        Err(d) => panic!("CSV readers disagree: {d}"),
                    });
                    // The streamed reader reads a file from disk: the input
                    // is written to the run's scratch file first.
                    if have_stream_dir && std::fs::write(&stream_file, &input).is_ok() {
                        call("stream", &|| match check_stream_agrees(&stream_file) {
                            Ok(()) => Ok(()),
                            Err(d) => panic!("streamed and whole-file readers disagree: {d}"),
                        });
                    }
                }
                // The streamed TDMS reader, from disk as well.
                if kind == Kind::Tdms
                    && have_stream_dir
                    && std::fs::write(&stream_tdms, &input).is_ok()
                {
                    call("stream", &|| match check_tdms_stream_agrees(&stream_tdms) {
                        Ok(()) => Ok(()),
                        Err(d) => panic!("streamed and whole-file TDMS readers disagree: {d}"),
                    });
                }
                // The streamed MATLAB v7.3 reader, from disk, on inputs that
                // still start like a v7.3 file (HDF5 at byte 0 or 512).
                let v73 = input.starts_with(b"MATLAB 7.3")
                    || input.get(512..520) == Some(b"\x89HDF\r\n\x1a\n".as_slice())
                    || input.starts_with(b"\x89HDF\r\n\x1a\n");
                if kind == Kind::Mat
                    && v73
                    && have_stream_dir
                    && std::fs::write(&stream_mat, &input).is_ok()
                {
                    call("stream", &|| match check_mat_stream_agrees(&stream_mat) {
                        Ok(()) => Ok(()),
                        Err(d) => panic!("streamed and whole-file v7.3 readers disagree: {d}"),
                    });
                }
                // The streamed MF4 reader, from disk as well.
                if kind == Kind::Mf4
                    && have_stream_dir
                    && std::fs::write(&stream_mf4, &input).is_ok()
                {
                    call("stream", &|| match check_mf4_stream_agrees(&stream_mf4) {
                        Ok(()) => Ok(()),
                        Err(d) => panic!("streamed and whole-file MF4 readers disagree: {d}"),
                    });
                }
            }
            Kind::Profile => call("parse", &|| {
                let text = String::from_utf8_lossy(&input);
                Profile::parse(&path, &text)
                    .and_then(|p| p.load_options())
                    .map(|_| ())
                    .map_err(err)
            }),
            Kind::Manifest => call("parse", &|| {
                let text = String::from_utf8_lossy(&input);
                parse_manifest(&path, &text).map(|_| ()).map_err(err)
            }),
        }
    }
    watch.done.store(true, Relaxed);
    let _ = dog.join();
    let _ = std::fs::remove_dir_all(&stream_dir);
    report.elapsed = begin.elapsed();
    report
}

/// Ends the process when a call takes 100 times its limit, with its input saved.
fn watchdog(w: &Watch, begin: Instant, dir: &Path, seed: u64) {
    while !w.done.load(Relaxed) {
        std::thread::sleep(Duration::from_millis(50));
        let start = w.started_ns.load(Relaxed);
        if start == 0 {
            continue;
        }
        let now = begin.elapsed().as_nanos() as u64;
        let limit = w.limit_ns.load(Relaxed).max(1);
        if now.saturating_sub(start) > limit.saturating_mul(100) {
            let (input, what) = w
                .input
                .lock()
                .map(|g| (g.0.clone(), g.1.clone()))
                .unwrap_or_default();
            let _ = std::fs::create_dir_all(dir);
            let p = dir.join(format!("hang-seed{seed}-{}.bin", what.replace(' ', "-")));
            let _ = std::fs::write(&p, &input);
            eprintln!(
                "HANG: {what} ({} bytes) has run {:.1} s, 100 times its limit; input saved to {}",
                input.len(),
                (now - start) as f64 / 1e9,
                p.display()
            );
            std::process::exit(3);
        }
    }
}

fn save(dir: &Path, seed: u64, exec: u64, kind: Kind, call: &str, input: &[u8]) -> Option<PathBuf> {
    std::fs::create_dir_all(dir).ok()?;
    let p = dir.join(format!("seed{seed}-exec{exec}-{call}.{}", kind.name()));
    std::fs::write(&p, input).ok()?;
    Some(p)
}
