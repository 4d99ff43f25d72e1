//! Covariance of overlapping Allan-variance estimates between cluster sizes under the five-term
//! model (THEORY.md sections 4 and 5).
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
//! quadratic form in `c` and the expensive part is cached per `(m1, m2, M1, M2)`.
//!
//! The lag sum runs over the whole overlap range `-(M2-1) ..= M1-1` with no truncation: short
//! stretches are summed exactly, long smooth stretches between breakpoints by Gauss-Legendre panels
//! graded geometrically towards the breakpoints, with the Euler-Maclaurin end corrections. The
//! flicker cross-covariance decays as `c12(h) ~ -(m1 m2)^2 / (pi h^2)`, which the geometric panels
//! follow out to the end of the range. Against the exact lag-by-lag sum the quadrature agrees to
//! better than 1e-6 relative (tests/fit_covariance.rs).

use nalgebra::DMatrix;
use std::collections::HashMap;
use std::f64::consts::PI;

/// Index of the random terms in [`PairSums`]: Q, N, B, K.
const NQ: usize = 0;
const NRAND: usize = 4;

/// Lag sums of one pair of cluster sizes, per unit coefficient and lag unit `tau0 = 1`:
/// `quad[t][u] = sum_h n(h) g_t(h) g_u(h)` and `lin[t] = sum_h n(h) g_t(h)`, where `g_t` is the
/// cross-covariance of the two second differences for term `t` (Q, N, B, K).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PairSums {
    pub quad: [[f64; NRAND]; NRAND],
    pub lin: [f64; NRAND],
}

/// Weights of the second difference.
const A: [f64; 3] = [1.0, -2.0, 1.0];

/// `sum_i a_i G_N(u + i m)` for `G_N(t) = -|t|/2`.
fn inner_n(u: f64, m: f64) -> f64 {
    -(u.abs() - 2.0 * (u + m).abs() + (u + 2.0 * m).abs()) / 2.0
}

/// `sum_i a_i G_K(u + i m)` for `G_K(t) = |t|^3/12`; outside `(-2m, 0)` all three lags share a
/// sign and the sum is exactly `m^2 |u + m| / 2` (no cancellation of large cubes).
fn inner_k(u: f64, m: f64) -> f64 {
    if u >= 0.0 || u <= -2.0 * m {
        m * m * (u + m).abs() / 2.0
    } else {
        let c = |t: f64| t.abs().powi(3) / 12.0;
        c(u) - 2.0 * c(u + m) + c(u + 2.0 * m)
    }
}

/// `G_B(t) = t^2 ln|t| / (2 pi)`, 0 at 0.
fn g_b(t: f64) -> f64 {
    if t == 0.0 {
        0.0
    } else {
        t * t * t.abs().ln() / (2.0 * PI)
    }
}

/// `sum_i a_i G_B(u + i m)`. Far from the origin (all lags of one sign, `|u| >= 2m`), written as
/// `2 m^2 ln|u| + sum_i a_i (u + i m)^2 ln(1 + i m / u)` so the large `u^2 ln|u|` parts cancel
/// analytically.
fn inner_b(u: f64, m: f64) -> f64 {
    if u >= 2.0 * m || u <= -4.0 * m {
        let mut s = 2.0 * m * m * u.abs().ln();
        for (i, a) in A.iter().enumerate().skip(1) {
            let t = u + i as f64 * m;
            s += a * t * t * (i as f64 * m / u).ln_1p();
        }
        s / (2.0 * PI)
    } else {
        g_b(u) - 2.0 * g_b(u + m) + g_b(u + 2.0 * m)
    }
}

/// Cross-covariances `(g_N, g_B, g_K)` of `D_{m1}(l + h)` and `D_{m2}(l)` at (real) lag `h`.
fn g_cont(h: f64, m1: f64, m2: f64) -> [f64; 3] {
    let mut g = [0.0; 3];
    // White and random-walk rate are exactly 0 outside [-2 m1, 2 m2] (all lags of one sign).
    let inside = h >= -2.0 * m1 && h <= 2.0 * m2;
    for (j, b) in A.iter().enumerate() {
        let u = h - j as f64 * m2;
        g[1] += b * inner_b(u, m1);
        if inside {
            g[0] += b * inner_n(u, m1);
            g[2] += b * inner_k(u, m1);
        }
    }
    g
}

/// Number of pairs `(k, l)`, `0 <= k < M1`, `0 <= l < M2`, with `k - l = h` (piecewise linear).
fn pair_count(h: f64, big_m1: f64, big_m2: f64) -> f64 {
    ((big_m2).min(big_m1 - h) - (-h).max(0.0)).max(0.0)
}

/// The 7 accumulated quantities at one lag: `n g_t g_u` for `t <= u` over (N, B, K), then `n g_t`.
type Vals = [f64; 9];

fn vals(h: f64, m1: f64, m2: f64, big_m1: f64, big_m2: f64) -> Vals {
    let n = pair_count(h, big_m1, big_m2);
    let g = g_cont(h, m1, m2);
    [
        n * g[0] * g[0],
        n * g[0] * g[1],
        n * g[0] * g[2],
        n * g[1] * g[1],
        n * g[1] * g[2],
        n * g[2] * g[2],
        n * g[0],
        n * g[1],
        n * g[2],
    ]
}

fn add(acc: &mut Vals, v: &Vals, w: f64) {
    for (a, b) in acc.iter_mut().zip(v) {
        *a += w * b;
    }
}

/// 8-point Gauss-Legendre nodes and weights on [-1, 1].
const GL_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
const GL_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// Points summed exactly at each end of a long stretch.
const END_EXACT: i64 = 8;
/// Growth factor of the graded panels away from each breakpoint.
const PANEL_GROWTH: f64 = 4.0;

/// `sum_{h=p}^{q} F(h)` for `F` smooth on `[p, q]` (integers, `p <= q`).
fn sum_stretch(p: i64, q: i64, f: &dyn Fn(f64) -> Vals, acc: &mut Vals) {
    if q - p < 4 * END_EXACT + 8 {
        for h in p..=q {
            add(acc, &f(h as f64), 1.0);
        }
        return;
    }
    for h in (p..p + END_EXACT).chain(q - END_EXACT + 1..=q) {
        add(acc, &f(h as f64), 1.0);
    }
    // Middle [a, b]: Euler-Maclaurin, sum = integral + (F(a) + F(b))/2 + (F'(b) - F'(a))/12.
    let a = (p + END_EXACT) as f64;
    let b = (q - END_EXACT) as f64;
    let fa = f(a);
    let fb = f(b);
    let (fa_m, fa_p, fb_m, fb_p) = (f(a - 1.0), f(a + 1.0), f(b - 1.0), f(b + 1.0));
    for k in 0..9 {
        let da = (fa_p[k] - fa_m[k]) / 2.0;
        let db = (fb_p[k] - fb_m[k]) / 2.0;
        acc[k] += (fa[k] + fb[k]) / 2.0 + (db - da) / 12.0;
    }
    // Integral over panels graded from both ends towards the middle.
    let mid = 0.5 * (a + b);
    let mut edges_lo = vec![a];
    let mut w = END_EXACT as f64;
    while edges_lo.last().copied().unwrap_or(a) + w < mid {
        let e = edges_lo.last().copied().unwrap_or(a) + w;
        edges_lo.push(e);
        w *= PANEL_GROWTH;
    }
    let mut edges = edges_lo.clone();
    edges.push(mid);
    let mut hi: Vec<f64> = edges_lo.iter().map(|e| a + b - e).collect();
    hi.reverse();
    edges.extend(hi);
    for win in edges.windows(2) {
        let (lo, hi) = (win[0], win[1]);
        if hi <= lo {
            continue;
        }
        let half = 0.5 * (hi - lo);
        let c = 0.5 * (hi + lo);
        for (x, wt) in GL_X.iter().zip(GL_W) {
            add(acc, &f(c - half * x), wt * half);
            add(acc, &f(c + half * x), wt * half);
        }
    }
}

/// Lag sums by quadrature (see the module doc). `m1, m2 >= 1`, `M1, M2 >= 1`.
pub fn pair_sums(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairSums {
    let (fm1, fm2, fbm1, fbm2) = (m1 as f64, m2 as f64, big_m1 as f64, big_m2 as f64);
    let lo = -(big_m2 as i64 - 1);
    let hi = big_m1 as i64 - 1;
    let mut bps: Vec<i64> = vec![lo, hi + 1, 0, big_m1 as i64 - big_m2 as i64];
    for i in 0..3i64 {
        for j in 0..3i64 {
            bps.push(j * m2 as i64 - i * m1 as i64);
        }
    }
    bps.retain(|&b| b >= lo && b <= hi + 1);
    bps.sort_unstable();
    bps.dedup();
    let f = |h: f64| vals(h, fm1, fm2, fbm1, fbm2);
    let mut acc: Vals = [0.0; 9];
    for w in bps.windows(2) {
        sum_stretch(w[0], w[1] - 1, &f, &mut acc);
    }
    assemble(acc, m1, m2, big_m1, big_m2)
}

/// Lag sums summed lag by lag over the whole range (the slow reference for [`pair_sums`]).
pub fn pair_sums_exact(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairSums {
    let (fm1, fm2, fbm1, fbm2) = (m1 as f64, m2 as f64, big_m1 as f64, big_m2 as f64);
    let mut acc: Vals = [0.0; 9];
    for h in -(big_m2 as i64 - 1)..=(big_m1 as i64 - 1) {
        add(&mut acc, &vals(h as f64, fm1, fm2, fbm1, fbm2), 1.0);
    }
    assemble(acc, m1, m2, big_m1, big_m2)
}

/// Unpack the continuous-term sums and add the white-phase point masses (nonzero only where a
/// lag `h + i m1 - j m2` is exactly 0).
fn assemble(acc: Vals, m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairSums {
    let mut s = PairSums::default();
    let idx = [
        (1, 1, 0),
        (1, 2, 1),
        (1, 3, 2),
        (2, 2, 3),
        (2, 3, 4),
        (3, 3, 5),
    ];
    for (t, u, k) in idx {
        s.quad[t][u] = acc[k];
        s.quad[u][t] = acc[k];
    }
    s.lin[1] = acc[6];
    s.lin[2] = acc[7];
    s.lin[3] = acc[8];
    // g_Q(h) = sum_{i,j: h = j m2 - i m1} a_i a_j.
    let mut masses: Vec<(i64, f64)> = Vec::with_capacity(9);
    for (i, ai) in A.iter().enumerate() {
        for (j, aj) in A.iter().enumerate() {
            let h = j as i64 * m2 as i64 - i as i64 * m1 as i64;
            match masses.iter_mut().find(|(hh, _)| *hh == h) {
                Some(e) => e.1 += ai * aj,
                None => masses.push((h, ai * aj)),
            }
        }
    }
    let (fm1, fm2, fbm1, fbm2) = (m1 as f64, m2 as f64, big_m1 as f64, big_m2 as f64);
    for (h, gq) in masses {
        let n = pair_count(h as f64, fbm1, fbm2);
        if n <= 0.0 || gq == 0.0 {
            continue;
        }
        let g = g_cont(h as f64, fm1, fm2);
        s.quad[NQ][NQ] += n * gq * gq;
        for (t, gt) in g.iter().enumerate() {
            s.quad[NQ][t + 1] += n * gq * gt;
            s.quad[t + 1][NQ] += n * gq * gt;
        }
        s.lin[NQ] += n * gq;
    }
    s
}

/// One estimate on the curve as the covariance needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CovPoint {
    /// Cluster size.
    pub m: u64,
    /// Number of second differences averaged (`M`).
    pub count: u64,
}

/// Lag sums of one pair computed at counts `(M1, M2)`.
type CountedSums = ((u64, u64), PairSums);

/// Covariance matrices of AVAR estimates, with the per-pair lag sums cached (they depend only on
/// `(m1, m2, M1, M2)`, not on the coefficients or `tau0`).
///
/// Live refits see the counts `M` grow between calls. With a count tolerance `eps > 0`
/// ([`AvarCovariance::with_count_tolerance`]), sums computed at counts within a fraction `eps` of
/// the requested ones are reused, scaled by `M2 / M2'`: the pair count is `n(h) = M2 + psi(h)`
/// with `psi` fixed by the cluster sizes, so the scaled sums are off by at most about
/// `eps * (2 m_max / M2)`, relative (the edge share of the overlap range times the count change).
#[derive(Debug, Default, Clone)]
pub struct AvarCovariance {
    cache: HashMap<(u64, u64), Vec<CountedSums>>,
    count_tolerance: f64,
}

impl AvarCovariance {
    pub fn new() -> Self {
        Self::default()
    }

    /// Reuse lag sums computed at counts within the fraction `eps` of the requested ones.
    pub fn with_count_tolerance(eps: f64) -> Self {
        Self {
            cache: HashMap::new(),
            count_tolerance: eps.max(0.0),
        }
    }

    /// Number of cached pairs.
    pub fn cached_pairs(&self) -> usize {
        self.cache.values().map(Vec::len).sum()
    }

    fn sums(&mut self, a: CovPoint, b: CovPoint) -> PairSums {
        // The sums are symmetric under swapping the two estimates (h -> -h).
        let (m1, m2, c1, c2) = if (a.m, a.count) <= (b.m, b.count) {
            (a.m, b.m, a.count, b.count)
        } else {
            (b.m, a.m, b.count, a.count)
        };
        let eps = self.count_tolerance;
        let entries = self.cache.entry((m1, m2)).or_default();
        if let Some((_, s)) = entries.iter().find(|(k, _)| *k == (c1, c2)) {
            return *s;
        }
        if eps > 0.0 {
            let close = |x: u64, y: u64| (x as f64 - y as f64).abs() <= eps * y as f64;
            if let Some(((_, k2), s)) = entries
                .iter()
                .find(|((k1, k2), _)| close(*k1, c1) && close(*k2, c2))
            {
                let f = c2 as f64 / *k2 as f64;
                let mut out = *s;
                for row in out.quad.iter_mut() {
                    for v in row.iter_mut() {
                        *v *= f;
                    }
                }
                for v in out.lin.iter_mut() {
                    *v *= f;
                }
                return out;
            }
        }
        let s = pair_sums(m1, m2, c1, c2);
        // Keep a few count versions per pair (the live case moves forward; old ones go).
        if entries.len() >= 4 {
            entries.remove(0);
        }
        entries.push(((c1, c2), s));
        s
    }

    /// `Cov(AVAR_hat_i, AVAR_hat_j)` in (u/s)^4 for the five-term model with
    /// `c = (Q^2, N^2, B^2, K^2, R^2)`, sampling step `tau0_s` (THEORY.md section 5).
    pub fn matrix(&mut self, tau0_s: f64, points: &[CovPoint], c: &[f64; 5]) -> DMatrix<f64> {
        let n = points.len();
        // Physical scale of each term's g per unit coefficient: tau0^(0, 1, 2, 3).
        let scale = [1.0, tau0_s, tau0_s * tau0_s, tau0_s.powi(3)];
        let cs: [f64; 4] = std::array::from_fn(|t| c[t] * scale[t]);
        let c_r = c[4];
        let mut out = DMatrix::zeros(n, n);
        for i in 0..n {
            for j in i..n {
                let (a, b) = (points[i], points[j]);
                let s = self.sums(a, b);
                let tau1 = a.m as f64 * tau0_s;
                let tau2 = b.m as f64 * tau0_s;
                let t12 = tau1 * tau1 * tau2 * tau2;
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
            }
        }
        out
    }
}

/// `Cov(D_{m1}(l + h), D_{m2}(l))` per unit coefficient with `tau0 = 1`, for (Q, N, B, K) (the
/// generalized-covariance algebra of the module doc, exposed for tests).
pub fn second_difference_cov(h: i64, m1: u64, m2: u64) -> [f64; 4] {
    let g = g_cont(h as f64, m1 as f64, m2 as f64);
    let mut gq = 0.0;
    for (i, ai) in A.iter().enumerate() {
        for (j, aj) in A.iter().enumerate() {
            if h == j as i64 * m2 as i64 - i as i64 * m1 as i64 {
                gq += ai * aj;
            }
        }
    }
    [gq, g[0], g[1], g[2]]
}
