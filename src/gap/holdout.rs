//! The gap on a held-out run (docs/theory.md section 5): the effects fitted on one run held fixed on
//! another, only the five-term amplitudes refitted, judged as the fitting run's effects are
//! (each kept only if it lowers the held-out gap), so the record says which effects carried.

use super::diagnose::{DiagnoseError, DiagnoseOptions, Diagnosis};
use super::effects::{effect_column, EffectKind};
use super::evidence::EvidenceSnapshot;
use super::problem::{GapProblem, ModelSpec};

/// One effect of the fitting run on the held-out run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldEffect {
    pub kind: EffectKind,
    /// The held-out gap with this effect added to those that carried before it.
    pub gap_after: f64,
    /// Whether it lowered the held-out gap (and so was kept for the effects after it).
    pub carried: bool,
}

/// The gap on a held-out run.
#[derive(Debug, Clone, PartialEq)]
pub struct HoldoutGap {
    /// The five-term model alone, refitted on the held-out run.
    pub gap_before: f64,
    /// With the effects that carried; never above `gap_before`.
    pub gap_after: f64,
    /// The fitting run's effects in their order (bias jumps, events of one run, are left out).
    pub effects: Vec<HeldEffect>,
}

impl HoldoutGap {
    /// Whether any effect lowered the held-out gap.
    pub fn carried(&self) -> bool {
        self.effects.iter().any(|e| e.carried)
    }
}

/// The gap on a held-out run with the effects (kinds, shapes and amplitudes) fitted on another
/// run held fixed; only the five-term amplitudes are refitted (they may differ run to run, as
/// the seed paper's table 2 shows). The effects are added in the fitting run's order, each kept
/// only if it lowers the held-out gap of the model with those kept before it (the rule of the
/// fitting run's bookkeeping). Bias jumps are events of one run and are not carried over.
pub fn holdout_gap(
    fitted: &Diagnosis,
    snap: &EvidenceSnapshot,
    opts: &DiagnoseOptions,
) -> Result<HoldoutGap, DiagnoseError> {
    let prob = GapProblem::new(snap, opts)?;
    let j = prob.len();
    let base = prob
        .gls(&ModelSpec::default())
        .ok_or(DiagnoseError::Fit("base GLS".into()))?;
    let mut spec = ModelSpec {
        offset: Some(vec![0.0; j]),
        ..ModelSpec::default()
    };
    let mut gap = base.gap();
    let mut effects = Vec::new();
    for e in &fitted.effects {
        let kind = e.params.kind();
        let mut trial = spec.clone();
        match kind {
            EffectKind::BiasJumps => continue,
            k if k.is_filter() => trial.filter = e.params.lowpass(),
            _ => {
                let a = e.params.amplitude();
                let col = effect_column(kind, e.params.shape(), &prob.ms, prob.tau0_s, prob.n_inc);
                if let Some(off) = trial.offset.as_mut() {
                    for (o, c) in off.iter_mut().zip(col) {
                        *o += a * a * c;
                    }
                }
            }
        }
        let trial_gap = prob.gls(&trial).map_or(f64::INFINITY, |f| f.gap());
        let carried = trial_gap.is_finite() && trial_gap < gap;
        if carried {
            spec = trial;
            gap = trial_gap;
        }
        effects.push(HeldEffect {
            kind,
            gap_after: trial_gap,
            carried,
        });
    }
    Ok(HoldoutGap {
        gap_before: base.gap(),
        gap_after: gap,
        effects,
    })
}
