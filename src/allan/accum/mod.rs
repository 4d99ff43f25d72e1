//! Streaming accumulators for the overlapping Allan, overlapping Hadamard and modified Allan
//! variances (docs/theory.md section 1), updated sample by sample and readable at any moment.
//!
//! # How it works
//!
//! Phase points `x_k` (the running sum of increments) and their running sum `C_k = x_0 + ... +
//! x_{k-1}` (the "double running sum" MVAR needs: its inner sum of `m` second differences is a
//! third difference of `C`) enter a *stream* at stride 1. Every cluster size `m` (a *level*)
//! reads a stream of stride `s`: `s = 1` in exact mode, and in bounded mode the largest divisor
//! of `m` not above `max(1, m/L)`, so each level sees at least `L` stream points per cluster
//! (docs/theory.md section 1, "Bounded memory"). Streams of larger strides are
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
//! only up to a constant, so no difference spans it (docs/theory.md section 1, "Gaps"). Sums and counts
//! carry on; the streams restart.
//!
//! # Files
//!
//! `config.rs` (what to accumulate), `repr.rs` (integer and double-double phase), `engine.rs`
//! (streams, levels, the per-block update), `kernels.rs` (the inner loops), `channel.rs` (the
//! facade a channel uses).

mod channel;
mod config;
mod engine;
mod kernels;
mod repr;

pub use channel::*;
pub use config::*;
pub use engine::*;
use kernels::*;
pub use repr::*;

use super::batch::CompensatedSum;
use super::Stat;

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
                // 0 exactly when equal (a channel's constancy is read off it).
                assert_eq!(v == 0, d == r, "d={d} r={r}");
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
