//! The warm-up test with the rate random walk profiled on the block means (docs/gap.md, "The
//! warm-up's null level", session 12).
//!
//! [`fit_warmup`](super::warmup::fit_warmup) whitens the block-mean differences with one fixed
//! covariance, and since session 8 the diagnosis fixes its `K^2` at the curve's upper profile
//! bound. On a run of 10-20 minutes the curve cannot resolve `K` at all: the bound sits at its
//! ceiling, the `K` whose term alone reaches the longest tau, and a random walk that large hides
//! any warm-up of a minute or two (fog5k: 0 of 3 named where the oracle names 3). Here `K^2` is a
//! nuisance parameter fitted on the block means themselves, jointly with the drift under the
//! null and with the drift and the warm-up under the alternative, anywhere in `[0, k_hi]` (`k_hi`
//! the curve's bound): the profile likelihood ratio (e.g. Pawitan, "In All Likelihood",
//! section 10.3). Its p-value is a parametric bootstrap at the null's own estimate of `K^2`
//! (Davison and Hinkley 1997, section 4.2): the profile ratio depends on the nuisance far less
//! than the ratio at a fixed value does, so the plug-in null holds its level where the fixed
//! bound had to be the worst case.
//!
//! The covariance of the differences is linear in `K^2`, and one rotation makes it diagonal for
//! every `K^2` ([`KRotation`]): the Gaussian log likelihood at any `k` is then a weighted
//! least-squares fit, cheap enough to profile `k` on a grid for each bootstrap draw.

use super::block_cov::usable_block_means;
use super::effects::{EffectParams, Grid};
use super::k_profile::KRotation;
use super::warmup::{log_mean_exp, warmup_block_curve, WarmupFinding, WARMUP_NULL_DRAWS};
use nalgebra::{DMatrix, DVector};

/// Seed of the bootstrap draws (fixed: the same evidence gives the same p-value).
const PROFILE_NULL_SEED: u64 = 0x5e55_1012;

/// The warm-up test of [`fit_warmup`](super::warmup::fit_warmup) with the rate random walk's
/// `K^2` (u^2/s^3, `c[3]`'s unit) profiled over `[0, k_hi]` on the block means, jointly with the
/// fitted parameters under each hypothesis (module doc). `c` gives the other four terms (its
/// `c[3]` is not used), `effects` the stationary effects found so far. In the finding, `W(T)` is
/// the profile likelihood ratio `2 (max_k l1(T, k) - max_k l0(k))`, `log_bf` integrates it over the
/// scanned `T` as before, `null_scale` is the drift-alone residual scale at the null's `K^2`, and
/// `p_value` is the share of [`WARMUP_NULL_DRAWS`] bootstrap draws (Gaussian, at the null's
/// `K^2`, through the same profile and scan) whose `B` reaches the observed one.
pub fn fit_warmup_profiled(
    block_means: &[f64],
    block_s: f64,
    t_run_s: f64,
    c: &[f64; 5],
    k_hi: f64,
    effects: &[EffectParams],
) -> Option<(WarmupFinding, f64)> {
    if !usable_block_means(block_means) {
        return None;
    }
    let nb = block_means.len();
    let n = nb - 1;
    let rot = KRotation::new(nb, block_s, c, effects)?;
    let d: Vec<f64> = block_means.windows(2).map(|p| p[1] - p[0]).collect();
    let z = rot.rotate(DVector::from_column_slice(&d))?;
    let u1 = rot.rotate(DVector::from_element(n, 1.0))?;
    let grid = Grid {
        lo: block_s / 2.0,
        hi: t_run_s / 4.0,
        per_decade: 24.0,
    };
    let mut ts = Vec::new();
    let mut rows: Vec<DVector<f64>> = Vec::new();
    for t in grid.points() {
        let e = warmup_block_curve(n + 1, block_s, t);
        let de = DVector::from_iterator(n, e.windows(2).map(|p| p[1] - p[0]));
        rows.push(rot.rotate(de)?);
        ts.push(t);
    }
    if ts.is_empty() {
        return None;
    }
    let e_rows = DMatrix::from_fn(ts.len(), n, |i, j| rows[i][j]);
    let prof = Profile::new(&rot, u1, e_rows, k_hi)?;
    let obs = prof.evaluate(&z);
    let half_w: Vec<f64> = obs.w.iter().map(|w| w / 2.0).collect();
    let log_bf = log_mean_exp(&half_w);
    let k_null = prof.k[obs.k0];
    let null_scale = obs.rss0 / (n.max(2) - 1) as f64;
    let scaled: Vec<f64> = half_w.iter().map(|h| h / null_scale.max(1.0)).collect();
    let best = (0..ts.len()).max_by(|&i, &j| obs.w[i].total_cmp(&obs.w[j]))?;
    let p_value = prof.p_value(&rot.lambda, k_null, log_bf);
    Some((
        WarmupFinding {
            amplitude: obs.amp[best],
            time_constant_s: ts[best],
            w_stat: obs.w[best],
            log_bf,
            null_scale,
            log_bf_scaled: log_mean_exp(&scaled),
            p_value,
        },
        k_null,
    ))
}

/// The rotated design of the profile: per grid value of `K^2`, the weights `1 / (1 + k
/// lambda_i)`, the log determinant and the inverse normal matrices of `[1, e_T]` per `T`.
struct Profile {
    k: Vec<f64>,
    weights: Vec<DVector<f64>>,
    log_det: Vec<f64>,
    /// `1' W 1` per `k`.
    s11: Vec<f64>,
    /// Row-major 2x2 inverse normal matrix per `k`, then per `T`.
    inv: Vec<Vec<[f64; 3]>>,
    u1: DVector<f64>,
    e_rows: DMatrix<f64>,
}

/// The profile of one set of rotated differences.
struct Evaluated {
    /// `W(T)`, the profile likelihood ratio per scanned `T`.
    w: Vec<f64>,
    /// Warm-up amplitude (u/s) at each `T` at its profiled `K^2`.
    amp: Vec<f64>,
    /// Grid index of the null's `K^2`.
    k0: usize,
    /// The drift-alone weighted residual sum of squares there.
    rss0: f64,
}

impl Profile {
    fn new(rot: &KRotation, u1: DVector<f64>, e_rows: DMatrix<f64>, k_hi: f64) -> Option<Self> {
        let lambda = &rot.lambda;
        let k = rot.grid(k_hi);
        let (mut weights, mut log_det, mut s11, mut inv) = (vec![], vec![], vec![], vec![]);
        for &kv in &k {
            let w =
                DVector::from_iterator(lambda.len(), lambda.iter().map(|l| 1.0 / (1.0 + kv * l)));
            log_det.push(lambda.iter().map(|l| (kv * l).ln_1p()).sum::<f64>());
            let wu = u1.component_mul(&w);
            let a = u1.dot(&wu);
            let ew = &e_rows * &wu;
            let mut per_t = Vec::with_capacity(e_rows.nrows());
            for (ti, row) in e_rows.row_iter().enumerate() {
                let ee: f64 = row.iter().zip(w.iter()).map(|(e, wi)| e * e * wi).sum();
                let b = ew[ti];
                let det = a * ee - b * b;
                if det.is_nan() || det <= 0.0 {
                    // A column the drift already spans: no warm-up there.
                    per_t.push([f64::NAN; 3]);
                    continue;
                }
                per_t.push([ee / det, -b / det, a / det]);
            }
            s11.push(a);
            inv.push(per_t);
            weights.push(w);
        }
        if !(s11.iter().all(|v| *v > 0.0)) {
            return None;
        }
        Some(Self {
            k,
            weights,
            log_det,
            s11,
            inv,
            u1,
            e_rows,
        })
    }

    /// `W(T)` of rotated differences `z`: `max_k (-2 l1(T, k)) ` against `max_k (-2 l0(k))`.
    fn evaluate(&self, z: &DVector<f64>) -> Evaluated {
        let nt = self.e_rows.nrows();
        let (mut best0, mut k0, mut rss0_at) = (f64::NEG_INFINITY, 0, f64::NAN);
        let mut best1 = vec![f64::NEG_INFINITY; nt];
        let mut amp = vec![0.0; nt];
        for (ki, w) in self.weights.iter().enumerate() {
            let wz = z.component_mul(w);
            let szz = z.dot(&wz);
            let s1z = self.u1.dot(&wz);
            let rss0 = szz - s1z * s1z / self.s11[ki];
            let l0 = -self.log_det[ki] - rss0;
            if l0 > best0 {
                best0 = l0;
                k0 = ki;
                rss0_at = rss0;
            }
            let sez = &self.e_rows * &wz;
            for (ti, iv) in self.inv[ki].iter().enumerate() {
                if iv[0].is_nan() {
                    continue;
                }
                let q = iv[0] * s1z * s1z + 2.0 * iv[1] * s1z * sez[ti] + iv[2] * sez[ti] * sez[ti];
                let l1 = -self.log_det[ki] - (szz - q);
                if l1 > best1[ti] {
                    best1[ti] = l1;
                    amp[ti] = iv[1] * s1z + iv[2] * sez[ti];
                }
            }
        }
        // The alternative nests the null at every k, so W >= 0 up to rounding.
        let w = best1.iter().map(|b| (b - best0).max(0.0)).collect();
        Evaluated {
            w,
            amp,
            k0,
            rss0: rss0_at,
        }
    }

    /// Parametric bootstrap p-value of the observed `B` at `K^2 = k_null`: rotated differences
    /// `z_i ~ N(0, 1 + k_null lambda_i)` through the same profile and scan (the drift drops out
    /// of the ratio, so it is not drawn).
    fn p_value(&self, lambda: &[f64], k_null: f64, observed: f64) -> f64 {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        if !observed.is_finite() {
            return f64::NAN;
        }
        let sd: Vec<f64> = lambda.iter().map(|l| (1.0 + k_null * l).sqrt()).collect();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(PROFILE_NULL_SEED);
        let mut at_least = 0usize;
        for _ in 0..WARMUP_NULL_DRAWS {
            let z = DVector::from_iterator(
                sd.len(),
                sd.iter().map(|s| {
                    let x: f64 = StandardNormal.sample(&mut rng);
                    s * x
                }),
            );
            let e = self.evaluate(&z);
            let half: Vec<f64> = e.w.iter().map(|w| w / 2.0).collect();
            if log_mean_exp(&half) >= observed {
                at_least += 1;
            }
        }
        (1 + at_least) as f64 / (WARMUP_NULL_DRAWS + 1) as f64
    }
}
