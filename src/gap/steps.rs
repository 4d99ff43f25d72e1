//! Bias jumps found in time (docs/theory.md sections 3 and 5): steps in the block-mean rate by
//! generalised least squares with the fitted model's noise covariance ([`super::block_cov`]),
//! forward selection and the acceptance rule of [`JumpFinding::accepted`]; the single-step scan
//! and standard errors the calibration and [`super::jump_mixture`] use.

use super::block_cov::{block_diff_covariance, usable_block_means};
use super::effects::EffectParams;
use super::k_profile::KRotation;
use super::step_null::JumpNull;
use nalgebra::{DMatrix, DVector};

/// Bias jumps found in the block means.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JumpFinding {
    /// Times of the jumps (s from the first block the block tests kept: the run's start unless
    /// short blocks at its start were left out, `EvidenceSnapshot::block_first`).
    pub times_s: Vec<f64>,
    /// Estimated sizes (u/s).
    pub sizes: Vec<f64>,
    /// The z score of each jump when forward selection added it.
    pub z_scores: Vec<f64>,
    /// Block length used (s).
    pub block_s: f64,
}

impl JumpFinding {
    /// The steps as sample indices (at `tau0_s`) and sizes (u/s), with steps less than 1.5
    /// blocks apart merged into one: a jump inside a block is split by the search over two
    /// differences. A merged step has the summed size, at its members' |size|-weighted time.
    pub fn merged_steps(&self, tau0_s: f64) -> (Vec<u64>, Vec<f64>) {
        let mut order: Vec<usize> = (0..self.sizes.len()).collect();
        order.sort_by(|&a, &b| self.times_s[a].total_cmp(&self.times_s[b]));
        // (|size|-weighted time sum, weight, size) per merged step.
        let mut merged: Vec<(f64, f64, f64)> = Vec::new();
        let mut last_t = f64::NEG_INFINITY;
        for i in order {
            let (t, sz) = (self.times_s[i], self.sizes[i]);
            match merged.last_mut() {
                Some(g) if t - last_t < 1.5 * self.block_s => {
                    g.0 += t * sz.abs();
                    g.1 += sz.abs();
                    g.2 += sz;
                }
                _ => merged.push((t * sz.abs(), sz.abs(), sz)),
            }
            last_t = t;
        }
        let positions = merged
            .iter()
            .map(|g| (g.0 / g.1.max(f64::MIN_POSITIVE) / tau0_s).round().max(0.0) as u64)
            .collect();
        (positions, merged.iter().map(|g| g.2).collect())
    }

    /// `block_means` (u/s, blocks of [`Self::block_s`]) with these steps taken out: a step of
    /// size `s` at time `t` lowers each block after it by `s` and the block it falls in by `s`
    /// times the share of that block after `t`.
    pub fn remove_from(&self, block_means: &[f64]) -> Vec<f64> {
        block_means
            .iter()
            .enumerate()
            .map(|(i, &b)| {
                b - self
                    .times_s
                    .iter()
                    .zip(&self.sizes)
                    .map(|(&t, &s)| s * self.step_share(i, t))
                    .sum::<f64>()
            })
            .collect()
    }

    /// Each jump's block curve over `n_blocks` blocks: its size on each block after it, and on
    /// the block it falls in times the share of that block after it (what [`Self::remove_from`]
    /// takes out, one jump at a time).
    pub fn step_curves(&self, n_blocks: usize) -> Vec<Vec<f64>> {
        self.times_s
            .iter()
            .zip(&self.sizes)
            .map(|(&t, &s)| (0..n_blocks).map(|i| s * self.step_share(i, t)).collect())
            .collect()
    }

    /// The share of block `i` after time `t` (s): 0 before it, 1 after it.
    fn step_share(&self, i: usize, t: f64) -> f64 {
        let end = (i + 1) as f64 * self.block_s;
        ((end - t) / self.block_s).clamp(0.0, 1.0)
    }

    /// The jumps that pass the rule "at least `k` jumps with `z >= z_crit[k - 1]`" for the
    /// largest `k` it holds for (`z_crit` non-increasing): those with `z >= z_crit[k - 1]`.
    /// None pass when the rule holds for no `k`.
    pub fn accepted(&self, z_crit: &[f64]) -> JumpFinding {
        let mut zs = self.z_scores.clone();
        zs.sort_by(|a, b| b.total_cmp(a));
        let level = (1..=z_crit.len())
            .rev()
            .find(|&k| zs.get(k - 1).is_some_and(|&z| z >= z_crit[k - 1]))
            .map_or(f64::INFINITY, |k| z_crit[k - 1]);
        let keep: Vec<usize> = (0..self.z_scores.len())
            .filter(|&i| self.z_scores[i] >= level)
            .collect();
        JumpFinding {
            times_s: keep.iter().map(|&i| self.times_s[i]).collect(),
            sizes: keep.iter().map(|&i| self.sizes[i]).collect(),
            z_scores: keep.iter().map(|&i| self.z_scores[i]).collect(),
            block_s: self.block_s,
        }
    }
}

/// Bias jumps by generalised least squares on the first differences of the block-mean rate
/// (docs/theory.md sections 3 and 5): `d = r 1 + sum_j s_j p_j + noise`, the noise covariance from
/// the fitted model (five terms `c`, flicker and random walk included, plus the stationary
/// `effects`: [`block_diff_covariance`]). A jump at a block boundary is a spike `p = e_k` in `d`; one
/// inside block `k` splits over `d_{k-1}` and `d_k` (`p = (e_{k-1} + e_k) / 2`). Forward
/// selection: the candidate whose column brings the largest drop of the whitened residual sum of
/// squares is added while the drop's square root (a z score) exceeds the last (lowest) entry of
/// `z_crit`, with all the sizes refitted jointly each time. The jumps kept are those of
/// [`JumpFinding::accepted`]: at least `k` of them at `z >= z_crit[k - 1]` (one strong jump, or
/// several moderate ones: a test of the jumps as a whole, since with small jumps one at a time
/// none may stand out).
///
/// The random walk's `K^2` (`c[3]`, the curve's fit) is the null's nuisance. The curve's fit
/// absorbs the jumps (their share is `sum s^2 / T_run`), and it can also leave `K` out (often at
/// 0, a rate ramp or the flicker taking its place), where the search reads the block means' own
/// wander as steps. So the `K^2` of each search is the larger of the curve's less the kept
/// jumps' share (at least a quarter of the curve's) and the block means' own maximum likelihood
/// value with the kept jumps taken out ([`KRotation::max_likelihood_k2`], on `[0, k_hi]`; `k_hi` the curve's upper
/// bound, 0 to leave the profile out); the search is run again while that `K^2` moves (twice at
/// most). With `alpha > 0` (since session 28) the first search's `K^2` already has the
/// strongest candidates taken out, as many as `z_crit` has entries, as if kept (both the
/// curve's `K^2` and the block means' own take up the jumps' share, which hid them), and
/// `z_crit` is shifted to the level `alpha` by a parametric bootstrap of that procedure
/// ([`JumpNull`]; docs/gap.md, "The jump rule on its own run (session 28)"); `alpha = 0` is the
/// rule of sessions 21-27. Returns `None` when the series is too short or `z_crit` is empty.
/// (Mixture statistics
/// for the presence test, [`jump_mixture_stat`](super::jump_mixture::jump_mixture_stat) and
/// [`jump_forward_mixture_stat`](super::jump_mixture::jump_forward_mixture_stat), were measured
/// against this rule and not adopted: docs/gap.md, "Mixture statistics".)
pub fn detect_steps(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    z_crit: &[f64],
    k_hi: f64,
    alpha: f64,
) -> Option<JumpFinding> {
    if !usable_block_means(block_means) {
        return None;
    }
    z_crit.last()?;
    let t_run = block_means.len() as f64 * block_s;
    let k2_curve = c[3];
    // The rotation depends on the model and the effects only: one for every re-search, and
    // the jump procedure's (`alpha`) works in it too.
    let mut rot = (k_hi > 0.0 || alpha > 0.0)
        .then(|| KRotation::new(block_means.len(), block_s, c, effects))
        .flatten();
    let k2_blocks = |rot: Option<&KRotation>, found: &JumpFinding| -> f64 {
        rot.filter(|_| k_hi > 0.0)
            .and_then(|r| r.max_likelihood_k2(&found.remove_from(block_means), k_hi))
            .unwrap_or(0.0)
    };
    let mut c = *c;
    c[3] = k2_curve.max(k2_blocks(rot.as_ref(), &JumpFinding::default()));
    // With `alpha`, the procedure of `step_null`: the first search's K^2 with the strongest
    // candidates taken out (both the curve's K^2 and the block means' own take up the jumps'
    // share and hid them), and the rule shifted to its level on the run's own null.
    let mut shift = 0.0;
    let mut null = None;
    if alpha > 0.0 {
        if let Some(r) = rot.take() {
            match JumpNull::with_rotation(r, block_means.len(), block_s, c[3], z_crit, k_hi) {
                Ok(mut n) => {
                    if let Some(z) = n.rotate(block_means) {
                        let st = n.statistic(&z);
                        c[3] = st.k1;
                        shift = n.shift(st.k0, alpha).unwrap_or(0.0);
                    }
                    null = Some(n);
                }
                Err(r) => rot = Some(r),
            }
        }
    }
    let rot = null.as_ref().map(JumpNull::rotation).or(rot.as_ref());
    let k2_without = |found: &JumpFinding| {
        k2_with_steps_out(k2_curve, &found.sizes, t_run, k2_blocks(rot, found))
    };
    let z_crit: Vec<f64> = z_crit.iter().map(|z| z + shift).collect();
    let z_crit = z_crit.as_slice();
    let z_min = *z_crit.last()?;
    let mut found = step_search(block_means, block_s, &c, effects, z_min)?.accepted(z_crit);
    for _ in 0..2 {
        let k2 = k2_without(&found);
        if (k2 - c[3]).abs() <= 0.02 * k2.max(c[3]) {
            break;
        }
        c[3] = k2;
        found = step_search(block_means, block_s, &c, effects, z_min)?.accepted(z_crit);
    }
    Some(found)
}

/// The random walk's `K^2` (u^2/s^3) with steps of `sizes` (u/s) taken out of a run of
/// `t_run_s`: the larger of `k2_ref` less their share `sum s^2 / T_run` (at least a quarter of
/// `k2_ref`) and `k2_blocks`, the block means' own maximum likelihood value without them
/// (session 21's rule for kept jumps; [`JumpNull`] applies it before the first search).
pub(super) fn k2_with_steps_out(k2_ref: f64, sizes: &[f64], t_run_s: f64, k2_blocks: f64) -> f64 {
    let share: f64 = sizes.iter().map(|s| s * s).sum::<f64>() / t_run_s;
    (k2_ref - share).max(0.25 * k2_ref).max(k2_blocks)
}

/// Standard error (u/s) of the GLS estimate of a single step at each block boundary, with the
/// drift column in the design, under the model `c` plus `effects` ([`block_diff_covariance`]):
/// `1 / |P u_k|`, `u_k` the whitened spike column and `P` the projection off the whitened drift.
/// A step must be about `z_crit` of these to be found by [`detect_steps`] (docs/gap.md uses it
/// to size the smallest findable jump).
pub fn step_standard_errors(
    n_blocks: usize,
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<Vec<f64>> {
    let linv = whitening(n_blocks, block_s, c, effects)?;
    let n = linv.nrows();
    let ones = &linv * DVector::from_element(n, 1.0);
    let q = &ones / ones.norm();
    Some(
        (0..n)
            .map(|k| {
                let col = linv.column(k).into_owned();
                let u = &col - &q * q.dot(&col);
                1.0 / u.norm()
            })
            .collect(),
    )
}

/// The steps forward selection finds down to `z_min`, with their z scores, on the covariance of
/// `c` as given (no acceptance rule, no re-estimation of `K`, no shift of the rule): the first
/// pass of [`detect_steps`] when `c` holds that pass's `K^2`, which is how the rule was
/// calibrated (docs/gap.md).
pub fn forward_steps(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    z_min: f64,
) -> Option<JumpFinding> {
    if !usable_block_means(block_means) {
        return None;
    }
    step_search(block_means, block_s, c, effects, z_min)
}

fn step_search(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    z_crit: f64,
) -> Option<JumpFinding> {
    let (linv, yw, ones) = whitened_block_diffs(block_means, block_s, c, effects)?;
    let n = yw.len();
    // `pos[i]` is candidate i's jump time in blocks.
    let (cols, pos): (Vec<DVector<f64>>, Vec<f64>) = step_candidates(&linv).unzip();
    let mut chosen: Vec<usize> = Vec::new();
    let max_jumps = (n / 8).max(1);
    let fit = |chosen: &[usize]| -> Option<(DVector<f64>, DVector<f64>)> {
        let mut xs = vec![ones.clone()];
        xs.extend(chosen.iter().map(|&i| cols[i].clone()));
        let x = DMatrix::from_columns(&xs);
        let beta = (x.transpose() * &x).try_inverse()? * x.transpose() * &yw;
        let r = &yw - &x * &beta;
        Some((beta, r))
    };
    let (_, mut resid) = fit(&chosen)?;
    let mut z_at: Vec<f64> = Vec::new();
    let mut q = vec![ones.clone() / ones.norm()];
    while chosen.len() < max_jumps {
        // Drop of the RSS for each candidate: (u' r)^2 / |u|^2, u the column projected off
        // the current design (orthonormal basis q).
        let mut best: Option<(usize, f64)> = None;
        for (i, col) in cols.iter().enumerate() {
            if chosen.contains(&i) {
                continue;
            }
            let mut u = col.clone();
            for qv in &q {
                let a = qv.dot(&u);
                u -= qv * a;
            }
            let nu = u.norm_squared();
            if nu <= 1e-12 * col.norm_squared() {
                continue;
            }
            let drop = u.dot(&resid).powi(2) / nu;
            if best.is_none_or(|b| drop > b.1) {
                best = Some((i, drop));
            }
        }
        let Some((i, drop)) = best else { break };
        if drop.sqrt() < z_crit {
            break;
        }
        let mut u = cols[i].clone();
        for qv in &q {
            let a = qv.dot(&u);
            u -= qv * a;
        }
        let nu = u.norm();
        q.push(u / nu);
        chosen.push(i);
        z_at.push(drop.sqrt());
        resid = fit(&chosen)?.1;
    }
    let (beta, _) = fit(&chosen)?;
    let mut jumps: Vec<(f64, f64, f64)> = chosen
        .iter()
        .enumerate()
        .map(|(j, &i)| (pos[i] * block_s, beta[j + 1], z_at[j]))
        .collect();
    jumps.sort_by(|a, b| a.0.total_cmp(&b.0));
    Some(JumpFinding {
        times_s: jumps.iter().map(|j| j.0).collect(),
        sizes: jumps.iter().map(|j| j.1).collect(),
        z_scores: jumps.iter().map(|j| j.2).collect(),
        block_s,
    })
}

/// Single-step evidence at every candidate position of [`detect_steps`] (the first search pass,
/// nothing chosen yet): the GLS z score of one step with the drift in the design, and its
/// standard error.
#[derive(Debug, Clone, PartialEq)]
pub struct StepScan {
    /// `u' y_w / |u|`, `u` the whitened candidate column projected off the whitened drift.
    pub z: Vec<f64>,
    /// `1 / |u|` (u/s): the standard error of the step's size.
    pub se: Vec<f64>,
    /// Whether the candidate is a step at a block boundary (otherwise inside a block).
    pub boundary: Vec<bool>,
}

/// The [`StepScan`] of the block means under the model `c` plus `effects` ([`block_diff_covariance`]),
/// with the candidates of [`detect_steps`] (spikes and halves in the block-mean differences).
/// `None` when the series is too short, not finite, or the covariance is not positive definite.
pub fn step_scan(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<StepScan> {
    if !usable_block_means(block_means) {
        return None;
    }
    let (linv, yw, ones) = whitened_block_diffs(block_means, block_s, c, effects)?;
    let n = yw.len();
    let q = &ones / ones.norm();
    let mut out = StepScan {
        z: Vec::with_capacity(2 * n),
        se: Vec::with_capacity(2 * n),
        boundary: Vec::with_capacity(2 * n),
    };
    for (col, pos) in step_candidates(&linv) {
        let u = &col - &q * q.dot(&col);
        let nu = u.norm();
        if nu > 1e-12 * col.norm() {
            out.z.push(u.dot(&yw) / nu);
            out.se.push(1.0 / nu);
            out.boundary.push(pos.fract() == 0.0);
        }
    }
    Some(out)
}

/// `L^-1`, with `L L'` the covariance of the differences of `n_blocks` block means under the
/// model ([`block_diff_covariance`]).
fn whitening(
    n_blocks: usize,
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<DMatrix<f64>> {
    let sigma = block_diff_covariance(n_blocks, block_s, c, effects)?;
    let n = sigma.nrows();
    sigma
        .cholesky()?
        .l()
        .solve_lower_triangular(&DMatrix::identity(n, n))
}

/// The block-mean differences whitened by the model covariance ([`block_diff_covariance`]):
/// `(L^-1, L^-1 d, L^-1 1)`, with `L L'` the covariance and `1` the drift column.
fn whitened_block_diffs(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<(DMatrix<f64>, DVector<f64>, DVector<f64>)> {
    let linv = whitening(block_means.len(), block_s, c, effects)?;
    let n = linv.nrows();
    let d = DVector::from_iterator(n, block_means.windows(2).map(|p| p[1] - p[0]));
    let yw = &linv * d;
    let ones = &linv * DVector::from_element(n, 1.0);
    Some((linv, yw, ones))
}

/// The step candidates' whitened columns with their jump times in blocks: a spike (a jump at
/// the boundary after block k, time k + 1) and, from the second block on, a half over two
/// differences (a jump inside block k, time k + 0.5).
pub(super) fn step_candidates(
    linv: &DMatrix<f64>,
) -> impl Iterator<Item = (DVector<f64>, f64)> + '_ {
    (0..linv.ncols()).flat_map(move |k| {
        let spike = (linv.column(k).into_owned(), k as f64 + 1.0);
        let half = (k > 0).then(|| ((linv.column(k - 1) + linv.column(k)) * 0.5, k as f64 + 0.5));
        std::iter::once(spike).chain(half)
    })
}
