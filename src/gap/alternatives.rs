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
//!
//! A temperature and a warm-up are found in time, on the block means, and are compared there
//! ([`temperature_alternatives`]): a temperature that only settles has a warm-up's shape.

use super::diagnose::{coef5, spec_from, warmup_curve_offset, AddedEffect, DiagnoseOptions};
use super::effects::{EffectKind, EffectParams};
use super::evidence::EvidenceSnapshot;
use super::problem::{GapProblem, GlsFit, ModelSpec};
use super::temperature::{fit_shape, TemperatureInModel, TEMPERATURE_Z, Z95};
use super::warmup::warmup_block_curve;

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
        coef: coef5(&fit.coef),
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

/// The alternatives of a temperature that the block means cannot tell from a warm-up, or that
/// its own evidence names but the diagnosis did not keep (docs/gap.md, "Alternatives"). The
/// temperature and the warm-up are judged in time, on the block means, not on the curve, so
/// these are read there too; each is then refitted on the curve like the others (its gap, its
/// `delta_chi2` against the chosen model, its five terms):
/// - the temperature named, no warm-up: when a warm-up could take its place
///   ([`TemperatureInModel::warmup_lookalike`]: beside the warm-up of the temperature's own
///   settling time constant the temperature's `|z|` is at most [`TEMPERATURE_Z`], the rule
///   that drops a temperature beside a warm-up the diagnosis found), the final model with a
///   warm-up in place of the temperature: of the one at the settling's time constant and the
///   one that fits the block means best (its time constant scanned), each carrying what the
///   temperature did (its own `|z|` above the temperature's beside it), the one the curve fits
///   better. A chamber that only settles gives the bias a warm-up's shape (session 36: a bias
///   warm-up of 2200 s beside a temperature settling over 1500 s, no coefficient, named as a
///   temperature at `|z|` 6.1-7.9);
/// - a warm-up named, no temperature: when the temperature fitted alone (the warm-up out)
///   explains the block means about as well as the warm-up with the same noise (Akaike's drop,
///   `z^2` less two per parameter, within [`AIC_MARGIN`] of the warm-up's, its time constant
///   counted) and is beyond the 95% level itself (`|z| > 1.96`), the final model with that
///   temperature in place of the warm-up. A warm-up of about the settling's time constant is
///   what the warm-up test finds where the temperature's own `|z|` stayed below
///   [`TEMPERATURE_Z`] (a MEMS gyro settling 25 degC, session 37);
/// - neither named: when the temperature fitted alone has `|z|` above [`TEMPERATURE_Z`] (the
///   curve did not show it and its time-domain evidence is below
///   [`TEMPERATURE_Z_ALONE`](super::temperature::TEMPERATURE_Z_ALONE)), the final model with
///   the temperature added.
///
/// Each is listed only where the curve does not reject it and fits it about as well: its gap
/// at most `gap_bar` (the critical gap, or the chosen model's when that is above it) and its
/// `delta_chi2` at most [`AIC_MARGIN`] (the same number of free amplitudes on the curve: the
/// time-domain effects enter it as fixed offsets). A temperature whose block means say `|z|`
/// 4.3 but whose `c^2 AVAR_T` at that coefficient lifts the curve's gap from 0.65 to 4.4 (a 25
/// Hz gyro settling 8 degC in 34 minutes, seed 6 of tests/cli/diagnose.rs's unit) is not
/// "about as good", nor one that lifts a consistent run's gap from 0.995 to 1.39
/// (`delta_chi2` 6.7: a review's slow bias sinusoid, no coefficient).
///
/// `named` is the temperature the diagnosis kept, `in_curve` the exact curve offsets of the
/// time-domain effects whose offsets are in the final model `fit`, `k2_hi` the top of the block
/// means' random walk ([`TemperatureInModel::k2_hi`]).
#[allow(clippy::too_many_arguments)]
pub fn temperature_alternatives(
    prob: &GapProblem,
    snap: &EvidenceSnapshot,
    temp: &EvidenceSnapshot,
    named: Option<&TemperatureInModel>,
    effects: &[AddedEffect],
    in_curve: &[(EffectKind, Vec<f64>)],
    fit: &GlsFit,
    k2_hi: f64,
    gap_bar: f64,
) -> Vec<Alternative> {
    let has = |k: EffectKind| effects.iter().any(|e| e.params.kind() == k);
    let c5 = fit.five_terms();
    let params: Vec<EffectParams> = effects.iter().map(|e| e.params).collect();
    let block_s = snap.block_len as f64 * snap.tau0_s;
    // The final model's offset without `out`'s, with `add` in.
    let offset_with = |out: Option<EffectKind>, add: &[f64]| -> Vec<f64> {
        let mut o = add.to_vec();
        for (_, v) in in_curve.iter().filter(|(k, _)| Some(*k) != out) {
            for (a, b) in o.iter_mut().zip(v) {
                *a += b;
            }
        }
        o
    };
    // The temperature fitted alone with the final model's noise (the warm-up out).
    let alone = || {
        let t = TemperatureInModel::fitted(prob, snap, temp, &c5, &params, k2_hi);
        tracing::debug!(finding = ?t.as_ref().map(|t| t.finding), "the temperature alone");
        t
    };
    // The temperature in place of the warm-up found: when, with the same noise, it explains the
    // block means about as well (Akaike's drop, `z^2` less two per parameter, within
    // [`AIC_MARGIN`] of the warm-up's, whose time constant was scanned: `z_T^2 >= z_W^2 - 6`)
    // and is itself beyond the 95% level.
    let about_as_well = |t: TemperatureInModel| -> Option<TemperatureInModel> {
        let (amp, tc) = effects.iter().find_map(|e| match e.params {
            EffectParams::Warmup {
                amplitude,
                time_constant_s,
            } => Some((amplitude, time_constant_s)),
            _ => None,
        })?;
        let shape = warmup_block_curve(snap.block_means.len(), block_s, tc);
        let w = fit_shape(&snap.block_means, &shape, block_s, &c5, &params, k2_hi)?;
        tracing::debug!(
            amp,
            z_w = w.z,
            z_t = t.finding.z,
            "the temperature against the warm-up"
        );
        let (zt2, zw2) = (t.finding.z.powi(2), w.z.powi(2));
        (t.finding.z.abs() > Z95 && zt2 - 2.0 >= zw2 - 4.0 - AIC_MARGIN).then_some(t)
    };
    // The models to refit: the effects and the curve's offset of each.
    let mut trials: Vec<(Vec<AddedEffect>, Vec<f64>)> = Vec::new();
    match (has(EffectKind::Temperature), has(EffectKind::Warmup)) {
        (true, false) => {
            let Some(t) = named else {
                return Vec::new();
            };
            let w = t.warmup_lookalike(&snap.block_means, block_s, &c5, &params);
            tracing::debug!(?w, "the warm-ups in the temperature's place");
            let Some(w) = w.filter(|w| w.z_temperature_beside.abs() <= TEMPERATURE_Z) else {
                return Vec::new();
            };
            for wi in w
                .warmups
                .iter()
                .filter(|wi| wi.z.abs() > w.z_temperature_beside.abs())
            {
                let mut alt = effects.to_vec();
                for e in alt.iter_mut() {
                    if e.params.kind() == EffectKind::Temperature {
                        e.params = EffectParams::Warmup {
                            amplitude: wi.amplitude,
                            time_constant_s: wi.time_constant_s,
                        };
                    }
                }
                let warm = warmup_curve_offset(prob, wi.amplitude, wi.time_constant_s);
                trials.push((alt, offset_with(Some(EffectKind::Temperature), &warm)));
            }
        }
        (false, true) => {
            let Some(t) = alone().and_then(about_as_well) else {
                return Vec::new();
            };
            let mut alt = effects.to_vec();
            for e in alt.iter_mut() {
                if e.params.kind() == EffectKind::Warmup {
                    e.params = t.finding.params();
                }
            }
            trials.push((
                alt,
                offset_with(Some(EffectKind::Warmup), &t.curve_offset()),
            ));
        }
        (false, false) => {
            let Some(t) = alone().filter(|t| t.finding.z.abs() > TEMPERATURE_Z) else {
                return Vec::new();
            };
            let mut alt = effects.to_vec();
            alt.push(placeholder(t.finding.params()));
            trials.push((alt, offset_with(None, &t.curve_offset())));
        }
        (true, true) => {}
    };
    // The one the curve fits best, where it does not reject it.
    trials
        .iter()
        .filter_map(|(alt, out)| refit(prob, alt, out, fit))
        .filter(|a| a.gap <= gap_bar && a.delta_chi2 <= AIC_MARGIN)
        .min_by(|a, b| a.delta_chi2.total_cmp(&b.delta_chi2))
        .into_iter()
        .collect()
}
