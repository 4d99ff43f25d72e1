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

use crate::allan::CurvePoint;
use nalgebra::DMatrix;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

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

/// Products accumulated at each lag: `g_t g_u` for `t <= u` over (N, B, K), then `g_t`.
const NV: usize = 9;
/// The products weighted by the pair count `n(h)` (entries `0..NV`), then unweighted
/// (`NV..2 NV`): the unweighted sums are what a growing count adds to the old range.
type Vals = [f64; 2 * NV];

fn products(g: &[f64; 3]) -> [f64; NV] {
    [
        g[0] * g[0],
        g[0] * g[1],
        g[0] * g[2],
        g[1] * g[1],
        g[1] * g[2],
        g[2] * g[2],
        g[0],
        g[1],
        g[2],
    ]
}

fn add(acc: &mut Vals, v: &Vals, w: f64) {
    for (a, b) in acc.iter_mut().zip(v) {
        *a += w * b;
    }
}

/// Terms of the far-field series of the flicker cross-covariance (orders `h^-2 .. h^-(NSER+1)`).
const NSER: usize = 23;
/// The series is used where `|h| >= FAR_FACTOR * max(m1, m2)`: there every lag `h + i m1 - j m2`
/// is within a factor `1 +- 1/8` of `h`, the N and K cross-covariances are exactly 0, and the
/// terms fall by 8 per order, so 23 orders reach 1e-19 of the leading one.
const FAR_FACTOR: f64 = 16.0;

/// One pair of cluster sizes at given counts: what the lag function needs.
struct PairCtx {
    m1: f64,
    m2: f64,
    big_m1: f64,
    big_m2: f64,
    /// `max(m1, m2)`.
    scale: f64,
    /// `|h|` from which the series is used (infinite: never).
    far: f64,
    /// `g_B(h) = scale^2 sum_k series[k] (scale / h)^(k + 2)`.
    series: [f64; NSER],
    /// `tail[k] = sum_{j >= k} |series[j]| (1/16)^(j - k)`: with `|x| = scale/|h| <= 1/16`, the
    /// terms from order `k` on add at most `|x|^k tail[k]` ([`PairCtx::terms_for`]).
    tail: [f64; NSER],
}

/// Relative size, against the leading term, of the far-field terms a window may leave out:
/// 2^-64, far below rounding.
const SERIES_TOL: f64 = 5.421_010_862_427_522e-20;

/// Far-field expansion of `g_B(h) = sum_{i,j} a_i a_j G_B(h + i m1 - j m2)`.
///
/// Taylor expansion of `G_B(h + d)` about `h`: with `G_B^(n)(t) = (-1)^(n-3) (n-3)! / (pi t^(n-2))`
/// for `n >= 3`, and `mu_n = sum_{i,j} a_i a_j (i m1 - j m2)^n` vanishing for `n < 4` (the second
/// differences annihilate lines), `g_B(h) = sum_{n>=4} mu_n (-1)^(n-3) / (n (n-1) (n-2) pi h^(n-2))`,
/// convergent for `|h| > 2 max(m1, m2)`. `mu_n` is summed binomially,
/// `mu_n = sum_{p=2}^{n-2} C(n, p) (2^p - 2) (2^(n-p) - 2) m1^p (-m2)^(n-p)`, with `m` scaled by
/// `max(m1, m2)` (no overflow, and no cancellation of large powers when `m1 << m2`). Leading term:
/// `-(m1 m2)^2 / (pi h^2)`.
fn flicker_series(m1: f64, m2: f64) -> [f64; NSER] {
    let s = m1.max(m2);
    let (x1, x2) = (m1 / s, -m2 / s);
    // Powers 0 ..= NSER + 3 of 2, m1/s and -m2/s.
    let mut pow2 = [1.0; NSER + 4];
    let mut pow1 = [1.0; NSER + 4];
    let mut pow2m = [1.0; NSER + 4];
    for k in 1..NSER + 4 {
        pow2[k] = 2.0 * pow2[k - 1];
        pow1[k] = x1 * pow1[k - 1];
        pow2m[k] = x2 * pow2m[k - 1];
    }
    let mut out = [0.0; NSER];
    for (k, o) in out.iter_mut().enumerate() {
        let n = k + 4;
        let mut mu = 0.0;
        let mut binom = 1.0; // C(n, p), built up from p = 0
        for p in 0..=n {
            if p >= 1 {
                binom *= (n + 1 - p) as f64 / p as f64;
            }
            if p < 2 || p + 2 > n {
                continue;
            }
            let q = n - p;
            mu += binom * (pow2[p] - 2.0) * (pow2[q] - 2.0) * pow1[p] * pow2m[q];
        }
        let nf = n as f64;
        let sign = if (n - 3) % 2 == 0 { 1.0 } else { -1.0 };
        *o = sign * mu / (nf * (nf - 1.0) * (nf - 2.0) * PI);
    }
    out
}

impl PairCtx {
    /// `series`: the pair's [`flicker_series`], or `None` to evaluate `g` directly everywhere.
    fn new(m1: u64, m2: u64, big_m1: u64, big_m2: u64, series: Option<&[f64; NSER]>) -> PairCtx {
        let (fm1, fm2) = (m1 as f64, m2 as f64);
        let scale = fm1.max(fm2);
        PairCtx {
            m1: fm1,
            m2: fm2,
            big_m1: big_m1 as f64,
            big_m2: big_m2 as f64,
            scale,
            far: if series.is_some() {
                FAR_FACTOR * scale
            } else {
                f64::INFINITY
            },
            series: series.copied().unwrap_or([0.0; NSER]),
            tail: series.map_or([0.0; NSER], |c| {
                let mut t = [0.0; NSER];
                let mut acc = 0.0;
                for k in (0..NSER).rev() {
                    acc = c[k].abs() + acc / FAR_FACTOR;
                    t[k] = acc;
                }
                t
            }),
        }
    }

    /// Number of far-field terms that represent `g_B` to [`SERIES_TOL`] of the leading one
    /// wherever `|scale / h| <= x_max` (`x_max <= 1/16`).
    fn terms_for(&self, x_max: f64) -> usize {
        let tol = SERIES_TOL * self.series[0].abs();
        let mut pw = x_max;
        for k in 1..NSER {
            if pw * self.tail[k] <= tol {
                return k;
            }
            pw *= x_max;
        }
        NSER
    }

    /// `(g_N, g_B, g_K)` at lag `h`: the series (its first `terms` terms) far out, the direct
    /// sums nearer.
    #[inline]
    fn g(&self, h: f64, terms: usize) -> [f64; 3] {
        if h.abs() >= self.far {
            let x = self.scale / h;
            let mut acc = 0.0;
            for c in self.series[..terms.min(NSER)].iter().rev() {
                acc = acc * x + c;
            }
            [0.0, self.scale * self.scale * acc * x * x, 0.0]
        } else {
            g_cont(h, self.m1, self.m2)
        }
    }

    #[inline]
    fn vals(&self, h: f64, terms: usize) -> Vals {
        let n = pair_count(h, self.big_m1, self.big_m2);
        let p = products(&self.g(h, terms));
        let mut v = [0.0; 2 * NV];
        for k in 0..NV {
            v[k] = n * p[k];
            v[NV + k] = p[k];
        }
        v
    }

    /// Lags where `g` is not smooth: `j m2 - i m1` (a lag of `G` crosses 0), sorted, and how many
    /// are distinct (no allocation: the live refit calls this for every pair).
    fn kinks(&self) -> ([i64; 9], usize) {
        let (m1, m2) = (self.m1 as i64, self.m2 as i64);
        let mut k = [0i64; 9];
        for i in 0..3i64 {
            for j in 0..3i64 {
                k[(3 * i + j) as usize] = j * m2 - i * m1;
            }
        }
        k.sort_unstable();
        let n = dedup_sorted(&mut k);
        (k, n)
    }

    /// Adds `sum_{h=lo}^{hi}` of the lag values to `acc`. The range is cut where the integrand
    /// changes form (kinks of `g`, of `n(h)` at 0 and `M1 - M2`, and at `+- far` where the
    /// series takes over); each piece is summed by [`sum_graded`] with its distances to the
    /// nearest kinks of `g`, towards which the quadrature panels are graded.
    fn sum_range(&self, lo: i64, hi: i64, acc: &mut Vals) {
        if hi < lo {
            return;
        }
        let (kink_buf, nk) = self.kinks();
        let kinks = &kink_buf[..nk];
        let mut buf = [0i64; 15];
        let mut nb = 0;
        let mut push = |b: i64| {
            if b >= lo && b <= hi + 1 {
                buf[nb] = b;
                nb += 1;
            }
        };
        push(lo);
        push(hi + 1);
        push(0);
        push(self.big_m1 as i64 - self.big_m2 as i64);
        for &k in kinks {
            push(k);
        }
        if self.far.is_finite() {
            let f = self.far.ceil() as i64;
            push(f);
            push(-f + 1);
        }
        let bps = &mut buf[..nb];
        bps.sort_unstable();
        let nb = dedup_sorted(bps);
        let bps = &buf[..nb];
        for w in bps.windows(2) {
            let (p, q) = (w[0], w[1] - 1);
            // A window of the far field (one sign; the quadrature reads it at most one lag
            // beyond its ends) needs only the series terms its nearest lag does.
            let near = (p.abs().min(q.abs()) - 1) as f64;
            let terms = if self.far.is_finite() && p.signum() == q.signum() && near >= self.far {
                self.terms_for(self.scale / near)
            } else {
                NSER
            };
            let f = |h: f64| self.vals(h, terms);
            let s_lo = kinks
                .iter()
                .rev()
                .find(|&&k| k <= p)
                .map_or(f64::INFINITY, |&k| (p - k) as f64);
            let s_hi = kinks
                .iter()
                .find(|&&k| k > q)
                .map_or(f64::INFINITY, |&k| (k - q) as f64);
            sum_graded(p, q, s_lo, s_hi, &f, acc);
        }
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

fn gauss_panel(lo: f64, hi: f64, f: &dyn Fn(f64) -> Vals, acc: &mut Vals) {
    if hi <= lo {
        return;
    }
    let half = 0.5 * (hi - lo);
    let c = 0.5 * (hi + lo);
    for (x, wt) in GL_X.iter().zip(GL_W) {
        add(acc, &f(c - half * x), wt * half);
        add(acc, &f(c + half * x), wt * half);
    }
}

/// Euler-Maclaurin ends: `(F(a) + F(b))/2 + (F'(b) - F'(a))/12`, derivatives by central
/// differences.
fn euler_maclaurin_ends(a: f64, b: f64, f: &dyn Fn(f64) -> Vals, acc: &mut Vals) {
    let fa = f(a);
    let fb = f(b);
    let (fa_m, fa_p, fb_m, fb_p) = (f(a - 1.0), f(a + 1.0), f(b - 1.0), f(b + 1.0));
    for k in 0..2 * NV {
        let da = (fa_p[k] - fa_m[k]) / 2.0;
        let db = (fb_p[k] - fb_m[k]) / 2.0;
        acc[k] += (fa[k] + fb[k]) / 2.0 + (db - da) / 12.0;
    }
}

/// `sum_{h=p}^{q} F(h)` for `F` smooth on `[p, q]` (integers, `p <= q`), whose nearest
/// non-smooth points lie `s_lo` below `p` and `s_hi` above `q` (infinite: none).
///
/// Ends within `END_EXACT` of a kink are summed point by point; the rest by Euler-Maclaurin,
/// `sum = integral + (F(a) + F(b))/2 + (F'(b) - F'(a))/12`, with the integral on 8-point
/// Gauss-Legendre panels whose width is at most `PANEL_GROWTH - 1` times their distance to
/// the nearest kink (graded towards kinks, one panel across a stretch far from any).
fn sum_graded(p: i64, q: i64, s_lo: f64, s_hi: f64, f: &dyn Fn(f64) -> Vals, acc: &mut Vals) {
    if q - p < 4 * END_EXACT + 8 {
        for h in p..=q {
            add(acc, &f(h as f64), 1.0);
        }
        return;
    }
    let e_lo = if s_lo < END_EXACT as f64 {
        END_EXACT
    } else {
        0
    };
    let e_hi = if s_hi <= END_EXACT as f64 {
        END_EXACT
    } else {
        0
    };
    for h in (p..p + e_lo).chain(q - e_hi + 1..=q) {
        add(acc, &f(h as f64), 1.0);
    }
    let a = (p + e_lo) as f64;
    let b = (q - e_hi) as f64;
    euler_maclaurin_ends(a, b, f, acc);
    // Distance of a point x to the nearest kink on each side.
    let d_lo = |x: f64| s_lo + (x - p as f64);
    let d_hi = |x: f64| s_hi + (q as f64 - x);
    let mid = if s_lo.is_infinite() && s_hi.is_infinite() {
        0.5 * (a + b)
    } else if s_lo.is_infinite() {
        a
    } else if s_hi.is_infinite() {
        b
    } else {
        // Where the two distances are equal.
        (0.5 * (a + b + s_hi - s_lo)).clamp(a, b)
    };
    let g = PANEL_GROWTH - 1.0;
    let mut x = a;
    while x < mid {
        let next = (x + g * d_lo(x).max(1.0)).min(mid);
        gauss_panel(x, next, f, acc);
        x = next;
    }
    let mut x = b;
    while x > mid {
        let next = (x - g * d_hi(x).max(1.0)).max(mid);
        gauss_panel(next, x, f, acc);
        x = next;
    }
}

/// A pair's lag sums at its current counts, and what a larger count needs to update them.
#[derive(Debug, Clone)]
struct PairState {
    m1: u64,
    m2: u64,
    counts: (u64, u64),
    /// `sum_h n(h) p(h)` and `sum_h p(h)` over the overlap range, for the continuous terms.
    acc: Vals,
    /// White-phase point masses: lag `h`, `g_Q(h)`, and `(g_N, g_B, g_K)` at `h`.
    masses: Vec<(i64, f64, [f64; 3])>,
    /// The pair's far-field flicker series (count-independent).
    series: [f64; NSER],
}

impl PairState {
    /// Sums over the whole overlap range `-(M2-1) ..= M1-1` (see the module doc).
    fn fresh(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairState {
        let series = flicker_series(m1 as f64, m2 as f64);
        let ctx = PairCtx::new(m1, m2, big_m1, big_m2, Some(&series));
        let mut acc = [0.0; 2 * NV];
        ctx.sum_range(-(big_m2 as i64 - 1), big_m1 as i64 - 1, &mut acc);
        PairState {
            m1,
            m2,
            counts: (big_m1, big_m2),
            acc,
            masses: masses(m1, m2),
            series,
        }
    }

    /// Moves the sums to counts `(M1 + d, M2 + d)`, `d >= 0`. The pair count is
    /// `n(h) = min(M2, M1 - h) - max(-h, 0)`, so on the old range every `n(h)` grows by exactly
    /// `d` (adding `d` times the unweighted sums), and the range gains `d` lags at each end.
    /// Returns `false` (nothing changed) when the counts do not move that way.
    fn advance(&mut self, big_m1: u64, big_m2: u64) -> bool {
        let (o1, o2) = self.counts;
        if big_m1 < o1 || big_m2 < o2 || big_m1 - o1 != big_m2 - o2 {
            return false;
        }
        let d = (big_m1 - o1) as f64;
        if d == 0.0 {
            return true;
        }
        for k in 0..NV {
            self.acc[k] += d * self.acc[NV + k];
        }
        let ctx = PairCtx::new(self.m1, self.m2, big_m1, big_m2, Some(&self.series));
        ctx.sum_range(-(big_m2 as i64 - 1), -(o2 as i64), &mut self.acc);
        ctx.sum_range(o1 as i64, big_m1 as i64 - 1, &mut self.acc);
        self.counts = (big_m1, big_m2);
        true
    }

    fn sums(&self) -> PairSums {
        assemble(&self.acc, &self.masses, self.counts.0, self.counts.1)
    }
}

/// Fresh pair states kept for the whole process, keyed by `(m1, m2, M1, M2)`: the lag sums are
/// per unit coefficient, so they depend on nothing else, and the channels of one run (same
/// cluster sizes, same counts) need the same ones. Eight channels' final fits computed each pair
/// eight times (BENCHMARKS.md, "session 7"). Each entry is a cell that the first caller fills
/// while later callers of the same key wait for it, so two threads fitting two channels at
/// once compute each pair once. Cleared when it reaches [`SHARED_CAPACITY`] keys.
type SharedFresh = HashMap<(u64, u64, u64, u64), Arc<OnceLock<PairState>>>;

static SHARED_FRESH: Mutex<Option<SharedFresh>> = Mutex::new(None);

/// Keys the process-wide cache holds before it is cleared (a pair state is about 0.5 kB).
const SHARED_CAPACITY: usize = 1024;

/// [`PairState::fresh`] through the process-wide cache ([`SharedFresh`]): the same value,
/// computed once per key.
fn shared_fresh(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairState {
    let key = (m1, m2, big_m1, big_m2);
    let cell = {
        let mut guard = SHARED_FRESH.lock().unwrap_or_else(PoisonError::into_inner);
        let map = guard.get_or_insert_with(HashMap::new);
        if map.len() >= SHARED_CAPACITY && !map.contains_key(&key) {
            map.clear();
        }
        Arc::clone(map.entry(key).or_default())
    };
    cell.get_or_init(|| PairState::fresh(m1, m2, big_m1, big_m2))
        .clone()
}

/// Empties the process-wide cache of fresh pair states, so the next covariance computes every
/// pair (benchmarks of a cold fit call this between iterations).
pub fn clear_shared_cache() {
    let mut guard = SHARED_FRESH.lock().unwrap_or_else(PoisonError::into_inner);
    *guard = None;
}

/// Lag sums by quadrature (see the module doc). `m1, m2 >= 1`, `M1, M2 >= 1`.
pub fn pair_sums(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairSums {
    PairState::fresh(m1, m2, big_m1, big_m2).sums()
}

/// Lag sums at counts `(M1, M2)` reached from `(M1 - d, M2 - d)` by the incremental update the
/// live cache uses (exposed for tests: it must agree with [`pair_sums`]).
pub fn pair_sums_advanced(m1: u64, m2: u64, steps: &[(u64, u64)]) -> Option<PairSums> {
    let (first, rest) = steps.split_first()?;
    let mut st = PairState::fresh(m1, m2, first.0, first.1);
    for &(c1, c2) in rest {
        if !st.advance(c1, c2) {
            return None;
        }
    }
    Some(st.sums())
}

/// Lag sums summed lag by lag over the whole range (the slow reference for [`pair_sums`]).
pub fn pair_sums_exact(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairSums {
    let ctx = PairCtx::new(m1, m2, big_m1, big_m2, None);
    let mut acc = [0.0; 2 * NV];
    for h in -(big_m2 as i64 - 1)..=(big_m1 as i64 - 1) {
        add(&mut acc, &ctx.vals(h as f64, NSER), 1.0);
    }
    assemble(&acc, &masses(m1, m2), big_m1, big_m2)
}

/// The white-phase point masses of a pair: `g_Q(h) = sum_{i,j: h = j m2 - i m1} a_i a_j`, with the
/// continuous terms' values at those lags.
fn masses(m1: u64, m2: u64) -> Vec<(i64, f64, [f64; 3])> {
    let mut out: Vec<(i64, f64, [f64; 3])> = Vec::with_capacity(9);
    for (i, ai) in A.iter().enumerate() {
        for (j, aj) in A.iter().enumerate() {
            let h = j as i64 * m2 as i64 - i as i64 * m1 as i64;
            match out.iter_mut().find(|e| e.0 == h) {
                Some(e) => e.1 += ai * aj,
                None => out.push((h, ai * aj, [0.0; 3])),
            }
        }
    }
    out.retain(|e| e.1 != 0.0);
    for e in &mut out {
        e.2 = g_cont(e.0 as f64, m1 as f64, m2 as f64);
    }
    out
}

/// Unpack the continuous-term sums and add the white-phase point masses (nonzero only where a
/// lag `h + i m1 - j m2` is exactly 0).
fn assemble(acc: &Vals, masses: &[(i64, f64, [f64; 3])], big_m1: u64, big_m2: u64) -> PairSums {
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
    let (fbm1, fbm2) = (big_m1 as f64, big_m2 as f64);
    for &(h, gq, g) in masses {
        let n = pair_count(h as f64, fbm1, fbm2);
        if n <= 0.0 {
            continue;
        }
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

/// Removes repeats from a sorted slice in place; returns the number of distinct values (now at
/// its front).
fn dedup_sorted(v: &mut [i64]) -> usize {
    let mut n = 0;
    for i in 0..v.len() {
        if n == 0 || v[i] != v[n - 1] {
            v[n] = v[i];
            n += 1;
        }
    }
    n
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
        for i in 0..n {
            for j in i..n {
                let (a, b) = (points[i], points[j]);
                let s = self.sums_strided(a, b, i, j, strides);
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
        for i in 0..n {
            for j in i..n {
                let (a, b) = (points[i], points[j]);
                let s = self.sums_strided(a, b, i, j, strides);
                let tau1 = a.m as f64 * tau0_s;
                let tau2 = b.m as f64 * tau0_s;
                let t12 = tau1 * tau1 * tau2 * tau2;
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

/// The far-field series of the flicker cross-covariance at lag `h` (for tests; valid for
/// `|h| > 2 max(m1, m2)`), per unit coefficient with `tau0 = 1`.
pub fn flicker_far_field(h: f64, m1: u64, m2: u64) -> f64 {
    let series = flicker_series(m1 as f64, m2 as f64);
    let mut ctx = PairCtx::new(m1, m2, 1, 1, Some(&series));
    ctx.far = 0.0;
    ctx.g(h, NSER)[1]
}
