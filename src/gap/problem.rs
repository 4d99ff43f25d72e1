//! The generalised-least-squares problem on one measured AVAR curve (docs/theory.md section 5): the
//! curve's taus, `ln AVAR_hat`, and the covariance `S` of the log estimates (the analytic
//! covariance of the five-term model fitted to the curve, [`AvarCovariance`], with a ridge
//! [`RIDGE`]); the GLS fit of a model (five terms plus effect columns and a fixed offset), the
//! gap statistic `G`, the regions outside the band, and the scan of an effect's shape. Used by
//! [`super::diagnose`](mod@super::diagnose), [`super::holdout`] and [`super::oracle`].

use super::column_memo::ColumnMemo;
use super::diagnose::{DiagnoseError, DiagnoseOptions, Region};
use super::discrepancy::{floor_harmonics, rounding_discrepancy, RoundingDiscrepancy};
use super::effects::{canonical_lowpass, effect_column, EffectKind, EffectParams, Grid};
use super::evidence::EvidenceSnapshot;
use super::filter_cov::filter_cov_correction;
use super::rounding::{filtered_sigma, rounding_avar_with, GridPosition, MIN_SIGMA_STEPS};
use super::sawtooth::{
    golden_min, Sawtooth, SAWTOOTH_DITHER_STEPS, SAWTOOTH_FREQ_SPAN, SAWTOOTH_GOLDEN_STEPS,
    SAWTOOTH_GRID_DROP, SAWTOOTH_GRID_SHARE, SAWTOOTH_MAX_DITHER, SAWTOOTH_MAX_GAP,
    SAWTOOTH_MIN_DROP, SAWTOOTH_MIN_SHARE, SAWTOOTH_ROUNDS, SAWTOOTH_ROUND_TOL, SAWTOOTH_SHAPES,
    SAWTOOTH_WANDER_SPAN,
};
use crate::allan::CurvePoint;
use crate::model::avar_cov::{AvarCovariance, CovPoint};
use crate::model::fit::{fit, FitOptions};
use crate::model::lowpass::{LowPass, SecondOrderForm};
use crate::model::nnls::nnls;
use crate::model::terms::basis;
use nalgebra::{DMatrix, DVector};

/// Ridge added to the log covariance, as a fraction of its diagonal (see the module doc).
pub const RIDGE: f64 = 0.05;
/// The fewest cluster lengths `m` the second differences of a point must span
/// (`count * stride >= MIN_SPAN_CLUSTERS m`). A contiguous run's points span at least 7.5 (`m` up
/// to a tenth of the run, [`DiagnoseOptions::tau_max_fraction`]), so this leaves them all; a
/// run cut by gaps into stretches shorter than `2 m` has few or no differences at the longest
/// taus. A rev15 review's channel with 16 single empty cells (17 stretches over an hour at
/// 200 Hz) had one difference at 328 s, its ADEV 0.03 of the truth, whose log the fit read as
/// a Gaussian at `z = -5`: five bias jumps were invented and the verdict was `unexplained`
/// (G 6.6 where the same data without the cells gave 0.96).
pub const MIN_SPAN_CLUSTERS: u64 = 4;
/// Reweighting passes of each GLS fit (the model-weighted fit settles in 3-5).
const GLS_PASSES: usize = 4;
/// The most passes of [`GapProblem::gls`] when the model carries the rounding after its filter,
/// whose curve depends on the fit's own `N` ([`GapProblem::floor_n2`]).
const GLS_PASSES_FLOOR: usize = 8;
/// The change of that `N^2`, relative to it or to the floor's starting value when it is
/// smaller (a fit whose N column is at 0), below which those passes stop.
const FLOOR_N2_TOL: f64 = 1e-4;
/// The least gap of a first pass's five terms alone at which a counter's sawtooth behind a
/// low-pass is looked for ([`GapProblem::counter_filter`]): a unit with a filter the five
/// terms miss by thousands; a clean unit is not scanned.
const COUNTER_FILTER_MIN_GAP: f64 = 2.0;
/// The span of the filter's memory, as factors of the scan's, searched with the counter's
/// sawtooth behind it ([`GapProblem::filter_behind_counter`]), and the golden section's steps.
const BEHIND_MEMORY_SPAN: (f64, f64) = (0.3, 1.5);
const BEHIND_GOLDEN_STEPS: usize = 12;
/// Fixed-point passes of the width's `N` before a sawtooth behind a filter is fitted
/// ([`GapProblem::set_sawtooth`]).
const BEHIND_N_PASSES: usize = 4;

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
    /// The plain five-term fit (the paper's model-weighted NNLS) of the curve.
    pub c_init: [f64; 5],
    /// The five terms `(Q^2, N^2, B^2, K^2, R^2)` whose analytic covariance is `S`: `c_init`,
    /// or those given ([`DiagnoseOptions::cov_coef`]).
    pub c_cov: [f64; 5],
    /// The rounding of each delivered rate sample after the unit's filter, which the filter
    /// does not smooth ([`super::rounding`]; white, `N_q^2 / tau` with
    /// `N_q^2 = lsb^2 / (12 tau0)`, when the step is fine against the filtered noise). When
    /// set, every model with a filter carries its AVAR, for that filter, as a fixed part beside
    /// the filtered N column ([`GapProblem::set_filter_floor`]; docs/gap.md, "Filters and
    /// Gauss-Markov terms", "Rounding after a filter"). None: no such part.
    pub filter_floor: Option<FilterFloor>,
    /// The rounding model's known error after the filter of the covariance
    /// ([`super::discrepancy`]), carried in `S`; None: none carried.
    pub discrepancy: Option<RoundingDiscrepancy>,
    /// The filter found by an earlier pass whose covariance this problem carries
    /// ([`DiagnoseOptions::cov_filter`]).
    pub cov_filter: Option<LowPass>,
    /// The filter every model carries where none is named ([`DiagnoseOptions::base_filter`]).
    pub base_filter: Option<LowPass>,
    /// Where the unit's mean falls on the rounding grid, as the run's block means show it
    /// (None: the values show no step).
    grid: Option<GridPosition>,
    /// The filter columns and rounding floors already computed ([`ColumnMemo`]).
    memo: ColumnMemo,
    /// The counter's sawtooth and its AVAR at `ms`, a fixed part of every model when set
    /// ([`GapProblem::set_sawtooth`]; [`super::sawtooth`]).
    pub sawtooth: Option<(Sawtooth, Vec<f64>)>,
}

/// The search for the white rate `N^2` at which the rounding after the filter is computed in
/// [`GapProblem::gls`]: the fixed point `n = g(n)` of the fit's `N^2` coefficient `g` with the
/// rounding at `n`. The first pass (weighted by the data, not yet by the model) only gives the
/// plain step `n = g`; from the second on, the secant through the last two passes on
/// `h(n) = g(n) - n`. Plain iteration alone creeps toward the point where the rounding's share
/// of the short taus rises with `N` (`g` increasing in `n`, slope 0.5-0.7: some 15 passes to
/// 1e-4), swings about it where it falls, and between 0 and a large `N` for a candidate filter
/// that does not fit (the fit at each end wants the other); the secant takes each to it in a
/// few passes (each kept within a factor 2 of the last pass's `n` and `g`).
#[derive(Debug, Default)]
struct FloorN2Search {
    /// The last pass after the first: `(n, h)`.
    last: Option<(f64, f64)>,
}

impl FloorN2Search {
    /// The next `n` after pass `pass` (from 0) at `n` whose fit gave `g`.
    fn next(&mut self, pass: usize, n: f64, g: f64) -> f64 {
        if pass == 0 {
            return g;
        }
        let h = g - n;
        let next = match self.last.replace((n, h)) {
            Some((na, ha)) if ha != h => n - h * (n - na) / (h - ha),
            _ => g,
        };
        // kept within a factor 2 of this pass's n and g: far from the point g is not linear
        let (lo, hi) = (0.5 * n.min(g), 2.0 * n.max(g));
        if next.is_finite() {
            next.clamp(lo, hi)
        } else {
            g
        }
    }
}

/// The rate rounding after a unit's filter ([`GapProblem::filter_floor`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilterFloor {
    /// The step of the delivered rate samples, u/s.
    pub step: f64,
    /// The unit's white rate `N^2` (u^2/s) that sets the filtered samples' noise where a fit
    /// has none yet: the starting value of each GLS fit, which then takes its own N column's
    /// ([`GapProblem::gls`]).
    pub n2: f64,
}

/// One model to fit: the five terms (N column optionally filtered) plus free effect columns and
/// a fixed offset.
#[derive(Debug, Clone, Default)]
pub struct ModelSpec {
    /// The unit's output filter, through which the N column is taken.
    pub filter: Option<LowPass>,
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

    /// The five terms' squares `(Q^2, N^2, B^2, K^2, R^2)` (0 where the fit has fewer), as the
    /// block covariance of the time-domain tests takes them.
    pub fn five_terms(&self) -> [f64; 5] {
        std::array::from_fn(|i| self.coef.get(i).copied().unwrap_or(0.0))
    }
}

/// `spec` with `k col` added to its fixed offset: a five-term coefficient held at `k` (or, its
/// column still free, at `k` or above).
fn with_term_offset(spec: &ModelSpec, col: &[f64], k: f64) -> ModelSpec {
    let mut s = spec.clone();
    let base = s.offset.take().unwrap_or_else(|| vec![0.0; col.len()]);
    s.offset = Some(base.iter().zip(col).map(|(o, x)| o + k * x).collect());
    s
}

impl GapProblem {
    /// Builds the problem from the dense curve of `snap`.
    pub fn new(snap: &EvidenceSnapshot, opts: &DiagnoseOptions) -> Result<Self, DiagnoseError> {
        let n = snap.n_increments.max(1);
        let m_max = ((n as f64) * opts.tau_max_fraction).floor() as u64;
        let pts: Vec<_> = snap
            .curve
            .iter()
            .filter(|p| {
                p.m <= m_max
                    && p.m >= opts.min_m
                    && p.avar.is_finite()
                    && p.avar > 0.0
                    && p.count > 0
                    && p.count.saturating_mul(p.stride.max(1)) >= MIN_SPAN_CLUSTERS * p.m
            })
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
                // Full-overlap block estimates: their own count is the span.
                stride: 1,
                n_phase: p.count + 2 * p.m,
            })
            .collect();
        let base =
            fit(&cps, &FitOptions::default()).map_err(|e| DiagnoseError::Fit(e.to_string()))?;
        let c_init = base.c;
        let tau0 = snap.tau0_s;
        // Each point's count is that of the span its strided differences cover (`count *
        // stride`), and the covariance is that of differences taken at the point's stride
        // (`matrix_strided`): for N, B and K that is the full overlap's over the span, but white
        // phase noise (Q, quantization) loses degrees of freedom to the stride (docs/theory.md
        // section 1; docs/gap.md, "Covariance at strided levels").
        let cov_pts: Vec<CovPoint> = pts
            .iter()
            .map(|p| CovPoint {
                m: p.m,
                count: (p.count * p.stride).clamp(1, (n + 1).saturating_sub(2 * p.m).max(1)),
            })
            .collect();
        let strides: Vec<u64> = pts.iter().map(|p| p.stride.max(1)).collect();
        // The covariance's five terms: the plain fit's, or those given (DiagnoseOptions::cov_coef).
        let c_cov = opts.cov_coef.unwrap_or(c_init);
        let mut cov = AvarCovariance::new().matrix_strided(tau0, &cov_pts, &strides, &c_cov);
        // A found output filter smooths the white rate: the exact correction for it
        // ([`super::filter_cov`]; docs/gap.md, "Low-pass filters beyond first order").
        if let Some(lp) = opts.cov_filter {
            cov += filter_cov_correction(tau0, &cov_pts, &strides, &c_cov, &lp);
        }
        let a: Vec<f64> = pts
            .iter()
            .map(|p| {
                let b = basis(p.tau_s);
                let (n_col, b_col) = opts.cov_filter.map_or((b[1], b[2]), |lp| {
                    (
                        lp.white_rate_avar(tau0, &[p.m])[0],
                        lp.flicker_rate_avar(tau0, &[p.m])[0],
                    )
                });
                (0..5)
                    .map(|i| match i {
                        1 => n_col,
                        2 => b_col,
                        _ => b[i],
                    } * c_cov[i])
                    .sum::<f64>()
                    .max(1e-300)
            })
            .collect();
        let j = pts.len();
        let mut s = DMatrix::from_fn(j, j, |r, c| cov[(r, c)] / (a[r] * a[c]));
        // Rate samples rounded after the filter found (not a counter with carry, as the
        // previous pass read the step), coarsely against its noise: the
        // rounding model's known error enters as a model discrepancy of ln AVAR
        // ([`super::discrepancy`]; docs/gap.md, "The dead band as model discrepancy"), scaled
        // by where the block means place the unit's mean on the grid.
        // The flicker that moves the mean within each block is the covariance's (fitted
        // beyond ten memories of the filter on the later passes).
        let grid = snap.lsb.map(|_| GridPosition {
            block_means: snap.block_means.clone(),
            block_s: snap.block_len as f64 * tau0,
            flicker_b2: c_cov[2].max(0.0),
        });
        let discrepancy = match (opts.cov_filter, snap.lsb) {
            (Some(lp), Some(lsb)) if !opts.cov_counter => {
                rounding_discrepancy(&lp, tau0, lsb / tau0, c_cov[1], grid.as_ref())
            }
            _ => None,
        };
        if let Some(d) = &discrepancy {
            let taus: Vec<f64> = pts.iter().map(|p| p.tau_s).collect();
            s += d.covariance(&taus);
        }
        let s_diag: Vec<f64> = (0..j).map(|i| s[(i, i)]).collect();
        if s_diag.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(DiagnoseError::Covariance);
        }
        let s_plain = s.clone();
        for i in 0..j {
            s[(i, i)] *= 1.0 + RIDGE;
        }
        // The analytic covariance of strided levels behind a filter can miss positive
        // definiteness by more than the ridge (accfilt draw 4 of seed 181, a first order of 29
        // samples: the correlation matrix's least eigenvalue -0.056, its vector on m = 20-48
        // where the strides begin within the filter's memory). The ridge is then raised by the
        // shortfall, as a model error of that size, rather than the pass with the filter's
        // covariance given up (docs/gap.md, "The covariance's five terms after a filter
        // (session 19)").
        let chol = match s.cholesky() {
            Some(c) => c,
            None => {
                let corr = DMatrix::from_fn(j, j, |r, c| {
                    s_plain[(r, c)] / (s_diag[r] * s_diag[c]).sqrt()
                });
                let least = corr.symmetric_eigenvalues().min();
                let ridge = RIDGE + (-least).max(0.0);
                let mut s = s_plain.clone();
                for i in 0..j {
                    s[(i, i)] *= 1.0 + ridge;
                }
                tracing::debug!(
                    least,
                    ridge,
                    "the covariance's ridge raised to make it positive definite"
                );
                s.cholesky().ok_or(DiagnoseError::Covariance)?
            }
        };
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
            c_cov,
            filter_floor: None,
            discrepancy,
            cov_filter: opts.cov_filter,
            base_filter: opts.base_filter,
            grid,
            memo: ColumnMemo::default(),
            sawtooth: None,
        })
    }

    /// The fixed part of a model's curve at the coefficients `coef`: the spec's offset, plus
    /// the rounding after the filter ([`GapProblem::filter_floor`]) when the spec has a filter,
    /// for the filtered noise of the model's own white rate `N^2 = coef[1]`
    /// ([`GapProblem::floor_n2`]).
    fn offset_of(&self, spec: &ModelSpec, coef: &[f64]) -> Vec<f64> {
        self.offset_at(spec, self.floor_n2(coef))
    }

    /// The filter a model of `spec` carries: the one it names, or else the problem's base filter
    /// ([`DiagnoseOptions::base_filter`]). Every model's columns, fixed part and shape count
    /// take it from here, so a fit, its intervals and its degrees of freedom agree. (A filter
    /// candidate added to `spec` takes the base filter's place: `spec_with` composes with the
    /// named filter only.)
    fn model_filter(&self, spec: &ModelSpec) -> Option<LowPass> {
        spec.filter.or(self.base_filter)
    }

    /// [`GapProblem::offset_of`] with the rounding's white rate `N^2 = n2` (u^2/s) given.
    fn offset_at(&self, spec: &ModelSpec, n2: f64) -> Vec<f64> {
        let mut off = spec.offset.clone().unwrap_or_else(|| vec![0.0; self.len()]);
        if let Some((_, col)) = &self.sawtooth {
            for (o, c) in off.iter_mut().zip(col) {
                *o += c;
            }
        }
        if let (Some(lp), Some(fl)) = (self.model_filter(spec), self.filter_floor) {
            let r = self.memo.floor(&lp, n2, fl.step, || {
                let rho = self
                    .memo
                    .autocorrelation(&lp, || lp.autocorrelation(self.tau0_s));
                let grid = self.grid.as_ref();
                rounding_avar_with(&rho, &lp, self.tau0_s, fl.step, n2, grid, &self.ms)
            });
            for (o, f) in off.iter_mut().zip(r.iter()) {
                *o += f;
            }
        }
        off
    }

    /// The white rate `N^2` (u^2/s) whose filtered samples the rounding after the filter acts
    /// on, in a model with coefficients `coef`: its own N column's (the rounding's correlation
    /// depends on the filtered noise against the step, docs/gap.md "Rounding after a filter");
    /// the floor's starting value when `coef` has none.
    fn floor_n2(&self, coef: &[f64]) -> f64 {
        match (coef.get(1), self.filter_floor) {
            (Some(&n2), _) => n2.max(0.0),
            (None, Some(fl)) => fl.n2,
            (None, None) => 0.0,
        }
    }

    /// Decides whether the models with an output filter carry the rounding of rate samples
    /// rounded after the filter, for values that are whole multiples of `lsb` (u per increment):
    /// a MEMS part filters its rate, then rounds each sample, so that rounding
    /// ([`super::rounding`]: white `N_q^2 / tau` when the step is fine against the filtered
    /// noise, correlated as the filtered samples are when it is not) is rate noise the filter
    /// does not smooth, while a counter with carry leaves white phase noise (the Q column)
    /// instead. The two cases give the same values, so the curve decides: the first-order
    /// filter and the moving average are scanned with and without the rounding and it is kept
    /// when the best with it fits better. Without a filter on the curve the choice changes
    /// nothing (the filter is not named); with one and a counter with carry the floor is a
    /// white rate that is not there, and the fit without it wins.
    pub fn set_filter_floor(&mut self, lsb: f64) {
        self.filter_floor = None;
        if !(lsb > 0.0 && lsb.is_finite()) {
            return;
        }
        let step = lsb / self.tau0_s;
        let base = ModelSpec::default();
        // The first order and the moving average (the filters MEMS parts run), each scanned
        // without the rounding and with it; the best of each set decides.
        // The filter of the covariance, when one was found and is of another kind, is scanned
        // too: a second-order or zero-phase unit fits neither of the two well, and their
        // comparison then says nothing about its rounding (docs/gap.md, "The dead band as model
        // discrepancy (session 13)").
        let found = self
            .cov_filter
            .map(|lp| EffectParams::from_lowpass(lp).kind())
            .filter(|k| !matches!(k, EffectKind::OutputFilter | EffectKind::MovingAverage));
        let kinds: Vec<EffectKind> = [EffectKind::OutputFilter, EffectKind::MovingAverage]
            .into_iter()
            .chain(found)
            .collect();
        let best = |p: &Self| {
            kinds
                .iter()
                .filter_map(|&k| p.scan_params(&base, k))
                .min_by(|a, b| a.1.chi2.total_cmp(&b.1.chi2))
        };
        let without = best(self).map(|f| f.1.chi2);
        // The filtered noise the rounding acts on comes from the unit's N: first the plain
        // fit's (which holds the rounding's white part too), then the filter's own.
        self.filter_floor = Some(FilterFloor {
            step,
            n2: self.c_init[1].max(0.0),
        });
        let mut with = best(self);
        if let Some((p, f)) = &with {
            self.filter_floor = Some(FilterFloor {
                step,
                n2: f.coef.get(1).copied().unwrap_or(0.0).max(0.0),
            });
            with = self.scan_params(&base, p.kind());
        }
        let keep = match (&with, without) {
            (Some((p, w)), Some(wo)) if w.chi2 < wo => {
                // The averaged model holds while the filtered sample's noise is at least
                // MIN_SIGMA_STEPS steps ([`super::rounding`]): below, the rounding holds the
                // output on one step (a dead band) as the mean's position on the grid sets.
                // Where the block means resolve that position the grid model
                // (`rounding_avar_on_grid`, [`Self::offset_of`]) holds it, down to
                // MIN_SIGMA_STEPS_ON_GRID ([`floor_harmonics`]; docs/gap.md, "The grid model
                // wired (session 15)").
                let n2 = w.coef.get(1).copied().unwrap_or(0.0).max(0.0);
                p.lowpass().is_some_and(|lp| {
                    let sigma = filtered_sigma(&lp, self.tau0_s, n2);
                    sigma >= MIN_SIGMA_STEPS * step
                        || floor_harmonics(
                            self.grid.as_ref(),
                            step,
                            sigma,
                            n2,
                            lp.memory_s(self.tau0_s),
                        )
                        .is_some()
                })
            }
            _ => false,
        };
        tracing::debug!(
            keep,
            with = ?with.as_ref().map(|(p, f)| (p, f.chi2)),
            without,
            "the rounding after a filter"
        );
        if !keep {
            self.filter_floor = None;
        }
    }

    /// The low-pass a counter's sawtooth may sit behind ([`GapProblem::with_sawtooth`]): the
    /// filter of the covariance on a later pass whose previous pass read a counter
    /// (`counter`, [`DiagnoseOptions::cov_counter`]); on a first pass whose five terms miss the
    /// curve (`G > 2`), the scan's best first order (whose memory
    /// [`GapProblem::filter_behind_counter`] then refits; a unit's moving average is read
    /// through a first order of that memory until a later pass names it). None when the angle's change per sample behind it is not small against the LSB
    /// (`r >= R_WHITE` of [`super::quant_limit`], the error then white: nothing to model), or
    /// there is no LSB.
    fn counter_filter(&self, snap: &EvidenceSnapshot, counter: bool) -> Option<LowPass> {
        let lsb = snap.lsb.filter(|l| *l > 0.0 && l.is_finite())?;
        let base = ModelSpec::default();
        let (lp, coef) = match self.cov_filter {
            // A later pass looks behind its filter only when the pass before read a counter
            // (a counter's sawtooth kept, or the angle's quantization floor): a unit that
            // rounds its rate samples after the filter has its own floor there.
            Some(_) if !counter => return None,
            Some(lp) => {
                let spec = ModelSpec {
                    filter: Some(lp),
                    ..ModelSpec::default()
                };
                (lp, self.gls(&spec)?.coef)
            }
            None => {
                if self.gls(&base)?.gap() <= COUNTER_FILTER_MIN_GAP {
                    return None;
                }
                let (p, f) = self.scan_params(&base, EffectKind::OutputFilter)?;
                (p.lowpass()?, f.coef)
            }
        };
        let rho0 = lp.autocorrelation(self.tau0_s).first().copied()?;
        let qx2 = (coef[0] - lsb * lsb / 12.0).max(0.0);
        let v1 = coef[1].max(0.0) * self.tau0_s * rho0 + 2.0 * qx2;
        let ratio = v1.sqrt() / lsb;
        tracing::debug!(?lp, ratio, "a counter behind a filter?");
        (ratio < super::quant_limit::R_WHITE).then_some(lp)
    }

    /// The low-pass `lp` ([`GapProblem::counter_filter`]'s) refitted with the counter's
    /// sawtooth behind it: the scan, without the sawtooth, reads the error's correlation at the short taus as
    /// more smoothing (navfog seed 183's output-filter draw 1: 33 ms for the unit's 20 ms). Its
    /// memory is searched over [`BEHIND_MEMORY_SPAN`] of the scan's (golden section on its
    /// log; the time constant of a first order or zero-phase filter, the taps of a moving
    /// average, the period of a second order), the sawtooth fitted at each
    /// ([`GapProblem::set_sawtooth`]).
    fn filter_behind_counter(&mut self, snap: &EvidenceSnapshot, lp: LowPass) -> LowPass {
        let tau0_s = self.tau0_s;
        let scaled = |g: f64| match lp {
            // (a cascade is named in two steps, each part scanned behind the other)
            LowPass::Cascade { .. } => lp,
            LowPass::Fir {
                taps,
                cutoff_hz,
                decimation,
            } => LowPass::Fir {
                taps,
                cutoff_hz: (cutoff_hz / g).min(super::filter_scan::fir_top_hz(decimation, tau0_s)),
                decimation,
            },
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            } => LowPass::Butterworth {
                order,
                cutoff_hz: (cutoff_hz / g)
                    .min(super::filter_scan::BUTTERWORTH_TOP * f64::from(decimation) / tau0_s),
                decimation,
            },
            LowPass::FirstOrder { time_constant_s } => LowPass::FirstOrder {
                time_constant_s: time_constant_s * g,
            },
            LowPass::ZeroPhase { time_constant_s } => LowPass::ZeroPhase {
                time_constant_s: time_constant_s * g,
            },
            LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            } => LowPass::MovingAverage {
                taps: (taps as f64 * g).round().max(1.0) as u32,
                stages,
                decimation,
            },
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                form,
            } => LowPass::SecondOrder {
                // (the bilinear form is defined below Nyquist only)
                natural_frequency_hz: if form == SecondOrderForm::Bilinear {
                    (natural_frequency_hz / g).min(0.45 / tau0_s)
                } else {
                    natural_frequency_hz / g
                },
                damping,
                form,
            },
        };
        let (lo, hi) = BEHIND_MEMORY_SPAN;
        let (_, best) = golden_min(self, lo.ln(), hi.ln(), BEHIND_GOLDEN_STEPS, |p, lg| {
            let f = scaled(lg.exp());
            (p.set_sawtooth(snap, Some(f)), f)
        });
        tracing::debug!(scanned = ?lp, refitted = ?best, "the filter behind the counter");
        self.sawtooth = None;
        best
    }

    /// A counter behind a filter, when no plain sawtooth is kept ([`GapProblem::with_sawtooth`]):
    /// the filter of the covariance, or on a first pass the best low-pass the curve shows
    /// ([`GapProblem::counter_filter`]), refitted with the sawtooth behind it (docs/gap.md,
    /// "The counter behind a filter (session 25)"). A counter has no rate rounding after its
    /// filter: the floor decided for rate samples is set aside while the sawtooth is fitted,
    /// and the sawtooth is kept only if the filter fits better with it than with that floor.
    fn set_sawtooth_behind_filter(&mut self, snap: &EvidenceSnapshot, counter: bool) {
        let Some(lp) = self.counter_filter(snap, counter) else {
            return;
        };
        let floor = self.filter_floor.take();
        let lp = self.filter_behind_counter(snap, lp);
        let chi2 = self.set_sawtooth(snap, Some(lp));
        if self.sawtooth.is_none() {
            self.filter_floor = floor;
            return;
        }
        if floor.is_some() {
            let saw = self.sawtooth.take();
            self.filter_floor = floor;
            let spec = ModelSpec {
                filter: Some(lp),
                ..ModelSpec::default()
            };
            let with_floor = self.gls(&spec).map_or(f64::INFINITY, |f| f.chi2);
            tracing::debug!(
                chi2,
                with_floor,
                "the sawtooth behind the filter against the rate rounding's floor"
            );
            if chi2 < with_floor {
                self.filter_floor = None;
                self.sawtooth = saw;
            }
        }
    }

    /// This problem with the counter's sawtooth decided ([`GapProblem::set_sawtooth`]). The
    /// plain fit whose five terms set the covariance took the counter's line into its terms
    /// (its `N` up to ten times the unit's on rlg units): when the sawtooth is kept and no
    /// covariance was given, the problem is built again with the covariance of the five terms
    /// fitted beside it (the rounding after a filter decided again with it when `floor`: the
    /// diagnosis decides it, the held-out run does not), and the sawtooth fitted again with
    /// that covariance; it is kept if it leaves the base model's gap at most
    /// [`SAWTOOTH_MAX_GAP`] there, else this problem is returned without it (docs/gap.md, "The
    /// counter's sawtooth in the base model (session 23)").
    pub fn with_sawtooth(
        mut self,
        snap: &EvidenceSnapshot,
        opts: &DiagnoseOptions,
        floor: bool,
    ) -> Result<Self, DiagnoseError> {
        self.set_sawtooth(snap, None);
        let Some(st) = self.sawtooth.as_ref().map(|(st, _)| *st) else {
            self.set_sawtooth_behind_filter(snap, opts.cov_counter);
            return Ok(self);
        };
        if opts.cov_coef.is_some() {
            return Ok(self);
        }
        let Some(fit) = self.gls(&ModelSpec::default()) else {
            return Ok(self);
        };
        // The sawtooth's own variance is white phase noise to the covariance: beyond its
        // correlation time its AVAR is `3 R(0) / tau^2`, the Q column's at `Q^2 = R(0)`
        // (without it, where the sawtooth is most of the angle error, as on a counter with no
        // dither, the covariance at the short taus is too tight: servoacc's quantization-
        // limited runs read `G` 1.22 at the median, 1.00 with it; docs/gap.md, "The whole
        // curve of a quantization-limited counter (session 24)").
        let mut cc: [f64; 5] = std::array::from_fn(|i| fit.coef[i].max(0.0));
        cc[0] += st.coherent_variance();
        let o = DiagnoseOptions {
            cov_coef: Some(cc),
            ..opts.clone()
        };
        let mut again = GapProblem::new(snap, &o)?;
        if let (Some(lsb), true) = (snap.lsb, floor) {
            again.set_filter_floor(lsb);
        }
        again.set_sawtooth(snap, None);
        // The counter's line must be most of what the five terms missed: with its covariance
        // the base model is left at most SAWTOOTH_MAX_GAP, or the sawtooth is not kept (a unit's
        // filter, which it cannot mend, leaves thousands).
        let gap_with = again
            .gls(&ModelSpec::default())
            .map_or(f64::INFINITY, |f| f.gap());
        tracing::debug!(
            gap_with,
            kept = again.sawtooth.is_some(),
            "the sawtooth with its covariance"
        );
        if again.sawtooth.is_none() || gap_with > SAWTOOTH_MAX_GAP {
            self.sawtooth = None;
            return Ok(self);
        }
        Ok(again)
    }

    /// Decides whether every model of the curve carries the counter's sawtooth
    /// ([`super::sawtooth`]): for values that are whole multiples of an LSB (`snap.lsb`) and a
    /// rate whose block means have a mean, the sawtooth at the line `|mean| / LSB` is fitted in
    /// the base model over its three shape parameters: the dither (a grid from 0 to
    /// [`SAWTOOTH_MAX_DITHER`] LSB, then refined), the frequency (within
    /// [`SAWTOOTH_FREQ_SPAN`] of the line: the mean's own error) and the rate's wander (up to
    /// [`SAWTOOTH_WANDER_SPAN`] times the block means' spread beyond their white noise at the
    /// fit's `N` and `Q` with the flicker's between the sample and the block), by rounds of
    /// golden-section searches on one parameter at a time ([`SAWTOOTH_ROUNDS`] at most). The
    /// white rate `N` of its width is the fit's own, set at the start of each round (the plain
    /// fit's is raised by the line itself, up to ten times on rlg units). It is kept when it
    /// lowers the base model's `r' S^-1 r` by at least [`SAWTOOTH_MIN_DROP`] and by at least
    /// [`SAWTOOTH_MIN_SHARE`] of the base model's excess over its expectation: the counter's
    /// line is then most of what the five terms miss, where a unit's filter they miss by
    /// thousands would otherwise lend a sawtooth the small part of it one can follow
    /// ([`GapProblem::with_sawtooth`] also asks that it leave the base model's gap at most
    /// [`SAWTOOTH_MAX_GAP`] with its covariance). Not in a pass with a filter's covariance
    /// ([`DiagnoseOptions::cov_filter`]) unless `behind`: the sawtooth of a counter behind
    /// that low-pass, whose base model is then the five terms through it (the walk of
    /// [`super::sawtooth`]'s filtered rate; docs/gap.md, "The counter behind a filter
    /// (session 25)"), kept by the same rules against that model's misfit and when it leaves
    /// that model's gap at most [`SAWTOOTH_MAX_GAP`]. Returns the base model's `r' S^-1 r`
    /// with the sawtooth fitted, kept or not (infinite when none could be fitted).
    pub fn set_sawtooth(&mut self, snap: &EvidenceSnapshot, behind: Option<LowPass>) -> f64 {
        self.sawtooth = None;
        let t_start = std::time::Instant::now();
        let Some(lsb) = snap.lsb.filter(|l| *l > 0.0 && l.is_finite()) else {
            return f64::INFINITY;
        };
        let Some((mean, sd)) = super::limit_cycle::rate_stats(snap) else {
            return f64::INFINITY;
        };
        let f0 = mean.abs() / lsb;
        // A pass with a filter's covariance is diagnosing a unit with a filter, whose five
        // terms alone miss the curve for that reason; the sawtooth is decided without one.
        if !(f0 > 0.0 && f0.is_finite())
            || self.is_empty()
            || (self.cov_filter.is_some() && behind.is_none())
        {
            return f64::INFINITY;
        }
        let base = ModelSpec {
            filter: behind,
            ..ModelSpec::default()
        };
        let Some(plain) = self.gls(&base) else {
            return f64::INFINITY;
        };
        // The wander's search reaches twice the rate's spread at the scales a block mean
        // hides: the block means' own beyond their white noise, and the flicker rate's
        // between the sample and the block (its PSD `B^2 / (2 pi f)`, IEEE Std 952's bias
        // instability: `B^2 / (2 pi) ln(T_b / (2 tau0))` of variance), which moves the angle
        // within the lags the counter's line lives over.
        let block_s = snap.block_len as f64 * self.tau0_s;
        let octaves = (block_s / (2.0 * self.tau0_s)).max(1.0).ln();
        let wander_of = |coef: &[f64]| {
            let slow =
                super::limit_cycle::slow_spread(snap, sd, coef[0].max(0.0), coef[1].max(0.0));
            let flicker = coef[2].max(0.0) / (2.0 * std::f64::consts::PI) * octaves;
            SAWTOOTH_WANDER_SPAN * (slow * slow + flicker).sqrt()
        };
        let chi2_at = |p: &mut Self, st: Sawtooth| {
            p.sawtooth = Some((st, st.avar(p.tau0_s, &p.ms)));
            p.gls(&base).map_or(f64::INFINITY, |f| f.chi2)
        };
        let mut st = Sawtooth {
            lsb,
            frequency_hz: f0,
            dither: 0.0,
            n_arw: plain.coef[1].max(0.0).sqrt(),
            rate_wander: 0.0,
            filter: behind,
        };
        // Behind a filter the five terms alone fit an `N` lowered by the error's correlation
        // at the short taus (navfog seed 183's output-filter draw 1: 6.0e-5 for 7.8e-5), at
        // which the sawtooth is far too correlated to fit at any dither: the width's `N` is
        // first brought to the fixed point with an undithered counter.
        if behind.is_some() {
            for _ in 0..BEHIND_N_PASSES {
                self.sawtooth = Some((st, st.avar(self.tau0_s, &self.ms)));
                let Some(f) = self.gls(&base) else { break };
                st.n_arw = f.coef[1].max(0.0).sqrt();
            }
        }
        // The dither on a grid first (the curve's misfit has many minima in it far from the
        // line's own), then each parameter in turn.
        let mut chi2 = f64::INFINITY;
        for i in 0..=SAWTOOTH_DITHER_STEPS {
            let trial = Sawtooth {
                dither: i as f64 / SAWTOOTH_DITHER_STEPS as f64 * SAWTOOTH_MAX_DITHER * lsb,
                ..st
            };
            let c = chi2_at(self, trial);
            if c < chi2 {
                (chi2, st) = (c, trial);
            }
        }
        let step = SAWTOOTH_MAX_DITHER * lsb / SAWTOOTH_DITHER_STEPS as f64;
        // No dither on the grid makes any line at all (a unit whose values are rate samples
        // rounded on their own, a counter dithered by its white phase noise), or only a small
        // share of the base model's misfit: nothing to refine.
        let excess = (plain.chi2 - plain.expected).max(0.0);
        let rounds = if plain.chi2 - chi2 < SAWTOOTH_GRID_DROP.max(SAWTOOTH_GRID_SHARE * excess) {
            0
        } else {
            SAWTOOTH_ROUNDS
        };
        for _ in 0..rounds {
            let start = chi2;
            // The width's N is the fit's own: the rounds step toward the fixed point where the
            // N the sawtooth is widened by is the N fitted beside it.
            self.sawtooth = Some((st, st.avar(self.tau0_s, &self.ms)));
            let coef = self.gls(&base).map_or(plain.coef.clone(), |f| f.coef);
            let w_max = wander_of(&coef);
            st.n_arw = coef[1].max(0.0).sqrt();
            chi2 = chi2_at(self, st);
            type Set = fn(&mut Sawtooth, f64);
            let searches: [(f64, f64, Set); 3] = [
                ((st.dither - step).max(0.0), st.dither + step, |s, v| {
                    s.dither = v
                }),
                (
                    f0 * (1.0 - SAWTOOTH_FREQ_SPAN),
                    f0 * (1.0 + SAWTOOTH_FREQ_SPAN),
                    |s, v| s.frequency_hz = v,
                ),
                (0.0, w_max, |s, v| s.rate_wander = v),
            ];
            for (lo, hi, set) in searches {
                if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
                    continue;
                }
                let eval = |p: &mut Self, v: f64| {
                    let mut t = st;
                    set(&mut t, v);
                    (chi2_at(p, t), t)
                };
                let (c, t) = golden_min(self, lo, hi, SAWTOOTH_GOLDEN_STEPS, eval);
                if c < chi2 {
                    (chi2, st) = (c, t);
                }
            }
            if (start - chi2).abs() <= SAWTOOTH_ROUND_TOL * chi2 {
                break;
            }
        }
        let mut keep = plain.chi2 - chi2 >= SAWTOOTH_MIN_DROP.max(SAWTOOTH_MIN_SHARE * excess)
            && st.dither < SAWTOOTH_MAX_DITHER * lsb;
        // Behind a filter no covariance is rebuilt for it (the pass's is the filter's, or the
        // plain fit's on a first pass): its base model must be left at a gap of at most
        // SAWTOOTH_MAX_GAP here.
        if keep && behind.is_some() {
            self.sawtooth = Some((st, st.avar(self.tau0_s, &self.ms)));
            keep = self.gls(&base).is_some_and(|f| f.gap() <= SAWTOOTH_MAX_GAP);
        }
        tracing::debug!(
            f0,
            frequency_hz = st.frequency_hz,
            dither_lsb = st.dither / lsb,
            n_arw = st.n_arw,
            rate_wander = st.rate_wander,
            drop = plain.chi2 - chi2,
            plain_chi2 = plain.chi2,
            plain_expected = plain.expected,
            keep,
            behind = ?behind,
            secs = t_start.elapsed().as_secs_f64(),
            "the counter's sawtooth in the base model"
        );
        self.sawtooth = keep.then(|| (st, st.avar(self.tau0_s, &self.ms)));
        chi2
    }

    pub fn len(&self) -> usize {
        self.tau.len()
    }

    /// The unridged covariance `S` of `ln AVAR_hat` at the curve's taus (the analytic
    /// covariance of the five terms `c_cov`, docs/theory.md section 5).
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

    /// The model curve `X c + offset` of a spec at coefficients `coef` (five terms, then the
    /// extra columns' amplitudes squared).
    pub fn model_of(&self, spec: &ModelSpec, coef: &[f64]) -> Vec<f64> {
        self.linear_part(spec, coef)
            .into_iter()
            .zip(self.offset_of(spec, coef))
            .map(|(v, o)| v + o)
            .collect()
    }

    /// The five terms' and extra columns' part `X c` of a model's curve, without its fixed
    /// part (the offset and the rounding after the filter).
    pub fn linear_part(&self, spec: &ModelSpec, coef: &[f64]) -> Vec<f64> {
        let x = self.columns(spec);
        (0..self.len())
            .map(|r| {
                (0..x.ncols())
                    .map(|c| x[(r, c)] * coef.get(c).copied().unwrap_or(0.0))
                    .sum()
            })
            .collect()
    }

    /// The design columns of a spec.
    fn columns(&self, spec: &ModelSpec) -> DMatrix<f64> {
        let j = self.len();
        let k = 5 + spec.extra.len();
        // The filter's white-rate column, and its flicker-rate column: the unit's filter
        // smooths its flicker floor too (LowPass::flicker_rate_avar). Kept per filter.
        let cols = self.model_filter(spec).map(|lp| {
            self.memo.columns(&lp, || {
                let white = match lp {
                    LowPass::FirstOrder { time_constant_s } => effect_column(
                        EffectKind::OutputFilter,
                        time_constant_s,
                        &self.ms,
                        self.tau0_s,
                        self.n_inc,
                    ),
                    other => other.white_rate_avar(self.tau0_s, &self.ms),
                };
                (white, lp.flicker_rate_avar(self.tau0_s, &self.ms))
            })
        });
        let filt = cols.as_ref().map(|c| &c.0);
        let filt_b = cols.as_ref().map(|c| &c.1);
        DMatrix::from_fn(j, k, |r, c| {
            if c < 5 {
                match (&filt, &filt_b, c) {
                    (Some(f), _, 1) => f[r],
                    (_, Some(f), 2) => f[r],
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
        self.gls_with(spec, None)
    }

    /// `held`: a five-term coefficient held at a value (its column zeroed here, its part in
    /// the spec's offset).
    fn gls_with(&self, spec: &ModelSpec, held: Option<(usize, f64)>) -> Option<GlsFit> {
        let j = self.len();
        let mut x = self.columns(spec);
        if let Some((t, _)) = held {
            x.column_mut(t).fill(0.0);
        }
        let k = x.ncols();
        // The rounding after the filter depends on the fit's own N (`floor_n2`): it starts at
        // the floor's value and is solved for the fixed point where the N it is computed at is
        // the N fitted with it ([`FloorN2Search`], which says why plain iteration does not
        // reach it; docs/gap.md, "The grid model wired (session 15)").
        let floor_in = self.model_filter(spec).is_some() && self.filter_floor.is_some();
        let n_start = self.floor_n2(&[]);
        // below this N^2 (u^2/s) a raw rate sample's noise is under 0.03 steps: the fit holds
        // no white rate the rounding could act on, and the search stops there
        let n_none = self
            .filter_floor
            .map_or(0.0, |fl| 1e-3 * fl.step * fl.step * self.tau0_s);
        let mut n_off = n_start;
        let mut search = FloorN2Search::default();
        let mut off = self.offset_at(spec, n_off);
        let passes = if floor_in {
            GLS_PASSES_FLOOR
        } else {
            GLS_PASSES
        };
        let mut d: Vec<f64> = self.y.clone();
        let mut coef = DVector::zeros(k);
        let mut model = vec![0.0; j];
        let mut a_last = DMatrix::zeros(j, k);
        for pass in 0..passes {
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
            let mut done = false;
            if floor_in {
                // The N the rounding acts on: the held value when N is the term held.
                let g = match held {
                    Some((1, k)) => k,
                    _ => coef[1],
                }
                .max(0.0);
                let converged = (g - n_off).abs() <= FLOOR_N2_TOL * g.max(n_off).max(n_start)
                    || g.max(n_off) <= n_none;
                done = converged && pass + 1 >= GLS_PASSES;
                n_off = if converged || pass + 1 == passes {
                    g
                } else {
                    search.next(pass, n_off, g)
                };
                off = self.offset_at(spec, n_off);
            }
            let mv = &x * &coef;
            for r in 0..j {
                model[r] = mv[r] + off[r];
            }
            if done {
                break;
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
        let n_shape = spec.extra.len()
            + self.model_filter(spec).map_or(0, |f| f.n_shape())
            + if self.sawtooth.is_some() {
                SAWTOOTH_SHAPES
            } else {
                0
            };
        expected -= n_shape as f64 * tr_m / j as f64;
        Some(GlsFit {
            coef: coef.iter().copied().collect(),
            model,
            chi2,
            expected,
        })
    }

    /// The whitened residual projection `P = I - A (A'A)^-1 A'` of the fit `fit` of `spec`:
    /// `A` the whitened design of its active columns, weighted by the fit's own model. The
    /// misfit `r' S^-1 r` of a right model is `z' P z` with `z ~ N(0, M)`, `M` the covariance
    /// seen through the whitening.
    fn residual_projection(&self, spec: &ModelSpec, fit: &GlsFit) -> DMatrix<f64> {
        let j = self.len();
        let x = self.columns(spec);
        let active: Vec<usize> = (0..x.ncols().min(fit.coef.len()))
            .filter(|&c| fit.coef[c] > 0.0)
            .collect();
        let mut p = DMatrix::<f64>::identity(j, j);
        if !active.is_empty() {
            let xd = DMatrix::from_fn(j, active.len(), |r, c| {
                x[(r, active[c])] / fit.model[r].max(1e-6 * self.y[r])
            });
            let a = &self.linv * xd;
            if let Some(inv) = (a.transpose() * &a).try_inverse() {
                p -= &a * inv * a.transpose();
            }
        }
        p
    }

    /// The effective degrees of freedom of `r' S^-1 r` at the fit `fit` of `spec`: with
    /// `B = P M P` (`P` the whitened residual projection, `residual_projection`) the misfit
    /// of a right model has mean `tr B` and variance `2 tr B^2`, and Satterthwaite's
    /// `nu = tr(B)^2 / tr(B^2)` makes
    /// `G` about `chi2_nu / nu` (F. E. Satterthwaite, "An approximate distribution of
    /// estimates of variance components", Biometrics Bulletin 2(6), 1946). Used to read the
    /// null `G` of clean runs per family (docs/gap.md, "Every family on one commit, and the
    /// base `G`'s tail (session 22)").
    pub fn effective_dof(&self, spec: &ModelSpec, fit: &GlsFit) -> f64 {
        let p = self.residual_projection(spec, fit);
        let b = &p * &self.m_white * &p;
        let t1 = b.trace();
        let t2 = (&b * &b).trace();
        if t2 > 0.0 {
            t1 * t1 / t2
        } else {
            f64::NAN
        }
    }

    /// One-sided upper profile bound on the five-term coefficient `term` (`Q^2 .. R^2`) of the
    /// fit `fit` of `spec`: the least `k >= fit.coef[term]` at which holding the coefficient at
    /// `k` or above (a fixed offset `k x_term`, the column itself still free) raises `r' S^-1 r`
    /// by `delta`; `delta = 1` is the one-sided profile-likelihood bound at about 84% (Wilks;
    /// e.g. Pawitan, "In All Likelihood", section 9.3). The curve cannot tell the term from any
    /// value below it. Bisection in `ln k` up to the value whose term alone reaches the data at
    /// some tau (the bound's ceiling, often reached on runs of an hour or two); `None` when no
    /// fit can be made.
    pub fn upper_bound(
        &self,
        spec: &ModelSpec,
        fit: &GlsFit,
        term: usize,
        delta: f64,
    ) -> Option<f64> {
        let col: Vec<f64> = self.columns(spec).column(term).iter().copied().collect();
        let c0 = fit.coef.get(term).copied()?.max(0.0);
        let chi2_at = |k: f64| -> f64 {
            self.gls(&with_term_offset(spec, &col, k))
                .map_or(f64::INFINITY, |f| f.chi2)
        };
        let k_max = self.term_ceiling(spec, term, 0.0)?;
        let target = fit.chi2 + delta;
        if chi2_at(k_max) < target {
            return Some(k_max.max(c0));
        }
        let mut lo = if c0 > 0.0 { c0 } else { k_max * 1e-9 };
        if chi2_at(lo) >= target {
            return Some(c0);
        }
        let mut hi = k_max;
        for _ in 0..30 {
            let mid = (lo * hi).sqrt();
            if chi2_at(mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi / lo < 1.01 {
                break;
            }
        }
        Some(lo.max(c0))
    }

    /// Lower profile bound on the five-term coefficient `term` (`Q^2 .. R^2`) of the fit `fit`
    /// of `spec`: the least `k <= fit.coef[term]` at which holding the coefficient at exactly
    /// `k` (a fixed offset `k x_term`, its column out of the fit, the others refitted) raises
    /// `r' S^-1 r` by less than `delta`; 0 when even `k = 0` does. Bisection on `[0, c]` to
    /// 0.5%. The twin of [`Self::upper_bound`] for the intervals of [`super::intervals`].
    pub fn lower_bound(&self, spec: &ModelSpec, fit: &GlsFit, term: usize, delta: f64) -> f64 {
        let c_hat = fit.coef.get(term).copied().unwrap_or(0.0).max(0.0);
        let col: Vec<f64> = self.columns(spec).column(term).iter().copied().collect();
        let target = fit.chi2 + delta;
        let within = |k: f64| {
            self.gls_with(&with_term_offset(spec, &col, k), Some((term, k)))
                .is_some_and(|f| f.chi2 < target)
        };
        if c_hat <= 0.0 || within(0.0) {
            return 0.0;
        }
        let (mut below, mut inside) = (0.0, c_hat);
        for _ in 0..40 {
            let mid = 0.5 * (below + inside);
            if within(mid) {
                inside = mid;
            } else {
                below = mid;
            }
            if inside - below <= 0.005 * inside {
                break;
            }
        }
        inside
    }

    /// The largest value of the five-term coefficient `term` (`Q^2 .. R^2`) the curve allows:
    /// the term alone at the data's level where it comes closest to them, each point raised by
    /// `z` of its standard deviation (`exp(z sqrt(S_jj))`; `z = 0` the points themselves);
    /// `None` when its column is zero at every tau.
    pub fn term_ceiling(&self, spec: &ModelSpec, term: usize, z: f64) -> Option<f64> {
        let k_max = self
            .y
            .iter()
            .zip(&self.s_diag)
            .zip(self.columns(spec).column(term).iter())
            .filter(|(_, x)| **x > 0.0)
            .map(|((y, s), x)| y * (z * s.max(0.0).sqrt()).exp() / x)
            .fold(f64::INFINITY, f64::min);
        (k_max.is_finite() && k_max > 0.0).then_some(k_max)
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
            // First maximum of the sinusoid's AVAR at 0.371 / f0 (docs/theory.md section 3).
            EffectKind::Sinusoid => Grid {
                lo: 0.371 / tmax,
                hi: (0.5 / self.tau0_s).min(0.371 / tmin * 2.0),
                per_decade: 60.0,
            },
            EffectKind::OutputFilter | EffectKind::ZeroPhaseFilter => Grid {
                lo: 0.3 * self.tau0_s,
                hi: 30.0 * self.tau0_s,
                per_decade: 12.0,
            },
            // The FIR's cut-off (Hz), from a hundredth of the output rate to near Nyquist
            // ([`super::filter_scan`] scans it with the taps).
            EffectKind::FirFilter => Grid {
                lo: 0.01 / self.tau0_s,
                hi: super::filter_scan::fir_top_hz(1, self.tau0_s),
                per_decade: 12.0,
            },
            // The Butterworth's cut-off (Hz), as the FIR's.
            EffectKind::ButterworthFilter => Grid {
                lo: 0.01 / self.tau0_s,
                hi: super::filter_scan::BUTTERWORTH_TOP / self.tau0_s,
                per_decade: 12.0,
            },
            // Taps (the moving average) and Hz (the second order's natural frequency, its
            // `1 / (2 pi f)` over the first order's range): [`super::filter_scan`] scans them.
            EffectKind::MovingAverage => Grid {
                lo: 2.0,
                hi: super::filter_scan::MAX_TAPS as f64,
                per_decade: 16.0,
            },
            EffectKind::SecondOrderFilter => Grid {
                lo: 1.0 / (2.0 * std::f64::consts::PI * 30.0 * self.tau0_s),
                hi: 1.0 / (2.0 * std::f64::consts::PI * 0.4 * self.tau0_s),
                per_decade: 12.0,
            },
            EffectKind::Warmup => Grid {
                lo: tmin.max(self.tau0_s * 4.0),
                hi: t_run / 3.0,
                per_decade: 12.0,
            },
            // Its centre (Hz); the width is scanned relative to it ([`super::band_noise`]).
            EffectKind::BandNoise => super::band_noise::centre_grid(tmin, tmax, self.tau0_s),
            EffectKind::BiasJumps | EffectKind::Temperature => Grid {
                lo: 1.0,
                hi: 1.0,
                per_decade: 1.0,
            },
        }
    }

    /// The shortest shape a scan of `kind` tries (the grid's points below it are left out, the
    /// others kept as they are): a Gauss-Markov `tau_c` of the curve's shortest tau, a first
    /// order's or zero phase's time constant of half the sampling step. Shorter, either shows
    /// only at the first one or two taus, where the rounding of the values and the sampling
    /// set the curve as much: every such shape named on the saved benchmark runs of sessions 28
    /// to 30 (2 clean draws, a first order at 0.36 tau0) and on the phone-class and ADXL-class
    /// units of sessions 31 and 32 (first orders at 0.34-0.36 tau0, a Gauss-Markov term at
    /// tau0 / 2) was a false alarm, and no true effect drawn lies there (filters from 0.64
    /// tau0, Gauss-Markov terms from 20 tau0; docs/gap.md, "The scans' shortest shapes").
    pub fn shape_floor(&self, kind: EffectKind) -> f64 {
        match kind {
            EffectKind::GaussMarkov => self.tau[0],
            EffectKind::OutputFilter | EffectKind::ZeroPhaseFilter => 0.5 * self.tau0_s,
            _ => 0.0,
        }
    }

    /// `base` with one effect added, with all its parameters (a filter in the N column, with
    /// the filter of `base` in cascade when one is a moving average and the other a first or
    /// second order, [`LowPass::compose`]; an extra column otherwise).
    pub(crate) fn spec_with_params(&self, base: &ModelSpec, p: &EffectParams) -> ModelSpec {
        match p.lowpass() {
            Some(lp) => ModelSpec {
                filter: Some(LowPass::compose(base.filter, lp)),
                ..base.clone()
            },
            None => {
                let mut s = base.clone();
                s.extra.push(super::effects::params_column(
                    p,
                    &self.ms,
                    self.tau0_s,
                    self.n_inc,
                ));
                s
            }
        }
    }

    /// Best parameters of one stationary candidate on top of `base` ([`GapProblem::scan`], or
    /// [`super::filter_scan`] for the filters with two shape parameters). The amplitude is the
    /// fitted last column's.
    pub fn scan_params(
        &self,
        base: &ModelSpec,
        kind: EffectKind,
    ) -> Option<(EffectParams, GlsFit)> {
        match kind {
            EffectKind::MovingAverage
            | EffectKind::SecondOrderFilter
            | EffectKind::FirFilter
            | EffectKind::ButterworthFilter => super::filter_scan::scan(self, base, kind),
            EffectKind::BandNoise => super::band_noise::scan(self, base),
            _ => {
                let (sh, f) = self.scan(base, kind)?;
                let amp = f.coef.last().copied().unwrap_or(0.0).max(0.0).sqrt();
                Some((EffectParams::from_shape(kind, sh, amp), f))
            }
        }
    }

    /// `base` with one candidate effect of shape `shape` added (a filtered N column for a
    /// filter, in its canonical form [`canonical_lowpass`], an extra column otherwise).
    pub(crate) fn spec_with(&self, base: &ModelSpec, kind: EffectKind, shape: f64) -> ModelSpec {
        let mut s = base.clone();
        if kind.is_filter() {
            s.filter = Some(LowPass::compose(
                base.filter,
                canonical_lowpass(kind, shape),
            ));
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
        self.scan_from(base, kind, self.shape_floor(kind))
    }

    /// [`GapProblem::scan`] over the grid's points from `floor` up.
    pub fn scan_from(
        &self,
        base: &ModelSpec,
        kind: EffectKind,
        floor: f64,
    ) -> Option<(f64, GlsFit)> {
        let pts: Vec<f64> = self
            .grid(kind)
            .points()
            .into_iter()
            .filter(|&p| p >= floor)
            .collect();
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
        let lo = pts[bi.saturating_sub(1)].ln();
        let hi = pts[(bi + 1).min(pts.len() - 1)].ln();
        let f = |x: f64| eval(x.exp()).map_or(f64::INFINITY, |f| f.chi2);
        let gb = golden_section(f, lo, hi, 24);
        let cand = [pts[bi].ln(), 0.5 * (gb.lo + gb.hi)];
        cand.iter()
            .filter_map(|&x| eval(x.exp()).map(|fit| (x.exp(), fit)))
            .min_by(|a, b| a.1.chi2.total_cmp(&b.1.chi2))
    }
}

/// The last state of a golden-section search for a minimum of `f` on `[lo, hi]`: the bracket
/// and its two inner points with their values (Press et al., Numerical Recipes, section 10.2).
pub(crate) struct GoldenBracket {
    pub lo: f64,
    pub hi: f64,
    pub x1: f64,
    pub f1: f64,
    pub x2: f64,
    pub f2: f64,
}

impl GoldenBracket {
    /// The inner point with the lower value.
    pub fn best(&self) -> f64 {
        if self.f1 < self.f2 {
            self.x1
        } else {
            self.x2
        }
    }
}

/// `steps` golden-section reductions of `[lo, hi]` toward a minimum of `f` (the curve scans'
/// polish, [`GapProblem::scan`] and [`super::filter_scan`]).
pub(crate) fn golden_section(
    f: impl Fn(f64) -> f64,
    mut lo: f64,
    mut hi: f64,
    steps: usize,
) -> GoldenBracket {
    let g = 0.618_033_988_749_895;
    let mut x1 = hi - g * (hi - lo);
    let mut x2 = lo + g * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..steps {
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
    GoldenBracket {
        lo,
        hi,
        x1,
        f1,
        x2,
        f2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The passes [`FloorN2Search`] needs from `n0` to `|g(n) - n| <= 1e-4 max(g, n)`, at
    /// most `max`, and the point it stops at.
    fn passes_to_fixed_point(map: impl Fn(f64) -> f64, n0: f64, max: usize) -> (usize, f64) {
        let mut search = FloorN2Search::default();
        let mut n = n0;
        for pass in 0..max {
            let g = map(n);
            if (g - n).abs() <= 1e-4 * g.max(n) {
                return (pass + 1, n);
            }
            n = search.next(pass, n, g);
        }
        (max, n)
    }

    #[test]
    fn the_floor_search_reaches_the_fixed_point_in_a_few_passes() {
        // g rising with n, slope 0.6 (fixed point 1): plain iteration needs 20 passes from
        // 0.5 to 1e-4; the secant is exact on a line from its third pass.
        let (p, n) = passes_to_fixed_point(|n| 0.6 * n + 0.4, 0.5, 30);
        assert!(p <= 4 && (n - 1.0).abs() < 1e-4, "{p} passes, {n}");
        // g falling, slope -0.43: plain iteration swings about 1.
        let (p, n) = passes_to_fixed_point(|n| 1.43 - 0.43 * n, 0.2, 30);
        assert!(p <= 4 && (n - 1.0).abs() < 1e-4, "{p} passes, {n}");
        // g = 2 exp(-3 n): slope -3 n < -1 at its fixed point (solved by Newton below), where
        // plain iteration falls into a two-cycle.
        let fixed = {
            let mut x: f64 = 0.4;
            for _ in 0..100 {
                // Newton on 2 exp(-3 x) - x
                let f = 2.0 * (-3.0 * x).exp() - x;
                let d = -6.0 * (-3.0 * x).exp() - 1.0;
                x -= f / d;
            }
            x
        };
        let (p, n) = passes_to_fixed_point(|n| 2.0 * (-3.0 * n).exp(), 1.0, 30);
        assert!(
            p <= 10 && (n / fixed - 1.0).abs() < 2e-4,
            "{p} passes, {n} vs {fixed}"
        );
        let mut plain: f64 = 1.0;
        for _ in 0..200 {
            plain = 2.0 * (-3.0 * plain).exp();
        }
        assert!(
            (plain / fixed - 1.0).abs() > 0.1,
            "plain iteration converged: {plain}"
        );
    }

    /// A VOG4-like gyro (config/models/vog4.toml's N, B, K), 30 minutes at 4 ms, simulated.
    fn vog4_problem() -> (GapProblem, GlsFit) {
        use crate::gap::{GapConfig, GapEvidence};
        use crate::sim::{SimModel, Simulator};
        let text = "tau0_s = 0.004\n[[channel]]\nname = \"g\"\nunit = \"arcsec\"\nN = 0.254\nB = 0.225\nK = 1.826e-2\nflicker_band_s = [0.004, 1.0e5]\n";
        let m = SimModel::from_toml_str(text, std::path::Path::new("<test>")).expect("model");
        let mut sim = Simulator::new(&m, 7);
        let mut inc = vec![0.0; (1800.0 / 0.004) as usize];
        sim.fill_channel(0, &mut inc);
        let mut ev = GapEvidence::from_increments(GapConfig::new(0.004), &inc);
        let prob = GapProblem::new(&ev.snapshot(), &DiagnoseOptions::default()).expect("problem");
        let fit = prob.gls(&ModelSpec::default()).expect("fit");
        (prob, fit)
    }

    /// The scans start at their floors (a Gauss-Markov `tau_c` at the curve's shortest tau, a
    /// first order's or zero phase's time constant at tau0 / 2) and keep the grid's other
    /// points as they are: the shapes they return are never below, and a floor between grid
    /// points drops only the points under it.
    #[test]
    fn scans_start_at_their_floors() {
        let (prob, _) = vog4_problem();
        let base = ModelSpec::default();
        for (kind, floor) in [
            (EffectKind::GaussMarkov, 0.004),
            (EffectKind::OutputFilter, 0.002),
            (EffectKind::ZeroPhaseFilter, 0.002),
        ] {
            assert_eq!(prob.shape_floor(kind), floor);
            let all = prob.grid(kind).points();
            let below = all.iter().filter(|&&p| p < floor).count();
            assert!(below >= 2, "{kind:?}: {below} points below the floor");
            let (shape, _) = prob.scan(&base, kind).expect("scan");
            assert!(shape >= floor, "{kind:?}: {shape}");
        }
        assert_eq!(prob.shape_floor(EffectKind::Sinusoid), 0.0);
    }

    #[test]
    fn the_effective_dof_is_that_of_the_misfit_of_a_right_model() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let (prob, fit) = vog4_problem();
        let spec = ModelSpec::default();
        let j = prob.len();
        let p = prob.residual_projection(&spec, &fit);
        // a projection: symmetric, idempotent, of rank j less the active columns
        assert!((&p * &p - &p).amax() < 1e-9 && (&p - p.transpose()).amax() < 1e-12);
        let active = fit.coef.iter().filter(|c| **c > 0.0).count();
        assert!(
            (p.trace() - (j - active) as f64).abs() < 1e-6,
            "{}",
            p.trace()
        );
        // tr(P M P) is the expectation gls computes its own way (weights of its last pass)
        let b = &p * &prob.m_white * &p;
        assert!(
            (b.trace() / fit.expected - 1.0).abs() < 0.02,
            "{} vs {}",
            b.trace(),
            fit.expected
        );
        let nu = prob.effective_dof(&spec, &fit);
        assert!(nu > 1.0 && nu <= (j - active) as f64 + 1e-9, "nu {nu}");
        // Monte Carlo of z' P z, z ~ N(0, M): mean tr B, and 2 mean^2 / var = nu
        let l = prob.m_white.clone().cholesky().expect("M").l();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let n = 20_000;
        let qs: Vec<f64> = (0..n)
            .map(|_| {
                let g = DVector::from_fn(j, |_, _| StandardNormal.sample(&mut rng));
                let z = &l * g;
                (z.transpose() * &p * &z)[(0, 0)]
            })
            .collect();
        let mean = qs.iter().sum::<f64>() / n as f64;
        let var = qs.iter().map(|q| (q - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let nu_mc = 2.0 * mean * mean / var;
        assert!(
            (mean / b.trace() - 1.0).abs() < 0.02,
            "{mean} vs {}",
            b.trace()
        );
        assert!(
            (nu_mc / nu - 1.0).abs() < 0.05,
            "Monte Carlo {nu_mc} vs {nu}"
        );
    }
}
