//! The warm-up's null takes the rate random walk `K` at its upper profile bound from the curve
//! (`GapProblem::upper_bound`; docs/gap.md, "The warm-up's null level"): the bound is at or above
//! the fitted `K`, the curve's `r' S^-1 r` rises by the stated `delta` there (or the bound is at
//! its ceiling, the `K` whose term alone reaches the data), and it covers the true `K` in more
//! runs than the fitted `K` does.
//!
//! Runs of one hour at tau0 = 4 ms of a VOG4-like base (config/models/vog4.toml's N, B, K,
//! LSB 0.004 arcsec), ten seeds.

use allanscope::gap::problem::{GapProblem, ModelSpec};
use allanscope::gap::warmup::WARMUP_K_DELTA;
use allanscope::gap::{DiagnoseOptions, GapConfig, GapEvidence};
use allanscope::model::terms::basis;
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

const TAU0: f64 = 0.004;
const DURATION_S: f64 = 3600.0;
const K: f64 = 1.826e-2;

#[test]
fn k_upper_bound_raises_chi2_by_delta_and_covers_the_true_k() {
    let toml = format!(
        "tau0_s = {TAU0}\n[[channel]]\nname = \"g\"\nunit = \"arcsec\"\nlsb = 0.004\nN = 0.254\nB = 0.225\nK = {K}\nflicker_band_s = [{TAU0}, 1.0e5]\n"
    );
    let m = SimModel::from_toml_str(&toml, Path::new("<test>")).expect("model");
    let (mut covered, mut fit_covers, mut at_zero) = (0, 0, 0);
    for seed in 31..41u64 {
        let mut sim = Simulator::new(&m, seed);
        let mut out = vec![0.0; (DURATION_S / TAU0) as usize];
        sim.fill_channel(0, &mut out);
        let snap = GapEvidence::from_increments(GapConfig::new(TAU0), &out).snapshot();
        let prob = GapProblem::new(&snap, &DiagnoseOptions::default()).expect("problem");
        let spec = ModelSpec::default();
        let fit = prob.gls(&spec).expect("fit");
        let k_up = prob
            .upper_bound(&spec, &fit, 3, WARMUP_K_DELTA)
            .expect("bound");
        if fit.coef[3] == 0.0 {
            at_zero += 1;
        }
        assert!(
            k_up >= fit.coef[3],
            "seed {seed}: bound {k_up} below the fit {}",
            fit.coef[3]
        );
        // The definition: K^2 held at the bound or above (a fixed offset, the column still
        // free) raises r' S^-1 r by delta; the bisection stops within 1% of k below it.
        let off: Vec<f64> = prob.tau.iter().map(|t| k_up * basis(*t)[3]).collect();
        let held = prob
            .gls(&ModelSpec {
                offset: Some(off),
                ..ModelSpec::default()
            })
            .expect("held fit");
        let rise = held.chi2 - fit.chi2;
        eprintln!(
            "seed {seed}: K^2 fit {:.3e} bound {k_up:.3e} true {:.3e} rise {rise:.3}",
            fit.coef[3],
            K * K
        );
        // Or the bisection's ceiling: the K whose term alone reaches the data at some tau.
        let cap = prob
            .y
            .iter()
            .zip(&prob.tau)
            .map(|(y, t)| y / basis(*t)[3])
            .fold(f64::INFINITY, f64::min);
        let at_cap = (k_up / cap - 1.0).abs() < 1e-9;
        assert!(
            rise <= WARMUP_K_DELTA + 1e-9 && (rise >= 0.8 * WARMUP_K_DELTA || at_cap),
            "seed {seed}: rise {rise}, bound {k_up}, cap {cap}"
        );
        if k_up >= K * K {
            covered += 1;
        }
        if fit.coef[3] >= K * K {
            fit_covers += 1;
        }
    }
    eprintln!("covered {covered} of 10 (the fit alone {fit_covers}), K at 0 in {at_zero}");
    // A one-sided bound at about 84% (capped at the data) covers the true K in most runs; the
    // fitted K, a median-like estimate, in about half (measured 7 and 3 of 10 on these seeds).
    assert!(
        covered >= 6,
        "the bound covers the true K in {covered} of 10"
    );
    assert!(covered > fit_covers, "{covered} vs the fit's {fit_covers}");
}
