//! Streaming accumulators for the overlapping Allan, overlapping Hadamard and modified Allan
//! variances (THEORY.md section 1), updated sample by sample and readable at any moment.
//!
//! # How it works
//!
//! Phase points `x_k` (the running sum of increments) and their running sum `C_k = x_0 + ... +
//! x_{k-1}` (the "double running sum" MVAR needs: its inner sum of `m` second differences is a
//! third difference of `C`) enter a *stream* at stride 1. Every cluster size `m` (a *level*)
//! reads a stream of stride `s`: `s = 1` in exact mode, and in bounded mode the largest divisor
//! of `m` not above `max(1, m/L)`, so each level sees at least `L` stream points per cluster
//! (THEORY.md section 1, "Streaming with bounded memory"). Streams of larger strides are
//! decimations of smaller ones. Each stream keeps only the points its levels still need (about
//! `4L` of them in bounded mode), so memory does not grow with the run; in exact mode stream 1
//! keeps everything and every level uses every difference.
//!
//! New points are processed in blocks (the stream's unprocessed tail), so the inner loops run
//! over contiguous slices. Reading a curve first processes the tail.
//!
//! # Precision
//!
//! Integer counts ([`IntRepr`]): phase in `i64`, `C` in `i128`, both with wrapping arithmetic, so
//! every difference is exact (a difference is exact modulo 2^64 or 2^128 and its true value is far
//! smaller). The phase of a 24-hour 1 kHz run of `i32` increments stays below `8.64e7 * 2^31 <
//! 2^63`; third differences of `C` at `m <= 2^30` stay below `2^95`. Floating input
//! ([`FloatRepr`]): phase and `C` are double-double numbers (about 106 bits), and differences are
//! taken as nested first differences of the high and low parts, so cancellation happens between
//! nearly equal doubles, which is exact (Sterbenz). Sums of squares use four partial sums per
//! block and a compensated sum across blocks.
//!
//! # Gaps
//!
//! A gap (lost frames, an empty or NaN row) ends the phase segment: the phase after it is known
//! only up to a constant, so no difference spans it (THEORY.md section 1, "Gaps"). Sums and counts
//! carry on; the streams restart.

use super::batch::CompensatedSum;
use super::Stat;

/// Which statistics to accumulate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct StatSet {
    pub avar: bool,
    pub hvar: bool,
    pub mvar: bool,
}

impl StatSet {
    pub const ALL: StatSet = StatSet {
        avar: true,
        hvar: true,
        mvar: true,
    };

    pub fn contains(self, stat: Stat) -> bool {
        match stat {
            Stat::Avar => self.avar,
            Stat::Hvar => self.hvar,
            Stat::Mvar => self.mvar,
        }
    }

    pub fn only(stat: Stat) -> StatSet {
        StatSet {
            avar: stat == Stat::Avar,
            hvar: stat == Stat::Hvar,
            mvar: stat == Stat::Mvar,
        }
    }
}

/// Overlap of the estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Overlap {
    /// The exact overlapping estimate: every difference, memory grows with the run.
    Full,
    /// Bounded memory: differences at stride `max(1, m/L)` (`L >= 1`).
    Bounded(u64),
}

/// The default `L` of bounded mode.
///
/// Chosen from Greenhall's edf of the decimated estimator against full overlap
/// (`cargo run --release --example choose_l`, table in BENCHMARKS.md, "Choosing L"): for a
/// 3-hour 250 Hz run, at `L = 16` AVAR and HVAR keep at least 99.4% of the full overlap's degrees
/// of freedom at every m for white, flicker and random-walk rate noise (the N, B and K terms, which
/// dominate beyond the shortest taus), and MVAR keeps 99.4% for every noise type. White and
/// flicker phase noise on AVAR and HVAR lose edf in proportion to L/m once m > L (their
/// neighbouring differences are nearly independent, so skipping them costs); quantization
/// dominates only at the shortest taus, where the stride is 1. L = 8 keeps 98%, L = 32 99.9%
/// at twice the memory. Memory per channel stays a few hundred KB.
pub const DEFAULT_L: u64 = 16;

/// Which cluster sizes `m` to compute.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TauSpec {
    /// `m = 1, 2, 4, 8, ...`
    Octave,
    /// `m = 1, 2, 4, 10, 20, 40, 100, ...` (Stable32's decade spacing)
    Decade,
    /// An explicit list of cluster sizes.
    List(Vec<u64>),
}

/// Largest cluster size considered by the open-ended tau specs: 2^40 samples is 35 years at 1 kHz.
const MAX_M: u64 = 1 << 40;

impl TauSpec {
    /// The cluster sizes, ascending and without duplicates.
    pub fn cluster_sizes(&self) -> Vec<u64> {
        let mut ms: Vec<u64> = match self {
            TauSpec::Octave => (0..=40).map(|j| 1u64 << j).collect(),
            TauSpec::Decade => {
                let mut v = Vec::new();
                let mut decade = 1u64;
                while decade <= MAX_M {
                    for f in [1, 2, 4] {
                        v.push(f * decade);
                    }
                    decade *= 10;
                }
                v
            }
            TauSpec::List(list) => list.iter().copied().filter(|&m| m >= 1).collect(),
        };
        ms.sort_unstable();
        ms.dedup();
        ms
    }
}

/// Settings of one channel's accumulator.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AccumConfig {
    /// Sampling step in seconds.
    pub tau0_s: f64,
    pub stats: StatSet,
    pub overlap: Overlap,
    pub taus: TauSpec,
    /// Also accumulate the lag-1 autocorrelations used to identify the noise type per tau.
    pub noise_id: bool,
}

impl AccumConfig {
    /// Each setting that differs from `other`'s, as `name: this vs other` (empty when equal),
    /// in the words of the command line.
    pub fn differences(&self, other: &AccumConfig) -> Vec<String> {
        let mut out = Vec::new();
        if self.tau0_s.to_bits() != other.tau0_s.to_bits() {
            out.push(format!("tau0: {:?} s vs {:?} s", self.tau0_s, other.tau0_s));
        }
        if self.stats != other.stats {
            let names = |s: StatSet| {
                [("avar", s.avar), ("hvar", s.hvar), ("mvar", s.mvar)]
                    .iter()
                    .filter(|x| x.1)
                    .map(|x| x.0)
                    .collect::<Vec<_>>()
                    .join(",")
            };
            out.push(format!(
                "--stats: {} vs {}",
                names(self.stats),
                names(other.stats)
            ));
        }
        if self.overlap != other.overlap {
            let show = |o: Overlap| match o {
                Overlap::Full => "full".to_string(),
                Overlap::Bounded(l) => l.to_string(),
            };
            out.push(format!(
                "--overlap: {} vs {}",
                show(self.overlap),
                show(other.overlap)
            ));
        }
        if self.taus != other.taus {
            let show = |t: &TauSpec| match t {
                TauSpec::Octave => "octave".to_string(),
                TauSpec::Decade => "decade".to_string(),
                TauSpec::List(v) => v.iter().map(u64::to_string).collect::<Vec<_>>().join(","),
            };
            out.push(format!(
                "--taus: {} vs {}",
                show(&self.taus),
                show(&other.taus)
            ));
        }
        if self.noise_id != other.noise_id {
            out.push(format!(
                "noise identification: {} vs {}",
                self.noise_id, other.noise_id
            ));
        }
        out
    }

    pub fn new(tau0_s: f64) -> AccumConfig {
        AccumConfig {
            tau0_s,
            stats: StatSet::ALL,
            overlap: Overlap::Bounded(DEFAULT_L),
            taus: TauSpec::Octave,
            noise_id: true,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Number representations

/// A double-double number `hi + lo`, `|lo| <= ulp(hi)/2`.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Dd {
    pub hi: f64,
    pub lo: f64,
}

impl Dd {
    /// `self + v`, with the rounding error of the sum carried in `lo` (Knuth's two-sum).
    #[inline(always)]
    fn add_f64(self, v: f64) -> Dd {
        let s = self.hi + v;
        let bb = s - self.hi;
        let err = (self.hi - (s - bb)) + (v - bb);
        Dd::renorm(s, err + self.lo)
    }

    #[inline(always)]
    fn add_dd(self, o: Dd) -> Dd {
        let s = self.hi + o.hi;
        let bb = s - self.hi;
        let err = (self.hi - (s - bb)) + (o.hi - bb);
        Dd::renorm(s, err + self.lo + o.lo)
    }

    #[inline(always)]
    fn renorm(s: f64, e: f64) -> Dd {
        let hi = s + e;
        Dd {
            hi,
            lo: e - (hi - s),
        }
    }

    pub fn value(self) -> f64 {
        self.hi + self.lo
    }
}

/// How phase and its running sum are represented for one kind of input.
pub trait Repr: 'static {
    /// One increment as it arrives.
    type Inc: Copy + std::fmt::Debug + serde::Serialize + serde::de::DeserializeOwned;
    /// A phase point.
    type X: Copy + Default + std::fmt::Debug + serde::Serialize + serde::de::DeserializeOwned;
    /// A point of the running sum of phase.
    type C: Copy + Default + std::fmt::Debug + serde::Serialize + serde::de::DeserializeOwned;
    fn zero_x() -> Self::X {
        Self::X::default()
    }
    fn step(x: Self::X, d: Self::Inc) -> Self::X;
    fn accumulate(c: Self::C, x: Self::X) -> Self::C;
    /// `a - b`
    fn d1(a: Self::X, b: Self::X) -> f64;
    /// `a - 2b + c`
    fn d2(a: Self::X, b: Self::X, c: Self::X) -> f64;
    /// `a - 3b + 3c - d`
    fn d3(a: Self::X, b: Self::X, c: Self::X, d: Self::X) -> f64;
    /// `a - 3b + 3c - d` on the running sum.
    fn c3(a: Self::C, b: Self::C, c: Self::C, d: Self::C) -> f64;
    /// The same, where the caller has proved the result fits a narrower type (see
    /// [`Engine`]'s `spread`); the default is [`Repr::c3`].
    #[inline(always)]
    fn c3_narrow(a: Self::C, b: Self::C, c: Self::C, d: Self::C) -> f64 {
        Self::c3(a, b, c, d)
    }
    /// `a - 2b + c` where the caller has proved `|result| < 2^51`; the default is [`Repr::d2`].
    #[inline(always)]
    fn d2_narrow(a: Self::X, b: Self::X, c: Self::X) -> f64 {
        Self::d2(a, b, c)
    }
    /// `a - 3b + 3c - d` where the caller has proved `|result| < 2^51`.
    #[inline(always)]
    fn d3_narrow(a: Self::X, b: Self::X, c: Self::X, d: Self::X) -> f64 {
        Self::d3(a, b, c, d)
    }
    /// A whole number of counts `v` with `v + 1 >= |d - reference|`, whose bitwise OR over many
    /// increments is again such a bound for each (so it is kept with `|=`, which vectorizes);
    /// 0 where not needed (floats).
    fn deviation(_d: Self::Inc, _reference: Self::Inc) -> u64 {
        0
    }
    /// The phase points as wrapping 64-bit integers, for the integer kernels
    /// ([`second_differences`], the moving-sum MVAR); `None` for representations without them.
    #[inline(always)]
    fn as_i64(_x: &[Self::X]) -> Option<&[i64]> {
        None
    }
}

/// Integer counts, summed exactly.
#[derive(Debug, Clone)]
pub struct IntRepr;

impl Repr for IntRepr {
    type Inc = i64;
    type X = i64;
    type C = i128;
    #[inline(always)]
    fn step(x: i64, d: i64) -> i64 {
        x.wrapping_add(d)
    }
    #[inline(always)]
    fn accumulate(c: i128, x: i64) -> i128 {
        c.wrapping_add(x as i128)
    }
    #[inline(always)]
    fn d1(a: i64, b: i64) -> f64 {
        a.wrapping_sub(b) as f64
    }
    #[inline(always)]
    fn d2(a: i64, b: i64, c: i64) -> f64 {
        a.wrapping_sub(b).wrapping_sub(b.wrapping_sub(c)) as f64
    }
    #[inline(always)]
    fn d3(a: i64, b: i64, c: i64, d: i64) -> f64 {
        third_difference(a, b, c, d) as f64
    }
    #[inline(always)]
    fn c3(a: i128, b: i128, c: i128, d: i128) -> f64 {
        let ab = a.wrapping_sub(b);
        let bc = b.wrapping_sub(c);
        let cd = c.wrapping_sub(d);
        let v = ab.wrapping_sub(bc).wrapping_sub(bc.wrapping_sub(cd));
        // i128 -> f64 is a library call; nearly every value fits in i64, whose conversion is
        // one instruction (and exact in the same cases).
        let low = v as i64;
        if low as i128 == v {
            low as f64
        } else {
            v as f64
        }
    }
    /// On the low 64 bits: exact modulo 2^64, so exact whenever the true value fits (the
    /// caller proves `|result| < 2^51`).
    #[inline(always)]
    fn c3_narrow(a: i128, b: i128, c: i128, d: i128) -> f64 {
        small_i64_to_f64(third_difference(a as i64, b as i64, c as i64, d as i64))
    }
    #[inline(always)]
    fn deviation(d: i64, reference: i64) -> u64 {
        // One's-complement magnitude of d - reference (|t| - 1 for negative t), or all ones when
        // the wrapping difference overflowed (operands of opposite signs, result sign flipped).
        let t = d.wrapping_sub(reference);
        let overflow = ((d ^ reference) & (d ^ t)) >> 63;
        ((t ^ (t >> 63)) | overflow) as u64
    }
    #[inline(always)]
    fn d2_narrow(a: i64, b: i64, c: i64) -> f64 {
        small_i64_to_f64(a.wrapping_sub(b).wrapping_sub(b.wrapping_sub(c)))
    }
    #[inline(always)]
    fn d3_narrow(a: i64, b: i64, c: i64, d: i64) -> f64 {
        small_i64_to_f64(third_difference(a, b, c, d))
    }
    #[inline(always)]
    fn as_i64(x: &[i64]) -> Option<&[i64]> {
        Some(x)
    }
}

/// `a - 3b + 3c - d` as nested first differences in wrapping i64 arithmetic: exact modulo
/// 2^64, so exact whenever the true value fits in i64.
#[inline(always)]
fn third_difference(a: i64, b: i64, c: i64, d: i64) -> i64 {
    let ab = a.wrapping_sub(b);
    let bc = b.wrapping_sub(c);
    let cd = c.wrapping_sub(d);
    ab.wrapping_sub(bc).wrapping_sub(bc.wrapping_sub(cd))
}

/// `v as f64` for `|v| < 2^51`, exactly, by the 1.5 * 2^52 bias trick: an integer add and a
/// float subtract, both of which run on vector lanes (AVX2 has no i64 -> f64 conversion).
#[inline(always)]
fn small_i64_to_f64(v: i64) -> f64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0; // 1.5 * 2^52
    f64::from_bits(v.wrapping_add(MAGIC.to_bits() as i64) as u64) - MAGIC
}

/// Floating-point increments or phase, carried in double-double.
#[derive(Debug, Clone)]
pub struct FloatRepr;

/// Nested differences of double-double numbers: the high parts are subtracted first, pairwise
/// between neighbours (exact when they are close), then the low parts.
#[inline(always)]
fn dd_d2(a: Dd, b: Dd, c: Dd) -> f64 {
    let hi = (a.hi - b.hi) - (b.hi - c.hi);
    let lo = (a.lo - b.lo) - (b.lo - c.lo);
    hi + lo
}

#[inline(always)]
fn dd_d3(a: Dd, b: Dd, c: Dd, d: Dd) -> f64 {
    let (ab, bc, cd) = (a.hi - b.hi, b.hi - c.hi, c.hi - d.hi);
    let hi = (ab - bc) - (bc - cd);
    let (abl, bcl, cdl) = (a.lo - b.lo, b.lo - c.lo, c.lo - d.lo);
    let lo = (abl - bcl) - (bcl - cdl);
    hi + lo
}

impl Repr for FloatRepr {
    type Inc = f64;
    type X = Dd;
    type C = Dd;
    #[inline(always)]
    fn step(x: Dd, d: f64) -> Dd {
        x.add_f64(d)
    }
    #[inline(always)]
    fn accumulate(c: Dd, x: Dd) -> Dd {
        c.add_dd(x)
    }
    #[inline(always)]
    fn d1(a: Dd, b: Dd) -> f64 {
        (a.hi - b.hi) + (a.lo - b.lo)
    }
    #[inline(always)]
    fn d2(a: Dd, b: Dd, c: Dd) -> f64 {
        dd_d2(a, b, c)
    }
    #[inline(always)]
    fn d3(a: Dd, b: Dd, c: Dd, d: Dd) -> f64 {
        dd_d3(a, b, c, d)
    }
    #[inline(always)]
    fn c3(a: Dd, b: Dd, c: Dd, d: Dd) -> f64 {
        dd_d3(a, b, c, d)
    }
}

// ---------------------------------------------------------------------------------------------
// Streams and levels

/// Points of one stream since the start of the segment, of which the first `base` were dropped.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Buf<T> {
    data: Vec<T>,
    /// Segment-relative stream index of `data[0]`.
    base: u64,
    /// Index into `data` where this block's new points begin (for decimating children).
    new_from: usize,
}

impl<T: Copy> Buf<T> {
    fn new() -> Self {
        Buf {
            data: Vec::new(),
            base: 0,
            new_from: 0,
        }
    }
    fn end(&self) -> u64 {
        self.base + self.data.len() as u64
    }
    fn clear(&mut self) {
        self.data.clear();
        self.base = 0;
        self.new_from = 0;
    }
    /// Drops points before segment index `keep_from`.
    fn trim(&mut self, keep_from: u64) {
        if keep_from > self.base {
            let n = ((keep_from - self.base) as usize).min(self.data.len());
            self.data.drain(..n);
            self.base += n as u64;
        }
        self.new_from = self.data.len();
    }
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
struct Stream<R: Repr> {
    stride: u64,
    /// Index of the stream this one decimates (itself for stride 1).
    parent: usize,
    /// `stride / parent.stride`.
    factor: u64,
    x: Buf<R::X>,
    c: Buf<R::C>,
    /// Whether any level reads the `C` points.
    needs_c: bool,
}

/// Sum of squared differences of one statistic at one level.
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
struct SqSum {
    sum: CompensatedSum,
    count: u64,
    /// Segment-relative stream index of the next difference to take.
    next: u64,
}

impl SqSum {
    /// Adds the sum of `n` squared differences just taken.
    fn add(&mut self, n: usize, sum_sq: f64) {
        self.sum.add(sum_sq);
        self.count += n as u64;
        self.next += n as u64;
    }
}

/// Moments for the lag-1 autocorrelation of one differenced series (noise identification).
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
struct LagMoments {
    /// The first value seen, subtracted from every value so the moments do not cancel.
    shift: Option<f64>,
    n: u64,
    sum: f64,
    sum_sq: f64,
    sum_lag: f64,
}

impl LagMoments {
    #[inline(always)]
    fn add(&mut self, a: f64, b: f64) {
        let s = *self.shift.get_or_insert(a);
        let (a, b) = (a - s, b - s);
        self.n += 1;
        self.sum += a + b;
        self.sum_sq += a * a + b * b;
        self.sum_lag += a * b;
    }

    /// Lag-1 autocorrelation of the series, its mean removed.
    fn r1(&self) -> Option<f64> {
        if self.n < 2 {
            return None;
        }
        let n = self.n as f64;
        let mean = self.sum / (2.0 * n);
        let var = self.sum_sq / (2.0 * n) - mean * mean;
        let cov = self.sum_lag / n - mean * mean;
        (var > 0.0).then(|| (cov / var).clamp(-1.0, 1.0))
    }
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Level {
    m: u64,
    stream: usize,
    /// Cluster size in stream points: `m / stride`.
    mp: u64,
    avar: SqSum,
    hvar: SqSum,
    mvar: SqSum,
    /// Next term of the noise-identification moments (a multiple of `mp`; span `4 mp`).
    nid_next: u64,
    lag: [LagMoments; 3],
}

/// What a level holds at the moment it is read.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelReading {
    /// Cluster size.
    pub m: u64,
    /// Samples between successive differences (1 = full overlap).
    pub stride: u64,
    /// Averaging time in seconds.
    pub tau_s: f64,
    /// `(variance in u^2/s^2, number of differences)` per statistic, `None` when no difference
    /// has been taken yet or the statistic is off.
    pub avar: Option<(f64, u64)>,
    pub hvar: Option<(f64, u64)>,
    pub mvar: Option<(f64, u64)>,
    /// Lag-1 autocorrelations (lag `m`) of the `m`-averaged rate and of its first and second
    /// differences, for noise identification.
    pub lag1: [Option<f64>; 3],
}

impl LevelReading {
    pub fn get(&self, stat: Stat) -> Option<(f64, u64)> {
        match stat {
            Stat::Avar => self.avar,
            Stat::Hvar => self.hvar,
            Stat::Mvar => self.mvar,
        }
    }
}

/// Smallest step between the starts of noise-identification block pairs: at m = 1 a 3-hour
/// 250 Hz run still gives 42 000 pairs (standard error of the lag-1 autocorrelation about 0.005,
/// against decision steps of 0.25 in Riley and Greenhall's delta), and a 5-minute run 1 200.
/// 64 rather than 16 took 11% off the stand benchmark (BENCHMARKS.md, "Allan engine").
const NID_MIN_STEP: u64 = 64;

/// Points of stream 1 gathered before the levels are updated: large enough that the inner loops
/// run over long slices, small enough to stay in L1 cache with its history.
const BLOCK: usize = 2048;

/// The streaming accumulator of one channel, generic over the number representation.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub struct Engine<R: Repr> {
    cfg: AccumConfig,
    streams: Vec<Stream<R>>,
    levels: Vec<Level>,
    /// Is a phase segment open (false at the start and after a gap)?
    open: bool,
    x_cur: R::X,
    c_cur: R::C,
    /// Phase points received in all segments.
    n_points: u64,
    /// Increments accounted for, gaps included (for `t_data`).
    n_steps: u64,
    /// Number of segments started.
    segments: u64,
    /// The first increment, and the OR of [`Repr::deviation`] over the increments since, so that
    /// `spread + 1 >= |d - first|` for each of them: MVAR's inner sum at
    /// cluster m is at most `2 m^2 (spread + 1)` in magnitude (each of its m second differences is a
    /// difference of two sums of m increments, and a constant offset cancels), which decides
    /// when its third difference of the running sum fits in 64 bits.
    first_inc: Option<R::Inc>,
    spread: u64,
    /// Scratch for the moving sums of phase at m = 2, 4, 8, ... (integer input); rebuilt at
    /// every block, so a saved state leaves it out.
    #[serde(skip)]
    pyramid: Vec<Vec<i64>>,
    /// Scratch for one level's second differences (integer input).
    #[serde(skip)]
    scratch: Vec<f64>,
}

impl<R: Repr> Engine<R> {
    pub fn new(cfg: AccumConfig) -> Engine<R> {
        let ms = cfg.taus.cluster_sizes();
        let mut strides: Vec<u64> = vec![1];
        let mut level_strides = Vec::with_capacity(ms.len());
        for &m in &ms {
            let s = match cfg.overlap {
                Overlap::Full => 1,
                Overlap::Bounded(l) => largest_divisor_at_most(m, (m / l.max(1)).max(1)),
            };
            level_strides.push(s);
            if !strides.contains(&s) {
                strides.push(s);
            }
        }
        strides.sort_unstable();
        let mut streams: Vec<Stream<R>> = Vec::with_capacity(strides.len());
        for (i, &s) in strides.iter().enumerate() {
            // Parent: the largest smaller stride that divides this one.
            let parent = (0..i).rev().find(|&j| s % strides[j] == 0).unwrap_or(0);
            streams.push(Stream {
                stride: s,
                parent,
                factor: if i == 0 { 1 } else { s / strides[parent] },
                x: Buf::new(),
                c: Buf::new(),
                needs_c: false,
            });
        }
        let levels: Vec<Level> = ms
            .iter()
            .zip(&level_strides)
            .map(|(&m, &s)| {
                let stream = strides.iter().position(|&t| t == s).unwrap_or(0);
                Level {
                    m,
                    stream,
                    mp: m / s,
                    avar: SqSum::default(),
                    hvar: SqSum::default(),
                    mvar: SqSum::default(),
                    nid_next: 0,
                    lag: [LagMoments::default(); 3],
                }
            })
            .collect();
        if cfg.stats.mvar {
            // A stream carries C points if it, or any stream decimated from it, feeds an MVAR level.
            for lv in &levels {
                let mut s = lv.stream;
                loop {
                    streams[s].needs_c = true;
                    if s == 0 {
                        break;
                    }
                    s = streams[s].parent;
                }
            }
        }
        Engine {
            cfg,
            streams,
            levels,
            open: false,
            x_cur: R::zero_x(),
            c_cur: R::C::default(),
            n_points: 0,
            n_steps: 0,
            segments: 0,
            first_inc: None,
            spread: 0,
            pyramid: Vec::new(),
            scratch: Vec::new(),
        }
    }

    pub fn config(&self) -> &AccumConfig {
        &self.cfg
    }

    /// Phase points received so far, all segments together.
    pub fn phase_points(&self) -> u64 {
        self.n_points
    }

    /// Seconds of data accounted for, gaps included.
    pub fn t_data_s(&self) -> f64 {
        self.n_steps as f64 * self.cfg.tau0_s
    }

    /// Number of contiguous segments so far.
    pub fn segments(&self) -> u64 {
        self.segments
    }

    /// Feeds one increment `d_k` (THEORY.md section 1).
    #[inline]
    pub fn push_increment(&mut self, d: R::Inc) {
        if !self.open {
            self.start_segment(R::zero_x());
        }
        match self.first_inc {
            Some(r) => self.spread |= R::deviation(d, r),
            None => self.first_inc = Some(d),
        }
        let x = R::step(self.x_cur, d);
        self.append_point(x);
        self.n_steps += 1;
    }

    /// Feeds a run of increments, as [`Engine::push_increment`] on each in turn (the same
    /// result), with the per-sample bookkeeping done a block at a time.
    pub fn push_increments(&mut self, ds: &[R::Inc]) {
        let mut rest = ds;
        while let Some((&d0, tail)) = rest.split_first() {
            if !self.open || self.first_inc.is_none() {
                self.push_increment(d0);
                rest = tail;
                continue;
            }
            let s0 = &mut self.streams[0];
            let room = BLOCK.saturating_sub(s0.x.data.len() - s0.x.new_from).max(1);
            let (chunk, tail) = rest.split_at(room.min(rest.len()));
            if let Some(r) = self.first_inc {
                self.spread |= chunk.iter().fold(0, |acc, &d| acc | R::deviation(d, r));
            }
            let from = s0.x.data.len();
            let mut x = self.x_cur;
            s0.x.data.extend(chunk.iter().map(|&d| {
                x = R::step(x, d);
                x
            }));
            self.x_cur = x;
            if s0.needs_c {
                let mut c = self.c_cur;
                s0.c.data.extend(s0.x.data[from..].iter().map(|&x| {
                    c = R::accumulate(c, x);
                    c
                }));
                self.c_cur = c;
            }
            self.n_points += chunk.len() as u64;
            self.n_steps += chunk.len() as u64;
            if s0.x.data.len() - s0.x.new_from >= BLOCK {
                self.process();
            }
            rest = tail;
        }
    }

    /// Feeds `missing` lost increments: the segment ends here.
    pub fn push_gap(&mut self, missing: u64) {
        if missing == 0 {
            return;
        }
        self.close_segment();
        self.n_steps += missing;
    }

    /// Ends the current phase segment without accounting for time (a phase point was missing).
    pub fn break_segment(&mut self) {
        self.close_segment();
    }

    /// Feeds one phase point directly (phase input).
    pub fn push_phase(&mut self, x: R::X) {
        if !self.open {
            self.start_segment(x);
        } else {
            self.append_point(x);
            self.n_steps += 1;
        }
    }

    fn start_segment(&mut self, x0: R::X) {
        for s in &mut self.streams {
            s.x.clear();
            s.c.clear();
        }
        for lv in &mut self.levels {
            lv.avar.next = 0;
            lv.hvar.next = 0;
            lv.mvar.next = 0;
            lv.nid_next = 0;
        }
        self.open = true;
        self.segments += 1;
        self.x_cur = x0;
        self.c_cur = R::C::default();
        // C_0 = 0 and C_1 = x_0: the running sum is one point ahead of the phase, so that with
        // P phase points the C stream holds C_0..C_P and MVAR has P - 3m + 1 terms.
        let s0 = &mut self.streams[0];
        s0.x.data.push(x0);
        if s0.needs_c {
            s0.c.data.push(self.c_cur);
            self.c_cur = R::accumulate(self.c_cur, x0);
            s0.c.data.push(self.c_cur);
        }
        self.n_points += 1;
    }

    #[inline(always)]
    fn append_point(&mut self, x: R::X) {
        let s0 = &mut self.streams[0];
        if s0.needs_c {
            self.c_cur = R::accumulate(self.c_cur, x);
            s0.c.data.push(self.c_cur);
        }
        s0.x.data.push(x);
        self.x_cur = x;
        self.n_points += 1;
        if s0.x.data.len() - s0.x.new_from >= BLOCK {
            self.process();
        }
    }

    fn close_segment(&mut self) {
        if self.open {
            self.process();
            self.open = false;
        }
    }

    /// Decimates the new points down the streams, updates every level, trims the streams.
    fn process(&mut self) {
        // Decimation, parents before children (streams are sorted by stride).
        for i in 1..self.streams.len() {
            let (head, tail) = self.streams.split_at_mut(i);
            let child = &mut tail[0];
            let parent = &head[child.parent];
            decimate(&parent.x, &mut child.x, child.factor);
            if child.needs_c {
                decimate(&parent.c, &mut child.c, child.factor);
            }
        }
        let stats = self.cfg.stats;
        let nid = self.cfg.noise_id;
        let spread = self.spread;
        // Bounds from the spread (see `spread`), with s = spread + 1: |second difference| <= 2 m s,
        // |third difference| <= 4 m s, |MVAR inner sum| <= 2 m^2 s.
        let bounds: Vec<Narrow> = self
            .levels
            .iter()
            .map(|lv| {
                let m = lv.m as u128;
                let s = spread as u128 + 1;
                Narrow {
                    d2: (2 * m).saturating_mul(s) < (1 << 51),
                    d3: (4 * m).saturating_mul(s) < (1 << 51),
                    c3: m.saturating_mul(m).saturating_mul(2 * s) < (1 << 51),
                }
            })
            .collect();
        // MVAR of stream 0's levels at m = 2^k (integer phase, narrow bound) from the moving
        // sums of phase, built by doubling: A_2m(j) = A_m(j) + A_m(j + m), A_1 = x.
        let uses_sums =
            |lv: &Level, b: &Narrow| stats.mvar && lv.stream == 0 && lv.m.is_power_of_two() && b.c3;
        let mut pyramid = std::mem::take(&mut self.pyramid);
        let s0 = &self.streams[0].x;
        let mut lo = s0.end();
        let mut top = 0;
        if let Some(xi) = R::as_i64(&s0.data) {
            for (lv, b) in self.levels.iter().zip(&bounds) {
                if uses_sums(lv, b) {
                    lo = lo.min(lv.mvar.next);
                    top = top.max(lv.m.trailing_zeros() as usize);
                }
            }
            pyramid.resize_with(top, Vec::new);
            for k in 0..top {
                let (done, rest) = pyramid.split_at_mut(k);
                let prev: &[i64] = if k == 0 {
                    &xi[(lo - s0.base) as usize..]
                } else {
                    &done[k - 1]
                };
                let half = 1usize << k;
                let next = &mut rest[0];
                next.clear();
                if prev.len() > half {
                    let len = prev.len() - half;
                    next.extend(
                        prev[..len]
                            .iter()
                            .zip(&prev[half..])
                            .map(|(a, b)| a.wrapping_add(*b)),
                    );
                }
            }
        }
        for (lv, b) in self.levels.iter_mut().zip(&bounds) {
            let st = &self.streams[lv.stream];
            let sums = if uses_sums(lv, b) {
                match (lv.m.trailing_zeros() as usize, R::as_i64(&st.x.data)) {
                    (0, Some(xi)) => Some((xi, st.x.base)),
                    (k, Some(_)) => Some((&pyramid[k - 1][..], lo)),
                    _ => None,
                }
            } else {
                None
            };
            update_level::<R>(lv, st, stats, nid, *b, sums, &mut self.scratch);
        }
        self.pyramid = pyramid;
        // Trim: each stream keeps what its levels still need.
        let mut keep: Vec<u64> = self.streams.iter().map(|s| s.x.end()).collect();
        let mut keep_c: Vec<u64> = self.streams.iter().map(|s| s.c.end()).collect();
        for lv in &self.levels {
            let k = &mut keep[lv.stream];
            if stats.avar {
                *k = (*k).min(lv.avar.next);
            }
            if stats.hvar {
                *k = (*k).min(lv.hvar.next);
            }
            if nid {
                *k = (*k).min(lv.nid_next);
            }
            if stats.mvar {
                keep_c[lv.stream] = keep_c[lv.stream].min(lv.mvar.next);
                if lv.stream == 0 {
                    // The moving sums read phase from MVAR's next term on.
                    *k = (*k).min(lv.mvar.next);
                }
            }
        }
        for (i, s) in self.streams.iter_mut().enumerate() {
            // A child decimates only new points, so nothing is kept for children.
            s.x.trim(keep[i]);
            s.c.trim(keep_c[i]);
        }
    }

    /// Processes pending points and reads every level.
    pub fn read(&mut self) -> Vec<LevelReading> {
        if self.open {
            self.process();
        }
        let tau0 = self.cfg.tau0_s;
        let stats = self.cfg.stats;
        self.levels
            .iter()
            .map(|lv| {
                let tau = lv.m as f64 * tau0;
                let stride = self.streams[lv.stream].stride;
                let fin = |q: &SqSum, on: bool, denom: f64| {
                    (on && q.count > 0).then(|| (q.sum.value() / (denom * q.count as f64), q.count))
                };
                let mf = lv.m as f64;
                LevelReading {
                    m: lv.m,
                    stride,
                    tau_s: tau,
                    // THEORY.md section 1: AVAR divides by 2 tau^2, HVAR by 6 tau^2, MVAR by 2 m^2 tau^2.
                    avar: fin(&lv.avar, stats.avar, 2.0 * tau * tau),
                    hvar: fin(&lv.hvar, stats.hvar, 6.0 * tau * tau),
                    mvar: fin(&lv.mvar, stats.mvar, 2.0 * mf * mf * tau * tau),
                    lag1: [lv.lag[0].r1(), lv.lag[1].r1(), lv.lag[2].r1()],
                }
            })
            .filter(|r| r.avar.is_some() || r.hvar.is_some() || r.mvar.is_some())
            .collect()
    }

    /// Checks a state read back from a checkpoint: the streams and levels must be the ones its
    /// configuration builds, and every index must point into what the streams hold, so that a
    /// damaged or forged state is refused rather than read out of bounds. The numbers in the
    /// sums are not checked (any value is a possible sum).
    pub fn check_restored(&self) -> Result<(), String> {
        let fresh = Engine::<R>::new(self.cfg.clone());
        if self.streams.len() != fresh.streams.len() || self.levels.len() != fresh.levels.len() {
            return Err(format!(
                "{} streams and {} levels, where its settings give {} and {}",
                self.streams.len(),
                self.levels.len(),
                fresh.streams.len(),
                fresh.levels.len()
            ));
        }
        // Indices stay far below u64::MAX, so the sums of index and span cannot overflow.
        const MAX_INDEX: u64 = 1 << 62;
        for (i, (s, f)) in self.streams.iter().zip(&fresh.streams).enumerate() {
            if (s.stride, s.parent, s.factor, s.needs_c)
                != (f.stride, f.parent, f.factor, f.needs_c)
            {
                return Err(format!("stream {i} is not the one its settings build"));
            }
            for (name, base, len, new_from) in [
                ("x", s.x.base, s.x.data.len(), s.x.new_from),
                ("c", s.c.base, s.c.data.len(), s.c.new_from),
            ] {
                if new_from > len || base > MAX_INDEX || len as u64 > MAX_INDEX {
                    return Err(format!(
                        "stream {i} ({name}): new points from {new_from} of {len} held, base {base}"
                    ));
                }
            }
            if !s.needs_c && !s.c.data.is_empty() {
                return Err(format!("stream {i} holds running sums it does not use"));
            }
        }
        for (lv, f) in self.levels.iter().zip(&fresh.levels) {
            if (lv.m, lv.stream, lv.mp) != (f.m, f.stream, f.mp) {
                return Err(format!(
                    "the level of m = {} is not the one its settings build",
                    lv.m
                ));
            }
            let st = &self.streams[lv.stream];
            let within = |next: u64, b: &Buf<R::X>| next >= b.base && next <= b.end() + 4 * lv.mp;
            let within_c = |next: u64, b: &Buf<R::C>| next >= b.base && next <= b.end() + 4 * lv.mp;
            let stats = self.cfg.stats;
            let bad = (stats.avar && !within(lv.avar.next, &st.x))
                || (stats.hvar && !within(lv.hvar.next, &st.x))
                || (self.cfg.noise_id && !within(lv.nid_next, &st.x))
                || (stats.mvar && !within_c(lv.mvar.next, &st.c))
                || (stats.mvar && lv.stream == 0 && !within(lv.mvar.next, &st.x));
            if bad {
                return Err(format!(
                    "the level of m = {} points outside the data it holds",
                    lv.m
                ));
            }
        }
        if self.n_points > self.n_steps.saturating_add(self.segments) || self.n_steps > MAX_INDEX {
            return Err(format!(
                "{} points in {} steps and {} segments",
                self.n_points, self.n_steps, self.segments
            ));
        }
        Ok(())
    }

    /// Bytes held by the streams (the part of memory that could grow with the run).
    pub fn stream_bytes(&self) -> usize {
        self.streams
            .iter()
            .map(|s| {
                s.x.data.capacity() * std::mem::size_of::<R::X>()
                    + s.c.data.capacity() * std::mem::size_of::<R::C>()
            })
            .sum()
    }
}

impl Engine<FloatRepr> {
    /// Feeds one phase value in u (phase input); a non-finite value ends the segment.
    pub fn push_phase_f64(&mut self, x: f64) {
        if x.is_finite() {
            self.push_phase(Dd { hi: x, lo: 0.0 });
        } else {
            self.break_segment();
        }
    }
}

/// The largest divisor of `m` not above `cap` (`cap >= 1`): the stride of a level in bounded mode.
fn largest_divisor_at_most(m: u64, cap: u64) -> u64 {
    if cap >= m {
        return m;
    }
    // m / d is a divisor <= cap for every divisor d >= m / cap; the smallest such d gives the
    // largest one. Divisors come in pairs around sqrt(m), so search each side up to sqrt(m).
    let mut d = m.div_ceil(cap);
    while d.saturating_mul(d) <= m {
        if m.is_multiple_of(d) {
            return m / d;
        }
        d += 1;
    }
    let mut e = cap.min(m.isqrt());
    while e > 1 {
        if m.is_multiple_of(e) {
            return e;
        }
        e -= 1;
    }
    1
}

/// Appends to `child` every `factor`-th point of `parent`'s new points (segment-relative index
/// divisible by `factor`).
fn decimate<T: Copy>(parent: &Buf<T>, child: &mut Buf<T>, factor: u64) {
    let first_new = parent.base + parent.new_from as u64;
    // First index >= first_new that is a multiple of factor.
    let k = first_new.div_ceil(factor) * factor;
    if let Some(from) = parent.data.get((k - parent.base) as usize..) {
        if factor == 2 {
            // The usual case (octave strides); pairs vectorize where `step_by` does not.
            let pairs = from.chunks_exact(2);
            let last = pairs.remainder().first().copied();
            child.data.extend(pairs.map(|p| p[0]));
            child.data.extend(last);
        } else {
            child
                .data
                .extend(from.iter().step_by(factor as usize).copied());
        }
    }
}

/// The differences of span `(K - 1) mp` not yet taken from `buf`, starting at stream index
/// `next`: `K` equal-length slices of the buffer at offsets `0, mp, 2 mp, ...`.
#[inline(always)]
fn lagged<T: Copy, const K: usize>(buf: &Buf<T>, next: u64, mp: u64) -> Option<[&[T]; K]> {
    lagged_in(&buf.data, buf.base, next, mp)
}

/// [`lagged`] on a slice whose first element is stream index `base`.
#[inline(always)]
fn lagged_in<T, const K: usize>(data: &[T], base: u64, next: u64, mp: u64) -> Option<[&[T]; K]> {
    let span = (K as u64 - 1) * mp;
    let end = base + data.len() as u64;
    (end > next + span).then(|| lagged_at(data, base, next, mp, (end - span - next) as usize))
}

/// Sum of `f(a_i, b_i, c_i)^2` over equal-length slices, in [`LANES`] partial sums over
/// `chunks_exact` so the loop has no bounds checks and runs on vector lanes.
#[inline(always)]
fn sum_sq3<T: Copy>(a: &[T], b: &[T], c: &[T], f: impl Fn(T, T, T) -> f64) -> f64 {
    let mut acc = [0.0f64; LANES];
    let (ca, cb, cc) = (
        a.chunks_exact(LANES),
        b.chunks_exact(LANES),
        c.chunks_exact(LANES),
    );
    let mut rest = 0.0;
    for ((x, y), z) in ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .zip(cc.remainder())
    {
        let v = f(*x, *y, *z);
        rest += v * v;
    }
    for ((x, y), z) in ca.zip(cb).zip(cc) {
        for l in 0..LANES {
            let v = f(x[l], y[l], z[l]);
            acc[l] += v * v;
        }
    }
    fold_lanes(acc) + rest
}

/// The same with four slices.
#[inline(always)]
fn sum_sq4<T: Copy>(a: &[T], b: &[T], c: &[T], d: &[T], f: impl Fn(T, T, T, T) -> f64) -> f64 {
    let mut acc = [0.0f64; LANES];
    let (ca, cb, cc, cd) = (
        a.chunks_exact(LANES),
        b.chunks_exact(LANES),
        c.chunks_exact(LANES),
        d.chunks_exact(LANES),
    );
    let mut rest = 0.0;
    let rem = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .zip(cc.remainder())
        .zip(cd.remainder());
    for (((w, x), y), z) in rem {
        let v = f(*w, *x, *y, *z);
        rest += v * v;
    }
    for (((w, x), y), z) in ca.zip(cb).zip(cc).zip(cd) {
        for l in 0..LANES {
            let v = f(w[l], x[l], y[l], z[l]);
            acc[l] += v * v;
        }
    }
    fold_lanes(acc) + rest
}

/// `K` slices of `data` (whose first element is stream index `base`), `n` long each, starting
/// at stream indices `from, from + mp, from + 2 mp, ...`.
#[inline(always)]
fn lagged_at<T, const K: usize>(data: &[T], base: u64, from: u64, mp: u64, n: usize) -> [&[T]; K] {
    let o = (from - base) as usize;
    let m = mp as usize;
    std::array::from_fn(|j| &data[o + j * m..o + j * m + n])
}

/// Second differences `x2 - 2 x1 + x0` of integer phase as exact doubles (THEORY.md section 1),
/// into `out`; the caller proves `|result| < 2^51`, so their differences are exact too.
/// (Summing their squares in the same loop was measured slower: the stores and the add chains
/// together defeat the vectorizer.)
#[inline(never)]
fn second_differences(x0: &[i64], x1: &[i64], x2: &[i64], out: &mut Vec<f64>) {
    out.clear();
    out.extend(
        x0.iter()
            .zip(x1)
            .zip(x2)
            .map(|((&a, &b), &c)| IntRepr::d2_narrow(c, b, a)),
    );
}

/// Sum of squares, in [`LANES`] partial sums (independent add chains, so the loop is bound by
/// throughput rather than by the latency of one chain).
#[inline(never)]
fn sum_sq(v: &[f64]) -> f64 {
    let mut acc = [0.0f64; LANES];
    let c = v.chunks_exact(LANES);
    let rest: f64 = c.remainder().iter().map(|x| x * x).sum();
    for x in c {
        for l in 0..LANES {
            acc[l] += x[l] * x[l];
        }
    }
    fold_lanes(acc) + rest
}

/// Sum of `(b_i - a_i)^2`, in [`LANES`] partial sums.
#[inline(never)]
fn sum_sq_diff(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let rest: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| (y - x) * (y - x))
        .sum();
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            let d = y[l] - x[l];
            acc[l] += d * d;
        }
    }
    fold_lanes(acc) + rest
}

/// Partial sums per kernel: 8 doubles are 4 independent two-lane SSE2 add chains, enough to
/// cover the add latency (4 and 16 were measured slower on kernel_probe, BENCHMARKS.md).
const LANES: usize = 8;

/// The partial sums added pairwise.
#[inline(always)]
fn fold_lanes(mut acc: [f64; LANES]) -> f64 {
    let mut w = LANES;
    while w > 1 {
        w /= 2;
        for l in 0..w {
            acc[l] += acc[l + w];
        }
    }
    acc[0]
}

/// Which differences of a level are proved below 2^51 in magnitude (integer input), so they
/// can take the narrow, vectorizable conversions.
#[derive(Debug, Clone, Copy)]
struct Narrow {
    d2: bool,
    d3: bool,
    c3: bool,
}

fn update_level<R: Repr>(
    lv: &mut Level,
    st: &Stream<R>,
    stats: StatSet,
    nid: bool,
    narrow: Narrow,
    moving_sums: Option<(&[i64], u64)>,
    scratch: &mut Vec<f64>,
) {
    let mp = lv.mp;
    let x = &st.x;
    // Integer phase with both bounds proved: AVAR and HVAR from one set of second differences.
    // AVAR first catches up to HVAR's next + mp (the start of a segment), so that AVAR's
    // difference at k + mp is the one HVAR subtracts its difference at k from.
    let mut fused = false;
    // The AVAR terms this update took in one piece: (first index, count, sum of squares).
    let mut avar_piece: Option<(u64, usize, f64)> = None;
    if let (true, true, true, Some(xi)) = (stats.avar, stats.hvar, narrow.d3, R::as_i64(&x.data)) {
        let target = lv.hvar.next + mp;
        if lv.avar.next <= target {
            fused = true;
            let upto = target.min(x.end().saturating_sub(2 * mp));
            if upto > lv.avar.next {
                let n = (upto - lv.avar.next) as usize;
                let [a, b, c] = lagged_at(xi, x.base, lv.avar.next, mp, n);
                lv.avar
                    .add(n, sum_sq3(a, b, c, |a, b, c| IntRepr::d2_narrow(c, b, a)));
            }
            if lv.avar.next == target && x.end() > lv.hvar.next + 3 * mp {
                // Second differences at k in [hvar.next, end - 2 mp): AVAR takes them from
                // k = hvar.next + mp on, HVAR their differences at lag mp (THEORY.md section 1).
                let n = (x.end() - 3 * mp - lv.hvar.next) as usize;
                let m = mp as usize;
                let [a, b, c] = lagged_at(xi, x.base, lv.hvar.next, mp, n + m);
                second_differences(a, b, c, scratch);
                let sq = sum_sq(&scratch[m..]);
                avar_piece = Some((target, n, sq));
                lv.avar.add(n, sq);
                lv.hvar.add(n, sum_sq_diff(&scratch[..n], &scratch[m..]));
            }
        }
    }
    // AVAR: x_{k+2m} - 2 x_{k+m} + x_k (THEORY.md section 1).
    if stats.avar && !fused {
        if let Some([a, b, c]) = lagged(x, lv.avar.next, mp) {
            lv.avar.add(
                a.len(),
                if narrow.d2 {
                    sum_sq3(a, b, c, |a, b, c| R::d2_narrow(c, b, a))
                } else {
                    sum_sq3(a, b, c, |a, b, c| R::d2(c, b, a))
                },
            );
        }
    }
    // HVAR: x_{k+3m} - 3 x_{k+2m} + 3 x_{k+m} - x_k (THEORY.md section 1).
    if stats.hvar && !fused {
        if let Some([a, b, c, d]) = lagged(x, lv.hvar.next, mp) {
            lv.hvar.add(
                a.len(),
                if narrow.d3 {
                    sum_sq4(a, b, c, d, |a, b, c, d| R::d3_narrow(d, c, b, a))
                } else {
                    sum_sq4(a, b, c, d, |a, b, c, d| R::d3(d, c, b, a))
                },
            );
        }
    }
    // MVAR: the inner sum of m second differences is C_{j+3m} - 3C_{j+2m} + 3C_{j+m} - C_j
    // (THEORY.md section 1 with C the running sum of phase); with stride s the stream holds
    // C at every s-th index, and mp = m/s.
    if let (true, Some((sums, base))) = (stats.mvar, moving_sums) {
        // The same inner sum as the second difference at lag m of the moving sums
        // A_m(j) = C_{j+m} - C_j of phase, which the caller holds from `base` up to P - m + 1
        // (P phase points), in wrapping i64, with |result| < 2^51 proved.
        if let Some([a, b, c]) = lagged_in(sums, base, lv.mvar.next, mp) {
            match avar_piece {
                // At m = 1 MVAR's inner sum is AVAR's second difference: the same terms in the
                // same order give the same sum, so it is not taken twice.
                Some((from, n, sq)) if lv.m == 1 && from == lv.mvar.next && n == a.len() => {
                    lv.mvar.add(n, sq)
                }
                _ => {
                    second_differences(a, b, c, scratch);
                    lv.mvar.add(a.len(), sum_sq(scratch));
                }
            }
        }
    } else if stats.mvar {
        if let Some([a, b, c, d]) = lagged(&st.c, lv.mvar.next, mp) {
            lv.mvar.add(
                a.len(),
                if narrow.c3 {
                    sum_sq4(a, b, c, d, |a, b, c, d| R::c3_narrow(d, c, b, a))
                } else {
                    sum_sq4(a, b, c, d, |a, b, c, d| R::c3(d, c, b, a))
                },
            );
        }
    }
    // Noise identification (Riley and Greenhall 2004): lag-1 products of the non-overlapping
    // m-averaged rate (first phase differences at cluster m, taken every m samples) and of its
    // first and second differences (second and third phase differences).
    // At short clusters every block would give far more pairs than the identification needs,
    // so pairs start every NID_MIN_STEP points at least (lag-1 is still between adjacent blocks).
    if nid {
        let m = mp as usize;
        let step = mp.max(NID_MIN_STEP);
        while x.end() > lv.nid_next + 4 * mp {
            let o = (lv.nid_next - x.base) as usize;
            let p = |j: usize| x.data[o + j * m];
            let (x0, x1, x2, x3, x4) = (p(0), p(1), p(2), p(3), p(4));
            lv.lag[0].add(R::d1(x1, x0), R::d1(x2, x1));
            lv.lag[1].add(R::d2(x2, x1, x0), R::d2(x3, x2, x1));
            lv.lag[2].add(R::d3(x3, x2, x1, x0), R::d3(x4, x3, x2, x1));
            lv.nid_next += step;
        }
    }
}

/// What a channel's accumulator needs of its engine, whatever the number representation.
trait ChannelEngine {
    fn gap(&mut self, missing: u64);
    fn break_seg(&mut self);
    fn points(&self) -> u64;
    fn seconds(&self) -> f64;
    fn segment_count(&self) -> u64;
    fn cfg(&self) -> &AccumConfig;
    fn bytes(&self) -> usize;
}

impl<R: Repr> ChannelEngine for Engine<R> {
    fn gap(&mut self, missing: u64) {
        self.push_gap(missing)
    }
    fn break_seg(&mut self) {
        self.break_segment()
    }
    fn points(&self) -> u64 {
        self.phase_points()
    }
    fn seconds(&self) -> f64 {
        self.t_data_s()
    }
    fn segment_count(&self) -> u64 {
        self.segments()
    }
    fn cfg(&self) -> &AccumConfig {
        self.config()
    }
    fn bytes(&self) -> usize {
        self.stream_bytes()
    }
}

/// A channel's accumulator for whichever kind of input it receives.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub enum ChannelAccumulator {
    /// Integer counts (frame fields); the reading is scaled by `scale` (u per count).
    Counts { engine: Engine<IntRepr>, scale: f64 },
    /// Floating increments or phase in u.
    Real(Engine<FloatRepr>),
}

impl ChannelAccumulator {
    pub fn counts(cfg: AccumConfig, scale: f64) -> Self {
        ChannelAccumulator::Counts {
            engine: Engine::new(cfg),
            scale,
        }
    }

    pub fn real(cfg: AccumConfig) -> Self {
        ChannelAccumulator::Real(Engine::new(cfg))
    }

    /// The engine behind the channel, whichever its representation.
    fn engine(&self) -> &dyn ChannelEngine {
        match self {
            ChannelAccumulator::Counts { engine, .. } => engine,
            ChannelAccumulator::Real(e) => e,
        }
    }

    fn engine_mut(&mut self) -> &mut dyn ChannelEngine {
        match self {
            ChannelAccumulator::Counts { engine, .. } => engine,
            ChannelAccumulator::Real(e) => e,
        }
    }

    pub fn push_gap(&mut self, missing: u64) {
        self.engine_mut().gap(missing)
    }

    /// Ends the current phase segment without accounting for time: the data after it are not
    /// contiguous with the data before (a resumed live run), so no difference spans the break.
    pub fn break_segment(&mut self) {
        self.engine_mut().break_seg()
    }

    pub fn phase_points(&self) -> u64 {
        self.engine().points()
    }

    pub fn t_data_s(&self) -> f64 {
        self.engine().seconds()
    }

    pub fn segments(&self) -> u64 {
        self.engine().segment_count()
    }

    pub fn config(&self) -> &AccumConfig {
        self.engine().cfg()
    }

    pub fn stream_bytes(&self) -> usize {
        self.engine().bytes()
    }

    /// [`Engine::check_restored`] for whichever engine this is; a count scale must be a
    /// finite non-zero number.
    pub fn check_restored(&self) -> Result<(), String> {
        match self {
            ChannelAccumulator::Counts { engine, scale } => {
                if !(scale.is_finite() && *scale != 0.0) {
                    return Err(format!("count scale {scale}"));
                }
                engine.check_restored()
            }
            ChannelAccumulator::Real(e) => e.check_restored(),
        }
    }

    /// Readings in u^2/s^2 (counts scaled).
    pub fn read(&mut self) -> Vec<LevelReading> {
        match self {
            ChannelAccumulator::Counts { engine, scale } => {
                let s2 = *scale * *scale;
                let sc = |v: Option<(f64, u64)>| v.map(|(var, n)| (var * s2, n));
                engine
                    .read()
                    .into_iter()
                    .map(|r| LevelReading {
                        avar: sc(r.avar),
                        hvar: sc(r.hvar),
                        mvar: sc(r.mvar),
                        ..r
                    })
                    .collect()
            }
            ChannelAccumulator::Real(e) => e.read(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{largest_divisor_at_most, IntRepr, Repr};

    #[test]
    fn deviation_bounds_the_distance_and_is_tight_within_two() {
        // `deviation + 1 >= |d - r|` for every pair, and no more than twice it while the
        // difference fits in i64 (all ones when it cannot), checked in 128-bit arithmetic.
        let edge = [
            i64::MIN,
            i64::MIN + 1,
            -(1 << 40),
            -7,
            -1,
            0,
            1,
            6,
            1 << 40,
            i64::MAX,
        ];
        let mut s: u64 = 0x2545F4914F6CDD1D;
        let mut vals: Vec<i64> = edge.to_vec();
        for _ in 0..200 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            vals.push((s as i64) >> (s % 64));
        }
        for &d in &vals {
            for &r in &vals {
                let dist = (d as i128 - r as i128).unsigned_abs();
                let v = IntRepr::deviation(d, r);
                assert!(v as u128 + 1 >= dist, "d={d} r={r} v={v}");
                if dist < 1 << 63 {
                    assert!(v as u128 <= 2 * dist, "d={d} r={r} v={v}");
                } else if dist > 1 << 63 {
                    // Out of i64 range: the wrapping difference overflowed.
                    assert_eq!(v, u64::MAX, "d={d} r={r}");
                }
                // The OR of two deviations bounds both.
                let w = v | IntRepr::deviation(r, d);
                assert!(w as u128 + 1 >= dist);
            }
        }
    }

    #[test]
    fn strides_are_the_largest_divisors_under_the_cap() {
        // Checked against a brute-force scan.
        for m in 1..400u64 {
            for cap in 1..=m {
                let brute = (1..=cap).rev().find(|d| m % d == 0).unwrap();
                assert_eq!(largest_divisor_at_most(m, cap), brute, "m={m} cap={cap}");
            }
        }
        assert_eq!(largest_divisor_at_most(1 << 40, (1 << 40) / 3), 1 << 38);
        assert_eq!(largest_divisor_at_most(1_000_003, 62), 1, "a prime");
    }
}
