//! Ambiguity said out loud: when another explanation fits about as well as the one chosen,
//! the diagnosis lists it with its gap instead of choosing silently (docs/gap.md,
//! "Alternatives").
//!
//! The decisions of the stationary search are thresholds on the drop of `r' S^-1 r` per added
//! parameter (a candidate's `score`; [`super::thresholds`]). "About as well" is read on that same
//! scale: within [`ALT_MARGIN`] per parameter of the decision. At the first stationary step:
//! - a candidate `Y` that passed its own threshold and whose Akaike drop (its drop of
//!   `r' S^-1 r` less two per parameter) is within [`AIC_MARGIN`] of the chosen `X`'s: the
//!   final model with `Y` in place of `X` (its shape from the scan). For kinds with the same
//!   number of parameters this is the margin [`ALT_MARGIN`] on their drops per parameter
//!   (two-parameter kinds; one-parameter kinds get twice it);
//! - a chosen `X` added on its likelihood ratio alone (the five terms alone were not flagged by
//!   `G`) whose score is within the margin of its threshold: the final model without `X`, in
//!   which the five terms absorb what `X` took (a Gauss-Markov hump becomes a raised flicker
//!   floor, typically: the alternative's `coef` shows it);
//! - nothing chosen, the five terms not flagged, and a candidate `Y` within the margin below its
//!   threshold: the final model with `Y` added.
//!
//! Each alternative is refitted (generalised least squares, the same covariance) and given with
//! its effects, its gap `G`, its `delta_chi2` against the chosen model (positive: it fits worse
//! by that much) and its five terms.

use super::diagnose::{spec_from, AddedEffect, DiagnoseOptions};
use super::effects::{EffectKind, EffectParams};
use super::problem::{GapProblem, GlsFit, ModelSpec};

/// Margin on the score (drop of `r' S^-1 r` per parameter) within which two decisions are
/// "about equal". A score is a likelihood-ratio statistic per parameter, so 2 is a likelihood
/// ratio of `e` per parameter: weak evidence either way (Kass and Raftery 1995, J. Am. Stat.
/// Assoc. 90, 773: Bayes factors below about 3 are "not worth more than a bare mention").
pub const ALT_MARGIN: f64 = 2.0;

/// Margin on Akaike's drop (the drop of `r' S^-1 r` less two per parameter) between candidates
/// with different numbers of parameters: beyond 4 the model behind has "considerably less
/// support" (Burnham and Anderson, "Model Selection and Multimodel Inference", 2002, section
/// 2.6: a likelihood ratio above `e^2`). Twice [`ALT_MARGIN`], which is the same margin on the
/// drop per parameter of a two-parameter kind. A candidate beyond it replaces the choice made
/// per parameter ([`super::diagnose`](mod@super::diagnose)); within it, it is listed.
pub const AIC_MARGIN: f64 = 2.0 * ALT_MARGIN;

/// One candidate of a scan step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CandidateScore {
    pub kind: EffectKind,
    /// Its parameters at the best shape.
    pub params: EffectParams,
    /// Drop of `r' S^-1 r` per parameter against the model before the step.
    pub score: f64,
    /// The threshold it had to pass at that step.
    pub crit: f64,
    /// The gap `G` of the model with the candidate in (its residual scale: about 1 when the
    /// covariance is right).
    pub gap_alt: f64,
    /// For a filter judged by its own threshold (the model not flagged by `G`): its drop per
    /// parameter against the model with white phase noise of either sign, the statistic its
    /// threshold judged (`diagnose`'s `beyond_tail_reference`); `score` otherwise.
    pub score_tail: f64,
}

/// The first step of the stationary search.
#[derive(Debug, Clone, PartialEq)]
pub struct FirstScan {
    /// The model before the step was flagged by `G`.
    pub flagged_g: bool,
    pub scores: Vec<CandidateScore>,
    pub chosen: Option<EffectKind>,
}

/// Another explanation of about equal fit (its record: [`super::record::AlternativeRecord`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Alternative {
    /// The effects of that model (kinds and parameters; empty: the five terms alone).
    pub effects: Vec<EffectParams>,
    pub gap: f64,
    /// Its `r' S^-1 r` less the chosen model's.
    pub delta_chi2: f64,
    /// Its five terms `(Q, N, B, K, R)`.
    pub coef: [f64; 5],
}

/// The effect `p` with the amplitude of column `col` of `fit` (filters have none).
fn params_at(p: &EffectParams, fit: &GlsFit, col: usize) -> EffectParams {
    let amp = fit.coef.get(col).copied().unwrap_or(0.0).max(0.0).sqrt();
    p.with_amplitude(amp)
}

/// The model of `effects` (the final offset of the time-domain effects kept) refitted.
fn refit(
    prob: &GapProblem,
    effects: &[AddedEffect],
    offset: &[f64],
    chosen: &GlsFit,
) -> Option<Alternative> {
    let spec = spec_from(prob, effects, offset);
    let fit = prob.gls(&spec)?;
    // Amplitudes as refitted: the stationary extra columns in order, after the five terms.
    let mut col = 5;
    let params = effects
        .iter()
        .map(|e| {
            let k = e.params.kind();
            if k.is_stationary() && !k.is_filter() {
                let p = params_at(&e.params, &fit, col);
                col += 1;
                p
            } else {
                e.params
            }
        })
        .collect();
    Some(Alternative {
        effects: params,
        gap: fit.gap(),
        delta_chi2: fit.chi2 - chosen.chi2,
        coef: std::array::from_fn(|i| fit.coef.get(i).copied().unwrap_or(0.0).max(0.0).sqrt()),
    })
}

fn placeholder(params: EffectParams) -> AddedEffect {
    AddedEffect {
        params,
        gap_after: f64::NAN,
        delta_chi2: f64::NAN,
    }
}

/// The alternatives to the final model (`effects`, `spec`, `fit`) from the first stationary
/// step's scores (see the module doc).
pub fn alternatives(
    prob: &GapProblem,
    _opts: &DiagnoseOptions,
    first: &FirstScan,
    effects: &[AddedEffect],
    spec: &ModelSpec,
    fit: &GlsFit,
) -> Vec<Alternative> {
    let offset = spec.offset.clone().unwrap_or_else(|| vec![0.0; prob.len()]);
    let mut out = Vec::new();
    match first.chosen {
        Some(x) => {
            // Only while the chosen effect is still in the final model.
            let Some(pos) = effects.iter().position(|e| e.params.kind() == x) else {
                return out;
            };
            let Some(sx) = first.scores.iter().find(|c| c.kind == x) else {
                return out;
            };
            // Akaike's drop of a candidate: its drop less two per parameter.
            let aic = |c: &CandidateScore| {
                let k = c.kind.n_params() as f64;
                (c.score - 2.0) * k
            };
            for y in first.scores.iter().filter(|c| c.kind != x) {
                if y.score_tail >= y.crit && aic(y) >= aic(sx) - AIC_MARGIN {
                    let mut alt = effects.to_vec();
                    alt[pos] = placeholder(y.params);
                    out.extend(refit(prob, &alt, &offset, fit));
                }
            }
            if !first.flagged_g && sx.score_tail < sx.crit + ALT_MARGIN {
                let mut alt = effects.to_vec();
                alt.remove(pos);
                out.extend(refit(prob, &alt, &offset, fit));
            }
        }
        None if !first.flagged_g => {
            for y in &first.scores {
                if y.score_tail >= y.crit - ALT_MARGIN && y.score_tail < y.crit {
                    let mut alt = effects.to_vec();
                    alt.push(placeholder(y.params));
                    out.extend(refit(prob, &alt, &offset, fit));
                }
            }
        }
        None => {}
    }
    out.sort_by(|a, b| a.delta_chi2.total_cmp(&b.delta_chi2));
    out
}
