//! Covariance of overlapping Allan-variance estimates between cluster sizes under the five-term
//! model (docs/theory.md sections 4 and 5).
//!
//! The phase of each random term has a generalized covariance function `G(t)` (valid for filters
//! that annihilate polynomials of degree <= 1, such as the second difference):
//!
//! | term | `G(t)`, `t` in s |
//! |---|---|
//! | Q, white phase | `Q^2` at `t = 0`, else 0 (phase white with sd `Q`) |
//! | N, white rate | `-N^2 abs(t) / 2` |
//! | B, flicker rate | `(B^2 / (2 pi)) t^2 ln abs(t)` |
//! | K, rate random walk | `K^2 abs(t)^3 / 12` |
//!
//! Applying the weights `(1, -2, 1)` at `0, tau, 2 tau` twice gives `Var D = 2 tau^2 AVAR` with
//! AVAR the closed forms `3Q^2/tau^2`, `N^2/tau`, `(2 ln2/pi) B^2`, `K^2 tau/3` (tested). The ramp
//! R is deterministic: `D_m = R tau^2` exactly, so it enters only as a mean.
//!
//! With `D_1(k) = x_{k+2 m1} - 2 x_{k+m1} + x_k` (mean `mu_1`), `D_2(l)` likewise, and
//! `c12(h) = Cov(D_1(k), D_2(l))` for `h = k - l`, Gaussian moments give
//!
//! ```text
//! Cov(AVAR_1, AVAR_2) = sum_h n(h) [2 c12(h)^2 + 4 mu_1 mu_2 c12(h)] / (4 tau1^2 tau2^2 M1 M2)
//! ```
//!
//! where `n(h)` counts the pairs `(k, l)` at lag `h` (`M1`, `M2` differences averaged). All sums
//! are kept per unit coefficient (lag unit `tau0 = 1`), so the matrix for any coefficients is a
//! quadratic form in `c` and the expensive part is cached per pair `(m1, m2)`.
//!
//! The lag sum runs over the whole overlap range `-(M2-1) ..= M1-1` with no truncation: short
//! stretches are summed exactly, long smooth stretches between breakpoints by Gauss-Legendre panels
//! graded geometrically towards the kinks of `c12`, with the Euler-Maclaurin end corrections. The
//! flicker cross-covariance decays as `c12(h) ~ -(m1 m2)^2 / (pi h^2)`; beyond
//! `|h| = 16 max(m1, m2)` it is evaluated from its far-field series in `1/h` (`flicker_series`,
//! no logarithms, and free of the cancellation the direct nine-term sum suffers there). Against
//! the exact lag-by-lag sum the quadrature agrees to better than 1e-6 relative
//! (tests/model/covariance.rs).
//!
//! Live refits: as the run grows every count grows by the same `d`, `n(h)` grows by exactly `d` on
//! the old range, and the range gains `d` lags at each end. The cache keeps, per pair, the sums
//! weighted by `n(h)` and unweighted, and updates them with the new lags only
//! ([`AvarCovariance`]); each window of far lags evaluates only the series terms its nearest lag
//! needs (2^-64 of the leading term). The two fits of a live tick take about 0.35 ms for 21
//! octave taus, a cold fit about 7 ms (BENCHMARKS.md, "Noise-model fit").
//!
//! Pairs computed from scratch are also kept process-wide ([`clear_shared_cache`]): the sums
//! depend only on `(m1, m2, M1, M2)`, so the channels of one run share them.

//!
//! Files: [`lag_covariance`] (the cross-covariance at a lag), [`far_field`] (its flicker series
//! far out), [`quadrature`] (sums over long lag ranges), [`pair`] (one pair's lag sums and their
//! live update), [`shared`] (the process-wide cache of fresh pairs); this file, the matrices.

mod far_field;
mod lag_covariance;
mod pair;
mod quadrature;
mod shared;

pub use lag_covariance::second_difference_cov;
pub use pair::{flicker_far_field, pair_sums, pair_sums_advanced, pair_sums_exact, PairSums};
pub use shared::clear_shared_cache;

use crate::allan::CurvePoint;
use nalgebra::DMatrix;
use pair::{PairState, NQ, NRAND};
use shared::shared_fresh;
use std::collections::HashMap;

/// One estimate on the curve as the covariance needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CovPoint {
    /// Cluster size.
    pub m: u64,
    /// Number of full-overlap (stride 1) second differences the estimate spans (`M`).
    pub count: u64,
}

/// The full-overlap count of a point: the number of stride-1 second differences its span holds,
/// `n - 2m + 1` with `n = n_phase - 1` increments.
fn full_count(p: &CurvePoint) -> u64 {
    p.n_phase.saturating_sub(2 * p.m).max(1)
}

/// The covariance points of an AVAR curve, in the order of `points`, with their strides
/// ([`strides`]).
///
/// The lag sums are those of the full-overlap estimate (stride 1). A bounded-memory estimate
/// (`--overlap L`) takes differences at a stride `s >= 2` for `m >= 2L`, and its `count` is the
/// number of strided differences; such a point gets the full count `n - 2m + 1` (the span it
/// covers, from the point's phase count) and its stride, and
/// [`AvarCovariance::matrix_strided`] corrects the sums for the stride. A stride-1 point keeps
/// its own count (full overlap, gaps included). The stride and the phase count are the
/// accumulator's own ([`CurvePoint::stride`], [`CurvePoint::n_phase`]), not inferred.
pub fn cov_points(points: &[CurvePoint]) -> Vec<CovPoint> {
    points
        .iter()
        .map(|p| CovPoint {
            m: p.m,
            count: if p.stride > 1 { full_count(p) } else { p.count },
        })
        .collect()
}

/// The stride of each point of an AVAR curve (1 at full overlap).
pub fn strides(points: &[CurvePoint]) -> Vec<u64> {
    points.iter().map(|p| p.stride.max(1)).collect()
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a.max(1)
    } else {
        gcd(b, a % b)
    }
}

/// Covariance matrices of AVAR estimates, with each pair's lag sums kept between calls.
///
/// Live refits see every count grow by the same number of differences `d` between calls (one
/// contiguous segment: `M = n - 2m + 1`). The sums are then updated exactly rather than
/// recomputed: on the old lag range each pair count grows by `d` (so the sums gain `d` times the
/// cached unweighted sums) and the range gains `d` lags at each end, summed by quadrature (the
/// far-field series of the flicker term makes that cheap). Other changes (a gap, a shorter
/// curve) recompute the pair.
#[derive(Debug, Default, Clone)]
pub struct AvarCovariance {
    cache: HashMap<(u64, u64), Vec<PairState>>,
}

/// Count versions kept per pair (a caller alternating between a few curves stays cached).
const STATES_PER_PAIR: usize = 3;

impl AvarCovariance {
    pub fn new() -> Self {
        Self::default()
    }

    /// Kept for compatibility: counts that grow are now handled exactly (see the type doc), so
    /// no tolerance is needed and `eps` is ignored.
    pub fn with_count_tolerance(_eps: f64) -> Self {
        Self::default()
    }

    /// Number of cached pair states.
    pub fn cached_pairs(&self) -> usize {
        self.cache.values().map(Vec::len).sum()
    }

    /// The pair's sums for strided estimates (points `i` and `j` of `strides`): white phase's
    /// cross-covariance sits on the stride lattice, so its terms are `gcd(s_i, s_j)` times the
    /// full overlap's (see [`Self::matrix_strided`]); the other noises' are unchanged.
    fn sums_strided(
        &mut self,
        a: CovPoint,
        b: CovPoint,
        i: usize,
        j: usize,
        strides: &[u64],
    ) -> PairSums {
        let mut s = self.sums(a, b);
        let st = |k: usize| strides.get(k).copied().unwrap_or(1).max(1);
        let g = gcd(st(i), st(j));
        if g > 1 {
            let gf = g as f64;
            for t in 0..NRAND {
                s.quad[NQ][t] *= gf;
                if t != NQ {
                    s.quad[t][NQ] *= gf;
                }
            }
            s.lin[NQ] *= gf;
        }
        s
    }

    fn sums(&mut self, a: CovPoint, b: CovPoint) -> PairSums {
        // The sums are symmetric under swapping the two estimates (h -> -h).
        let (m1, m2, c1, c2) = if (a.m, a.count) <= (b.m, b.count) {
            (a.m, b.m, a.count, b.count)
        } else {
            (b.m, a.m, b.count, a.count)
        };
        let states = self.cache.entry((m1, m2)).or_default();
        if let Some(st) = states.iter().find(|s| s.counts == (c1, c2)) {
            return st.sums();
        }
        // Advance the furthest state that can reach these counts.
        let best = states
            .iter()
            .enumerate()
            .filter(|(_, s)| {
                let (o1, o2) = s.counts;
                o1 <= c1 && o2 <= c2 && c1 - o1 == c2 - o2
            })
            .max_by_key(|(_, s)| s.counts.0)
            .map(|(i, _)| i);
        if let Some(i) = best {
            let st = &mut states[i];
            if st.advance(c1, c2) {
                return st.sums();
            }
        }
        let st = shared_fresh(m1, m2, c1, c2);
        let s = st.sums();
        if states.len() >= STATES_PER_PAIR {
            states.remove(0);
        }
        states.push(st);
        s
    }

    /// `Cov(AVAR_hat_i, AVAR_hat_j)` in (u/s)^4 for the five-term model with
    /// `c = (Q^2, N^2, B^2, K^2, R^2)`, sampling step `tau0_s` (docs/theory.md section 5), for
    /// full-overlap estimates.
    pub fn matrix(&mut self, tau0_s: f64, points: &[CovPoint], c: &[f64; 5]) -> DMatrix<f64> {
        self.matrix_strided(tau0_s, points, &[], c)
    }

    /// As [`matrix`](AvarCovariance::matrix), for estimates taken at strides `strides[i]`
    /// (missing entries: 1), each point's `count` being the full count of the span it covers.
    ///
    /// Strided differences `D_1(k s1)`, `D_2(l s2)` meet at lags on the lattice `g Z`,
    /// `g = gcd(s1, s2)`, with about `g / (s1 s2)` times as many pairs per lag as at full
    /// overlap, and the counts are `M / s`. For the continuous terms (N, B, K), whose
    /// cross-covariance varies on the scale of `m >> s`, the lattice sum is the full sum times
    /// `g / (s1 s2)`, which the counts cancel: the covariance is that of the full overlap over
    /// the same span. The white-phase cross-covariance is concentrated at lags `j m2 - i m1`,
    /// which lie on the lattice, so its sums are `1 / (s1 s2)` of the full ones and its part of
    /// the covariance is `g` times the full overlap's: striding does cost white phase noise its
    /// degrees of freedom.
    pub fn matrix_strided(
        &mut self,
        tau0_s: f64,
        points: &[CovPoint],
        strides: &[u64],
        c: &[f64; 5],
    ) -> DMatrix<f64> {
        let n = points.len();
        // Physical scale of each term's g per unit coefficient: tau0^(0, 1, 2, 3).
        let scale = [1.0, tau0_s, tau0_s * tau0_s, tau0_s.powi(3)];
        let cs: [f64; 4] = std::array::from_fn(|t| c[t] * scale[t]);
        let c_r = c[4];
        let mut out = DMatrix::zeros(n, n);
        self.each_pair(tau0_s, points, strides, |i, j, s, t12| {
            let (a, b) = (points[i], points[j]);
            let mut quad = 0.0;
            let mut lin = 0.0;
            for t in 0..NRAND {
                lin += cs[t] * s.lin[t];
                for u in 0..NRAND {
                    quad += cs[t] * cs[u] * s.quad[t][u];
                }
            }
            let v = (2.0 * quad + 4.0 * c_r * t12 * lin)
                / (4.0 * t12 * a.count as f64 * b.count as f64);
            out[(i, j)] = v;
            out[(j, i)] = v;
        });
        out
    }

    /// The same covariance as a quadratic form in `c`: for each pair `i <= j` (row-major over
    /// the upper triangle), the symmetric 5 x 5 matrix `T` with
    /// `Cov(AVAR_hat_i, AVAR_hat_j) = c' T c` (the entries of [`Self::matrix_strided`] are these
    /// forms at one `c`). The fit uses them to evaluate the variance of its estimates under any
    /// trial model without re-reading the lag sums.
    pub fn tensors_strided(
        &mut self,
        tau0_s: f64,
        points: &[CovPoint],
        strides: &[u64],
    ) -> Vec<[[f64; 5]; 5]> {
        let n = points.len();
        let scale = [1.0, tau0_s, tau0_s * tau0_s, tau0_s.powi(3)];
        let mut out = Vec::with_capacity(n * (n + 1) / 2);
        self.each_pair(tau0_s, points, strides, |i, j, s, t12| {
            let (a, b) = (points[i], points[j]);
            let den = 4.0 * t12 * a.count as f64 * b.count as f64;
            let mut t = [[0.0; 5]; 5];
            for u in 0..NRAND {
                for v in 0..NRAND {
                    t[u][v] = 2.0 * scale[u] * scale[v] * s.quad[u][v] / den;
                }
                // The mean term 4 c_R t12 sum c_u lin_u, split over both triangles.
                let m = 2.0 * t12 * scale[u] * s.lin[u] / den;
                t[u][4] = m;
                t[4][u] = m;
            }
            out.push(t);
        });
        out
    }

    /// Calls `each(i, j, sums, t12)` for every pair of points `i <= j`, row-major over the upper
    /// triangle, with the pair's (strided) lag sums and `t12 = tau_i^2 tau_j^2` in s^4.
    fn each_pair(
        &mut self,
        tau0_s: f64,
        points: &[CovPoint],
        strides: &[u64],
        mut each: impl FnMut(usize, usize, &PairSums, f64),
    ) {
        let n = points.len();
        for i in 0..n {
            for j in i..n {
                let (a, b) = (points[i], points[j]);
                let s = self.sums_strided(a, b, i, j, strides);
                let tau1 = a.m as f64 * tau0_s;
                let tau2 = b.m as f64 * tau0_s;
                each(i, j, &s, tau1 * tau1 * tau2 * tau2);
            }
        }
    }
}
