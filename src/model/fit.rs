//! Fit of the five-term model (THEORY.md section 2) to an AVAR curve, with honest 95% intervals
//! and a calibrated goodness of fit (THEORY.md sections 4 and 5). Works on curve points only.
//!
//! Methods ([`FitMethod`]):
//! - `Model` (default): weighted NNLS in `c = (Q^2, N^2, B^2, K^2, R^2) >= 0` with weights
//!   `1 / Var(AVAR_hat(tau_j))`, `Var = 2 AVAR_model(tau_j)^2 / edf_j`, the model being the current
//!   fit, iterated to a fixed point. Weights from the noisy estimate itself bias the fit low
//!   (THEORY.md section 2); weights from the model do not.
//! - `Paper`: the seed paper's formulas (6)-(7): weights `1/AVAR_hat`, then one fit per term with
//!   weights `term_i / (AVAR_hat * p^2)`, keeping that term's coefficient (SEED.md).
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

use crate::allan::CurvePoint;
use crate::model::avar_cov::{cov_points, strides, AvarCovariance, CovPoint};
use crate::model::nnls::{nnls, NnlsError};
use crate::model::terms::{basis, TERM_NAMES};
pub use crate::stats::chi2_quantile;
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

/// One coefficient of the fit, in its native unit (THEORY.md section 2 table).
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
    /// `dominant && significant && lo >= value * QUANTITATION_FRACTION` (THEORY.md section 2,
    /// with the quantitation condition of [`QUANTITATION_FRACTION`]).
    pub determined: bool,
    /// The term is still the largest at one or more fitted taus when it sits at the lower end of
    /// its interval and the other terms at their profile values there (a stricter reading of
    /// "dominates", compared in docs/fit.md).
    pub dominant_at_lo: bool,
    /// Standard deviation of the squared coefficient `c_i`.
    pub sd_c: f64,
}

/// One coefficient as CONTRACT.md's `fit` record prints it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoefValue {
    pub value: Option<f64>,
    pub lo: f64,
    pub hi: f64,
    pub determined: bool,
}

/// The `coef` object of CONTRACT.md's `fit` record: keys Q, N, B, K, R.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct CoefRecord {
    pub Q: CoefValue,
    pub N: CoefValue,
    pub B: CoefValue,
    pub K: CoefValue,
    pub R: CoefValue,
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

    /// The `coef` object of CONTRACT.md's `fit` record.
    pub fn coef_record(&self) -> CoefRecord {
        let v = |i: usize| {
            let e = &self.coef[i];
            CoefValue {
                value: e.determined.then_some(e.value),
                lo: e.lo,
                hi: e.hi,
                determined: e.determined,
            }
        };
        CoefRecord {
            Q: v(0),
            N: v(1),
            B: v(2),
            K: v(3),
            R: v(4),
        }
    }

    /// `coef` as JSON (keys Q..R).
    pub fn coef_json(&self) -> serde_json::Value {
        serde_json::to_value(self.coef_record()).unwrap_or(serde_json::Value::Null)
    }

    /// The fields this module owns in the `fit` record: `{"coef": {...}, "gof": ...}` (gof null
    /// when not finite, e.g. as many parameters as points).
    pub fn record_fields(&self) -> serde_json::Value {
        serde_json::json!({
            "coef": self.coef_json(),
            "gof": if self.gof.is_finite() { Some(self.gof) } else { None },
        })
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

    /// Fit the AVAR curve `points` (THEORY.md section 2).
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
        // The slope bound of each term from the points' 97.5% upper limits (THEORY.md section
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

/// `c' t c` for a symmetric `t` (its upper triangle is read).
fn quad_form(t: &[[f64; 5]; 5], c: &[f64; 5]) -> f64 {
    let mut q = 0.0;
    for a in 0..5 {
        let mut row = 0.0;
        for b in a + 1..5 {
            row += t[a][b] * c[b];
        }
        q += c[a] * (t[a][a] * c[a] + 2.0 * row);
    }
    q
}

/// Term `i`, at `ci`, is the largest of the five at one fitted tau or more, the others at `c`.
fn dominates(x: &DMatrix<f64>, i: usize, ci: f64, c: &[f64; 5]) -> bool {
    ci > 0.0
        && (0..x.nrows()).any(|k| {
            let own = x[(k, i)] * ci;
            (0..5).all(|t| t == i || x[(k, t)] * c[t] <= own)
        })
}

/// One coefficient's interval from [`inverted_intervals`], in `c_i` (squared units).
#[derive(Debug, Clone, Copy)]
struct Inverted {
    lo: f64,
    /// `None`: no finite upper end (the term's own noise at any trial value is as large as it).
    hi: Option<f64>,
    /// The profile model at `c_i = lo`.
    c_at_lo: [f64; 5],
}

/// 95% intervals by test inversion, with the variance under the null (THEORY.md section 4: the
/// variance of the estimates follows from the model; here from the trial model, not the fitted
/// one, as in Wilson's score interval for a proportion). For each term `i` and trial value `t`:
/// the other terms take their profile values `c_-i(t) = c_hat_-i + Cov(c_-i, c_i) / Var(c_i)
/// (t - c_hat_i)` (the maximum of the estimator's Gaussian approximation given `c_i = t`),
/// clipped at zero; the estimate's variance there is `r' S(c(t)) r` (`r` the row of the linear
/// map `c = G y`, `S` the analytic covariance of the AVAR estimates, exactly quadratic in `c`);
/// `t` is accepted when `(c_hat_i - t)^2 <= 1.96^2 r' S(c(t)) r`. Near zero the fitted model's
/// variance understates the variance at the truth when the estimate came out low; this does
/// not. A term held at zero by the NNLS uses the row of the unconstrained weighted fit (weights
/// `edf / (2 AVAR_model^2)`, all allowed terms free) and its estimate counts as 0.
fn inverted_intervals(
    prob: &Problem,
    g: &DMatrix<f64>,
    s: &DMatrix<f64>,
    c: &[f64; 5],
    cov_c: &[[f64; 5]; 5],
    tensors: &[[[f64; 5]; 5]],
    free_rows: bool,
) -> [Option<Inverted>; 5] {
    let j = prob.tau.len();
    let mut out = [None; 5];
    if tensors.len() != j * (j + 1) / 2 {
        return out;
    }
    // The unconstrained weighted fit's map, for terms the NNLS holds at zero.
    let held: Vec<usize> = (0..5)
        .filter(|&i| prob.allowed[i] && !(c[i] > 0.0 && g.row(i).iter().any(|v| *v != 0.0)))
        .collect();
    let free = if !free_rows && held.is_empty() {
        None
    } else {
        free_map(prob, c).map(|gf| {
            let cov = &gf * s * gf.transpose();
            (gf, cov)
        })
    };
    for i in 0..5 {
        if !prob.allowed[i] {
            continue;
        }
        let is_held = held.contains(&i);
        let (row, dir): (Vec<f64>, [f64; 5]) = if free_rows || is_held {
            let Some((gf, cov)) = free.as_ref() else {
                continue;
            };
            let cii = cov[(i, i)];
            if !(cii.is_finite() && cii > 0.0) {
                continue;
            }
            (
                gf.row(i).iter().copied().collect(),
                std::array::from_fn(|t| {
                    if prob.allowed[t] {
                        cov[(t, i)] / cii
                    } else {
                        0.0
                    }
                }),
            )
        } else {
            let cii = cov_c[i][i];
            if !(cii.is_finite() && cii > 0.0) {
                continue;
            }
            (
                g.row(i).iter().copied().collect(),
                std::array::from_fn(|t| cov_c[t][i] / cii),
            )
        };
        // v = sum_kl r_k r_l T_kl: the estimate's variance is c' v c for any model c.
        let mut v = [[0.0; 5]; 5];
        let mut idx = 0;
        for k in 0..j {
            for l in k..j {
                let w = if k == l { 1.0 } else { 2.0 } * row[k] * row[l];
                let t = &tensors[idx];
                idx += 1;
                if w == 0.0 {
                    continue;
                }
                // The upper triangle (T is symmetric, and T[4][4] = 0: the ramp enters only
                // through the means).
                for a in 0..4 {
                    for b in a..5 {
                        v[a][b] += w * t[a][b];
                    }
                }
            }
        }
        let upper = v;
        for (a, row) in v.iter_mut().enumerate() {
            for (b, x) in row.iter_mut().enumerate().take(a) {
                *x = upper[b][a];
            }
        }
        let ci = if is_held { 0.0 } else { c[i] };
        let profile = |t: f64| -> [f64; 5] {
            std::array::from_fn(|a| {
                if a == i {
                    t
                } else {
                    (c[a] + dir[a] * (t - ci)).max(0.0)
                }
            })
        };
        let var_at = |m: &[f64; 5]| -> f64 { quad_form(&v, m).max(0.0) };
        // Accepted where f <= 0.
        let f = |t: f64| (ci - t) * (ci - t) - Z95 * Z95 * var_at(&profile(t));
        let var_hat = var_at(&profile(ci));
        if !(var_hat.is_finite() && var_hat > 0.0) {
            continue;
        }
        let bisect = |mut a: f64, mut b: f64| -> f64 {
            // f(a) <= 0 < f(b); returns the accepted end.
            // To 1e-7 of the end: far below the interval's own uncertainty.
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if f(m) <= 0.0 {
                    a = m;
                } else {
                    b = m;
                }
                if (b - a).abs() <= 1e-7 * b.abs().max(a.abs()) {
                    break;
                }
            }
            a
        };
        let lo = if ci > 0.0 && f(0.0) > 0.0 {
            bisect(ci, 0.0)
        } else {
            0.0
        };
        // The first rejected value above the estimate, in doubling steps, then bisection.
        let mut step = Z95 * var_hat.sqrt();
        let mut accepted = ci;
        let mut hi = None;
        for _ in 0..200 {
            let t = ci + step;
            if !t.is_finite() {
                break;
            }
            if f(t) > 0.0 {
                hi = Some(bisect(accepted, t));
                break;
            }
            accepted = t;
            step *= 2.0;
        }
        out[i] = Some(Inverted {
            lo,
            hi,
            c_at_lo: profile(lo),
        });
    }
    out
}

/// The linear map of the unconstrained weighted least-squares fit with every allowed term free
/// (weights `edf / (2 AVAR_model^2)` at the model `c`), 5 x J (zero rows for disallowed terms).
fn free_map(prob: &Problem, c: &[f64; 5]) -> Option<DMatrix<f64>> {
    let j = prob.tau.len();
    let cols: Vec<usize> = (0..5).filter(|&t| prob.allowed[t]).collect();
    if cols.len() > j {
        return None;
    }
    let mut model = model_values(&prob.x, c);
    floor_model(&mut model, &prob.y);
    let sw: Vec<f64> = (0..j)
        .map(|r| (prob.edf[r] / (2.0 * model[r] * model[r])).sqrt())
        .collect();
    let mut a = DMatrix::from_fn(j, cols.len(), |r, k| prob.x[(r, cols[k])] * sw[r]);
    let mut scale = vec![0.0; cols.len()];
    for (k, sc) in scale.iter_mut().enumerate() {
        let n = a.column(k).norm();
        *sc = if n > 0.0 { 1.0 / n } else { 0.0 };
        a.column_mut(k).scale_mut(*sc);
    }
    let ata = a.transpose() * &a;
    let inv = ata
        .clone()
        .cholesky()
        .map(|ch| ch.inverse())
        .or_else(|| ata.pseudo_inverse(1e-13).ok())?;
    let gp = inv * a.transpose();
    let mut g = DMatrix::zeros(5, j);
    for (k, &t) in cols.iter().enumerate() {
        for r in 0..j {
            g[(t, r)] = gp[(k, r)] * sw[r] * scale[k];
        }
    }
    Some(g)
}

fn model_values(x: &DMatrix<f64>, c: &[f64; 5]) -> DVector<f64> {
    x * DVector::from_column_slice(c)
}

fn select(points: &[CurvePoint], opts: &FitOptions) -> Result<Problem, FitError> {
    if !opts.terms.iter().any(|t| *t) {
        return Err(FitError::NoTerms);
    }
    let lo = opts.tau_min_s.unwrap_or(0.0);
    let hi = opts.tau_max_s.unwrap_or(f64::INFINITY);
    let mut sel: Vec<&CurvePoint> = points
        .iter()
        .filter(|p| {
            p.tau_s >= lo
                && p.tau_s <= hi
                && p.m >= 1
                && p.count >= 1
                && p.tau_s.is_finite()
                && p.tau_s > 0.0
                && p.var.is_finite()
                && p.var > 0.0
        })
        .collect();
    sel.sort_by(|a, b| a.tau_s.total_cmp(&b.tau_s));
    sel.dedup_by(|a, b| a.m == b.m);
    let need = 2;
    if sel.len() < need {
        return Err(FitError::TooFewPoints {
            usable: sel.len(),
            need,
        });
    }
    let tau0_s = sel[0].tau_s / sel[0].m as f64;
    for p in &sel {
        let t0 = p.tau_s / p.m as f64;
        if (t0 - tau0_s).abs() > 1e-9 * tau0_s {
            return Err(FitError::InconsistentTau0(tau0_s, t0));
        }
    }
    let j = sel.len();
    let tau: Vec<f64> = sel.iter().map(|p| p.tau_s).collect();
    let y = DVector::from_iterator(j, sel.iter().map(|p| p.var));
    // A missing or silly edf falls back to the white-FM large-sample form 3M/(2m) (at least 1).
    let edf: Vec<f64> = sel
        .iter()
        .map(|p| {
            if p.edf.is_finite() && p.edf > 0.0 {
                p.edf
            } else {
                (1.5 * p.count as f64 / p.m as f64).max(1.0)
            }
        })
        .collect();
    let x = DMatrix::from_fn(
        j,
        5,
        |r, t| {
            if opts.terms[t] {
                basis(tau[r])[t]
            } else {
                0.0
            }
        },
    );
    // Covariance counts and strides from the whole curve (a strided level's span, see
    // `cov_points`).
    let all_cov = cov_points(points);
    let all_strides = strides(points);
    let index: Vec<Option<usize>> = sel
        .iter()
        .map(|p| points.iter().position(|q| std::ptr::eq(q, *p)))
        .collect();
    let cov_pts = sel
        .iter()
        .zip(&index)
        .map(|(p, i)| {
            i.map(|i| all_cov[i]).unwrap_or(CovPoint {
                m: p.m,
                count: p.count,
            })
        })
        .collect();
    let cov_strides = index
        .iter()
        .map(|i| i.map_or(1, |i| all_strides[i]))
        .collect();
    Ok(Problem {
        tau,
        y,
        edf,
        x,
        cov_pts,
        cov_strides,
        tau0_s,
        allowed: opts.terms,
    })
}

/// Weighted NNLS: minimise `sum_j w_j (z_j - (X c)_j)^2`, `c >= 0`, with the columns scaled to
/// unit norm for conditioning. Returns `c` and the linear map `G` with `c = G z` on the passive
/// set (zeros elsewhere).
fn weighted_nnls(
    x: &DMatrix<f64>,
    z: &DVector<f64>,
    w: &[f64],
    allowed: &[bool; 5],
) -> Result<([f64; 5], DMatrix<f64>), FitError> {
    let sol = weighted_nnls_solve(x, z, w, allowed)?;
    Ok((sol.c, sol.map()))
}

/// A solved [`weighted_nnls`] whose map `G` is formed only when asked for (an iterated fit
/// needs the map of its last pass alone).
struct WeightedSolution {
    c: [f64; 5],
    /// The weighted, column-scaled design.
    a: DMatrix<f64>,
    sw: Vec<f64>,
    scale: [f64; 5],
    passive: [bool; 5],
}

fn weighted_nnls_solve(
    x: &DMatrix<f64>,
    z: &DVector<f64>,
    w: &[f64],
    allowed: &[bool; 5],
) -> Result<WeightedSolution, FitError> {
    let j = x.nrows();
    let sw: Vec<f64> = w.iter().map(|v| v.max(0.0).sqrt()).collect();
    let mut a = DMatrix::from_fn(j, 5, |r, t| x[(r, t)] * sw[r]);
    let mut scale = [0.0; 5];
    for t in 0..5 {
        let n = a.column(t).norm();
        scale[t] = if allowed[t] && n > 0.0 { 1.0 / n } else { 0.0 };
        a.column_mut(t).scale_mut(scale[t]);
    }
    let b = DVector::from_fn(j, |r, _| z[r] * sw[r]);
    let sol = nnls(&a, &b)?;
    let mut c = [0.0; 5];
    for t in 0..5 {
        c[t] = sol.x[t] * scale[t];
    }
    Ok(WeightedSolution {
        c,
        a,
        sw,
        scale,
        passive: std::array::from_fn(|t| sol.passive[t]),
    })
}

impl WeightedSolution {
    /// `G` on the passive set: `(A_P' A_P)^-1 A_P' diag(sw)`, then the column scaling undone.
    fn map(&self) -> DMatrix<f64> {
        let (a, sw, scale, c) = (&self.a, &self.sw, &self.scale, &self.c);
        let j = a.nrows();
        let cols: Vec<usize> = (0..5).filter(|&t| self.passive[t] && c[t] > 0.0).collect();
        let mut g = DMatrix::zeros(5, j);
        if !cols.is_empty() {
            let ap = a.select_columns(&cols);
            let ata = ap.transpose() * &ap;
            let inv = ata
                .clone()
                .cholesky()
                .map(|ch| ch.inverse())
                .or_else(|| ata.pseudo_inverse(1e-13).ok());
            if let Some(inv) = inv {
                let gp = inv * ap.transpose();
                for (k, &t) in cols.iter().enumerate() {
                    for r in 0..j {
                        g[(t, r)] = gp[(k, r)] * sw[r] * scale[t];
                    }
                }
            }
        }
        g
    }
}

fn converged(old: &[f64; 5], new: &[f64; 5], x: &DMatrix<f64>, tol: f64) -> bool {
    // Compare each term's largest contribution over the taus with the model there.
    let model = model_values(x, new);
    (0..5).all(|t| {
        (0..x.nrows()).all(|r| (x[(r, t)] * (new[t] - old[t])).abs() <= tol * model[r].abs())
    })
}

fn floor_model(model: &mut DVector<f64>, y: &DVector<f64>) {
    let floor = 1e-12 * y.amax();
    for v in model.iter_mut() {
        *v = v.max(floor);
    }
}

/// THEORY.md section 2: weights `edf_j / (2 AVAR_model(tau_j)^2)` at the current model, iterated.
fn est_model(prob: &Problem, opts: &FitOptions) -> Result<Estimate, FitError> {
    // Start from the data's own weights, then move the weights to the model.
    let w0: Vec<f64> = (0..prob.y.len())
        .map(|r| prob.edf[r] / (2.0 * prob.y[r] * prob.y[r]))
        .collect();
    let mut sol = weighted_nnls_solve(&prob.x, &prob.y, &w0, &prob.allowed)?;
    let mut c = sol.c;
    let mut iterations = 0;
    for _ in 0..opts.max_iter {
        iterations += 1;
        let mut model = model_values(&prob.x, &c);
        floor_model(&mut model, &prob.y);
        let w: Vec<f64> = (0..prob.y.len())
            .map(|r| prob.edf[r] / (2.0 * model[r] * model[r]))
            .collect();
        sol = weighted_nnls_solve(&prob.x, &prob.y, &w, &prob.allowed)?;
        let done = converged(&c, &sol.c, &prob.x, opts.rel_tol);
        c = sol.c;
        if done {
            break;
        }
    }
    // The map of the last pass (the one that produced c).
    let g = sol.map();
    Ok(Estimate { c, g, iterations })
}

/// The seed paper's formulas (6)-(7) (SEED.md).
fn est_paper(prob: &Problem) -> Result<Estimate, FitError> {
    let j = prob.y.len();
    let w1: Vec<f64> = (0..j).map(|r| 1.0 / prob.y[r]).collect();
    let (c1, g1) = weighted_nnls(&prob.x, &prob.y, &w1, &prob.allowed)?;
    let mut model = model_values(&prob.x, &c1);
    floor_model(&mut model, &prob.y);
    let mut c = [0.0; 5];
    let mut g = DMatrix::zeros(5, j);
    for i in 0..5 {
        if c1[i] <= 0.0 {
            continue;
        }
        // P = term_i / (AVAR_hat * p^2), formula (7).
        let w: Vec<f64> = (0..j)
            .map(|r| prob.x[(r, i)] * c1[i] / (prob.y[r] * model[r]))
            .collect();
        let (ci, gi) = weighted_nnls(&prob.x, &prob.y, &w, &prob.allowed)?;
        c[i] = ci[i];
        g.set_row(i, &gi.row(i));
        if ci[i] <= 0.0 {
            // The per-term fit dropped it; keep the first-pass value rather than lose the term.
            c[i] = c1[i];
            g.set_row(i, &g1.row(i));
        }
    }
    Ok(Estimate {
        c,
        g,
        iterations: 2,
    })
}

/// IEEE Std 952 slope read-out: `c_i = min_j AVAR_hat_j / basis_i(tau_j)` (the line of the term's
/// slope that touches the curve from below).
fn est_slopes(prob: &Problem) -> Estimate {
    let j = prob.y.len();
    let mut c = [0.0; 5];
    let mut g = DMatrix::zeros(5, j);
    for i in 0..5 {
        if !prob.allowed[i] {
            continue;
        }
        let mut best = (f64::INFINITY, 0);
        for r in 0..j {
            let v = prob.y[r] / prob.x[(r, i)];
            if v < best.0 {
                best = (v, r);
            }
        }
        c[i] = best.0;
        g[(i, best.1)] = 1.0 / prob.x[(best.1, i)];
    }
    Estimate {
        c,
        g,
        iterations: 1,
    }
}

/// Unweighted least squares of `ln AVAR` by Gauss-Newton steps, each an NNLS in `c`.
fn est_loglog(prob: &Problem, opts: &FitOptions) -> Result<Estimate, FitError> {
    let j = prob.y.len();
    let w0: Vec<f64> = (0..j).map(|r| 1.0 / (prob.y[r] * prob.y[r])).collect();
    let (mut c, mut g) = weighted_nnls(&prob.x, &prob.y, &w0, &prob.allowed)?;
    let mut iterations = 0;
    for _ in 0..opts.max_iter {
        iterations += 1;
        let mut model = model_values(&prob.x, &c);
        floor_model(&mut model, &prob.y);
        // ln y ~ ln m + (X c - m)/m  =>  minimise sum ((m (1 + ln(y/m)) - X c) / m)^2.
        let z = DVector::from_fn(j, |r, _| model[r] * (1.0 + (prob.y[r] / model[r]).ln()));
        let w: Vec<f64> = (0..j).map(|r| 1.0 / (model[r] * model[r])).collect();
        let (c_new, g_new) = weighted_nnls(&prob.x, &z, &w, &prob.allowed)?;
        // dz/dy = m / y.
        let mut g_y = g_new;
        for r in 0..j {
            let f = model[r] / prob.y[r];
            for t in 0..5 {
                g_y[(t, r)] *= f;
            }
        }
        let done = converged(&c, &c_new, &prob.x, opts.rel_tol.max(1e-7));
        c = c_new;
        g = g_y;
        if done {
            break;
        }
    }
    Ok(Estimate { c, g, iterations })
}

/// Chi-squared interval for `c` with Satterthwaite degrees of freedom `nu = 2 c^2 / var`.
fn chi2_interval(c: f64, var: f64) -> (f64, f64) {
    let nu = 2.0 * c * c / var;
    if nu > 1e6 {
        let h = Z95 * var.sqrt();
        return (c - h, c + h);
    }
    let lo = nu * c / chi2_quantile(nu, 0.975);
    let hi = nu * c / chi2_quantile(nu, 0.025);
    if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (0.0, c + Z95 * var.sqrt())
    }
}

/// Standard deviation of each allowed `c_i` from the Fisher information `X' S^-1 X` of the full
/// model (all allowed terms free): the scale of an upper bound for a term held at zero.
fn fisher_sd(prob: &Problem, s_inv: Option<&DMatrix<f64>>) -> [f64; 5] {
    let cols: Vec<usize> = (0..5).filter(|&t| prob.allowed[t]).collect();
    let mut out = [0.0; 5];
    let Some(s_inv) = s_inv else {
        return out;
    };
    let xp = prob.x.select_columns(&cols);
    // Column scaling for conditioning.
    let sc: Vec<f64> = (0..cols.len())
        .map(|k| 1.0 / xp.column(k).norm().max(f64::MIN_POSITIVE))
        .collect();
    let xs = DMatrix::from_fn(xp.nrows(), xp.ncols(), |r, k| xp[(r, k)] * sc[k]);
    let f = xs.transpose() * s_inv * &xs;
    if let Ok(inv) = f.pseudo_inverse(1e-12) {
        for (k, &t) in cols.iter().enumerate() {
            out[t] = inv[(k, k)].max(0.0).sqrt() * sc[k];
        }
    }
    out
}

/// Inverse of a symmetric positive (semi)definite matrix: Cholesky, with a small ridge when the
/// strong correlation between neighbouring taus makes it numerically singular.
fn spd_inverse(s: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = s.nrows();
    // Work on the correlation matrix so the ridge is relative.
    let d: Vec<f64> = (0..n)
        .map(|i| s[(i, i)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let corr = DMatrix::from_fn(n, n, |i, j| s[(i, j)] / (d[i] * d[j]));
    for ridge in [0.0, 1e-12, 1e-10, 1e-8, 1e-6] {
        let mut m = corr.clone();
        for i in 0..n {
            m[(i, i)] += ridge;
        }
        if let Some(ch) = m.cholesky() {
            let inv = ch.inverse();
            return Some(DMatrix::from_fn(n, n, |i, j| inv[(i, j)] / (d[i] * d[j])));
        }
    }
    None
}

/// `e' S^-1 e / tr(S^-1 P S P')` with `e = y - X c` and `P = I - X G` (the expectation of the
/// numerator when the model is right, to first order): about 1 for a correct model.
fn gof(
    prob: &Problem,
    g: &DMatrix<f64>,
    s: &DMatrix<f64>,
    s_inv: Option<&DMatrix<f64>>,
    model: &DVector<f64>,
) -> f64 {
    let j = prob.y.len();
    let Some(s_inv) = s_inv else {
        return f64::NAN;
    };
    let e = &prob.y - model;
    let num = (e.transpose() * s_inv * &e)[0];
    let p = DMatrix::<f64>::identity(j, j) - &prob.x * g;
    let den = (s_inv * &p * s * p.transpose()).trace();
    if den > 1e-9 {
        num / den
    } else {
        f64::NAN
    }
}
