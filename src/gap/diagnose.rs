//! The diagnosis proper (THEORY.md section 5): where the measured AVAR curve departs from the
//! fitted five-term model (on the tau axis and in time), which effect of THEORY.md section 3
//! closes the gap, and by how much. Works on an [`EvidenceSnapshot`]; pure and synchronous.
//!
//! # Method
//!
//! - Covariance. `S`, the covariance of the log estimates `ln AVAR_hat(tau_j)`, is the analytic
//!   covariance of the five-term model fitted to the curve ([`AvarCovariance`], full-overlap
//!   counts), divided by `AVAR_i AVAR_j`. It is computed once per curve and used for every
//!   candidate model, so the gap statistics of different models are comparable. A ridge
//!   `S + RIDGE diag(S)` keeps the inverse from amplifying the small mismatch between the
//!   analytic covariance and the bounded-overlap estimator in its smallest eigen-directions;
//!   [`Thresholds`] are calibrated by simulation with that ridge.
//! - Fit of a model (five terms plus effect columns): generalised least squares with the
//!   covariance `D S D`, `D = diag(model)`, solved as NNLS after whitening, reweighted from the
//!   model a few times (weights from the data bias the fit low: THEORY.md section 2).
//! - Gap statistic `G = r' S^-1 r / (J - p)`, `r = ln AVAR_hat - ln AVAR_model` (THEORY.md
//!   section 5); near 1 when the model is right.
//! - Effects: for each candidate, its shape parameter on a log grid (NNLS at each), the best one
//!   polished by golden section; the candidate with the largest drop in `r' S^-1 r` is added if
//!   the drop exceeds [`Thresholds::add_chi2`] per parameter, and effects are added while `G`
//!   stays above [`Thresholds::gap_crit`]. A candidate also flags the model on its own when its
//!   drop per parameter exceeds its own [`Thresholds::lr_crit`] (a likelihood-ratio test
//!   against the named alternatives, which catches bumps that the omnibus `G` misses).
//! - Bias jumps have the second-order law of a rate random walk (K absorbs them on the curve),
//!   so they are found in time: steps in the block-mean rate by generalised least squares with
//!   the fitted model's noise covariance, forward selection ([`detect_steps`]).
//! - A warm-up is found in time too ([`fit_warmup`]): its test statistic is the block-mean
//!   evidence integrated over the scanned time constant ([`WarmupFinding::log_bf`], against
//!   [`Thresholds::warmup_bf`]), not its maximum (docs/gap.md, "Mixture statistics").

use super::effects::{effect_column, EffectKind, EffectParams, Grid};
use super::evidence::EvidenceSnapshot;
use crate::allan::CurvePoint;
use crate::model::avar_cov::{AvarCovariance, CovPoint};
use crate::model::fit::{fit, FitOptions};
use crate::model::nnls::nnls;
use crate::model::terms::{self, basis};
use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Ridge added to the log covariance, as a fraction of its diagonal (see the module doc).
pub const RIDGE: f64 = 0.05;
/// Reweighting passes of each GLS fit (the model-weighted fit settles in 3-5).
const GLS_PASSES: usize = 4;

/// Decision thresholds, calibrated by simulation of correct models (docs/gap.md, "Calibration").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// `G` above this flags the model (about the null 97% quantile, leaving room for the
    /// time-domain tests within a 5% overall false-alarm rate).
    pub gap_crit: f64,
    /// Simultaneous band on `|z_j| = |r_j| / sqrt(S_jj)`: the whole correct curve stays inside
    /// it in 95% of runs.
    pub band_z: f64,
    /// Drop in `r' S^-1 r` per added parameter needed to add an effect once the model is
    /// flagged.
    pub add_chi2: f64,
    /// Drop in `r' S^-1 r` per added parameter by a stationary candidate that flags the model
    /// on its own, even when `G <= gap_crit` (a likelihood-ratio test against the named
    /// alternatives, more sensitive to them than the omnibus `G`), one threshold per candidate
    /// because their scans are searches of very different sizes (12 shapes per decade for the
    /// Gauss-Markov term, 60 for the sinusoid): Gauss-Markov, sinusoid, output filter. Set so
    /// that their union stays within the false-alarm budget (docs/gap.md, "Calibration").
    pub lr_crit: [f64; 3],
    /// z scores (square roots of the drops of the whitened residual sum of squares at forward
    /// selection) that steps in the block means need to count as bias jumps: at least `k`
    /// steps at `z >= jump_z[k - 1]` ([`detect_steps`]).
    pub jump_z: [f64; 3],
    /// Drop of the block-mean residual sum of squares (in robust block variances) that a
    /// warm-up must bring at its best `T` ([`fit_warmup`]'s `w_stat`); infinite: not used.
    pub warmup_w: f64,
    /// The warm-up's evidence integrated over the scanned `T` ([`WarmupFinding::log_bf`]) that
    /// a warm-up must bring. A warm-up is found when either statistic passes its threshold.
    pub warmup_bf: f64,
}

impl Thresholds {
    /// The likelihood-ratio threshold of a stationary candidate (`lr_crit`); infinite for the
    /// effects found in time.
    pub fn lr_crit_of(&self, kind: EffectKind) -> f64 {
        match kind {
            EffectKind::GaussMarkov => self.lr_crit[0],
            EffectKind::Sinusoid => self.lr_crit[1],
            EffectKind::OutputFilter => self.lr_crit[2],
            EffectKind::Warmup | EffectKind::BiasJumps => f64::INFINITY,
        }
    }
}

impl Default for Thresholds {
    fn default() -> Self {
        Self {
            gap_crit: 1.9,
            band_z: 2.5,
            add_chi2: 3.0,
            lr_crit: [5.5, 7.0, 7.0],
            jump_z: [4.5, 4.0, 3.4],
            // The integrated statistic replaces the maximum (docs/gap.md, "Mixture
            // statistics"): at the same share of clean runs its tail is steadier across seeds.
            warmup_w: f64::INFINITY,
            warmup_bf: 3.39,
        }
    }
}

/// What to diagnose.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseOptions {
    /// Taus up to this fraction of the run are used (longer ones have too few degrees of
    /// freedom for the Gaussian approximation of the log estimate).
    pub tau_max_fraction: f64,
    /// At most this many effects are added.
    pub max_effects: usize,
    pub candidates: Vec<EffectKind>,
    pub thresholds: Thresholds,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            tau_max_fraction: 0.1,
            max_effects: 2,
            candidates: EffectKind::ALL.to_vec(),

            thresholds: Thresholds::default(),
        }
    }
}

/// Why no diagnosis could be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DiagnoseError {
    #[error("diagnose: {0} usable curve points, need at least {1} (run too short?)")]
    TooFewPoints(usize, usize),
    #[error("diagnose: the five-term fit failed: {0}")]
    Fit(String),
    #[error("diagnose: the covariance of the curve is not positive definite")]
    Covariance,
}

/// The verdict of CONTRACT.md's `diagnosis` record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Consistent,
    Explained,
    Unexplained,
}

/// A run of taus where the model misses the curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    pub tau_lo_s: f64,
    pub tau_hi_s: f64,
    /// +1 where the data lie above the model.
    pub sign: i32,
    /// Measured ADEV over model ADEV at the worst tau of the run.
    pub worst_ratio: f64,
}

/// An effect added to the model, with the gap once it is in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AddedEffect {
    pub params: EffectParams,
    pub gap_after: f64,
    /// Drop of `r' S^-1 r` it brought.
    pub delta_chi2: f64,
}

/// Homogeneity of one tau across the segments (THEORY.md section 5, "Where in time").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentTest {
    pub tau_s: f64,
    /// `sum_k (ln v_k - mean)^2 / Var(ln v_k)` over `K - 1`: about 1 when homogeneous.
    pub stat: f64,
    /// Probability of a larger statistic under homogeneity (chi-squared with K - 1 dof).
    pub p_value: f64,
    /// The segment that departs most, and its ADEV over the segments' geometric mean.
    pub worst_segment: usize,
    pub worst_ratio: f64,
}

/// Bias jumps found in the block means.
#[derive(Debug, Clone, PartialEq)]
pub struct JumpFinding {
    /// Times of the jumps (s from the start).
    pub times_s: Vec<f64>,
    /// Estimated sizes (u/s).
    pub sizes: Vec<f64>,
    /// The z score of each jump when forward selection added it.
    pub z_scores: Vec<f64>,
    /// Block length used (s).
    pub block_s: f64,
}

impl JumpFinding {
    /// The steps as sample indices (at `tau0_s`) and sizes (u/s), with steps less than 1.5
    /// blocks apart merged into one: a jump inside a block is split by the search over two
    /// differences. A merged step has the summed size, at its members' |size|-weighted time.
    pub fn merged_steps(&self, tau0_s: f64) -> (Vec<u64>, Vec<f64>) {
        let mut order: Vec<usize> = (0..self.sizes.len()).collect();
        order.sort_by(|&a, &b| self.times_s[a].total_cmp(&self.times_s[b]));
        // (|size|-weighted time sum, weight, size) per merged step.
        let mut merged: Vec<(f64, f64, f64)> = Vec::new();
        let mut last_t = f64::NEG_INFINITY;
        for i in order {
            let (t, sz) = (self.times_s[i], self.sizes[i]);
            match merged.last_mut() {
                Some(g) if t - last_t < 1.5 * self.block_s => {
                    g.0 += t * sz.abs();
                    g.1 += sz.abs();
                    g.2 += sz;
                }
                _ => merged.push((t * sz.abs(), sz.abs(), sz)),
            }
            last_t = t;
        }
        let positions = merged
            .iter()
            .map(|g| (g.0 / g.1.max(f64::MIN_POSITIVE) / tau0_s).round().max(0.0) as u64)
            .collect();
        (positions, merged.iter().map(|g| g.2).collect())
    }

    /// The jumps that pass the rule "at least `k` jumps with `z >= z_crit[k - 1]`" for the
    /// largest `k` it holds for (`z_crit` non-increasing): those with `z >= z_crit[k - 1]`.
    /// None pass when the rule holds for no `k`.
    pub fn accepted(&self, z_crit: &[f64]) -> JumpFinding {
        let mut zs = self.z_scores.clone();
        zs.sort_by(|a, b| b.total_cmp(a));
        let level = (1..=z_crit.len())
            .rev()
            .find(|&k| zs.get(k - 1).is_some_and(|&z| z >= z_crit[k - 1]))
            .map_or(f64::INFINITY, |k| z_crit[k - 1]);
        let keep: Vec<usize> = (0..self.z_scores.len())
            .filter(|&i| self.z_scores[i] >= level)
            .collect();
        JumpFinding {
            times_s: keep.iter().map(|&i| self.times_s[i]).collect(),
            sizes: keep.iter().map(|&i| self.sizes[i]).collect(),
            z_scores: keep.iter().map(|&i| self.z_scores[i]).collect(),
            block_s: self.block_s,
        }
    }
}

/// The full diagnosis of one channel.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnosis {
    pub gap_before: f64,
    pub gap_after: f64,
    pub verdict: Verdict,
    pub regions: Vec<Region>,
    /// Regions still outside the band with the effects in.
    pub regions_after: Vec<Region>,
    pub effects: Vec<AddedEffect>,
    /// The five-term fit alone, `(Q, N, B, K, R)`.
    pub base_coef: [f64; 5],
    /// The five terms with the effects in.
    pub final_coef: [f64; 5],
    /// Taus used and the number of them.
    pub tau_span_s: (f64, f64),
    pub n_taus: usize,
    pub t_data_s: f64,
    pub segment_tests: Vec<SegmentTest>,
    pub jumps: Option<JumpFinding>,
    /// A word on what is left when the verdict is `unexplained`.
    pub residual_shape: Option<String>,
    /// The taus of the curve diagnosed (s) and, at each, the AVAR (u^2/s^2) of the five-term
    /// model alone and of the model with the effects in (warm-up and jumps as their exact AVAR
    /// on this record), for plots.
    pub model_tau_s: Vec<f64>,
    pub model_base_avar: Vec<f64>,
    pub model_final_avar: Vec<f64>,
}

/// The curve with its log covariance, ready for GLS fits.
#[derive(Debug, Clone)]
pub struct GapProblem {
    pub ms: Vec<u64>,
    pub tau: Vec<f64>,
    pub y: Vec<f64>,
    ln_y: DVector<f64>,
    /// Inverse Cholesky factor of the ridged log covariance.
    linv: DMatrix<f64>,
    /// Diagonal of the (unridged) log covariance.
    pub s_diag: Vec<f64>,
    /// The unridged log covariance `S` itself (for the oracle bounds of [`super::oracle`]).
    s_plain: DMatrix<f64>,
    /// The unridged covariance seen through the whitening, `Linv S Linv'` (for the expectation
    /// of `r' S_ridge^-1 r`).
    m_white: DMatrix<f64>,
    pub tau0_s: f64,
    pub n_inc: u64,
    /// The plain five-term fit (the paper's model-weighted NNLS) that set the covariance.
    pub c_init: [f64; 5],
}

/// One model to fit: the five terms (N column optionally filtered) plus free effect columns and
/// a fixed offset.
#[derive(Debug, Clone, Default)]
pub struct ModelSpec {
    pub filter_tc_s: Option<f64>,
    pub extra: Vec<Vec<f64>>,
    pub offset: Option<Vec<f64>>,
}

/// A GLS fit.
#[derive(Debug, Clone)]
pub struct GlsFit {
    /// Five-term `c = (Q^2, N^2, B^2, K^2, R^2)` then the extra columns' amplitudes squared.
    pub coef: Vec<f64>,
    pub model: Vec<f64>,
    /// `r' S^-1 r`.
    pub chi2: f64,
    /// Its expectation when the model is right: `tr((I - H) M)` with `H` the whitened hat
    /// matrix of the active columns and `M` the whitened covariance (as fit.rs's gof), less one
    /// per shape parameter (each extra column or filter of the spec).
    pub expected: f64,
}

impl GlsFit {
    /// The gap statistic `G = r' S^-1 r / E[r' S^-1 r]`, about 1 when the model is right.
    pub fn gap(&self) -> f64 {
        self.chi2 / self.expected.max(1.0)
    }
}

impl GapProblem {
    /// Builds the problem from the dense curve of `snap`.
    pub fn new(snap: &EvidenceSnapshot, opts: &DiagnoseOptions) -> Result<Self, DiagnoseError> {
        let n = snap.n_increments.max(1);
        let m_max = ((n as f64) * opts.tau_max_fraction).floor() as u64;
        let pts: Vec<_> = snap
            .curve
            .iter()
            .filter(|p| p.m <= m_max && p.avar.is_finite() && p.avar > 0.0 && p.count > 0)
            .collect();
        let need = 8;
        if pts.len() < need {
            return Err(DiagnoseError::TooFewPoints(pts.len(), need));
        }
        let cps: Vec<CurvePoint> = pts
            .iter()
            .map(|p| CurvePoint {
                m: p.m,
                tau_s: p.tau_s,
                var: p.avar,
                count: p.count,
                edf: f64::NAN,
                alpha: 0,
                sigma_lo: f64::NAN,
                sigma_hi: f64::NAN,
            })
            .collect();
        let base =
            fit(&cps, &FitOptions::default()).map_err(|e| DiagnoseError::Fit(e.to_string()))?;
        let c_init = base.c;
        let tau0 = snap.tau0_s;
        // Full-overlap counts: the bounded estimator's stride-s differences stand for the
        // count * stride differences of the full overlap (THEORY.md section 1).
        let cov_pts: Vec<CovPoint> = pts
            .iter()
            .map(|p| CovPoint {
                m: p.m,
                count: (p.count * p.stride).clamp(1, (n + 1).saturating_sub(2 * p.m).max(1)),
            })
            .collect();
        let cov = AvarCovariance::new().matrix(tau0, &cov_pts, &c_init);
        let a: Vec<f64> = pts
            .iter()
            .map(|p| base.model_avar(p.tau_s).max(1e-300))
            .collect();
        let j = pts.len();
        let mut s = DMatrix::from_fn(j, j, |r, c| cov[(r, c)] / (a[r] * a[c]));
        let s_diag: Vec<f64> = (0..j).map(|i| s[(i, i)]).collect();
        if s_diag.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(DiagnoseError::Covariance);
        }
        let s_plain = s.clone();
        for i in 0..j {
            s[(i, i)] *= 1.0 + RIDGE;
        }
        let chol = s.cholesky().ok_or(DiagnoseError::Covariance)?;
        let l = chol.l();
        let linv = l
            .solve_lower_triangular(&DMatrix::identity(j, j))
            .ok_or(DiagnoseError::Covariance)?;
        let m_white = &linv * &s_plain * linv.transpose();
        Ok(Self {
            ms: pts.iter().map(|p| p.m).collect(),
            tau: pts.iter().map(|p| p.tau_s).collect(),
            y: pts.iter().map(|p| p.avar).collect(),
            ln_y: DVector::from_iterator(j, pts.iter().map(|p| p.avar.ln())),
            linv,
            s_diag,
            s_plain,
            m_white,
            tau0_s: tau0,
            n_inc: n,
            c_init,
        })
    }

    pub fn len(&self) -> usize {
        self.tau.len()
    }

    /// The unridged covariance `S` of `ln AVAR_hat` at the curve's taus (the analytic
    /// covariance of the five-term fit `c_init`, THEORY.md section 5).
    pub fn log_covariance(&self) -> &DMatrix<f64> {
        &self.s_plain
    }

    /// `ln AVAR_hat` at the curve's taus.
    pub fn ln_avar(&self) -> &DVector<f64> {
        &self.ln_y
    }

    /// `L^-1 v`, with `L L'` the ridged covariance the GLS fits whiten with, so that
    /// `|L^-1 r|^2` is the `r' S^-1 r` of [`GapProblem::chi2_of`].
    pub fn whiten(&self, v: &DVector<f64>) -> DVector<f64> {
        &self.linv * v
    }

    pub fn is_empty(&self) -> bool {
        self.tau.is_empty()
    }

    /// The design columns of a spec.
    fn columns(&self, spec: &ModelSpec) -> DMatrix<f64> {
        let j = self.len();
        let k = 5 + spec.extra.len();
        let filt = spec.filter_tc_s.map(|t| {
            effect_column(
                EffectKind::OutputFilter,
                t,
                &self.ms,
                self.tau0_s,
                self.n_inc,
            )
        });
        DMatrix::from_fn(j, k, |r, c| {
            if c < 5 {
                match (&filt, c) {
                    (Some(f), 1) => f[r],
                    _ => basis(self.tau[r])[c],
                }
            } else {
                spec.extra[c - 5][r]
            }
        })
    }

    /// `r' S^-1 r` of a model curve.
    pub fn chi2_of(&self, model: &[f64]) -> f64 {
        let r = DVector::from_iterator(
            self.len(),
            model
                .iter()
                .zip(self.ln_y.iter())
                .map(|(m, ly)| ly - m.max(1e-300).ln()),
        );
        (&self.linv * r).norm_squared()
    }

    /// Generalised least squares with model-based weights, coefficients `>= 0`.
    pub fn gls(&self, spec: &ModelSpec) -> Option<GlsFit> {
        let j = self.len();
        let x = self.columns(spec);
        let k = x.ncols();
        let off = spec.offset.clone().unwrap_or_else(|| vec![0.0; j]);
        let mut d: Vec<f64> = self.y.clone();
        let mut coef = DVector::zeros(k);
        let mut model = vec![0.0; j];
        let mut a_last = DMatrix::zeros(j, k);
        for _ in 0..GLS_PASSES {
            let xd = DMatrix::from_fn(j, k, |r, c| x[(r, c)] / d[r]);
            let yd = DVector::from_fn(j, |r, _| (self.y[r] - off[r]) / d[r]);
            let mut a = &self.linv * xd;
            let b = &self.linv * yd;
            let mut norms = vec![1.0; k];
            for (c, nrm) in norms.iter_mut().enumerate() {
                let v = a.column(c).norm();
                if v > 0.0 && v.is_finite() {
                    *nrm = v;
                    a.column_mut(c).scale_mut(1.0 / v);
                }
            }
            let sol = nnls(&a, &b).ok()?;
            a_last = a.clone();
            coef = DVector::from_fn(k, |c, _| sol.x[c] / norms[c]);
            let mv = &x * &coef;
            for r in 0..j {
                model[r] = mv[r] + off[r];
            }
            // Floor the weights' model at a tiny fraction of the data (a term-less stretch).
            for r in 0..j {
                d[r] = model[r].max(1e-6 * self.y[r]);
            }
        }
        let chi2 = self.chi2_of(&model);
        let active: Vec<usize> = (0..k).filter(|&c| coef[c] > 0.0).collect();
        let tr_m = self.m_white.trace();
        let mut expected = tr_m;
        if !active.is_empty() {
            let xa = a_last.select_columns(&active);
            let xtx = xa.transpose() * &xa;
            if let Some(inv) = xtx.try_inverse() {
                expected -= (inv * xa.transpose() * &self.m_white * &xa).trace();
            }
        }
        let n_shape = spec.extra.len() + usize::from(spec.filter_tc_s.is_some());
        expected -= n_shape as f64 * tr_m / j as f64;
        Some(GlsFit {
            coef: coef.iter().copied().collect(),
            model,
            chi2,
            expected,
        })
    }

    /// Per-tau `z_j = r_j / sqrt(S_jj)` of a model.
    pub fn z(&self, model: &[f64]) -> Vec<f64> {
        (0..self.len())
            .map(|i| (self.ln_y[i] - model[i].max(1e-300).ln()) / self.s_diag[i].sqrt())
            .collect()
    }

    /// Runs of taus outside `|z| < band` with their sign and worst ADEV ratio.
    pub fn regions(&self, model: &[f64], band: f64) -> Vec<Region> {
        let z = self.z(model);
        let mut out: Vec<Region> = Vec::new();
        let mut open: Option<(usize, i32, usize)> = None; // start, sign, worst index
        for i in 0..=z.len() {
            let s = z.get(i).map(|&v| {
                if v > band {
                    1
                } else if v < -band {
                    -1
                } else {
                    0
                }
            });
            match (open, s) {
                (Some((st, sg, w)), Some(s)) if s == sg => {
                    let w = if z[i].abs() > z[w].abs() { i } else { w };
                    open = Some((st, sg, w));
                }
                (cur, s) => {
                    if let Some((st, sg, w)) = cur {
                        out.push(Region {
                            tau_lo_s: self.tau[st],
                            tau_hi_s: self.tau[i - 1],
                            sign: sg,
                            worst_ratio: (self.y[w] / model[w].max(1e-300)).sqrt(),
                        });
                    }
                    open = match s {
                        Some(s) if s != 0 => Some((i, s, i)),
                        _ => None,
                    };
                }
            }
        }
        out
    }

    /// The shape grid of a candidate over this curve.
    pub fn grid(&self, kind: EffectKind) -> Grid {
        let tmin = self.tau[0];
        let tmax = self.tau[self.len() - 1];
        let t_run = self.n_inc as f64 * self.tau0_s;
        match kind {
            EffectKind::GaussMarkov => Grid {
                lo: tmin / 2.0,
                hi: tmax,
                per_decade: 12.0,
            },
            // First maximum of the sinusoid's AVAR at 0.371 / f0 (THEORY.md section 3).
            EffectKind::Sinusoid => Grid {
                lo: 0.371 / tmax,
                hi: (0.5 / self.tau0_s).min(0.371 / tmin * 2.0),
                per_decade: 60.0,
            },
            EffectKind::OutputFilter => Grid {
                lo: 0.3 * self.tau0_s,
                hi: 30.0 * self.tau0_s,
                per_decade: 12.0,
            },
            EffectKind::Warmup => Grid {
                lo: tmin.max(self.tau0_s * 4.0),
                hi: t_run / 3.0,
                per_decade: 12.0,
            },
            EffectKind::BiasJumps => Grid {
                lo: 1.0,
                hi: 1.0,
                per_decade: 1.0,
            },
        }
    }

    fn spec_with(&self, base: &ModelSpec, kind: EffectKind, shape: f64) -> ModelSpec {
        let mut s = base.clone();
        if kind == EffectKind::OutputFilter {
            s.filter_tc_s = Some(shape);
        } else {
            s.extra.push(effect_column(
                kind,
                shape,
                &self.ms,
                self.tau0_s,
                self.n_inc,
            ));
        }
        s
    }

    /// Best shape of one candidate on top of `base`: grid scan, then golden-section polish
    /// in `ln shape`. Returns `(shape, fit)`.
    pub fn scan(&self, base: &ModelSpec, kind: EffectKind) -> Option<(f64, GlsFit)> {
        let pts = self.grid(kind).points();
        if pts.len() < 2 {
            return None;
        }
        let eval = |sh: f64| self.gls(&self.spec_with(base, kind, sh));
        let mut best: Option<(usize, f64)> = None;
        for (i, &sh) in pts.iter().enumerate() {
            if let Some(f) = eval(sh) {
                if best.is_none_or(|(_, c)| f.chi2 < c) {
                    best = Some((i, f.chi2));
                }
            }
        }
        let (bi, _) = best?;
        let mut lo = pts[bi.saturating_sub(1)].ln();
        let mut hi = pts[(bi + 1).min(pts.len() - 1)].ln();
        let g = 0.618_033_988_749_895;
        let f = |x: f64| eval(x.exp()).map_or(f64::INFINITY, |f| f.chi2);
        let mut x1 = hi - g * (hi - lo);
        let mut x2 = lo + g * (hi - lo);
        let (mut f1, mut f2) = (f(x1), f(x2));
        for _ in 0..24 {
            if f1 < f2 {
                hi = x2;
                x2 = x1;
                f2 = f1;
                x1 = hi - g * (hi - lo);
                f1 = f(x1);
            } else {
                lo = x1;
                x1 = x2;
                f1 = f2;
                x2 = lo + g * (hi - lo);
                f2 = f(x2);
            }
        }
        let cand = [pts[bi].ln(), 0.5 * (lo + hi)];
        cand.iter()
            .filter_map(|&x| eval(x.exp()).map(|fit| (x.exp(), fit)))
            .min_by(|a, b| a.1.chi2.total_cmp(&b.1.chi2))
    }
}

/// Five-term `(Q, N, B, K, R)` from `c`.
fn coef5(c: &[f64]) -> [f64; 5] {
    std::array::from_fn(|i| c.get(i).copied().unwrap_or(0.0).max(0.0).sqrt())
}

/// The effect parameters from a fit whose last free column (or filter) is the effect.
fn params_of(kind: EffectKind, shape: f64, fit: &GlsFit) -> EffectParams {
    let amp = fit.coef.last().copied().unwrap_or(0.0).max(0.0).sqrt();
    match kind {
        EffectKind::GaussMarkov => EffectParams::GaussMarkov {
            sigma: amp,
            tau_c_s: shape,
        },
        EffectKind::Sinusoid => EffectParams::Sinusoid {
            amplitude: amp,
            frequency_hz: shape,
        },
        EffectKind::OutputFilter => EffectParams::OutputFilter {
            time_constant_s: shape,
        },
        EffectKind::Warmup => EffectParams::Warmup {
            amplitude: amp,
            time_constant_s: shape,
        },
        EffectKind::BiasJumps => EffectParams::BiasJumps {
            count: 0,
            rms_size: 0.0,
        },
    }
}

/// Diagnoses one channel's evidence.
pub fn diagnose(
    snap: &EvidenceSnapshot,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let prob = GapProblem::new(snap, opts)?;
    let th = opts.thresholds;
    let j = prob.len();
    let base = prob
        .gls(&ModelSpec::default())
        .ok_or(DiagnoseError::Fit("base GLS".into()))?;
    let gap_before = base.gap();
    let regions = prob.regions(&base.model, th.band_z);
    let flagged = gap_before > th.gap_crit;

    let mut effects: Vec<AddedEffect> = Vec::new();
    let block_s = snap.block_len as f64 * snap.tau0_s;
    let t_run = snap.n_increments as f64 * snap.tau0_s;
    let stationary: Vec<EffectKind> = opts
        .candidates
        .iter()
        .copied()
        .filter(|k| !matches!(k, EffectKind::BiasJumps | EffectKind::Warmup))
        .collect();

    // 1. Stationary effects on the curve, while the gap stays significant.
    let mut offset = vec![0.0; j];
    // Flagged by `G`, or by the best candidate's likelihood ratio (add_stationary).
    let (mut spec, mut cur) = add_stationary(
        &prob,
        &stationary,
        &offset,
        &mut effects,
        base.clone(),
        opts,
        true,
    );
    let flagged = flagged || !effects.is_empty();

    // 2. A warm-up, in time: the block means against the model found so far.
    let mut warm_curve: Option<Vec<f64>> = None;
    let mut time_flag = false;
    if opts.candidates.contains(&EffectKind::Warmup) {
        let c5: [f64; 5] = std::array::from_fn(|i| cur.coef.get(i).copied().unwrap_or(0.0));
        let stat_params: Vec<EffectParams> = effects.iter().map(|e| e.params).collect();
        let warm = fit_warmup(&snap.block_means, block_s, t_run, &c5, &stat_params);
        if let Some(w) = warm.filter(|w| w.w_stat > th.warmup_w || w.log_bf > th.warmup_bf) {
            time_flag = true;
            // Its AVAR, exact for the estimator on this record, enters as a fixed offset.
            let col = effect_column(
                EffectKind::Warmup,
                w.time_constant_s,
                &prob.ms,
                prob.tau0_s,
                prob.n_inc,
            );
            for (o, c) in offset.iter_mut().zip(&col) {
                *o += w.amplitude * w.amplitude * c;
            }
            // Keep only the stationary effects still needed beside it, then look again.
            let kept = still_needed(&prob, &effects, &offset, opts);
            let prev = cur.clone();
            let f = prob
                .gls(&spec_from(&prob, &kept, &offset))
                .unwrap_or_else(|| prev.clone());
            // In the order they were added (CONTRACT.md): the stationary effects kept, then
            // the warm-up.
            effects = kept;
            for e in effects.iter_mut() {
                e.gap_after = f.gap();
            }
            effects.push(AddedEffect {
                params: EffectParams::Warmup {
                    amplitude: w.amplitude,
                    time_constant_s: w.time_constant_s,
                },
                gap_after: f.gap(),
                delta_chi2: base.chi2 - f.chi2,
            });
            cur = f;
            if cur.gap() > th.gap_crit {
                let (sp, c2) = add_stationary(
                    &prob,
                    &stationary,
                    &offset,
                    &mut effects,
                    cur.clone(),
                    opts,
                    false,
                );
                spec = sp;
                cur = c2;
            } else {
                spec = spec_from(&prob, &effects, &offset);
            }
            warm_curve = Some(w.block_curve(snap.block_means.len(), block_s));
        }
    }
    let _ = &spec;

    // 3. Bias jumps, in time (after the warm-up is taken out of the block means).
    let jumps = if opts.candidates.contains(&EffectKind::BiasJumps) {
        let resid: Vec<f64> = match &warm_curve {
            Some(wc) => snap
                .block_means
                .iter()
                .zip(wc)
                .map(|(b, w)| b - w)
                .collect(),
            None => snap.block_means.clone(),
        };
        let c5: [f64; 5] = std::array::from_fn(|i| cur.coef.get(i).copied().unwrap_or(0.0));
        let stat_params: Vec<EffectParams> = effects
            .iter()
            .map(|e| e.params)
            .filter(|p| matches!(p.kind(), EffectKind::GaussMarkov | EffectKind::Sinusoid))
            .collect();
        detect_steps(&resid, block_s, &c5, &stat_params, &th.jump_z)
    } else {
        None
    };
    if let Some(f) = jumps.as_ref().filter(|f| !f.sizes.is_empty()) {
        time_flag = true;
        let rms = (f.sizes.iter().map(|s| s * s).sum::<f64>() / f.sizes.len() as f64).sqrt();
        // In law the jumps are part of K (a rate random walk's), but a few large ones leave
        // their own shape on this record's curve, which a stationary candidate may have taken
        // (a slow sinusoid, typically). Their exact AVAR on the record enters as a fixed offset,
        // as a warm-up's does; the stationary effects must then pass the forward rules again.
        let (positions, sizes) = f.merged_steps(prob.tau0_s);
        let mut offset_j = offset.clone();
        for (o, &m) in offset_j.iter_mut().zip(&prob.ms) {
            *o += terms::steps_avar(&positions, &sizes, m, prob.n_inc);
        }
        let kept = still_needed(&prob, &effects, &offset_j, opts);
        let before = cur.chi2;
        if let Some(fit) = prob.gls(&spec_from(&prob, &kept, &offset_j)) {
            effects = kept;
            for e in effects.iter_mut() {
                e.gap_after = fit.gap();
            }
            cur = fit;
        }
        effects.push(AddedEffect {
            params: EffectParams::BiasJumps {
                count: f.sizes.len() as u64,
                rms_size: rms,
            },
            gap_after: cur.gap(),
            delta_chi2: before - cur.chi2,
        });
    }
    let flagged = flagged || time_flag;
    let mut gap_after = cur.gap();
    gap_after = if gap_after.is_finite() {
        gap_after
    } else {
        gap_before
    };
    let verdict = if !flagged {
        Verdict::Consistent
    } else if gap_after <= th.gap_crit {
        Verdict::Explained
    } else {
        Verdict::Unexplained
    };
    let regions_after = prob.regions(&cur.model, th.band_z);
    let residual_shape = (verdict == Verdict::Unexplained).then(|| describe(&regions_after));
    Ok(Diagnosis {
        gap_before,
        gap_after,
        verdict,
        regions,
        regions_after,
        effects,
        base_coef: coef5(&base.coef),
        final_coef: coef5(&cur.coef),
        tau_span_s: (prob.tau[0], prob.tau[j - 1]),
        n_taus: j,
        t_data_s: snap.n_increments as f64 * snap.tau0_s,
        segment_tests: segment_tests(snap, &prob.c_init),
        jumps,
        residual_shape,
        model_tau_s: prob.tau[..j].to_vec(),
        model_base_avar: base.model.clone(),
        model_final_avar: cur.model.clone(),
    })
}

/// The stationary effects of `effects` still needed once `offset` (a warm-up's or jumps' exact
/// AVAR) is in the model, by the rules of the forward search: each must lower `r' S^-1 r` per
/// parameter by `add_chi2` while the model without it is flagged by `G`, by its own
/// likelihood-ratio threshold otherwise. Other entries (warm-ups) are kept as they are.
fn still_needed(
    prob: &GapProblem,
    effects: &[AddedEffect],
    offset: &[f64],
    opts: &DiagnoseOptions,
) -> Vec<AddedEffect> {
    let th = opts.thresholds;
    let with = prob.gls(&spec_from(prob, effects, offset));
    let mut kept: Vec<AddedEffect> = Vec::new();
    for e in effects {
        if !e.params.kind().is_stationary() {
            kept.push(*e);
            continue;
        }
        let others: Vec<AddedEffect> = effects.iter().filter(|o| *o != e).copied().collect();
        let without = prob.gls(&spec_from(prob, &others, offset));
        if let (Some(a), Some(b)) = (with.as_ref(), without) {
            let crit = if b.gap() > th.gap_crit {
                th.add_chi2
            } else {
                th.lr_crit_of(e.params.kind())
            };
            if (b.chi2 - a.chi2) / e.params.kind().n_params() as f64 >= crit {
                kept.push(*e);
            }
        }
    }
    kept
}

/// The model spec of the stationary effects in `effects` (warm-ups and jumps are in `offset`
/// or nowhere), their shapes fixed and amplitudes free.
fn spec_from(prob: &GapProblem, effects: &[AddedEffect], offset: &[f64]) -> ModelSpec {
    let mut spec = ModelSpec {
        offset: Some(offset.to_vec()),
        ..ModelSpec::default()
    };
    for e in effects {
        let kind = e.params.kind();
        if kind.is_stationary() {
            spec = prob.spec_with(&spec, kind, e.params.shape());
        }
    }
    spec
}

/// Adds stationary effects one at a time (the best drop of `r' S^-1 r` per parameter, if it
/// exceeds the threshold) while the gap stays above its critical value.
fn add_stationary(
    prob: &GapProblem,
    kinds: &[EffectKind],
    offset: &[f64],
    effects: &mut Vec<AddedEffect>,
    start: GlsFit,
    opts: &DiagnoseOptions,
    lr_first: bool,
) -> (ModelSpec, GlsFit) {
    let th = opts.thresholds;
    let mut spec = spec_from(prob, effects, offset);
    let mut cur = start;
    let mut added = 0;
    while added < opts.max_effects && (cur.gap() > th.gap_crit || (lr_first && added == 0)) {
        // Below gap_crit only a candidate's own likelihood-ratio threshold can add (the
        // first) effect; among those that pass, the largest drop per parameter wins.
        let flagged_g = cur.gap() > th.gap_crit;
        let mut best: Option<(EffectKind, f64, GlsFit, f64)> = None;
        for &kind in kinds {
            if effects.iter().any(|e| e.params.kind() == kind) {
                continue;
            }
            if let Some((sh, f)) = prob.scan(&spec, kind) {
                let score = (cur.chi2 - f.chi2) / kind.n_params() as f64;
                let crit = if flagged_g {
                    th.add_chi2
                } else {
                    th.lr_crit_of(kind)
                };
                if score >= crit && best.as_ref().is_none_or(|b| score > b.3) {
                    best = Some((kind, sh, f, score));
                }
            }
        }
        let Some((kind, sh, f, _)) = best else {
            break;
        };
        effects.push(AddedEffect {
            params: params_of(kind, sh, &f),
            gap_after: f.gap(),
            delta_chi2: cur.chi2 - f.chi2,
        });
        spec = prob.spec_with(&spec, kind, sh);
        cur = f;
        added += 1;
    }
    (spec, cur)
}

/// A few words on the shape of what the model leaves.
fn describe(regions: &[Region]) -> String {
    if regions.is_empty() {
        return "diffuse: no tau run outside the band, misfit spread over the curve".into();
    }
    let signs: Vec<i32> = regions.iter().map(|r| r.sign).collect();
    let alternations = signs.windows(2).filter(|w| w[0] != w[1]).count();
    let parts: Vec<String> = regions
        .iter()
        .map(|r| {
            format!(
                "{} {:.3e}-{:.3e} s (x{:.2})",
                if r.sign > 0 { "excess" } else { "deficit" },
                r.tau_lo_s,
                r.tau_hi_s,
                r.worst_ratio
            )
        })
        .collect();
    let kind = if alternations >= 2 {
        "oscillation"
    } else if regions.len() == 1 && regions[0].sign > 0 {
        "bump"
    } else if regions.len() == 1 {
        "dip"
    } else {
        "mixed"
    };
    format!("{kind}: {}", parts.join("; "))
}

/// Homogeneity across the segments of each octave tau with enough differences per segment:
/// `ln v_k` against its weighted mean, scaled by the model's relative variance at the
/// segment's count (THEORY.md section 5, "Where in time"). Segments shorter than half the
/// longest are left out.
pub fn segment_tests(snap: &EvidenceSnapshot, c: &[f64; 5]) -> Vec<SegmentTest> {
    let longest = snap.segments.iter().map(|s| s.len).max().unwrap_or(0);
    let segs: Vec<_> = snap
        .segments
        .iter()
        .filter(|s| s.len * 2 >= longest)
        .collect();
    if segs.len() < 3 {
        return Vec::new();
    }
    let shortest = segs.iter().map(|s| s.len).min().unwrap_or(0);
    let tau0 = snap.tau0_s;
    let mut cov = AvarCovariance::new();
    let mut out = Vec::new();
    let mut m = 1u64;
    while m * 16 <= shortest {
        let tau = m as f64 * tau0;
        let a: f64 = basis(tau).iter().zip(c).map(|(b, c)| b * c).sum();
        let vals: Vec<(f64, f64)> = segs
            .iter()
            .filter_map(|s| {
                let (v, _) = s.avar(m)?;
                let count = (s.len + 1).saturating_sub(2 * m).max(1);
                let var = cov.matrix(tau0, &[CovPoint { m, count }], c)[(0, 0)] / (a * a);
                (v > 0.0 && var > 0.0).then_some((v.ln(), var))
            })
            .collect();
        if vals.len() >= 3 && a > 0.0 {
            let wsum: f64 = vals.iter().map(|(_, w)| 1.0 / w).sum();
            let mean = vals.iter().map(|(l, w)| l / w).sum::<f64>() / wsum;
            let h: f64 = vals.iter().map(|(l, w)| (l - mean).powi(2) / w).sum();
            let k1 = (vals.len() - 1) as f64;
            let p = ChiSquared::new(k1).map_or(f64::NAN, |d| 1.0 - d.cdf(h));
            let (wi, wl) = vals
                .iter()
                .enumerate()
                .max_by(|x, y| (x.1 .0 - mean).abs().total_cmp(&(y.1 .0 - mean).abs()))
                .map(|(i, v)| (i, v.0))
                .unwrap_or((0, mean));
            out.push(SegmentTest {
                tau_s: tau,
                stat: h / k1,
                p_value: p,
                worst_segment: wi,
                worst_ratio: ((wl - mean) / 2.0).exp(),
            });
        }
        m *= 2;
    }
    out
}

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

/// Generalised covariance `G(t)` of the phase (u^2) under the five-term model `c` plus
/// stationary effects (avar_cov.rs's table; Gauss-Markov `-S(t)/2` with the structure
/// function `S(t) = 2 s^2 T^2 (t/T - 1 + e^{-t/T})`; sinusoid `A^2 cos(w t) / (2 w^2)`). Valid
/// under filters that annihilate polynomials of degree <= 1, such as a second difference.
fn phase_gcov(c: &[f64; 5], effects: &[EffectParams], t: f64) -> f64 {
    let at = t.abs();
    let mut g = if at == 0.0 { c[0] } else { 0.0 };
    g += -c[1] * at / 2.0;
    if at > 0.0 {
        g += c[2] / (2.0 * std::f64::consts::PI) * at * at * at.ln();
    }
    g += c[3] * at * at * at / 12.0;
    for e in effects {
        match *e {
            EffectParams::GaussMarkov { sigma, tau_c_s } => {
                let x = at / tau_c_s;
                g -= sigma * sigma * tau_c_s * tau_c_s * (x - 1.0 + (-x).exp());
            }
            EffectParams::Sinusoid {
                amplitude,
                frequency_hz,
            } => {
                let w = 2.0 * std::f64::consts::PI * frequency_hz;
                g += amplitude * amplitude * (w * at).cos() / (2.0 * w * w);
            }
            _ => {}
        }
    }
    g
}

/// Covariance (u^2/s^2) of the first differences of block-mean rates `d_i = b_{i+1} - b_i`
/// (second differences of phase at lag `tb`, divided by `tb`) at lags `0..n`.
fn block_diff_acov(c: &[f64; 5], effects: &[EffectParams], tb: f64, n: usize) -> Vec<f64> {
    const A: [f64; 3] = [1.0, -2.0, 1.0];
    (0..n)
        .map(|h| {
            let mut v = 0.0;
            for (i, ai) in A.iter().enumerate() {
                for (j, aj) in A.iter().enumerate() {
                    v += ai * aj * phase_gcov(c, effects, (h as f64 + j as f64 - i as f64) * tb);
                }
            }
            v / (tb * tb)
        })
        .collect()
}

/// Whether block means can carry the time-domain tests: at least 24 blocks, none missing.
pub fn usable_block_means(block_means: &[f64]) -> bool {
    block_means.len() >= 24 && block_means.iter().all(|v| v.is_finite())
}

/// Covariance matrix (u^2/s^2) of the `n_blocks - 1` first differences of the block-mean rate
/// under the model `c` plus stationary `effects` ([`block_diff_acov`], a Toeplitz matrix): the
/// noise model of [`fit_warmup`] and [`detect_steps`]. `None` below 3 blocks.
pub fn block_diff_covariance(
    n_blocks: usize,
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<DMatrix<f64>> {
    if n_blocks < 3 {
        return None;
    }
    let n = n_blocks - 1;
    let acov = block_diff_acov(c, effects, block_s, n);
    Some(DMatrix::from_fn(n, n, |i, j| acov[i.abs_diff(j)]))
}

/// A warm-up in the block means: generalised least squares of the first differences of the
/// block-mean rate on `r + A (e_{i+1} - e_i)`, `e_i` the block mean of `e^{-t/T}` (the warm-up
/// of THEORY.md section 3 over a linear drift `r`), with the covariance of the differences from
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

/// The gap on a held-out run with the effects (kinds, shapes and amplitudes) fitted on another
/// run held fixed; only the five-term amplitudes are refitted (they may differ run to run, as
/// the seed paper's table 2 shows). Returns `(gap_before, gap_after)`.
pub fn holdout_gap(
    fitted: &Diagnosis,
    snap: &EvidenceSnapshot,
    opts: &DiagnoseOptions,
) -> Result<(f64, f64), DiagnoseError> {
    let prob = GapProblem::new(snap, opts)?;
    let j = prob.len();
    let base = prob
        .gls(&ModelSpec::default())
        .ok_or(DiagnoseError::Fit("base GLS".into()))?;
    let mut spec = ModelSpec {
        offset: Some(vec![0.0; j]),
        ..ModelSpec::default()
    };
    for e in &fitted.effects {
        let kind = e.params.kind();
        match kind {
            EffectKind::OutputFilter => spec.filter_tc_s = Some(e.params.shape()),
            EffectKind::BiasJumps => {}
            _ => {
                let a = e.params.amplitude();
                let col = effect_column(kind, e.params.shape(), &prob.ms, prob.tau0_s, prob.n_inc);
                if let Some(off) = spec.offset.as_mut() {
                    for (o, c) in off.iter_mut().zip(col) {
                        *o += a * a * c;
                    }
                }
            }
        }
    }
    let after = prob
        .gls(&spec)
        .ok_or(DiagnoseError::Fit("holdout GLS".into()))?;
    Ok((base.gap(), after.gap()))
}

/// Bias jumps by generalised least squares on the first differences of the block-mean rate
/// (THEORY.md sections 3 and 5): `d = r 1 + sum_j s_j p_j + noise`, the noise covariance from
/// the fitted model (five terms `c`, flicker and random walk included, plus the stationary
/// `effects`: [`block_diff_acov`]). A jump at a block boundary is a spike `p = e_k` in `d`; one
/// inside block `k` splits over `d_{k-1}` and `d_k` (`p = (e_{k-1} + e_k) / 2`). Forward
/// selection: the candidate whose column brings the largest drop of the whitened residual sum of
/// squares is added while the drop's square root (a z score) exceeds the last (lowest) entry of
/// `z_crit`, with all the sizes refitted jointly each time. The jumps kept are those of
/// [`JumpFinding::accepted`]: at least `k` of them at `z >= z_crit[k - 1]` (one strong jump, or
/// several moderate ones: a test of the jumps as a whole, since with small jumps one at a time
/// none may stand out). As jumps are kept, their share of the random walk (`sum s^2 / T_run`,
/// which the curve's `K` has absorbed) is taken out of `K` and the search is run again (twice
/// at most). Returns `None` when the series is too short or `z_crit` is empty. (Mixture
/// statistics for the presence test, [`jump_mixture_stat`] and [`jump_forward_mixture_stat`],
/// were measured against this rule and not adopted: docs/gap.md, "Mixture statistics".)
pub fn detect_steps(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    z_crit: &[f64],
) -> Option<JumpFinding> {
    if !usable_block_means(block_means) {
        return None;
    }
    let z_min = *z_crit.last()?;
    let t_run = block_means.len() as f64 * block_s;
    let mut c = *c;
    let k2_total = c[3];
    let mut found = step_search(block_means, block_s, &c, effects, z_min)?.accepted(z_crit);
    for _ in 0..2 {
        let kj2: f64 = found.sizes.iter().map(|s| s * s).sum::<f64>() / t_run;
        let k2 = (k2_total - kj2).max(0.25 * k2_total);
        if (k2 - c[3]).abs() <= 0.02 * k2_total {
            break;
        }
        c[3] = k2;
        found = step_search(block_means, block_s, &c, effects, z_min)?.accepted(z_crit);
    }
    Some(found)
}

/// Standard error (u/s) of the GLS estimate of a single step at each block boundary, with the
/// drift column in the design, under the model `c` plus `effects` ([`block_diff_acov`]):
/// `1 / |P u_k|`, `u_k` the whitened spike column and `P` the projection off the whitened drift.
/// A step must be about `z_crit` of these to be found by [`detect_steps`] (docs/gap.md uses it
/// to size the smallest findable jump).
pub fn step_standard_errors(
    n_blocks: usize,
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<Vec<f64>> {
    let sigma = block_diff_covariance(n_blocks, block_s, c, effects)?;
    let n = sigma.nrows();
    let chol = sigma.cholesky()?;
    let linv = chol.l().solve_lower_triangular(&DMatrix::identity(n, n))?;
    let ones = &linv * DVector::from_element(n, 1.0);
    let q = &ones / ones.norm();
    Some(
        (0..n)
            .map(|k| {
                let col = linv.column(k).into_owned();
                let u = &col - &q * q.dot(&col);
                1.0 / u.norm()
            })
            .collect(),
    )
}

/// The steps forward selection finds down to `z_min`, with their z scores, on the covariance of
/// `c` as given (no acceptance rule, no re-estimation of `K`): the first pass of
/// [`detect_steps`]. A run is flagged by [`detect_steps`] exactly when these pass
/// [`JumpFinding::accepted`], which is how the rule is calibrated (docs/gap.md).
pub fn forward_steps(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    z_min: f64,
) -> Option<JumpFinding> {
    if !usable_block_means(block_means) {
        return None;
    }
    step_search(block_means, block_s, c, effects, z_min)
}

fn step_search(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    z_crit: f64,
) -> Option<JumpFinding> {
    let (linv, yw, ones) = whitened_block_diffs(block_means, block_s, c, effects)?;
    let n = yw.len();
    // `pos[i]` is candidate i's jump time in blocks.
    let (cols, pos): (Vec<DVector<f64>>, Vec<f64>) = step_candidates(&linv).unzip();
    let mut chosen: Vec<usize> = Vec::new();
    let max_jumps = (n / 8).max(1);
    let fit = |chosen: &[usize]| -> Option<(DVector<f64>, DVector<f64>)> {
        let mut xs = vec![ones.clone()];
        xs.extend(chosen.iter().map(|&i| cols[i].clone()));
        let x = DMatrix::from_columns(&xs);
        let beta = (x.transpose() * &x).try_inverse()? * x.transpose() * &yw;
        let r = &yw - &x * &beta;
        Some((beta, r))
    };
    let (_, mut resid) = fit(&chosen)?;
    let mut z_at: Vec<f64> = Vec::new();
    let mut q = vec![ones.clone() / ones.norm()];
    while chosen.len() < max_jumps {
        // Drop of the RSS for each candidate: (u' r)^2 / |u|^2, u the column projected off
        // the current design (orthonormal basis q).
        let mut best: Option<(usize, f64)> = None;
        for (i, col) in cols.iter().enumerate() {
            if chosen.contains(&i) {
                continue;
            }
            let mut u = col.clone();
            for qv in &q {
                let a = qv.dot(&u);
                u -= qv * a;
            }
            let nu = u.norm_squared();
            if nu <= 1e-12 * col.norm_squared() {
                continue;
            }
            let drop = u.dot(&resid).powi(2) / nu;
            if best.is_none_or(|b| drop > b.1) {
                best = Some((i, drop));
            }
        }
        let Some((i, drop)) = best else { break };
        if drop.sqrt() < z_crit {
            break;
        }
        let mut u = cols[i].clone();
        for qv in &q {
            let a = qv.dot(&u);
            u -= qv * a;
        }
        let nu = u.norm();
        q.push(u / nu);
        chosen.push(i);
        z_at.push(drop.sqrt());
        resid = fit(&chosen)?.1;
    }
    let (beta, _) = fit(&chosen)?;
    let mut jumps: Vec<(f64, f64, f64)> = chosen
        .iter()
        .enumerate()
        .map(|(j, &i)| (pos[i] * block_s, beta[j + 1], z_at[j]))
        .collect();
    jumps.sort_by(|a, b| a.0.total_cmp(&b.0));
    Some(JumpFinding {
        times_s: jumps.iter().map(|j| j.0).collect(),
        sizes: jumps.iter().map(|j| j.1).collect(),
        z_scores: jumps.iter().map(|j| j.2).collect(),
        block_s,
    })
}

/// Single-step evidence at every candidate position of [`detect_steps`] (the first search pass,
/// nothing chosen yet): the GLS z score of one step with the drift in the design, and its
/// standard error.
#[derive(Debug, Clone, PartialEq)]
pub struct StepScan {
    /// `u' y_w / |u|`, `u` the whitened candidate column projected off the whitened drift.
    pub z: Vec<f64>,
    /// `1 / |u|` (u/s): the standard error of the step's size.
    pub se: Vec<f64>,
    /// Whether the candidate is a step at a block boundary (otherwise inside a block).
    pub boundary: Vec<bool>,
}

/// The [`StepScan`] of the block means under the model `c` plus `effects` ([`block_diff_acov`]),
/// with the candidates of [`detect_steps`] (spikes and halves in the block-mean differences).
/// `None` when the series is too short, not finite, or the covariance is not positive definite.
pub fn step_scan(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<StepScan> {
    if !usable_block_means(block_means) {
        return None;
    }
    let (linv, yw, ones) = whitened_block_diffs(block_means, block_s, c, effects)?;
    let n = yw.len();
    let q = &ones / ones.norm();
    let mut out = StepScan {
        z: Vec::with_capacity(2 * n),
        se: Vec::with_capacity(2 * n),
        boundary: Vec::with_capacity(2 * n),
    };
    for (col, pos) in step_candidates(&linv) {
        let u = &col - &q * q.dot(&col);
        let nu = u.norm();
        if nu > 1e-12 * col.norm() {
            out.z.push(u.dot(&yw) / nu);
            out.se.push(1.0 / nu);
            out.boundary.push(pos.fract() == 0.0);
        }
    }
    Some(out)
}

/// The block-mean differences whitened by the model covariance ([`block_diff_covariance`]):
/// `(L^-1, L^-1 d, L^-1 1)`, with `L L'` the covariance and `1` the drift column.
fn whitened_block_diffs(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<(DMatrix<f64>, DVector<f64>, DVector<f64>)> {
    let sigma = block_diff_covariance(block_means.len(), block_s, c, effects)?;
    let n = sigma.nrows();
    let linv = sigma
        .cholesky()?
        .l()
        .solve_lower_triangular(&DMatrix::identity(n, n))?;
    let d = DVector::from_iterator(n, block_means.windows(2).map(|p| p[1] - p[0]));
    let yw = &linv * d;
    let ones = &linv * DVector::from_element(n, 1.0);
    Some((linv, yw, ones))
}

/// The step candidates' whitened columns with their jump times in blocks: a spike (a jump at
/// the boundary after block k, time k + 1) and, from the second block on, a half over two
/// differences (a jump inside block k, time k + 0.5).
fn step_candidates(linv: &DMatrix<f64>) -> impl Iterator<Item = (DVector<f64>, f64)> + '_ {
    (0..linv.ncols()).flat_map(move |k| {
        let spike = (linv.column(k).into_owned(), k as f64 + 1.0);
        let half = (k > 0).then(|| ((linv.column(k - 1) + linv.column(k)) * 0.5, k as f64 + 0.5));
        std::iter::once(spike).chain(half)
    })
}

/// Spike-and-slab mixture statistic of the jumps over the candidate positions:
/// `ln prod_j (1 - p + p B_j)`, `B_j = (1 + r_j)^(-1/2) exp(z_j^2 r_j / (2 (1 + r_j)))` the Bayes
/// factor of a step of size `N(0, rms_size^2)` at candidate `j` against none (`r_j = rms_size^2 /
/// se_j^2`), `p = count / positions` the prior chance of a step at each candidate. This is the
/// log marginal likelihood ratio of "each candidate holds a Gaussian step with probability
/// `p`" against no steps when the candidates' z scores are treated as independent (they are
/// not: neighbours share block means; docs/gap.md, "Mixture statistics"). `boundary_only`
/// keeps the steps at block boundaries only.
pub fn jump_mixture_log_bf(scan: &StepScan, rms_size: f64, count: f64, boundary_only: bool) -> f64 {
    let idx: Vec<usize> = (0..scan.z.len())
        .filter(|&j| !boundary_only || scan.boundary[j])
        .collect();
    if idx.is_empty()
        || rms_size.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || count.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return 0.0;
    }
    let p = (count / idx.len() as f64).min(0.5);
    let (lp, lq) = (p.ln(), (1.0 - p).ln());
    idx.iter()
        .map(|&j| {
            let r = (rms_size / scan.se[j]).powi(2);
            let lb = -0.5 * (1.0 + r).ln() + scan.z[j].powi(2) * r / (2.0 * (1.0 + r));
            let (a, b) = (lq, lp + lb);
            let m = a.max(b);
            m + ((a - m).exp() + (b - m).exp()).ln()
        })
        .sum()
}

/// Prior rms step sizes, in units of the median single-step standard error, and expected step
/// counts, over which [`jump_mixture_stat`] averages the mixture's marginal likelihood.
pub const JUMP_MIX_SIZES: [f64; 6] = [1.0, 1.5, 2.0, 3.0, 4.0, 6.0];
pub const JUMP_MIX_COUNTS: [f64; 3] = [2.0, 4.0, 8.0];

/// The mixture statistic of the jumps with the prior's size and count unknown: `ln` of the mean
/// over the grid `JUMP_MIX_SIZES x JUMP_MIX_COUNTS` (equal weights) of the marginal likelihood
/// ratio `exp(jump_mixture_log_bf)`, sizes scaled by the median standard error of the scan.
/// With `max` the grid's largest value instead of the mean.
pub fn jump_mixture_stat(scan: &StepScan, boundary_only: bool, max: bool) -> f64 {
    let mut se = scan.se.clone();
    se.sort_by(|a, b| a.total_cmp(b));
    let Some(&med) = se.get(se.len() / 2) else {
        return 0.0;
    };
    let vals: Vec<f64> = JUMP_MIX_SIZES
        .iter()
        .flat_map(|&k| {
            JUMP_MIX_COUNTS
                .iter()
                .map(move |&m| jump_mixture_log_bf(scan, k * med, m, boundary_only))
        })
        .collect();
    if max {
        vals.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    } else {
        log_mean_exp(&vals)
    }
}

/// Lowest z of the forward search whose steps [`jump_forward_mixture_stat`] scores.
pub const JUMP_FWD_Z_MIN: f64 = 2.5;

/// The spike-and-slab mixture of [`jump_mixture_log_bf`] on the steps forward selection found
/// (their z scores at selection, each conditional on the steps chosen before it) instead of the
/// single-step scan: `sum_k ln(1 - p + p B(z_k))`, `B(z) = (1 + r)^(-1/2) exp(z^2 r / (2 (1 +
/// r)))`, `r = rms_rel^2` (the prior rms over the median single-step standard error), `p =
/// count / n_candidates`. The positions not chosen are left out (their `B` is near 1).
/// Conditioning on the chosen steps stops one local wander of the noise from counting as many
/// independent steps, which the scan version does (docs/gap.md, "Mixture statistics").
pub fn jump_forward_mixture_log_bf(
    z_scores: &[f64],
    n_candidates: usize,
    rms_rel: f64,
    count: f64,
) -> f64 {
    if n_candidates == 0
        || rms_rel.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || count.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return 0.0;
    }
    let p = (count / n_candidates as f64).min(0.5);
    let r = rms_rel * rms_rel;
    let (lp, lq) = (p.ln(), (1.0 - p).ln());
    z_scores
        .iter()
        .map(|z| {
            let lb = -0.5 * (1.0 + r).ln() + z * z * r / (2.0 * (1.0 + r));
            let m = lq.max(lp + lb);
            m + ((lq - m).exp() + (lp + lb - m).exp()).ln()
        })
        .sum()
}

/// [`jump_forward_mixture_log_bf`] with the prior's size and count unknown: `ln` of the mean over
/// `JUMP_MIX_SIZES x JUMP_MIX_COUNTS` of its likelihood ratio.
pub fn jump_forward_mixture_stat(z_scores: &[f64], n_candidates: usize) -> f64 {
    let vals: Vec<f64> = JUMP_MIX_SIZES
        .iter()
        .flat_map(|&k| {
            JUMP_MIX_COUNTS
                .iter()
                .map(move |&m| jump_forward_mixture_log_bf(z_scores, n_candidates, k, m))
        })
        .collect();
    log_mean_exp(&vals)
}
