//! Oracle bounds for the diagnosis (docs/gap.md, "Oracle bounds"): statistics that are told the
//! true effect's parameters, and Cramér-Rao bounds on its shape and amplitude, on the same
//! evidence the diagnosis uses. They measure how much a detector could at best gain, not how to
//! detect: none of this runs on the diagnosis's path.
//!
//! Evidence models (the ones the diagnosis fits with):
//! - the curve: `ln AVAR_hat ~ N(ln AVAR(theta), S)` with `S` the analytic log covariance of
//!   [`GapProblem`] (docs/theory.md section 5), the five-term amplitudes as nuisance;
//! - the block means: their first differences `d ~ N(r 1 + signal, Sigma)` with `Sigma` from
//!   the five-term model ([`block_diff_covariance`]), the drift `r` as nuisance (the level drops
//!   out of the differences).
//!
//! For a fully known alternative (all effect parameters given) in a Gaussian model whose
//! nuisance enters linearly, the most powerful test invariant to the nuisance rejects for large
//! `z = u'y / |u|`, `u` the whitened signal projected off the whitened nuisance columns, and its
//! power at level `alpha` is `Phi(|u| - z_alpha)` (Neyman-Pearson on the maximal invariant; e.g.
//! Lehmann and Romano, Testing Statistical Hypotheses, ch. 6). On the curve the model is linear in
//! the five amplitudes only after linearising `ln AVAR` at the truth, so there `z` is the score
//! statistic of that linearisation.

use super::block_cov::{block_diff_covariance, usable_block_means};
use super::effects::{effect_column, EffectKind};
use super::problem::{GapProblem, ModelSpec};
use super::warmup::warmup_block_shape;
use crate::model::terms::basis;
use nalgebra::{DMatrix, DVector};

/// Relative step of the numerical derivatives in `ln` of a shape parameter.
const LN_STEP: f64 = 1e-4;

/// Orthonormal basis (columns) of the span of `cols` (modified Gram-Schmidt; columns that add
/// less than `1e-10` of their norm are dropped).
fn orthonormal(cols: &[DVector<f64>]) -> Vec<DVector<f64>> {
    let mut q: Vec<DVector<f64>> = Vec::new();
    for c in cols {
        let mut u = c.clone();
        for v in &q {
            let a = v.dot(&u);
            u -= v * a;
        }
        let n = u.norm();
        if n > 1e-10 * c.norm() && n > 0.0 {
            q.push(u / n);
        }
    }
    q
}

/// `v` projected off the span of the orthonormal `q`.
fn project_off(v: &DVector<f64>, q: &[DVector<f64>]) -> DVector<f64> {
    let mut u = v.clone();
    for w in q {
        let a = w.dot(&u);
        u -= w * a;
    }
    u
}

/// The Gauss-Markov oracle on the curve at the true `(sigma, tau_c)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmOracle {
    /// Drop of `r' S^-1 r` (ridged `S`, as the diagnosis) from the base five-term GLS fit to the
    /// fit with a Gauss-Markov column at the true `tau_c`, amplitude fitted (`>= 0`).
    pub drop_fitted: f64,
    /// The same with the amplitude fixed at the true `sigma` (may be negative).
    pub drop_fixed: f64,
    /// Score statistic of the fully known alternative: `u' r_w / |u|`, `r_w` the whitened
    /// residual of the base fit, `u` the whitened Gauss-Markov signature `sigma^2 g / AVAR`
    /// projected off the base fit's active five-term columns (`b_i / AVAR`). About `N(0, 1)` on
    /// clean runs.
    pub z_known: f64,
    /// `|u|`: the mean of `z_known` under the alternative, to first order (its noncentrality).
    pub delta: f64,
}

/// The Gauss-Markov oracle statistics of `prob` at the true `sigma` (u/s) and `tau_c_s`.
pub fn gm_oracle(prob: &GapProblem, sigma: f64, tau_c_s: f64) -> Option<GmOracle> {
    let base = prob.gls(&ModelSpec::default())?;
    let col = effect_column(
        EffectKind::GaussMarkov,
        tau_c_s,
        &prob.ms,
        prob.tau0_s,
        prob.n_inc,
    );
    let fitted = prob.gls(&ModelSpec {
        extra: vec![col.clone()],
        ..ModelSpec::default()
    })?;
    let s2 = sigma * sigma;
    let fixed = prob.gls(&ModelSpec {
        offset: Some(col.iter().map(|g| s2 * g).collect()),
        ..ModelSpec::default()
    })?;
    let signal: Vec<f64> = col.iter().map(|g| s2 * g).collect();
    let (z_known, delta) = curve_known_z(prob, &signal)?;
    Some(GmOracle {
        drop_fitted: base.chi2 - fitted.chi2,
        drop_fixed: base.chi2 - fixed.chi2,
        z_known,
        delta,
    })
}

/// The known-signal test on the curve for any fully known effect: `signal_avar` is the AVAR
/// (u^2/s^2) the effect adds at each of `prob`'s cluster sizes (for an effect that replaces a
/// term, such as an output filter on the white rate, the difference it makes). Returns
/// `(z, delta)`: the score statistic `u' r_w / |u|` of the base five-term fit's whitened
/// residual `r_w` along the whitened signature `signal / AVAR` projected off the active
/// five-term columns (`ln AVAR` linearised at the base fit), about `N(0, 1)` on clean runs, and
/// its noncentrality `|u|` (the most powerful invariant test at a known shape and amplitude,
/// to first order; module doc). `None` when the base fit fails.
pub fn curve_known_z(prob: &GapProblem, signal_avar: &[f64]) -> Option<(f64, f64)> {
    let lin = CurveLinearisation::new(prob)?;
    let u = lin.signature(signal_avar);
    let delta = u.norm();
    Some((
        if delta > 0.0 {
            u.dot(&lin.rw) / delta
        } else {
            0.0
        },
        delta,
    ))
}

/// The base five-term fit of a [`GapProblem`] linearised for the known-signal tests of
/// [`curve_known_z`] and [`ShapeCeiling`]: the whitened residual and the orthonormal basis of
/// the whitened active five-term columns.
struct CurveLinearisation<'a> {
    prob: &'a GapProblem,
    /// The base fit's AVAR at each cluster size (u^2/s^2).
    model: Vec<f64>,
    /// The whitened residual `r_w` of `ln AVAR_hat - ln AVAR`.
    rw: DVector<f64>,
    /// Orthonormal basis of the whitened nuisance columns `b_i / AVAR` (active terms).
    q: Vec<DVector<f64>>,
}

impl<'a> CurveLinearisation<'a> {
    fn new(prob: &'a GapProblem) -> Option<Self> {
        let base = prob.gls(&ModelSpec::default())?;
        let j = prob.len();
        let a = &base.model;
        let r = DVector::from_fn(j, |i, _| prob.ln_avar()[i] - a[i].max(1e-300).ln());
        let rw = prob.whiten(&r);
        let nuis: Vec<DVector<f64>> = (0..5)
            .filter(|&c| base.coef[c] > 0.0)
            .map(|c| prob.whiten(&DVector::from_fn(j, |i, _| basis(prob.tau[i])[c] / a[i])))
            .collect();
        Some(Self {
            prob,
            model: a.clone(),
            rw,
            q: orthonormal(&nuis),
        })
    }

    /// The whitened signature `signal / AVAR` (`ln AVAR` linearised) projected off the nuisance.
    fn signature(&self, signal_avar: &[f64]) -> DVector<f64> {
        self.signature_of(signal_avar, |x| x)
    }

    /// The whitened shift of `ln AVAR` itself, `ln(1 + signal / AVAR)`, projected off the
    /// nuisance, where the signal adds AVAR: the same to first order, and still the effect's
    /// mean shift on the curve when it is strong. Where it takes AVAR away (a filter on a
    /// fitted term) the first-order shift is kept: the base fit has already lost what the
    /// filter removes, and the logarithm of what is left is no shift of the run's curve (it
    /// put the output filter's ceiling at 11 of 120 draws where the oracle decides 105).
    fn log_signature(&self, signal_avar: &[f64]) -> DVector<f64> {
        self.signature_of(signal_avar, |x| if x > 0.0 { x.ln_1p() } else { x })
    }

    fn signature_of(&self, signal_avar: &[f64], shift: impl Fn(f64) -> f64) -> DVector<f64> {
        let a = &self.model;
        let sig = self.prob.whiten(&DVector::from_fn(self.prob.len(), |i, _| {
            shift(signal_avar.get(i).copied().unwrap_or(0.0) / a[i])
        }));
        project_off(&sig, &self.q)
    }
}

/// The fair ceiling of an effect whose amplitude law is known and whose shape is not: the log
/// mixture likelihood ratio `ln (1/m) sum_k exp(u_k' y - |u_k|^2 / 2)` over `m` fully known
/// alternatives `k` (a grid over the shape prior, each with its amplitude), `u_k` the whitened
/// signal off the nuisance and `y` the whitened evidence; each term is the known-signal ratio
/// of one alternative ([`curve_known_z`], [`BlockGls::z_known`]). By Neyman-Pearson the mixture
/// ratio is the most powerful test against the prior that puts weight `1/m` on each
/// alternative (Lehmann and Romano, ch. 3): no detector that uses this evidence, told the
/// amplitude law but not the shape, has a higher power averaged over that prior at the same
/// level, in the Gaussian model of the evidence (on the curve, to first order). The stationary
/// effects' and the warm-up's analogue of [`JumpCeiling`] (docs/gap.md, "Fair ceilings of the
/// stationary effects and the warm-up (session 27)").
#[derive(Debug, Clone)]
pub struct ShapeCeiling {
    /// The whitened signatures `u_k`, projected off the nuisance.
    us: Vec<DVector<f64>>,
    /// `|u_k|^2 / 2`.
    half_sq: Vec<f64>,
    /// The run's whitened evidence off the nuisance.
    y: DVector<f64>,
}

impl ShapeCeiling {
    /// On the curve: `signals[k]` is the AVAR (u^2/s^2) alternative `k` adds at each of
    /// `prob`'s cluster sizes, as for [`curve_known_z`], taken as the shift it makes in
    /// `ln AVAR` at the base fit (`CurveLinearisation::log_signature`: `ln(1 + signal /
    /// AVAR)` where it adds AVAR, first order where it takes AVAR away; the five terms'
    /// amplitudes linearised as nuisance). `signal / AVAR` everywhere was tried first: a
    /// strong line's true alternative then has a ratio far below one (its `|u|^2 / 2` is many
    /// times `u' y`), and the sinusoid's ceiling fell below the diagnosis. A refitted drop
    /// per alternative was tried next: its null is not the linear model's (17% of clean runs
    /// past the 1% point). `None` when the base fit fails or `signals` is empty.
    pub fn on_curve(prob: &GapProblem, signals: &[Vec<f64>]) -> Option<Self> {
        let lin = CurveLinearisation::new(prob)?;
        let us = signals.iter().map(|s| lin.log_signature(s)).collect();
        Self::new(us, lin.rw)
    }

    /// On the block means: `profiles[k]` is the rate (u/s) alternative `k` adds to each block
    /// mean (a warm-up: `A` times [`BlockGls::warmup_profile`]), the drift the nuisance.
    pub fn on_block_means(gls: &BlockGls, profiles: &[Vec<f64>]) -> Option<Self> {
        let us = profiles
            .iter()
            .map(|p| gls.whitened_perp(&BlockGls::diff(p)))
            .collect();
        Self::new(us, project_off(&gls.yw, std::slice::from_ref(&gls.q_drift)))
    }

    fn new(us: Vec<DVector<f64>>, y: DVector<f64>) -> Option<Self> {
        if us.is_empty() {
            return None;
        }
        let half_sq = us
            .iter()
            .map(|u: &DVector<f64>| 0.5 * u.norm_squared())
            .collect();
        Some(Self { us, half_sq, y })
    }

    /// The log mixture ratio for the whitened evidence `w`.
    pub fn log_lr(&self, w: &DVector<f64>) -> f64 {
        let terms: Vec<f64> = self
            .us
            .iter()
            .zip(&self.half_sq)
            .map(|(u, h)| u.dot(w) - h)
            .collect();
        super::warmup::log_mean_exp(&terms)
    }

    /// The run's log mixture ratio and its p-value under the null of the same model (the
    /// whitened evidence off the nuisance `N(0, I)`; only its components along the `u_k`
    /// matter, and those are already off the nuisance), from `n_null` draws: `(1 + #{null >=
    /// run}) / (1 + n_null)`.
    pub fn p_value(&self, n_null: usize, seed: u64) -> (f64, f64) {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let obs = self.log_lr(&self.y);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let n = self.y.len();
        let above = (0..n_null)
            .filter(|_| {
                let e = DVector::from_fn(n, |_, _| StandardNormal.sample(&mut rng));
                self.log_lr(&e) >= obs
            })
            .count();
        ((1 + above) as f64 / (1 + n_null) as f64, obs)
    }
}

/// Cramér-Rao bound of the Gauss-Markov parameters on the curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmCrb {
    /// Standard deviation of any unbiased estimate of `ln tau_c` (relative sd of `tau_c`).
    pub sd_ln_tau_c: f64,
    /// The same for `ln sigma`.
    pub sd_ln_sigma: f64,
    /// Noncentrality `sigma^4 (J_s' W J_s)_perp` of the amplitude-fitted drop of
    /// [`GmOracle::drop_fitted`] at known `tau_c` (linearised, weights `W` = the ridged `S^-1`
    /// of the diagnosis, nuisance columns the free five terms), so that its mean is about
    /// `noncentrality + noise`.
    pub noncentrality: f64,
    /// The drop's mean on clean data under the same linearisation: `u' M u / |u|^2`, `M` the
    /// whitened true covariance (below 1 because of the ridge).
    pub noise: f64,
}

/// Cramér-Rao bound of `(ln sigma, ln tau_c)` from the curve's Fisher information
/// `F = J' S^-1 J` (Gaussian `ln AVAR_hat` with the fixed covariance `S` of `prob`, unridged;
/// the information in the covariance's own dependence on the parameters is left out), `J` the
/// Jacobian of `ln AVAR(tau_j)` at the truth: five-term coefficients `c` (`Q^2 .. R^2`, those
/// with `free[i]`; the others known) and the Gauss-Markov `sigma`, `tau_c`.
pub fn gm_curve_crb(
    prob: &GapProblem,
    c: &[f64; 5],
    sigma: f64,
    tau_c_s: f64,
    free: [bool; 5],
) -> Option<GmCrb> {
    let j = prob.len();
    let s2 = sigma * sigma;
    let g = |t: f64| {
        effect_column(
            EffectKind::GaussMarkov,
            t,
            &prob.ms,
            prob.tau0_s,
            prob.n_inc,
        )
    };
    let g0 = g(tau_c_s);
    let gp = g(tau_c_s * LN_STEP.exp());
    let gm = g(tau_c_s * (-LN_STEP).exp());
    let a: Vec<f64> = (0..j)
        .map(|i| {
            let b = basis(prob.tau[i]);
            (0..5).map(|k| c[k] * b[k]).sum::<f64>() + s2 * g0[i]
        })
        .collect();
    let mut cols: Vec<DVector<f64>> = (0..5)
        .filter(|&k| free[k])
        .map(|k| DVector::from_fn(j, |i, _| basis(prob.tau[i])[k] / a[i]))
        .collect();
    let nb = cols.len();
    // d ln AVAR / d ln sigma and d ln AVAR / d ln tau_c.
    cols.push(DVector::from_fn(j, |i, _| 2.0 * s2 * g0[i] / a[i]));
    cols.push(DVector::from_fn(j, |i, _| {
        s2 * (gp[i] - gm[i]) / (2.0 * LN_STEP) / a[i]
    }));
    let x = DMatrix::from_columns(&cols);
    let s = prob.log_covariance();
    let chol = s.clone().cholesky()?;
    let fisher = x.transpose() * chol.solve(&x);
    let inv = fisher.try_inverse()?;
    let sd_ln_sigma = inv[(nb, nb)].max(0.0).sqrt();
    let sd_ln_tau_c = inv[(nb + 1, nb + 1)].max(0.0).sqrt();
    // Noncentrality of the amplitude-fitted drop, in the diagnosis's (ridged) metric.
    let whiten = |v: &DVector<f64>| prob.whiten(v);
    let q = orthonormal(&cols[..nb].iter().map(whiten).collect::<Vec<_>>());
    let sig = whiten(&DVector::from_fn(j, |i, _| s2 * g0[i] / a[i]));
    let u = project_off(&sig, &q);
    // M = L^-1 S L^-T (whitened true covariance): u' M u = |L_s' L^-T u|^2.
    let lt_inv_u = whiten_transpose(prob, &u)?;
    let noise = (chol.l().transpose() * lt_inv_u).norm_squared() / u.norm_squared();
    Some(GmCrb {
        sd_ln_tau_c,
        sd_ln_sigma,
        noncentrality: u.norm_squared(),
        noise,
    })
}

/// `L^-T u` for the whitening `L^-1` of `prob` (from `L^-1` applied to the unit vectors).
fn whiten_transpose(prob: &GapProblem, u: &DVector<f64>) -> Option<DVector<f64>> {
    let j = prob.len();
    let linv = DMatrix::from_columns(
        &(0..j)
            .map(|k| {
                let mut e = DVector::zeros(j);
                e[k] = 1.0;
                prob.whiten(&e)
            })
            .collect::<Vec<_>>(),
    );
    Some(linv.transpose() * u)
}

/// Generalised least squares on the first differences of the block-mean rate with the model
/// covariance (the evidence of the warm-up and jump tests), drift as the nuisance.
#[derive(Debug, Clone)]
pub struct BlockGls {
    n_blocks: usize,
    block_s: f64,
    linv: DMatrix<f64>,
    /// Whitened differences.
    yw: DVector<f64>,
    /// Orthonormal whitened drift column.
    q_drift: DVector<f64>,
}

impl BlockGls {
    /// From block means (u/s, blocks of `block_s` s) and the five-term model `c` (`Q^2 .. R^2`)
    /// that sets the covariance. `None` with fewer than 24 blocks, a missing block or a
    /// covariance that is not positive definite.
    pub fn new(block_means: &[f64], block_s: f64, c: &[f64; 5]) -> Option<Self> {
        if !usable_block_means(block_means) {
            return None;
        }
        let sigma = block_diff_covariance(block_means.len(), block_s, c, &[])?;
        let n = sigma.nrows();
        let chol = sigma.cholesky()?;
        let linv = chol.l().solve_lower_triangular(&DMatrix::identity(n, n))?;
        let d = DVector::from_iterator(n, block_means.windows(2).map(|p| p[1] - p[0]));
        let yw = &linv * d;
        let ones = &linv * DVector::from_element(n, 1.0);
        let q_drift = &ones / ones.norm();
        Some(Self {
            n_blocks: block_means.len(),
            block_s,
            linv,
            yw,
            q_drift,
        })
    }

    /// Number of differences.
    pub fn len(&self) -> usize {
        self.yw.len()
    }

    pub fn is_empty(&self) -> bool {
        self.yw.is_empty()
    }

    /// First differences of a block-mean profile (one value per block).
    pub fn diff(profile: &[f64]) -> DVector<f64> {
        DVector::from_iterator(
            profile.len().saturating_sub(1),
            profile.windows(2).map(|p| p[1] - p[0]),
        )
    }

    /// Block-mean profile of a unit step at `t_s` (s from the start): the fraction of each block
    /// after the step.
    pub fn step_profile(&self, t_s: f64) -> Vec<f64> {
        (0..self.n_blocks)
            .map(|i| {
                let end = (i + 1) as f64 * self.block_s;
                ((end - t_s) / self.block_s).clamp(0.0, 1.0)
            })
            .collect()
    }

    /// Block-mean profile of a unit warm-up `e^{-t/T}` ([`warmup_block_shape`]).
    pub fn warmup_profile(&self, t_s: f64) -> Vec<f64> {
        (0..self.n_blocks)
            .map(|i| warmup_block_shape(i, self.block_s, t_s))
            .collect()
    }

    fn whitened_perp(&self, signal: &DVector<f64>) -> DVector<f64> {
        let u = &self.linv * signal;
        project_off(&u, std::slice::from_ref(&self.q_drift))
    }

    /// Drop of the whitened residual sum of squares when the difference-space `columns` are
    /// added to the drift, their sizes fitted (chi-squared with `columns.len()` degrees of
    /// freedom on clean data when the covariance is right).
    pub fn drop(&self, columns: &[DVector<f64>]) -> f64 {
        let us: Vec<DVector<f64>> = columns.iter().map(|c| self.whitened_perp(c)).collect();
        orthonormal(&us)
            .iter()
            .map(|q| q.dot(&self.yw).powi(2))
            .sum()
    }

    /// `(z, delta)` of a fully known difference-space signal: `z = u' y_w / |u|` (`N(0, 1)` on
    /// clean data, mean `delta = |u|` under the alternative), `u` the whitened signal off the
    /// drift.
    pub fn z_known(&self, signal: &DVector<f64>) -> (f64, f64) {
        let u = self.whitened_perp(signal);
        let delta = u.norm();
        if delta > 0.0 {
            (u.dot(&self.yw) / delta, delta)
        } else {
            (0.0, 0.0)
        }
    }

    /// Inverse Fisher information of the parameters whose difference-space derivatives are
    /// `columns`, the drift (first parameter) included: `(X' Sigma^-1 X)^-1`, `X = [1, columns]`.
    pub fn inverse_fisher(&self, columns: &[DVector<f64>]) -> Option<DMatrix<f64>> {
        let n = self.len();
        let mut xs = vec![&self.linv * DVector::from_element(n, 1.0)];
        xs.extend(columns.iter().map(|c| &self.linv * c));
        let x = DMatrix::from_columns(&xs);
        (x.transpose() * x).try_inverse()
    }
}

/// Cramér-Rao bound of a warm-up `A e^{-t/T}` in the block means.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WarmupCrb {
    pub sd_ln_t: f64,
    pub sd_ln_a: f64,
}

/// The warm-up's Cramér-Rao bound: parameters drift `r`, `A`, `ln T` in
/// `d = r 1 + A diff(e(T)) + noise`, `e` the block means of `e^{-t/T}`, covariance of `gls`.
pub fn warmup_crb(gls: &BlockGls, amplitude: f64, time_constant_s: f64) -> Option<WarmupCrb> {
    let e0 = BlockGls::diff(&gls.warmup_profile(time_constant_s));
    let ep = BlockGls::diff(&gls.warmup_profile(time_constant_s * LN_STEP.exp()));
    let em = BlockGls::diff(&gls.warmup_profile(time_constant_s * (-LN_STEP).exp()));
    let dt = (ep - em) * (amplitude / (2.0 * LN_STEP));
    let inv = gls.inverse_fisher(&[e0, dt])?;
    Some(WarmupCrb {
        sd_ln_t: inv[(2, 2)].max(0.0).sqrt(),
        sd_ln_a: inv[(1, 1)].max(0.0).sqrt() / amplitude.abs(),
    })
}

/// The warm-up oracle: `W` at the true `T` (amplitude fitted; the diagnosis's `W` without the
/// scan over `T`) and the known-signal `(z, delta)` at the true `A` and `T`.
pub fn warmup_oracle(gls: &BlockGls, amplitude: f64, time_constant_s: f64) -> (f64, f64, f64) {
    let e = BlockGls::diff(&gls.warmup_profile(time_constant_s));
    let w = gls.drop(std::slice::from_ref(&e));
    let (z, delta) = gls.z_known(&(e * amplitude));
    (w, z, delta)
}

/// The jump oracle at the true jumps `(time s, size u/s)`: the drop of the whitened residual sum
/// of squares with steps at the true times, sizes fitted (chi-squared with as many degrees of
/// freedom as jumps on clean data), and the known-signal `(z, delta)` with the true sizes.
pub fn jumps_oracle(gls: &BlockGls, jumps: &[(f64, f64)]) -> (f64, f64, f64) {
    let cols: Vec<DVector<f64>> = jumps
        .iter()
        .map(|&(t, _)| BlockGls::diff(&gls.step_profile(t)))
        .collect();
    let chi2 = gls.drop(&cols);
    let mut signal = DVector::zeros(gls.len());
    for (c, &(_, s)) in cols.iter().zip(jumps) {
        signal += c * s;
    }
    let (z, delta) = gls.z_known(&signal);
    (chi2, z, delta)
}

/// Quantile `p` of `|e^x - 1|` over the mixture of `x ~ N(0, sd_i^2)` with equal weights: the
/// `p` quantile of the relative error of an estimate whose log error has the given standard
/// deviations (bisection on the mixture's tail probability).
pub fn mixture_rel_error_quantile(sds: &[f64], p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    let sds: Vec<f64> = sds
        .iter()
        .copied()
        .filter(|s| s.is_finite() && *s > 0.0)
        .collect();
    if sds.is_empty() {
        return f64::NAN;
    }
    let nrm = Normal::new(0.0, 1.0).expect("unit normal");
    // P(|e^x - 1| > q) = P(x > ln(1 + q)) + P(x < ln(1 - q)) (the second is 0 for q >= 1).
    let tail = |q: f64| -> f64 {
        sds.iter()
            .map(|&s| {
                let hi = 1.0 - nrm.cdf((1.0 + q).ln() / s);
                let lo = if q < 1.0 {
                    nrm.cdf((1.0 - q).ln() / s)
                } else {
                    0.0
                };
                hi + lo
            })
            .sum::<f64>()
            / sds.len() as f64
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    while tail(hi) > 1.0 - p && hi < 1e6 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if tail(mid) > 1.0 - p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Candidate jump times per block of [`jumps_marginal_oracle`] (at the centres of equal
/// sub-blocks), standing in for the benchmark's uniform times.
pub const JUMP_SUBBLOCKS: usize = 4;

/// The jump ceiling with the count and rms size known and the times unknown: the log marginal
/// likelihood ratio `ln E_S[LR(S)]` of `count` steps at independent uniform times (on a grid of
/// [`JUMP_SUBBLOCKS`] per block) with sizes `N(0, rms_size^2)` against none, in the block-mean
/// differences with the drift as nuisance. For steps at given times `S`, with `U_S` their
/// whitened columns off the drift and `y` the whitened differences off the drift (Woodbury):
/// `LR(S) = |I + s^2 U_S' U_S|^(-1/2) exp(c' (U_S' U_S + I / s^2)^(-1) c / 2)`, `c = U_S' y`.
/// By Neyman-Pearson this ratio is the most powerful test against that prior (Lehmann and
/// Romano, ch. 3), in the Gaussian model of the evidence with the model covariance. The mean
/// over `S` is estimated by importance sampling with `samples` draws: each time from a defensive
/// mixture, half uniform and half in proportion to the single-step Bayes factor at that time.
/// Returns `None` when the block GLS cannot be set up.
pub fn jumps_marginal_oracle(
    gls: &BlockGls,
    count: usize,
    rms_size: f64,
    samples: usize,
    seed: u64,
) -> Option<f64> {
    let ceil = JumpCeiling::new(gls);
    ceil.log_lr(&ceil.y, count, rms_size, samples, seed)
}

/// The candidate step columns of [`jumps_marginal_oracle`] (whitened, off the drift) with their
/// Gram matrix, so that the ratio can be evaluated on the run and on draws of the null.
#[derive(Debug, Clone)]
pub struct JumpCeiling {
    cols: Vec<DVector<f64>>,
    gram: DMatrix<f64>,
    /// The run's whitened differences off the drift.
    y: DVector<f64>,
    q_drift: DVector<f64>,
}

impl JumpCeiling {
    pub fn new(gls: &BlockGls) -> Self {
        let y = project_off(&gls.yw, std::slice::from_ref(&gls.q_drift));
        let t_run = gls.n_blocks as f64 * gls.block_s;
        let n_cand = gls.n_blocks * JUMP_SUBBLOCKS;
        let cols: Vec<DVector<f64>> = (0..n_cand)
            .map(|i| {
                let t = (i as f64 + 0.5) / n_cand as f64 * t_run;
                gls.whitened_perp(&BlockGls::diff(&gls.step_profile(t)))
            })
            .collect();
        let mat = DMatrix::from_columns(&cols);
        let gram = mat.transpose() * &mat;
        Self {
            y,
            cols,
            gram,
            q_drift: gls.q_drift.clone(),
        }
    }

    /// `ln E_S[LR(S)]` of [`jumps_marginal_oracle`] for the whitened differences `y` (off the
    /// drift).
    pub fn log_lr(
        &self,
        y: &DVector<f64>,
        count: usize,
        rms_size: f64,
        samples: usize,
        seed: u64,
    ) -> Option<f64> {
        use rand::{RngExt, SeedableRng};
        if count == 0
            || rms_size.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
            || samples == 0
            || self.cols.is_empty()
        {
            return None;
        }
        let n_cand = self.cols.len();
        let s2 = rms_size * rms_size;
        let cy: Vec<f64> = self.cols.iter().map(|u| u.dot(y)).collect();
        // Single-step log Bayes factors, for the proposal.
        let lb: Vec<f64> = (0..n_cand)
            .map(|i| {
                let g = self.gram[(i, i)];
                let c = cy[i];
                -0.5 * (1.0 + s2 * g).ln() + 0.5 * c * c / (g + 1.0 / s2)
            })
            .collect();
        let m = lb.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let wsum: f64 = lb.iter().map(|v| (v - m).exp()).sum();
        let q: Vec<f64> = lb
            .iter()
            .map(|v| 0.5 * (v - m).exp() / wsum + 0.5 / n_cand as f64)
            .collect();
        let mut cdf = Vec::with_capacity(n_cand);
        let mut acc = 0.0;
        for v in &q {
            acc += v;
            cdf.push(acc);
        }
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut logw: Vec<f64> = Vec::with_capacity(samples);
        for _ in 0..samples {
            let idx: Vec<usize> = (0..count)
                .map(|_| {
                    let u = rng.random::<f64>() * acc;
                    cdf.partition_point(|&c| c < u).min(n_cand - 1)
                })
                .collect();
            let g = DMatrix::from_fn(count, count, |a, b| self.gram[(idx[a], idx[b])]);
            let c = DVector::from_iterator(count, idx.iter().map(|&i| cy[i]));
            let a = &g * s2 + DMatrix::identity(count, count);
            let Some(ch_a) = a.cholesky() else { continue };
            let logdet: f64 = ch_a.l().diagonal().iter().map(|v| 2.0 * v.ln()).sum();
            let b = &g + DMatrix::identity(count, count) / s2;
            let Some(ch_b) = b.cholesky() else { continue };
            let quad = c.dot(&ch_b.solve(&c));
            let prop: f64 = idx.iter().map(|&i| (q[i] * n_cand as f64).ln()).sum();
            logw.push(-0.5 * logdet + 0.5 * quad - prop);
        }
        if logw.is_empty() {
            return None;
        }
        Some(super::warmup::log_mean_exp(&logw))
    }

    /// The p-value of the run's ratio under the null of the same Gaussian model (whitened
    /// differences `N(0, I)` off the drift), from `n_null` draws: `(1 + #{null >= run}) /
    /// (1 + n_null)`, with the run's ratio. This is the fair ceiling per run: the most powerful
    /// test told the count and the rms but not the times, at its exact level in that model
    /// (docs/gap.md, "Per-family benchmark against the oracle").
    pub fn p_value(
        &self,
        count: usize,
        rms_size: f64,
        samples: usize,
        n_null: usize,
        seed: u64,
    ) -> Option<(f64, f64)> {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let obs = self.log_lr(&self.y, count, rms_size, samples, seed)?;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x0a11_5eed);
        let n = self.y.len();
        let mut above = 0usize;
        for k in 0..n_null {
            let e = DVector::from_fn(n, |_, _| StandardNormal.sample(&mut rng));
            let e = project_off(&e, std::slice::from_ref(&self.q_drift));
            let v = self.log_lr(
                &e,
                count,
                rms_size,
                samples,
                seed.wrapping_add(k as u64 + 1),
            )?;
            if v >= obs {
                above += 1;
            }
        }
        Some(((1 + above) as f64 / (1 + n_null) as f64, obs))
    }
}
