//! The jump test on its own run: the first search's random walk with the strongest steps taken
//! out, and the rule's level set by a parametric bootstrap of that whole procedure under the
//! run's Gaussian null (docs/gap.md, "The jump rule on its own run (session 28)").
//!
//! [`detect_steps`](super::steps::detect_steps) keeps jumps by the group rule "at least `k`
//! steps at `z >= z_crit[k - 1]`", the z scores from forward selection on the block-mean
//! differences whitened with the model's covariance. That covariance holds the rate random
//! walk's `K^2`, read as the larger of the curve's and the block means' own maximum likelihood
//! value. Both take up the jumps' share (`sum s^2 / T_run`) when jumps are there, and the
//! jumps then hide in the very wander they add. So the procedure here is:
//! 1. `k0`: the larger of the reference `K^2` (`c[3]` of [`JumpNull::new`]; `detect_steps`
//!    passes the run's first `K^2`, the larger of the curve's and the block means' own) and the
//!    block means' own;
//! 2. forward selection of as many steps as the rule looks at (`z_crit.len()`), at `k0`, with
//!    their sizes fitted jointly with the drift;
//! 3. `k1`: the larger of the reference `K^2` less those steps' share (at least a quarter of
//!    it) and the block means' own with those steps taken out, the rule the re-search of kept
//!    jumps has used since session 21 (with the curve's `K^2` there);
//! 4. forward selection at `k1`; the rule's excess `S = max_k (z_(k) - z_crit[k - 1])` (`z_(k)`
//!    the `k`-th largest z; the fixed rule holds when `S >= 0`).
//!
//! Step 3 lowers `K^2` on clean runs too (the strongest steps of pure noise are taken out), so
//! the fixed rule at `k1` flags more clean runs than at `k0`. The shift `d` of the rule is the
//! `1 - alpha` quantile of `S` over runs drawn from the fitted model at `k0` (Davison and Hinkley
//! 1997, section 4.2: a parametric bootstrap through the same estimation of `K^2`, the
//! reference held at the run's), and the run's rule is `z_crit + d`.
//!
//! Everything is computed in the rotation of [`KRotation`], where the covariance of the
//! differences is `I + k diag(lambda)` for every `K^2 = k`: inner products at `k` carry the
//! weights `1 / (1 + k lambda_i)`, and a null run is `z_i ~ N(0, 1 + k0 lambda_i)`. Forward
//! selection updates each candidate's residual inner product and squared norm by Gram-Schmidt
//! from the Gram column of the step chosen: the drop of the residual sum of squares is
//! `(u_i'r)^2 / |u_i|^2` with `u_i` off the drift and the steps chosen so far, the drop
//! [`forward_steps`](super::steps::forward_steps) computes by projecting each column. `K^2` is
//! snapped to a grid of [`K_SNAP_PER_DECADE`] per decade so that the weighted quantities are
//! shared between null runs.

use super::effects::EffectParams;
use super::k_profile::KRotation;
use super::steps::k2_with_steps_out;
use nalgebra::{DMatrix, DVector};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::HashMap;

/// Null runs of [`JumpNull::shift`]: the shift at 1% is the 5th largest of 499.
pub const STEP_NULL_DRAWS: usize = 499;
/// Seed of the null runs (fixed: the same run always gets the same rule).
const STEP_NULL_SEED: u64 = 0x5e55_1028;
/// `K^2` is rounded to this many points per decade (a factor 1.1 between neighbours).
pub const K_SNAP_PER_DECADE: f64 = 24.0;

/// `K^2` rounded to the grid of [`K_SNAP_PER_DECADE`] per decade (0 stays 0).
fn snap(k: f64) -> f64 {
    if k > 0.0 && k.is_finite() {
        10f64.powf((k.log10() * K_SNAP_PER_DECADE).round() / K_SNAP_PER_DECADE)
    } else {
        0.0
    }
}

/// The weighted inner products at one `K^2`: for weights `w_j = 1 / (1 + k lambda_j)`, each
/// candidate's squared norm off the drift, its inner product with the drift, and the Gram
/// columns (off the drift) asked for so far.
struct Weighted {
    w: DVector<f64>,
    /// `<u_0, u_0>_w`, the drift's squared norm.
    d0: f64,
    /// `<u_0, u_i>_w`.
    g0: DVector<f64>,
    /// `<u_i, u_i>_w - <u_0, u_i>_w^2 / d0`.
    norm2: Vec<f64>,
    cols: HashMap<usize, Vec<f64>>,
}

/// The jump test's procedure and its bootstrap for one run's model (module doc).
pub struct JumpNull {
    rot: KRotation,
    /// Rotated candidates `u_i = U' L^-1 p_i` (`n x m`), in the order of `step_candidates`.
    cand: DMatrix<f64>,
    /// Each candidate's step time in blocks.
    pos: Vec<f64>,
    /// The rotated drift column `U' L^-1 1`.
    drift: DVector<f64>,
    /// The rule's `z_crit` (non-increasing).
    z_crit: Vec<f64>,
    /// The reference `K^2` (u^2/s^3).
    k2_curve: f64,
    /// Upper end of the block means' own `K^2` (0: not read off the block means).
    k_hi: f64,
    t_run: f64,
    /// The weighted quantities by snapped `K^2` (its bits).
    weighted: HashMap<u64, Weighted>,
}

/// What the procedure reads off one run (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JumpStat {
    /// `k0` (u^2/s^3), snapped.
    pub k0: f64,
    /// `k1` (u^2/s^3), snapped: the `K^2` of the search the rule decides on.
    pub k1: f64,
    /// The rule's excess `S` at `k1`.
    pub excess: f64,
}

impl JumpNull {
    /// The procedure for `n_blocks` block means of `block_s` seconds under the five terms `c`
    /// (`c[3]` the reference `K^2`, module doc) plus the stationary `effects`, the rule `z_crit`, and the
    /// block means' own `K^2` read on `[0, k_hi]` (0: not read). `None` when the covariance is
    /// not positive definite, there are fewer than 3 blocks or `z_crit` is empty.
    pub fn new(
        n_blocks: usize,
        block_s: f64,
        c: &[f64; 5],
        effects: &[EffectParams],
        z_crit: &[f64],
        k_hi: f64,
    ) -> Option<Self> {
        let rot = KRotation::new(n_blocks, block_s, c, effects)?;
        Self::with_rotation(rot, n_blocks, block_s, c[3], z_crit, k_hi).ok()
    }

    /// [`Self::new`] on a rotation already built for the model ([`KRotation::new`] of the same
    /// `n_blocks`, `block_s`, terms and effects), with the reference `K^2` `k2_ref`. The
    /// rotation is handed back when the procedure cannot be formed (`z_crit` empty).
    pub fn with_rotation(
        rot: KRotation,
        n_blocks: usize,
        block_s: f64,
        k2_ref: f64,
        z_crit: &[f64],
        k_hi: f64,
    ) -> Result<Self, KRotation> {
        if z_crit.is_empty() {
            return Err(rot);
        }
        let Some(m_rot) = rot.matrix() else {
            return Err(rot);
        };
        let n = m_rot.ncols();
        let (cols, pos): (Vec<DVector<f64>>, Vec<f64>) =
            super::steps::step_candidates(&m_rot).unzip();
        let drift = &m_rot * DVector::from_element(n, 1.0);
        Ok(Self {
            rot,
            cand: DMatrix::from_columns(&cols),
            pos,
            drift,
            z_crit: z_crit.to_vec(),
            k2_curve: k2_ref.max(0.0),
            k_hi,
            t_run: n_blocks as f64 * block_s,
            weighted: HashMap::new(),
        })
    }

    /// The rotation the procedure works in.
    pub fn rotation(&self) -> &KRotation {
        &self.rot
    }

    /// The rotated differences of `block_means` (as many as the procedure was built for).
    pub fn rotate(&self, block_means: &[f64]) -> Option<DVector<f64>> {
        let n = self.drift.len();
        if block_means.len() != n + 1 {
            return None;
        }
        let d = DVector::from_iterator(n, block_means.windows(2).map(|p| p[1] - p[0]));
        self.rot.rotate(d)
    }

    /// The block means' own maximum likelihood `K^2` of the rotated differences `z`, 0 when not
    /// read.
    fn k2_blocks(&self, z: &DVector<f64>) -> f64 {
        if self.k_hi > 0.0 {
            self.rot
                .max_likelihood_k2_rotated(z, &self.drift, self.k_hi)
                .unwrap_or(0.0)
        } else {
            0.0
        }
    }

    fn weighted(&mut self, k: f64) -> &mut Weighted {
        weighted_at(
            &mut self.weighted,
            &self.cand,
            &self.drift,
            &self.rot.lambda,
            k,
        )
    }

    /// Forward selection of `steps` steps at `K^2 = k` on the rotated differences `z`: the
    /// candidates chosen, in order, and their z scores.
    fn forward(&mut self, k: f64, z: &DVector<f64>, steps: usize) -> (Vec<usize>, Vec<f64>) {
        let Self {
            cand,
            drift,
            rot,
            weighted,
            ..
        } = self;
        let m = cand.ncols();
        let wt = weighted_at(weighted, cand, drift, &rot.lambda, k);
        let wz = z.component_mul(&wt.w);
        let a0 = drift.dot(&wz);
        let mut corr: Vec<f64> = cand
            .tr_mul(&wz)
            .iter()
            .zip(wt.g0.iter())
            .map(|(a, g)| a - g * a0 / wt.d0)
            .collect();
        let mut norm2 = wt.norm2.clone();
        let mut chosen: Vec<usize> = Vec::with_capacity(steps);
        let mut proj: Vec<Vec<f64>> = Vec::with_capacity(steps);
        let mut zs = Vec::with_capacity(steps);
        for _ in 0..steps {
            let best = (0..m)
                .filter(|i| !chosen.contains(i) && norm2[*i] > 1e-12 * wt.norm2[*i])
                .map(|i| (i, corr[i] * corr[i] / norm2[i]))
                .max_by(|x, y| x.1.total_cmp(&y.1));
            let Some((b, drop)) = best else { break };
            zs.push(drop.sqrt());
            let nb = norm2[b].sqrt();
            let qy = corr[b] / nb;
            let g = wt.gram_column(cand, b);
            let row: Vec<f64> = (0..m)
                .map(|i| {
                    let prior: f64 = proj.iter().map(|p| p[b] * p[i]).sum();
                    (g[i] - prior) / nb
                })
                .collect();
            for i in 0..m {
                corr[i] -= row[i] * qy;
                norm2[i] -= row[i] * row[i];
            }
            proj.push(row);
            chosen.push(b);
        }
        (chosen, zs)
    }

    /// The sizes (u/s) of the steps `chosen`, fitted jointly with the drift by weighted least
    /// squares at `K^2 = k`.
    fn sizes(&mut self, k: f64, z: &DVector<f64>, chosen: &[usize]) -> Option<Vec<f64>> {
        let w = self.weighted(k).w.clone();
        let mut cols = vec![self.drift.clone()];
        cols.extend(chosen.iter().map(|&i| self.cand.column(i).into_owned()));
        let x = DMatrix::from_columns(&cols);
        let xw = DMatrix::from_fn(x.nrows(), x.ncols(), |r, c| x[(r, c)] * w[r]);
        let beta = (xw.tr_mul(&x)).try_inverse()? * xw.tr_mul(z);
        Some(beta.iter().skip(1).copied().collect())
    }

    /// The procedure on the rotated differences `z` (module doc, steps 1-4).
    pub fn statistic(&mut self, z: &DVector<f64>) -> JumpStat {
        let k0 = snap(self.k2_curve.max(self.k2_blocks(z)));
        let steps = self.z_crit.len();
        let (top, _) = self.forward(k0, z, steps);
        let sizes = self.sizes(k0, z, &top).unwrap_or_default();
        let mut rest = z.clone();
        for (&i, s) in top.iter().zip(&sizes) {
            rest -= self.cand.column(i) * *s;
        }
        let k1 = snap(k2_with_steps_out(
            self.k2_curve,
            &sizes,
            self.t_run,
            self.k2_blocks(&rest),
        ));
        let (_, zs) = self.forward(k1, z, steps);
        JumpStat {
            k0,
            k1,
            excess: rule_excess(&zs, &self.z_crit),
        }
    }

    /// The shift `d` that puts the rule at level `alpha` (module doc): the
    /// `ceil(alpha (draws + 1))`-th largest `S` of [`STEP_NULL_DRAWS`] runs drawn at `K^2 = k0`.
    /// `None` unless `0 < alpha < 1`.
    pub fn shift(&mut self, k0: f64, alpha: f64) -> Option<f64> {
        if !(alpha > 0.0 && alpha < 1.0) {
            return None;
        }
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(STEP_NULL_SEED);
        let sd: Vec<f64> = self
            .rot
            .lambda
            .iter()
            .map(|l| (1.0 + k0 * l).sqrt())
            .collect();
        let mut s: Vec<f64> = (0..STEP_NULL_DRAWS)
            .map(|_| {
                let z = DVector::from_iterator(
                    sd.len(),
                    sd.iter().map(|v| {
                        let x: f64 = StandardNormal.sample(&mut rng);
                        v * x
                    }),
                );
                self.statistic(&z).excess
            })
            .collect();
        s.sort_by(|a, b| b.total_cmp(a));
        let k = ((alpha * (STEP_NULL_DRAWS + 1) as f64).ceil() as usize).clamp(1, STEP_NULL_DRAWS);
        Some(s[k - 1])
    }

    /// The first `steps` z scores of forward selection on `block_means` at `K^2 = k` (snapped),
    /// in the order chosen, with the chosen steps' times in blocks: what
    /// [`forward_steps`](super::steps::forward_steps) finds with `k` in the model. `None` when
    /// the count of block means does not match.
    pub fn forward_z(
        &mut self,
        k: f64,
        block_means: &[f64],
        steps: usize,
    ) -> Option<(Vec<f64>, Vec<f64>)> {
        let z = self.rotate(block_means)?;
        let (chosen, zs) = self.forward(snap(k), &z, steps);
        Some((zs, chosen.iter().map(|&i| self.pos[i]).collect()))
    }
}

/// The [`Weighted`] quantities at the snapped `K^2 = k`, computed on first use.
fn weighted_at<'a>(
    cache: &'a mut HashMap<u64, Weighted>,
    cand: &DMatrix<f64>,
    drift: &DVector<f64>,
    lambda: &[f64],
    k: f64,
) -> &'a mut Weighted {
    cache.entry(k.to_bits()).or_insert_with(|| {
        let w = DVector::from_iterator(lambda.len(), lambda.iter().map(|l| 1.0 / (1.0 + k * l)));
        let wd = drift.component_mul(&w);
        let d0 = drift.dot(&wd);
        let g0 = cand.tr_mul(&wd);
        let norm2 = cand
            .column_iter()
            .zip(g0.iter())
            .map(|(u, g)| {
                let s: f64 = u.iter().zip(w.iter()).map(|(x, wi)| x * x * wi).sum();
                s - g * g / d0
            })
            .collect();
        Weighted {
            w,
            d0,
            g0,
            norm2,
            cols: HashMap::new(),
        }
    })
}

impl Weighted {
    /// Column `b` of the weighted Gram matrix of the candidates off the drift.
    fn gram_column(&mut self, cand: &DMatrix<f64>, b: usize) -> Vec<f64> {
        let (w, g0, d0) = (&self.w, &self.g0, self.d0);
        self.cols
            .entry(b)
            .or_insert_with(|| {
                let wb = cand.column(b).component_mul(w);
                cand.tr_mul(&wb)
                    .iter()
                    .zip(g0.iter())
                    .map(|(x, g)| x - g * g0[b] / d0)
                    .collect()
            })
            .clone()
    }
}

/// The group rule's excess `S = max_k (z_(k) - z_crit[k - 1])` over the z scores `zs` (any
/// order): the rule of [`JumpFinding::accepted`](super::steps::JumpFinding::accepted) holds
/// exactly when `S >= 0`. `-inf` when there are no z scores.
pub fn rule_excess(zs: &[f64], z_crit: &[f64]) -> f64 {
    let mut s = zs.to_vec();
    s.sort_by(|a, b| b.total_cmp(a));
    s.iter()
        .zip(z_crit)
        .map(|(z, c)| z - c)
        .fold(f64::NEG_INFINITY, f64::max)
}
