//! The diagnosis on units other than the VOG4-like gyro it was first tuned on, and its
//! bookkeeping: the seed paper's pendulous MA4 accelerometer, simulated clean from the shipped
//! config/models/ma4.toml (white phase noise, quantization with carry, dominating up to tau ~ 18
//! s; R present) is `consistent`, and on every run each effect's `gap_after` is the gap after it
//! is added, each lower than the one before, the last the final gap, never above `gap_before`.
//!
//! The MA4 rate over 100 seeds (the target: >= 95 consistent) is a study in docs/gap.md
//! ("Families of units"); here five seeds, all of which must be consistent: with the study's
//! 98/100, five of five happen by chance in about 90% of seed sets, and these five are fixed.

use allanscope::gap::{diagnose, DiagnoseOptions, Diagnosis, GapConfig, GapEvidence, Verdict};
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

/// Two hours, the run.
const DURATION_S: f64 = 7200.0;

fn ma4_run(seed: u64) -> Diagnosis {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/models/ma4.toml");
    let text = std::fs::read_to_string(&path).expect("config/models/ma4.toml");
    let m = SimModel::from_toml_str(&text, &path).expect("model");
    let tau0 = m.tau0_s;
    let mut sim = Simulator::new(&m, seed);
    let mut inc = vec![0.0; (DURATION_S / tau0) as usize];
    sim.fill_channel(0, &mut inc);
    let mut ev = GapEvidence::from_increments(GapConfig::new(tau0), &inc);
    diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis")
}

/// The bookkeeping rules of docs/gap.md ("Bookkeeping").
fn assert_honest(d: &Diagnosis) {
    let mut prev = d.gap_before;
    for e in &d.effects {
        assert!(
            e.gap_after < prev,
            "{:?} did not lower the gap from {prev}",
            e
        );
        prev = e.gap_after;
    }
    assert_eq!(d.gap_after, prev, "final gap vs the last effect's");
    assert!(d.gap_after <= d.gap_before);
}

#[test]
fn ma4_clean_runs_are_consistent() {
    for seed in [901, 902, 903, 904, 905] {
        let d = ma4_run(seed);
        assert_honest(&d);
        assert_eq!(
            d.verdict,
            Verdict::Consistent,
            "seed {seed}: G {} -> {}, {:?}",
            d.gap_before,
            d.gap_after,
            d.effects
        );
        // The base model's gap is near 1 (its null median is 1.0; docs/gap.md), not the
        // 9.5-25 the full-overlap covariance gave on these runs.
        assert!(d.gap_before < 1.6, "seed {seed}: G {}", d.gap_before);
    }
}
