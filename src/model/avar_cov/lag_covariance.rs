//! The cross-covariance of two second differences at a lag, under each random term of the
//! five-term model: the generalized covariance functions `G(t)` of the module
//! [`super`] applied with the weights `(1, -2, 1)` twice, written so that large terms cancel
//! analytically (docs/theory.md section 5).

use std::f64::consts::PI;

/// Weights of the second difference.
pub(super) const A: [f64; 3] = [1.0, -2.0, 1.0];

/// `sum_i a_i G_N(u + i m)` for `G_N(t) = -|t|/2`.
pub(super) fn inner_n(u: f64, m: f64) -> f64 {
    -(u.abs() - 2.0 * (u + m).abs() + (u + 2.0 * m).abs()) / 2.0
}

/// `sum_i a_i G_K(u + i m)` for `G_K(t) = |t|^3/12`; outside `(-2m, 0)` all three lags share a
/// sign and the sum is exactly `m^2 |u + m| / 2` (no cancellation of large cubes).
pub(super) fn inner_k(u: f64, m: f64) -> f64 {
    if u >= 0.0 || u <= -2.0 * m {
        m * m * (u + m).abs() / 2.0
    } else {
        let c = |t: f64| t.abs().powi(3) / 12.0;
        c(u) - 2.0 * c(u + m) + c(u + 2.0 * m)
    }
}

/// `G_B(t) = t^2 ln|t| / (2 pi)`, 0 at 0.
pub(super) fn g_b(t: f64) -> f64 {
    if t == 0.0 {
        0.0
    } else {
        t * t * t.abs().ln() / (2.0 * PI)
    }
}

/// `sum_i a_i G_B(u + i m)`. Far from the origin (all lags of one sign, `|u| >= 2m`), written as
/// `2 m^2 ln|u| + sum_i a_i (u + i m)^2 ln(1 + i m / u)` so the large `u^2 ln|u|` parts cancel
/// analytically.
pub(super) fn inner_b(u: f64, m: f64) -> f64 {
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
pub(super) fn g_cont(h: f64, m1: f64, m2: f64) -> [f64; 3] {
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
pub(super) fn pair_count(h: f64, big_m1: f64, big_m2: f64) -> f64 {
    ((big_m2).min(big_m1 - h) - (-h).max(0.0)).max(0.0)
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
