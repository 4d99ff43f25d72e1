//! The quantization step (LSB) of a channel, read off its values: a unit that counts whole LSBs
//! delivers values that are all integer multiples of one step. Streaming and bounded: the
//! smallest non-zero difference between consecutive values is the candidate (one LSB apart is
//! common in any noisy counter), and the first [`KEEP`] values are kept to check that every one
//! of them is a whole multiple of it. Unquantized (floating) values fail the check. Two values
//! that differ by less than [`PRINT_REL`](crate::smallest_step::PRINT_REL) of the largest value
//! seen are the same count written twice ([`crate::smallest_step`]).
//!
//! A unit whose step changes during the run (a range switched, a new output format) is told
//! too: the step of each window of [`WINDOW`] values is read the same way, and a step that
//! differs from the one held before it for [`PERSIST`] windows in a row is a change
//! ([`StepChange`]; before session 53 a rev15 review's range switch was not said).

use crate::smallest_step::SmallestStep;

/// Values kept for the check.
pub const KEEP: usize = 20_000;
/// Fewest values for an estimate.
const MIN_VALUES: usize = 100;
/// Tolerance on `value / lsb` being a whole number, in LSBs, beside [`TOL_REL`]: decimal text
/// read back as f64 is off by a few ulps; a floating value is off by a uniform fraction, so that
/// the kept values all pass by chance with probability about `(2 tol)^n`.
const TOL: f64 = 1e-3;
/// The part of the tolerance that grows with the count (`TOL_REL |k|`; at most 0.017 LSB at
/// [`MAX_COUNT`]).
const TOL_REL: f64 = 1e-9;
/// The largest count (`|value| / lsb`) the check is made at: 2^24, a 24-bit converter's full
/// scale. Above it the smallest difference of floating values is no step: a MEMS gyro's
/// increments written as floats near 0.6 deg (a bias of 620 deg/s at 1 kHz) differed by as
/// little as 1.6e-8 deg among a million samples, every value then 4e7 such steps, and with the
/// tolerance relative to the count (1e-6 of it, 40 steps) the check passed and the record gave
/// a quantization of 1.6e-8 deg (a review, session 39).
const MAX_COUNT: f64 = 16_777_216.0;

/// Values per window whose step is read for [`StepChange`]s.
pub const WINDOW: usize = 4096;
/// Windows in a row a new step must hold to be a change.
pub const PERSIST: u32 = 2;
/// Changes kept (more are counted).
pub const MAX_CHANGES: usize = 8;

/// The values' step changed: from `from` to `to` (u), after the `at_value`-th finite value (the
/// end of the last window with the old step: the change falls within the next window or so).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepChange {
    pub at_value: u64,
    pub from: f64,
    pub to: f64,
}

/// The step of consecutive windows of values, and its changes.
#[derive(Debug, Clone, Default)]
struct WindowSteps {
    values: Vec<f64>,
    step: SmallestStep,
    /// The step held, and a new one seen in the windows since (how many windows in a row).
    held: Option<f64>,
    /// The end of the last window with the held step (finite values).
    held_end: u64,
    candidate: Option<(f64, u32)>,
    changes: Vec<StepChange>,
    more: u64,
}

impl WindowSteps {
    /// One finite value `v`, the `n`-th, after `prev` (the finite value before it, `None` after
    /// a gap: [`LsbEstimator`]'s chain of differences).
    fn push(&mut self, prev: Option<f64>, v: f64, n: u64) {
        if let Some(p) = prev {
            self.step.push(p, v);
        }
        self.values.push(v);
        if self.values.len() == WINDOW {
            let q = self.step.get().and_then(|m| whole_step(&self.values, m));
            self.judge(q, n);
            self.values.clear();
            self.step = SmallestStep::default();
        }
    }

    /// A window's step (`None`: the window shows none, as floating values or a stuck stretch),
    /// the window ending at the `end`-th finite value.
    fn judge(&mut self, q: Option<f64>, end: u64) {
        let Some(q) = q else { return };
        let same = |a: f64, b: f64| ((a - b) / b).abs() <= 1e-6;
        let Some(held) = self.held else {
            self.held = Some(q);
            self.held_end = end;
            return;
        };
        if same(q, held) {
            self.candidate = None;
            self.held_end = end;
            return;
        }
        let count = match self.candidate {
            Some((c, count)) if same(q, c) => count + 1,
            _ => 1,
        };
        self.candidate = Some((q, count));
        if count >= PERSIST {
            if self.changes.len() < MAX_CHANGES {
                self.changes.push(StepChange {
                    at_value: self.held_end,
                    from: held,
                    to: q,
                });
            } else {
                self.more += 1;
            }
            self.held = Some(q);
            self.held_end = end;
            self.candidate = None;
        }
    }
}

/// Estimates the LSB of one channel's values (increments, or rate samples).
#[derive(Debug, Clone, Default)]
pub struct LsbEstimator {
    kept: Vec<f64>,
    last: Option<f64>,
    step: SmallestStep,
    n: u64,
    /// The first finite value, and whether any later one differed from it.
    first: Option<f64>,
    varies: bool,
    windows: WindowSteps,
}

impl LsbEstimator {
    pub fn new() -> Self {
        Self::default()
    }

    /// One value (non-finite values are skipped and break the chain of differences).
    pub fn push(&mut self, v: f64) {
        if !v.is_finite() {
            self.last = None;
            return;
        }
        self.n += 1;
        match self.first {
            None => self.first = Some(v),
            Some(f) => self.varies |= v != f,
        }
        if self.kept.len() < KEEP {
            self.kept.push(v);
        }
        if let Some(p) = self.last {
            self.step.push(p, v);
        }
        self.windows.push(self.last, v, self.n);
        self.last = Some(v);
    }

    /// The value every one of at least two finite values had, bit for bit (a channel that
    /// does not move: stuck, saturated or not connected); `None` when they vary.
    pub fn constant(&self) -> Option<f64> {
        (self.n >= 2 && !self.varies)
            .then_some(self.first)
            .flatten()
    }

    /// Finite values seen.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// The step (same unit as the values) when every kept value is a whole multiple of the
    /// smallest difference seen (its shortest decimal, [`snap_decimal`]), and the counts are not
    /// so large that the check means nothing (at most [`MAX_COUNT`]); `None` otherwise.
    pub fn estimate(&self) -> Option<f64> {
        whole_step(&self.kept, self.step.get()?)
    }

    /// The changes of the values' step over the run (at most [`MAX_CHANGES`]) and how many
    /// more there were.
    pub fn step_changes(&self) -> (&[StepChange], u64) {
        (&self.windows.changes, self.windows.more)
    }
}

/// `min_step` as the step of `values` (its shortest decimal, [`snap_decimal`]) when there are
/// at least [`MIN_VALUES`] of them, every one a whole multiple of it at counts of at most
/// [`MAX_COUNT`].
fn whole_step(values: &[f64], min_step: f64) -> Option<f64> {
    if values.len() < MIN_VALUES {
        return None;
    }
    let q = snap_decimal(min_step);
    let whole = values.iter().all(|&v| {
        let k = v / q;
        k.abs() <= MAX_COUNT && (k - k.round()).abs() <= TOL + TOL_REL * k.abs()
    });
    whole.then_some(q)
}

/// The shortest decimal within 1e-9 (relative) of `q`: the smallest difference of two decimal
/// values read back as f64 is off by an ulp or so (0.00399999999999999 for 0.004).
fn snap_decimal(q: f64) -> f64 {
    (1..=15)
        .filter_map(|digits| format!("{q:.*e}", digits - 1).parse::<f64>().ok())
        .find(|s| ((s - q) / q).abs() <= 1e-9)
        .unwrap_or(q)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// Counts of a noisy counter times a decimal LSB, as the simulator prints them (decimal
    /// text read back): the LSB is found to 1e-12; the same values with a uniform fraction of
    /// an LSB added are not quantized.
    #[test]
    fn finds_the_step_of_counted_values_only() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let lsb = 2.104e-4;
        let mut q = LsbEstimator::new();
        let mut f = LsbEstimator::new();
        for _ in 0..50_000 {
            let count: i64 = 15 + rng.random_range(-4..=4);
            let text = format!("{}", count as f64 * lsb);
            q.push(text.parse::<f64>().unwrap());
            f.push(count as f64 * lsb + rng.random::<f64>() * lsb);
        }
        let est = q.estimate().expect("quantized");
        assert_eq!(est, lsb, "the decimal LSB itself");
        assert_eq!(f.estimate(), None);
    }

    /// Floating values far from zero (increments near 0.62 deg, a bias of 620 deg/s at 1 kHz,
    /// noise 2e-3 deg): the smallest difference among 100 000 of them is about 1e-8 deg, each
    /// value then some 1e7-1e8 such steps; no step is found (a review found one of 1.6e-8 deg).
    /// Counted values with a large offset (a 16-bit gyro's rate samples near 30 000 LSB) are
    /// found.
    #[test]
    fn floating_values_far_from_zero_have_no_step() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(9);
        let mut f = LsbEstimator::new();
        let mut q = LsbEstimator::new();
        let lsb = 0.007_629_394_531_25; // 250 deg/s over 2^15
        for _ in 0..100_000 {
            let v = -0.6239 + 2e-3 * (rng.random::<f64>() - 0.5) * 3.46;
            f.push(format!("{v:e}").parse::<f64>().unwrap());
            let count: i64 = 30_000 + rng.random_range(-40..=40);
            q.push(format!("{}", count as f64 * lsb).parse::<f64>().unwrap());
        }
        let smallest = f.step.get().unwrap();
        assert!(smallest < 1e-7, "{smallest}");
        assert_eq!(f.estimate(), None);
        let est = q.estimate().expect("counted");
        assert!((est / lsb - 1.0).abs() < 1e-9, "{est}");
    }

    /// Increments formed as differences of an accumulated count times the LSB, printed with ten
    /// significant digits (`4.999999999e-05` beside `5e-05`, as a review's logger wrote them):
    /// the LSB is found; without the printing tolerance the smallest difference was 1e-14.
    #[test]
    fn a_count_printed_through_accumulated_products_keeps_its_step() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let lsb = 5e-5;
        let mut q = LsbEstimator::new();
        // An accumulated velocity near 72 m/s (1.44e6 counts), moving 0-2 counts a sample.
        let mut k: i64 = 1_440_000;
        let mut printed_off = 0;
        for _ in 0..50_000 {
            let k1 = k + rng.random_range(0..=2);
            let text = format!("{:.9e}", k1 as f64 * lsb - k as f64 * lsb);
            printed_off += usize::from(text != format!("{:.9e}", (k1 - k) as f64 * lsb));
            q.push(text.parse::<f64>().unwrap());
            k = k1;
        }
        assert!(
            printed_off > 1000,
            "the printing leaves its mark: {printed_off}"
        );
        let est = q.estimate().expect("the count's step");
        assert!((est / lsb - 1.0).abs() < 1e-9, "{est}");
    }

    /// Too few values, or constant values, give no estimate.
    #[test]
    fn no_estimate_without_evidence() {
        let mut q = LsbEstimator::new();
        for _ in 0..1000 {
            q.push(0.5);
        }
        assert_eq!(q.estimate(), None);
        let mut s = LsbEstimator::new();
        for i in 0..10 {
            s.push(i as f64);
        }
        assert_eq!(s.estimate(), None);
    }

    /// A counter whose step changes from 0.01 to 0.025 (not a multiple) after 30 000 values
    /// (a range switched): one change, from 0.01 to 0.025, at the window the switch falls in.
    /// A counter of large noise (consecutive counts up to two thousand steps apart), a float
    /// stream, and a counter whose step never changes, give none.
    #[test]
    fn a_step_that_changes_is_told_and_noise_is_not() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(13);
        let text = |k: i64, q: f64| format!("{}", k as f64 * q).parse::<f64>().unwrap();
        let mut switched = LsbEstimator::new();
        let mut wide = LsbEstimator::new();
        let mut floats = LsbEstimator::new();
        let mut steady = LsbEstimator::new();
        for i in 0..60_000 {
            let q = if i < 30_000 { 0.01 } else { 0.025 };
            switched.push(text(40 + rng.random_range(-3..=3), q));
            wide.push(text(rng.random_range(-1000..=1000), 0.01));
            floats.push(rng.random::<f64>() * 0.1);
            steady.push(text(rng.random_range(-3..=3), 0.004));
        }
        let (changes, more) = switched.step_changes();
        assert_eq!(more, 0);
        assert_eq!(changes.len(), 1, "{changes:?}");
        let c = changes[0];
        assert!((c.from / 0.01 - 1.0).abs() < 1e-9 && (c.to / 0.025 - 1.0).abs() < 1e-9);
        assert!(
            c.at_value <= 30_000 && 30_000 - c.at_value < WINDOW as u64,
            "{c:?}"
        );
        for e in [&wide, &floats, &steady] {
            assert!(e.step_changes().0.is_empty(), "{:?}", e.step_changes());
        }
    }
}
