//! Whether an effect carries to a held-out run (docs/gap.md, "Held-out runs"): an effect
//! carries only if it lowers the held-out `r' S^-1 r` by the fitting run's `add_chi2` (on the
//! scale of the model with it in), not by any amount. Two hours of a VOG4-like unit
//! (tests/gap/diagnosis.rs's base) split in halves: a warm-up (3 arcsec/s, T = 60 s) is found on
//! the first hour and has settled for 60 time constants when the second begins, so it must not
//! carry; a Gauss-Markov term (sigma 0.5 arcsec/s, tau_c 2 s) present on both halves must.

use super::diagnosis::{model, TAU0};
use allanscope::gap::{
    diagnose, holdout_gap, DiagnoseOptions, Diagnosis, DiagnosisRecord, EffectKind,
    EvidenceSnapshot, GapConfig, GapEvidence, Verdict,
};
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

/// The two one-hour halves of a two-hour run of [`model`]`(extra)` from power-on.
fn halves(extra: &str, seed: u64) -> (EvidenceSnapshot, EvidenceSnapshot) {
    let m = SimModel::from_toml_str(&model(extra), Path::new("<test>")).expect("model");
    let mut sim = Simulator::new(&m, seed);
    let mut first = vec![0.0; (7200.0 / TAU0) as usize];
    sim.fill_channel(0, &mut first);
    let second = first.split_off(first.len() / 2);
    let snap = |x: &[f64]| GapEvidence::from_increments(GapConfig::new(TAU0), x).snapshot();
    (snap(&first), snap(&second))
}

const WARMUP: &str = "warmup = { amplitude = 3.0, time_constant = 60.0 }";

/// The fitting run named a warm-up.
fn assert_names_a_warm_up(d: &Diagnosis) {
    assert!(d.names(EffectKind::Warmup), "{:?}", d.effects);
}

/// Seed 4: the warm-up is named on the first hour; on the second it lowers the held-out gap a
/// little (1.17 -> 1.07, a drop of r' S^-1 r of 1.8), which before this rule was reported as
/// carried. The record now says plainly that nothing carried.
#[test]
fn a_settled_warmup_does_not_carry_on_a_negligible_gain() {
    let opts = DiagnoseOptions::default();
    let (a, b) = halves(WARMUP, 4);
    let d = diagnose(&a, &opts).expect("diagnosis");
    assert_names_a_warm_up(&d);
    let h = holdout_gap(&d, &b, &opts).expect("holdout");
    let w = h.effect(EffectKind::Warmup).expect("held warm-up");
    assert!(!w.carried, "{h:?}");
    assert!(w.delta_chi2 < opts.thresholds.add_chi2, "{h:?}");
    assert!(!h.carried(), "{h:?}");
    assert_eq!(h.gap_after, h.gap_before, "{h:?}");
    let rec = DiagnosisRecord::new("g4", &d, Some(&h), true);
    let v: serde_json::Value = serde_json::from_str(&rec.to_json_line()).expect("json");
    assert_eq!(v["holdout"]["carried"], false);
    let e0 = &v["holdout"]["effects"][0];
    assert_eq!(e0["carried"], false);
    assert!((e0["delta_chi2"].as_f64().unwrap_or(f64::NAN) - w.delta_chi2).abs() < 1e-9);
}

/// The warm-up beside a Gauss-Markov term, seeds 1 and 2: both are named on the first hour;
/// on the second the Gauss-Markov term carries (a drop of r' S^-1 r above 100, the held-out
/// gap from above 10 to below 2.5) and the settled warm-up does not (on both seeds it lowered
/// the held-out gap a little and was reported as carried before).
#[test]
fn a_gauss_markov_term_carries_and_the_settled_warmup_beside_it_does_not() {
    let opts = DiagnoseOptions::default();
    let extra = format!("{WARMUP}\ngauss_markov = {{ sigma = 0.5, tau_c = 2.0 }}");
    for seed in [1, 2] {
        let (a, b) = halves(&extra, seed);
        let d = diagnose(&a, &opts).expect("diagnosis");
        assert_ne!(d.verdict, Verdict::Consistent, "seed {seed}");
        let h = holdout_gap(&d, &b, &opts).expect("holdout");
        let held = |k: EffectKind| {
            h.effect(k)
                .unwrap_or_else(|| panic!("seed {seed}: no held {k:?}: {h:?}"))
        };
        let gm = held(EffectKind::GaussMarkov);
        assert!(gm.carried && gm.delta_chi2 > 100.0, "seed {seed}: {h:?}");
        assert!(!held(EffectKind::Warmup).carried, "seed {seed}: {h:?}");
        assert!(h.carried(), "seed {seed}");
        assert!(
            h.gap_before > 10.0 && h.gap_after < 2.5,
            "seed {seed}: {h:?}"
        );
    }
}

/// A warm-up carries in time, as the fitting run found it (session 39): the seed's MA4
/// (config/models/ma4.toml's terms, a counter with carry) with a warm-up of 1e-3 m/s^2 over
/// 600 s, two hours from power-on. Named on seed 11; on the curve alone the held-out five
/// terms took its slow fall as K and R and it never carried (a review: 0 of 3 runs of its unit,
/// curve drops -1.8 to 1.9). Its block curve, held fixed, taken out of the held-out block means
/// lowers their whitened residuals by 21-26 on seeds 101 and 102 of the unit (expected 14), so
/// it carries; on the same seeds of the unit without a warm-up the drop is -19 to -25 and it
/// does not (20 of 20 and 0 of 20 over seeds 201-220 through the CLI).
#[test]
fn a_warm_up_from_power_on_carries_in_time_to_a_run_of_its_unit() {
    let text = |warm: &str| {
        format!(
            "tau0_s = 0.004\n[[channel]]\nname = \"a4\"\nunit = \"m/s\"\nlsb = 2.104e-4\n\
             Q = 6.840e-4\nN = 2.811e-4\nB = 0.403e-4\nK = 2.228e-6\nR = 6.020e-8\n\
             flicker_band_s = [0.004, 1.0e4]\n{warm}"
        )
    };
    let run = |t: &str, seed: u64| {
        let m = SimModel::from_toml_str(t, Path::new("<test>")).expect("model");
        let mut sim = Simulator::new(&m, seed);
        let mut x = vec![0.0; (7200.0 / 0.004) as usize];
        sim.fill_channel(0, &mut x);
        for v in x.iter_mut() {
            *v = format!("{v}").parse().expect("number");
        }
        GapEvidence::from_increments(GapConfig::new(0.004), &x).snapshot()
    };
    let with = text("warmup = { amplitude = 1.0e-3, time_constant = 600.0 }\n");
    let without = text("");
    let opts = DiagnoseOptions::default();
    let d = diagnose(&run(&with, 11), &opts).expect("diagnosis");
    assert_names_a_warm_up(&d);
    for seed in [101, 102] {
        for (t, carries) in [(&with, true), (&without, false)] {
            let h = holdout_gap(&d, &run(t, seed), &opts).expect("holdout");
            let w = h
                .effect(EffectKind::Warmup)
                .unwrap_or_else(|| panic!("seed {seed}: no held warm-up: {h:?}"));
            assert_eq!(w.carried, carries, "seed {seed}, {carries}: {h:?}");
            assert!(h.gap_after <= h.gap_before, "seed {seed}: {h:?}");
        }
    }
}
