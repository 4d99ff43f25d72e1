//! The quantization step (LSB) of a channel, read off its values: a unit that counts whole LSBs
//! delivers values that are all integer multiples of one step. Streaming and bounded: the
//! smallest non-zero difference between consecutive values is the candidate (one LSB apart is
//! common in any noisy counter), and the first [`KEEP`] values are kept to check that every one
//! of them is a whole multiple of it. Unquantized (floating) values fail the check.

/// Values kept for the check.
pub const KEEP: usize = 20_000;
/// Fewest values for an estimate.
const MIN_VALUES: usize = 100;
/// Tolerance on `value / lsb` being a whole number (decimal text read back as f64 is off by a
/// few ulps; a floating value is off by a uniform fraction).
const TOL: f64 = 1e-6;

/// Estimates the LSB of one channel's values (increments, or rate samples).
#[derive(Debug, Clone, Default)]
pub struct LsbEstimator {
    kept: Vec<f64>,
    last: Option<f64>,
    min_step: f64,
    n: u64,
    /// The first finite value, and whether any later one differed from it.
    first: Option<f64>,
    varies: bool,
}

impl LsbEstimator {
    pub fn new() -> Self {
        Self {
            min_step: f64::INFINITY,
            ..Self::default()
        }
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
            let d = (v - p).abs();
            if d > 0.0 && d < self.min_step {
                self.min_step = d;
            }
        }
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
    /// smallest difference seen, and the counts are not so large that the check means nothing
    /// (below 2^40); `None` otherwise.
    pub fn estimate(&self) -> Option<f64> {
        let q = self.min_step;
        if self.kept.len() < MIN_VALUES || !(q.is_finite() && q > 0.0) {
            return None;
        }
        let whole = self.kept.iter().all(|&v| {
            let k = v / q;
            k.abs() < (1u64 << 40) as f64 && (k - k.round()).abs() <= TOL * k.abs().max(1.0)
        });
        whole.then_some(snap_decimal(q))
    }
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
}
