//! The seed inputs: every committed fixture of every format, text files in
//! the dialects labs write, profiles, manifests, and the structured MAT
//! stress files of [`crate::matgen`].

use std::path::Path;

/// What an input is read as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Kind {
    /// Delimited text (the CSV loader; its two readers are compared too).
    Csv,
    /// MATLAB MAT-file (level 5 or v7.3).
    Mat,
    /// NI TDMS.
    Tdms,
    /// ASAM MDF 4.
    Mf4,
    /// A bench profile (TOML).
    Profile,
    /// A campaign manifest (CSV).
    Manifest,
}

impl Kind {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Csv => "csv",
            Kind::Mat => "mat",
            Kind::Tdms => "tdms",
            Kind::Mf4 => "mf4",
            Kind::Profile => "profile",
            Kind::Manifest => "manifest",
        }
    }

    /// A file name of this kind, for messages and format detection.
    pub fn file_name(self) -> &'static str {
        match self {
            Kind::Csv => "fuzz.csv",
            Kind::Mat => "fuzz.mat",
            Kind::Tdms => "fuzz.tdms",
            Kind::Mf4 => "fuzz.mf4",
            Kind::Profile => "fuzz.toml",
            Kind::Manifest => "manifest.csv",
        }
    }

    /// Whether the input is text (mutated with text tokens too).
    pub fn is_text(self) -> bool {
        matches!(self, Kind::Csv | Kind::Profile | Kind::Manifest)
    }
}

/// One seed input.
#[derive(Debug, Clone)]
pub struct Seed {
    /// What it is read as.
    pub kind: Kind,
    /// Where it comes from (a fixture name or a generator).
    pub name: String,
    /// The bytes.
    pub bytes: Vec<u8>,
}

/// The committed fixtures of `crates/ballpass/tests/data`.
pub fn fixtures() -> Vec<Seed> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../ballpass/tests/data");
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(&dir) else {
        return out;
    };
    let mut names: Vec<_> = rd.filter_map(|e| e.ok()).map(|e| e.path()).collect();
    names.sort();
    for p in names {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let kind = if name.ends_with(".csv") {
            Kind::Csv
        } else if name.ends_with(".mat") {
            Kind::Mat
        } else if name.ends_with(".tdms") {
            Kind::Tdms
        } else if name.ends_with(".mf4") {
            Kind::Mf4
        } else {
            continue;
        };
        if let Ok(bytes) = std::fs::read(&p) {
            out.push(Seed { kind, name, bytes });
        }
    }
    out
}

fn text(kind: Kind, name: &str, t: String) -> Seed {
    Seed {
        kind,
        name: name.into(),
        bytes: t.into_bytes(),
    }
}

/// Text recordings in the dialects of issue 15, profiles and manifests.
pub fn texts() -> Vec<Seed> {
    let rows = |n: usize, f: &dyn Fn(usize) -> String| (0..n).map(f).collect::<Vec<_>>().join("\n");
    let mut out = vec![
        text(
            Kind::Csv,
            "plain",
            format!(
                "time_s,friction_N,position_mm,optical_V\n{}\n",
                rows(40, &|i| format!(
                    "{},{},{},{}",
                    i as f64 / 1000.0,
                    2.0 + (i as f64).sin(),
                    0.009 * i as f64,
                    0.3
                ))
            ),
        ),
        text(
            Kind::Csv,
            "decimal comma",
            format!(
                "time_s;friction_N\n{}\n",
                rows(40, &|i| format!("0,{i:03};{i},25"))
            ),
        ),
        text(
            Kind::Csv,
            "units row",
            format!(
                "Zeit\tKraft\tfriction_N\n[ms]\t[kN]\tN\n{}\n",
                rows(40, &|i| format!("{i}\t{}\t{}", i as f64 * 1e-3, i))
            ),
        ),
        text(
            Kind::Csv,
            "preamble",
            format!(
                "Logger v1\nDate: 2024-01-01\n\n\"time_s\",\"friction_N\"\n{}\n# end",
                rows(40, &|i| format!("{},{i}", i as f64 / 1000.0))
            ),
        ),
        text(
            Kind::Csv,
            "gaps",
            format!(
                "time_ms,friction_N,optical_V\r\n{}\r\n",
                rows(60, &|i| if i % 17 == 3 {
                    format!("{i},NaN,")
                } else if i % 23 == 5 {
                    String::new()
                } else {
                    format!("{i},{i},1")
                })
            ),
        ),
        text(
            Kind::Csv,
            "quoted",
            format!(
                "time_s,friction_N,note\n{}\n",
                rows(30, &|i| format!(
                    "{},{i},\"a, \"\"b\"\"\"",
                    i as f64 / 1000.0
                ))
            ),
        ),
        text(
            Kind::Csv,
            "huge values",
            format!(
                "time_s,friction_N\n{}\n",
                rows(30, &|i| format!(
                    "{},{}",
                    i as f64 / 1000.0,
                    if i % 2 == 0 { "1e308" } else { "1.7e308" }
                ))
            ),
        ),
    ];
    out.push(text(
        Kind::Profile,
        "profile",
        r#"
name = "bench"
format = "mat"
fs_hz = 1000.0
fs_from = "bearing.sr"
time = "Zeit"
time_unit = "ms"
decimal_comma = true
skip_lines = 2
fill_gaps = 0.01
split_gaps = true
bearing = "sr25w"
min_periods = 3.0

[friction]
name = "bearing.gs"
scale = 1.0

[position]
name = "Counts"
scale = 1e-4

[optical]
name = "Voltage"
offset = -0.1

[geometry]
balls_in_race = 35

[analysis]
lowpass_hz = 20.0
"#
        .into(),
    ));
    out.push(text(
        Kind::Manifest,
        "manifest",
        "path,bearing,velocity_mm_s,repeat,condition,notes\n\
        a.csv,sr25w,9,1,new,\"first, run\"\n\
        b.csv,sr25w,9,2,new,\n\
        c.mat,sr25w,18,1,worn,\"quoted \"\"x\"\"\"\n"
            .into(),
    ));
    out
}

/// Every seed: fixtures, texts and the MAT stress files.
pub fn all() -> Vec<Seed> {
    let mut out = fixtures();
    out.extend(texts());
    for (k, bytes) in crate::matgen::stress_corpus().into_iter().enumerate() {
        out.push(Seed {
            kind: Kind::Mat,
            name: format!("stress {k}"),
            bytes,
        });
    }
    out
}
