//! The text reader's fast path against the general reader, and the dialects.

use super::header::sniff_delimiter;
use super::*;

/// Rows of `text` by the fast path (`None` if it declines) and by the
/// general reader.
fn both(text: &str) -> (Option<Rows>, Rows) {
    let path = Path::new("t.csv");
    let opts = LoadOptions::default();
    let l = layout(path, text.as_bytes(), Format::Csv, &opts).unwrap();
    let plan = Plan::new(path, &l.header, &opts).unwrap();
    let fast = fast_only(&l, &plan);
    let slow = reader_rows(path, &l, &plan, 4).unwrap();
    (fast, slow)
}

fn fast_only(l: &Layout<'_>, plan: &Plan) -> Option<Rows> {
    if l.quoted_head {
        return None;
    }
    let d = Dialect {
        delimiter: l.header.delimiter,
        decimal_comma: l.header.decimal_comma,
    };
    fast_rows(l.body, l.body_line, l.header.columns.len(), plan, d, 4)
}

/// The fast path's rows of `text`, `None` when it declines.
fn fast_of(text: &[u8]) -> Option<Rows> {
    let path = Path::new("t.csv");
    let opts = LoadOptions::default();
    let l = layout(path, text, Format::Csv, &opts).unwrap();
    let plan = Plan::new(path, &l.header, &opts).unwrap();
    fast_only(&l, &plan)
}

/// The fast path reads exactly what the general reader reads (values
/// bit for bit, each row's line, time decimals) on files with comments,
/// blank lines, CRLF, a BOM, padding, unused columns, `;` and tab
/// delimiters, and no final newline.
#[test]
fn fast_rows_agree_with_the_csv_reader() {
    let texts = [
        "time_s,friction_N,optical_V\n0.0,1.5,2\n0.001,-2e-3,3.25\n",
        "# note\n\n time_s , friction_N\r\n0.000, 1\r\n\r\n# mid\r\n0.001 ,2\r\n0.002,3",
        "\u{FEFF}time_s;friction_N;x\n0;1;a\n1;2;b\n",
        "time_s\tposition_mm\toptical_V\n0\t0.1\t1\n\n\n1\t0.2\t1e3\n",
        "friction_N,unused\n1,\n",
        "time_s,friction_N\n0,1\n# c\n\n1,2\n#\n2,3",
    ];
    for t in texts {
        let (fast, slow) = both(t);
        let fast = fast.unwrap_or_else(|| panic!("fast path declined {t:?} {:?}", slow.lines));
        assert_eq!(fast.lines, slow.lines, "{t:?}");
        assert_eq!(fast.time_decimals, slow.time_decimals, "{t:?}");
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast.time), bits(&slow.time), "{t:?}");
        assert_eq!(fast.channels.len(), slow.channels.len());
        for (a, b) in fast.channels.iter().zip(&slow.channels) {
            assert_eq!(bits(a), bits(b), "{t:?}");
        }
    }
}

/// A body long enough to be parsed in two halves gives the same rows,
/// values and line numbers as the general reader; with a comment or a
/// `\r\n` it is parsed in one pass, with the same result.
#[test]
fn long_bodies_parsed_in_halves_agree_with_the_csv_reader() {
    let mut body = String::new();
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    for i in 0..20_000 {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let u = (state >> 11) as f64 / (1u64 << 53) as f64;
        let v = (u - 0.5) * 10f64.powi((i % 13) - 6);
        body.push_str(&format!("{},{v},{:e},x{i}, {}\n", i as f64 / 1000.0, u, -u));
    }
    let head = "time_s,friction_N,position_mm,note,optical_V\n";
    let plain = format!("{head}{body}");
    assert!(plain.len() >= 2 * fast::PARALLEL_BYTES);
    let crlf = plain.replace('\n', "\r\n");
    let commented = format!("{head}# a comment\n{body}");
    for t in [&plain, &crlf, &commented] {
        let (fast, slow) = both(t);
        let fast = fast.expect("fast path read it");
        assert_eq!(fast.lines.len(), 20_000);
        assert_eq!(fast.lines, slow.lines);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast.time), bits(&slow.time));
        assert_eq!(fast.time_decimals, slow.time_decimals);
        for (a, b) in fast.channels.iter().zip(&slow.channels) {
            assert_eq!(bits(a), bits(b));
        }
    }
    // A bad cell in the second half sends the file to the general reader.
    let bad = plain.replacen(",x19990,", ",x19990,,", 1);
    assert!(fast_of(bad.as_bytes()).is_none());
}

/// Quotes, lone `\r` line ends, ragged rows and bad cells are left to
/// the general reader (which reads or reports them).
#[test]
fn fast_rows_decline_what_they_do_not_handle() {
    for t in [
        "time_s,friction_N\n0,\"1\"\n",
        "time_s,friction_N\r0,1\r1,2\r",
        "time_s,friction_N\n0,1,2\n",
        "time_s,friction_N\n0\n",
        "time_s,friction_N\n0,1\n1,inf\n",
        "time_s,friction_N\n0,1\n1,x\n",
        "time_s,friction_N\n0,1\n1,\n",
        // Quotes where no number is parsed: a comment, an unused field.
        "time_s,friction_N\n# a \"quoted\" note\n0,1\n",
        "time_s,friction_N,note\n0,1,\"a, b\"\n",
        "\"time_s\",friction_N\n0,1\n",
    ] {
        assert!(fast_of(t.as_bytes()).is_none(), "{t:?}");
    }
}

/// Bytes that are not text, where no number is parsed (a comment, an
/// unused field), send the file to the general reader too.
#[test]
fn fast_rows_decline_bytes_that_are_not_text() {
    for t in [
        &b"time_s,friction_N,note\n0,1,ok\n1,2,\xFF\n"[..],
        &b"time_s,friction_N\n0,1\n# \xC3\n1,2\n"[..],
    ] {
        assert!(fast_of(t).is_none(), "{t:?}");
    }
    // The same files as text are read.
    for t in [
        &b"time_s,friction_N,note\n0,1,ok\n1,2,\xC3\xA9\n"[..],
        &b"time_s,friction_N\n0,1\n# \xC3\xA9\n1,2\n"[..],
    ] {
        assert!(fast_of(t).is_some(), "{t:?}");
    }
}

#[test]
fn decimals_count_printed_precision() {
    assert_eq!(decimals(b"0.0125"), 4);
    assert_eq!(decimals(b"1.25e-2"), 4);
    assert_eq!(decimals(b"12"), 0);
    assert_eq!(decimals(b"1e3"), -3);
    assert_eq!(decimals(b"-3.5E+1"), 0);
    assert_eq!(decimals(b"5."), 0);
    assert_eq!(decimals(b".25"), 2);
    assert_eq!(decimals(b"2.5e"), 1);
}

#[test]
fn delimiter_is_sniffed_from_the_header_line() {
    assert_eq!(sniff_delimiter(b"# c,o,m\na\tb\tc\n1\t2\t3\n"), b'\t');
    assert_eq!(sniff_delimiter(b"a;b;c\n1,5;2;3\n"), b';');
    assert_eq!(sniff_delimiter(b"a,b\n"), b',');
    assert_eq!(sniff_delimiter(b"a\n1\n"), b',');
}
