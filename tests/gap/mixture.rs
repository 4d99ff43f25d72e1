//! The mixture (Bayes-factor) statistics of the gap diagnosis (docs/gap.md, "Mixture
//! statistics"): the per-position Bayes factor of a Gaussian step has mean 1 under the null
//! (it is a likelihood ratio), the forward-selection mixture matches its closed form, and the
//! warm-up statistic integrated over `T` lies between the maximum's `W / 2` and `W / 2` less the
//! log of the grid's size (a mean of `exp(W(T) / 2)` is below its largest term and above
//! its largest term over the count).

use allanscope::gap::jump_mixture::{jump_forward_mixture_log_bf, jump_mixture_log_bf};
use allanscope::gap::steps::StepScan;
use allanscope::gap::warmup::{fit_warmup, log_mean_exp, warmup_block_shape};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

/// `E_0[1 - p + p B] = 1` when `z ~ N(0, 1)`: `B` is the ratio of the marginal density of `z`
/// under a `N(0, s^2)` step (`z ~ N(0, 1 + r)`) to its null density. With `r = 0.5` the second
/// moment `E[B^2] = (1 + r)^-1 (1 - 2 r / (1 + r))^-1/2 = 1.155` is finite, so the mean of
/// 200 000 draws has a standard error of about 0.0004 (`p = 0.5`).
#[test]
fn step_bayes_factor_has_null_mean_one() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
    let se = 0.2;
    let rms = se * 0.5f64.sqrt();
    let n = 200_000;
    let mut sum = 0.0;
    for _ in 0..n {
        let z: f64 = StandardNormal.sample(&mut rng);
        let scan = StepScan {
            z: vec![z],
            se: vec![se],
            boundary: vec![true],
        };
        // One candidate, prior count 0.5: p = 0.5.
        sum += jump_mixture_log_bf(&scan, rms, 0.5, false).exp();
    }
    let mean = sum / n as f64;
    assert!((mean - 1.0).abs() < 0.003, "mean {mean}");
    // Under a step of the prior's law the mean is E_1[B] p + (1 - p) = 0.5 (E_0[B^2]) + 0.5.
    let mut sum1 = 0.0;
    for _ in 0..n {
        let z: f64 = StandardNormal.sample(&mut rng);
        let z = z * 1.5f64.sqrt();
        let scan = StepScan {
            z: vec![z],
            se: vec![se],
            boundary: vec![true],
        };
        sum1 += jump_mixture_log_bf(&scan, rms, 0.5, false).exp();
    }
    let want = 0.5 * (1.0 / 1.5) * (1.0 - 1.0 / 1.5f64).powf(-0.5) + 0.5;
    let mean1 = sum1 / n as f64;
    assert!((mean1 - want).abs() < 0.01, "mean {mean1} vs {want}");
}

/// The boundary-only variant skips the steps inside blocks, and the forward mixture is the sum
/// of `ln(1 - p + p B(z))` over the chosen steps.
#[test]
fn mixture_closed_forms() {
    let scan = StepScan {
        z: vec![3.0, -4.0, 0.5],
        se: vec![0.1, 0.2, 0.1],
        boundary: vec![true, false, true],
    };
    let ln_term = |z: f64, r: f64, p: f64| {
        let b = (1.0 + r).powf(-0.5) * (z * z * r / (2.0 * (1.0 + r))).exp();
        (1.0 - p + p * b).ln()
    };
    // rms 0.2: r = 4, 1, 4; count 1 over 3 candidates (p = 1/3), over 2 boundaries (p = 1/2).
    let all =
        ln_term(3.0, 4.0, 1.0 / 3.0) + ln_term(-4.0, 1.0, 1.0 / 3.0) + ln_term(0.5, 4.0, 1.0 / 3.0);
    assert!((jump_mixture_log_bf(&scan, 0.2, 1.0, false) - all).abs() < 1e-12);
    let bnd = ln_term(3.0, 4.0, 0.5) + ln_term(0.5, 4.0, 0.5);
    assert!((jump_mixture_log_bf(&scan, 0.2, 1.0, true) - bnd).abs() < 1e-12);
    // Forward mixture: r = rms_rel^2 = 9, p = 4 / 500.
    let zs = [4.2, 3.1, 2.6];
    let want: f64 = zs.iter().map(|&z| ln_term(z, 9.0, 4.0 / 500.0)).sum();
    assert!((jump_forward_mixture_log_bf(&zs, 500, 3.0, 4.0) - want).abs() < 1e-12);
    // No steps: no evidence either way.
    assert_eq!(jump_forward_mixture_log_bf(&[], 500, 3.0, 4.0), 0.0);
    // log-mean-exp of equal values is that value; of very large ones it does not overflow.
    assert!((log_mean_exp(&[2.0, 2.0, 2.0]) - 2.0).abs() < 1e-12);
    assert!((log_mean_exp(&[1000.0, 1000.0 - 2f64.ln()]) - (1000.0 + 0.75f64.ln())).abs() < 1e-9);
}

/// A warm-up in white block means: the integrated statistic is between `W / 2 - ln(grid)` and
/// `W / 2`, and a strong warm-up lifts both far above a clean series.
#[test]
fn warmup_integrated_statistic_is_bounded_by_the_maximum() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let (n_blocks, block_s) = (256usize, 42.0);
    let t_run = n_blocks as f64 * block_s;
    // White rate noise N^2 = 0.01 (u^2/s): block-mean sd 0.1 / sqrt(42).
    let c = [0.0, 0.01, 0.0, 0.0, 0.0];
    let sd = (0.01f64 / block_s).sqrt();
    // The scan's grid: 24 per decade from block_s / 2 to t_run / 4.
    let n_grid = ((t_run / 4.0 / (block_s / 2.0)).log10() * 24.0).ceil() + 1.0;
    for amp in [0.0, 0.2] {
        let bm: Vec<f64> = (0..n_blocks)
            .map(|i| {
                let e: f64 = StandardNormal.sample(&mut rng);
                sd * e + amp * warmup_block_shape(i, block_s, 600.0)
            })
            .collect();
        let w = fit_warmup(&bm, block_s, t_run, &c, &[]).expect("fit");
        assert!(w.log_bf <= w.w_stat / 2.0 + 1e-9, "{w:?}");
        assert!(w.log_bf >= w.w_stat / 2.0 - n_grid.ln() - 1e-9, "{w:?}");
        if amp > 0.0 {
            // 0.2 u/s decaying over 600 s against a block sd of 0.015: W in the hundreds.
            assert!(w.w_stat > 100.0 && w.log_bf > 45.0, "{w:?}");
        } else {
            assert!(w.w_stat < 20.0, "{w:?}");
        }
    }
}

/// The marginal-likelihood jump ceiling (importance sampling over the times) against its exact
/// value, by enumerating all pairs of times of a short series (40 blocks, 160 candidate times)
/// and computing each pair's likelihood ratio directly from the `n x n` covariance
/// `I + s^2 U U'` (not the `2 x 2` Woodbury form the oracle uses).
#[test]
fn jump_ceiling_matches_exact_enumeration() {
    use allanscope::gap::block_cov::block_diff_covariance;
    use allanscope::gap::oracle::{jumps_marginal_oracle, BlockGls, JUMP_SUBBLOCKS};
    use nalgebra::{DMatrix, DVector};
    let (n_blocks, block_s) = (40usize, 10.0);
    let c = [0.0, 0.01, 0.0, 1e-6, 0.0];
    let sd = (0.01f64 / block_s).sqrt();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    // Two steps of 2.5 and -2 block sds at 112 s and 301 s.
    let bm: Vec<f64> = (0..n_blocks)
        .map(|i| {
            let e: f64 = StandardNormal.sample(&mut rng);
            let mid = |t0: f64| (((i + 1) as f64 * block_s - t0) / block_s).clamp(0.0, 1.0);
            sd * e + 2.5 * sd * mid(112.0) - 2.0 * sd * mid(301.0)
        })
        .collect();
    let rms = 2.0 * sd;
    let gls = BlockGls::new(&bm, block_s, &c).expect("gls");
    let est = jumps_marginal_oracle(&gls, 2, rms, 20_000, 9).expect("oracle");

    // Exact: whiten, project off the drift, enumerate.
    let sigma = block_diff_covariance(n_blocks, block_s, &c, &[]).expect("cov");
    let n = sigma.nrows();
    let linv = sigma
        .cholesky()
        .expect("chol")
        .l()
        .solve_lower_triangular(&DMatrix::identity(n, n))
        .expect("inv");
    let ones = &linv * DVector::from_element(n, 1.0);
    let q = &ones / ones.norm();
    let perp = |v: DVector<f64>| &v - &q * q.dot(&v);
    let d = DVector::from_iterator(n, bm.windows(2).map(|p| p[1] - p[0]));
    let y = perp(&linv * d);
    let t_run = n_blocks as f64 * block_s;
    let n_cand = n_blocks * JUMP_SUBBLOCKS;
    let cols: Vec<DVector<f64>> = (0..n_cand)
        .map(|i| {
            let t = (i as f64 + 0.5) / n_cand as f64 * t_run;
            let prof: Vec<f64> = (0..n_blocks)
                .map(|b| (((b + 1) as f64 * block_s - t) / block_s).clamp(0.0, 1.0))
                .collect();
            perp(&linv * BlockGls::diff(&prof))
        })
        .collect();
    let yy = y.norm_squared();
    let mut logs = Vec::with_capacity(n_cand * n_cand);
    for a in 0..n_cand {
        for b in 0..n_cand {
            let u = DMatrix::from_columns(&[cols[a].clone(), cols[b].clone()]);
            let cov = DMatrix::identity(n, n) + &u * u.transpose() * (rms * rms);
            let ch = cov.cholesky().expect("pd");
            let logdet: f64 = ch.l().diagonal().iter().map(|v| 2.0 * v.ln()).sum();
            logs.push(-0.5 * logdet - 0.5 * y.dot(&ch.solve(&y)) + 0.5 * yy);
        }
    }
    let exact = log_mean_exp(&logs);
    eprintln!("jump ceiling: importance sampling {est:.4}, exact {exact:.4}");
    assert!(exact > 1.0, "the steps should carry evidence: {exact}");
    assert!(
        (est - exact).abs() < 0.05,
        "importance sampling {est} vs exact {exact}"
    );
}

/// The fair jump ceiling's p-value (`JumpCeiling::p_value`, count and rms told, times
/// unknown) is a real p-value: on 60 white block-mean series of 40 blocks (the model's own
/// covariance, so the Gaussian null holds exactly) the share at or below 0.1 is within the
/// binomial 99% range of 10% (0-13 of 60), and two steps of 3 block sds (at 112 s and 301 s)
/// give p <= 0.05 in at least 50 of 60 series.
#[test]
fn jump_ceiling_p_value_has_its_level_and_power() {
    use allanscope::gap::oracle::{BlockGls, JumpCeiling};
    let (n_blocks, block_s) = (40usize, 10.0);
    let c = [0.0, 0.01, 0.0, 0.0, 0.0];
    let sd = (0.01f64 / block_s).sqrt();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(21);
    let mut series = |amp: f64| -> Vec<f64> {
        (0..n_blocks)
            .map(|i| {
                let e: f64 = StandardNormal.sample(&mut rng);
                let mid = |t0: f64| (((i + 1) as f64 * block_s - t0) / block_s).clamp(0.0, 1.0);
                sd * e + amp * sd * (mid(112.0) - mid(301.0))
            })
            .collect()
    };
    let p_of = |bm: &[f64], seed: u64| {
        let g = BlockGls::new(bm, block_s, &c).expect("gls");
        JumpCeiling::new(&g)
            .p_value(2, 3.0 * sd, 300, 99, seed)
            .expect("p")
            .0
    };
    let mut null_low = 0;
    let mut found = 0;
    for k in 0..60u64 {
        if p_of(&series(0.0), k) <= 0.1 {
            null_low += 1;
        }
        if p_of(&series(3.0), 100 + k) <= 0.05 {
            found += 1;
        }
    }
    assert!(null_low <= 13, "{null_low} of 60 clean series at p <= 0.1");
    assert!(
        found >= 50,
        "{found} of 60 series with two steps at p <= 0.05"
    );
}
