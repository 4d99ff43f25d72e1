//! A filter's tail is white phase noise (docs/gap.md, "A filter's tail is white phase noise"):
//! on a unit without white phase noise (a MEMS gyro that rounds its rate samples), the base
//! fit holds `Q = 0` at its bound and a chance deficit of the shortest taus was taken by a
//! filter of sub-sample memory. The filters' likelihood ratios are now judged beyond their tail
//! (against the model with white phase noise of either sign).

use allanscope::gap::{
    diagnose, DiagnoseOptions, Diagnosis, GapConfig, GapEvidence, Thresholds, Verdict,
};
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

/// The unit of family_gap's 'short' clean draw 5 (seed 91; a false alarm of session 9): a MEMS
/// gyro at 105 Hz, 734 s, rate samples rounded to 0.15 of their noise.
const SHORT: &str = "tau0_s = 0.009523809523809525\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\n\
                     N = 2.5746e-3\nB = 6.4923e-4\nK = 1.3403e-5\nrate_lsb = 3.9497e-3\n\
                     flicker_band_s = [0.0095238, 1.0e5]\n";
const TAU0: f64 = 0.009523809523809525;

fn run(seed: u64, filter_tail: bool) -> Diagnosis {
    let m = SimModel::from_toml_str(SHORT, Path::new("<test>")).expect("model");
    let mut sim = Simulator::new(&m, seed);
    let mut inc = vec![0.0; (734.0 / TAU0) as usize];
    sim.fill_channel(0, &mut inc);
    let mut ev = GapEvidence::from_increments(GapConfig::new(TAU0), &inc);
    let opts = DiagnoseOptions {
        thresholds: Thresholds {
            filter_tail,
            ..Thresholds::default()
        },
        ..DiagnoseOptions::default()
    };
    let d = diagnose(&ev.snapshot(), &opts).expect("diagnosis");
    crate::diagnosis::assert_bookkeeping(&d);
    d
}

/// Two clean runs (simulator seeds 128 and 163 of 260 tried; about 1 in 50 clean runs of this
/// unit) on which a filter of sub-sample memory (time constant 0.36 tau0) passed its own
/// likelihood-ratio threshold judged against the model before it: now `consistent`, and every
/// filter's statistic beyond its tail is at most its plain drop.
///
/// From session 33 to 43 the scans' floor at tau0 / 2 (docs/gap.md, "The scans' shortest
/// shapes") kept even the session-9 rule from naming a filter on them. Since session 44 the
/// moving averages run faster than the output have short shapes the floor does not hold, and
/// once one passes, a first order below the floor competes for the kind. Under the session-9
/// rule seed 128 is then given a filter again (a first order of 0.45 tau0, G 0.53), so the
/// filter's tail is what keeps these runs clean, as the test asserts. Seed 31 is a third clean
/// run: there the moving average of two samples passed, and a first order at the short end of
/// its grid (0.30 tau0, not located) was named in its place until the first order below the
/// floor was asked to lie inside its grid.
#[test]
fn a_sub_sample_filter_on_a_clean_short_mems_run_is_not_claimed() {
    let old_rule = run(128, false);
    assert!(
        old_rule.effects.iter().any(|e| e.params.kind().is_filter()),
        "seed 128: the session-9 rule named {:?}",
        old_rule.effects
    );
    for seed in [128, 163, 31] {
        let d = run(seed, true);
        assert_eq!(
            d.verdict,
            Verdict::Consistent,
            "seed {seed}: {:?}",
            d.effects
        );
        for c in d.first_scores.iter().filter(|c| c.kind.is_filter()) {
            assert!(c.score_tail <= c.score + 1e-9, "seed {seed}: {c:?}");
        }
    }
}
