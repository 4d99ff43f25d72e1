//! The far-field series of the flicker (B) cross-covariance of two second differences: a
//! Taylor expansion in `1 / h`, used where every lag is far from the origin (no logarithms,
//! and none of the cancellation the direct nine-term sum suffers there).

use std::f64::consts::PI;

/// Terms of the far-field series of the flicker cross-covariance (orders `h^-2 .. h^-(NSER+1)`).
pub(super) const NSER: usize = 23;
/// The series is used where `|h| >= FAR_FACTOR * max(m1, m2)`: there every lag `h + i m1 - j m2`
/// is within a factor `1 +- 1/8` of `h`, the N and K cross-covariances are exactly 0, and the
/// terms fall by 8 per order, so 23 orders reach 1e-19 of the leading one.
pub(super) const FAR_FACTOR: f64 = 16.0;

/// Relative size, against the leading term, of the far-field terms a window may leave out:
/// 2^-64, far below rounding.
pub(super) const SERIES_TOL: f64 = 5.421_010_862_427_522e-20;

/// Far-field expansion of `g_B(h) = sum_{i,j} a_i a_j G_B(h + i m1 - j m2)`.
///
/// Taylor expansion of `G_B(h + d)` about `h`: with `G_B^(n)(t) = (-1)^(n-3) (n-3)! / (pi t^(n-2))`
/// for `n >= 3`, and `mu_n = sum_{i,j} a_i a_j (i m1 - j m2)^n` vanishing for `n < 4` (the second
/// differences annihilate lines), `g_B(h) = sum_{n>=4} mu_n (-1)^(n-3) / (n (n-1) (n-2) pi h^(n-2))`,
/// convergent for `|h| > 2 max(m1, m2)`. `mu_n` is summed binomially,
/// `mu_n = sum_{p=2}^{n-2} C(n, p) (2^p - 2) (2^(n-p) - 2) m1^p (-m2)^(n-p)`, with `m` scaled by
/// `max(m1, m2)` (no overflow, and no cancellation of large powers when `m1 << m2`). Leading term:
/// `-(m1 m2)^2 / (pi h^2)`.
pub(super) fn flicker_series(m1: f64, m2: f64) -> [f64; NSER] {
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
