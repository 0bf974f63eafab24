use super::*;
use crate::{butter, cheby1, FilterBand};

fn noise(n: usize) -> Vec<f64> {
    let mut s = 0x2545_f491_4f6c_dd1du64;
    (0..n)
        .map(|i| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5 + (i as f64 * 0.01).sin() + 3.0
        })
        .collect()
}

fn norm_err(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// Chunked vs sample by sample, forward and reversed, from a nonzero
/// state. 1e-13 norm-wise: the superposition regroups the sums, a few
/// ulp of the state size per sample (observed ~1e-15). The cheby1 case
/// runs as 8 chunks shorter than its settle length on AVX-512F, its
/// free responses carried across seams.
fn check_chunked(sections: &[[f64; 6]], n: usize, expect_chunked: bool) {
    let cascade = Cascade::new(sections);
    let x = noise(n);
    assert_eq!(cascade.chunks(n, 8).is_some(), expect_chunked);
    let zi: Vec<[f64; 2]> = (0..sections.len())
        .map(|s| [0.3 * s as f64 - 0.2, 0.1])
        .collect();
    for rev in [false, true] {
        let mut plain = x.clone();
        cascade.filter(&mut plain, &mut zi.clone(), rev);
        let mut fast = x.clone();
        cascade.filter_from(&mut fast, &zi, rev);
        let err = norm_err(&fast, &plain);
        assert!(err <= 1e-13, "rev {rev}: {err:e}");
        if expect_chunked {
            // The dispatched run (8 or 4 chunks on a CPU with AVX-512F
            // or AVX2) against the fallback's 2 chunks: the seams
            // differ, so 1e-13 as above, not bitwise.
            let mut fallback = x.clone();
            dispatch!(cascade, S, F, c => filter_chunked::<_, CHUNKS, S, F>(
                Baseline, c, &mut fallback, &zi, rev
            ));
            let err = norm_err(&fast, &fallback);
            assert!(err <= 1e-13, "rev {rev}, vs fallback: {err:e}");
        }
    }
}

/// Bits of a signal, so that comparisons are bitwise.
fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// The loops compiled for AVX2 / AVX-512F against the baseline build of
/// the same generic code with the same chunk count, forward and
/// reversed: bitwise equal.
fn check_wide<const S: usize, const F: u8>(sections: &[[f64; 6]], wide: Wide) {
    let mut cascade = Cascade::new(sections);
    if F == GENERAL {
        cascade.layout = GENERAL;
    }
    assert_eq!(cascade.layout, F);
    let c: &[Coef; S] = cascade.coefs.as_slice().try_into().unwrap();
    let x = noise(30_011);
    let zi: Vec<[f64; 2]> = (0..S).map(|s| [0.3 * s as f64 - 0.2, 0.1]).collect();
    let avx2 = match wide {
        Wide::Avx2(isa) => isa,
        Wide::Avx512(isa) => isa.avx2(),
    };
    for rev in [false, true] {
        let run = |f: &dyn Fn(&mut [f64])| {
            let mut y = x.clone();
            f(&mut y);
            bits(&y)
        };
        assert_eq!(
            run(&|y| filter_chunked::<_, 4, S, F>(avx2, c, y, &zi, rev)),
            run(&|y| filter_chunked::<_, 4, S, F>(Baseline, c, y, &zi, rev)),
            "AVX2, 4 chunks, rev {rev}"
        );
        if let Wide::Avx512(isa) = wide {
            assert_eq!(
                run(&|y| filter_chunked::<_, 8, S, F>(isa, c, y, &zi, rev)),
                run(&|y| filter_chunked::<_, 8, S, F>(Baseline, c, y, &zi, rev)),
                "AVX-512F, 8 chunks, rev {rev}"
            );
        }
    }
}

#[test]
fn wide_kernels_round_as_the_baseline() {
    let Some(wide) = simd::detect() else {
        eprintln!("no AVX2 on this CPU: only the baseline runs");
        return;
    };
    let lp = FilterBand::LowPass { cutoff_hz: 20.0 };
    let butter5 = butter(5, lp, 1000.0).unwrap();
    let anti_alias = FilterBand::LowPass { cutoff_hz: 0.04 };
    let cheby8 = cheby1(8, 0.05, anti_alias, 2.0).unwrap();
    check_wide::<3, LOWPASS_ODD>(butter5.sections(), wide);
    check_wide::<3, GENERAL>(butter5.sections(), wide);
    check_wide::<4, LOWPASS>(cheby8.sections(), wide);
}

#[test]
fn chunked_matches_sample_by_sample() {
    let lp = FilterBand::LowPass { cutoff_hz: 20.0 };
    check_chunked(butter(5, lp, 1000.0).unwrap().sections(), 30_001, true);
    let anti_alias = FilterBand::LowPass { cutoff_hz: 0.04 };
    check_chunked(
        cheby1(8, 0.05, anti_alias, 2.0).unwrap().sections(),
        30_003,
        true,
    );
    // Too short to chunk: the plain path (the check is then exact).
    check_chunked(butter(5, lp, 1000.0).unwrap().sections(), 2000, false);
}

#[test]
fn section_kinds_round_as_the_general_form() {
    // Bit-identical to the 5-multiply form (no tolerance): the kinds
    // only drop multiplies by exact factors (2 b0 = b0 + b0, 1 x = x).
    let lp = FilterBand::LowPass { cutoff_hz: 20.0 };
    let anti_alias = FilterBand::LowPass { cutoff_hz: 0.04 };
    for sos in [
        butter(5, lp, 1000.0).unwrap(),
        butter(4, lp, 1000.0).unwrap(),
        cheby1(8, 0.05, anti_alias, 2.0).unwrap(),
    ] {
        let fast = Cascade::new(sos.sections());
        assert_ne!(fast.layout, GENERAL);
        let mut general = fast.clone();
        general.layout = GENERAL;
        let x = noise(5000);
        let zi = vec![[0.25, -0.5]; sos.n_sections()];
        for rev in [false, true] {
            let (mut a, mut b) = (x.clone(), x.clone());
            let (mut za, mut zb) = (zi.clone(), zi.clone());
            fast.filter(&mut a, &mut za, rev);
            general.filter(&mut b, &mut zb, rev);
            assert_eq!(a, b);
            assert_eq!(za, zb);
        }
    }
}

#[test]
fn slow_filter_carries_free_responses_across_chunks() {
    // Settles in ~11 000 samples, far longer than the 2 000-sample
    // chunks forced here: the free responses must run through several
    // chunks in further rounds. 1e-12 norm-wise (observed ~1e-15); a
    // dropped carry errs by ~1e-3.
    let sos = butter(2, FilterBand::LowPass { cutoff_hz: 1.0 }, 1000.0).unwrap();
    let cascade = Cascade::new(sos.sections());
    let c: &[Coef; 1] = cascade.coefs.as_slice().try_into().unwrap();
    let x = noise(8_003);
    let zi = [[0.5, -0.25]];
    for rev in [false, true] {
        let mut plain = x.clone();
        cascade.filter(&mut plain, &mut zi.to_vec(), rev);
        let mut fast = x.clone();
        filter_chunked::<_, 4, 1, GENERAL>(Baseline, c, &mut fast, &zi, rev);
        let err = norm_err(&fast, &plain);
        assert!(err <= 1e-12, "rev {rev}: {err:e}");
    }
}
