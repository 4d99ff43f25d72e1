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
    /// The whitened residual sum of squares of the drift alone per degree of freedom: about 1
    /// when the model's covariance of the block means is right (a check of its scale).
    pub null_scale: f64,
    /// `log_bf` with each `W(T)` divided by `max(1, null_scale)`: the evidence in units of the
    /// block means' own residual scale when that is above the model's (an F-type statistic;
    /// docs/gap.md, "Calibration").
    pub log_bf_scaled: f64,
    /// The p-value of `log_bf` under this run's own Gaussian null: the share of
    /// [`WARMUP_NULL_DRAWS`] draws of whitened block-mean differences `N(0, I)` (the fitted
    /// model's covariance, drift alone) whose `B`, through the same scan over `T`, reaches the
    /// observed one, `(1 + #{B_null >= B}) / (draws + 1)`. A level set per run from its own
    /// covariance and scan, so it needs no clean runs of the family (docs/gap.md,
    /// "Calibration").
    pub p_value: f64,
}

/// Rise of the curve's `r' S^-1 r` at which the warm-up's null takes the rate random walk `K`
/// ([`GapProblem::upper_bound`](super::problem::GapProblem::upper_bound)): 1 is the one-sided
/// profile bound at about 84%. The fitted `K` is often 0 on runs of an hour or two, and the
/// block means then wander more slowly than their covariance says. On 600 clean 1-hour runs
/// of the six families, p <= 0.02 in 22 (3.7%) at the fitted `K`, in 11 (1.8%) at the true
/// model and in 4 (0.7%) at this bound (docs/gap.md, "The warm-up's null level").
pub const WARMUP_K_DELTA: f64 = 1.0;

/// Draws of the Gaussian null behind [`WarmupFinding::p_value`].
pub const WARMUP_NULL_DRAWS: usize = 999;
/// Seed of those draws (fixed: the same evidence gives the same p-value).
const WARMUP_NULL_SEED: u64 = 0x3a7e_0b1f;

impl WarmupFinding {
    /// The warm-up's mean over each block.
    pub fn block_curve(&self, n_blocks: usize, block_s: f64) -> Vec<f64> {
        warmup_block_means(n_blocks, block_s, self.amplitude, self.time_constant_s)
    }
}

/// The block means of the warm-up `amplitude e^{-t/T}` (u/s) over blocks `0..n_blocks` of `tb`
/// s: [`warmup_block_curve`] scaled.
pub fn warmup_block_means(n_blocks: usize, tb: f64, amplitude: f64, t: f64) -> Vec<f64> {
    warmup_block_curve(n_blocks, tb, t)
        .into_iter()
        .map(|e| amplitude * e)
        .collect()
}

/// [`warmup_block_shape`] over blocks `0..n_blocks`: the block means of `e^{-t/T}`.
pub fn warmup_block_curve(n_blocks: usize, tb: f64, t: f64) -> Vec<f64> {
    (0..n_blocks)
        .map(|i| warmup_block_shape(i, tb, t))
        .collect()
}

/// The time constant (s) of the warm-up `A e^{-t/T}` that best fits `block_means` (u/s per
/// block of `block_s` s) beside a drift, as [`fit_warmup`] fits one (the covariance of `c`,
/// squared five terms, and the stationary `effects`): the least residual sum of squares over a
/// log grid of `T` from a block to the run's length (24 per decade, then 960 per decade around
/// the best: [`Grid::refined_min`]). Unlike [`fit_warmup`]'s scan (up to a quarter of the run)
/// it reaches the slow settlings a temperature gives; beyond the run a warm-up is a bend of the
/// rate the run does not show as one (a 25 Hz run of 2026 s put its best at 21 000 s with an
/// amplitude a hundred times the settling's). `None` when the block means cannot carry it.
pub fn best_warmup_time_constant(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<f64> {
    let fitter = WarmupFitter::new(block_means, block_s, c, effects)?;
    let run_s = block_s * block_means.len() as f64;
    let grid = Grid {
        lo: block_s,
        hi: run_s,
        per_decade: 24.0,
    };
    grid.refined_min(run_s, |t| fitter.at(t).map(|(_, rss, _)| rss))
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
    let mut cols: Vec<NullColumn> = Vec::new();
    for t in grid.points() {
        let Some((a, rss, col)) = fitter.at(t) else {
            continue;
        };
        cols.push(col);
        half_w.push((fitter.rss_drift - rss) / 2.0);
        if best.is_none_or(|b| rss < b.2) {
            best = Some((t, a, rss));
        }
    }
    let (t, a, rss) = best?;
    let null_scale = fitter.rss_drift / (fitter.yw.len().max(2) - 1) as f64;
    let scaled: Vec<f64> = half_w.iter().map(|h| h / null_scale.max(1.0)).collect();
    let log_bf = log_mean_exp(&half_w);
    let p_value = null_p_value(&fitter, &cols, log_bf);
    Some(WarmupFinding {
        amplitude: a,
        time_constant_s: t,
        w_stat: fitter.rss_drift - rss,
        log_bf,
        null_scale,
        log_bf_scaled: log_mean_exp(&scaled),
        p_value,
    })
}

/// One scanned `T` of the warm-up fit, for the null draws: the whitened warm-up column and the
/// inverse of the normal matrix of `[1, e_w]`.
struct NullColumn {
    ew: DVector<f64>,
    /// `(X'X)^-1` of the drift and warm-up columns, row-major 2x2.
    inv: [f64; 4],
}

/// [`WarmupFinding::p_value`]: `B` of `N(0, I)` whitened differences through the same columns.
/// For whitened data `y`, `W(T) = b' (X'X)^-1 b - (1'y)^2 / |1|^2` with `b = (1'y, e_w'y)`.
fn null_p_value(fitter: &WarmupFitter, cols: &[NullColumn], observed: f64) -> f64 {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    if cols.is_empty() || !observed.is_finite() {
        return f64::NAN;
    }
    let n = fitter.yw.len();
    let ones_sq = fitter.ones.norm_squared();
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(WARMUP_NULL_SEED);
    let mut half_w = vec![0.0; cols.len()];
    let mut at_least = 0usize;
    for _ in 0..WARMUP_NULL_DRAWS {
        let y = DVector::from_fn(n, |_, _| StandardNormal.sample(&mut rng));
        let b0 = fitter.ones.dot(&y);
        let drift = b0 * b0 / ones_sq;
        for (h, c) in half_w.iter_mut().zip(cols) {
            let b1 = c.ew.dot(&y);
            let q = c.inv[0] * b0 * b0 + 2.0 * c.inv[1] * b0 * b1 + c.inv[3] * b1 * b1;
            *h = (q - drift) / 2.0;
        }
        if log_mean_exp(&half_w) >= observed {
            at_least += 1;
        }
    }
    (1 + at_least) as f64 / (WARMUP_NULL_DRAWS + 1) as f64
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

    /// `(A, rss)` of the drift plus a warm-up of time constant `t` (s), and its column for
    /// the null draws.
    fn at(&self, t: f64) -> Option<(f64, f64, NullColumn)> {
        let n = self.yw.len();
        let e = warmup_block_curve(n + 1, self.block_s, t);
        let de = DVector::from_iterator(n, e.windows(2).map(|p| p[1] - p[0]));
        let ew = self.chol.l().solve_lower_triangular(&de)?;
        let x = DMatrix::from_columns(&[self.ones.clone(), ew.clone()]);
        let inv = (x.transpose() * &x).try_inverse()?;
        let beta = &inv * x.transpose() * &self.yw;
        let rss = (&self.yw - &x * &beta).norm_squared();
        let col = NullColumn {
            ew,
            inv: [inv[(0, 0)], inv[(0, 1)], inv[(1, 0)], inv[(1, 1)]],
        };
        Some((beta[1], rss, col))
    }
}
