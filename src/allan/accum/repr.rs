//! Number representations of the phase: exact integer counts ([`IntRepr`]) and double-double
//! floating values ([`FloatRepr`], [`Dd`]), with the differences each takes exactly.

#[allow(unused_imports)]
use super::*;

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
    /// increments is again such a bound for each (so it is kept with `|=`, which vectorizes),
    /// and 0 exactly when `d == reference`. Floats, which need no bound, give only the last:
    /// 1 where `d` differs, so the OR is 0 only while every increment equals the first.
    fn deviation(d: Self::Inc, reference: Self::Inc) -> u64;
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
        // The magnitude of d - reference, 0 only when they are equal (the one's complement used
        // before session 30 was 0 for d = reference - 1 too, so a channel stepping between two
        // neighbouring counts read as constant), or all ones when the wrapping difference
        // overflowed (operands of opposite signs, result sign flipped).
        let t = d.wrapping_sub(reference);
        let overflow = ((d ^ reference) & (d ^ t)) >> 63;
        t.unsigned_abs() | overflow as u64
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
pub(super) fn third_difference(a: i64, b: i64, c: i64, d: i64) -> i64 {
    let ab = a.wrapping_sub(b);
    let bc = b.wrapping_sub(c);
    let cd = c.wrapping_sub(d);
    ab.wrapping_sub(bc).wrapping_sub(bc.wrapping_sub(cd))
}

/// `v as f64` for `|v| < 2^51`, exactly, by the 1.5 * 2^52 bias trick: an integer add and a
/// float subtract, both of which run on vector lanes (AVX2 has no i64 -> f64 conversion).
#[inline(always)]
pub(super) fn small_i64_to_f64(v: i64) -> f64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0; // 1.5 * 2^52
    f64::from_bits(v.wrapping_add(MAGIC.to_bits() as i64) as u64) - MAGIC
}

/// Floating-point increments or phase, carried in double-double.
#[derive(Debug, Clone)]
pub struct FloatRepr;

/// Nested differences of double-double numbers: the high parts are subtracted first, pairwise
/// between neighbours (exact when they are close), then the low parts.
#[inline(always)]
pub(super) fn dd_d2(a: Dd, b: Dd, c: Dd) -> f64 {
    let hi = (a.hi - b.hi) - (b.hi - c.hi);
    let lo = (a.lo - b.lo) - (b.lo - c.lo);
    hi + lo
}

#[inline(always)]
pub(super) fn dd_d3(a: Dd, b: Dd, c: Dd, d: Dd) -> f64 {
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
    #[inline(always)]
    fn deviation(d: f64, reference: f64) -> u64 {
        u64::from(d != reference)
    }
}
