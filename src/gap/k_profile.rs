//! The rate random walk's `K^2` (u^2/s^3) read off the block means themselves: the rotation that
//! makes the covariance of the block-mean differences diagonal for every `K^2`, and the maximum
//! likelihood `K^2` of the differences with the drift fitted (docs/gap.md, "The warm-up's null
//! level (session 12)" and "The jump test's random walk (session 21)").
//!
//! The covariance of the `n` differences is linear in `K^2`: `C(k) = C0 + k C1`, `C0` the other
//! four terms and the stationary effects, `C1` the random walk's per unit `K^2`
//! ([`block_diff_covariance`]). With `C0 = L L'` and `L^-1 C1 L^-T = U diag(lambda) U'`, the
//! rotated differences `z = U' L^-1 d` have the diagonal covariance `I + k diag(lambda)`, so the
//! Gaussian log likelihood at any `k`, the drift `beta` profiled out, is
//! `-2 l(k) = sum ln(1 + k lambda_i) + min_beta sum (z_i - u_i beta)^2 / (1 + k lambda_i)` up to
//! a constant (`u = U' L^-1 1`; a weighted least-squares fit; e.g. Pawitan, "In All
//! Likelihood", section 10.3, for the profile over a nuisance parameter).

use super::block_cov::{block_diff_covariance, usable_block_means};
use super::effects::EffectParams;
use super::problem::golden_section;
use nalgebra::{DMatrix, DVector};

/// Grid points per decade of `K^2` (a step of a factor 1.47).
const K_PER_DECADE: f64 = 6.0;
/// The grid ends where the random walk's largest whitened share `k lambda_max` is this small (it
/// then changes the likelihood by far less than one unit); `k = 0` is always on it.
const K_FLOOR_SHARE: f64 = 1e-3;
/// At most this many nonzero grid points of `K^2`.
const K_MAX_POINTS: usize = 60;
/// Golden-section steps that polish the grid's best `K^2` (in `ln K^2`, within its neighbours).
const K_POLISH_STEPS: usize = 20;

/// The rotation of the block-mean differences that diagonalises `C(k)` for every `k` (module doc).
pub struct KRotation {
    /// `lambda_i >= 0`, the random walk's whitened variances per unit `K^2`.
    pub lambda: Vec<f64>,
    l: DMatrix<f64>,
    ut: DMatrix<f64>,
}

impl KRotation {
    /// The rotation for `n_blocks` block means of `block_s` seconds under the five terms `c`
    /// (its `c[3]` is not used) plus the stationary `effects`. `None` when the covariance is not
    /// positive definite or there are fewer than 3 blocks.
    pub fn new(
        n_blocks: usize,
        block_s: f64,
        c: &[f64; 5],
        effects: &[EffectParams],
    ) -> Option<Self> {
        let mut c0 = *c;
        c0[3] = 0.0;
        let chol = block_diff_covariance(n_blocks, block_s, &c0, effects)?.cholesky()?;
        let c1 = block_diff_covariance(n_blocks, block_s, &[0.0, 0.0, 0.0, 1.0, 0.0], &[])?;
        let l = chol.l();
        // L^-1 C1 L^-T, symmetrised against rounding.
        let a = l.solve_lower_triangular(&c1)?;
        let m = l.solve_lower_triangular(&a.transpose())?;
        let m = (&m + m.transpose()) * 0.5;
        let eig = m.symmetric_eigen();
        let lambda = eig.eigenvalues.iter().map(|v| v.max(0.0)).collect();
        Some(Self {
            lambda,
            l,
            ut: eig.eigenvectors.transpose(),
        })
    }

    /// `U' L^-1` (`n x n`, `n` the differences): the rotation as a matrix.
    pub fn matrix(&self) -> Option<DMatrix<f64>> {
        let n = self.lambda.len();
        Some(&self.ut * self.l.solve_lower_triangular(&DMatrix::identity(n, n))?)
    }

    /// `U' L^-1 v` for a vector of `n_blocks - 1` differences.
    pub fn rotate(&self, v: DVector<f64>) -> Option<DVector<f64>> {
        Some(&self.ut * self.l.solve_lower_triangular(&v)?)
    }

    /// The grid of `K^2` on `[0, k_hi]`: `0`, then `k_hi` down by [`K_PER_DECADE`] per decade
    /// until the random walk's largest whitened share is below [`K_FLOOR_SHARE`].
    pub fn grid(&self, k_hi: f64) -> Vec<f64> {
        let lmax = self.lambda.iter().copied().fold(0.0, f64::max);
        let mut k = vec![0.0];
        if k_hi > 0.0 && lmax > 0.0 {
            let step = 10f64.powf(-1.0 / K_PER_DECADE);
            let mut v = k_hi;
            while v * lmax >= K_FLOOR_SHARE && k.len() <= K_MAX_POINTS {
                k.push(v);
                v *= step;
            }
        }
        k
    }
}

/// The maximum likelihood `K^2` (u^2/s^3) on `[0, k_hi]` of the first differences of
/// `block_means` (u/s, blocks of `block_s` s) with a drift (a constant difference) fitted, the
/// other four terms `c` (its `c[3]` is not used) and the stationary `effects` fixed (module doc;
/// [`KRotation::max_likelihood_k2`] on the rotation of `c` and `effects`). `None` when the series
/// is too short or not finite, or the covariance is not positive definite.
pub fn profile_k2(
    block_means: &[f64],
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
    k_hi: f64,
) -> Option<f64> {
    if !usable_block_means(block_means) {
        return None;
    }
    KRotation::new(block_means.len(), block_s, c, effects)?.max_likelihood_k2(block_means, k_hi)
}

impl KRotation {
    /// The maximum likelihood `K^2` (u^2/s^3) on `[0, k_hi]` of the first differences of
    /// `block_means` (as many as the rotation was built for) with a drift fitted (module doc).
    /// The grid's best point is polished by golden section in `ln K^2` between its neighbours.
    /// `None` when the series does not match the rotation or is not finite.
    pub fn max_likelihood_k2(&self, block_means: &[f64], k_hi: f64) -> Option<f64> {
        let n = self.lambda.len();
        if block_means.len() != n + 1 || !usable_block_means(block_means) {
            return None;
        }
        let d = DVector::from_iterator(n, block_means.windows(2).map(|p| p[1] - p[0]));
        let z = self.rotate(d)?;
        let u = self.rotate(DVector::from_element(n, 1.0))?;
        self.max_likelihood_k2_rotated(&z, &u, k_hi)
    }

    /// [`Self::max_likelihood_k2`] of differences already rotated, `z = U' L^-1 d`, with the
    /// drift column rotated the same way (`u = U' L^-1 1`).
    pub fn max_likelihood_k2_rotated(
        &self,
        z: &DVector<f64>,
        u: &DVector<f64>,
        k_hi: f64,
    ) -> Option<f64> {
        // -2 l(k), the drift profiled out.
        let m2l = |k: f64| -> f64 {
            let (mut szz, mut suz, mut suu, mut logdet) = (0.0, 0.0, 0.0, 0.0);
            for ((zi, ui), li) in z.iter().zip(u.iter()).zip(&self.lambda) {
                let v = 1.0 + k * li;
                szz += zi * zi / v;
                suz += ui * zi / v;
                suu += ui * ui / v;
                logdet += (k * li).ln_1p();
            }
            logdet + szz - if suu > 0.0 { suz * suz / suu } else { 0.0 }
        };
        let grid = self.grid(k_hi);
        let vals: Vec<f64> = grid.iter().map(|&k| m2l(k)).collect();
        let best = (0..grid.len()).min_by(|&a, &b| vals[a].total_cmp(&vals[b]))?;
        // The grid runs down from k_hi: neighbours at best - 1 (larger) and best + 1 (smaller).
        if best == 0 || best + 1 >= grid.len() || grid[best + 1] <= 0.0 {
            return Some(grid[best]);
        }
        let (lo, hi) = (grid[best + 1].ln(), grid[best - 1].ln());
        let x = golden_section(|x| m2l(x.exp()), lo, hi, K_POLISH_STEPS).best();
        let k = x.exp();
        Some(if m2l(k) <= vals[best] { k } else { grid[best] })
    }
}
