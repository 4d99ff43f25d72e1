//! The textbook batch formulas of docs/theory.md section 1, written as plainly as possible.
//!
//! They are the reference the streaming accumulators are tested against, and they are slow
//! (no sharing between cluster sizes). Input is phase (u), in one or more contiguous segments:
//! a difference never spans two segments (docs/theory.md section 1, "Gaps").

/// A neumaier-compensated running sum, so reference sums of many squares stay exact to ~1 ulp.
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
pub struct CompensatedSum {
    sum: f64,
    comp: f64,
}

impl CompensatedSum {
    #[inline]
    pub fn add(&mut self, v: f64) {
        let t = self.sum + v;
        if self.sum.abs() >= v.abs() {
            self.comp += (self.sum - t) + v;
        } else {
            self.comp += (v - t) + self.sum;
        }
        self.sum = t;
    }

    pub fn value(&self) -> f64 {
        self.sum + self.comp
    }
}

/// Sum of squared differences and their number, one statistic at one cluster size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BatchPoint {
    /// The variance in u^2/s^2.
    pub var: f64,
    /// Number of differences averaged.
    pub count: u64,
}

/// Phase from increments: `x_0 = 0`, `x_k = d_1 + ... + d_k` (docs/theory.md section 1), summed with
/// compensation.
pub fn phase_from_increments(d: &[f64]) -> Vec<f64> {
    let mut x = Vec::with_capacity(d.len() + 1);
    let mut acc = CompensatedSum::default();
    x.push(0.0);
    for &v in d {
        acc.add(v);
        x.push(acc.value());
    }
    x
}

fn finish(sum: CompensatedSum, count: u64, denom_per_term: f64) -> Option<BatchPoint> {
    (count > 0).then(|| BatchPoint {
        var: sum.value() / (denom_per_term * count as f64),
        count,
    })
}

/// Overlapping Allan variance (docs/theory.md section 1, the seed paper's formula (4)):
/// `sum (x_{k+2m} - 2x_{k+m} + x_k)^2 / (2 tau^2 count)`.
pub fn oavar(segments: &[&[f64]], m: usize, tau0_s: f64) -> Option<BatchPoint> {
    let tau = m as f64 * tau0_s;
    let mut sum = CompensatedSum::default();
    let mut count = 0u64;
    for x in segments {
        for k in 0..x.len().saturating_sub(2 * m) {
            let d = x[k + 2 * m] - 2.0 * x[k + m] + x[k];
            sum.add(d * d);
            count += 1;
        }
    }
    finish(sum, count, 2.0 * tau * tau)
}

/// Overlapping Hadamard variance (docs/theory.md section 1):
/// `sum (x_{k+3m} - 3x_{k+2m} + 3x_{k+m} - x_k)^2 / (6 tau^2 count)`.
pub fn ohvar(segments: &[&[f64]], m: usize, tau0_s: f64) -> Option<BatchPoint> {
    let tau = m as f64 * tau0_s;
    let mut sum = CompensatedSum::default();
    let mut count = 0u64;
    for x in segments {
        for k in 0..x.len().saturating_sub(3 * m) {
            let d = x[k + 3 * m] - 3.0 * x[k + 2 * m] + 3.0 * x[k + m] - x[k];
            sum.add(d * d);
            count += 1;
        }
    }
    finish(sum, count, 6.0 * tau * tau)
}

/// Modified Allan variance (docs/theory.md section 1):
/// `sum_j (sum_{i=j}^{j+m-1} (x_{i+2m} - 2x_{i+m} + x_i))^2 / (2 m^2 tau^2 count)`.
pub fn mvar(segments: &[&[f64]], m: usize, tau0_s: f64) -> Option<BatchPoint> {
    let tau = m as f64 * tau0_s;
    let mut sum = CompensatedSum::default();
    let mut count = 0u64;
    for x in segments {
        if x.len() < 3 * m {
            continue;
        }
        for j in 0..=(x.len() - 3 * m) {
            let mut inner = CompensatedSum::default();
            for i in j..j + m {
                inner.add(x[i + 2 * m] - 2.0 * x[i + m] + x[i]);
            }
            let v = inner.value();
            sum.add(v * v);
            count += 1;
        }
    }
    let mf = m as f64;
    finish(sum, count, 2.0 * mf * mf * tau * tau)
}
