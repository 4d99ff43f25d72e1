//! Ambiguity said out loud (docs/gap.md, "Alternatives"): on a short run a Gauss-Markov hump
//! and a raised flicker floor fit about equally, and the record lists the one not chosen with
//! its gap and its five terms; a clear case lists none.
//!
//! 20-minute runs at tau0 = 4 ms of a VOG4-like base (config/models/vog4.toml's N, B, K, LSB)
//! with a Gauss-Markov term of correlation time 30 s.

use allanscope::gap::alternatives::ALT_MARGIN;
use allanscope::gap::{
    diagnose, DiagnoseOptions, Diagnosis, DiagnosisRecord, EffectKind, GapConfig, GapEvidence,
    Thresholds, Verdict,
};
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

fn run(sigma: f64, seed: u64) -> Diagnosis {
    let text = crate::diagnosis::model(&format!(
        "gauss_markov = {{ sigma = {sigma}, tau_c = 30.0 }}"
    ));
    let m = SimModel::from_toml_str(&text, Path::new("<test>")).expect("model");
    let mut sim = Simulator::new(&m, seed);
    let mut inc = vec![0.0; (1200.0 / 0.004) as usize];
    sim.fill_channel(0, &mut inc);
    let mut ev = GapEvidence::from_increments(GapConfig::new(0.004), &inc);
    diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis")
}

/// sigma 0.3 arcsec/s (seed 1): the five terms alone pass (`consistent`, B raised to take the
/// hump), and the Gauss-Markov term, whose likelihood ratio fell just short of its threshold, is
/// listed: a lower gap, a lower B, and a misfit lower by between `2 (crit - margin)` and
/// `2 crit` (two parameters).
#[test]
fn a_hump_or_a_raised_flicker_floor_is_said_out_loud() {
    let d = run(0.3, 1);
    assert_eq!(d.verdict, Verdict::Consistent, "{d:?}");
    let gm: Vec<_> = d
        .alternatives
        .iter()
        .filter(|a| a.effects.len() == 1 && a.effects[0].kind() == EffectKind::GaussMarkov)
        .collect();
    assert_eq!(gm.len(), 1, "{:?}", d.alternatives);
    let a = gm[0];
    let crit = Thresholds::default().lr_crit_of(EffectKind::GaussMarkov);
    assert!(
        a.delta_chi2 <= -2.0 * (crit - ALT_MARGIN) + 1e-9 && a.delta_chi2 > -2.0 * crit,
        "{a:?}"
    );
    assert!(a.gap < d.gap_after, "{a:?} vs {}", d.gap_after);
    assert!(
        a.coef[2] < d.final_coef[2],
        "B {:?} vs {:?}",
        a.coef,
        d.final_coef
    );
    // The hump's own parameters: tau_c within a factor 3 of 30 s.
    let tc = a.effects[0].shape();
    assert!(tc > 10.0 && tc < 90.0, "tau_c {tc}");
    // The record carries it.
    let rec = DiagnosisRecord::new("g4", &d, None, true);
    let v: serde_json::Value = serde_json::from_str(&rec.to_json_line()).expect("json");
    assert_eq!(v["alternatives"][0]["effects"][0]["kind"], "gauss_markov");
    assert!(v["alternatives"][0]["gap"].as_f64().is_some());
}

/// A hump four times larger (sigma 1.2) is named and nothing else is listed; a clean run lists
/// nothing.
#[test]
fn a_clear_case_lists_none() {
    let d = run(1.2, 1);
    assert_eq!(
        d.effects.first().map(|e| e.params.kind()),
        Some(EffectKind::GaussMarkov),
        "{d:?}"
    );
    assert!(d.alternatives.is_empty(), "{:?}", d.alternatives);
    let c = run(0.0, 1);
    assert!(c.alternatives.is_empty(), "{:?}", c.alternatives);
}
