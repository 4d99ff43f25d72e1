//! Fit of the five-term model (docs/theory.md section 2) to an AVAR curve, with honest 95% intervals
//! and a calibrated goodness of fit (docs/theory.md sections 4 and 5). Works on curve points only.
//!
//! Methods ([`FitMethod`]):
//! - `Model` (default): weighted NNLS in `c = (Q^2, N^2, B^2, K^2, R^2) >= 0` with weights
//!   `1 / Var(AVAR_hat(tau_j))`, `Var = 2 AVAR_model(tau_j)^2 / edf_j`, the model being the current
//!   fit, iterated to a fixed point. Weights from the noisy estimate itself bias the fit low
//!   (docs/theory.md section 2); weights from the model do not.
//! - `Paper`: the seed paper's formulas (6)-(7): weights `1/AVAR_hat`, then one fit per term with
//!   weights `term_i / (AVAR_hat * p^2)`, keeping that term's coefficient (the seed paper, docs/theory.md section 6).
//! - `Slopes`: the IEEE Std 952 read-out: the line of each term's slope that touches the curve from
//!   below (N at tau = 1 s on the -1/2 line, K at 3 s on +1/2, Q at sqrt(3) s on -1, R at sqrt(2) s
//!   on +1, B = min ADEV / 0.664).
//! - `LogLog`: unweighted least squares of `ln AVAR` (every tau counts the same), the common
//!   "fit a curve on the log-log plot"; a comparison baseline.
//!
//! Uncertainty, whatever the method: each estimator is linearised as `c = G y` around the fitted
//! values (`y` the AVAR estimates), the covariance `S` of `y` is the analytic one
//! ([`crate::model::avar_cov`], strong correlation between neighbouring taus included), a
//! quadratic form in the model `c`, and `Var c = G S G'` at the fit. The 95% interval of each `c_i`
//! comes from inverting a test whose variance is taken under the trial value, the other terms at
//! their profile values (`inverted_intervals`: honest where a term is near zero, where the
//! fitted model's variance is too small); the reported interval is its square root. An
//! undetermined term's upper end is capped by the curve's own 97.5% limits. `determined`: the
//! term dominates at one fitted tau or more, its interval excludes zero, and its lower end is at
//! least [`QUANTITATION_FRACTION`] of the value (docs/fit.md, "Which terms are determined").

mod estimators;
mod intervals;

use crate::allan::CurvePoint;
use crate::model::avar_cov::{cov_points, strides, AvarCovariance, CovPoint};
use crate::model::nnls::{nnls, NnlsError};
use crate::model::terms::{basis, TERM_NAMES};
pub use crate::stats::chi2_quantile;
use estimators::*;
use intervals::*;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Two-sided 95% normal quantile.
const Z95: f64 = 1.959_963_984_540_054;

/// A determined coefficient's 95% interval must reach no lower than this fraction of its value
/// (a limit of quantitation beside the limit of detection `lo > 0`): below it the value is
/// detected but not measured, and the runs that pass a detection test alone are the ones whose
/// estimate came out high (docs/fit.md, "Which terms are determined").
pub const QUANTITATION_FRACTION: f64 = 1.0 / 3.0;

/// How the coefficients are estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FitMethod {
    /// Weighted NNLS with model-based weights, iterated (the default).
    #[default]
    Model,
    /// The seed paper's formulas (6)-(7).
    Paper,
    /// IEEE Std 952 slope read-out.
    Slopes,
    /// Unweighted least squares on the log-log plot.
    LogLog,
}

impl FitMethod {
    pub fn name(self) -> &'static str {
        match self {
            FitMethod::Model => "model",
            FitMethod::Paper => "paper",
            FitMethod::Slopes => "slopes",
            FitMethod::LogLog => "loglog",
        }
    }
}

impl std::str::FromStr for FitMethod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "model" => Ok(FitMethod::Model),
            "paper" => Ok(FitMethod::Paper),
            "slopes" => Ok(FitMethod::Slopes),
            "loglog" => Ok(FitMethod::LogLog),
            other => Err(format!(
                "unknown fit method `{other}` (allowed: model, paper, slopes, loglog)"
            )),
        }
    }
}

/// What to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    pub method: FitMethod,
    /// Terms allowed in the model, in the order Q, N, B, K, R; a disallowed term is held at 0.
    pub terms: [bool; 5],
    /// Only curve points with `tau_min_s <= tau_s <= tau_max_s` are used.
    pub tau_min_s: Option<f64>,
    pub tau_max_s: Option<f64>,
    /// Cap on the reweighting iterations (`Model`, `LogLog`).
    pub max_iter: usize,
    /// Stop iterating when no coefficient moves by more than this fraction of the largest
    /// model contribution.
    pub rel_tol: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            method: FitMethod::Model,
            terms: [true; 5],
            tau_min_s: None,
            tau_max_s: None,
            // Measured: the model-weighted iteration settles in 3-8 passes on octave curves.
            max_iter: 50,
            rel_tol: 1e-9,
        }
    }
}

/// Why no fit could be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FitError {
    #[error("fit: {usable} usable curve points in the tau range, need at least {need}")]
    TooFewPoints { usable: usize, need: usize },
    #[error("fit: no term is allowed")]
    NoTerms,
    #[error("fit: curve points disagree on tau0 (tau_s / m): {0} s vs {1} s")]
    InconsistentTau0(f64, f64),
    #[error("fit: {0}")]
    Nnls(#[from] NnlsError),
}

/// One coefficient of the fit, in its native unit (docs/theory.md section 2 table).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoefEstimate {
    /// The estimate (kept even when not determined; the JSON record prints null then).
    pub value: f64,
    /// 95% interval.
    pub lo: f64,
    pub hi: f64,
    /// The term is the largest of the five at one or more of the fitted taus.
    pub dominant: bool,
    /// The 95% interval excludes zero (`lo > 0`).
    pub significant: bool,
    /// `dominant && significant && lo >= value * QUANTITATION_FRACTION` (docs/theory.md section 2,
    /// with the quantitation condition of [`QUANTITATION_FRACTION`]).
    pub determined: bool,
    /// The term is still the largest at one or more fitted taus when it sits at the lower end of
    /// its interval and the other terms at their profile values there (a stricter reading of
    /// "dominates", compared in docs/fit.md).
    pub dominant_at_lo: bool,
    /// Standard deviation of the squared coefficient `c_i`.
    pub sd_c: f64,
}

/// The result of one fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitResult {
    pub method: FitMethod,
    /// `c = (Q^2, N^2, B^2, K^2, R^2)` in u^2 s^-?, the model's linear coefficients.
    pub c: [f64; 5],
    /// Q, N, B, K, R with intervals.
    pub coef: [CoefEstimate; 5],
    /// Covariance of `c` (`G S G'`).
    pub cov_c: [[f64; 5]; 5],
    /// Generalised chi-square of the relative residuals with the full covariance, divided by its
    /// expectation under the fitted model: about 1 when the model explains the curve.
    pub gof: f64,
    /// Curve points used, and the tau span they cover (s).
    pub n_points: usize,
    pub tau_span_s: (f64, f64),
    /// Sampling step inferred from the points (s).
    pub tau0_s: f64,
    /// Reweighting passes made.
    pub iterations: usize,
}

impl FitResult {
    /// The fitted AVAR at `tau_s` (u^2/s^2).
    pub fn model_avar(&self, tau_s: f64) -> f64 {
        basis(tau_s).iter().zip(&self.c).map(|(b, c)| b * c).sum()
    }
    /// Coefficient by name ("Q".."R").
    pub fn get(&self, name: &str) -> Option<&CoefEstimate> {
        TERM_NAMES
            .iter()
            .position(|n| *n == name)
            .map(|i| &self.coef[i])
    }
}

/// A fitter that keeps the covariance lag sums between refits of the same tau grid (the live
/// pipeline refits periodically; see [`AvarCovariance`]).
#[derive(Debug, Default, Clone)]
pub struct Fitter {
    cov: AvarCovariance,
}

/// Fit once (no cache kept).
pub fn fit(points: &[CurvePoint], opts: &FitOptions) -> Result<FitResult, FitError> {
    Fitter::new().fit(points, opts)
}

/// The selected curve points as columns of the problem.
struct Problem {
    tau: Vec<f64>,
    y: DVector<f64>,
    edf: Vec<f64>,
    x: DMatrix<f64>,
    cov_pts: Vec<CovPoint>,
    /// Stride of each estimate (1: full overlap).
    cov_strides: Vec<u64>,
    tau0_s: f64,
    allowed: [bool; 5],
}

/// An estimate with its linear sensitivity `c = G y` (5 x J).
struct Estimate {
    c: [f64; 5],
    g: DMatrix<f64>,
    iterations: usize,
}

impl Fitter {
    pub fn new() -> Self {
        Self::default()
    }

    /// A fitter for live refits, whose curves gain differences between calls: covariance lag
    /// sums are reused while the counts stay within the fraction `eps` (see
    /// [`AvarCovariance::with_count_tolerance`]; 0.02 keeps the covariance within ~1e-3).
    pub fn with_count_tolerance(eps: f64) -> Self {
        Self {
            cov: AvarCovariance::with_count_tolerance(eps),
        }
    }

    /// Fit the AVAR curve `points` (docs/theory.md section 2).
    pub fn fit(&mut self, points: &[CurvePoint], opts: &FitOptions) -> Result<FitResult, FitError> {
        let prob = select(points, opts)?;
        let est = match opts.method {
            FitMethod::Model => est_model(&prob, opts)?,
            FitMethod::Paper => est_paper(&prob)?,
            FitMethod::Slopes => est_slopes(&prob),
            FitMethod::LogLog => est_loglog(&prob, opts)?,
        };
        Ok(self.finish(&prob, est, opts.method))
    }

    fn finish(&mut self, prob: &Problem, est: Estimate, method: FitMethod) -> FitResult {
        let j = prob.tau.len();
        let c = est.c;
        let model = model_values(&prob.x, &c);
        // Covariance of the estimates at the fitted model; if the model is degenerate (all zero)
        // fall back to the per-point chi-squared variances of the data.
        // The covariance as quadratic forms in c (one read of the lag sums), evaluated at the fit.
        let tensors = self
            .cov
            .tensors_strided(prob.tau0_s, &prob.cov_pts, &prob.cov_strides);
        let mut s = DMatrix::zeros(j, j);
        let mut idx = 0;
        for a in 0..j {
            for b in a..j {
                let v = quad_form(&tensors[idx], &c);
                idx += 1;
                s[(a, b)] = v;
                s[(b, a)] = v;
            }
        }
        let mut model_cov = true;
        for i in 0..j {
            if !(s[(i, i)].is_finite() && s[(i, i)] > 0.0) {
                model_cov = false;
                s = DMatrix::from_diagonal(&DVector::from_fn(j, |k, _| {
                    2.0 * prob.y[k] * prob.y[k] / prob.edf[k]
                }));
                break;
            }
        }
        let cov_c_m = &est.g * &s * est.g.transpose();
        let mut cov_c = [[0.0; 5]; 5];
        for a in 0..5 {
            for b in 0..5 {
                cov_c[a][b] = cov_c_m[(a, b)];
            }
        }
        let s_inv = spd_inverse(&s);
        let fisher_sd = fisher_sd(prob, s_inv.as_ref());
        let mut coef = [CoefEstimate {
            value: 0.0,
            lo: 0.0,
            hi: 0.0,
            dominant: false,
            significant: false,
            determined: false,
            dominant_at_lo: false,
            sd_c: 0.0,
        }; 5];
        // The slope bound of each term from the points' 97.5% upper limits (docs/theory.md section
        // 4): c_i basis_i(tau_k) <= AVAR(tau_k) <= edf_k AVAR_hat_k / chi2_{0.025}(edf_k).
        // Computed only when a term is left undetermined (the quantiles are half of a refit).
        let bounds = std::cell::OnceCell::new();
        let data_bound = |i: usize| -> f64 {
            bounds.get_or_init(|| {
                let upper: Vec<f64> = (0..j)
                    .map(|k| {
                        let q = chi2_quantile(prob.edf[k], 0.025);
                        if q > 0.0 {
                            prob.edf[k] * prob.y[k] / q
                        } else {
                            f64::INFINITY
                        }
                    })
                    .collect();
                let b: [f64; 5] = std::array::from_fn(|t| {
                    (0..j)
                        .map(|k| upper[k] / prob.x[(k, t)])
                        .filter(|b| b.is_finite() && *b > 0.0)
                        .fold(f64::INFINITY, f64::min)
                });
                b
            })[i]
        };
        let inverted = if model_cov {
            inverted_intervals(
                prob,
                &est.g,
                &s,
                &c,
                &cov_c,
                &tensors,
                method == FitMethod::Model,
            )
        } else {
            [None; 5]
        };
        for i in 0..5 {
            let var = cov_c[i][i].max(0.0);
            let sd = var.sqrt();
            let ci = c[i];
            let dominant = dominates(&prob.x, i, ci, &c);
            let (lo_c, hi_c, dominant_at_lo) = if !prob.allowed[i] {
                (0.0, 0.0, false)
            } else if let Some(inv) = inverted[i] {
                // A term not determined (not dominant, or its interval reaches below a third
                // of its value, or has no finite upper end): the curve itself bounds it, as
                // below.
                let measured = dominant
                    && inv.lo > 0.0
                    && inv.lo.sqrt() >= QUANTITATION_FRACTION * ci.sqrt()
                    && inv.hi.is_some();
                let hi = inv.hi.unwrap_or(f64::INFINITY);
                let hi = if measured {
                    hi
                } else {
                    hi.min(data_bound(i)).max(ci)
                };
                (
                    inv.lo,
                    hi,
                    inv.lo > 0.0 && dominates(&prob.x, i, inv.lo, &inv.c_at_lo),
                )
            } else if ci > 0.0 && sd > 0.0 {
                let significant = ci > Z95 * sd;
                let (lo, hi) = chi2_interval(ci, var);
                // For a term the data do not resolve (not significant, or Satterthwaite's
                // nu = 2 c^2 / var below 1) the chi-squared upper bound can run off to absurd
                // values (seen: 1e22 for a term 1e-5 of the curve); the curve itself bounds the
                // term there, so cap it (never below the estimate). A resolved term keeps its
                // chi-squared bound: a minimum over many points' bounds is no longer a 97.5%
                // statement about it.
                let nu = 2.0 * ci * ci / var;
                let hi = if nu < 1.0 || !significant {
                    hi.min(data_bound(i)).max(ci)
                } else {
                    hi
                };
                (if significant { lo } else { 0.0 }, hi, false)
            } else if ci > 0.0 {
                (ci, ci, dominant)
            } else {
                // Held at zero: the Fisher bound, capped by the curve as above.
                (0.0, (Z95 * fisher_sd[i]).min(data_bound(i)), false)
            };
            let significant = lo_c > 0.0;
            let (value, lo) = (ci.sqrt(), lo_c.max(0.0).sqrt());
            coef[i] = CoefEstimate {
                value,
                lo,
                hi: hi_c.max(0.0).sqrt(),
                dominant,
                significant,
                determined: dominant && significant && lo >= QUANTITATION_FRACTION * value,
                dominant_at_lo,
                sd_c: sd,
            };
        }
        let gof = gof(prob, &est.g, &s, s_inv.as_ref(), &model);
        FitResult {
            method,
            c,
            coef,
            cov_c,
            gof,
            n_points: j,
            tau_span_s: (prob.tau[0], prob.tau[j - 1]),
            tau0_s: prob.tau0_s,
            iterations: est.iterations,
        }
    }
}
