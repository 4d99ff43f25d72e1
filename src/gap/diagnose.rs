//! The diagnosis proper (docs/theory.md section 5): where the measured AVAR curve departs from the
//! fitted five-term model (on the tau axis and in time), which effect of docs/theory.md section 3
//! closes the gap, and by how much. Works on an [`EvidenceSnapshot`]; pure and synchronous.
//!
//! # Method
//!
//! - Covariance. `S`, the covariance of the log estimates `ln AVAR_hat(tau_j)`, is the analytic
//!   covariance of the five-term model fitted to the curve
//!   ([`AvarCovariance::matrix_strided`](crate::model::avar_cov::AvarCovariance::matrix_strided):
//!   each level at the stride the bounded-overlap estimator took it, which costs white phase
//!   noise its degrees of freedom), divided by `AVAR_i AVAR_j`. It is computed once per curve and used for every
//!   candidate model, so the gap statistics of different models are comparable. A ridge
//!   `S + RIDGE diag(S)` keeps the inverse from amplifying the small mismatch between the
//!   analytic covariance and the bounded-overlap estimator in its smallest eigen-directions;
//!   [`Thresholds`] are calibrated by simulation with that ridge.
//! - Fit of a model (five terms plus effect columns): generalised least squares with the
//!   covariance `D S D`, `D = diag(model)`, solved as NNLS after whitening, reweighted from the
//!   model a few times (weights from the data bias the fit low: docs/theory.md section 2).
//! - Gap statistic `G = r' S^-1 r / (J - p)`, `r = ln AVAR_hat - ln AVAR_model` (docs/theory.md
//!   section 5); near 1 when the model is right.
//! - Effects: for each candidate, its shape parameter on a log grid (NNLS at each), the best one
//!   polished by golden section; the candidate with the largest drop in `r' S^-1 r` is added if
//!   the drop exceeds [`Thresholds::add_chi2`] per parameter, and effects are added while `G`
//!   stays above [`Thresholds::gap_crit`] ([`Thresholds::gap_crit_filtered`] once a low-pass
//!   filter is among them). A candidate also flags the model on its own when its
//!   drop per parameter exceeds its own [`Thresholds::lr_crit`] (a likelihood-ratio test
//!   against the named alternatives, which catches bumps that the omnibus `G` misses).
//! - Bias jumps have the second-order law of a rate random walk (K absorbs them on the curve),
//!   so they are found in time: steps in the block-mean rate by generalised least squares with
//!   the fitted model's noise covariance, forward selection ([`detect_steps`]).
//! - A warm-up is found in time too ([`fit_warmup`]): its test statistic is the block-mean
//!   evidence integrated over the scanned time constant ([`WarmupFinding::log_bf`](super::warmup::WarmupFinding::log_bf), against
//!   [`Thresholds::warmup_bf`]), not its maximum (docs/gap.md, "Mixture statistics").
//! - Bookkeeping: the effects found are added again in their order, each kept only if it
//!   lowers the gap of the model with the effects kept before it; an effect's `gap_after` is
//!   that model's gap, so the final gap is never above the base model's. The verdict is
//!   `consistent` when nothing is kept and the base `G` is not flagged (docs/gap.md,
//!   "Bookkeeping").
//!
//! Layout: the GLS problem on the curve is [`super::problem`], its thresholds
//! [`super::thresholds`]; the time-domain tests are [`super::warmup`] and [`super::steps`] on the
//! block-mean covariance of [`super::block_cov`]; [`super::segments`] tests homogeneity across
//! segments and [`super::holdout`] judges a held-out run. This file orchestrates them.

use super::alternatives::{
    alternatives, temperature_alternatives, Alternative, CandidateScore, FirstScan, AIC_MARGIN,
};
use super::effects::{effect_column, EffectKind, EffectParams};
use super::evidence::EvidenceSnapshot;
use super::first_block::FirstBlock;
use super::outliers::OutlierCount;
use super::problem::{GapProblem, GlsFit, ModelSpec};
use super::quant_limit::{quantization_limit, QuantizationLimit};
use super::quantization::{judge_quantization, QuantizationFinding};
use super::segments::{segment_tests, SegmentTest};
use super::steps::{detect_steps, JumpFinding};
use super::temperature::{enter_temperature, TEMPERATURE_Z, TEMPERATURE_Z_ALONE};
use super::thresholds::Thresholds;
use super::warmup::{fit_warmup, WARMUP_K_DELTA};
use super::warmup_profile::fit_warmup_profiled;
use crate::model::terms;

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
    /// Cluster sizes below this are left out of the curve (1: none); the diagnosis raises it
    /// for a quantization-limited unit ([`super::quant_limit`]).
    pub min_m: u64,
    /// Five-term coefficients `(Q^2, N^2, B^2, K^2, R^2)` whose analytic covariance is taken as
    /// `S` instead of the plain five-term fit's. The diagnosis sets it for its second pass when
    /// it found an output filter (docs/gap.md, "Low-pass filters beyond first order"): a curve
    /// pulled down at short taus by a filter misleads the plain fit (N near 0, B inflated), and
    /// `S` with it.
    pub cov_coef: Option<[f64; 5]>,
    /// The output filter found by the previous pass: `S` gets its exact correction for the
    /// filtered white rate ([`super::filter_cov`]) and the model it is normalised by takes the
    /// white and flicker rate through the filter ([`super::problem::GapProblem::new`]).
    pub cov_filter: Option<crate::model::lowpass::LowPass>,
    /// The previous pass read the values' step as a counter with carry (white phase,
    /// [`super::quantization::QuantKind::Angle`]): its quantization error is in the model, and
    /// the covariance carries no rounding discrepancy ([`super::discrepancy`], which is for
    /// rate samples rounded after the filter).
    pub cov_counter: bool,
    /// A filter every model of the curve carries where no filter is named in its place: the
    /// unit's filter as the whole curve named it, for the diagnosis beyond that filter's own
    /// stretch, where its tail (white phase noise of negative size) is still in the curve
    /// ([`super::filter_shape`]). None: no such filter.
    pub base_filter: Option<crate::model::lowpass::LowPass>,
    /// Threads on which the candidates of a step are scanned (at least 1; the record is the
    /// same for any count: each candidate's scan is computed alone and they are judged in
    /// order). The default is the machine's parallelism, at most [`MAX_SCAN_THREADS`].
    pub threads: usize,
}

/// The most threads [`DiagnoseOptions::threads`] takes by default: a step scans about a dozen
/// candidates, the second order's the longest (docs/gap.md, "Speed (session 47): the
/// candidates side by side").
pub const MAX_SCAN_THREADS: usize = 4;

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            tau_max_fraction: 0.1,
            max_effects: 2,
            candidates: EffectKind::ALL.to_vec(),

            thresholds: Thresholds::default(),
            min_m: 1,
            cov_coef: None,
            cov_filter: None,
            cov_counter: false,
            base_filter: None,
            threads: std::thread::available_parallelism()
                .map_or(1, |n| n.get())
                .min(MAX_SCAN_THREADS),
        }
    }
}

/// `f` of each item, in the items' order, on up to `threads` scoped threads taking the next
/// item as they finish (the items are given longest first where that is known, so that no
/// thread is left with the longest at the end).
fn map_on_threads<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let threads = threads.clamp(1, items.len().max(1));
    if threads == 1 {
        return items.iter().map(f).collect();
    }
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut done: Vec<(usize, R)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(item) = items.get(i) else {
                            return out;
                        };
                        out.push((i, f(item)));
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| match w.join() {
                Ok(v) => v,
                Err(panic) => std::panic::resume_unwind(panic),
            })
            .collect()
    });
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, r)| r).collect()
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
    /// Every increment received was the same value, given here as a rate (u/s).
    #[error(
        "diagnose: every sample is the same, a rate of {0} u/s throughout: the channel does not \
         move (stuck, saturated or not connected?), so it has no noise to diagnose"
    )]
    Constant(f64),
    /// Too few curve points because the samples come one or two at a time between gaps: the
    /// samples received and the stretches they come in.
    #[error(
        "diagnose: its {0} samples come in {1} stretches, one or two samples each (a value on \
         every other row: a channel logged slower than the file's rows?), so no differences are \
         left for a curve; analyse it alone (--channels NAME: with a time column its rows are \
         then its samples)"
    )]
    Scattered(u64, u64),
}

/// The verdict of docs/records.md's `diagnosis` record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Consistent,
    Explained,
    Unexplained,
}

impl Verdict {
    /// The record's word for it (`consistent`, `explained`, `unexplained`).
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Consistent => "consistent",
            Verdict::Explained => "explained",
            Verdict::Unexplained => "unexplained",
        }
    }
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

/// An effect kept in the model, with the gap of the model of the effects kept up to and
/// including it (each lower than the one before).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AddedEffect {
    pub params: EffectParams,
    pub gap_after: f64,
    /// Drop of `r' S^-1 r` it brought.
    pub delta_chi2: f64,
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
    /// Their 95% intervals ([`super::intervals::TermInterval`]); `None` where none could be
    /// computed.
    pub final_terms: [Option<super::intervals::TermInterval>; 5],
    /// The five terms `(Q, N, B, K, R)` whose analytic covariance is the `S` of `G`: the plain
    /// fit's, or after a filter the previous pass's `final_coef` (docs/gap.md, "The
    /// covariance's five terms after a filter (session 19)").
    pub cov_coef: [f64; 5],
    /// Taus used and the number of them.
    pub tau_span_s: (f64, f64),
    pub n_taus: usize,
    pub t_data_s: f64,
    pub segment_tests: Vec<SegmentTest>,
    /// The bias jumps named (empty when none was kept), their times in s from the record's
    /// first sample (not from the block tests' first block, as [`JumpFinding`] has them).
    pub jumps: Option<JumpFinding>,
    /// A word on what is left when the verdict is `unexplained`.
    pub residual_shape: Option<String>,
    /// The taus of the curve diagnosed (s) and, at each, the AVAR (u^2/s^2) of the five-term
    /// model alone and of the model with the effects in (warm-up and jumps as their exact AVAR
    /// on this record), for plots.
    pub model_tau_s: Vec<f64>,
    pub model_base_avar: Vec<f64>,
    pub model_final_avar: Vec<f64>,
    /// Set when the unit's quantization is not white at the shortest taus (its LSB is coarse
    /// against the per-sample noise): the curve is then diagnosed from `tau_white_s` on only
    /// ([`super::quant_limit`]; docs/gap.md, "Quantization-limited units").
    pub quantization_limited: Option<QuantizationLimit>,
    /// Outliers found and replaced in the stream before the curve was computed
    /// ([`super::outliers`]).
    pub outliers: OutlierCount,
    /// Stretches where the channel did not move, taken out as gaps before the curve was
    /// computed ([`super::stuck`]); `None` when there is none.
    pub stuck: Option<super::stuck::StuckSpan>,
    /// The block tests' first block, when its mean is far off the rest of the run but the
    /// transient is too short to name as a warm-up ([`super::first_block`]); `None` otherwise.
    pub first_block: Option<FirstBlock>,
    /// What the values' step does to the curve, when they are whole multiples of one
    /// ([`super::quantization`]).
    pub quantization: Option<QuantizationFinding>,
    /// Other explanations that fit about as well as the one chosen ([`super::alternatives`]).
    pub alternatives: Vec<Alternative>,
    /// The temperature's coefficient and why it is or is not named, when the input has a
    /// temperature ([`super::temperature_check`]).
    pub temperature_check: Option<super::temperature_check::TemperatureCheck>,
    /// 95% intervals of each effect's parameters, in the order of `effects`
    /// ([`super::intervals`]).
    pub effect_intervals: Vec<super::intervals::Intervals>,
    /// The first step of the stationary search on the curve: each candidate's best drop of
    /// `r' S^-1 r` per parameter against the base model and the threshold it had to pass
    /// (their null distribution on clean runs calibrates `lr_crit`; docs/gap.md,
    /// "Calibration").
    pub first_scores: Vec<CandidateScore>,
    /// Named sinusoids that are the counter's limit cycle, not an effect of the unit
    /// ([`super::limit_cycle`]).
    pub limit_cycles: Vec<super::limit_cycle::LimitCycle>,
    /// The counter's sawtooth, when the base model carries it ([`super::sawtooth`]): part of
    /// every model of the curve, not an effect of the unit.
    pub sawtooth: Option<super::sawtooth::Sawtooth>,
    /// Set when the curve was judged beyond the unit's filter's own stretch
    /// ([`super::filter_shape`]): the filter the whole curve named, from which tau on, and
    /// what was set aside.
    pub filter_shape: Option<super::filter_shape::FilterShape>,
}

impl Diagnosis {
    /// The five terms this diagnosis fitted, squared, as the next pass's covariance takes them
    /// ([`DiagnoseOptions::cov_coef`]); None when the fit has no white rate or a term is not
    /// finite.
    pub(crate) fn fitted_cov_coef(&self) -> Option<[f64; 5]> {
        let fitted = self.final_coef.map(|c| c * c);
        (fitted[1] > 0.0 && fitted.iter().all(|v| v.is_finite())).then_some(fitted)
    }

    /// Whether this diagnosis read the values' step as a counter with carry (a sawtooth kept,
    /// or the quantization judged white phase), for the next pass's
    /// [`DiagnoseOptions::cov_counter`].
    pub(crate) fn read_a_counter(&self) -> bool {
        self.sawtooth.is_some()
            || self
                .quantization
                .is_some_and(|q| q.kind == super::quantization::QuantKind::Angle)
    }

    /// Whether an effect of this kind is kept in the model.
    pub fn names(&self, kind: EffectKind) -> bool {
        self.effects.iter().any(|e| e.params.kind() == kind)
    }
}

/// Five-term `(Q, N, B, K, R)` from `c`.
pub(crate) fn coef5(c: &[f64]) -> [f64; 5] {
    std::array::from_fn(|i| c.get(i).copied().unwrap_or(0.0).max(0.0).sqrt())
}

/// Diagnoses one channel's evidence.
pub fn diagnose(
    snap: &EvidenceSnapshot,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    diagnose_with_temperature(snap, None, opts)
}

/// Diagnoses one channel's evidence with, when the input has one, the unit's temperature
/// gathered beside it (the same [`GapConfig`](super::evidence::GapConfig), fed `T tau0` per step:
/// [`super::temperature`]).
///
/// When the increments are quantized with an LSB so coarse against the per-sample noise that
/// the quantization error is not white ([`quantization_limit`]), the diagnosis says so
/// (`quantization_limited`). It reads the whole curve when the counter's sawtooth in the base
/// model ([`super::sawtooth`]) describes it (the base model's gap at most `gap_crit` with it;
/// since session 24), and otherwise only from the tau where the error is white again (when
/// enough of it is left; otherwise the whole curve, still flagged).
pub fn diagnose_with_temperature(
    snap: &EvidenceSnapshot,
    temperature: Option<&EvidenceSnapshot>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    // Its curve would be the rounding of the running sum (1e-19 of the rate, say), which no
    // noise model describes.
    if let Some(d) = snap.constant {
        return Err(DiagnoseError::Constant(d / snap.tau0_s));
    }
    let mut d = diagnose_quantized(snap, temperature, opts).map_err(|e| match e {
        // Not a short run: a channel on a slower clock than the rows (docs/robustness.md).
        DiagnoseError::TooFewPoints(..)
            if snap.n_received >= 16 && snap.n_received < 2 * snap.n_stretches =>
        {
            DiagnoseError::Scattered(snap.n_received, snap.n_stretches)
        }
        e => e,
    })?;
    super::limit_cycle::attribute(&mut d, snap);
    Ok(d)
}

/// [`diagnose_with_temperature`] before the counter's limit cycles are attributed.
fn diagnose_quantized(
    snap: &EvidenceSnapshot,
    temperature: Option<&EvidenceSnapshot>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let Some(limit) = check_quantization(snap, opts) else {
        let d = diagnose_curve(snap, temperature, opts)?;
        return Ok(super::filter_shape::judge_beyond(
            snap,
            temperature,
            opts,
            d,
        ));
    };
    // The counter's sawtooth in the base model is the quantization error's own autocovariance
    // (super::sawtooth): where the base model with it describes the whole curve (`G <=
    // gap_crit`), the short taus are read too. Without the sawtooth kept the whole curve is not
    // read, even when the five terms alone fit it: the error's structure at the short taus is
    // then left to the candidates (docs/gap.md, "The whole curve of a quantization-limited
    // counter (session 24)").
    //
    // A counter behind a filter (session 25) has no base model that fits: its model is the
    // filter with the sawtooth behind it. The whole curve is read when that model describes
    // it, the gap right after the filter at most `gap_crit_filtered` (docs/gap.md, "The whole
    // curve of a filtered counter (session 26)").
    if let Ok(mut d) = diagnose_curve(snap, temperature, opts) {
        let behind = behind_filter_gap(&d);
        let whole = d.sawtooth.is_some()
            && (d.gap_before <= opts.thresholds.gap_crit
                || behind.is_some_and(|g| g <= opts.thresholds.gap_crit_filtered));
        tracing::debug!(
            sawtooth = d.sawtooth.is_some(),
            gap_before = d.gap_before,
            behind_filter = behind,
            whole,
            "a quantization-limited unit's whole curve"
        );
        if whole {
            d.quantization_limited = Some(limit);
            return Ok(d);
        }
    }
    let restricted = DiagnoseOptions {
        min_m: opts.min_m.max(limit.m_white),
        ..opts.clone()
    };
    let mut d = match diagnose_curve(snap, temperature, &restricted) {
        Ok(d) => d,
        Err(e) => {
            tracing::debug!(error = %e, m_white = limit.m_white, "no diagnosis from the white tau on");
            nearest_cut(snap, temperature, opts, limit.m_white)?
        }
    };
    d.quantization_limited = Some(limit);
    Ok(d)
}

/// The diagnosis of a quantization-limited unit whose run ends too soon after `tau_white`
/// (`m_white` samples) for a curve there: from the longest cut below it, halving, that leaves
/// a curve to judge (the record's `tau_span` says where it starts); the whole curve only when
/// none does. Before (session 49), the whole curve at once: a tenth blind review's pendulous
/// accelerometers (an LSB 100-150 times the per-sample noise, `tau_white` 58-150 s on runs of
/// an hour) were `unexplained` there, G 23 with a 0.3 Hz line named on a clean unit whose curve
/// from 10 s on fits the five terms (G 1.2).
fn nearest_cut(
    snap: &EvidenceSnapshot,
    temperature: Option<&EvidenceSnapshot>,
    opts: &DiagnoseOptions,
    m_white: u64,
) -> Result<Diagnosis, DiagnoseError> {
    let mut m = m_white / 2;
    while m > opts.min_m.max(1) {
        let cut = DiagnoseOptions {
            min_m: m,
            ..opts.clone()
        };
        match diagnose_curve(snap, temperature, &cut) {
            Ok(d) => {
                tracing::debug!(
                    min_m = m,
                    m_white,
                    "the curve judged from the nearest cut below the white tau"
                );
                return Ok(d);
            }
            Err(e) => tracing::trace!(error = %e, min_m = m, "no curve from this cut either"),
        }
        m /= 2;
    }
    diagnose_curve(snap, temperature, opts)
}

/// The gap of a diagnosis's model right after the low-pass its sawtooth is behind
/// ([`super::sawtooth::Sawtooth::filter`]): the first filter among the effects (each effect's
/// gap is of the model with every effect up to it; the sawtooth's copy of the filter may have
/// been fitted apart from the effect's). None without a sawtooth behind a filter named among
/// the effects.
fn behind_filter_gap(d: &Diagnosis) -> Option<f64> {
    d.sawtooth.as_ref()?.filter?;
    d.effects
        .iter()
        .find(|e| e.params.lowpass().is_some())
        .map(|e| e.gap_after)
}

/// The quantization check of [`diagnose_with_temperature`]. The five-term fit of the whole
/// curve gives a first `Q` and `N`; when they say the quantization is white, it is. Otherwise
/// the shortest taus may only have biased that fit (an output filter lowers them too), so the
/// curve is refitted from cluster sizes 8, 16, 32, ... on while the cut is below the median of
/// the white taus found ([`CREDIBLE_FIT_GAP`]); a fit that calls the quantization white
/// (`None`), or, before any is found, one whose own white tau lies at or below its cut, decides;
/// else that median (the last fit's limit when no fit describes its taus).
fn check_quantization(
    snap: &EvidenceSnapshot,
    opts: &DiagnoseOptions,
) -> Option<QuantizationLimit> {
    let lsb = snap.lsb?;
    // The verdict of the five-term fit from cluster size `min_m` on, and that fit's gap.
    let judge = |min_m: u64| {
        let o = DiagnoseOptions {
            min_m,
            ..opts.clone()
        };
        let fit = GapProblem::new(snap, &o).ok()?.gls(&ModelSpec::default())?;
        let c = |i: usize| fit.coef.get(i).copied().unwrap_or(0.0);
        let limit = quantization_limit(lsb, c(0), c(1), snap.tau0_s);
        tracing::debug!(
            min_m,
            gap = fit.gap(),
            q = c(0).sqrt(),
            n = c(1).sqrt(),
            ?limit,
            "the quantization judged from a cut"
        );
        // Whether the white rate alone whitens the quantization (no excess white phase noise
        // counted): a fit from taus where `Q` no longer shows may make its excess up.
        let white_by_n = quantization_limit(lsb, lsb * lsb / 12.0, c(1), snap.tau0_s).is_none();
        Some((limit, fit.gap(), white_by_n))
    };
    let credible = |gap: f64| gap <= CREDIBLE_FIT_GAP;
    let (first, gap, _) = judge(opts.min_m)?;
    let mut last = first?;
    // The limits found by fits that describe their taus and see a white rate, and their median.
    let mut found: Vec<QuantizationLimit> = Vec::new();
    let keep = |found: &mut Vec<QuantizationLimit>, l: QuantizationLimit, gap: f64| {
        if credible(gap) && l.m_white != u64::MAX {
            found.push(l);
            found.sort_by_key(|l| l.m_white);
        }
    };
    let median = |found: &[QuantizationLimit]| found.get(found.len() / 2).copied();
    keep(&mut found, last, gap);
    let mut cut = opts.min_m.max(8);
    // At most ~40 doublings: the fit fails once fewer than 8 taus are left. Once a limit is
    // found, fits are made only from cuts below its white tau: from there on a fit reads only
    // taus already called white, where `Q` is not determined (session 41, below).
    while median(&found).is_none_or(|f| cut < f.m_white) {
        let Some((verdict, gap, white_by_n)) = judge(cut) else {
            break;
        };
        match verdict {
            // The fit from this cut on says the quantization is white. Once a white tau is
            // found, only a fit that describes its taus and whose white rate alone whitens the
            // counter says so: one made white by an excess `Q` it cannot see is not believed.
            None if found.is_empty() || (credible(gap) && white_by_n) => return None,
            None => {}
            Some(l) => {
                last = l;
                // A fit whose own white tau lies at or below its cut read white taus only: with
                // no limit found yet it decides (a dead-band unit behind a filter, whose fits
                // all follow the filter); after one, it is one more reading of the white tau.
                if found.is_empty() && l.m_white <= cut {
                    return Some(l);
                }
                keep(&mut found, l, gap);
            }
        }
        cut = cut.saturating_mul(2);
    }
    Some(median(&found).unwrap_or(last))
}

/// The largest gap of a five-term fit whose verdict on the quantization
/// ([`check_quantization`]) is taken as a reading of the white tau. The pendulous counters of
/// the session-41 review (N 1e-4 m/s/sqrt(s) on a 1e-3 m/s pulse, 250 Hz, 3 h, the pulse rate
/// drifting) show why: their fits from cluster sizes below about 1 s follow the limit cycle's
/// lines (gaps 800-120 000) and give any white tau from 0.7 s to never; from 2 s on the gaps
/// are 0.5-3.8 and the white taus 20-390 s, against the 42 s of the true N, scattered because
/// N is weakly determined where Q rules. Their median is taken (the upper middle of an even
/// count), the scan stops once its cut passes it, and a fit that loses N (beside a
/// Gauss-Markov term) has no white tau and is not a reading. Before, the scan went on until a
/// fit from 33-65 s on, where `Q` is no longer seen, made `Q` 1.2-2 times the LSB's and called
/// the quantization white: the whole curve was read, its lines named as a sinusoid and band
/// noise, verdict `unexplained` on 2 of 5 clean runs of the review and 2 of 11 of ours.
const CREDIBLE_FIT_GAP: f64 = 10.0;

/// The diagnosis of the curve (from `opts.min_m` on) and of the block means; when it finds an
/// output filter, again with the covariance of its five terms ([`DiagnoseOptions::cov_coef`]).
pub(crate) fn diagnose_curve(
    snap: &EvidenceSnapshot,
    temperature: Option<&EvidenceSnapshot>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let mut d = diagnose_curve_once(snap, temperature, opts)?;
    log_pass(1, &d);
    if opts.cov_coef.is_some() {
        return Ok(d);
    }
    // Again with the covariance of the filter found, until the filter named is the one whose
    // covariance was used (three passes at most: the first pass's covariance, without the
    // filter, can favour another filter of the family).
    let mut used: Option<crate::model::lowpass::LowPass> = None;
    // A first pass that named a Gauss-Markov term and no filter, where the first scan's best
    // filter fitted about as well: white rate through a first order is a Gauss-Markov process
    // at its time constant, and the first pass's covariance, without the filter, cannot tell
    // the two apart. The pass with that filter's covariance is tried, and kept only if it
    // ends with a lower gap (docs/gap.md, "A Gauss-Markov term tied with a filter (session
    // 17)").
    let mut tied = tied_filter(&d.effects, &d.first_scores);
    for _ in 0..2 {
        let trial = tied.take();
        let Some(lp) = EffectParams::unit_filter(d.effects.iter().map(|e| &e.params)).or(trial)
        else {
            return Ok(d);
        };
        if used.is_some_and(|u| same_filter(&u, &lp, snap.lsb.is_some(), snap.tau0_s)) {
            return Ok(d);
        }
        // The covariance's five terms: those the pass fitted with the filter in its model (its
        // N and B columns through the filter). Until session 19 they were the plain fit of the
        // taus beyond ten memories of the filter, but ten memories out a filter still takes
        // about a tenth off the white rate's AVAR, a dip the plain fit can only follow with B
        // (three to twelve times B's true value on zpexp draws of seed 181), and `S` too
        // loose or too tight with it (docs/gap.md, "The covariance's five terms after a
        // filter (session 19)"). The plain fit beyond ten memories remains for a filter tried
        // beside a Gauss-Markov term (`trial`: its five terms were fitted beside that term,
        // not through the filter) and a pass whose fit has no white rate.
        let c_cov = if let Some(fitted) = d.fitted_cov_coef().filter(|_| trial.is_none()) {
            fitted
        } else {
            let m_cut = (10.0 * lp.memory_s(snap.tau0_s) / snap.tau0_s)
                .ceil()
                .max(1.0) as u64;
            let cut = DiagnoseOptions {
                min_m: opts.min_m.max(m_cut),
                ..opts.clone()
            };
            let Ok(beyond) = GapProblem::new(snap, &cut) else {
                return Ok(d);
            };
            beyond.c_init
        };
        tracing::debug!(c_cov = ?c_cov.map(f64::sqrt), "the next pass's covariance: five terms (Q, N, B, K, R)");
        let next = DiagnoseOptions {
            cov_coef: Some(c_cov),
            cov_filter: Some(lp),
            // A pass that kept a counter's sawtooth read a counter (behind the filter, its
            // quantization is neither floor: docs/gap.md, "The counter behind a filter
            // (session 25)"), which has no rate rounding after the filter.
            cov_counter: d.read_a_counter(),
            ..opts.clone()
        };
        match diagnose_curve_once(snap, temperature, &next) {
            // Kept only if it ends lower: the tied filter's trial pass, and a third pass (with
            // the covariance of a filter the second pass named in place of the first pass's).
            // Session 20 kept a third pass that names no filter only so (accgrav seed 191 draw
            // 18: the first order alone at G 0.81, then a Gauss-Markov term at its time
            // constant, G 1.22); since session 21 any third pass (the same draw, with
            // `gap_crit_filtered`: the first order at G 2.97 and a sinusoid beside it, G 2.15).
            Ok(n)
                if (trial.is_some() || used.is_some())
                    && n.gap_after.partial_cmp(&d.gap_after) != Some(std::cmp::Ordering::Less) =>
            {
                log_pass(2 + usize::from(used.is_some()), &n);
                return Ok(d);
            }
            Ok(n) => {
                d = n;
                log_pass(2 + usize::from(used.is_some()), &d);
            }
            Err(e) => {
                tracing::debug!(%e, "the pass with the filter's covariance failed; the previous pass stands");
                return Ok(d);
            }
        }
        used = Some(lp);
    }
    Ok(d)
}

/// The share by which the first scan's best filter may fit worse than the best candidate and
/// still count as tied with it ([`tied_filter`]): its gap within 5%.
const TIE_GAP_RATIO: f64 = 1.05;

/// The filter tied with a Gauss-Markov term that a pass named in its place (see
/// [`diagnose_curve`]), from the pass's `effects` and its first scan's `scores`: None when the
/// pass named a filter, named no Gauss-Markov term, or the first scan's best filter's gap is
/// above [`TIE_GAP_RATIO`] times the best candidate's.
fn tied_filter(
    effects: &[AddedEffect],
    scores: &[CandidateScore],
) -> Option<crate::model::lowpass::LowPass> {
    if effects.iter().any(|e| e.params.lowpass().is_some())
        || !effects
            .iter()
            .any(|e| e.params.kind() == EffectKind::GaussMarkov)
    {
        return None;
    }
    let best = scores
        .iter()
        .map(|c| c.gap_alt)
        .filter(|g| g.is_finite())
        .fold(f64::INFINITY, f64::min);
    scores
        .iter()
        .filter(|c| c.gap_alt.is_finite() && c.gap_alt <= TIE_GAP_RATIO * best)
        .filter_map(|c| c.params.lowpass().map(|lp| (c.gap_alt, lp)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, lp)| lp)
}

/// One pass of [`diagnose_curve`] at debug level (`ALLANSCOPE_LOG=allanscope=debug`): its
/// gaps, the effects it kept and the step's kind.
fn log_pass(pass: usize, d: &Diagnosis) {
    tracing::debug!(
        pass,
        gap_before = d.gap_before,
        gap_after = d.gap_after,
        effects = ?d.effects.iter().map(|e| (e.params, e.gap_after)).collect::<Vec<_>>(),
        quantization = ?d.quantization.map(|q| q.kind),
        "diagnosis pass"
    );
}

/// Whether the filter named `b` is the one whose covariance was used, `a`: the same kind and,
/// on a channel whose values show their step (whose covariance carries the rounding's
/// discrepancy, set by the filter's memory: [`super::discrepancy`]), a memory within 25%.
fn same_filter(
    a: &crate::model::lowpass::LowPass,
    b: &crate::model::lowpass::LowPass,
    stepped: bool,
    tau0_s: f64,
) -> bool {
    if std::mem::discriminant(a) != std::mem::discriminant(b) {
        return false;
    }
    let r = b.memory_s(tau0_s) / a.memory_s(tau0_s);
    !stepped || (0.8..=1.25).contains(&r)
}

/// One pass of the diagnosis. A temperature that entered first (step 0) and that the
/// bookkeeping did not keep has had its block shape taken out of the block means the warm-up
/// test saw, and with it the warm-up it resembles in a settling chamber: a unit's own warm-up
/// (5e-4 rad/s over 300 s) in a chamber settling over 1500 s was named in 3 of 20 runs with the
/// temperature column and in 17 of 20 without it, the temperature entering at `|z|` 4-6 and then
/// not lowering the curve's gap. The pass is then run again without the temperature entering
/// (it is still checked, [`super::temperature_check`]), and taken when it names a warm-up the
/// first did not. Only then: on the settling chamber's unit with a coefficient of 1e-4 the pass
/// without it named jumps (1 run of 20) where the first named nothing (docs/gap.md, "A
/// temperature not kept (session 39)").
fn diagnose_curve_once(
    snap: &EvidenceSnapshot,
    temperature: Option<&EvidenceSnapshot>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let (d, entered) = diagnose_curve_pass(snap, temperature, opts, true)?;
    if !entered || d.names(EffectKind::Temperature) || d.names(EffectKind::Warmup) {
        return Ok(d);
    }
    let (again, _) = diagnose_curve_pass(snap, temperature, opts, false)?;
    let warm = again.names(EffectKind::Warmup);
    tracing::debug!(
        warm,
        "the temperature entered first and was not kept: the pass again without it"
    );
    Ok(if warm { again } else { d })
}

/// [`diagnose_curve_once`]'s pass; with `enter_first` the temperature may enter at step 0. Also
/// returns whether it did.
fn diagnose_curve_pass(
    snap: &EvidenceSnapshot,
    temperature: Option<&EvidenceSnapshot>,
    opts: &DiagnoseOptions,
    enter_first: bool,
) -> Result<(Diagnosis, bool), DiagnoseError> {
    let mut prob = GapProblem::new(snap, opts)?;
    if let Some(lsb) = snap.lsb {
        prob.set_filter_floor(lsb);
        prob = prob.with_sawtooth(snap, opts, true)?;
    }
    let prob = prob;
    let th = opts.thresholds;
    let j = prob.len();
    let base = prob
        .gls(&ModelSpec::default())
        .ok_or(DiagnoseError::Fit("base GLS".into()))?;
    let gap_before = base.gap();
    let regions = prob.regions(&base.model, th.band_z);

    let mut effects: Vec<AddedEffect> = Vec::new();
    let block_s = snap.block_len as f64 * snap.tau0_s;
    let t_run = snap.n_increments as f64 * snap.tau0_s;
    let stationary: Vec<EffectKind> = opts
        .candidates
        .iter()
        .copied()
        .filter(|k| !matches!(k, EffectKind::BiasJumps | EffectKind::Warmup))
        .collect();

    // 0. The temperature-driven bias, when the input has a temperature: its AVAR on the curve
    // is a fixed offset, and the time-domain tests see the block means without it.
    let mut offset = vec![0.0; j];
    let mut start = base.clone();
    let mut block_means = snap.block_means.clone();
    let mut temp_in = None;
    let entry = temperature.filter(|_| enter_first);
    if let Some(ts) = entry.filter(|_| opts.candidates.contains(&EffectKind::Temperature)) {
        if let Some((t, fit)) = enter_temperature(&prob, snap, ts, &base, TEMPERATURE_Z) {
            offset = t.curve_offset();
            block_means = t.remove_from(&snap.block_means);
            effects.push(AddedEffect {
                params: t.finding.params(),
                gap_after: fit.gap(),
                delta_chi2: base.chi2 - fit.chi2,
            });
            start = fit;
            temp_in = Some(t);
        }
    }

    // 1. Stationary effects on the curve, while the gap stays significant.
    // Flagged by `G`, or by the best candidate's likelihood ratio (add_stationary).
    let (mut spec, mut cur, first_scan) =
        add_stationary(&prob, &stationary, &offset, &mut effects, start, opts, true);

    // 2. A warm-up, in time: the block means against the model found so far.
    let mut warm_curve: Option<Vec<f64>> = None;
    // The exact AVAR on this record of each effect found in time, for the bookkeeping below.
    let mut time_offsets: Vec<(EffectKind, Vec<f64>)> = Vec::new();
    if let Some(t) = &temp_in {
        time_offsets.push((EffectKind::Temperature, t.curve_offset()));
    }
    // The curve's upper bound on K^2 for the model found so far, kept while that model stands
    // (the warm-up test and the jump search both take it).
    let mut k_up_kept: Option<f64> = None;
    let mut first_block: Option<FirstBlock> = None;
    if opts.candidates.contains(&EffectKind::Warmup) {
        let mut c5 = cur.five_terms();
        // The null's random walk: a K fitted low (often 0) leaves the block means' slow wander
        // out of the covariance, and the scan over T reads it as a warm-up (docs/gap.md, "The
        // warm-up's null level"). K^2 is profiled on the block means under both hypotheses,
        // up to the curve's upper bound (session 12); at that bound when the profile cannot be
        // formed (session 8's rule).
        let k_up = k2_upper(&prob, &spec, &cur);
        k_up_kept = Some(k_up);
        let stat_params: Vec<EffectParams> = effects.iter().map(|e| e.params).collect();
        let warm = fit_warmup_profiled(&block_means, block_s, t_run, &c5, k_up, &stat_params)
            .map(|(w, k_null)| {
                // at k_up when the block means want more wander than the curve allows
                tracing::debug!(k_null, "the warm-up profile's K^2 under the null");
                w
            })
            .or_else(|| {
                c5[3] = k_up;
                fit_warmup(&block_means, block_s, t_run, &c5, &stat_params)
            });
        if let Some(w) = &warm {
            tracing::debug!(
                p_value = w.p_value,
                log_bf = w.log_bf,
                null_scale = w.null_scale,
                amplitude = w.amplitude,
                time_constant_s = w.time_constant_s,
                k_up,
                ?c5,
                block_s,
                blocks = block_means.len(),
                "the warm-up test"
            );
        }
        // A warm-up at the scan's shortest time constant (half a block) has decayed within the
        // first block mean: that one mean is all it shows, its amplitude and time constant are
        // not told apart (only their product), and one block's excursion of the noise (a slow
        // Gauss-Markov wander) shows the same. Not named (docs/gap.md, "A warm-up at the scan's
        // edge (session 43)").
        // Its first block is reported when the test passes (super::first_block).
        let warm = warm.filter(|w| {
            let at_edge = w.time_constant_s <= WARMUP_EDGE_BLOCKS * block_s;
            if at_edge {
                tracing::debug!(
                    time_constant_s = w.time_constant_s,
                    block_s,
                    "a warm-up at the scan's shortest time constant is not named"
                );
                if th.warmup_found(w) {
                    let start_s = lead_samples(snap) as f64 * snap.tau0_s;
                    first_block = FirstBlock::from_edge_warmup(w, &block_means, block_s, start_s);
                }
            }
            !at_edge
        });
        if let Some(w) = warm.filter(|w| th.warmup_found(w)) {
            // Its AVAR, exact for the estimator on this record, enters as a fixed offset.
            let warm_offset = warmup_curve_offset(&prob, w.amplitude, w.time_constant_s);
            for (o, c) in offset.iter_mut().zip(&warm_offset) {
                *o += c;
            }
            time_offsets.push((EffectKind::Warmup, warm_offset));
            k_up_kept = None;
            // Keep only the stationary effects still needed beside it, then look again.
            let kept = still_needed(&prob, &effects, &offset, opts);
            let prev = cur.clone();
            let f = prob
                .gls(&spec_from(&prob, &kept, &offset))
                .unwrap_or_else(|| prev.clone());
            // In the order they were added (docs/records.md): the stationary effects kept, then
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
            if cur.gap() > th.gap_crit_given(has_filter(&effects)) {
                let (sp, c2, _) = add_stationary(
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
            // The temperature and the warm-up fitted jointly: the coefficient once more, with
            // the warm-up's block shape as a column beside it.
            if let Some(t) = temp_in.as_mut() {
                let shape = w.block_curve(snap.block_means.len(), block_s);
                let c5 = cur.five_terms();
                let entered_offset = t.curve_offset();
                t.refit(&snap.block_means, block_s, &c5, &stat_params, &[shape]);
                if t.finding.strongest_z() > TEMPERATURE_Z {
                    block_means = t.remove_from(&snap.block_means);
                    if let Some(e) = effects
                        .iter_mut()
                        .find(|e| e.params.kind() == EffectKind::Temperature)
                    {
                        e.params = t.finding.params();
                    }
                    if let Some(o) = time_offsets
                        .iter_mut()
                        .find(|(k, _)| *k == EffectKind::Temperature)
                    {
                        o.1 = t.curve_offset();
                    }
                } else {
                    // Fitted beside the warm-up the temperature no longer stands on its own
                    // (a review's run: |z| 2.2 beside a warm-up, named before): it leaves the
                    // model, its offset the curve, and the jump search sees the block means
                    // with only the warm-up out.
                    tracing::debug!(
                        z = t.finding.z,
                        "the temperature fitted beside the warm-up: dropped"
                    );
                    effects.retain(|e| e.params.kind() != EffectKind::Temperature);
                    time_offsets.retain(|(k, _)| *k != EffectKind::Temperature);
                    for (o, e) in offset.iter_mut().zip(&entered_offset) {
                        *o -= e;
                    }
                    block_means = snap.block_means.clone();
                    let without = spec_from(&prob, &effects, &offset);
                    if let Some(f) = prob.gls(&without) {
                        for e in effects.iter_mut() {
                            e.gap_after = f.gap();
                        }
                        spec = without;
                        cur = f;
                    }
                }
            }
        }
    }

    // 3. Bias jumps, in time (after the warm-up is taken out of the block means).
    let jump_search = |resid: &[f64], effects: &[AddedEffect], k_up: f64, c5: &[f64; 5]| {
        let stat_params: Vec<EffectParams> = effects
            .iter()
            .map(|e| e.params)
            .filter(|p| {
                matches!(
                    p.kind(),
                    EffectKind::GaussMarkov | EffectKind::Sinusoid | EffectKind::BandNoise
                )
            })
            .collect();
        detect_steps(
            resid,
            block_s,
            c5,
            &stat_params,
            &th.jump_z,
            k_up,
            th.jump_alpha,
        )
    };
    // The jumps' exact AVAR on this record (their merged steps), a fixed offset of the curve.
    let jump_offset = |f: &JumpFinding| -> Vec<f64> {
        let (mut positions, sizes) = f.merged_steps(prob.tau0_s);
        // The block tests' time 0 is the first block they kept (`EvidenceSnapshot::block_first`:
        // short blocks at the start are left out); the record's is its first sample.
        positions.iter_mut().for_each(|p| *p += lead_samples(snap));
        prob.ms
            .iter()
            .map(|&m| terms::steps_avar(&positions, &sizes, m, prob.n_inc))
            .collect()
    };
    // The jumps as the record's effect: their count and rms size (u/s).
    let jump_params = |f: &JumpFinding| EffectParams::BiasJumps {
        count: f.sizes.len() as u64,
        rms_size: (f.sizes.iter().map(|s| s * s).sum::<f64>() / f.sizes.len() as f64).sqrt(),
    };
    let mut jumps = if opts.candidates.contains(&EffectKind::BiasJumps) {
        let resid: Vec<f64> = match &warm_curve {
            Some(wc) => block_means.iter().zip(wc).map(|(b, w)| b - w).collect(),
            None => block_means.clone(),
        };
        // The null's random walk, as the warm-up's: K^2 is also read off the block means,
        // up to the curve's upper bound (steps.rs, `detect_steps`; docs/gap.md, "The jump
        // test's random walk (session 21)").
        let k_up = k_up_kept.unwrap_or_else(|| k2_upper(&prob, &spec, &cur));
        jump_search(&resid, &effects, k_up, &cur.five_terms())
    } else {
        None
    };
    if let Some(f) = jumps.as_ref().filter(|f| !f.sizes.is_empty()) {
        // In law the jumps are part of K (a rate random walk's), but a few large ones leave
        // their own shape on this record's curve, which a stationary candidate may have taken
        // (a slow sinusoid, typically). Their exact AVAR on the record enters as a fixed offset,
        // as a warm-up's does; the stationary effects must then pass the forward rules again.
        let j_offset = jump_offset(f);
        let offset_j: Vec<f64> = offset.iter().zip(&j_offset).map(|(o, j)| o + j).collect();
        time_offsets.push((EffectKind::BiasJumps, j_offset));
        let before = cur.chi2;
        keep_needed(&prob, &mut effects, &mut cur, &offset_j, opts);
        effects.push(AddedEffect {
            params: jump_params(f),
            gap_after: cur.gap(),
            delta_chi2: before - cur.chi2,
        });
    }
    // 3b. A warm-up the jumps hid: the warm-up's null takes its random walk from the block
    // means and the curve, and jumps not yet taken out raise both, so that a warm-up beside a
    // jump passed for wander (a review's accelerometer: a 200 s warm-up of 6.7e-5 g beside a
    // jump, found to 1% in amplitude and 12% in T at p 0.02, above the level of 0.01, with K^2
    // at the curve's bound). With the jumps out of the block means and their AVAR in the
    // curve's model, the warm-up is tested once more; when it is named, the jumps are searched
    // again with it out (docs/gap.md, "A warm-up beside jumps (session 55)"). Not beside a
    // temperature, which step 2 refits jointly with a warm-up.
    let hid = jumps.as_ref().filter(|f| {
        !f.sizes.is_empty()
            && warm_curve.is_none()
            && temp_in.is_none()
            && opts.candidates.contains(&EffectKind::Warmup)
    });
    if let Some(resid) = hid.map(|f| f.remove_from(&block_means)) {
        // the model `cur` was fitted to: the offsets so far and the jumps' (step 3)
        let jumps_offset = time_offsets
            .iter()
            .find(|(k, _)| *k == EffectKind::BiasJumps)
            .map(|(_, o)| o.clone())
            .unwrap_or_default();
        let with_jumps: Vec<f64> = offset
            .iter()
            .zip(&jumps_offset)
            .map(|(o, j)| o + j)
            .collect();
        let c5 = cur.five_terms();
        let k_up = k2_upper(&prob, &spec_from(&prob, &effects, &with_jumps), &cur);
        let stat_params: Vec<EffectParams> = effects
            .iter()
            .filter(|e| e.params.kind() != EffectKind::BiasJumps)
            .map(|e| e.params)
            .collect();
        let warm = fit_warmup_profiled(&resid, block_s, t_run, &c5, k_up, &stat_params)
            .map(|(w, _)| w)
            .filter(|w| w.time_constant_s > WARMUP_EDGE_BLOCKS * block_s);
        if let Some(w) = &warm {
            tracing::debug!(
                p_value = w.p_value,
                amplitude = w.amplitude,
                time_constant_s = w.time_constant_s,
                k_up,
                "the warm-up test with the jumps out"
            );
        }
        if let Some(w) = warm.filter(|w| th.warmup_found(w)) {
            let warm_offset = warmup_curve_offset(&prob, w.amplitude, w.time_constant_s);
            let wc = w.block_curve(snap.block_means.len(), block_s);
            // the jumps again, with the warm-up out of the block means
            let without_warm: Vec<f64> = block_means.iter().zip(&wc).map(|(b, w)| b - w).collect();
            let mut offset_w: Vec<f64> = offset
                .iter()
                .zip(&warm_offset)
                .map(|(o, w)| o + w)
                .collect();
            let warm_spec = spec_from(&prob, &effects, &offset_w);
            let again = prob.gls(&warm_spec).and_then(|fit| {
                let k_up = k2_upper(&prob, &warm_spec, &fit);
                jump_search(&without_warm, &effects, k_up, &fit.five_terms())
            });
            let found = again.as_ref().filter(|j| !j.sizes.is_empty());
            effects.retain(|e| e.params.kind() != EffectKind::BiasJumps);
            time_offsets.retain(|(k, _)| *k != EffectKind::BiasJumps);
            time_offsets.push((EffectKind::Warmup, warm_offset));
            let before = cur.chi2;
            if let Some(j) = found {
                let j_offset = jump_offset(j);
                for (o, x) in offset_w.iter_mut().zip(&j_offset) {
                    *o += x;
                }
                time_offsets.push((EffectKind::BiasJumps, j_offset));
            }
            keep_needed(&prob, &mut effects, &mut cur, &offset_w, opts);
            effects.push(AddedEffect {
                params: EffectParams::Warmup {
                    amplitude: w.amplitude,
                    time_constant_s: w.time_constant_s,
                },
                gap_after: cur.gap(),
                delta_chi2: before - cur.chi2,
            });
            if let Some(j) = found {
                effects.push(AddedEffect {
                    params: jump_params(j),
                    gap_after: cur.gap(),
                    delta_chi2: 0.0,
                });
            }
            jumps = again;
        }
    }
    // 4. The bookkeeping: the effects found, in order, each kept only if it lowers the gap of
    // the model with the effects kept before it; its `gap_after` is that model's gap.
    let Settled {
        effects,
        fit: cur,
        spec: final_spec,
        in_curve,
    } = settle(&prob, &effects, &time_offsets, &base);
    if !effects
        .iter()
        .any(|e| e.params.kind() == EffectKind::BiasJumps)
    {
        if let Some(f) = jumps.as_mut() {
            *f = JumpFinding {
                block_s: f.block_s,
                ..JumpFinding::default()
            };
        }
    }
    let gap_after = cur.gap();
    // Flagged: by `G` on the base model, or by an effect that was kept (the likelihood-ratio
    // candidates and the time-domain tests flag only through the effect they bring).
    // Outliers found in the stream are an effect of their own (docs/gap.md, "Outliers"): a
    // curve that needs nothing else is then `explained` by them, not `consistent`. Not when
    // they are the far end of the white noise's own heavy tail (session 49): that is the
    // noise's law, which the curve's terms already hold, not something added to the unit.
    let verdict = if effects.is_empty() {
        if gap_before > th.gap_crit {
            Verdict::Unexplained
        } else if snap.outliers.count > 0 && !snap.outliers.heavy_tail() {
            Verdict::Explained
        } else {
            Verdict::Consistent
        }
    } else if gap_after <= th.gap_crit_given(has_filter(&effects)) {
        Verdict::Explained
    } else {
        Verdict::Unexplained
    };
    let first_scores = first_scan
        .as_ref()
        .map(|fs| fs.scores.clone())
        .unwrap_or_default();
    let mut alternatives = first_scan
        .map(|fs| alternatives(&prob, opts, &fs, &effects, &final_spec, &cur))
        .unwrap_or_default();
    let mut temperature_check = None;
    if let Some(ts) = temperature.filter(|_| opts.candidates.contains(&EffectKind::Temperature)) {
        let named = temp_in.as_ref().filter(|_| {
            effects
                .iter()
                .any(|e| e.params.kind() == EffectKind::Temperature)
        });
        let k2_hi = temp_in.as_ref().map_or_else(
            || k2_upper(&prob, &ModelSpec::default(), &base),
            |t| t.k2_hi,
        );
        alternatives.extend(temperature_alternatives(
            &prob,
            snap,
            ts,
            named,
            &effects,
            &in_curve,
            &cur,
            k2_hi,
            th.gap_crit_given(has_filter(&effects)).max(gap_after),
        ));
        alternatives.sort_by(|a, b| a.delta_chi2.total_cmp(&b.delta_chi2));
        temperature_check = super::temperature_check::check_temperature(
            &prob,
            snap,
            ts,
            &effects,
            &cur,
            named,
            jumps.as_ref(),
            k2_hi,
        );
    }
    let super::intervals::FitIntervals {
        effects: effect_intervals,
        terms: final_terms,
    } = super::intervals::fit_intervals(&prob, &final_spec, &cur, &effects);
    let regions_after = prob.regions(&cur.model, th.band_z);
    let residual_shape = (verdict == Verdict::Unexplained).then(|| describe(&regions_after));
    let entered = temp_in.is_some();
    let d = Diagnosis {
        gap_before,
        gap_after,
        verdict,
        regions,
        regions_after,
        effects,
        base_coef: coef5(&base.coef),
        final_coef: coef5(&cur.coef),
        final_terms,
        cov_coef: coef5(&prob.c_cov),
        tau_span_s: (prob.tau[0], prob.tau[j - 1]),
        n_taus: j,
        t_data_s: snap.n_increments as f64 * snap.tau0_s,
        segment_tests: segment_tests(snap, &prob.c_init),
        // The block tests' time 0 is their first kept block; the record's is its first sample.
        jumps: jumps.map(|mut f| {
            let lead_s = lead_samples(snap) as f64 * snap.tau0_s;
            f.times_s.iter_mut().for_each(|t| *t += lead_s);
            f
        }),
        residual_shape,
        model_tau_s: prob.tau[..j].to_vec(),
        model_base_avar: base.model.clone(),
        model_final_avar: cur.model.clone(),
        quantization_limited: dead_band_limit(&prob, snap, &final_spec, &cur),
        outliers: snap.outliers,
        stuck: snap.stuck.span(snap.tau0_s),
        first_block,
        quantization: snap
            .lsb
            .and_then(|l| judge_quantization(&prob, &final_spec, &cur, l)),
        alternatives,
        temperature_check,
        effect_intervals,
        first_scores,
        limit_cycles: Vec::new(),
        filter_shape: None,
        sawtooth: prob.sawtooth.as_ref().map(|(st, _)| *st),
    };
    Ok((d, entered))
}

/// A channel whose rate samples are rounded after its filter with the filtered noise below
/// [`super::quant_limit::R_WHITE`] steps is quantization-limited too: its shortest taus, up to
/// ten memories of the filter, carry the rounding model's known error in their covariance
/// ([`super::discrepancy`]), and the record says so (the tau where the discrepancy's full size
/// ends as `tau_white`). Its `ratio`, the filtered rate sample's noise over the step, is that of
/// the final fit (its `N` through the filter it names, or through the covariance's filter when
/// it names none): the covariance's own `N`, fitted beyond ten memories of the filter where the
/// rounding's correlated error still lowers the curve, put it 9-13% low on the dead-band
/// unit accf29 of `tests/gap/rounding.rs` (docs/gap.md, "The grid model wired (session 15)", "The
/// record's ratio").
fn dead_band_limit(
    prob: &GapProblem,
    snap: &EvidenceSnapshot,
    final_spec: &ModelSpec,
    fit: &GlsFit,
) -> Option<QuantizationLimit> {
    let d = prob.discrepancy?;
    let lsb = snap.lsb?;
    let ratio = match (final_spec.filter.or(prob.cov_filter), fit.coef.get(1)) {
        (Some(lp), Some(&n2)) if n2 > 0.0 => {
            super::rounding::filtered_sigma(&lp, snap.tau0_s, n2) * snap.tau0_s / lsb
        }
        _ => d.sigma_steps,
    };
    (d.sigma_steps < super::quant_limit::R_WHITE).then(|| QuantizationLimit {
        lsb,
        ratio,
        tau_white_s: d.tau_full_s,
        m_white: (d.tau_full_s / snap.tau0_s).ceil().max(1.0) as u64,
    })
}

/// The honest bookkeeping of the effects found: in their order, each is added to the model
/// of the effects kept before it (a stationary effect as a free column of its shape, a warm-up
/// or jumps as their exact AVAR on the record, `time_offsets`) and kept only if that model's
/// gap is below the previous one; its `gap_after` and `delta_chi2` are against the previous
/// model. So the final gap is never above the base model's (`base`), which it returns when
/// nothing is kept.
fn settle(
    prob: &GapProblem,
    effects: &[AddedEffect],
    time_offsets: &[(EffectKind, Vec<f64>)],
    base: &GlsFit,
) -> Settled {
    let mut kept: Vec<AddedEffect> = Vec::new();
    let mut in_curve: Vec<(EffectKind, Vec<f64>)> = Vec::new();
    let mut offset = vec![0.0; prob.len()];
    let mut cur = base.clone();
    let mut spec = ModelSpec::default();
    for e in effects {
        let mut trial_offset = offset.clone();
        let time_offset = time_offsets.iter().find(|(k, _)| *k == e.params.kind());
        if let Some((_, o)) = time_offset {
            for (t, v) in trial_offset.iter_mut().zip(o) {
                *t += v;
            }
        }
        let mut trial = kept.clone();
        trial.push(*e);
        let trial_spec = spec_from(prob, &trial, &trial_offset);
        let fit = prob.gls(&trial_spec);
        match fit {
            Some(fit) if fit.gap().is_finite() && fit.gap() < cur.gap() => {
                spec = trial_spec;
                kept.push(AddedEffect {
                    params: e.params,
                    gap_after: fit.gap(),
                    delta_chi2: cur.chi2 - fit.chi2,
                });
                offset = trial_offset;
                cur = fit;
                in_curve.extend(time_offset.cloned());
            }
            // Found in time, by its own calibrated test on the block means: kept on that
            // evidence even where the curve does not show it (a short warm-up or a few jumps
            // that the five terms absorb), with its curve offset left out, so the model and
            // the gap stay those before it (docs/gap.md, "Bookkeeping").
            _ if kept_in_time(&e.params) => kept.push(AddedEffect {
                params: e.params,
                gap_after: cur.gap(),
                delta_chi2: 0.0,
            }),
            _ => {}
        }
    }
    Settled {
        effects: kept,
        fit: cur,
        spec,
        in_curve,
    }
}

/// The effects kept by [`settle`], the final model's fit and spec, and the time-domain effects
/// whose exact curve offsets are in that model (those kept in time with the curve not showing
/// them are not).
struct Settled {
    effects: Vec<AddedEffect>,
    fit: GlsFit,
    spec: ModelSpec,
    in_curve: Vec<(EffectKind, Vec<f64>)>,
}

/// The effects found in time by a test of their own that the bookkeeping keeps on that
/// evidence when the curve does not show them: the warm-up (its `B`'s p-value under the run's
/// own null) and, since session 18, bias jumps (the rule `jump_z` on the first pass of the step
/// search, which fires on 0.7% of clean runs). Session 6 left the jumps out (the shipped MA4
/// model then `consistent` in 94 of 100 two-hour runs, with the warm-up test of that day); on
/// session 18's benchmark keeping them took the jump draws from 17 to 30 of 120 against the
/// fair jump ceiling's 35 (docs/gap.md, "Bookkeeping", "Jumps kept in time (session 18)").
/// Since session 35 the temperature too, when its time-domain evidence alone is strong:
/// `|z| >= TEMPERATURE_Z_ALONE` (twice the threshold that names it). A blind check's 34-minute
/// gyro with a temperature cycle had `|z|` 14.8 and the coefficient within 2%, and was dropped
/// because its curve's gap (0.63) was already under 1 and did not fall. A slow signal of the
/// bias that the model lacks and that resembles the temperature (an unrelated sinusoid near the
/// chamber's cycle, a jump beside a temperature step) raised `|z|` to 4.1-5.2 in a review's
/// runs with no coefficient, where the curve's gap kept it out; at twice the threshold none.
fn kept_in_time(params: &EffectParams) -> bool {
    match *params {
        EffectParams::Warmup { .. } | EffectParams::BiasJumps { .. } => true,
        EffectParams::Temperature {
            coefficient,
            lo,
            hi,
            quadratic,
            ..
        } => {
            // Each interval is its term +- Z95 se (temperature.rs).
            let strong = |v: f64, lo: f64, hi: f64| {
                let se = (hi - lo) / (2.0 * super::temperature::Z95);
                se > 0.0 && (v / se).abs() >= TEMPERATURE_Z_ALONE
            };
            strong(coefficient, lo, hi)
                || quadratic.is_some_and(|q| strong(q.coefficient, q.lo, q.hi))
        }
        _ => false,
    }
}

/// A warm-up's AVAR (u^2/s^2) at each of the curve's cluster sizes, exact for the estimator on
/// this record (`A^2` times its column, [`effect_column`]): the fixed offset it enters the curve
/// fit as.
pub(crate) fn warmup_curve_offset(
    prob: &GapProblem,
    amplitude: f64,
    time_constant_s: f64,
) -> Vec<f64> {
    effect_column(
        EffectKind::Warmup,
        time_constant_s,
        &prob.ms,
        prob.tau0_s,
        prob.n_inc,
    )
    .iter()
    .map(|c| amplitude * amplitude * c)
    .collect()
}

/// The curve's upper profile bound on `K^2` (u^2/s^3) at `WARMUP_K_DELTA` for the model `spec`
/// fitted as `fit`, never below the fit's own `K^2`; the fit's `K^2` when the bound cannot be
/// formed. The null's random walk of the time-domain tests goes up to it.
pub(crate) fn k2_upper(prob: &GapProblem, spec: &ModelSpec, fit: &GlsFit) -> f64 {
    let k2 = fit.coef.get(3).copied().unwrap_or(0.0);
    prob.upper_bound(spec, fit, 3, WARMUP_K_DELTA)
        .map_or(k2, |k| k.max(k2))
}

/// Whether `effects` hold a low-pass filter (the model's `G` is then judged against
/// [`Thresholds::gap_crit_filtered`](super::thresholds::Thresholds::gap_crit_filtered)).
fn has_filter(effects: &[AddedEffect]) -> bool {
    effects.iter().any(|e| e.params.kind().is_filter())
}

/// A warm-up whose time constant is at most this many blocks (the profiled scan's shortest is
/// half a block) is not named ([`diagnose`]'s warm-up step).
const WARMUP_EDGE_BLOCKS: f64 = 0.5 * (1.0 + 1e-9);

/// Samples before the block tests' first kept block (`EvidenceSnapshot::block_first`: short
/// blocks at the start are left out): their time 0 is this far into the record.
fn lead_samples(snap: &EvidenceSnapshot) -> u64 {
    snap.block_first as u64 * snap.block_len
}

/// `effects` cut to those [`still_needed`] beside `offset`, and `cur` the fit of that model, each
/// effect's `gap_after` its gap (both left as they were when that model cannot be fitted).
fn keep_needed(
    prob: &GapProblem,
    effects: &mut Vec<AddedEffect>,
    cur: &mut GlsFit,
    offset: &[f64],
    opts: &DiagnoseOptions,
) {
    let kept = still_needed(prob, effects, offset, opts);
    if let Some(fit) = prob.gls(&spec_from(prob, &kept, offset)) {
        *effects = kept;
        for e in effects.iter_mut() {
            e.gap_after = fit.gap();
        }
        *cur = fit;
    }
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
            let flagged = b.gap() > th.gap_crit_given(has_filter(&others));
            let crit = if flagged {
                th.add_chi2
            } else {
                th.lr_crit_of(e.params.kind())
            };
            let score = (b.chi2 - a.chi2) / e.params.kind().n_params() as f64;
            let stat = if flagged {
                score
            } else {
                th.lr_stat(score, a.gap())
            };
            if stat >= crit {
                kept.push(*e);
            }
        }
    }
    kept
}

/// The model spec of the stationary effects in `effects` (warm-ups and jumps are in `offset`
/// or nowhere), their shapes fixed and amplitudes free.
pub(crate) fn spec_from(prob: &GapProblem, effects: &[AddedEffect], offset: &[f64]) -> ModelSpec {
    let mut spec = ModelSpec {
        offset: Some(offset.to_vec()),
        ..ModelSpec::default()
    };
    for e in effects {
        let kind = e.params.kind();
        if kind.is_stationary() {
            spec = prob.spec_with_params(&spec, &e.params);
        }
    }
    spec
}

/// Adds stationary effects one at a time (the best drop of `r' S^-1 r` per parameter, if it
/// exceeds the threshold) while the gap stays above its critical value.
///
/// When that greedy search ends with the model still flagged by `G`, the other first steps
/// are tried too ([`other_first_steps`]): the effect that fits best alone is not always the
/// first of the pair that fits best (a resonant second-order filter takes a line and the
/// unit's own roll-off in one candidate, and the two-effect limit then never reaches the
/// filter and the line; docs/gap.md, "Pairs: the first step is not always the pair's").
fn add_stationary(
    prob: &GapProblem,
    kinds: &[EffectKind],
    offset: &[f64],
    effects: &mut Vec<AddedEffect>,
    start: GlsFit,
    opts: &DiagnoseOptions,
    lr_first: bool,
) -> (ModelSpec, GlsFit, Option<FirstScan>) {
    let before = effects.clone();
    let (spec, cur, first, passed_first) = greedy_stationary(
        prob,
        kinds,
        offset,
        effects,
        start.clone(),
        opts,
        lr_first,
        None,
    );
    if cur.gap() <= opts.thresholds.gap_crit_given(has_filter(effects)) || opts.max_effects < 2 {
        return (spec, cur, first);
    }
    match other_first_steps(
        prob,
        kinds,
        offset,
        &before,
        effects,
        &start,
        &cur,
        opts,
        &passed_first,
    ) {
        Some((alt_effects, alt_spec, alt_cur, chosen)) => {
            *effects = alt_effects;
            let first = first.map(|f| FirstScan {
                chosen: Some(chosen),
                ..f
            });
            (alt_spec, alt_cur, first)
        }
        None => (spec, cur, first),
    }
}

/// Akaike's criterion of a model of the curve: its `r' S^-1 r` plus two per parameter that
/// its stationary effects add to the five terms (the terms themselves are common to all).
fn akaike(fit: &GlsFit, effects: &[AddedEffect]) -> f64 {
    let k: usize = effects
        .iter()
        .filter(|e| e.params.kind().is_stationary())
        .map(|e| e.params.kind().n_params())
        .sum();
    fit.chi2 + 2.0 * k as f64
}

/// The greedy search of [`add_stationary`] started from each other candidate that passed its
/// threshold at the first step (`passed_first`), each then continued by the same rules and
/// polished; the one whose final model has the lowest Akaike criterion ([`akaike`]) when that is
/// below the greedy search's (`greedy`, `greedy_fit`, polished the same way), with the kind it
/// started from; else the polished greedy model when its polish lowered `r' S^-1 r`. Only the
/// stationary effects of this search count (`before` holds those found earlier).
#[allow(clippy::too_many_arguments)]
fn other_first_steps(
    prob: &GapProblem,
    kinds: &[EffectKind],
    offset: &[f64],
    before: &[AddedEffect],
    greedy: &[AddedEffect],
    start: &GlsFit,
    greedy_fit: &GlsFit,
    opts: &DiagnoseOptions,
    passed_first: &[Passed],
) -> Option<(Vec<AddedEffect>, ModelSpec, GlsFit, EffectKind)> {
    let greedy_first = greedy.get(before.len()).map(|e| e.params.kind());
    // The greedy search's own model is polished and ordered as each other start's is before
    // the two are compared (session 49): unpolished, it kept a line's frequency from before the
    // filter beside it was in, and a start whose polish moved its line to the true frequency
    // won by Akaike's criterion with a Gauss-Markov term of the filter's time constant in the
    // filter's place (a tenth blind review's MEMS gyro behind a first order of 20 ms: the
    // greedy search had named the line and the filter; the start from another candidate
    // ended with the line and that term, `unexplained`).
    let mut polished = greedy.to_vec();
    let polished_fit = polish(
        prob,
        offset,
        before.len(),
        &mut polished,
        greedy_fit.clone(),
    );
    bookkeeping_order(prob, offset, before.len(), &mut polished);
    let mut best_aic = akaike(&polished_fit, &polished[before.len()..]);
    let mut best = greedy_first
        .filter(|_| polished_fit.chi2 < greedy_fit.chi2)
        .map(|k| {
            let spec = spec_from(prob, &polished, offset);
            (polished, spec, polished_fit, k)
        });
    let starts: Vec<&Passed> = passed_first
        .iter()
        .filter(|p| Some(p.0.kind()) != greedy_first)
        .collect();
    // Each start's search on its own, side by side (their candidates then on one thread
    // each), then compared in the starts' order.
    let inner = DiagnoseOptions {
        threads: if starts.len() > 1 { 1 } else { opts.threads },
        ..opts.clone()
    };
    let searched = map_on_threads(&starts, opts.threads, |p| {
        let mut effs = before.to_vec();
        let (_, cur, _, _) = greedy_stationary(
            prob,
            kinds,
            offset,
            &mut effs,
            start.clone(),
            &inner,
            true,
            Some((*p).clone()),
        );
        let cur = polish(prob, offset, before.len(), &mut effs, cur);
        bookkeeping_order(prob, offset, before.len(), &mut effs);
        (effs, cur)
    });
    for (p, (effs, cur)) in starts.into_iter().zip(searched) {
        let a = akaike(&cur, &effs[before.len()..]);
        if a < best_aic {
            best_aic = a;
            let spec = spec_from(prob, &effs, offset);
            best = Some((effs, spec, cur, p.0.kind()));
        }
    }
    best
}

/// Orders the effects of one search (`effects[from..]`) as the bookkeeping ([`settle`]) takes
/// them: first the one that lowers the gap most on its own (beside `effects[..from]` and
/// `offset`), then the next with it, and so on. The greedy search finds them in that order; a
/// search started from another candidate ([`other_first_steps`]) need not: its forced first
/// step may lower `r' S^-1 r` by less than the shape parameters it adds to the gap's
/// expectation (a Gauss-Markov term at the short end of its scan in front of a band, on the
/// real ADIS16405 gyro z), and the bookkeeping, which keeps an effect only if it lowers the gap
/// of the effects kept before it, would then drop it although the pair lowers the gap far
/// below either alone (docs/gap.md, "Real recording (session 12)"). The set and its joint fit
/// do not change; only the order.
fn bookkeeping_order(prob: &GapProblem, offset: &[f64], from: usize, effects: &mut [AddedEffect]) {
    for pos in from..effects.len() {
        let gap_with = |i: usize| {
            let mut trial: Vec<AddedEffect> = effects[..pos].to_vec();
            trial.push(effects[i]);
            prob.gls(&spec_from(prob, &trial, offset))
                .map_or(f64::INFINITY, |f| f.gap())
        };
        let best = (pos..effects.len())
            .map(|i| (i, gap_with(i)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i);
        if let Some(i) = best {
            effects[pos..=i].rotate_right(1);
        }
    }
}

/// The effects of this search (`effects[from..]`, `fit` their model's fit) fitted jointly: each
/// stationary one's shape scanned again with the others in (one pass, kept where it lowers
/// `r' S^-1 r`), then every amplitude taken from the joint fit. A search that took a line
/// first fixed its frequency and amplitude before the filter beside it was in.
fn polish(
    prob: &GapProblem,
    offset: &[f64],
    from: usize,
    effects: &mut [AddedEffect],
    fit: GlsFit,
) -> GlsFit {
    let mut fit = fit;
    for i in from..effects.len() {
        let kind = effects[i].params.kind();
        if !kind.is_stationary() {
            continue;
        }
        let others = all_but(effects, i);
        let Some((p, _)) = prob.scan_params(&spec_from(prob, &others, offset), kind) else {
            continue;
        };
        let mut trial = effects.to_vec();
        trial[i].params = p;
        if let Some(f) = prob.gls(&spec_from(prob, &trial, offset)) {
            if f.chi2 < fit.chi2 {
                effects.copy_from_slice(&trial);
                fit = f;
            }
        }
    }
    // Amplitudes from the joint fit: the extra columns follow the five terms in the order of
    // the stationary effects that are not filters.
    let mut col = 5;
    for (i, e) in effects.iter_mut().enumerate() {
        let k = e.params.kind();
        if k.is_stationary() && !k.is_filter() {
            if i >= from {
                let amp = fit.coef.get(col).copied().unwrap_or(0.0).max(0.0).sqrt();
                e.params = EffectParams::from_shape(k, e.params.shape(), amp);
            }
            col += 1;
        }
    }
    fit
}

/// `effects` without the one at `i`.
fn all_but(effects: &[AddedEffect], i: usize) -> Vec<AddedEffect> {
    effects
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != i)
        .map(|(_, e)| *e)
        .collect()
}

/// A candidate that passed its threshold at a step: its parameters, its fit, its score.
type Passed = (EffectParams, GlsFit, f64);

/// Adds the effect `params` (fitted as `f`) to the search's model: recorded with the gap after
/// it and its drop of `r' S^-1 r` from `cur`, then taken into `spec` and `cur`.
fn take_step(
    prob: &GapProblem,
    effects: &mut Vec<AddedEffect>,
    spec: &mut ModelSpec,
    cur: &mut GlsFit,
    params: EffectParams,
    f: GlsFit,
) {
    effects.push(AddedEffect {
        params,
        gap_after: f.gap(),
        delta_chi2: cur.chi2 - f.chi2,
    });
    *spec = prob.spec_with_params(spec, &params);
    *cur = f;
}

/// One greedy search of [`add_stationary`]; `forced_first` (a candidate that passed at the
/// first step, with its fit) is taken as the first step in place of the scan's choice. Also
/// returns the candidates that passed at the first step, each with its fit and score.
#[allow(clippy::too_many_arguments)]
fn greedy_stationary(
    prob: &GapProblem,
    kinds: &[EffectKind],
    offset: &[f64],
    effects: &mut Vec<AddedEffect>,
    start: GlsFit,
    opts: &DiagnoseOptions,
    lr_first: bool,
    forced_first: Option<Passed>,
) -> (ModelSpec, GlsFit, Option<FirstScan>, Vec<Passed>) {
    let th = opts.thresholds;
    let mut spec = spec_from(prob, effects, offset);
    let mut cur = start;
    let mut added = 0;
    let mut first: Option<FirstScan> = None;
    let mut passed_first: Vec<Passed> = Vec::new();
    if let Some((params, f, _)) = forced_first {
        take_step(prob, effects, &mut spec, &mut cur, params, f);
        added += 1;
    }
    // The first effect of the search may be added on its own likelihood ratio; so may the
    // first after a low-pass, which is the unit's own shaping rather than something beside it:
    // a MEMS part's filter always comes first, and a Gauss-Markov term beside it that the
    // filter's pass left below the flag was never weighed (a review's accelerometer behind a
    // third-order Butterworth: its 3 s term named on the first pass at G 2.56, lost on the
    // second at 1.92; docs/gap.md, "An effect beside the unit's filter (session 55)").
    let lr_open = |effects: &[AddedEffect], added: usize| {
        lr_first
            && effects[effects.len() - added..]
                .iter()
                .all(|e| e.params.kind().is_filter())
    };
    while added < opts.max_effects
        && (cur.gap() > th.gap_crit_given(has_filter(effects)) || lr_open(effects, added))
    {
        // Below gap_crit only a candidate's own likelihood-ratio threshold can add (the
        // first effect, or the first after the unit's filter: `lr_open`); among those that
        // pass, the largest drop per parameter wins. Beside a
        // filter the model's G is judged against `gap_crit_filtered`.
        let flagged_g = cur.gap() > th.gap_crit_given(has_filter(effects));
        let mut best: Option<(EffectParams, GlsFit, f64)> = None;
        let mut scores: Vec<CandidateScore> = Vec::new();
        let mut passed: Vec<(EffectParams, GlsFit, f64)> = Vec::new();
        // The filters' likelihood ratios are taken against the model with white phase noise
        // of either sign (`beyond_tail_reference`), computed once per step.
        let mut tail_ref: Option<f64> = None;
        // The named filter refitted behind or in front of each cascade's other part scanned
        // (its index among the effects, its parameters; [`complete_cascade`]).
        let mut cascade_named: Vec<(EffectKind, (usize, EffectParams))> = Vec::new();
        // One output filter at most (it takes the N column), or a moving average and a first or
        // second order behind it (a cascade: docs/gap.md, "A low-pass behind a decimator
        // (session 46)").
        let open: Vec<EffectKind> = kinds
            .iter()
            .copied()
            .filter(|&kind| {
                !effects.iter().any(|e| {
                    let named = e.params.kind();
                    let cascade = kind.cascades_with(named) && short_front(&e.params);
                    named == kind || (kind.is_filter() && named.is_filter() && !cascade)
                })
            })
            .collect();
        // Each candidate's scan on its own, side by side (the second order's first: it is the
        // longest), then judged in the kinds' order.
        let mut order: Vec<usize> = (0..open.len()).collect();
        order.sort_by_key(|&i| open[i] != EffectKind::SecondOrderFilter);
        let effects_now: &[AddedEffect] = effects;
        let (spec_now, chi2_now) = (&spec, cur.chi2);
        let mut scans = map_on_threads(&order, opts.threads, |&i| {
            let kind = open[i];
            match complete_cascade(prob, offset, effects_now, kind, chi2_now) {
                Some((params, f, named)) => Some((params, f, Some(named))),
                None => prob
                    .scan_params(spec_now, kind)
                    .map(|(params, f)| (params, f, None)),
            }
        })
        .into_iter()
        .zip(&order)
        .map(|(s, &i)| (i, s))
        .collect::<Vec<_>>();
        scans.sort_by_key(|(i, _)| *i);
        for (kind, (_, scanned)) in open.iter().copied().zip(scans) {
            let scanned = scanned.map(|(params, f, named)| {
                if let Some(named) = named {
                    cascade_named.push((kind, named));
                }
                (params, f)
            });
            if let Some((params, f)) = scanned {
                tracing::trace!(?params, chi2 = f.chi2, gap = f.gap(), "candidate");
                let score = (cur.chi2 - f.chi2) / kind.n_params() as f64;
                let crit = if flagged_g {
                    th.add_chi2
                } else {
                    th.lr_crit_of(kind)
                };
                // A filter flags the model on its own only by what it shows beyond its tail
                // (docs/gap.md, "A filter's tail is white phase noise").
                let score_tail = if kind.is_filter() && !flagged_g && th.filter_tail {
                    let r =
                        *tail_ref.get_or_insert_with(|| beyond_tail_reference(prob, &spec, &cur));
                    (r - f.chi2) / kind.n_params() as f64
                } else {
                    score
                };
                if added == 0 {
                    scores.push(CandidateScore {
                        kind,
                        params,
                        score,
                        crit,
                        gap_alt: f.gap(),
                        score_tail,
                    });
                }
                let stat = if flagged_g {
                    score
                } else {
                    th.lr_stat(score_tail, f.gap())
                };
                if stat >= crit {
                    passed.push((params, f, score));
                }
            }
        }
        // The filters compete among themselves by the drop less two per parameter (Akaike):
        // per parameter, a one-parameter filter would beat the second order whatever the
        // drop. The best of them then competes with the other kinds at the filters' best drop
        // per parameter: the filters are one family of explanations (a first-order filter is
        // also the second order's limit), and a Gauss-Markov term, which mimics a filtered
        // white rate with N near 0, must not win because the family's Akaike choice has two
        // parameters.
        let aic = |p: &(EffectParams, GlsFit, f64)| {
            (cur.chi2 - p.1.chi2) - 2.0 * p.0.kind().n_params() as f64
        };
        let mut best_filter = passed
            .iter()
            .filter(|p| p.0.kind().is_filter())
            .max_by(|a, b| aic(a).total_cmp(&aic(b)))
            .map(|p| p.0.kind());
        // The first order is the reference low-pass: another kind is named over it only when
        // its Akaike criterion is better by more than AIC_MARGIN. The second order nests it
        // (its limit at large damping; docs/gap.md, "Rounding after a filter (session 11)");
        // a moving average or a zero-phase filter of the same memory differs from it only in
        // the shape of the shortest taus, which white phase noise can hide (MA4's Q up to
        // tens of seconds): within the margin the curve does not tell them apart, and the
        // other kind is listed as an alternative (docs/gap.md, "The first order when the
        // kinds tie (session 26)").
        // The scans' floor keeps a first order of sub-sample memory from being the reason a
        // filter is named ("The scans' shortest shapes"). Once another kind is named, the
        // first order competes for the kind over its whole grid: a second order at its top
        // frequency with real poles is the first order below the floor in another form (a
        // first order run at the internal rate and read every few samples is a first order at
        // the output rate; docs/gap.md, "A first order below the floor (session 44)").
        if let Some(k) = best_filter.filter(|&k| k != EffectKind::OutputFilter) {
            let floor = prob.shape_floor(EffectKind::OutputFilter);
            let lo = prob.grid(EffectKind::OutputFilter).lo;
            // (strictly inside the grid: a time constant at its short end is not located, a
            // chance deficit of the first tau on a clean short run)
            if let Some((t, f)) = prob
                .scan_from(&spec, EffectKind::OutputFilter, lo)
                .filter(|(t, _)| *t < floor && *t > lo * (1.0 + super::filter_scan::END_TOL))
            {
                let fo = (
                    EffectParams::OutputFilter { time_constant_s: t },
                    f.clone(),
                    (cur.chi2 - f.chi2) / EffectKind::OutputFilter.n_params() as f64,
                );
                let other = passed.iter().find(|p| p.0.kind() == k);
                if other.is_some_and(|b| aic(b) <= aic(&fo) + AIC_MARGIN) {
                    tracing::debug!(?k, time_constant_s = t, "a first order below the floor");
                    passed.retain(|p| p.0.kind() != EffectKind::OutputFilter);
                    passed.push(fo);
                    best_filter = Some(EffectKind::OutputFilter);
                }
            }
        }
        let passed_kind = |k: EffectKind| passed.iter().find(|p| p.0.kind() == k);
        // A Butterworth and a FIR whose Akaike criteria are within AIC_MARGIN are the same
        // low-pass as far as the curve tells: a 47-tap windowed sinc cut at 131 Hz at 1 kHz and
        // an eighth-order Butterworth at 122 Hz differ by 0.03 in `r' S^-1 r` over 20 minutes,
        // and a fifth order at 12 Hz at 100 Hz and a 29-tap FIR by less than 4 (the seventeenth
        // review's Butterworths of orders 3 to 6 were better than the best FIR by 16 to 590).
        // The Butterworth is then named, its order being the smaller choice, unless it is at
        // the highest order scanned: there the curve asks for a steeper roll-off than the kind
        // reaches, and the FIR is named (docs/gap.md, "An n-th order Butterworth (session 54)").
        if let (Some(bw), Some(fir)) = (
            passed_kind(EffectKind::ButterworthFilter),
            passed_kind(EffectKind::FirFilter),
        ) {
            let top = matches!(
                bw.0,
                EffectParams::ButterworthFilter { order, .. }
                    if order >= *super::filter_scan::BUTTERWORTH_ORDERS.end()
            );
            let tied = (aic(bw) - aic(fir)).abs() <= AIC_MARGIN;
            match best_filter {
                Some(EffectKind::ButterworthFilter) if top && tied => {
                    best_filter = Some(EffectKind::FirFilter)
                }
                Some(EffectKind::FirFilter) if !top && tied => {
                    best_filter = Some(EffectKind::ButterworthFilter)
                }
                _ => {}
            }
        }
        // A moving average is named over a FIR unless the FIR is better by more than
        // AIC_MARGIN: a Bartlett window of ten output samples and a 31-tap windowed sinc cut at
        // a sixth of Nyquist differ at the shortest taus by less than the curve resolves, and
        // the average is the part's own simpler filter (family_gap's cntfog, seed 471: the
        // Bartlett named a FIR, Akaike's criterion 0.4 apart; docs/gap.md, "A FIR read every
        // so many samples (session 47)").
        if let (Some(EffectKind::FirFilter), Some(fir), Some(ma)) = (
            best_filter,
            passed_kind(EffectKind::FirFilter),
            passed_kind(EffectKind::MovingAverage),
        ) {
            if aic(fir) <= aic(ma) + AIC_MARGIN {
                best_filter = Some(EffectKind::MovingAverage);
            }
        }
        if let (Some(k), Some(fo)) = (best_filter, passed_kind(EffectKind::OutputFilter)) {
            if k != EffectKind::OutputFilter
                && passed_kind(k).is_some_and(|b| aic(b) <= aic(fo) + AIC_MARGIN)
            {
                best_filter = Some(EffectKind::OutputFilter);
            }
        }
        // A FIR is the one filter that no partner completes: where it is the best filter alone
        // and a cascade from the best first or second order fits better by Akaike's criterion,
        // the low-pass is named, and the next step completes it (a CIC + Butterworth was named a
        // FIR with a sinusoid beside it: docs/gap.md, "A linear-phase FIR low-pass (session
        // 46)").
        if best_filter == Some(EffectKind::FirFilter) && !has_filter(effects) {
            if let Some(fir) = passed_kind(EffectKind::FirFilter) {
                let fir_aic = aic(fir);
                let lowpass = [
                    EffectKind::SecondOrderFilter,
                    EffectKind::OutputFilter,
                    EffectKind::ButterworthFilter,
                ]
                .into_iter()
                .filter_map(passed_kind)
                .filter(|p| {
                    let mut with = effects.clone();
                    with.push(AddedEffect {
                        params: p.0,
                        gap_after: p.1.gap(),
                        delta_chi2: cur.chi2 - p.1.chi2,
                    });
                    let pair =
                        complete_cascade(prob, offset, &with, EffectKind::MovingAverage, p.1.chi2);
                    let n = (p.0.kind().n_params() + EffectKind::MovingAverage.n_params()) as f64;
                    pair.is_some_and(|(_, f, _)| {
                        (cur.chi2 - f.chi2) - 2.0 * n > fir_aic + AIC_MARGIN
                    })
                })
                .map(|p| p.0.kind())
                .next();
                if lowpass.is_some() {
                    tracing::debug!(?lowpass, "a cascade before a FIR");
                    best_filter = lowpass;
                }
            }
        }
        let filter_score = passed
            .iter()
            .filter(|p| p.0.kind().is_filter())
            .map(|p| p.2)
            .fold(f64::NEG_INFINITY, f64::max);
        let passed_all = passed.clone();
        if added == 0 {
            passed_first = passed_all.clone();
        }
        for mut p in passed {
            let k = p.0.kind();
            if k.is_filter() {
                if Some(k) != best_filter {
                    continue;
                }
                p.2 = filter_score;
            }
            if best.as_ref().is_none_or(|b| p.2 > b.2) {
                best = Some(p);
            }
        }
        // Across kinds the drop per parameter chooses. But a filter fitted at the long-memory
        // end of its scan is not located (`at_memory_end`): a Gauss-Markov hump with a
        // correlation time beyond the filters' range drops more per parameter through a
        // one-parameter filter, and the model it leaves fits far worse. Such a choice is then
        // replaced by a candidate that passed and fits better by more than AIC_MARGIN in
        // Akaike's terms (drop less two per parameter; docs/gap.md, "Filters and
        // Gauss-Markov terms").
        if let Some(b) = best
            .as_ref()
            .filter(|b| super::filter_scan::at_memory_end(prob, &b.0))
        {
            let b_aic = aic(b);
            if let Some(a) = passed_all
                .iter()
                .filter(|p| aic(p) > b_aic + AIC_MARGIN)
                .max_by(|x, y| aic(x).total_cmp(&aic(y)))
            {
                best = Some(a.clone());
            }
        }
        // A band nests a line, a hump and a resonance: weighed against them by its whole fit
        // (docs/gap.md, "Narrow-band noise (session 11)").
        best = super::band_noise::prefer_band(best, &passed_all);
        if added == 0 {
            first = Some(FirstScan {
                flagged_g,
                scores: std::mem::take(&mut scores),
                chosen: best.as_ref().map(|b| b.0.kind()),
            });
        }
        let Some((params, f, _)) = best else {
            break;
        };
        // a cascade's other part: the named filter takes the parameters it was refitted to
        if let Some(&(_, (i, named))) = cascade_named.iter().find(|c| c.0 == params.kind()) {
            effects[i].params = named;
            spec = spec_from(prob, effects, offset);
        }
        take_step(prob, effects, &mut spec, &mut cur, params, f);
        added += 1;
    }
    // A cascade's other part when the gap no longer flags the model: by its own likelihood
    // ratio, as a first effect is (a sinc^3 decimator in front of a Butterworth named alone,
    // the pair at G 1.55 and the Butterworth alone, refitted as an overdamped second order at
    // the top of its scan, at 1.85).
    if added < opts.max_effects && cur.gap() <= th.gap_crit_given(has_filter(effects)) {
        let mut best: Option<(EffectParams, GlsFit, (usize, EffectParams), f64)> = None;
        for &kind in kinds.iter().filter(|k| k.is_filter()) {
            if effects.iter().any(|e| e.params.kind() == kind) {
                continue;
            }
            let Some((params, f, named)) = complete_cascade(prob, offset, effects, kind, cur.chi2)
            else {
                continue;
            };
            let score = (cur.chi2 - f.chi2) / kind.n_params() as f64;
            let passes = th.lr_stat(score, f.gap()) >= th.lr_crit_of(kind);
            tracing::debug!(
                ?params,
                score,
                passes,
                "a cascade's other part below the flag"
            );
            if passes && best.as_ref().is_none_or(|b| score > b.3) {
                best = Some((params, f, named, score));
            }
        }
        if let Some((params, f, (i, named), _)) = best {
            effects[i].params = named;
            spec = spec_from(prob, effects, offset);
            take_step(prob, effects, &mut spec, &mut cur, params, f);
        }
    }
    (spec, cur, first, passed_first)
}

/// Whether `p` can be a cascade's front ([`complete_cascade`]): a moving average of more than
/// one tap (one is no filter) spanning at most [`CASCADE_FRONT_SPAN`] output samples (taps
/// times stages over the decimation), as a CIC decimator of up to four stages does; true for
/// the other kinds.
fn short_front(p: &EffectParams) -> bool {
    match *p {
        EffectParams::MovingAverage {
            taps,
            stages,
            decimation,
        } => {
            taps > 1
                && f64::from(taps) * f64::from(stages) <= CASCADE_FRONT_SPAN * f64::from(decimation)
        }
        _ => true,
    }
}

/// The longest front of a cascade, in output samples ([`short_front`]).
const CASCADE_FRONT_SPAN: f64 = 4.0;

/// Rounds of [`complete_cascade`]'s alternate refits.
const CASCADE_ROUNDS: usize = 2;

/// The drop of `r' S^-1 r` below the current model's from which [`complete_cascade`]'s start
/// is refitted in turns (one parameter's price by AIC).
const CASCADE_PRESCREEN: f64 = 2.0;

/// The decimators (stages, decimation; taps = decimation) [`complete_cascade`] starts from in
/// front of a named first or second order: sinc^2 to sinc^4 CICs by 8 (at the output rate a CIC
/// spans as many samples as it has stages, its shape near the longest's from a decimation of 8;
/// the alternation's scan of every average then sets the decimation).
const CASCADE_FRONTS: [(u32, u32); 3] = [(2, 8), (3, 8), (4, 8)];

/// The other part of a cascade whose one part is named (a moving average in front of a named
/// first or second order, or one of those behind a named moving average:
/// [`crate::model::lowpass::LowPass::Cascade`];
/// docs/gap.md, "A low-pass behind a decimator (session 46)"): `kind` scanned with the named
/// filter in, then the named filter scanned again with it in, and so on for
/// [`CASCADE_ROUNDS`]. The named filter was fitted alone, so it took the other part's share of
/// the roll-off (a sinc^3 decimator and a Butterworth behind it were named one second order
/// of damping 1.5): scanned with it fixed, the other part barely lowers the fit, and a
/// sinusoid near Nyquist took its place. Returns the part's parameters, the joint fit, and
/// the named filter's index among `effects` with its new parameters. None when `kind` does not
/// complete a cascade with a named filter.
fn complete_cascade(
    prob: &GapProblem,
    offset: &[f64],
    effects: &[AddedEffect],
    kind: EffectKind,
    cur_chi2: f64,
) -> Option<(EffectParams, GlsFit, (usize, EffectParams))> {
    let i = effects
        .iter()
        .position(|e| e.params.kind().is_filter() && kind.cascades_with(e.params.kind()))?;
    let named_kind = effects[i].params.kind();
    // A long average is no decimator's front (an ADIS16405's Bartlett spans 23 output samples):
    // its cascades cost tens of seconds and find a low-pass nothing in front of it asked for
    if !short_front(&effects[i].params) {
        return None;
    }
    // The named filter refitted: a moving average or a first order as such; a second order
    // behind the front as a first or second order, the first unless the second's Akaike
    // criterion is better by AIC_MARGIN (the reference low-pass, as in `greedy_stationary`; an
    // overdamped second order at the end of its damping scan is a first order by another
    // name). A first order stays one: as a second order it turned into a resonance that took
    // the line beside it, with a one-tap average in front (tests/gap/line_behind_filter.rs).
    let refit_named = |spec: &ModelSpec| -> Option<(EffectParams, GlsFit)> {
        // (a Butterworth in its order, its cut-off about the named one)
        if named_kind == EffectKind::ButterworthFilter {
            return super::filter_scan::scan_in_form(prob, spec, &effects[i].params);
        }
        if named_kind != EffectKind::SecondOrderFilter {
            return prob.scan_params(spec, named_kind);
        }
        let fo = prob.scan_params(spec, EffectKind::OutputFilter);
        let so = prob.scan_params(spec, EffectKind::SecondOrderFilter);
        let extra =
            (EffectKind::SecondOrderFilter.n_params() - EffectKind::OutputFilter.n_params()) as f64;
        match (fo, so) {
            (Some(fo), Some(so)) if so.1.chi2 + 2.0 * extra + AIC_MARGIN < fo.1.chi2 => Some(so),
            (Some(fo), _) => Some(fo),
            (None, so) => so,
        }
    };
    let mut trial = effects.to_vec();
    let base = spec_from(prob, &all_but(effects, i), offset);
    // A front in front of a named back: the back fitted alone is overdamped or at its top
    // frequency, and the front scanned behind that back is a short average of the output
    // samples (a boxcar of two for a sinc^3 decimator by 8), which the alternation does not
    // leave. Each decimator of CASCADE_FRONTS is tried, the back scanned behind it in its form;
    // the alternation then scans every average. A back behind a named front: scanned.
    let (mut part, mut fit) = if kind == EffectKind::MovingAverage {
        let mut best: Option<(EffectParams, GlsFit, EffectParams)> = None;
        for (stages, decimation) in CASCADE_FRONTS {
            let front = EffectParams::MovingAverage {
                taps: decimation,
                stages,
                decimation,
            };
            let with_front = prob.spec_with_params(&base, &front);
            let scanned = super::filter_scan::scan_in_form(prob, &with_front, &effects[i].params);
            if let Some((named, f)) = scanned {
                if best.as_ref().is_none_or(|b| f.chi2 < b.1.chi2) {
                    best = Some((front, f, named));
                }
            }
        }
        let (front, f, named) = best?;
        trial[i].params = named;
        (front, f)
    } else {
        prob.scan_params(&spec_from(prob, &trial, offset), kind)?
    };
    // The alternation only when the start lowers the fit at all (it costs a few scans of
    // each part, and it lowers the fit further only where the start already did).
    let rounds = if fit.chi2 < cur_chi2 - CASCADE_PRESCREEN {
        CASCADE_ROUNDS
    } else {
        0
    };
    for _ in 0..rounds {
        let with_part = prob.spec_with_params(&base, &part);
        let Some((named, f)) = refit_named(&with_part) else {
            break;
        };
        if f.chi2 >= fit.chi2 {
            break;
        }
        trial[i].params = named;
        fit = f;
        match prob.scan_params(&spec_from(prob, &trial, offset), kind) {
            Some((p, f)) if f.chi2 < fit.chi2 && short_front(&p) => {
                part = p;
                fit = f;
            }
            _ => break,
        }
    }
    tracing::trace!(?part, named = ?trial[i].params, chi2 = fit.chi2, "a cascade completed");
    Some((part, fit, (i, trial[i].params)))
}

/// The `r' S^-1 r` against which a filter's likelihood ratio is taken when the model is not
/// flagged by `G`: the lower of the current model's (`cur`, of `spec`) and that of the same
/// model with white phase noise of either sign (the Q column free below zero as well).
///
/// Far beyond its memory `T`, any low-pass filter of the white rate leaves `N^2 / tau` less a
/// term in `1 / tau^2` (a first order's filtered phase is the phase less `T` times the filtered
/// rate, which is stationary: white phase noise, negatively correlated with the rate's), i.e.
/// white phase noise of negative size. A filter whose memory is short against the curve's
/// first taus shows nothing else; and where the unit has no white phase noise (a MEMS part
/// that rounds rate samples), the base fit holds `Q = 0` at its bound, so on clean runs a
/// chance deficit of the shortest taus is taken by the filter in half the runs: its
/// likelihood ratio then has the law of about two degrees of freedom, not the one its
/// threshold was set for (docs/gap.md, "A filter's tail is white phase noise").
fn beyond_tail_reference(prob: &GapProblem, spec: &ModelSpec, cur: &GlsFit) -> f64 {
    let mut s = spec.clone();
    s.extra
        .push(prob.tau.iter().map(|&t| -terms::basis(t)[0]).collect());
    prob.gls(&s)
        .map(|f| f.chi2)
        .filter(|c| c.is_finite())
        .map_or(cur.chi2, |c| c.min(cur.chi2))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::lowpass::LowPass;

    /// [`map_on_threads`] gives `f` of each item in the items' order whatever the thread
    /// count (more threads than items included), the slow items taken first or last.
    #[test]
    fn map_on_threads_keeps_the_items_order() {
        let items: Vec<u64> = (0..23).collect();
        let f = |&x: &u64| {
            if x % 5 == 0 {
                std::thread::sleep(std::time::Duration::from_millis(3));
            }
            x * x + 1
        };
        let want: Vec<u64> = items.iter().map(f).collect();
        for threads in [0, 1, 2, 3, 8, 40] {
            assert_eq!(
                map_on_threads(&items, threads, f),
                want,
                "{threads} threads"
            );
        }
        assert!(map_on_threads(&Vec::<u64>::new(), 4, f).is_empty());
    }

    fn score(params: EffectParams, gap_alt: f64) -> CandidateScore {
        CandidateScore {
            kind: params.kind(),
            params,
            score: 0.0,
            crit: 0.0,
            gap_alt,
            score_tail: 0.0,
        }
    }

    fn added(params: EffectParams) -> AddedEffect {
        AddedEffect {
            params,
            gap_after: 2.5,
            delta_chi2: 10.0,
        }
    }

    /// accfilt s107 draw 26's first scan (family_gap's `galt_*`): the first order 3.38, the
    /// Gauss-Markov term 3.44, the second order 3.34; the pass named the Gauss-Markov term and
    /// a sinusoid. The tied filter is the best filter by its gap, the second order here.
    #[test]
    fn a_gauss_markov_term_named_in_a_filters_place_gives_the_tied_filter() {
        let gm = EffectParams::GaussMarkov {
            sigma: 5.8e-3,
            tau_c_s: 0.0794,
        };
        let first = EffectParams::OutputFilter {
            time_constant_s: 0.0798,
        };
        let second = EffectParams::SecondOrderFilter {
            natural_frequency_hz: 2.0,
            damping: 1.0,
            bilinear: false,
            zero: None,
        };
        let sin = EffectParams::Sinusoid {
            amplitude: 6e-4,
            frequency_hz: 1.34,
        };
        let scores = [score(gm, 3.44), score(first, 3.38), score(second, 3.34)];
        let named = [added(gm), added(sin)];
        assert_eq!(tied_filter(&named, &scores), second.lowpass());
        // with the first order the only filter on the scan, the first order is the tied one
        let scores1 = [score(gm, 3.44), score(first, 3.38)];
        assert_eq!(
            tied_filter(&named, &scores1),
            Some(LowPass::FirstOrder {
                time_constant_s: 0.0798
            })
        );
        // a filter more than 5% worse than the best candidate is not tied
        let far = [score(gm, 3.0), score(first, 3.2)];
        assert_eq!(tied_filter(&named, &far), None);
        // within 5%: 3.12 against 3.0
        let near = [score(gm, 3.0), score(first, 3.12)];
        assert!(tied_filter(&named, &near).is_some());
        // a filter named already, or no Gauss-Markov term named: nothing to try
        assert_eq!(tied_filter(&[added(first)], &scores), None);
        assert_eq!(tied_filter(&[added(sin)], &scores), None);
    }
}
