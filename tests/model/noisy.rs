//! The fit on simulated noisy curves with known coefficients (tests/common/fit.rs): bias, 95%
//! interval coverage and gof calibration of the default method over many seeds, and the refit
//! time. `cargo test --release --test model -- noisy:: --ignored --nocapture` prints the comparison
//! with the paper's method, the slope read-out and the unweighted log-log fit.
#![allow(clippy::needless_range_loop)]

use crate::common::fit::{bank_times, gm_avar, octave_curve, simulate_phase, Truth};
use allanscope::model::fit::{FitMethod, FitOptions, Fitter};
use std::f64::consts::{LN_2, PI};
use std::time::Instant;

/// The simulated model: crossovers Q-N at 0.04 s, N-B at 2 s, B-K at 40 s, so each of the four
/// random terms dominates two or more octaves of a 2621 s run at tau0 = 0.01 s.
const TRUTH: Truth = Truth {
    q: 0.115,
    n: 1.0,
    b: 1.06,
    k: 0.193,
};
const TAU0_S: f64 = 0.01;
const N_INCR: usize = 1 << 18;
/// Largest cluster: N/4 (the last octave before the top, where one or two differences remain).
const M_MAX: usize = N_INCR / 4;
const SEEDS: u64 = 100;

/// Stated tolerances (the brief's acceptance figures).
const BIAS_TOL: f64 = 0.05;
const COVERAGE_RANGE: (f64, f64) = (0.85, 0.99);
/// gof mean over SEEDS runs: 1 +- 0.25 (its sd per run is about sqrt(2/(J-p)) ~ 0.4, and the
/// flicker bank is only approximately the flicker term).
const GOF_MEAN_TOL: f64 = 0.25;

#[derive(Default, Clone)]
struct Stats {
    sum: [f64; 5],
    n_det: [usize; 5],
    covered: [usize; 5],
    runs: usize,
    gof: Vec<f64>,
}

fn run(method: FitMethod, seeds: u64) -> Stats {
    let mut fitter = Fitter::new();
    let opts = FitOptions {
        method,
        ..FitOptions::default()
    };
    let truth = TRUTH.coef();
    let mut st = Stats::default();
    for seed in 0..seeds {
        let x = simulate_phase(&TRUTH, TAU0_S, N_INCR, 1000 + seed);
        let pts = octave_curve(&x, TAU0_S, M_MAX);
        let r = fitter.fit(&pts, &opts).expect("fit");
        st.runs += 1;
        st.gof.push(r.gof);
        for i in 0..5 {
            let e = &r.coef[i];
            if e.determined {
                st.n_det[i] += 1;
                st.sum[i] += e.value;
            }
            if e.lo <= truth[i] && truth[i] <= e.hi {
                st.covered[i] += 1;
            }
        }
    }
    st
}

fn report(name: &str, st: &Stats) {
    let truth = TRUTH.coef();
    let names = ["Q", "N", "B", "K", "R"];
    let gof_mean = st.gof.iter().sum::<f64>() / st.gof.len() as f64;
    let mut line = format!("{name:8} gof {gof_mean:6.2} |");
    for i in 0..5 {
        let bias = if st.n_det[i] > 0 && truth[i] > 0.0 {
            format!(
                "{:+6.1}%",
                100.0 * (st.sum[i] / st.n_det[i] as f64 / truth[i] - 1.0)
            )
        } else {
            "     - ".to_string()
        };
        line += &format!(
            " {} det {:3} bias {} cov {:5.1}% |",
            names[i],
            st.n_det[i],
            bias,
            100.0 * st.covered[i] as f64 / st.runs as f64
        );
    }
    println!("{line}");
}

#[test]
fn flicker_bank_is_flat() {
    // The bank's AVAR against (2 ln2/pi) B^2 over the taus where B dominates the model (1..32 s):
    // within 1% (closed form of docs/theory.md section 3).
    let s2 = crate::common::fit::bank_variance(TRUTH.b);
    let target = 2.0 * LN_2 / PI * TRUTH.b * TRUTH.b;
    for k in 0..6 {
        let tau = 2f64.powi(k);
        let v: f64 = bank_times().iter().map(|&t| gm_avar(tau, s2, t)).sum();
        assert!((v / target - 1.0).abs() < 0.01, "tau {tau}: {}", v / target);
    }
}

#[test]
fn model_fit_is_unbiased_with_honest_intervals() {
    let st = run(FitMethod::Model, SEEDS);
    report("model", &st);
    let truth = TRUTH.coef();
    for i in 0..4 {
        // Every simulated term is determined in most runs ...
        assert!(
            st.n_det[i] as f64 >= 0.8 * SEEDS as f64,
            "term {i}: determined {} times",
            st.n_det[i]
        );
        // ... without bias beyond 5% ...
        let mean = st.sum[i] / st.n_det[i] as f64;
        assert!(
            (mean / truth[i] - 1.0).abs() <= BIAS_TOL,
            "term {i}: mean {mean} vs {}",
            truth[i]
        );
        // ... and its 95% interval covers the truth 85-99% of the time.
        let cov = st.covered[i] as f64 / st.runs as f64;
        assert!(
            cov >= COVERAGE_RANGE.0 && cov <= COVERAGE_RANGE.1,
            "term {i}: coverage {cov}"
        );
    }
    // R is absent: its interval must contain 0 nearly always (false determinations rare).
    assert!(
        st.n_det[4] as f64 <= 0.1 * SEEDS as f64,
        "R determined {} times",
        st.n_det[4]
    );
    let gof_mean = st.gof.iter().sum::<f64>() / st.gof.len() as f64;
    assert!(
        (gof_mean - 1.0).abs() <= GOF_MEAN_TOL,
        "gof mean {gof_mean}"
    );
}

// A speed figure, not a correctness check: the guide keeps speed targets in benchmarks
// (`cargo bench --bench fit`, BENCHMARKS.md), because a shared machine makes timed assertions
// flaky (this one failed once at load 19). Run by hand with `--ignored`.
#[test]
#[ignore]
fn refit_time_per_channel() {
    // ~20 octave taus: 2^21 increments at 4 ms (2.3 h), m = 1 .. 2^20.
    let tau0 = 0.004;
    let n = 1usize << 21;
    let pts = crate::common::fit::model_curve([2e-3, 3e-3, 1e-3, 2e-5, 1e-7], tau0, n, n / 2);
    assert!(pts.len() >= 20);
    let mut fitter = Fitter::new();
    let opts = FitOptions::default();
    let t = Instant::now();
    fitter.fit(&pts, &opts).unwrap();
    let cold = t.elapsed();
    let reps = 200;
    let t = Instant::now();
    for _ in 0..reps {
        fitter.fit(&pts, &opts).unwrap();
    }
    let warm = t.elapsed() / reps;
    // Live: the run grows 0.5% between refits (counts change); the lag sums are updated.
    let mut live = Fitter::new();
    let mut n_live = n;
    live.fit(
        &crate::common::fit::model_curve([2e-3, 3e-3, 1e-3, 2e-5, 1e-7], tau0, n_live, n_live / 2),
        &opts,
    )
    .unwrap();
    let curves: Vec<_> = (0..reps)
        .map(|_| {
            n_live += n_live / 200;
            crate::common::fit::model_curve([2e-3, 3e-3, 1e-3, 2e-5, 1e-7], tau0, n_live, n / 2)
        })
        .collect();
    let t = Instant::now();
    for c in &curves {
        live.fit(c, &opts).unwrap();
    }
    let grow = t.elapsed() / reps;
    println!(
        "{} taus: first fit {cold:?} (covariance lag sums), refit same curve {warm:?}, \
         live refit (+0.5% data each) {grow:?}",
        pts.len()
    );
    // Budget: a refit within 1 ms per channel.
    assert!(warm.as_secs_f64() < 1e-3, "refit took {warm:?}");
    // Live refits update the covariance lag sums (0.6 ms in benches/fit.rs on the reference
    // machine); bounded loosely here since test machines are shared.
    assert!(grow.as_secs_f64() < 5e-3, "live refit took {grow:?}");
}

#[test]
#[ignore]
fn compare_methods() {
    for method in [
        FitMethod::Model,
        FitMethod::Paper,
        FitMethod::Slopes,
        FitMethod::LogLog,
    ] {
        report(method.name(), &run(method, SEEDS));
    }
}
