//! The gap on a held-out run (THEORY.md section 5): the effects fitted on one run held fixed on
//! another, only the five-term amplitudes refitted.

use super::diagnose::{DiagnoseError, DiagnoseOptions, Diagnosis};
use super::effects::{effect_column, EffectKind};
use super::evidence::EvidenceSnapshot;
use super::problem::{GapProblem, ModelSpec};

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
