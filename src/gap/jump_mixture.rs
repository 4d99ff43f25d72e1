//! Spike-and-slab mixture (Bayes-factor) statistics of bias jumps over the candidate step
//! positions of [`super::steps`]: measured against the forward-selection rule and not adopted
//! (docs/gap.md, "Mixture statistics"); kept for the calibration example and its tests.

use super::steps::StepScan;
use super::warmup::log_mean_exp;

/// Spike-and-slab mixture statistic of the jumps over the candidate positions:
/// `ln prod_j (1 - p + p B_j)`, `B_j = (1 + r_j)^(-1/2) exp(z_j^2 r_j / (2 (1 + r_j)))` the Bayes
/// factor of a step of size `N(0, rms_size^2)` at candidate `j` against none (`r_j = rms_size^2 /
/// se_j^2`), `p = count / positions` the prior chance of a step at each candidate. This is the
/// log marginal likelihood ratio of "each candidate holds a Gaussian step with probability
/// `p`" against no steps when the candidates' z scores are treated as independent (they are
/// not: neighbours share block means; docs/gap.md, "Mixture statistics"). `boundary_only`
/// keeps the steps at block boundaries only.
pub fn jump_mixture_log_bf(scan: &StepScan, rms_size: f64, count: f64, boundary_only: bool) -> f64 {
    let idx: Vec<usize> = (0..scan.z.len())
        .filter(|&j| !boundary_only || scan.boundary[j])
        .collect();
    if idx.is_empty()
        || rms_size.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || count.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return 0.0;
    }
    let p = (count / idx.len() as f64).min(0.5);
    let (lp, lq) = (p.ln(), (1.0 - p).ln());
    idx.iter()
        .map(|&j| {
            let r = (rms_size / scan.se[j]).powi(2);
            let lb = -0.5 * (1.0 + r).ln() + scan.z[j].powi(2) * r / (2.0 * (1.0 + r));
            let (a, b) = (lq, lp + lb);
            let m = a.max(b);
            m + ((a - m).exp() + (b - m).exp()).ln()
        })
        .sum()
}

/// Prior rms step sizes, in units of the median single-step standard error, and expected step
/// counts, over which [`jump_mixture_stat`] averages the mixture's marginal likelihood.
pub const JUMP_MIX_SIZES: [f64; 6] = [1.0, 1.5, 2.0, 3.0, 4.0, 6.0];
pub const JUMP_MIX_COUNTS: [f64; 3] = [2.0, 4.0, 8.0];

/// The mixture statistic of the jumps with the prior's size and count unknown: `ln` of the mean
/// over the grid `JUMP_MIX_SIZES x JUMP_MIX_COUNTS` (equal weights) of the marginal likelihood
/// ratio `exp(jump_mixture_log_bf)`, sizes scaled by the median standard error of the scan.
/// With `max` the grid's largest value instead of the mean.
pub fn jump_mixture_stat(scan: &StepScan, boundary_only: bool, max: bool) -> f64 {
    let mut se = scan.se.clone();
    se.sort_by(|a, b| a.total_cmp(b));
    let Some(&med) = se.get(se.len() / 2) else {
        return 0.0;
    };
    let vals: Vec<f64> = JUMP_MIX_SIZES
        .iter()
        .flat_map(|&k| {
            JUMP_MIX_COUNTS
                .iter()
                .map(move |&m| jump_mixture_log_bf(scan, k * med, m, boundary_only))
        })
        .collect();
    if max {
        vals.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    } else {
        log_mean_exp(&vals)
    }
}

/// Lowest z of the forward search whose steps [`jump_forward_mixture_stat`] scores.
pub const JUMP_FWD_Z_MIN: f64 = 2.5;

/// The spike-and-slab mixture of [`jump_mixture_log_bf`] on the steps forward selection found
/// (their z scores at selection, each conditional on the steps chosen before it) instead of the
/// single-step scan: `sum_k ln(1 - p + p B(z_k))`, `B(z) = (1 + r)^(-1/2) exp(z^2 r / (2 (1 +
/// r)))`, `r = rms_rel^2` (the prior rms over the median single-step standard error), `p =
/// count / n_candidates`. The positions not chosen are left out (their `B` is near 1).
/// Conditioning on the chosen steps stops one local wander of the noise from counting as many
/// independent steps, which the scan version does (docs/gap.md, "Mixture statistics").
pub fn jump_forward_mixture_log_bf(
    z_scores: &[f64],
    n_candidates: usize,
    rms_rel: f64,
    count: f64,
) -> f64 {
    if n_candidates == 0
        || rms_rel.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || count.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
    {
        return 0.0;
    }
    let p = (count / n_candidates as f64).min(0.5);
    let r = rms_rel * rms_rel;
    let (lp, lq) = (p.ln(), (1.0 - p).ln());
    z_scores
        .iter()
        .map(|z| {
            let lb = -0.5 * (1.0 + r).ln() + z * z * r / (2.0 * (1.0 + r));
            let m = lq.max(lp + lb);
            m + ((lq - m).exp() + (lp + lb - m).exp()).ln()
        })
        .sum()
}

/// [`jump_forward_mixture_log_bf`] with the prior's size and count unknown: `ln` of the mean over
/// `JUMP_MIX_SIZES x JUMP_MIX_COUNTS` of its likelihood ratio.
pub fn jump_forward_mixture_stat(z_scores: &[f64], n_candidates: usize) -> f64 {
    let vals: Vec<f64> = JUMP_MIX_SIZES
        .iter()
        .flat_map(|&k| {
            JUMP_MIX_COUNTS
                .iter()
                .map(move |&m| jump_forward_mixture_log_bf(z_scores, n_candidates, k, m))
        })
        .collect();
    log_mean_exp(&vals)
}
