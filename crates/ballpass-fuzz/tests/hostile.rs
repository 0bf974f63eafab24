//! Hostile files of issue 18, each a regression test named after what it
//! guards, measured with the counting allocator; and a brief seeded run of
//! the whole harness.
//!
//! The tests share the allocator's counters, so they run one at a time.

use std::path::Path;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use ballpass::recording::inspect::{inspect_bytes, InspectSettings};
use ballpass::recording::io::{contents_of_bytes, load_all_bytes};
use ballpass::recording::LoadOptions;
use ballpass_fuzz::alloc::{self, Counting};
use ballpass_fuzz::harness::{memory_bound, run, Config};
use ballpass_fuzz::{corpus, matgen};

#[global_allocator]
static ALLOC: Counting = Counting;

static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

/// Every loader call on a MAT-file in memory: the error messages (or Ok
/// as "ok"), the longest call and the peak of live bytes.
fn all_calls(bytes: &[u8]) -> (Vec<String>, Duration, usize) {
    let path = Path::new("hostile.mat");
    let opts = LoadOptions::default();
    let mut msgs = Vec::new();
    let mut longest = Duration::ZERO;
    alloc::reset();
    let base = alloc::current();
    let mut time = |f: &dyn Fn() -> String| {
        let t = Instant::now();
        msgs.push(f());
        longest = longest.max(t.elapsed());
    };
    let text = |r: ballpass::Result<()>| r.map_or_else(|e| e.to_string(), |()| "ok".into());
    time(&|| text(load_all_bytes(path, bytes, &opts).map(|_| ())));
    time(&|| match contents_of_bytes(path, bytes, &opts, 500) {
        Ok(items) => items
            .iter()
            .map(|(n, w)| format!("{n}: {w}"))
            .collect::<Vec<_>>()
            .join("; "),
        Err(e) => e.to_string(),
    });
    time(&|| text(inspect_bytes(path, bytes, &opts, &InspectSettings::default()).map(|_| ())));
    (msgs, longest, alloc::usage(base).peak_bytes)
}

/// Issue 18, item 1: nested 1x1 cells took time doubling per level (depth
/// 22, a 2.4 KB file: 22 s; depth 32: over 120 s). Now each element is
/// parsed once: any depth returns at once. A cell variable is not parsed
/// to load a recording (it is no channel); listed, past 32 levels it says so.
#[test]
fn nested_1x1_cell_arrays_do_not_hang() {
    let _one = ONE_AT_A_TIME.lock();
    for depth in [20, 22, 31, 32, 33, 64, 2048] {
        for compressed in [false, true] {
            let plain = matgen::nested_cells(depth);
            let bytes = if compressed {
                matgen::file(&[matgen::compressed(&plain[128..])])
            } else {
                plain
            };
            let (msgs, longest, _) = all_calls(&bytes);
            // 2048 levels are ~150 KB: well under a millisecond of parsing;
            // 100 ms leaves room for a loaded machine.
            assert!(
                longest < Duration::from_millis(100),
                "depth {depth}: {longest:?}"
            );
            assert!(
                msgs[0].contains("no channel found"),
                "depth {depth}: {}",
                msgs[0]
            );
            if depth > 32 {
                assert!(
                    msgs[1].contains("nested more than 32 levels deep"),
                    "depth {depth}: {}",
                    msgs[1]
                );
            } else {
                assert!(msgs[1].contains("c{1}{1}{1}"), "depth {depth}: {}", msgs[1]);
            }
        }
    }
}

/// Issue 18, item 2: nested 1x1 structs 2048 deep overflowed the stack of
/// `inspect` (and 512 deep that of a loader thread); deep cells and
/// objects too. Run here on a thread with a 256 KiB stack, an eighth of a
/// rayon worker's.
#[test]
fn deep_structs_cells_and_objects_do_not_overflow_the_stack() {
    let _one = ONE_AT_A_TIME.lock();
    let files = [
        matgen::nested_structs(512),
        matgen::nested_structs(2048),
        matgen::nested_cells(2048),
        matgen::nested_objects(2048),
    ];
    let msgs = std::thread::Builder::new()
        .stack_size(256 << 10)
        .spawn(move || files.iter().map(|f| all_calls(f).0).collect::<Vec<_>>())
        .unwrap()
        .join()
        .expect("no stack overflow");
    // Structs are parsed to look for a ControlDesk recording: refused.
    for m in &msgs[..2] {
        assert!(
            m[0].contains("at s.f.f.f.f") && m[0].contains("nested more than 32"),
            "{}",
            m[0]
        );
        assert!(m[1].contains("nested more than 32"), "{}", m[1]);
        assert!(m[0].len() < 300, "{}", m[0]);
    }
    // Cells only when listed.
    assert!(msgs[2][1].contains("nested more than 32"), "{}", msgs[2][1]);
    // An object is listed as what it is, never walked into.
    assert!(msgs[3][0].contains("no channel found"), "{}", msgs[3][0]);
}

/// Issue 18, item 3: a compressed stream inside a compressed stream (a 6 KB
/// file took 3.2 GB), and a name length of 4 GB in a 1 KB file (4.2 GB
/// asked for). Nested streams are refused after inflating 8 bytes of the
/// outer one; lengths are checked against what remains before anything is
/// allocated.
#[test]
fn nested_zlib_streams_and_lying_lengths_do_not_blow_memory() {
    let _one = ONE_AT_A_TIME.lock();
    // 4 M zeros (32 MB) compressed twice: a few hundred bytes.
    let nested = matgen::nested_zlib(2, 4 << 20);
    assert!(nested.len() < 2048, "{}", nested.len());
    let (msgs, _, peak) = all_calls(&nested);
    assert!(
        msgs[0].contains("compressed stream inside a compressed stream"),
        "{}",
        msgs[0]
    );
    // Nothing near the 32 MB inside: the file's own size plus small buffers.
    assert!(peak < 1 << 20, "peak {peak} bytes");
    for claim in [u32::MAX, u32::MAX - 7, 1 << 30] {
        let lying = matgen::lying_name_length(claim);
        let (msgs, _, peak) = all_calls(&lying);
        assert!(
            msgs[0].contains(&format!("claims {claim} bytes")),
            "{claim}: {}",
            msgs[0]
        );
        assert!(peak < 1 << 20, "{claim}: peak {peak} bytes");
    }
    // Dimensions that claim more than the file holds (the variable is not
    // a channel, so only listing it parses it).
    for class in [1u8, 2, 6] {
        let (msgs, _, peak) = all_calls(&matgen::lying_dims(i32::MAX, i32::MAX, class));
        assert!(
            msgs[1].contains("claims") || msgs[1].contains("needs"),
            "{}",
            msgs[1]
        );
        assert!(peak < 1 << 20, "class {class}: peak {peak}");
    }
    // What a compressed file can really hold is read: 4 M zeros compressed
    // once are a valid 32 MB vector, within the bound for its size.
    let one = matgen::file(&[matgen::compressed(&matgen::double_vector(
        "friction_N",
        &vec![0.0; 4 << 20],
    ))]);
    let o = LoadOptions {
        fs_hz: Some(1000.0),
        ..Default::default()
    };
    alloc::reset();
    let base = alloc::current();
    let r = load_all_bytes(Path::new("ok.mat"), &one, &o).unwrap();
    let peak = alloc::usage(base).peak_bytes;
    assert_eq!(r[0].len(), 4 << 20);
    assert!(
        peak <= memory_bound(corpus::Kind::Mat, one.len()),
        "peak {peak} for {} bytes",
        one.len()
    );
}

/// Found by the long fuzz run (seed 1, before exec 200 000): a struct array
/// without fields whose dimensions claim 2^32 elements made the parser
/// reserve 103 GB for elements that hold nothing.
#[test]
fn a_struct_without_fields_claiming_billions_of_elements_allocates_nothing() {
    let _one = ONE_AT_A_TIME.lock();
    for (rows, cols) in [(i32::MAX, 2), (1 << 20, 1 << 10)] {
        let f = matgen::fieldless_struct(rows, cols);
        let (msgs, _, peak) = all_calls(&f);
        assert!(msgs[0].contains("no channel found"), "{}", msgs[0]);
        assert!(
            msgs[1].contains(&format!("s: struct {rows}x{cols}")),
            "{}",
            msgs[1]
        );
        assert!(peak < 1 << 20, "{rows}x{cols}: peak {peak}");
    }
}

/// Issue 18, item 3 (memory), found by the long fuzz run (seed 7, between
/// execs 800 000 and 900 000): a char array with no characters whose
/// dimensions claim 2^31 - 1 rows made `contents` reserve 51 GB of empty
/// rows and abort.
#[test]
fn an_empty_char_array_claiming_billions_of_rows_allocates_nothing() {
    let _one = ONE_AT_A_TIME.lock();
    for rows in [i32::MAX, 1 << 20] {
        let f = matgen::empty_text(rows);
        let (msgs, _, peak) = all_calls(&f);
        assert!(msgs[0].contains("no channel found"), "{}", msgs[0]);
        assert!(msgs[1].contains("c:"), "{}", msgs[1]);
        // 1 MB: the parser's own bookkeeping for a 200-byte file is far less.
        assert!(peak < 1 << 20, "{rows} rows: peak {peak}");
    }
}

/// Issue 18, item 11: the third-party readers' failures (HDF5, MDF) and
/// our MAT parser's are one-line errors in our words: no "binrw error", no
/// panic text, nothing that spans lines.
#[test]
fn third_party_failures_are_one_line_errors_in_our_words() {
    let _one = ONE_AT_A_TIME.lock();
    let seeds: Vec<corpus::Seed> = corpus::fixtures()
        .into_iter()
        .filter(|s| {
            matches!(
                s.kind,
                corpus::Kind::Mat | corpus::Kind::Mf4 | corpus::Kind::Tdms
            )
        })
        .collect();
    assert!(seeds.len() >= 20, "{} fixtures", seeds.len());
    let report = run(
        &seeds,
        &Config {
            seed: 11,
            execs: 1500,
            max_time: Some(Duration::from_secs(30)),
            save_dir: std::env::temp_dir().join("ballpass-fuzz-item11"),
            progress_every: 0,
            time_slack: 20.0,
        },
    );
    assert!(report.errors > 1000, "{report}");
    assert_eq!(report.failure_count, 0, "{report}");
}

/// A brief seeded run of the whole harness over every seed: no panic,
/// hang, memory beyond the bound, bad message or CSV disagreement. (The
/// long run is `cargo bench -p ballpass-fuzz --bench fuzz`.) The time limit
/// is 20 times the long run's: other test binaries share the cores here.
#[test]
fn brief_seeded_fuzz_run_finds_nothing() {
    let _one = ONE_AT_A_TIME.lock();
    let seeds = corpus::all();
    let report = run(
        &seeds,
        &Config {
            seed: 2024,
            execs: 4000,
            max_time: Some(Duration::from_secs(20)),
            save_dir: std::env::temp_dir().join("ballpass-fuzz-brief"),
            progress_every: 0,
            time_slack: 20.0,
        },
    );
    eprintln!("{report}");
    assert!(report.total_calls() > 3000, "{report}");
    assert_eq!(report.failure_count, 0, "{report}");
}
