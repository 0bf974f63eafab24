//! Run-time CPU dispatch of the lane kernels: the crate's only `unsafe`.
//!
//! The lock-step loops in `biquad.rs` (`run_lanes`, `add_free`) are
//! safe generic code over `K` lanes. Compiled for the x86_64 baseline
//! (SSE2) the compiler keeps two `f64` lanes per register; here the same
//! generic code is instantiated once more inside functions compiled with
//! AVX2 (four lanes per register) or AVX-512F (eight, and 32 registers),
//! so that `Cascade::filter_from` can run a long
//! signal as 4 or 8 chunks. Those functions are only called through a
//! proof value ([`Avx2`], [`Avx512`]) that [`detect`] makes after
//! `is_x86_feature_detected!` said yes (once per process, cached), which is
//! what makes the `unsafe` calls sound.
//!
//! FMA is deliberately not enabled: Rust never contracts `a * b + c` on its
//! own, and without the feature the wide code rounds every operation
//! exactly as the baseline code does, lane for lane (the test
//! `wide_kernels_round_as_the_baseline` checks this bitwise).
//!
//! [`widest`] does the same for any small closure over `#[inline(always)]`
//! code: the csd segment loop (window, pairwise mean, cross products) and
//! the input checks run through it (`wide_cross_sum_equals_the_baseline_bitwise`),
//! and so does the block loop of `find_peaks` with `distance`
//! (`peaks::peak_lanes`, 4 or 8 samples per instruction; its lanes are
//! exact maxima, so every instance returns the same bits:
//! `wide_peak_lanes_equal_the_baseline`).
//!
//! Off x86_64, or on a CPU without AVX2, [`detect`] says `None` and the
//! baseline path runs.
#![allow(unsafe_code)]

#[cfg(not(target_arch = "x86_64"))]
use crate::biquad::Baseline;
use crate::biquad::{Coef, Isa, Lanes};

/// The widest kernels the running CPU supports.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub(crate) enum Wide {
    /// AVX2: 4 lanes per register.
    Avx2(Avx2),
    /// AVX-512F (and AVX2): 8 lanes per register.
    Avx512(Avx512),
}

/// Detects the CPU's vector extensions (once per process); `None` without
/// AVX2 or off x86_64.
pub(crate) fn detect() -> Option<Wide> {
    #[cfg(target_arch = "x86_64")]
    {
        use std::sync::atomic::{AtomicU8, Ordering};
        // 0: not yet detected, 1: neither, 2: AVX2, 3: AVX2 and AVX-512F.
        static LEVEL: AtomicU8 = AtomicU8::new(0);
        let level = match LEVEL.load(Ordering::Relaxed) {
            0 => {
                let level = if !std::arch::is_x86_feature_detected!("avx2") {
                    1
                } else if std::arch::is_x86_feature_detected!("avx512f") {
                    3
                } else {
                    2
                };
                LEVEL.store(level, Ordering::Relaxed);
                level
            }
            level => level,
        };
        match level {
            3 => Some(Wide::Avx512(Avx512(()))),
            2 => Some(Wide::Avx2(Avx2(()))),
            _ => None,
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    None
}

/// Runs `f` compiled for the widest vectors the CPU has (see the proof
/// types' `run`): `f` should be a small closure calling `#[inline(always)]`
/// code, which is then compiled with the features. Same operations, same
/// bits: no FMA is enabled.
pub(crate) fn widest<R>(f: impl FnOnce() -> R) -> R {
    match detect() {
        Some(Wide::Avx512(p)) => p.run(f),
        Some(Wide::Avx2(p)) => p.run(f),
        None => f(),
    }
}

/// Proof that the running CPU has AVX2; only [`detect`] makes one.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub(crate) struct Avx2(());

/// Proof that the running CPU has AVX2 and AVX-512F; only [`detect`] makes
/// one.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
pub(crate) struct Avx512(());

impl Avx512 {
    /// AVX-512F machines checked here have AVX2 too.
    pub(crate) fn avx2(self) -> Avx2 {
        Avx2(())
    }
}

/// Implements [`Isa`] for a proof type by calling the loops compiled with
/// `$features` in module `$module`.
macro_rules! wide_isa {
    ($proof:ident, $module:ident, $features:literal) => {
        impl Isa for $proof {
            fn run_lanes<const K: usize, const S: usize, const F: u8>(
                self,
                c: &[Coef; S],
                st: &mut [Lanes<K>; S],
                lanes: [&mut [f64]; K],
                rev: bool,
            ) {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `self` exists only if `detect` saw every feature
                // of `$features` on this CPU.
                unsafe {
                    $module::run_lanes::<K, S, F>(c, st, lanes, rev)
                }
                #[cfg(not(target_arch = "x86_64"))]
                Baseline.run_lanes::<K, S, F>(c, st, lanes, rev)
            }

            fn add_free<const K: usize, const S: usize, const F: u8>(
                self,
                c: &[Coef; S],
                free: &mut [Lanes<K>; S],
                lanes: [&mut [f64]; K],
                limit: &[f64; K],
                rev: bool,
            ) {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: as in `run_lanes` above: the features were
                // detected.
                unsafe {
                    $module::add_free::<K, S, F>(c, free, lanes, limit, rev)
                }
                #[cfg(not(target_arch = "x86_64"))]
                Baseline.add_free::<K, S, F>(c, free, lanes, limit, rev)
            }
        }

        impl $proof {
            /// Runs `f` compiled with the features: `f` (a small closure)
            /// is inlined into a function that enables them, and with it the
            /// `#[inline(always)]` code it calls.
            pub(crate) fn run<R>(self, f: impl FnOnce() -> R) -> R {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: as in `run_lanes` above: the features were
                // detected.
                unsafe {
                    $module::run(f)
                }
                #[cfg(not(target_arch = "x86_64"))]
                f()
            }
        }

        impl crate::peaks::Runs for $proof {
            fn run_left(self, x: &[f64], lo: usize, hi: usize, v: f64) -> (Option<usize>, f64) {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: as in `run_lanes` above: the features were
                // detected.
                unsafe {
                    $module::run_left(x, lo, hi, v)
                }
                #[cfg(not(target_arch = "x86_64"))]
                crate::peaks::run_left(x, lo, hi, v)
            }

            fn run_right(self, x: &[f64], lo: usize, hi: usize, v: f64) -> (Option<usize>, f64) {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: as in `run_lanes` above: the features were
                // detected.
                unsafe {
                    $module::run_right(x, lo, hi, v)
                }
                #[cfg(not(target_arch = "x86_64"))]
                crate::peaks::run_right(x, lo, hi, v)
            }
        }

        /// The generic loops instantiated with the features enabled (they
        /// are `#[inline(always)]`, so they are compiled here).
        #[cfg(target_arch = "x86_64")]
        mod $module {
            use crate::biquad::{Coef, Lanes};

            /// `f()` with the features.
            ///
            /// # Safety
            /// The CPU must support the features.
            #[target_feature(enable = $features)]
            #[inline(never)]
            pub(super) unsafe fn run<R, F: FnOnce() -> R>(f: F) -> R {
                f()
            }

            #[target_feature(enable = $features)]
            #[inline(never)]
            pub(super) unsafe fn run_left(
                x: &[f64],
                lo: usize,
                hi: usize,
                v: f64,
            ) -> (Option<usize>, f64) {
                crate::peaks::run_left(x, lo, hi, v)
            }

            #[target_feature(enable = $features)]
            #[inline(never)]
            pub(super) unsafe fn run_right(
                x: &[f64],
                lo: usize,
                hi: usize,
                v: f64,
            ) -> (Option<usize>, f64) {
                crate::peaks::run_right(x, lo, hi, v)
            }

            /// [`crate::biquad::run_lanes`] with the features.
            ///
            /// # Safety
            /// The CPU must support the features.
            #[target_feature(enable = $features)]
            #[inline(never)]
            pub(super) unsafe fn run_lanes<const K: usize, const S: usize, const F: u8>(
                c: &[Coef; S],
                st: &mut [Lanes<K>; S],
                lanes: [&mut [f64]; K],
                rev: bool,
            ) {
                crate::biquad::run_lanes::<K, S, F>(c, st, lanes, rev)
            }

            /// [`crate::biquad::add_free`] with the features.
            ///
            /// # Safety
            /// The CPU must support the features.
            #[target_feature(enable = $features)]
            #[inline(never)]
            pub(super) unsafe fn add_free<const K: usize, const S: usize, const F: u8>(
                c: &[Coef; S],
                free: &mut [Lanes<K>; S],
                lanes: [&mut [f64]; K],
                limit: &[f64; K],
                rev: bool,
            ) {
                crate::biquad::add_free::<K, S, F>(c, free, lanes, limit, rev)
            }
        }
    };
}

wide_isa!(Avx2, avx2, "avx2");
wide_isa!(Avx512, avx512, "avx2,avx512f");
