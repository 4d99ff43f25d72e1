//! A column of accumulated angle or velocity (phase) read as increments or rate samples: its
//! values move steadily over the run, by far more than they change from one sample to the
//! next. Read as increments, such a column is a ramp of the rate, and every tau of its curve is
//! the ramp's (a rev15 review: a delta-velocity column integrated to 7e4 m/s over two hours,
//! read without `--phase`, gave `unexplained` and a K 12 000 times the truth, without a word).
//!
//! The hint, streaming and O(1): the column's range `max - min` is at least [`RANGE_STEPS`]
//! times the root mean square of its sample-to-sample changes, and the run ends at least half
//! that range from where it began (a steady drift, not a rate table's swing). Increments and
//! rate samples of a sensor change by about their own spread each sample (a range of a few
//! tens of changes); a rate sample's slow wander (a warm-up, a chamber ramp) spans hundreds,
//! where a phase column spans millions.

/// The least range, in root-mean-square sample-to-sample changes, of a phase column.
pub const RANGE_STEPS: f64 = 1e4;
/// Fewest values judged.
const MIN_VALUES: u64 = 1000;

/// One column's account.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct PhaseHint {
    first: Option<f64>,
    last: f64,
    /// The value before, when it was finite (the chain of changes).
    prev: Option<f64>,
    min: f64,
    max: f64,
    sum_d2: f64,
    n_d: u64,
    n: u64,
}

impl PhaseHint {
    /// One value (non-finite ones are passed over, and break the chain of changes).
    pub fn push(&mut self, v: f64) {
        if !v.is_finite() {
            self.prev = None;
            return;
        }
        if let Some(p) = self.prev {
            let d = v - p;
            self.sum_d2 += d * d;
            self.n_d += 1;
        }
        if self.first.is_none() {
            self.first = Some(v);
            self.min = v;
            self.max = v;
        }
        self.min = self.min.min(v);
        self.max = self.max.max(v);
        self.prev = Some(v);
        self.last = v;
        self.n += 1;
    }

    /// `(first, last, range over the rms change)` when the column looks like a phase.
    pub fn looks_like_phase(&self) -> Option<(f64, f64, f64)> {
        let first = self.first?;
        if self.n < MIN_VALUES || self.n_d == 0 {
            return None;
        }
        let rms = (self.sum_d2 / self.n_d as f64).sqrt();
        let range = self.max - self.min;
        let ratio = if rms > 0.0 {
            range / rms
        } else {
            f64::INFINITY
        };
        (range > 0.0 && ratio >= RANGE_STEPS && (self.last - first).abs() >= 0.5 * range)
            .then_some((first, self.last, ratio))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The running sum of increments near 0.05 (a bias) with noise of 0.01: a phase (range 1e5
    /// changes); the increments themselves, a sinusoid's swing of 1000 changes and a warm-up of
    /// 300 are not.
    #[test]
    fn a_running_sum_is_a_phase_and_its_increments_are_not() {
        let n = 200_000;
        let noise = |i: usize| ((i * 7919 % 1000) as f64 / 1000.0 - 0.5) * 0.035;
        let (mut phase, mut inc, mut swing, mut warm) = Default::default();
        let (mut p, mut x) = (0.0, 0.0);
        for i in 0..n {
            let d = 0.05 + noise(i);
            x += d;
            p = x;
            PhaseHint::push(&mut phase, p);
            PhaseHint::push(&mut inc, d);
            PhaseHint::push(&mut swing, 10.0 * (i as f64 * 1e-4).sin() + noise(i));
            PhaseHint::push(&mut warm, 3.0 * (-(i as f64) / 2e4).exp() + noise(i));
        }
        let (f, l, ratio): (f64, f64, f64) = phase.looks_like_phase().expect("a phase");
        assert!(f.abs() < 0.1 && (l - p).abs() < 1e-9, "{f} {l}");
        assert!(ratio > 1e5, "{ratio}");
        assert_eq!(inc.looks_like_phase(), None);
        assert_eq!(swing.looks_like_phase(), None);
        assert_eq!(warm.looks_like_phase(), None);
    }
}
