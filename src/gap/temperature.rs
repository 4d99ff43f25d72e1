//! The temperature effect: a bias that follows the unit's temperature, `b(t) = c (T(t) - T_ref)`
//! with `c` in u/s per degC (docs/gap.md, "Temperature"). When the input carries a temperature
//! (a `temperature_c` text column, or a descriptor's temperature field), it is gathered beside
//! each channel as a [`GapEvidence`] of its own, fed `T tau0` as if it were an increment, so its
//! block means and its AVAR curve share the channel's blocks and cluster sizes exactly.
//!
//! Fit: generalised least squares of the first differences of the channel's block-mean rate on
//! a drift, the first differences of the temperature's block means and, when a warm-up is in the
//! model, the first differences of its block shape (the warm-up and the temperature fitted
//! jointly):
//!
//! ```text
//! b_{i+1} - b_i = r + c (T_{i+1} - T_i) [+ A (e_{i+1} - e_i)] + noise,
//! ```
//!
//! the noise covariance from the fitted model ([`block_diff_covariance`], five terms plus the
//! stationary effects found). The differences remove the unknown constant (bias and `T_ref`);
//! the drift `r` takes up a rate ramp. `c` is the GLS estimate, its standard error
//! `sqrt((X' C^-1 X)^-1_cc)`, scaled up by `sqrt(rss / (n - p))` when the residuals are larger
//! than the model says (never down), and the interval is `c +- 1.96 se`. The test statistic is
//! `z = c / se` (about N(0, 1) without a temperature effect: the regressor is given, nothing
//! is scanned).
//!
//! On the curve, the temperature-driven bias is a deterministic signal whose AVAR on this record
//! is `c^2` times the temperature curve's own AVAR at each cluster size (computed by the same
//! estimator at the same strides); it enters the curve fit as a fixed offset, as a warm-up's
//! exact AVAR does.
//!
//! A bias that bends with the temperature (a quadratic over a chamber's -40..85 degC) has a
//! second column, `q ((T_{i+1} - T_ref)^2 - (T_i - T_ref)^2)`, `T_ref` the run's mean block
//! temperature, so `c` is the slope there. It is taken in when its own settled `|z|` passes the
//! same threshold; its AVAR on the curve is then that of the fitted signal read between block
//! centres ([`block_signal_avar`]; docs/gap.md, "A temperature that bends (session 51)"). A
//! unit whose temperature lags the recorded one has the recorded block means lagged through a
//! first order of a scanned time constant in their place ([`scan_lag`]; "A temperature that
//! lags (session 51)"). Both are tried only where the temperature turns back over its range
//! and kept only where they stand beside the best warm-up.

use nalgebra::{DMatrix, DVector};

use super::block_cov::{block_diff_covariance, usable_block_means};
use super::diagnose::k2_upper;
use super::effects::{EffectParams, TemperatureLag, TemperatureQuadratic};
use super::evidence::EvidenceSnapshot;
use super::k_profile::profile_k2;
use super::problem::{GapProblem, GlsFit, ModelSpec};
use super::warmup::{best_warmup_time_constant, warmup_block_curve};
use crate::sim::effects::TemperatureProfile;

/// The two-sided 97.5% normal quantile of the 95% interval.
pub const Z95: f64 = 1.959_963_984_540_054;

/// The temperature effect is taken in when `|z|` exceeds this. The regressor is given, not
/// searched, so under the null `z` is about N(0, 1); the threshold was set on clean runs with a
/// temperature profile and no coefficient (docs/gap.md, "Temperature").
pub const TEMPERATURE_Z: f64 = 4.0;

/// The `|z|` at which the temperature is kept on its time-domain evidence alone when the
/// curve's gap does not fall with it in (the bookkeeping, `diagnose.rs::kept_in_time`):
/// twice [`TEMPERATURE_Z`], above the 4.1-5.2 that slow signals of the bias resembling the
/// temperature reached on runs without a coefficient (docs/gap.md, "Bookkeeping"). Session 36
/// tried 6 (a MEMS gyro settling 25 degC in two hours had its temperature at `|z|` 5.3-7.7
/// dropped in 5 of 20 runs); a review then found a bias warm-up of 2200 s beside a temperature
/// settling over 1500 s, no coefficient, named at `|z|` 6.1-7.9 in 5 of 17 runs, and it is 8
/// again: a temperature that only settles is a warm-up's shape, and the two are told apart by
/// its cycles, not by `|z|`.
pub const TEMPERATURE_Z_ALONE: f64 = 8.0;

/// The second order of a temperature coefficient fitted to the block means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadraticFinding {
    /// `q`, u/s per degC^2.
    pub coefficient: f64,
    /// Its standard error (u/s per degC^2).
    pub std_error: f64,
    /// `T_ref` (degC), the mean of the run's block temperatures.
    pub reference_c: f64,
}

impl QuadraticFinding {
    /// `q / se`.
    pub fn z(&self) -> f64 {
        self.coefficient / self.std_error
    }
}

/// A temperature coefficient fitted to the block means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TemperatureFinding {
    /// `c`, u/s per degC (the slope at the second order's reference when there is one).
    pub coefficient: f64,
    /// Its standard error (u/s per degC).
    pub std_error: f64,
    /// `c / se`.
    pub z: f64,
    /// Residual variance against the model's: `rss / (n - p)`, about 1 when the noise model is
    /// right (the standard error is scaled by its square root when it is above 1).
    pub scale: f64,
    /// The second order, when fitted.
    pub quadratic: Option<QuadraticFinding>,
    /// The unit's temperature lagging the recorded one, when found ([`scan_lag`]): the
    /// coefficients are the lagged temperature's.
    pub lag: Option<TemperatureLag>,
    /// The coefficient's standard error from the lag's own uncertainty (u/s per degC), in
    /// quadrature in `std_error` and `z` ([`TemperatureFinding::with_lag_spread`]); 0 without
    /// a lag.
    pub lag_se: f64,
}

impl TemperatureFinding {
    /// With `lag_se` (u/s per degC) in quadrature in its standard error and `z`: the
    /// coefficient is fitted at the lag found, and moves with it (a longer lag, a smaller gain
    /// at the temperature's changes, a larger coefficient); half the spread of the
    /// coefficients at the lag interval's ends over 1.96 is that part of its error (the delta
    /// method). Without it, a simulated unit's 95% interval (0.503-0.569) excluded its truth
    /// (0.5) at a lag of 680 s (571-809) against 600.
    pub fn with_lag_spread(mut self, lag_se: f64) -> Self {
        self.std_error = self.std_error.hypot(lag_se);
        self.z = self.coefficient / self.std_error;
        self.lag_se = lag_se;
        self
    }

    /// A refit of `fitted` (a finding of the same temperature) with `fitted`'s lag and the lag's
    /// part of the error: the fits themselves are of the lagged series and know no lag.
    pub fn with_lag_of(self, fitted: &TemperatureFinding) -> Self {
        TemperatureFinding {
            lag: fitted.lag,
            ..self
        }
        .with_lag_spread(fitted.lag_se)
    }

    /// The largest `|z|` of its terms: the temperature is named when it passes the threshold.
    pub fn strongest_z(&self) -> f64 {
        self.quadratic
            .map_or(0.0, |q| q.z().abs())
            .max(self.z.abs())
    }

    /// The 95% interval of the coefficient (u/s per degC).
    pub fn interval(&self) -> (f64, f64) {
        (
            self.coefficient - Z95 * self.std_error,
            self.coefficient + Z95 * self.std_error,
        )
    }

    /// The record's effect.
    pub fn params(&self) -> EffectParams {
        let (lo, hi) = self.interval();
        EffectParams::Temperature {
            coefficient: self.coefficient,
            lo,
            hi,
            quadratic: self.quadratic.map(|q| TemperatureQuadratic {
                coefficient: q.coefficient,
                lo: q.coefficient - Z95 * q.std_error,
                hi: q.coefficient + Z95 * q.std_error,
                reference_c: q.reference_c,
            }),
            lag: self.lag,
        }
    }

    /// The temperature-driven bias over each block (u/s), up to a constant.
    pub fn block_curve(&self, temperature_block_means: &[f64]) -> Vec<f64> {
        temperature_signal(
            self.coefficient,
            self.quadratic.map(|q| (q.coefficient, q.reference_c)),
            temperature_block_means,
        )
    }
}

/// `c T + q (T - T_ref)^2` at each temperature of `temperature_c` (u/s, up to a constant;
/// `quadratic` is `(q, T_ref)`).
pub fn temperature_signal(
    coefficient: f64,
    quadratic: Option<(f64, f64)>,
    temperature_c: &[f64],
) -> Vec<f64> {
    temperature_c
        .iter()
        .map(|&t| coefficient * t + quadratic.map_or(0.0, |(q, r)| q * (t - r) * (t - r)))
        .collect()
}

/// Where a channel's blocks lie on its record, for the AVAR of a signal known by its block
/// means ([`block_signal_avar`]).
#[derive(Debug, Clone, PartialEq)]
pub struct BlockPlacement {
    /// Samples per block.
    pub block_len: u64,
    /// Samples before the first block.
    pub lead: u64,
    /// The curve's cluster sizes.
    pub ms: Vec<u64>,
    /// Samples on the record.
    pub n_inc: u64,
}

impl BlockPlacement {
    /// The blocks of `snap` on the curve of `prob`.
    pub fn of(prob: &GapProblem, snap: &EvidenceSnapshot) -> Self {
        BlockPlacement {
            block_len: snap.block_len,
            lead: snap.block_first as u64 * snap.block_len,
            ms: prob.ms.clone(),
            n_inc: prob.n_inc,
        }
    }
}

/// The overlapped AVAR (u^2/s^2) at each cluster size of `at` of a slow signal known by its
/// block means `values` (u/s): the signal is read as the straight lines between block centres,
/// held flat before the first centre and after the last. With `S(x)` its integral from the
/// record's start (exact: piecewise quadratic), a cluster mean is `(S(k + m) - S(k)) / m` and
/// `AVAR(m) = mean_k (S(k + 2m) - 2 S(k + m) + S(k))^2 / (2 m^2)` (docs/theory.md section 1),
/// the mean over starts `k` taken by the midpoint rule on runs of `max(m, block) / 32`
/// samples (the summand varies on the larger of the two). A signal that changes within a block
/// (a temperature-driven bias follows a chamber over minutes, the blocks are seconds) is all
/// that is left out. NaN values give 0 (no signal known there).
pub fn block_signal_avar(values: &[f64], at: &BlockPlacement) -> Vec<f64> {
    let nb = values.len();
    let n = at.n_inc as f64;
    let len = at.block_len as f64;
    if nb == 0 || len <= 0.0 || values.iter().any(|v| !v.is_finite()) {
        return vec![0.0; at.ms.len()];
    }
    // Knots: the record's start, the block centres, the record's end; the signal's value at
    // each, and S at each.
    let mut xs = Vec::with_capacity(nb + 2);
    let mut ys = Vec::with_capacity(nb + 2);
    xs.push(0.0);
    ys.push(values[0]);
    for (j, &v) in values.iter().enumerate() {
        let x = at.lead as f64 + (j as f64 + 0.5) * len;
        if x > *xs.last().unwrap_or(&0.0) && x < n {
            xs.push(x);
            ys.push(v);
        }
    }
    xs.push(n.max(*xs.last().unwrap_or(&0.0)));
    ys.push(values[nb - 1]);
    let mut s_at = vec![0.0; xs.len()];
    for i in 1..xs.len() {
        s_at[i] = s_at[i - 1] + 0.5 * (ys[i] + ys[i - 1]) * (xs[i] - xs[i - 1]);
    }
    let integral = |x: f64| -> f64 {
        let x = x.clamp(0.0, n);
        let i = xs.partition_point(|&k| k <= x).clamp(1, xs.len() - 1) - 1;
        let w = xs[i + 1] - xs[i];
        let d = x - xs[i];
        if w <= 0.0 {
            return s_at[i];
        }
        let slope = (ys[i + 1] - ys[i]) / w;
        s_at[i] + ys[i] * d + 0.5 * slope * d * d
    };
    at.ms
        .iter()
        .map(|&m| {
            let mf = m as f64;
            let span = n - 2.0 * mf;
            if m == 0 || span < 0.0 {
                return 0.0;
            }
            let h = (mf.max(len) / 32.0).max(1.0);
            let runs = (span / h).floor() as u64 + 1;
            let width = span / runs as f64;
            let mut sum = 0.0;
            for r in 0..runs {
                let k = (r as f64 + 0.5) * width;
                let d = integral(k + 2.0 * mf) - 2.0 * integral(k + mf) + integral(k);
                sum += d * d;
            }
            sum / runs as f64 / (2.0 * mf * mf)
        })
        .collect()
}

/// The temperature's block means (degC) from its evidence (fed `T tau0` per step), over the
/// channel's blocks in `snap` (each evidence leaves out its own short blocks at the start:
/// [`EvidenceSnapshot::block_first`]); NaN where the temperature has none.
pub fn temperature_blocks(snap: &EvidenceSnapshot, temp: &EvidenceSnapshot) -> Vec<f64> {
    (0..snap.block_means.len())
        .map(|j| {
            (snap.block_first + j)
                .checked_sub(temp.block_first)
                .and_then(|i| temp.block_means.get(i))
                .copied()
                .unwrap_or(f64::NAN)
        })
        .collect()
}

/// The AVAR (degC^2) of the temperature at each cluster size of `ms`, from its evidence; `None`
/// when one of them is missing (the two evidences did not see the same steps).
pub fn temperature_avar(temp: &EvidenceSnapshot, ms: &[u64]) -> Option<Vec<f64>> {
    ms.iter()
        .map(|&m| temp.curve.iter().find(|p| p.m == m).map(|p| p.avar))
        .collect()
}

/// The temperature's AVAR (degC^2 at each cluster size of `ms`) without the column's own white
/// noise: `AVAR_T(m) - AVAR_T(m_0) m_0 / m`, `m_0` the shortest cluster, floored at 0. A
/// sensor's noise and rounding on each sample are white in the evidence fed `T tau0` (a white
/// rate: `sigma_T^2 tau0 / tau`), and at the shortest cluster they are all of it; the bias
/// follows the unit's temperature, not the column's noise. A slow temperature's own AVAR at
/// `m_0` is `(dT/dt)^2 tau_0^2 / 2`, so what this takes from it at longer clusters is below
/// that: nothing against its growth as `tau^2`. `None` as [`temperature_avar`].
pub fn temperature_avar_without_noise(temp: &EvidenceSnapshot, ms: &[u64]) -> Option<Vec<f64>> {
    let avar = temperature_avar(temp, ms)?;
    let (&m0, &a0) = ms.first().zip(avar.first())?;
    Some(
        ms.iter()
            .zip(&avar)
            .map(|(&m, &a)| (a - a0 * m0 as f64 / m as f64).max(0.0))
            .collect(),
    )
}

/// The temperature effect in the model of one channel: the finding and the recorded
/// temperature's block means (degC).
#[derive(Debug, Clone, PartialEq)]
pub struct TemperatureInModel {
    pub finding: TemperatureFinding,
    pub blocks_c: Vec<f64>,
    /// The recorded temperature's AVAR without its white noise (degC^2 at the curve's cluster
    /// sizes, [`temperature_avar_without_noise`]).
    pub avar_c2: Vec<f64>,
    /// The largest `K^2` (u^2/s^3) the base model's curve allows, the top of the random walk's
    /// profile on the block means ([`TemperatureInModel::refit`]).
    pub k2_hi: f64,
    /// The channel's blocks on its record (the AVAR of a second order's signal).
    pub placement: BlockPlacement,
}

impl TemperatureInModel {
    /// Its AVAR on the curve (u^2/s^2 at each cluster size): `c^2 AVAR_T`, the recorded
    /// temperature's AVAR without the column's white noise; with a second order, that of the
    /// fitted signal read between block centres ([`block_signal_avar`]). Until session 51 the
    /// column's noise was in: the bias follows the unit's temperature, not the sensor's noise,
    /// and a review's 1 Hz gyro with a column noisy by 0.02 degC (rounded to 0.01) had `N` at
    /// half its truth, the column's white noise times `c^2` taken out of the curve (docs/gap.md,
    /// "A temperature that bends (session 51)").
    pub fn curve_offset(&self) -> Vec<f64> {
        if self.finding.quadratic.is_some() || self.finding.lag.is_some() {
            return block_signal_avar(&self.finding.block_curve(&self.blocks_c), &self.placement);
        }
        let c2 = self.finding.coefficient.powi(2);
        self.avar_c2.iter().map(|v| c2 * v).collect()
    }

    /// The channel's block means with the temperature-driven bias taken out.
    pub fn remove_from(&self, block_means: &[f64]) -> Vec<f64> {
        block_means
            .iter()
            .zip(self.finding.block_curve(&self.blocks_c))
            .map(|(b, t)| b - t)
            .collect()
    }

    /// Refits the coefficient with more of the model known: the five terms `c`, the
    /// stationary `effects` and `extra` block curves fitted jointly (a warm-up's shape, with its
    /// amplitude).
    ///
    /// The random walk in the noise covariance is at least what the block means themselves
    /// show with the temperature-driven bias and the `extra` curves taken out: the maximum
    /// likelihood `K^2` of their differences on `[0, k2_hi]` ([`profile_k2`], as the warm-up
    /// and jump tests read their null). Once the temperature's AVAR is in the curve's model, the
    /// curve's own fit often sets `K` to 0 (the temperature took the long-tau rise the base fit
    /// gave `K` and `R`); the slow wander the unit still has then left the covariance, and the
    /// interval was too narrow: a probe of FOG and pendulous-accelerometer units with a
    /// temperature ramp (session 36) covered the coefficient in 15 of 19 named runs, the
    /// intervals with `K` fitted 0 half as wide as the others (docs/gap.md, "Temperature").
    pub fn refit(
        &mut self,
        block_means: &[f64],
        block_s: f64,
        c: &[f64; 5],
        effects: &[EffectParams],
        extra: &[Vec<f64>],
    ) {
        let mut rest = self.remove_from(block_means);
        for e in extra {
            for (r, v) in rest.iter_mut().zip(e) {
                *r -= v;
            }
        }
        let c = with_block_random_walk(c, &rest, block_s, effects, self.k2_hi);
        let reference = self.finding.quadratic.map(|q| q.reference_c);
        if let Some(f) = fit_temperature_in(
            block_means,
            &self.blocks_c,
            block_s,
            &c,
            effects,
            extra,
            reference,
        ) {
            self.finding = f.with_lag_of(&self.finding);
        }
    }
}

/// A warm-up in the temperature's place in the block means: `A e^{-t/T}` fitted there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WarmupInPlace {
    /// `A`, u/s.
    pub amplitude: f64,
    /// `T`, s.
    pub time_constant_s: f64,
    /// Its `A / se` on the block means, alone.
    pub z: f64,
}

/// Whether the temperature-driven bias resembles a warm-up, and the warm-ups that would take
/// its place ([`TemperatureInModel::warmup_lookalike`]; docs/gap.md, "Alternatives").
#[derive(Debug, Clone, PartialEq)]
pub struct WarmupLookalike {
    /// The temperature's `z` fitted beside the warm-up of its own settling time constant.
    pub z_temperature_beside: f64,
    /// The warm-up at the temperature's settling time constant, then the one that fits the
    /// block means best when its time constant differs.
    pub warmups: Vec<WarmupInPlace>,
}

impl TemperatureInModel {
    /// The temperature found on `block_means` (u/s per block) with the noise of `c` (squared
    /// five terms) and the stationary `effects`, refitted once with the random walk the block
    /// means show ([`TemperatureInModel::refit`]). `None` when the test cannot be formed.
    pub fn fitted(
        prob: &GapProblem,
        snap: &EvidenceSnapshot,
        temp: &EvidenceSnapshot,
        c: &[f64; 5],
        effects: &[EffectParams],
        k2_hi: f64,
    ) -> Option<Self> {
        let block_s = snap.block_len as f64 * snap.tau0_s;
        let blocks_c = temperature_blocks(snap, temp);
        let avar_c2 = temperature_avar_without_noise(temp, &prob.ms)?;
        let finding = fit_shape(&snap.block_means, &blocks_c, block_s, c, effects, k2_hi)?;
        Some(TemperatureInModel {
            finding,
            blocks_c,
            avar_c2,
            k2_hi,
            placement: BlockPlacement::of(prob, snap),
        })
    }

    /// Whether a warm-up could take the temperature's place in `block_means`, and the warm-ups
    /// that would. A warm-up at the temperature's own settling time constant
    /// ([`settling_profile`]) is fitted beside the temperature: when the temperature only
    /// settles, `c T(t)` is `c (T_end + (T_0 - T_end) e^{-t/T})`, a warm-up of amplitude
    /// `c (T_0 - T_end)` at that time constant, the block means cannot tell the two apart and the
    /// temperature's `z` beside it falls to noise; a cycle (or any change of the temperature
    /// that is not one exponential) keeps it. The warm-ups given in the temperature's place are
    /// that one and the one that fits the block means best, its time constant scanned
    /// ([`best_warmup_time_constant`]): the bias's own, which a review found missing (a bias
    /// warm-up of 2200 s beside a chamber settling over 1500 s, no coefficient, was listed at
    /// the chamber's 1500 s and the unit's own warm-up never shown). The noise is as in
    /// [`TemperatureInModel::refit`]. `None` when the temperature's block means have no
    /// settling profile or the block means cannot carry the fit.
    pub fn warmup_lookalike(
        &self,
        block_means: &[f64],
        block_s: f64,
        c: &[f64; 5],
        effects: &[EffectParams],
    ) -> Option<WarmupLookalike> {
        let settling_tc = settling_profile(&self.blocks_c, block_s)?.time_constant_s;
        let shape_of = |tc: f64| warmup_block_curve(block_means.len(), block_s, tc);
        let settling_shape = shape_of(settling_tc);
        let mut beside = self.clone();
        beside.refit(
            block_means,
            block_s,
            c,
            effects,
            std::slice::from_ref(&settling_shape),
        );
        let cw = with_block_random_walk(
            c,
            &self.remove_from(block_means),
            block_s,
            effects,
            self.k2_hi,
        );
        let mut tcs = vec![settling_tc];
        tcs.extend(
            best_warmup_time_constant(block_means, block_s, &cw, effects)
                .filter(|tc| (tc / settling_tc - 1.0).abs() > 0.01),
        );
        let warmups = tcs
            .into_iter()
            .filter_map(|tc| {
                let f = fit_shape(block_means, &shape_of(tc), block_s, c, effects, self.k2_hi)?;
                Some(WarmupInPlace {
                    amplitude: f.coefficient,
                    time_constant_s: tc,
                    z: f.z,
                })
            })
            .collect();
        Some(WarmupLookalike {
            z_temperature_beside: beside.finding.z,
            warmups,
        })
    }
}

/// The amplitude of a given block curve `shape` in `block_means` ([`fit_temperature`] with
/// `shape` as the regressor: a temperature in degC gives its coefficient, a warm-up's block
/// shape its amplitude), refitted once with the random walk the block means show with it taken
/// out, as [`TemperatureInModel::refit`] does: the same noise for either explanation, so their
/// `z` compare.
pub fn fit_shape(
    block_means: &[f64],
    shape: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    k2_hi: f64,
) -> Option<TemperatureFinding> {
    let first = fit_temperature(block_means, shape, block_s, c, effects, &[])?;
    let rest: Vec<f64> = block_means
        .iter()
        .zip(shape)
        .map(|(b, s)| b - first.coefficient * s)
        .collect();
    let c = with_block_random_walk(c, &rest, block_s, effects, k2_hi);
    fit_temperature(block_means, shape, block_s, &c, effects, &[]).or(Some(first))
}

/// `c` (squared five terms) with `K^2` raised, never lowered, to the maximum likelihood `K^2`
/// on `[0, k2_hi]` of the block means `rest` (the temperature-driven bias taken out): the
/// random walk the unit's block means show stays in the covariance the coefficient is judged
/// with ([`profile_k2`]; [`TemperatureInModel::refit`], [`fixed_coefficient_drop`]).
fn with_block_random_walk(
    c: &[f64; 5],
    rest: &[f64],
    block_s: f64,
    effects: &[EffectParams],
    k2_hi: f64,
) -> [f64; 5] {
    let mut c = *c;
    if let Some(k2) = profile_k2(rest, block_s, &c, effects, k2_hi) {
        c[3] = c[3].max(k2);
    }
    c
}

/// The first differences of block series whitened by the noise model's block-difference
/// covariance ([`block_diff_covariance`]), a drift projected out: a series' squared norm is its
/// whitened residual sum of squares with the drift fitted, and two series' dot product their
/// whitened cross product ([`fixed_coefficient_drop`], [`scan_lag`]).
struct DiffWhitening {
    /// The covariance's Cholesky factor `L`.
    l: DMatrix<f64>,
    /// `L^-1 1`, the drift whitened, and its squared norm.
    u: DVector<f64>,
    uu: f64,
}

impl DiffWhitening {
    /// For `nb` block means of `block_s` s under the five terms `c` and the stationary
    /// `effects`; `None` when the covariance is not positive definite.
    fn new(nb: usize, block_s: f64, c: &[f64; 5], effects: &[EffectParams]) -> Option<Self> {
        let l = block_diff_covariance(nb, block_s, c, effects)?
            .cholesky()?
            .l();
        let u = l.solve_lower_triangular(&DVector::from_element(nb - 1, 1.0))?;
        let uu = u.norm_squared();
        (uu > 0.0).then_some(DiffWhitening { l, u, uu })
    }

    /// `v`'s first differences, whitened, the drift projected out.
    fn apply(&self, v: &[f64]) -> Option<DVector<f64>> {
        let d = DVector::from_iterator(v.len() - 1, v.windows(2).map(|p| p[1] - p[0]));
        let y = self.l.solve_lower_triangular(&d)?;
        let k = self.u.dot(&y) / self.uu;
        Some(y - &self.u * k)
    }
}

/// The time-domain test of a coefficient fitted on another run, held fixed on a held-out run
/// (`gap::holdout`): the drop of the whitened residual sum of squares of the held-out block
/// means' first differences when `c (T_{i+1} - T_i)` is taken out, the drift fitted either way,
/// and the residual variance with it out (`rss / (n - 1)`, about 1 when the noise model is
/// right). The noise covariance is the held-out model's (`c5`, `effects`) with the random walk
/// at least the maximum likelihood `K^2` of the block means with `c T` taken out, on
/// `[0, k2_hi]` (as [`TemperatureInModel::refit`]). For a fixed known signal of whitened size
/// `delta` the drop is about `N(delta^2, 4 delta^2)` when the held-out run has it and
/// `N(-delta^2, 4 delta^2)` when it has not (`holdout::carries`). Returns the drop, the scale
/// and `delta^2`, the drop expected if the held-out run has the effect (the whitened size of
/// `c (T_{i+1} - T_i)` with the drift fitted out, squared): how much the held-out run can show
/// at all. `None` when the series are not usable.
pub fn fixed_coefficient_drop(
    block_means: &[f64],
    temperature: &[f64],
    block_s: f64,
    c5: &[f64; 5],
    effects: &[EffectParams],
    coefficient: f64,
    k2_hi: f64,
) -> Option<(f64, f64, f64)> {
    let nb = block_means.len();
    if !usable_block_means(block_means)
        || temperature.len() != nb
        || !temperature.iter().all(|t| t.is_finite())
        || !coefficient.is_finite()
    {
        return None;
    }
    let rest: Vec<f64> = block_means
        .iter()
        .zip(temperature)
        .map(|(b, t)| b - coefficient * t)
        .collect();
    let c = with_block_random_walk(c5, &rest, block_s, effects, k2_hi);
    let w = DiffWhitening::new(nb, block_s, &c, effects)?;
    // The whitened residual sum of squares with the drift fitted.
    let rss = |v: &[f64]| Some(w.apply(v)?.norm_squared());
    let (rss0, rss1) = (rss(block_means)?, rss(&rest)?);
    let signal: Vec<f64> = temperature.iter().map(|t| coefficient * t).collect();
    let expected = rss(&signal)?;
    let dof = (nb - 1).saturating_sub(1).max(1) as f64;
    Some((rss0 - rss1, rss1 / dof, expected))
}

/// Step 0 of the diagnosis: the temperature's coefficient on the block means with the base
/// model's noise, then again with the noise of the model refitted with the temperature's AVAR
/// in, until `z` settles (at most [`TEMPERATURE_ROUNDS`] refits); taken in when the last `|z|`
/// exceeds `z_crit`. The base fit's `K` and `R` hold the temperature-driven wander when the
/// curve shows it (a temperature cycle of tens of minutes raises the curve there), which widens
/// the first interval: on a 1.4 h run with a 25 min cycle the first `z` was 3.9 and the
/// refitted one far above 4, the coefficient the same (docs/gap.md, "Temperature"). Returns
/// the effect and the curve fit with its offset in, or `None` when there is no temperature
/// effect (or no usable temperature).
pub fn enter_temperature(
    prob: &GapProblem,
    snap: &EvidenceSnapshot,
    temp: &EvidenceSnapshot,
    base: &GlsFit,
    z_crit: f64,
) -> Option<(TemperatureInModel, GlsFit)> {
    let block_s = snap.block_len as f64 * snap.tau0_s;
    let blocks_c = temperature_blocks(snap, temp);
    let avar_c2 = temperature_avar_without_noise(temp, &prob.ms)?;
    // The block means' noise comes from five terms fitted through the filter of the
    // covariance when a pass has one: without it a unit's low-pass is taken up by B (twelve
    // times its value on a review's accelerometer behind a CIC and an 80 Hz first order), and
    // the block means' covariance, 150 times too wide, put a temperature that the data show at
    // z 16 at z 1.6 (docs/gap.md, "The temperature behind a filter (session 45)"). The fit
    // returned is the curve's without the filter, the effects' starting point.
    let noise_spec = |offset: Option<Vec<f64>>| ModelSpec {
        offset,
        filter: prob.cov_filter,
        ..ModelSpec::default()
    };
    let noise_base = match prob.cov_filter {
        Some(_) => prob.gls(&noise_spec(None)).unwrap_or_else(|| base.clone()),
        None => base.clone(),
    };
    let first = fit_temperature(
        &snap.block_means,
        &blocks_c,
        block_s,
        &noise_base.five_terms(),
        &[],
        &[],
    )?;
    tracing::debug!(
        coefficient = first.coefficient,
        z = first.z,
        scale = first.scale,
        blocks = blocks_c.len(),
        "the temperature's first fit"
    );
    let mut t = TemperatureInModel {
        finding: first,
        blocks_c,
        avar_c2,
        k2_hi: k2_upper(prob, &ModelSpec::default(), base),
        placement: BlockPlacement::of(prob, snap),
    };
    let spec = |t: &TemperatureInModel| ModelSpec {
        offset: Some(t.curve_offset()),
        ..ModelSpec::default()
    };
    // Refits until the named term's `z` (the second order's, once it is in) settles; the
    // noise of the last one is returned.
    let settle = |t: &mut TemperatureInModel| -> Option<[f64; 5]> {
        let z_of = |f: &TemperatureFinding| f.quadratic.map_or(f.z, |q| q.z());
        let mut c = noise_base.five_terms();
        for _ in 0..TEMPERATURE_ROUNDS {
            let z = z_of(&t.finding);
            let fit = prob.gls(&noise_spec(Some(t.curve_offset())))?;
            c = fit.five_terms();
            t.refit(&snap.block_means, block_s, &c, &[], &[]);
            tracing::debug!(
                coefficient = t.finding.coefficient,
                z = t.finding.z,
                quadratic = ?t.finding.quadratic,
                scale = t.finding.scale,
                "the temperature refitted with its AVAR in the curve's model"
            );
            if (z_of(&t.finding) - z).abs() <= 0.01 * z.abs().max(1.0) {
                break;
            }
        }
        Some(c)
    };
    let mut c_linear = settle(&mut t)?;
    let fidelity = block_fidelity(&t);
    tracing::debug!(fidelity, "the temperature read between block centres");
    // A bend in temperature is told from a bend in time (a warm-up, a settling) only where the
    // temperature comes back over its own range: a settling temperature's square and lag are
    // other settlings, which took a review's accelerometer warm-up (no temperature effect) as a
    // second order at `|z|` 5.3 and halved the warm-up found beside it.
    let turns = temperature_turns(&t.blocks_c);
    let faithful = fidelity.is_some_and(|e| e <= BLOCK_FIDELITY) && turns >= 1;
    tracing::debug!(turns, "the temperature's turns");
    // And a bend or a lag is kept only if it still stands beside the warm-up that fits the
    // block means best (its block shape a column beside the temperature's): the review's
    // accelerometer warm-up of 165 s, under a temperature that turned twice, had the second
    // order at `|z|` 5.3 alone.
    let warmup_shape = best_warmup_time_constant(&snap.block_means, block_s, &c_linear, &[])
        .map(|tc| warmup_block_curve(snap.block_means.len(), block_s, tc));
    let beside_warmup = |blocks: &[f64], c5: &[f64; 5], reference: Option<f64>| {
        let shape = warmup_shape.as_ref()?;
        fit_temperature_in(
            &snap.block_means,
            blocks,
            block_s,
            c5,
            &[],
            std::slice::from_ref(shape),
            reference,
        )
    };
    // The unit's temperature lagging the recorded one (docs/gap.md, "A temperature that lags
    // (session 51)"): the lagged temperature in the recorded one's place, refitted as the
    // slope is, kept when its settled `|z|` passes the threshold.
    if let Some(lag) =
        scan_lag(&snap.block_means, &t.blocks_c, block_s, &c_linear).filter(|_| faithful)
    {
        let mut lagged = t.clone();
        lagged.blocks_c = lagged_blocks(&t.blocks_c, block_s, lag.time_constant);
        tracing::debug!(?lag, "the temperature's lag");
        if let Some(f) = fit_temperature(
            &snap.block_means,
            &lagged.blocks_c,
            block_s,
            &c_linear,
            &[],
            &[],
        ) {
            lagged.finding = TemperatureFinding {
                lag: Some(lag),
                ..f
            };
            // Beside the warm-up: the lagged coefficient still named, and still beating the
            // recorded temperature by LAG_DROP.
            let lagged_c = lagged.blocks_c.clone();
            let stands = |c5: &[f64; 5]| {
                let with = beside_warmup(&lagged_c, c5, None);
                let without = beside_warmup(&t.blocks_c, c5, None);
                match (with, without) {
                    (Some(w), Some(o)) => w.z.abs() > z_crit && w.z * w.z - o.z * o.z >= LAG_DROP,
                    _ => true,
                }
            };
            if let Some(c) =
                settle(&mut lagged).filter(|c| lagged.finding.z.abs() > z_crit && stands(c))
            {
                let at = |tc: f64| {
                    let blocks = lagged_blocks(&t.blocks_c, block_s, tc);
                    fit_temperature(&snap.block_means, &blocks, block_s, &c, &[], &[])
                        .map(|f| f.coefficient)
                };
                let spread = match (at(lag.lo), at(lag.hi)) {
                    (Some(a), Some(b)) => (a - b).abs() / (2.0 * Z95),
                    _ => 0.0,
                };
                lagged.finding = lagged.finding.with_lag_spread(spread);
                t = lagged;
                c_linear = c;
            }
        }
    }
    // The second order, fitted from the linear's last noise and refitted as the slope is, kept
    // when its own settled `|z|` passes the threshold (docs/gap.md, "A temperature that bends
    // (session 51)"): a quadratic over -40..85 degC was a sinusoid, a warm-up and 16 jumps.
    let reference_c = {
        let finite: Vec<f64> = t
            .blocks_c
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        finite.iter().sum::<f64>() / finite.len().max(1) as f64
    };
    if let Some(f) = Some(faithful).filter(|ok| *ok).and_then(|_| {
        fit_temperature_in(
            &snap.block_means,
            &t.blocks_c,
            block_s,
            &c_linear,
            &[],
            &[],
            Some(reference_c),
        )
    }) {
        let mut bent = t.clone();
        bent.finding = f.with_lag_of(&t.finding);
        tracing::debug!(quadratic = ?f.quadratic, "the temperature's second order, first fit");
        let bent_c = bent.blocks_c.clone();
        let stands = |c5: &[f64; 5]| {
            beside_warmup(&bent_c, c5, Some(reference_c))
                .is_none_or(|f| f.quadratic.is_some_and(|q| q.z().abs() > z_crit))
        };
        if settle(&mut bent).is_some_and(|c| {
            bent.finding.quadratic.is_some_and(|q| q.z().abs() > z_crit) && stands(&c)
        }) {
            t = bent;
        }
    }
    if t.finding.strongest_z() <= z_crit {
        return None;
    }
    let fit = prob.gls(&spec(&t))?;
    Some((t, fit))
}

/// The share of its range by which the temperature must come back for a turn
/// ([`temperature_turns`]).
pub const TURN_SHARE: f64 = 0.2;

/// How many times the temperature's block means (degC) turn back by at least [`TURN_SHARE`] of
/// their range (a walk with that hysteresis): 0 for a ramp or a settling, 1 for a chamber
/// taken up and down, two per cycle after.
pub fn temperature_turns(blocks_c: &[f64]) -> usize {
    let finite: Vec<f64> = blocks_c.iter().copied().filter(|t| t.is_finite()).collect();
    let (lo, hi) = finite
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
            (a.min(t), b.max(t))
        });
    let h = TURN_SHARE * (hi - lo);
    if h.is_nan() || h <= 0.0 {
        return 0;
    }
    // The extremes before a first move of `h`, then the direction (+1 up, -1 down) and the
    // running extreme since the last turn.
    let (mut low, mut high) = (finite[0], finite[0]);
    let (mut dir, mut ext, mut turns) = (0i32, finite[0], 0usize);
    for &t in &finite[1..] {
        if dir == 0 {
            low = low.min(t);
            high = high.max(t);
            if t - low >= h {
                (dir, ext) = (1, t);
            } else if high - t >= h {
                (dir, ext) = (-1, t);
            }
        } else if (dir == 1 && t > ext) || (dir == -1 && t < ext) {
            ext = t;
        } else if (t - ext).abs() >= h {
            turns += 1;
            (dir, ext) = (-dir, t);
        }
    }
    turns
}

/// The recorded temperature's block means (degC) as a unit lagging it by a first order of
/// `time_constant_s` would see them: `D_j = D_{j-1} + (1 - e^{-block / time_constant}) (T_j -
/// D_{j-1})`, `D_0 = T_0` (the first order stepped at the block means: exact for a temperature
/// constant over each block).
pub fn lagged_blocks(blocks_c: &[f64], block_s: f64, time_constant_s: f64) -> Vec<f64> {
    let a = -(-block_s / time_constant_s).exp_m1();
    let mut d = blocks_c.first().copied().unwrap_or(f64::NAN);
    blocks_c
        .iter()
        .map(|&t| {
            d += a * (t - d);
            d
        })
        .collect()
}

/// The whitened residual sum of squares a lag must take off the straight coefficient's (on the
/// scale of the residuals) to be named: `4^2`, the temperature's own bar squared; the scan's
/// look-elsewhere over its correlated time constants is well inside it on white noise (tests).
pub const LAG_DROP: f64 = 16.0;

/// Lags scanned per octave, from half a block to half the run.
const LAG_PER_OCTAVE: f64 = 8.0;

/// The lag of the unit's temperature behind the recorded one: the time constant whose lagged
/// temperature ([`lagged_blocks`]) takes the most off the whitened residual sum of squares of
/// the block-mean differences (a drift and the lagged temperature's differences fitted, the
/// noise of `c`), scanned on a log grid from half a block to half the run. Returned when that
/// beats the recorded temperature's own by [`LAG_DROP`] on the scale of the best fit's
/// residuals, with the 95% profile interval (the time constants within 3.84 of the best,
/// widened to the grid's next points, 9% apart). A review's FOG whose die lagged the chamber air
/// by 30 minutes had the slope read at half its truth, its interval excluding it, or not named
/// (docs/gap.md, "A temperature that lags (session 51)").
pub fn scan_lag(
    block_means: &[f64],
    blocks_c: &[f64],
    block_s: f64,
    c: &[f64; 5],
) -> Option<TemperatureLag> {
    let nb = block_means.len();
    if !usable_block_means(block_means)
        || blocks_c.len() != nb
        || !blocks_c.iter().all(|t| t.is_finite())
    {
        return None;
    }
    let w = DiffWhitening::new(nb, block_s, c, &[])?;
    let y = w.apply(block_means)?;
    let yy = y.norm_squared();
    // The whitened rss taken off by a temperature series.
    let drop = |t: &[f64]| -> Option<f64> {
        let x = w.apply(t)?;
        let xx = x.norm_squared();
        (xx > 0.0).then(|| x.dot(&y).powi(2) / xx)
    };
    let plain = drop(blocks_c)?;
    let run_s = nb as f64 * block_s;
    let octaves = (run_s / block_s).log2();
    let steps = (octaves * LAG_PER_OCTAVE).ceil().max(1.0) as usize;
    let grid: Vec<f64> = (0..=steps)
        .map(|k| 0.5 * block_s * 2f64.powf(k as f64 / LAG_PER_OCTAVE))
        .filter(|tc| *tc <= 0.5 * run_s * (1.0 + 1e-9))
        .collect();
    let drops: Vec<f64> = grid
        .iter()
        .map(|&tc| drop(&lagged_blocks(blocks_c, block_s, tc)).unwrap_or(0.0))
        .collect();
    let best = (0..grid.len()).max_by(|&a, &b| drops[a].total_cmp(&drops[b]))?;
    let dof = (nb - 1).saturating_sub(2).max(1) as f64;
    let scale = ((yy - drops[best]) / dof).max(1.0);
    if (drops[best] - plain) / scale < LAG_DROP {
        return None;
    }
    // The interval's ends are the first grid points outside it (the profile crosses 3.84
    // between them and the last inside), or the grid's ends.
    let within = |k: usize| (drops[best] - drops[k]) / scale <= 3.84;
    let lo = (0..=best)
        .rev()
        .take_while(|&k| within(k))
        .last()
        .unwrap_or(best);
    let hi = (best..grid.len())
        .take_while(|&k| within(k))
        .last()
        .unwrap_or(best);
    let (lo, hi) = (lo.saturating_sub(1), (hi + 1).min(grid.len() - 1));
    Some(TemperatureLag {
        time_constant: grid[best],
        lo: grid[lo],
        hi: grid[hi],
    })
}

/// The largest relative error allowed of the temperature's AVAR read between block centres
/// ([`block_signal_avar`]) against its own, at clusters from half a block, for a second order to
/// be fitted: its AVAR on the curve is read that way. A review's 1 Hz gyro had blocks of 512 s
/// under a 45-minute chamber cycle, its temperature's AVAR read 18-22% low there; a 6-hour run
/// at 100 Hz (82-s blocks under a 3-hour cycle) is within 1% (docs/gap.md, "A temperature that
/// bends (session 51)").
pub const BLOCK_FIDELITY: f64 = 0.05;

/// The largest `|AVAR_blocks / AVAR_T - 1|` of the temperature ([`BLOCK_FIDELITY`]) at the
/// clusters from half a block where its AVAR is at least a hundredth of its largest (where the
/// effect's AVAR can matter beside the unit's; a frame's coarse temperature field leaves
/// little but rounding elsewhere); `None` when there is none.
fn block_fidelity(t: &TemperatureInModel) -> Option<f64> {
    let read = block_signal_avar(&t.blocks_c, &t.placement);
    let half = t.placement.block_len / 2;
    let top = t.avar_c2.iter().copied().fold(0.0, f64::max);
    tracing::trace!(ms = ?t.placement.ms, own = ?t.avar_c2, read = ?read, "the temperature's AVAR");
    t.placement
        .ms
        .iter()
        .zip(&t.avar_c2)
        .zip(&read)
        .filter(|((&m, &a), _)| m >= half && a > 0.0 && a >= 0.01 * top)
        .map(|((_, &a), &r)| (r / a - 1.0).abs())
        .reduce(f64::max)
}

/// Refits of the temperature's coefficient with its AVAR in the curve's model
/// ([`enter_temperature`]); `z` settles within 1% in two or three.
pub const TEMPERATURE_ROUNDS: usize = 4;

/// A settling profile `T(t) = final + (start - final) e^{-t/time_constant}` fitted to the
/// temperature's block means by least squares (the time constant scanned on a log grid from a
/// block to ten runs, 24 per decade, then 960 per decade around the best; `start` and `final`
/// linear at each), for the model file of
/// the fitted unit: the simulator's temperature is such a profile. The reference temperature is
/// `final` (the bias the model file writes is the one at `final`).
pub fn settling_profile(blocks_c: &[f64], block_s: f64) -> Option<TemperatureProfile> {
    let nb = blocks_c.len();
    if nb < 3 || !blocks_c.iter().all(|t| t.is_finite()) {
        return None;
    }
    let grid = super::effects::Grid {
        lo: block_s,
        hi: 10.0 * block_s * nb as f64,
        per_decade: 24.0,
    };
    let y = DVector::from_column_slice(blocks_c);
    let at = |tc: f64| -> Option<(f64, f64, f64)> {
        let e = DVector::from_vec(warmup_block_curve(nb, block_s, tc));
        let x = DMatrix::from_columns(&[DVector::from_element(nb, 1.0), e]);
        let beta = (x.transpose() * &x).try_inverse()? * x.transpose() * &y;
        Some(((&y - &x * &beta).norm_squared(), beta[0], beta[1]))
    };
    let tc = grid.refined_min(f64::INFINITY, |tc| at(tc).map(|a| a.0))?;
    let (_, final_c, settle) = at(tc)?;
    Some(TemperatureProfile {
        start_c: final_c + settle,
        final_c,
        time_constant_s: tc,
        sine_amplitude_c: 0.0,
        sine_period_s: 1.0,
        reference_c: final_c,
    })
}

/// GLS of the block-mean differences on a drift, the temperature's differences and the
/// differences of each `extra` block curve (module doc). `block_means` (u/s) and
/// `temperature` (degC) are per block, `c` the five-term coefficients, `effects` the stationary
/// effects in the noise model. `None` when the block means cannot carry the test (fewer than 24
/// blocks, missing blocks, no temperature change, singular design).
pub fn fit_temperature(
    block_means: &[f64],
    temperature: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    extra: &[Vec<f64>],
) -> Option<TemperatureFinding> {
    fit_temperature_in(block_means, temperature, block_s, c, effects, extra, None)
}

/// [`fit_temperature`], with the second order about `quadratic_reference` (degC) when given:
/// a column `(T_{i+1} - T_ref)^2 - (T_i - T_ref)^2` after the temperature's, its coefficient
/// and standard error (scaled as the slope's) in the finding's `quadratic`.
pub fn fit_temperature_in(
    block_means: &[f64],
    temperature: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    extra: &[Vec<f64>],
    quadratic_reference: Option<f64>,
) -> Option<TemperatureFinding> {
    let nb = block_means.len();
    if !usable_block_means(block_means)
        || temperature.len() != nb
        || !temperature.iter().all(|t| t.is_finite())
        || extra.iter().any(|e| e.len() != nb)
    {
        return None;
    }
    let diff = |v: &[f64]| DVector::from_iterator(nb - 1, v.windows(2).map(|p| p[1] - p[0]));
    let y = diff(block_means);
    let mut cols = vec![DVector::from_element(nb - 1, 1.0), diff(temperature)];
    if let Some(r) = quadratic_reference {
        let sq: Vec<f64> = temperature.iter().map(|t| (t - r) * (t - r)).collect();
        cols.push(diff(&sq));
    }
    cols.extend(extra.iter().map(|e| diff(e)));
    let chol = block_diff_covariance(nb, block_s, c, effects)?.cholesky()?;
    let l = chol.l();
    let yw = l.solve_lower_triangular(&y)?;
    let xw_cols: Vec<DVector<f64>> = cols
        .iter()
        .map(|x| l.solve_lower_triangular(x))
        .collect::<Option<_>>()?;
    let xw = DMatrix::from_columns(&xw_cols);
    let xtx_inv = (xw.transpose() * &xw).try_inverse()?;
    let beta = &xtx_inv * xw.transpose() * &yw;
    let rss = (&yw - &xw * &beta).norm_squared();
    let dof = (nb - 1).saturating_sub(xw_cols.len()).max(1) as f64;
    let scale = rss / dof;
    let var = xtx_inv[(1, 1)] * scale.max(1.0);
    if !(var.is_finite() && var > 0.0) {
        return None;
    }
    let se = var.sqrt();
    let quadratic = match quadratic_reference {
        Some(reference_c) => {
            let var_q = xtx_inv[(2, 2)] * scale.max(1.0);
            if !(var_q.is_finite() && var_q > 0.0) {
                return None;
            }
            Some(QuadraticFinding {
                coefficient: beta[2],
                std_error: var_q.sqrt(),
                reference_c,
            })
        }
        None => None,
    };
    Some(TemperatureFinding {
        coefficient: beta[1],
        std_error: se,
        z: beta[1] / se,
        scale,
        quadratic,
        lag: None,
        lag_se: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// Errors over their standard errors that are N(0, 1): mean within 0.1, sd within 10% of 1.
    fn assert_standard_normal(zs: &[f64]) {
        let n = zs.len() as f64;
        let mean = zs.iter().sum::<f64>() / n;
        let sd = (zs.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        assert!(mean.abs() < 0.1, "mean z {mean}");
        assert!((sd - 1.0).abs() < 0.1, "sd z {sd}");
    }

    /// White rate noise only (N = 1 u/sqrt(s)): the block-mean rate is white with variance
    /// `N^2 / tb`, so the GLS of the block means is ordinary least squares and its estimate can be
    /// checked against a known coefficient over many draws: the z score of the error is N(0, 1)
    /// (mean within 0.1, sd within 10%), and the 95% interval covers the truth in 90-99% of 400
    /// draws.
    #[test]
    fn coefficient_and_interval_are_calibrated_on_white_noise() {
        let (nb, tb) = (256, 10.0);
        let c5 = [0.0, 1.0, 0.0, 0.0, 0.0];
        let truth = 0.05;
        let temp: Vec<f64> = (0..nb)
            .map(|i| {
                let t = (i as f64 + 0.5) * tb;
                30.0 - 10.0 * (-t / 600.0).exp() + 0.5 * (t / 300.0).sin()
            })
            .collect();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let (mut zs, mut covered) = (Vec::new(), 0);
        for _ in 0..400 {
            let b: Vec<f64> = temp
                .iter()
                .map(|t| {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    7.0 + truth * t + e / tb.sqrt()
                })
                .collect();
            let f = fit_temperature(&b, &temp, tb, &c5, &[], &[]).expect("fit");
            zs.push((f.coefficient - truth) / f.std_error);
            let (lo, hi) = f.interval();
            covered += usize::from(lo <= truth && truth <= hi);
        }
        assert_standard_normal(&zs);
        assert!((360..=396).contains(&covered), "covered {covered}/400");
    }

    /// A warm-up of the same time constant as the temperature's settling cannot be told apart
    /// from it by the settling alone; with the temperature's sine it can, and the joint fit
    /// (warm-up shape as an extra column) gives back the coefficient within 5 standard errors.
    #[test]
    fn joint_fit_with_a_warmup_column() {
        let (nb, tb) = (256, 10.0);
        let c5 = [0.0, 1.0, 0.0, 0.0, 0.0];
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let temp: Vec<f64> = (0..nb)
            .map(|i| 25.0 + 2.0 * ((i as f64 + 0.5) * tb / 200.0).sin())
            .collect();
        let warm: Vec<f64> = (0..nb)
            .map(|i| super::super::warmup::warmup_block_shape(i, tb, 300.0))
            .collect();
        let b: Vec<f64> = (0..nb)
            .map(|i| {
                let e: f64 = StandardNormal.sample(&mut rng);
                0.1 * temp[i] + 2.0 * warm[i] + e / tb.sqrt()
            })
            .collect();
        let f = fit_temperature(&b, &temp, tb, &c5, &[], &[warm]).expect("fit");
        assert!((f.coefficient - 0.1).abs() < 5.0 * f.std_error, "{f:?}");
        assert!(f.z > 5.0, "{f:?}");
    }

    /// A settling temperature, sampled as block means, gives back its profile: start, final
    /// within 0.01 degC and the time constant within 1%.
    #[test]
    fn settling_profile_of_block_means() {
        let (nb, tb) = (256, 40.0);
        let t: Vec<f64> = (0..nb)
            .map(|i| 35.0 - 13.0 * super::super::warmup::warmup_block_shape(i, tb, 1500.0))
            .collect();
        let p = settling_profile(&t, tb).expect("profile");
        assert!((p.final_c - 35.0).abs() < 0.01, "{p:?}");
        assert!((p.start_c - 22.0).abs() < 0.01, "{p:?}");
        assert!((p.time_constant_s / 1500.0 - 1.0).abs() < 0.01, "{p:?}");
    }

    /// The second order on white noise: a temperature cycling 10 degC about 25 degC, the bias
    /// `0.02 (T - 25) + 0.003 (T - 25)^2`. Over 400 draws the errors of `q` over their standard
    /// errors have mean within 0.1 and sd within 10% of 1, the 95% interval covers `q` in 90-99%
    /// of them, and the slope at the reference (the mean block temperature, here 25 degC up to
    /// the cycle's last part) is `0.02 + 2 q (T_ref - 25)`, covered as often.
    #[test]
    fn second_order_and_slope_are_calibrated_on_white_noise() {
        let (nb, tb) = (300, 10.0);
        let c5 = [0.0, 1.0, 0.0, 0.0, 0.0];
        let (c_true, q_true) = (0.02, 0.003);
        let temp: Vec<f64> = (0..nb)
            .map(|i| 25.0 + 10.0 * ((i as f64 + 0.5) * tb / 700.0).sin())
            .collect();
        let reference = temp.iter().sum::<f64>() / nb as f64;
        let slope_true = c_true + 2.0 * q_true * (reference - 25.0);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(23);
        let (mut zs, mut covered, mut slope_covered) = (Vec::new(), 0, 0);
        for _ in 0..400 {
            let b: Vec<f64> = temp
                .iter()
                .map(|t| {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    3.0 + c_true * (t - 25.0) + q_true * (t - 25.0).powi(2) + e / tb.sqrt()
                })
                .collect();
            let f = fit_temperature_in(&b, &temp, tb, &c5, &[], &[], Some(reference)).expect("fit");
            let q = f.quadratic.expect("second order");
            zs.push((q.coefficient - q_true) / q.std_error);
            let half = Z95 * q.std_error;
            covered += usize::from((q.coefficient - q_true).abs() <= half);
            let (lo, hi) = f.interval();
            slope_covered += usize::from(lo <= slope_true && slope_true <= hi);
        }
        assert_standard_normal(&zs);
        assert!((360..=396).contains(&covered), "covered {covered}/400");
        assert!(
            (360..=396).contains(&slope_covered),
            "slope covered {slope_covered}/400"
        );
    }

    /// The AVAR of a signal read between block centres against closed forms (docs/theory.md
    /// section 1): a rate ramp `a t` has `a^2 tau^2 / 2`, within 1% from one sample to a
    /// sixteenth of the record (the ends, held flat over half a block, are all that differ);
    /// a sinusoid of 100 blocks per period, `A^2 sin^4(pi f tau) / (pi f tau)^2`, within 1% at
    /// an eighth, a quarter and half of its period.
    #[test]
    fn a_signal_between_block_centres_has_its_closed_form_avar() {
        let (len, nb) = (1000u64, 2000usize);
        let n = len * nb as u64;
        let ms: Vec<u64> = vec![1, 10, 100, 1000, 10_000, n / 16];
        let at = BlockPlacement {
            block_len: len,
            lead: 0,
            ms: ms.clone(),
            n_inc: n,
        };
        let centre = |j: usize| (j as f64 + 0.5) * len as f64;
        let a = 1e-6;
        let ramp: Vec<f64> = (0..nb).map(|j| a * centre(j)).collect();
        for (m, v) in ms.iter().zip(block_signal_avar(&ramp, &at)) {
            let truth = a * a * (*m as f64).powi(2) / 2.0;
            assert!((v / truth - 1.0).abs() < 0.01, "m {m}: {v} against {truth}");
        }
        let period = 100.0 * len as f64;
        let f = 1.0 / period;
        let sine: Vec<f64> = (0..nb)
            .map(|j| {
                // The block mean of sin(2 pi f t) over the block, exactly.
                let (t0, t1) = (j as f64 * len as f64, (j + 1) as f64 * len as f64);
                let w = 2.0 * std::f64::consts::PI * f;
                ((w * t0).cos() - (w * t1).cos()) / (w * len as f64)
            })
            .collect();
        let ms: Vec<u64> = [8.0, 4.0, 2.0]
            .iter()
            .map(|d| (period / d) as u64)
            .collect();
        let at = BlockPlacement {
            ms: ms.clone(),
            ..at
        };
        for (m, v) in ms.iter().zip(block_signal_avar(&sine, &at)) {
            let x = std::f64::consts::PI * f * *m as f64;
            let truth = x.sin().powi(4) / (x * x);
            assert!((v / truth - 1.0).abs() < 0.01, "m {m}: {v} against {truth}");
        }
    }

    /// A step of the recorded temperature reaches the lagged one as `1 - e^{-t/tau}` at the
    /// block ends; turns are counted with their hysteresis.
    #[test]
    fn lagged_blocks_and_turns() {
        let (tb, tau) = (10.0, 120.0);
        let t: Vec<f64> = (0..50).map(|i| if i < 5 { 20.0 } else { 30.0 }).collect();
        let d = lagged_blocks(&t, tb, tau);
        for (i, v) in d.iter().enumerate().skip(5) {
            let truth = 30.0 - 10.0 * (-((i - 4) as f64) * tb / tau).exp();
            assert!((v - truth).abs() < 1e-9, "block {i}: {v} against {truth}");
        }
        assert_eq!(temperature_turns(&t), 0);
        let cycle: Vec<f64> = (0..400).map(|i| (i as f64 / 40.0).sin()).collect();
        // sin(x / 40) over 400 blocks turns at x = 20 pi, 60 pi, 100 pi, 140 pi (blocks 63,
        // 188, 314): three turns; a ripple under a fifth of the range is none.
        assert_eq!(temperature_turns(&cycle), 3);
        let ripple: Vec<f64> = (0..400)
            .map(|i| i as f64 / 400.0 + 0.05 * (i as f64).sin())
            .collect();
        assert_eq!(temperature_turns(&ripple), 0);
    }

    /// The lag scan on white noise: a chamber cycling 10 degC every 2000 s, the bias following
    /// the temperature lagged by 300 s (0.05 u/s per degC). Over 100 draws the lag is found in
    /// every one, its interval covering 300 s in at least 90; with no lag (the bias on the
    /// recorded temperature itself) it is found in at most 2 of 100.
    #[test]
    fn the_lag_is_found_with_its_interval_and_not_invented() {
        let (nb, tb) = (400, 20.0);
        let c5 = [0.0, 1.0, 0.0, 0.0, 0.0];
        let temp: Vec<f64> = (0..nb)
            .map(|i| {
                25.0 + 10.0 * ((i as f64 + 0.5) * tb * 2.0 * std::f64::consts::PI / 2000.0).sin()
            })
            .collect();
        let die = lagged_blocks(&temp, tb, 300.0);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(31);
        let (mut found, mut covered, mut invented) = (0, 0, 0);
        for _ in 0..100 {
            let mut draw = |t: &[f64]| -> Vec<f64> {
                t.iter()
                    .map(|t| {
                        let e: f64 = StandardNormal.sample(&mut rng);
                        0.05 * t + e / tb.sqrt()
                    })
                    .collect()
            };
            let lagged = draw(&die);
            if let Some(l) = scan_lag(&lagged, &temp, tb, &c5) {
                found += 1;
                covered += usize::from(l.lo <= 300.0 && 300.0 <= l.hi);
            }
            let plain = draw(&temp);
            invented += usize::from(scan_lag(&plain, &temp, tb, &c5).is_some());
        }
        assert_eq!(found, 100);
        assert!(covered >= 90, "covered {covered}/100");
        assert!(invented <= 2, "invented {invented}/100");
    }

    /// Too few blocks, a constant temperature or missing blocks give no fit.
    #[test]
    fn no_fit_without_evidence() {
        let c5 = [0.0, 1.0, 0.0, 0.0, 0.0];
        let b = vec![1.0; 40];
        assert!(fit_temperature(&b, &vec![20.0; 40], 1.0, &c5, &[], &[]).is_none());
        assert!(fit_temperature(&b[..10], &[1.0; 10], 1.0, &c5, &[], &[]).is_none());
        let mut t: Vec<f64> = (0..40).map(f64::from).collect();
        t[3] = f64::NAN;
        assert!(fit_temperature(&b, &t, 1.0, &c5, &[], &[]).is_none());
    }
}
