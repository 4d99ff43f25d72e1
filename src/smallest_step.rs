//! The smallest step between consecutive values of one column, with printing noise passed over:
//! the candidate LSB of a counter ([`crate::gap::lsb`]) and the resolution behind the chance of
//! two equal rows ([`crate::input::row_ties`]). One LSB apart is common in any noisy counter,
//! so the smallest non-zero difference seen is that step. Two values that differ by less than
//! [`PRINT_REL`] of the largest `|value|` seen are the same count written twice: a logger that
//! forms each increment as the difference of two accumulated products `k q` and prints ten
//! significant digits writes one LSB as `5e-05` and as `4.999999999e-05`.

/// Differences of consecutive values below this fraction of the largest `|value|` seen are
/// printing, not a step. A rev13 review's delta-velocity counter (an LSB of 5e-5 m/s, increments
/// differenced from an accumulated velocity near 72 m/s and printed with ten digits) differed by
/// 1e-14 between its `5e-05` and `4.999999999e-05`, and no LSB was found; the diagnosis then read
/// the counter's sub-LSB rounding (per-sample noise 0.3 LSB) as a 159 Hz second-order filter.
/// At 2e-8 a one-LSB step is still seen at counts up to 5e7, beyond a 24-bit converter's
/// full scale (2^24).
pub const PRINT_REL: f64 = 2e-8;

/// The smallest difference between consecutive values handed to [`SmallestStep::push`], and
/// the largest `|value|` (the scale printing noise is judged against). Streaming, constant
/// memory.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SmallestStep {
    min_step: f64,
    scale: f64,
}

impl Default for SmallestStep {
    fn default() -> Self {
        Self {
            min_step: f64::INFINITY,
            scale: 0.0,
        }
    }
}

impl SmallestStep {
    /// One pair of consecutive finite values: `v` and the value `prev` before it. Returns
    /// `|v - prev|`.
    pub fn push(&mut self, prev: f64, v: f64) -> f64 {
        self.scale = self.scale.max(v.abs()).max(prev.abs());
        let d = (v - prev).abs();
        if d > PRINT_REL * self.scale && d < self.min_step {
            self.min_step = d;
        }
        d
    }

    /// The smallest difference above printing noise seen, or `None` before any.
    pub fn get(&self) -> Option<f64> {
        (self.min_step.is_finite() && self.min_step > 0.0).then_some(self.min_step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counts of 5e-5 written through ten-digit printing: the step is 5e-5 (within the
    /// printing), not the 1e-14 between two writings of one count.
    #[test]
    fn printing_noise_is_no_step() {
        let mut s = SmallestStep::default();
        let vals = [72.0, 72.00005, 72.00005 + 1e-14, 72.0001, 72.00005];
        for w in vals.windows(2) {
            s.push(w[0], w[1]);
        }
        let step = s.get().unwrap();
        assert!((step - 5e-5).abs() < 1e-12, "step {step}");
    }

    #[test]
    fn equal_values_give_no_step() {
        let mut s = SmallestStep::default();
        assert_eq!(s.get(), None);
        s.push(1.0, 1.0);
        assert_eq!(s.get(), None);
        s.push(1.0, 1.25);
        assert_eq!(s.get(), Some(0.25));
    }
}
