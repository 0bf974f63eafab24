//! The running kernel of the second-order-section filters.
//!
//! # Recurrence form
//!
//! SciPy's `_sosfilt` runs direct form II transposed per section,
//!
//! ```text
//! y[n]    = b0 x[n] + z0[n]
//! z0[n+1] = (b1 x[n] - a1 y[n]) + z1[n]
//! z1[n+1] = b2 x[n] - a2 y[n]
//! ```
//!
//! whose loop-carried chain is `z0 -> y -> a1 y -> - -> + z1`: four dependent
//! floating-point operations per sample. The same filter is run here as
//!
//! ```text
//! y[n]    = (b0 x[n] + q[n]) - a1 y[n-1]
//! q[n+1]  = (b1 x[n] + r[n]) - a2 y[n-1]      r[n] = b2 x[n-1]
//! ```
//!
//! which is the same sum (`z0[n] = q[n] - a1 y[n-1]`,
//! `z1[n] = r[n] - a2 y[n-1]`) with the additions grouped so that each
//! feedback term is subtracted last: the chains from one output to the
//! next are `a1 y[n-1] -> -` (two operations per sample) and
//! `a2 y[n-1] -> - -> + -> -` (four per two samples): half SciPy's
//! latency, with the input terms off the chains. The rounding differs
//! from SciPy's grouping at the level of one unit in the last place per
//! operation (the fixture tests bound the result norm-wise at 1e-12;
//! observed ~1e-14). DF-II-T states convert exactly in
//! (`q = z0, r = z1, y[-1] = 0`) and with one rounding each out.
//!
//! # Lanes
//!
//! [`Lanes<K>`] runs `K` independent signals in lock step with identical
//! per-lane arithmetic, so a lane's result does not depend on `K` and the
//! compiler can keep the lanes in SIMD registers. A long single signal is
//! split into `K` chunks run as lanes (see [`filter_chunked`]): 2 on the
//! x86_64 baseline (SSE2), 4 or 8 when the CPU has AVX2 or AVX-512F
//! (run-time dispatch in `simd.rs`, which instantiates the same generic
//! loops with those features enabled; [`Isa`]).

use crate::simd::{self, Wide};

/// One section's coefficients, `a0 = 1` implied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Coef {
    b0: f64,
    b1: f64,
    b2: f64,
    a1: f64,
    a2: f64,
}

/// Exact relations between a section's coefficients that save multiplies
/// without changing a result: `b2 x = b0 x` when `b2 = b0`, and `1 x = x`,
/// `0 x = 0` are exact in floating point (up to the sign of a zero), so
/// each kind rounds exactly as [`Kind::General`]. Butterworth and
/// Chebyshev low-pass designs are made of such sections (double zeros at
/// `z = -1`, the gain in the first), so they run with 2-4 multiplies per
/// section and sample instead of 5. `b1 x` stays a multiply (by `b1 = 2 b0`
/// or 2) rather than becoming an addition: the additions are the scarcer
/// execution units here.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    /// Any coefficients.
    General,
    /// `b = b0 [1, 2, 1]`.
    Double,
    /// `b = [1, 2, 1]`.
    DoubleUnit,
    /// `b = [1, 1, 0]` (a single zero: `b1 x = x`, `b2 x = 0`).
    FirstUnit,
}

impl Coef {
    /// The cheapest [`Kind`] this section can run as.
    fn kind(&self) -> Kind {
        if self.b1 == 2.0 * self.b0 && self.b2 == self.b0 {
            if self.b0 == 1.0 {
                Kind::DoubleUnit
            } else {
                Kind::Double
            }
        } else if self.b0 == 1.0 && self.b1 == 1.0 && self.b2 == 0.0 {
            Kind::FirstUnit
        } else {
            Kind::General
        }
    }

    pub(crate) fn new(s: &[f64; 6]) -> Coef {
        Coef {
            b0: s[0],
            b1: s[1],
            b2: s[2],
            a1: s[4],
            a2: s[5],
        }
    }
}

/// State of one section for `K` lanes: `q`, `z1` and the previous output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Lanes<const K: usize> {
    q: [f64; K],
    r: [f64; K],
    yp: [f64; K],
}

impl<const K: usize> Default for Lanes<K> {
    fn default() -> Self {
        Lanes {
            q: [0.0; K],
            r: [0.0; K],
            yp: [0.0; K],
        }
    }
}

impl<const K: usize> Lanes<K> {
    /// Sets lane `k` from a DF-II-T state `[z0, z1]` (exact).
    fn set_df2t(&mut self, k: usize, z: [f64; 2]) {
        self.q[k] = z[0];
        self.r[k] = z[1];
        self.yp[k] = 0.0;
    }

    /// The DF-II-T state `[z0, z1]` of lane `k`.
    fn df2t(&self, c: &Coef, k: usize) -> [f64; 2] {
        [self.q[k] - c.a1 * self.yp[k], self.r[k] - c.a2 * self.yp[k]]
    }

    /// Lane `k` on its own.
    fn lane(&self, k: usize) -> Lanes<1> {
        Lanes {
            q: [self.q[k]],
            r: [self.r[k]],
            yp: [self.yp[k]],
        }
    }

    /// Largest magnitude in lane `k`'s state.
    fn max_abs(&self, k: usize) -> f64 {
        self.q[k].abs().max(self.r[k].abs()).max(self.yp[k].abs())
    }

    /// One sample through one section run as `kind` (a constant at every
    /// call site, so the match folds away).
    #[inline(always)]
    fn step(&mut self, kind: Kind, c: &Coef, x: [f64; K]) -> [f64; K] {
        let mut y = [0.0; K];
        // `self.yp` is still y[n-1] throughout.
        match kind {
            Kind::General => {
                for k in 0..K {
                    y[k] = (c.b0 * x[k] + self.q[k]) - c.a1 * self.yp[k];
                    self.q[k] = (c.b1 * x[k] + self.r[k]) - c.a2 * self.yp[k];
                    self.r[k] = c.b2 * x[k];
                }
            }
            Kind::Double => {
                for k in 0..K {
                    let u = c.b0 * x[k];
                    y[k] = (u + self.q[k]) - c.a1 * self.yp[k];
                    self.q[k] = (c.b1 * x[k] + self.r[k]) - c.a2 * self.yp[k];
                    self.r[k] = u;
                }
            }
            Kind::DoubleUnit => {
                for k in 0..K {
                    y[k] = (x[k] + self.q[k]) - c.a1 * self.yp[k];
                    self.q[k] = (c.b1 * x[k] + self.r[k]) - c.a2 * self.yp[k];
                    self.r[k] = x[k];
                }
            }
            Kind::FirstUnit => {
                for k in 0..K {
                    y[k] = (x[k] + self.q[k]) - c.a1 * self.yp[k];
                    self.q[k] = (x[k] + self.r[k]) - c.a2 * self.yp[k];
                    self.r[k] = 0.0;
                }
            }
        }
        self.yp = y;
        y
    }
}

/// Section layouts known at compile time (the `F` parameter of the
/// kernels): a run-time kind per section would keep the compiler from
/// unrolling the cascade and holding its state in registers.
const GENERAL: u8 = 0;
/// `Double` first, `DoubleUnit` after: an even-order Butterworth or
/// Chebyshev I low-pass.
const LOWPASS: u8 = 1;
/// As [`LOWPASS`], the last section `FirstUnit`: odd order.
const LOWPASS_ODD: u8 = 2;

/// Runs the cascade on one sample vector, sections laid out as `F`.
#[inline(always)]
fn cascade<const K: usize, const S: usize, const F: u8>(
    c: &[Coef; S],
    st: &mut [Lanes<K>; S],
    mut x: [f64; K],
) -> [f64; K] {
    if F == GENERAL || S < 2 {
        for s in 0..S {
            x = st[s].step(Kind::General, &c[s], x);
        }
    } else {
        x = st[0].step(Kind::Double, &c[0], x);
        for s in 1..S - 1 {
            x = st[s].step(Kind::DoubleUnit, &c[s], x);
        }
        let last = if F == LOWPASS_ODD {
            Kind::FirstUnit
        } else {
            Kind::DoubleUnit
        };
        x = st[S - 1].step(last, &c[S - 1], x);
    }
    x
}

/// Which layout `coefs` fits.
fn layout(coefs: &[Coef]) -> u8 {
    let kinds: Vec<Kind> = coefs.iter().map(Coef::kind).collect();
    match kinds.as_slice() {
        [Kind::Double | Kind::DoubleUnit, mid @ .., last]
            if mid.iter().all(|&k| k == Kind::DoubleUnit) =>
        {
            match last {
                Kind::DoubleUnit => LOWPASS,
                Kind::FirstUnit => LOWPASS_ODD,
                _ => GENERAL,
            }
        }
        _ => GENERAL,
    }
}

/// A filter's sections in kernel form.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Cascade {
    coefs: Vec<Coef>,
    /// [`GENERAL`], [`LOWPASS`] or [`LOWPASS_ODD`].
    layout: u8,
    /// Samples after which the slowest mode has decayed by 2^-70, from the
    /// largest pole radius; `None` for a marginally stable or unstable
    /// filter (never chunked).
    settle: Option<usize>,
}

/// Relative size below which a correction state is dropped (2^-70): the
/// free response left over is ~2^18 times below the rounding of the
/// signal it is added to.
const SETTLED: f64 = 8.470329472543003e-22;

/// Chunks (SIMD lanes) a long signal is split into on the x86_64 baseline:
/// 2 fill an SSE2 register; 4 and 8 measured 10 % and 15 % slower there
/// (register spills). On a CPU with AVX2 (AVX-512F) a signal long enough
/// runs as 4 (8) chunks instead ([`Wide`]).
const CHUNKS: usize = 2;

/// The most chunks the loops of `wide` (`None`: the baseline) run.
fn max_lanes(wide: Option<Wide>) -> usize {
    match wide {
        Some(Wide::Avx512(_)) => 8,
        Some(Wide::Avx2(_)) => 4,
        None => CHUNKS,
    }
}

/// Shortest chunk worth the bookkeeping.
const MIN_CHUNK: usize = 512;

/// Runs `$body` with `$c: &[Coef; S]` for the cascade's section count `S`
/// (1 to 8) and layout `F` as constants; falls through for more sections.
macro_rules! dispatch {
    ($self:ident, $S:ident, $F:ident, $c:ident => $body:expr) => {
        dispatch!(@n $self, $S, $F, $c, $body, 1 2 3 4 5 6 7 8)
    };
    (@n $self:ident, $S:ident, $F:ident, $c:ident, $body:expr, $($n:literal)*) => {
        match $self.coefs.len() {
            $($n => {
                const $S: usize = $n;
                let $c: &[Coef; $S] = $self.coefs.as_slice().try_into().expect("length checked");
                match $self.layout {
                    LOWPASS => {
                        const $F: u8 = LOWPASS;
                        $body
                    }
                    LOWPASS_ODD => {
                        const $F: u8 = LOWPASS_ODD;
                        $body
                    }
                    _ => {
                        const $F: u8 = GENERAL;
                        $body
                    }
                }
            })*
            _ => {}
        }
    };
}

impl Cascade {
    pub(crate) fn new(sections: &[[f64; 6]]) -> Cascade {
        let coefs: Vec<Coef> = sections.iter().map(Coef::new).collect();
        let r_max = coefs
            .iter()
            .map(|c| {
                // |roots of z^2 + a1 z + a2|
                let disc = c.a1 * c.a1 - 4.0 * c.a2;
                if disc < 0.0 {
                    c.a2.sqrt()
                } else {
                    let s = disc.sqrt();
                    ((-c.a1 + s) / 2.0).abs().max(((-c.a1 - s) / 2.0).abs())
                }
            })
            .fold(0.0, f64::max);
        let settle = (r_max < 1.0).then(|| {
            if r_max == 0.0 {
                // FIR sections: the state is gone after two samples.
                2 * coefs.len()
            } else {
                // ln(2^-70) / ln(r); repeated poles along the cascade take
                // a little longer, which the run-time check absorbs.
                (70.0 * std::f64::consts::LN_2 / -r_max.ln()).ceil() as usize + 2 * coefs.len()
            }
        });
        Cascade {
            layout: layout(&coefs),
            coefs,
            settle,
        }
    }

    /// The chunk count [`Cascade::filter_from`] splits `n` samples into,
    /// `None` to run sample by sample.
    ///
    /// The chunked run costs about `n / K + settle` lock-step samples
    /// whatever the chunk length (see [`filter_chunked`]) against `n` for
    /// the plain run, so it pays for `n >= 2 settle` on any lane count,
    /// and then the more lanes the better: the most the CPU runs (`lanes`:
    /// 8, 4 or [`CHUNKS`]) whose chunks are at least [`MIN_CHUNK`] long.
    /// Chunks may then be shorter than `settle` (the 8 chunks of the
    /// decimation filter's 30 000-sample run are ~3 750 samples against a
    /// `settle` of ~5 300): the free responses carry across them, which
    /// measured 9 % faster than 4 chunks that fit.
    fn chunks(&self, n: usize, lanes: usize) -> Option<usize> {
        let settle = self.settle?;
        if n < 2 * settle {
            return None;
        }
        [8, 4, CHUNKS]
            .into_iter()
            .find(|&k| k <= lanes && n / k >= MIN_CHUNK)
    }

    /// Filters `x` in place from DF-II-T state `zi` (the final state is not
    /// kept); `rev` runs from the last sample to the first. A signal long
    /// enough runs as chunks in SIMD lanes ([`filter_chunked`], chunk
    /// count from [`Cascade::chunks`], loops compiled for the widest vector
    /// extension the CPU has), else sample by sample.
    pub(crate) fn filter_from(&self, x: &mut [f64], zi: &[[f64; 2]], rev: bool) {
        debug_assert_eq!(zi.len(), self.coefs.len());
        let wide = simd::detect();
        match (self.chunks(x.len(), max_lanes(wide)), wide) {
            (Some(8), Some(Wide::Avx512(isa))) => {
                dispatch!(self, S, F, c => return filter_chunked::<_, 8, S, F>(isa, c, x, zi, rev));
            }
            (Some(4), Some(Wide::Avx512(isa))) => {
                let isa = isa.avx2();
                dispatch!(self, S, F, c => return filter_chunked::<_, 4, S, F>(isa, c, x, zi, rev));
            }
            (Some(4), Some(Wide::Avx2(isa))) => {
                dispatch!(self, S, F, c => return filter_chunked::<_, 4, S, F>(isa, c, x, zi, rev));
            }
            (Some(_), _) => {
                dispatch!(self, S, F, c => return filter_chunked::<_, CHUNKS, S, F>(Baseline, c, x, zi, rev));
            }
            (None, _) => {}
        }
        let mut z = zi.to_vec();
        self.filter(x, &mut z, rev);
    }

    /// Whether two signals of `n` samples run faster as the lanes of one
    /// [`Cascade::filter_pair`] than each through
    /// [`Cascade::filter_from`]: unless the latter splits them into more
    /// than [`CHUNKS`] chunks.
    pub(crate) fn pairs_pay(&self, n: usize) -> bool {
        self.chunks(n, max_lanes(simd::detect()))
            .is_none_or(|k| k <= CHUNKS)
    }

    /// Filters two signals of equal length in place as the two lanes of one
    /// run, `x[k]` from DF-II-T state `zi[k]` (final states not kept): each
    /// lane rounds exactly as [`Cascade::filter`] on it alone, with two
    /// samples per SIMD operation and no chunk corrections.
    pub(crate) fn filter_pair(&self, x: [&mut [f64]; 2], zi: [&[[f64; 2]]; 2], rev: bool) {
        debug_assert_eq!(x[0].len(), x[1].len());
        dispatch!(self, S, F, c => {
            let mut st = [Lanes::<2>::default(); S];
            for (k, z) in zi.iter().enumerate() {
                for (l, z) in st.iter_mut().zip(z.iter()) {
                    l.set_df2t(k, *z);
                }
            }
            return Baseline.run_lanes::<2, S, F>(c, &mut st, x, rev);
        });
        for (x, zi) in x.into_iter().zip(zi) {
            self.filter(x, &mut zi.to_vec(), rev);
        }
    }

    /// Filters `x` in place from DF-II-T state `z` (updated to the final
    /// state); `rev` runs from the last sample to the first.
    pub(crate) fn filter(&self, x: &mut [f64], z: &mut [[f64; 2]], rev: bool) {
        debug_assert_eq!(z.len(), self.coefs.len());
        dispatch!(self, S, F, c => return filter_plain::<S, F>(c, x, z, rev));
        let mut st: Vec<Lanes<1>> = z
            .iter()
            .map(|zs| {
                let mut l = Lanes::default();
                l.set_df2t(0, *zs);
                l
            })
            .collect();
        let mut run = |v: &mut f64| {
            let mut cur = [*v];
            for (l, c) in st.iter_mut().zip(&self.coefs) {
                cur = l.step(Kind::General, c, cur);
            }
            *v = cur[0];
        };
        if rev {
            x.iter_mut().rev().for_each(&mut run);
        } else {
            x.iter_mut().for_each(&mut run);
        }
        for ((zs, l), c) in z.iter_mut().zip(&st).zip(&self.coefs) {
            *zs = l.df2t(c, 0);
        }
    }
}

/// Position `pos` of a run over `n` samples, from the end when `rev`.
#[inline(always)]
fn at(pos: usize, n: usize, rev: bool) -> usize {
    if rev {
        n - 1 - pos
    } else {
        pos
    }
}

/// The `K` chunks of `len` samples of `x` in run order (from the end when
/// `rev`); the remainder `n - K len` is left out at the far end.
fn split_lanes<const K: usize>(x: &mut [f64], len: usize, rev: bool) -> [&mut [f64]; K] {
    let n = x.len();
    let body = if rev {
        &mut x[n - K * len..]
    } else {
        &mut x[..K * len]
    };
    let mut parts = body.chunks_exact_mut(len);
    let mut lanes: [&mut [f64]; K] =
        std::array::from_fn(|_| parts.next().expect("K chunks of len"));
    if rev {
        lanes.reverse();
    }
    lanes
}

/// Sample-by-sample run of one signal from DF-II-T state `z` (updated).
fn filter_plain<const S: usize, const F: u8>(
    c: &[Coef; S],
    x: &mut [f64],
    z: &mut [[f64; 2]],
    rev: bool,
) {
    let mut st = [Lanes::<1>::default(); S];
    for (l, zs) in st.iter_mut().zip(z.iter()) {
        l.set_df2t(0, *zs);
    }
    if rev {
        for v in x.iter_mut().rev() {
            *v = cascade::<1, S, F>(c, &mut st, [*v])[0];
        }
    } else {
        for v in x.iter_mut() {
            *v = cascade::<1, S, F>(c, &mut st, [*v])[0];
        }
    }
    for ((zs, l), co) in z.iter_mut().zip(&st).zip(c) {
        *zs = l.df2t(co, 0);
    }
}

/// Where the lock-step loops are compiled: [`Baseline`] for the target's
/// baseline features, the proof types of [`Wide`] with AVX2 or AVX-512F
/// enabled. All run the same generic code ([`run_lanes`], [`add_free`])
/// with the same rounding.
pub(crate) trait Isa: Copy {
    /// [`run_lanes`].
    fn run_lanes<const K: usize, const S: usize, const F: u8>(
        self,
        c: &[Coef; S],
        st: &mut [Lanes<K>; S],
        lanes: [&mut [f64]; K],
        rev: bool,
    );

    /// [`add_free`].
    fn add_free<const K: usize, const S: usize, const F: u8>(
        self,
        c: &[Coef; S],
        free: &mut [Lanes<K>; S],
        lanes: [&mut [f64]; K],
        limit: &[f64; K],
        rev: bool,
    );
}

/// The loops compiled for the target's baseline features, not inlined, so
/// that the register allocator sees only the loop.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Baseline;

impl Isa for Baseline {
    #[inline(never)]
    fn run_lanes<const K: usize, const S: usize, const F: u8>(
        self,
        c: &[Coef; S],
        st: &mut [Lanes<K>; S],
        lanes: [&mut [f64]; K],
        rev: bool,
    ) {
        run_lanes::<K, S, F>(c, st, lanes, rev)
    }

    #[inline(never)]
    fn add_free<const K: usize, const S: usize, const F: u8>(
        self,
        c: &[Coef; S],
        free: &mut [Lanes<K>; S],
        lanes: [&mut [f64]; K],
        limit: &[f64; K],
        rev: bool,
    ) {
        add_free::<K, S, F>(c, free, lanes, limit, rev)
    }
}

/// The lock-step loop: lane `k` filters `lanes[k]` in place (backwards when
/// `rev`).
#[inline(always)]
pub(crate) fn run_lanes<const K: usize, const S: usize, const F: u8>(
    c: &[Coef; S],
    st: &mut [Lanes<K>; S],
    mut lanes: [&mut [f64]; K],
    rev: bool,
) {
    let len = lanes[0].len();
    // Equal lengths, stated so that the indexing below needs no checks.
    assert!(lanes.iter().all(|l| l.len() == len));
    let mut local = *st;
    for i in 0..len {
        let j = if rev { len - 1 - i } else { i };
        let v: [f64; K] = std::array::from_fn(|k| lanes[k][j]);
        let y = cascade::<K, S, F>(c, &mut local, v);
        for (lane, y) in lanes.iter_mut().zip(y) {
            lane[j] = y;
        }
    }
    *st = local;
}

/// Adds the free response of the cascade from state `free` (input zero) to
/// `lanes[k]` for `k >= 1` (lane 0 has none), in run order (backwards when
/// `rev`), in blocks of 32 samples until every such lane's state is at most
/// `limit[k]` or the chunk ends.
#[inline(always)]
pub(crate) fn add_free<const K: usize, const S: usize, const F: u8>(
    c: &[Coef; S],
    free: &mut [Lanes<K>; S],
    lanes: [&mut [f64]; K],
    limit: &[f64; K],
    rev: bool,
) {
    let len = lanes[0].len();
    assert!(lanes.iter().all(|l| l.len() == len));
    let mut local = *free;
    let mut i = 0;
    while i < len && !(1..K).all(|k| lane_size(&local, k) <= limit[k]) {
        let end = (i + 32).min(len);
        for i in i..end {
            let j = if rev { len - 1 - i } else { i };
            let y = cascade::<K, S, F>(c, &mut local, [0.0; K]);
            for k in 1..K {
                lanes[k][j] += y[k];
            }
        }
        i = end;
    }
    *free = local;
}

/// Largest state magnitude of lane `k` over the sections.
fn lane_size<const K: usize, const S: usize>(st: &[Lanes<K>; S], k: usize) -> f64 {
    st.iter().map(|l| l.max_abs(k)).fold(0.0, f64::max)
}

/// Runs the cascade over `x` in place from DF-II-T state `zi`, split into
/// `K` chunks run as lanes (`rev`: from the last sample to the first).
///
/// By linearity the output of chunk `k` is its output from rest plus the
/// free response of the cascade to the state the signal left at the chunk's
/// start:
///
/// ```text
/// y_k = filter(x_k, 0) + free(s_k),   s_k = end state of chunk k-1
/// ```
///
/// The first chunk starts from `zi` itself. The chunks from rest run in
/// lock step (`K`-wide SIMD), then the free responses for all chunks, also
/// in lock step, until every lane's state has decayed below [`SETTLED`]
/// times its start (a stable filter's free response decays geometrically,
/// so the rest adds far less than the rounding of the samples it would be
/// added to). A free response still alive at the end of its chunk carries
/// its state into the next chunk in another round, still measured against
/// its start at its own seam, so the result never depends on how fast the
/// filter settles and the free responses take about `settle` lock-step
/// samples in all, however many chunks they cross; only the time depends
/// on the chunk length (`n / K + settle` lock-step samples).
///
/// The lock-step loops run as `isa` compiles them.
pub(crate) fn filter_chunked<I: Isa, const K: usize, const S: usize, const F: u8>(
    isa: I,
    c: &[Coef; S],
    x: &mut [f64],
    zi: &[[f64; 2]],
    rev: bool,
) {
    let n = x.len();
    let len = n / K;
    let mut st = [Lanes::<K>::default(); S];
    for (l, z) in st.iter_mut().zip(zi) {
        l.set_df2t(0, *z);
    }
    isa.run_lanes::<K, S, F>(c, &mut st, split_lanes::<K>(x, len, rev), rev);
    // carry[k]: state at the start of chunk k not yet accounted for.
    let mut carry: [[[f64; 2]; S]; K] = std::array::from_fn(|k| match k {
        0 => [[0.0; 2]; S],
        _ => std::array::from_fn(|s| st[s].df2t(&c[s], k - 1)),
    });
    // The last chunk also takes the remainder of n / K.
    let mut last: [Lanes<1>; S] = std::array::from_fn(|s| st[s].lane(K - 1));
    for pos in K * len..n {
        let v = &mut x[at(pos, n, rev)];
        *v = cascade::<1, S, F>(c, &mut last, [*v])[0];
    }
    // limit[k]: the size below which the free response in lane k is
    // dropped, from its state at its seam.
    let mut limit = [0.0; K];
    let mut first = true;
    loop {
        let mut free = [Lanes::<K>::default(); S];
        for k in 1..K {
            for s in 0..S {
                free[s].set_df2t(k, carry[k][s]);
            }
            if first {
                limit[k] = SETTLED * lane_size(&free, k);
            }
        }
        first = false;
        isa.add_free::<K, S, F>(c, &mut free, split_lanes::<K>(x, len, rev), &limit, rev);
        let settled = |k: usize| lane_size(&free, k) <= limit[k];
        // The last chunk's free response runs on into the remainder.
        let mut tail: [Lanes<1>; S] = std::array::from_fn(|s| free[s].lane(K - 1));
        let mut pos = K * len;
        while pos < n && !settled_one(&tail, limit[K - 1]) {
            x[at(pos, n, rev)] += cascade::<1, S, F>(c, &mut tail, [0.0])[0];
            pos += 1;
        }
        // Free responses alive at the end of a middle chunk go on into the
        // next one.
        let mut again = false;
        carry = [[[0.0; 2]; S]; K];
        let mut next_limit = [0.0; K];
        for k in 1..K - 1 {
            if !settled(k) {
                again = true;
                for s in 0..S {
                    carry[k + 1][s] = free[s].df2t(&c[s], k);
                }
                next_limit[k + 1] = limit[k];
            }
        }
        if !again {
            return;
        }
        limit = next_limit;
    }
}

fn settled_one<const S: usize>(st: &[Lanes<1>; S], limit: f64) -> bool {
    lane_size(st, 0) <= limit
}

#[cfg(test)]
mod tests;
