//! The warm-up test with the rate random walk's `K^2` profiled on the block means
//! (`gap::warmup_profile`; docs/gap.md, "The warm-up's null level", session 12), on block means
//! drawn exactly from the Gaussian model of their differences (white rate plus a random walk):
//! - with the profile's upper end 1000 times the true `K^2` (the curve's bound on a run of
//!   10-20 minutes sits there), the bootstrap p-value of clean series is about uniform: its share
//!   at or below 0.1 is within the binomial range of a uniform one, where session 8's null (the
//!   covariance at that upper end) is conservative;
//! - a warm-up that the null at the upper end does not find is found at the diagnosis's level
//!   (`warmup_alpha` = 0.01), with a median error of its time constant below 50% (the diagnosis
//!   tests' tolerance, tests/gap/diagnosis.rs).

use allanscope::gap::block_cov::block_diff_covariance;
use allanscope::gap::warmup::{fit_warmup, warmup_block_shape};
use allanscope::gap::warmup_profile::fit_warmup_profiled;
use nalgebra::DVector;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

/// 64 blocks of 10 s: the profile's grids stay small, so a run of 999 bootstrap draws is quick.
const N_BLOCKS: usize = 64;
const BLOCK_S: f64 = 10.0;
/// White rate `N^2` (u^2/s) and the true random walk `K^2` (u^2/s^3).
const N2: f64 = 0.01;
const K2: f64 = 1e-7;
/// The profile's upper end, as the curve's bound of a short run: 1000 times the truth.
const K_HI: f64 = 1e-4;

/// `n_blocks` block means (u/s) of `block_s` seconds whose first differences are Gaussian with
/// the covariance of the five terms `c` ([`block_diff_covariance`]), summed from 0.
pub(super) fn gaussian_block_means(
    rng: &mut Xoshiro256PlusPlus,
    n_blocks: usize,
    block_s: f64,
    c: &[f64; 5],
) -> Vec<f64> {
    let l = block_diff_covariance(n_blocks, block_s, c, &[])
        .expect("covariance")
        .cholesky()
        .expect("positive definite")
        .l();
    let x = DVector::from_fn(n_blocks - 1, |_, _| StandardNormal.sample(rng));
    let d = l * x;
    let mut b = vec![0.0; n_blocks];
    for i in 1..n_blocks {
        b[i] = b[i - 1] + d[i - 1];
    }
    b
}

/// One series of block means of white rate plus a random walk, plus a warm-up `amp e^{-t/T}`
/// (u/s).
fn series(rng: &mut Xoshiro256PlusPlus, amp: f64, t_s: f64) -> Vec<f64> {
    let mut b = gaussian_block_means(rng, N_BLOCKS, BLOCK_S, &[0.0, N2, 0.0, K2, 0.0]);
    for (i, v) in b.iter_mut().enumerate() {
        *v += amp * warmup_block_shape(i, BLOCK_S, t_s);
    }
    b
}

#[test]
fn profiled_null_is_about_uniform_on_clean_series() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1201);
    let t_run = N_BLOCKS as f64 * BLOCK_S;
    let c = [0.0, N2, 0.0, 0.0, 0.0];
    let mut c_hi = c;
    c_hi[3] = K_HI;
    let runs = 120;
    let (mut prof_low, mut fixed_low) = (0, 0);
    for _ in 0..runs {
        let b = series(&mut rng, 0.0, 1.0);
        let (w, k_null) =
            fit_warmup_profiled(&b, BLOCK_S, t_run, &c, K_HI, &[]).expect("profiled fit");
        assert!((0.0..=K_HI).contains(&k_null), "{k_null}");
        if w.p_value <= 0.1 {
            prof_low += 1;
        }
        let f = fit_warmup(&b, BLOCK_S, t_run, &c_hi, &[]).expect("fixed fit");
        if f.p_value <= 0.1 {
            fixed_low += 1;
        }
    }
    eprintln!("p <= 0.1: profiled {prof_low}, K^2 at the upper end {fixed_low} of {runs}");
    // Binomial(120, 0.1): mean 12, sd 3.3; [3, 23] holds 99.8% of it.
    assert!(
        (3..=23).contains(&prof_low),
        "profiled null: {prof_low} of {runs} at p <= 0.1"
    );
    // The null at the upper end holds the level too, by a wide margin (it is the worst case).
    assert!(fixed_low <= 23, "{fixed_low}");
}

#[test]
fn warmup_hidden_by_the_bound_is_found_with_its_time_constant() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1202);
    let t_run = N_BLOCKS as f64 * BLOCK_S;
    let c = [0.0, N2, 0.0, 0.0, 0.0];
    let mut c_hi = c;
    c_hi[3] = K_HI;
    // Block-mean sd 0.032 u/s; a warm-up of 0.2 u/s decaying over 60 s.
    let (amp, t_s) = (0.2, 60.0);
    let (mut found, mut fixed_found, runs) = (0, 0, 10);
    let mut t_err = Vec::new();
    for _ in 0..runs {
        let b = series(&mut rng, amp, t_s);
        let (w, _) = fit_warmup_profiled(&b, BLOCK_S, t_run, &c, K_HI, &[]).expect("profiled");
        let f = fit_warmup(&b, BLOCK_S, t_run, &c_hi, &[]).expect("fixed");
        eprintln!(
            "profiled p {:.3} T {:.0} A {:.3}; at the upper end p {:.3}",
            w.p_value, w.time_constant_s, w.amplitude, f.p_value
        );
        if w.p_value <= 0.01 {
            found += 1;
            t_err.push((w.time_constant_s / t_s - 1.0).abs());
        }
        if f.p_value <= 0.01 {
            fixed_found += 1;
        }
    }
    eprintln!("found {found} of {runs}; at the upper end {fixed_found}; T errors {t_err:?}");
    assert!(found >= 8, "found {found} of {runs}");
    t_err.sort_by(f64::total_cmp);
    let median = t_err[t_err.len() / 2];
    assert!(median < 0.5, "median T error {median}");
    assert!(found > fixed_found, "{found} vs {fixed_found}");
}
