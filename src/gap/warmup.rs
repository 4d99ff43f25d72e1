//! A warm-up found in time (docs/theory.md section 3): `A e^{-t/T}` fitted by generalised least squares
//! to the first differences of the block-mean rate, with the covariance of [`super::block_cov`],
//! `T` scanned on a log grid; its statistic integrated over `T` ([`WarmupFinding::log_bf`]).

use super::block_cov::{block_diff_covariance, usable_block_means};
use super::effects::{EffectParams, Grid};
use nalgebra::{DMatrix, DVector};

/// A warm-up fitted to the block means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WarmupFinding {
    /// `A` of `A e^{-t/T}`, u/s.
    pub amplitude: f64,
    pub time_constant_s: f64,
    /// Drop of the residual sum of squares against a line, in robust block variances.
    pub w_stat: f64,
    /// The same evidence integrated over the scanned `T` instead of maximised:
    /// `ln mean_T exp(W(T) / 2)` over the log grid (log-uniform weights), the log marginal
    /// likelihood ratio with the amplitude profiled, up to a constant (a Bayes-factor mixture
    /// statistic, e.g. Kass and Raftery 1995, section 4; docs/gap.md, "Mixture statistics").
    pub log_bf: f64,
}

impl WarmupFinding {
    /// The warm-up's mean over each block.
    pub fn block_curve(&self, n_blocks: usize, block_s: f64) -> Vec<f64> {
        (0..n_blocks)
            .map(|i| self.amplitude * warmup_block_shape(i, block_s, self.time_constant_s))
            .collect()
    }
}

/// Mean of `e^{-t/T}` over block `i` of length `tb`: `(T/tb)(e^{-i tb/T} - e^{-(i+1) tb/T})`.
pub fn warmup_block_shape(i: usize, tb: f64, t: f64) -> f64 {
    let a = i as f64 * tb / t;
    t / tb * (-a).exp() * -(-tb / t).exp_m1()
}

/// A warm-up in the block means: generalised least squares of the first differences of the
/// block-mean rate on `r + A (e_{i+1} - e_i)`, `e_i` the block mean of `e^{-t/T}` (the warm-up
/// of docs/theory.md section 3 over a linear drift `r`), with the covariance of the differences from
/// the fitted model (five terms `c` plus the stationary `effects`). `T` is scanned on a log grid
/// from half a block to a quarter of the run. The statistic is the drop of the whitened
/// residual sum of squares against the drift alone (about chi-squared with one degree of
/// freedom, plus the scan's look-elsewhere, when there is no warm-up).
///
/// Two variants were measured and dropped (docs/gap.md): re-estimating the covariance without
/// the warm-up (its AVAR taken off the curve, the five terms refitted) lifts the statistic of
/// clean runs more than that of warm-ups (null 99% quantile 11 -> 17); refining `T` on the
/// block means and the curve together left the benchmark's errors as they were.
pub fn fit_warmup(
    block_means: &[f64],
    block_s: f64,
    t_run_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<WarmupFinding> {
    let fitter = WarmupFitter::new(block_means, block_s, c, effects)?;
    let grid = Grid {
        lo: block_s / 2.0,
        hi: t_run_s / 4.0,
        per_decade: 24.0,
    };
    let mut best: Option<(f64, f64, f64)> = None; // (T, A, rss)
    let mut half_w: Vec<f64> = Vec::new();
    for t in grid.points() {
        let Some((a, rss)) = fitter.at(t) else {
            continue;
        };
        half_w.push((fitter.rss_drift - rss) / 2.0);
        if best.is_none_or(|b| rss < b.2) {
            best = Some((t, a, rss));
        }
    }
    let (t, a, rss) = best?;
    Some(WarmupFinding {
        amplitude: a,
        time_constant_s: t,
        w_stat: fitter.rss_drift - rss,
        log_bf: log_mean_exp(&half_w),
    })
}

/// `ln((1/n) sum_i exp(x_i))`, computed without overflow; `-inf` for an empty slice.
pub fn log_mean_exp(x: &[f64]) -> f64 {
    let m = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if !m.is_finite() {
        return m;
    }
    m + (x.iter().map(|v| (v - m).exp()).sum::<f64>() / x.len() as f64).ln()
}

/// The whitened block-mean differences of [`fit_warmup`], ready to fit a warm-up of any time
/// constant.
struct WarmupFitter {
    block_s: f64,
    chol: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    yw: DVector<f64>,
    ones: DVector<f64>,
    /// Residual sum of squares of the drift alone.
    rss_drift: f64,
}

impl WarmupFitter {
    fn new(
        block_means: &[f64],
        block_s: f64,
        c: &[f64; 5],
        effects: &[EffectParams],
    ) -> Option<Self> {
        if !usable_block_means(block_means) {
            return None;
        }
        let d: Vec<f64> = block_means.windows(2).map(|p| p[1] - p[0]).collect();
        let n = d.len();
        let chol = block_diff_covariance(block_means.len(), block_s, c, effects)?.cholesky()?;
        let yw = chol
            .l()
            .solve_lower_triangular(&DVector::from_column_slice(&d))?;
        let ones = chol
            .l()
            .solve_lower_triangular(&DVector::from_element(n, 1.0))?;
        let beta = ones.dot(&yw) / ones.norm_squared();
        let rss_drift = (&yw - &ones * beta).norm_squared();
        Some(Self {
            block_s,
            chol,
            yw,
            ones,
            rss_drift,
        })
    }

    /// `(A, rss)` of the drift plus a warm-up of time constant `t` (s).
    fn at(&self, t: f64) -> Option<(f64, f64)> {
        let n = self.yw.len();
        let e: Vec<f64> = (0..=n)
            .map(|i| warmup_block_shape(i, self.block_s, t))
            .collect();
        let de = DVector::from_iterator(n, e.windows(2).map(|p| p[1] - p[0]));
        let ew = self.chol.l().solve_lower_triangular(&de)?;
        let x = DMatrix::from_columns(&[self.ones.clone(), ew]);
        let beta = (x.transpose() * &x).try_inverse()? * x.transpose() * &self.yw;
        let rss = (&self.yw - &x * &beta).norm_squared();
        Some((beta[1], rss))
    }
}
