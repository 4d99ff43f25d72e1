//! Closed forms of the Allan variance for the five-term model (THEORY.md section 2, the seed
//! paper's formula (3), IEEE Std 952-1997 annex C).

use std::f64::consts::{LN_2, PI};

/// The five terms in the order of the coefficient vector `c = (Q^2, N^2, B^2, K^2, R^2)`.
pub const TERM_NAMES: [&str; 5] = ["Q", "N", "B", "K", "R"];

/// The basis functions of the five-term model at `tau_s`: `AVAR(tau) = sum_i c_i * basis_i(tau)`
/// with `c = (Q^2, N^2, B^2, K^2, R^2)` (THEORY.md section 2).
pub fn basis(tau_s: f64) -> [f64; 5] {
    [
        3.0 / (tau_s * tau_s),
        1.0 / tau_s,
        2.0 * LN_2 / PI,
        tau_s / 3.0,
        tau_s * tau_s / 2.0,
    ]
}

/// Five-term AVAR in u^2/s^2 for coefficients `(Q, N, B, K, R)` (not squared).
pub fn avar(coef: [f64; 5], tau_s: f64) -> f64 {
    basis(tau_s)
        .iter()
        .zip(coef.iter())
        .map(|(b, c)| b * c * c)
        .sum()
}
