//! `--help` reads the same across subcommands: `-o`/`--out DIR` everywhere,
//! one placeholder per kind of value (with its unit), the formats each
//! command reads, and no Rust type names.

mod common;

use common::run;

const COMMANDS: [&[&str]; 13] = [
    &["predict"],
    &["compensate"],
    &["inspect"],
    &["analyze"],
    &["passage"],
    &["sweep"],
    &["diagnose"],
    &["simulate"],
    &["simulate-campaign"],
    &["demo"],
    &["model", "signals"],
    &["model", "pulses"],
    &["model", "stage"],
];

fn help(cmd: &[&str]) -> String {
    let mut args = cmd.to_vec();
    args.push("--help");
    let (ok, out, err) = run(&args);
    assert!(ok, "{cmd:?} --help: {err}");
    out
}

/// The placeholder a flag shows, e.g. `HZ` for `--lowpass <HZ>`.
fn placeholder<'a>(text: &'a str, flag: &str) -> Option<&'a str> {
    let at = text.find(&format!("{flag} <"))? + flag.len() + 2;
    text[at..].split('>').next()
}

#[test]
fn flags_and_placeholders_agree_across_subcommands() {
    // flag → the one placeholder it shows wherever it appears
    let want = [
        ("--out", "DIR"),
        ("--lowpass", "HZ"),
        ("--harmonics", "K"),
        ("--jobs", "N"),
        ("--order", "N"),
        ("--fs", "HZ"),
        ("--velocity", "MM/S"),
        ("--profile", "FILE"),
        ("--seed", "SEED"),
    ];
    for cmd in COMMANDS {
        let h = help(cmd);
        for (flag, ph) in want {
            if let Some(got) = placeholder(&h, flag) {
                // simulate writes one recording: a file, not a folder
                let ph = if cmd == ["simulate"] && flag == "--out" {
                    "FILE"
                } else {
                    ph
                };
                assert_eq!(got, ph, "{cmd:?} {flag}");
            }
        }
        if h.contains("--out <") {
            assert!(h.contains("-o, --out"), "{cmd:?}: --out without -o");
        }
        // a value flag shows a chosen placeholder, not its own name in capitals
        for line in h.lines() {
            let line = line.trim_start();
            let Some(rest) = line
                .strip_prefix("--")
                .or_else(|| line.get(4..).and_then(|l| l.strip_prefix("--")))
            else {
                continue;
            };
            let Some((name, tail)) = rest.split_once(" <") else {
                continue;
            };
            let ph = tail.split('>').next().unwrap();
            let own = name.to_uppercase().replace('-', "_");
            let enum_like = h.contains("Possible values") || h.contains("[possible values");
            assert!(
                ph != own
                    || enum_like
                        && [
                            "FORMAT",
                            "DETREND",
                            "WINDOW",
                            "CORR_NORM",
                            "START",
                            "CONDITION",
                            "CONVENTION",
                            "RATIO_KIND"
                        ]
                        .contains(&ph)
                    || ["BEARING", "SEED", "PATTERN"].contains(&ph),
                "{cmd:?}: --{name} <{ph}> shows its own name"
            );
        }
        // no Rust type names (CamelCase words other than the product names
        // ControlDesk and LabVIEW, NaN, and the unit GiB)
        for w in h.split(|c: char| !c.is_alphanumeric()) {
            let caps = w.chars().filter(|c| c.is_uppercase()).count();
            let lower_first = w.chars().next().is_some_and(|c| c.is_uppercase())
                && w.chars().nth(1).is_some_and(|c| c.is_lowercase());
            assert!(
                !(caps >= 2 && lower_first)
                    || ["ControlDesk", "LabVIEW", "NaN", "GiB"].contains(&w),
                "{cmd:?}: '{w}' in the help"
            );
        }
        assert!(
            !h.contains("ERRATA"),
            "{cmd:?}: cites a file users do not have"
        );
    }
}

#[test]
fn every_command_that_reads_recordings_names_the_formats() {
    for cmd in [
        &["inspect"][..],
        &["analyze"],
        &["passage"],
        &["sweep"],
        &["diagnose"],
        &["compensate"],
    ] {
        let h = help(cmd);
        assert!(
            h.contains("CSV/TSV") && h.contains(".mat"),
            "{cmd:?} does not say it reads CSV/TSV and .mat"
        );
    }
}
