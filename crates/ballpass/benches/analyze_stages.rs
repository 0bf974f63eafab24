//! Where `analyze`'s time goes, stage by stage, on the record
//! `tools/bench_python.py` times (`ballpass.simulate(9.0, seed=1)`: 30 s at
//! 1 kHz, friction, encoder and optical, the default bearing):
//!
//! ```sh
//! GLIBC_TUNABLES=glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=1073741824 \
//!   RAYON_NUM_THREADS=1 cargo bench -p ballpass --bench analyze_stages -- [--repeat 60] [--cpu]
//! ```
//!
//! (`--cpu`: the mean CPU time per run of the whole process, all threads,
//! read from `/proc/self/task/*/schedstat` on Linux, instead of the best
//! wall time, which on a loaded machine mostly measures the waits for a
//! core.)
//!
//! (The tunables are the command line's `mallopt` settings, freed blocks
//! kept for reuse; the Python extension brings mimalloc for the same
//! reason. Without them every large buffer is mapped and zeroed anew and
//! the passages and checks take 1.5-3x longer.)
//!
//! Each stage is timed on its own (best of `--repeat` runs, wall time; run
//! with one rayon thread so that the figures add up): the checks before the
//! analysis (`preflight::check`, what the command line and Python run
//! first), the load-cell correction, the optical passage detection with
//! `analyze`'s settings, the position-domain spectra, and the whole
//! `analyze`; "the rest" is the whole less those three stages inside it
//! (low-pass, correlations, the three spectra, stage identification,
//! period, phases, harmonic tests, synchronous average).
//!
//! Measured on the shared 2-core machine with `--cpu` (mean CPU time of 60
//! runs, one thread, load average 8; two runs): checks 0.11-0.13 ms,
//! load-cell correction 0.70-0.79 ms, optical passages 5.6-5.7 ms,
//! position-domain spectra 2.85-2.87 ms, the rest 6.3-6.5 ms, analyze
//! 15.6 ms. (The previous release, another session at load 7: 0.13-0.18,
//! 1.33, 6.2, 2.9, 7.35, 17.8 ms. At that load the best wall time mostly
//! measures the waits for a core: 32 ms whole against 17.8 ms CPU.)

use std::hint::black_box;
use std::time::{Duration, Instant};

use ballpass::analysis::load_cell::restore_friction;
use ballpass::analysis::position::position_spectra;
use ballpass::analysis::preflight::{check, PreflightSettings};
use ballpass::analysis::{analyze, detect_passages, AnalyzeSettings, PassageSettings};
use ballpass::sim::{simulate, SimSettings};

fn arg(name: &str, default: usize) -> usize {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map_or(default, |v| v.parse().expect("a whole number"))
}

/// CPU time of every thread of this process so far (Linux: the first
/// field of each `/proc/self/task/*/schedstat`, in ns); `None` elsewhere.
fn cpu_time() -> Option<Duration> {
    let mut ns = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let stat = std::fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        ns += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(Duration::from_nanos(ns))
}

/// Best wall time of `repeat` runs of `f`; with `cpu`, the mean CPU time
/// of the whole process (the rayon workers included) over the `repeat`
/// runs (the kernel updates a running thread's count at its ticks, so
/// only a sum over many runs is exact to well under a run).
fn best<T>(repeat: usize, cpu: bool, mut f: impl FnMut() -> T) -> Duration {
    if let (true, Some(start)) = (cpu, cpu_time()) {
        for _ in 0..repeat {
            black_box(f());
        }
        if let Some(end) = cpu_time() {
            return end.saturating_sub(start) / repeat as u32;
        }
    }
    (0..repeat)
        .map(|_| {
            let t = Instant::now();
            black_box(f());
            t.elapsed()
        })
        .min()
        .expect("repeat >= 1")
}

fn main() {
    let repeat = arg("--repeat", 60).max(1);
    let cpu = std::env::args().any(|a| a == "--cpu");
    let sim = simulate(&SimSettings {
        velocity_mm_s: 9.0,
        seed: 1,
        ..SimSettings::default()
    })
    .expect("the default simulation runs");
    let geometry = sim.truth.settings.geometry;
    let settings = AnalyzeSettings::default();
    let rec = sim.recording;
    let checked = check(
        vec![rec.clone()],
        Some(9.0),
        &geometry,
        &PreflightSettings::default(),
    )
    .expect("the simulated record passes the checks");
    let recs = checked.recordings;
    let pred = geometry
        .predict(checked.velocity_mm_s, settings.harmonics)
        .expect("a prediction");
    let friction = recs[0]
        .channel(ballpass::recording::Channel::Friction)
        .expect("friction")
        .to_vec();
    let passage_settings = PassageSettings {
        velocity_mm_s: Some(pred.velocity_mm_s),
        fit_pulses: 0,
        ..PassageSettings::default()
    };
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    let threads = rayon::current_num_threads();
    println!(
        "analyze stages, 30 s 3-channel record at 9 mm/s, best of {repeat}, {threads} rayon thread(s), {}",
        if cpu && cpu_time().is_some() {
            "mean CPU time"
        } else {
            "best wall time"
        }
    );
    let t_check = best(repeat, cpu, || {
        check(
            vec![rec.clone()],
            Some(9.0),
            &geometry,
            &PreflightSettings::default(),
        )
    });
    let t_load = best(repeat, cpu, || {
        restore_friction(&friction, rec.fs_hz(), pred.tau_c_s, settings.load_cell)
    });
    let t_passages = best(repeat, cpu, || detect_passages(&recs[0], &passage_settings));
    let t_position = best(repeat, cpu, || {
        position_spectra(&recs, pred.d_avg_mm, &settings).expect("position spectra")
    });
    let t_all = best(repeat, cpu, || {
        analyze(&recs, &pred, &settings).expect("analysis")
    });
    let inside = t_load + t_passages + t_position;
    let rest = t_all.saturating_sub(inside);
    for (name, t) in [
        ("checks before the analysis (preflight)", t_check),
        ("load-cell correction", t_load),
        ("optical passages", t_passages),
        ("position-domain spectra", t_position),
        ("the rest of analyze", rest),
        ("analyze, whole", t_all),
    ] {
        println!(
            "{name:40} {:8.2} ms  {:5.1} %",
            ms(t),
            100.0 * t.as_secs_f64() / t_all.as_secs_f64()
        );
    }
}
