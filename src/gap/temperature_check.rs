//! What a diagnosis says of the unit's temperature, named or not (the record's
//! `temperature_check`; docs/gap.md, "The temperature's check"). When the input has a
//! temperature and no temperature effect is named, the diagnosis used to say nothing of it: a
//! test engineer could not tell a unit insensitive to temperature from a run that could not show
//! it. The check gives the coefficient the block means allow with its 95% interval (an upper
//! bound on the sensitivity a datasheet can quote) and why it was not named:
//!
//! - `not_shown`: `|z|` at most [`TEMPERATURE_Z`]; the interval bounds the coefficient;
//! - `straight`: the temperature changed nearly as a straight line in time (its block means
//!   depart from their line by less than [`STRAIGHT_BEND`] of their change, rms): the bias it
//!   drives is then a rate ramp, which the drift of the test (and `R` on the curve) takes as
//!   well, so no run of this kind can show the coefficient (THEORY.md section 3; docs/gap.md,
//!   "Temperature");
//! - `not_kept`: the block means show it (`|z|` above the bar) but the curve's gap does not fall
//!   with it in, or a warm-up took its place; the record's `alternatives` then say which;
//! - `constant`: the temperature did not change; `too_short`: too few usable blocks.
//!
//! The coefficient is fitted as the diagnosis fits it ([`TemperatureInModel::fitted`]: GLS of the
//! block-mean differences on a drift and the temperature's differences, the noise of the final
//! model with the random walk the block means show), jointly with the named warm-up's block
//! shape and each named bias jump's step, when there are such (a jump left in the block means
//! pulled the coefficient 2.3 standard errors off on a run without one).

use super::diagnose::AddedEffect;
use super::effects::{EffectKind, EffectParams};
use super::evidence::EvidenceSnapshot;
use super::problem::{GapProblem, GlsFit};
use super::steps::JumpFinding;
use super::temperature::{
    fit_shape, temperature_avar, temperature_blocks, TemperatureFinding, TemperatureInModel,
    TEMPERATURE_Z,
};
use super::warmup::{best_warmup_time_constant, warmup_block_curve, warmup_block_means};

/// Below this rms departure from a straight line, as a share of its change (max - min of the
/// block means), the temperature is read as a straight line: a settling whose time constant is
/// 30 times the run bends by 0.12% (`e^{-x}` on `[0, r]` departs from its line by about
/// `0.037 r` of its change for small `r`), twice the run by 1.9%, the run's length by 3.7%.
pub const STRAIGHT_BEND: f64 = 0.02;

/// A change of the temperature's block means below this (degC) is none: the resolution of a
/// chamber's own sensor, and far below any change that could show a coefficient.
pub const CONSTANT_C: f64 = 0.01;

/// Why the check came out as it did ([module doc](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TemperatureOutcome {
    /// A temperature effect is named (its interval is the effect's).
    Named,
    /// `|z|` at most the bar: the interval bounds the coefficient.
    NotShown,
    /// The temperature changed as a straight line: a rate ramp takes its bias as well.
    Straight,
    /// Shown in the block means but not kept by the curve.
    NotKept,
    /// The temperature did not change.
    Constant,
    /// Too few usable blocks to judge.
    TooShort,
}

/// The temperature's check (the record's `temperature_check`; fields in the order the record
/// writes its keys, sorted).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TemperatureCheck {
    /// The rms departure of the temperature's block means from their straight line in time, as
    /// a share of `change_c` (`null` when it did not change).
    pub bend: Option<f64>,
    /// The temperature's change over the run: the largest block mean less the smallest, degC.
    pub change_c: f64,
    /// The coefficient, u/s per degC (`null` when it cannot be judged).
    pub coefficient: Option<f64>,
    /// Its 95% interval, u/s per degC.
    pub interval: Option<[f64; 2]>,
    pub outcome: TemperatureOutcome,
    /// `coefficient / se`.
    pub z: Option<f64>,
}

/// The check of the temperature `temp` beside the channel `snap`, once the diagnosis is settled:
/// `effects` and `fit` the final model, `named` the temperature effect in it (with its last
/// finding), `jumps` the bias jumps found (their steps fitted beside the temperature when the
/// model keeps them), `k2_hi` the curve's upper bound on `K^2`. `None` when the temperature has
/// no block means at all.
#[allow(clippy::too_many_arguments)]
pub fn check_temperature(
    prob: &GapProblem,
    snap: &EvidenceSnapshot,
    temp: &EvidenceSnapshot,
    effects: &[AddedEffect],
    fit: &GlsFit,
    named: Option<&TemperatureInModel>,
    jumps: Option<&JumpFinding>,
    k2_hi: f64,
) -> Option<TemperatureCheck> {
    let blocks_c = temperature_blocks(snap, temp);
    let finite: Vec<f64> = blocks_c.iter().copied().filter(|t| t.is_finite()).collect();
    if finite.is_empty() {
        return None;
    }
    let (lo_c, hi_c) = finite
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
            (a.min(t), b.max(t))
        });
    // Block means of a constant temperature differ by rounding alone (6e-13 degC at 25 degC
    // over 30 minutes), a held chamber's by its sensor's dither (1e-4 degC for a column of
    // 25.000 and 25.001, which gave coefficients of 0.1-0.4 rad/s per degC on a review's run):
    // a change below CONSTANT_C is none.
    let change_c = Some(hi_c - lo_c)
        .filter(|d| *d >= CONSTANT_C)
        .unwrap_or(0.0);
    // A temperature that varies within the blocks far more than their means show (a cycle of
    // seconds under blocks of tens of seconds) is no straight line, whatever its block means do.
    let within_blocks = temperature_avar(temp, &prob.ms).map_or(0.0, |avar| {
        prob.ms
            .iter()
            .zip(&avar)
            .filter(|(m, _)| (**m as f64) < snap.block_len as f64)
            .map(|(_, v)| v.max(0.0).sqrt())
            .fold(0.0, f64::max)
    });
    let bend = straight_line_bend(&blocks_c).filter(|_| change_c > 0.0);
    let straight = bend.is_some_and(|b| b < STRAIGHT_BEND) && within_blocks < 0.25 * change_c;
    let from = |outcome, f: &TemperatureFinding| TemperatureCheck {
        outcome,
        coefficient: Some(f.coefficient),
        interval: Some(f.interval().into()),
        z: Some(f.z),
        change_c,
        bend,
    };
    let has = |k: EffectKind| effects.iter().any(|e| e.params.kind() == k);
    if let Some(t) = named.filter(|_| has(EffectKind::Temperature)) {
        return Some(from(TemperatureOutcome::Named, &t.finding));
    }
    let unjudged = |outcome| TemperatureCheck {
        outcome,
        coefficient: None,
        interval: None,
        z: None,
        change_c,
        bend,
    };
    if change_c <= 0.0 {
        return Some(unjudged(TemperatureOutcome::Constant));
    }
    let c5 = fit.five_terms();
    let params: Vec<EffectParams> = effects
        .iter()
        .map(|e| e.params)
        .filter(|p| {
            !matches!(
                p.kind(),
                EffectKind::Warmup | EffectKind::BiasJumps | EffectKind::Temperature
            )
        })
        .collect();
    let Some(mut t) = TemperatureInModel::fitted(prob, snap, temp, &c5, &params, k2_hi) else {
        return Some(unjudged(TemperatureOutcome::TooShort));
    };
    // Beside the named warm-up (as the diagnosis fits the two jointly) and the named jumps,
    // each a column of its block curve at its fitted size.
    let block_s = snap.block_len as f64 * snap.tau0_s;
    let nb = snap.block_means.len();
    let mut extra: Vec<Vec<f64>> = effects
        .iter()
        .filter_map(|e| match e.params {
            EffectParams::Warmup {
                amplitude,
                time_constant_s,
            } => Some(warmup_block_means(nb, block_s, amplitude, time_constant_s)),
            _ => None,
        })
        .collect();
    if let Some(j) = jumps.filter(|_| has(EffectKind::BiasJumps)) {
        extra.extend(j.step_curves(nb));
    }
    if !extra.is_empty() {
        t.refit(&snap.block_means, block_s, &c5, &params, &extra);
    }
    // Without a named warm-up: the coefficient again beside the warm-up that fits the block
    // means best (a settling chamber makes the temperature-driven bias a warm-up's shape, and a
    // unit's own warm-up then poses as a coefficient: a review's unit, warm-up 5e-4 rad/s over
    // 300 s, no coefficient, chamber settling over 1500 s, had its interval exclude 0 in 17 of
    // 20 runs). The interval given is the union of the two: what the run allows either way.
    let beside_warmup = (!has(EffectKind::Warmup))
        .then(|| best_warmup_time_constant(&snap.block_means, block_s, &c5, &params))
        .flatten()
        .and_then(|tc| {
            let shape = warmup_block_curve(nb, block_s, tc);
            let w = fit_shape(&snap.block_means, &shape, block_s, &c5, &params, k2_hi)?;
            let mut tw = t.clone();
            let mut cols = extra.clone();
            cols.push(shape.iter().map(|v| w.coefficient * v).collect());
            tw.refit(&snap.block_means, block_s, &c5, &params, &cols);
            Some(tw.finding)
        });
    let outcome = if t.finding.z.abs() > TEMPERATURE_Z {
        TemperatureOutcome::NotKept
    } else if straight {
        TemperatureOutcome::Straight
    } else {
        TemperatureOutcome::NotShown
    };
    let mut check = from(outcome, &t.finding);
    if let (Some(w), Some([lo, hi])) = (beside_warmup, check.interval) {
        let (wlo, whi) = w.interval();
        check.interval = Some([lo.min(wlo), hi.max(whi)]);
    }
    Some(check)
}

/// The rms departure of `v` (one value per block, NaN where missing) from its least-squares
/// straight line in the block index, as a share of its range; `None` with fewer than three
/// values or no range.
pub fn straight_line_bend(v: &[f64]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = v
        .iter()
        .enumerate()
        .filter(|(_, y)| y.is_finite())
        .map(|(i, &y)| (i as f64, y))
        .collect();
    if pts.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let slope = sxy / sxx;
    let rss: f64 = pts
        .iter()
        .map(|p| (p.1 - my - slope * (p.0 - mx)).powi(2))
        .sum();
    let (lo, hi) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
    (hi > lo).then(|| (rss / n).sqrt() / (hi - lo))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight line bends by 0; `e^{-x}` on `[0, r]` by about `r^2 / (12 sqrt 5)` over its
    /// change `1 - e^{-r}` for small `r` (the rms departure of `x^2 / 2` from its line on
    /// `[0, r]`), about `0.037 r`; a cycle by far more.
    #[test]
    fn bend_of_lines_settlings_and_cycles() {
        let line: Vec<f64> = (0..100).map(|i| 20.0 + 0.1 * i as f64).collect();
        assert!(straight_line_bend(&line).unwrap() < 1e-12);
        for r in [0.05, 0.2] {
            let settle: Vec<f64> = (0..400).map(|i| (-(r * i as f64 / 399.0)).exp()).collect();
            let b = straight_line_bend(&settle).unwrap();
            let expect = r * r / (12.0 * 5f64.sqrt()) / (1.0 - (-r).exp());
            assert!((b / expect - 1.0).abs() < 0.1, "r {r}: {b} vs {expect}");
        }
        let cycle: Vec<f64> = (0..400).map(|i| (i as f64 / 400.0 * 12.0).sin()).collect();
        assert!(straight_line_bend(&cycle).unwrap() > 0.3);
        let mut gappy = line.clone();
        gappy[5] = f64::NAN;
        assert!(straight_line_bend(&gappy).unwrap() < 1e-12);
        assert_eq!(straight_line_bend(&[1.0, 1.0, 1.0]), None);
    }
}
