//! Equivalent degrees of freedom (edf) of the Allan-family estimators and their chi-squared
//! confidence intervals (docs/theory.md section 4).
//!
//! The edf is Greenhall's algorithm: C. A. Greenhall and W. J. Riley, "Uncertainty of stability
//! variances based on finite differences", 35th PTTI meeting, 2003 (the method Stable32 and
//! allantools' `edf_greenhall` use). It assumes one power-law noise `S_y(f) ~ f^alpha` and Gaussian
//! data. Which `alpha` applies at a tau is decided elsewhere ([`super::noise_id`]); which stride the
//! estimator used is the accumulator's business ([`super::accum`]), passed in here as a number.
//!
//! The estimators are described by five numbers (the paper's notation):
//! - `d`: order of the phase difference (2 for AVAR and MVAR, 3 for HVAR),
//! - `m`: cluster size, `tau = m tau0`,
//! - `F`: filter factor, `F = m` for the unmodified variances (AVAR, HVAR), `F = 1` for the
//!   modified one (MVAR, which averages phase over `tau`),
//! - `S`: stride factor, differences are taken every `m / S` samples (`S = m`: fully overlapped,
//!   `S = 1`: non-overlapped),
//! - `N`: number of phase points.

use crate::stats::chi2_quantile;

use super::Stat;

/// The paper's `J_max`: above this many lag terms the exact sum gives way to the asymptotic forms
/// of its tables 1 to 3, which keeps one evaluation below a few thousand logarithms.
pub const J_MAX: u64 = 100;

/// Slack for `floor` of quantities that are integers in exact arithmetic (`S (N - L) / m`,
/// `(d + 1) S`) but may land a few ulps below one in floating point when `S` is `m / stride`.
const FLOOR_SLACK: f64 = 1e-9;

/// The filter factor `F` as it enters the covariance functions: a finite value, or the limit
/// `F -> infinity` the paper substitutes for large `m` (its equation (8)).
#[derive(Debug, Clone, Copy)]
enum Filter {
    Finite(f64),
    Infinite,
}

/// Greenhall's `sw(t, alpha)`, the generalized autocovariance of phase for power-law noise `alpha`
/// up to a constant factor (equation (7) of the paper).
fn sw(t: f64, alpha: i32) -> f64 {
    let t_ln = |p: i32| {
        if t == 0.0 {
            0.0
        } else {
            t.powi(p) * t.abs().ln()
        }
    };
    match alpha {
        2 => -t.abs(),
        1 => t_ln(2),
        0 => t.abs().powi(3),
        -1 => t_ln(4),
        -2 => t.abs().powi(5),
        -3 => t_ln(6),
        -4 => t.abs().powi(7),
        // Callers check alpha first; anything else has no covariance here.
        _ => f64::NAN,
    }
}

/// `sx(t, F, alpha)`: the covariance of phase averaged over `tau / F` (equation (8)).
fn sx(t: f64, f: Filter, alpha: i32) -> f64 {
    match f {
        Filter::Infinite => sw(t, alpha + 2),
        Filter::Finite(f) => {
            let h = 1.0 / f;
            f * f * (2.0 * sw(t, alpha) - sw(t - h, alpha) - sw(t + h, alpha))
        }
    }
}

/// Binomial coefficient for the small arguments used here (`n <= 12`).
fn binom(n: u32, k: u32) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * f64::from(n - i) / f64::from(i + 1))
}

/// `sz(t, F, alpha, d)`: covariance of the `d`-th phase difference at lag `t` (in units of `tau`),
/// the `2d`-th central difference of `sx` (equation (9)).
fn sz(t: f64, f: Filter, alpha: i32, d: u32) -> f64 {
    let di = d as i32;
    (-di..=di)
        .map(|k| {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            sign * binom(2 * d, (di + k) as u32) * sx(t + f64::from(k), f, alpha)
        })
        .sum()
}

/// The paper's `BasicSum(J, M, S, F, alpha, d)` (equation (10)): the variance of the sum of `M`
/// squared differences, lags `j / S` for `j < J`, with the lag `J` term weighted as an end point.
fn basic_sum(j_terms: u64, m_terms: f64, s: f64, f: Filter, alpha: i32, d: u32) -> f64 {
    let sz2 = |j: u64| sz(j as f64 / s, f, alpha, d).powi(2);
    let mut sum = sz2(0);
    if j_terms >= 1 {
        sum += (1.0 - j_terms as f64 / m_terms) * sz2(j_terms);
    }
    for j in 1..j_terms {
        sum += 2.0 * (1.0 - j as f64 / m_terms) * sz2(j);
    }
    sum
}

/// Table 1 of the paper: `(a0, a1)` of `1/edf ~ (a0 - a1/r)/r` for the modified variances.
fn table1(alpha: i32, d: u32) -> Option<(f64, f64)> {
    let v = match (alpha, d) {
        (2, 1) => (2.0 / 3.0, 1.0 / 3.0),
        (2, 2) => (7.0 / 9.0, 1.0 / 2.0),
        (2, 3) => (22.0 / 25.0, 2.0 / 3.0),
        (1, 1) => (0.840, 0.345),
        (1, 2) => (0.997, 0.616),
        (1, 3) => (1.141, 0.843),
        (0, 1) => (1.079, 0.368),
        (0, 2) => (1.033, 0.607),
        (0, 3) => (1.184, 0.848),
        (-1, 2) => (1.048, 0.534),
        (-1, 3) => (1.180, 0.816),
        (-2, 2) => (1.302, 0.535),
        (-2, 3) => (1.175, 0.777),
        (-3, 3) => (1.194, 0.703),
        (-4, 3) => (1.489, 0.702),
        _ => return None,
    };
    Some(v)
}

/// Table 2 of the paper: `(a0, a1)` for the unmodified variances.
fn table2(alpha: i32, d: u32) -> Option<(f64, f64)> {
    let v = match (alpha, d) {
        (2, 1) => (3.0 / 2.0, 1.0 / 2.0),
        (2, 2) => (35.0 / 18.0, 1.0),
        (2, 3) => (231.0 / 100.0, 3.0 / 2.0),
        (1, 1) => (78.6, 25.2),
        (1, 2) => (790.0, 410.0),
        (1, 3) => (9950.0, 6520.0),
        (0, 1) => (2.0 / 3.0, 1.0 / 6.0),
        (0, 2) => (2.0 / 3.0, 1.0 / 3.0),
        (0, 3) => (7.0 / 9.0, 1.0 / 2.0),
        (-1, 2) => (0.852, 0.375),
        (-1, 3) => (0.997, 0.617),
        (-2, 2) => (1.079, 0.368),
        (-2, 3) => (1.033, 0.607),
        (-3, 3) => (1.053, 0.553),
        (-4, 3) => (1.302, 0.535),
        _ => return None,
    };
    Some(v)
}

/// Table 3 of the paper: `sz(0, m, 1, d) ~ b0 + b1 ln m` for flicker PM, unmodified.
fn table3(d: u32) -> Option<(f64, f64)> {
    match d {
        1 => Some((6.0, 4.0)),
        2 => Some((15.23, 12.0)),
        3 => Some((47.8, 40.0)),
        _ => None,
    }
}

/// Greenhall's equivalent degrees of freedom of an Allan-family variance estimate.
///
/// `alpha` is the power-law exponent of `S_y` (+2 white PM ... -2 random-walk FM; -3 and -4 need
/// `d = 3`), `d` the difference order (1, 2 or 3; the paper requires `alpha + 2d > 1`), `m` the
/// cluster size, `f` the filter factor (`m`: unmodified, `1`: modified; no other value is defined),
/// `s` the stride factor (differences every `m / s` samples; `s` need not be an integer) and
/// `n_phase` the number of phase points. Returns `None` for an unsupported combination or when the
/// data are shorter than one difference (`N < m/F + m d`).
pub fn greenhall_edf(alpha: i32, d: u32, m: u64, f: u64, s: f64, n_phase: u64) -> Option<f64> {
    if !(1..=3).contains(&d) || !(-4..=2).contains(&alpha) || alpha + 2 * d as i32 <= 1 {
        return None;
    }
    if m == 0 || !(s.is_finite() && s > 0.0) || (f != 1 && f != m) {
        return None;
    }
    let modified = f == 1;
    let (mf, sf) = (m as f64, s);
    let df = f64::from(d);
    // L: the span of one difference in samples; M: how many differences fit (paper, section 4).
    let span = (m / f + m * u64::from(d)) as f64;
    let n = n_phase as f64;
    if n < span {
        return None;
    }
    let m_terms = 1.0 + (sf * (n - span) / mf + FLOOR_SLACK).floor();
    let j_lags = ((df + 1.0) * sf + FLOOR_SLACK).floor().max(1.0);
    let j_terms = m_terms.min(j_lags) as u64;
    let r = m_terms / sf;
    let jmax = J_MAX as f64;

    let inv_edf = if modified {
        // Case 1: modified variances, every alpha.
        let f1 = Filter::Finite(1.0);
        let norm = sz(0.0, f1, alpha, d).powi(2);
        if j_terms <= J_MAX {
            basic_sum(j_terms, m_terms, sf, f1, alpha, d) / (norm * m_terms)
        } else if r > df + 1.0 {
            let (a0, a1) = table1(alpha, d)?;
            (a0 - a1 / r) / r
        } else {
            let m_prime = jmax / r;
            basic_sum(J_MAX, jmax, m_prime, f1, alpha, d) / (norm * jmax)
        }
    } else if alpha <= 0 {
        // Case 2: unmodified, alpha <= 0.
        if j_terms <= J_MAX {
            let filt = if mf * (df + 1.0) <= jmax {
                Filter::Finite(mf)
            } else {
                Filter::Infinite
            };
            let norm = sz(0.0, filt, alpha, d).powi(2);
            basic_sum(j_terms, m_terms, sf, filt, alpha, d) / (norm * m_terms)
        } else if r > df + 1.0 {
            let (a0, a1) = table2(alpha, d)?;
            (a0 - a1 / r) / r
        } else {
            let m_prime = jmax / r;
            let norm = sz(0.0, Filter::Infinite, alpha, d).powi(2);
            basic_sum(J_MAX, jmax, m_prime, Filter::Infinite, alpha, d) / (norm * jmax)
        }
    } else if alpha == 1 {
        // Case 3: unmodified, flicker PM. The exact sum differences t^2 ln t at step 1/m, fine in
        // f64 for m below about 1e6 (the paper's caveat).
        if j_terms <= J_MAX {
            let filt = Filter::Finite(mf);
            let norm = sz(0.0, filt, 1, d).powi(2);
            basic_sum(j_terms, m_terms, sf, filt, 1, d) / (norm * m_terms)
        } else {
            let (b0, b1) = table3(d)?;
            let norm = (b0 + b1 * mf.ln()).powi(2);
            if r > df + 1.0 {
                let (a0, a1) = table2(1, d)?;
                (a0 - a1 / r) / (norm * r)
            } else {
                let m_prime = jmax / r;
                basic_sum(J_MAX, jmax, m_prime, Filter::Finite(m_prime), 1, d) / (norm * jmax)
            }
        }
    } else {
        // Case 4: unmodified, white PM. Differences correlate only at whole multiples of tau,
        // with correlation C(2d, d-k)/C(2d, d) at lag k.
        let k_lags = r.ceil();
        let c0 = binom(2 * d, d);
        if k_lags <= df {
            let mut sum = 1.0;
            for k in 1..(k_lags as u32) {
                let rho = binom(2 * d, d - k) / c0;
                sum += 2.0 * (1.0 - f64::from(k) / r) * rho * rho;
            }
            sum / m_terms
        } else {
            let a0 = binom(4 * d, 2 * d) / (c0 * c0);
            let a1 = df / 2.0;
            (a0 - a1 / r) / m_terms
        }
    };
    let edf = 1.0 / inv_edf;
    (edf.is_finite() && edf > 0.0).then_some(edf)
}

/// The edf of one statistic of [`Stat`] at cluster `m`, for `n_phase` phase points, when the
/// estimator takes a difference every `stride` samples (1: fully overlapped, as in docs/theory.md
/// section 1; `m`: non-overlapped; the bounded-memory mode uses `max(1, m / L)`).
///
/// Maps to [`greenhall_edf`] with `d` from [`Stat::diff_order`], `F = 1` for MVAR and `F = m`
/// otherwise, and `S = m / stride`. The estimator is assumed to average
/// `1 + floor((N - L) / stride)` differences (`L = m/F + m d`), which is the count of the
/// overlapped formulas of docs/theory.md section 1 when `stride = 1`. For MVAR, each difference is
/// taken to average all `m` phase second differences of its window.
pub fn edf(stat: Stat, alpha: i32, m: u64, stride: u64, n_phase: u64) -> Option<f64> {
    if m == 0 || stride == 0 {
        return None;
    }
    let f = match stat {
        Stat::Mvar => 1,
        Stat::Avar | Stat::Hvar => m,
    };
    let s = m as f64 / stride as f64;
    greenhall_edf(alpha, stat.diff_order(), m, f, s, n_phase)
}

/// Chi-squared confidence interval of a variance (docs/theory.md section 4):
/// `[edf var / chi2_{(1+c)/2}(edf), edf var / chi2_{(1-c)/2}(edf)]` for a two-sided confidence
/// `c` in (0, 1) (0.683 is Stable32's one-sigma interval, 0.95 the curve records'). `edf` need not
/// be an integer. Returns `None` for `edf <= 0`, a confidence outside (0, 1) or a non-finite or
/// negative variance. The deviation's interval is the square root of both ends
/// ([`sigma_interval`]).
pub fn chi2_interval(var: f64, edf: f64, confidence: f64) -> Option<(f64, f64)> {
    let var_ok = var.is_finite() && var >= 0.0;
    let conf_ok = confidence > 0.0 && confidence < 1.0;
    if !(var_ok && conf_ok && edf.is_finite() && edf > 0.0) {
        return None;
    }
    let tail = (1.0 - confidence) / 2.0;
    let q_hi = chi2_quantile(edf, 1.0 - tail);
    let q_lo = chi2_quantile(edf, tail);
    if !(q_hi.is_finite() && q_lo > 0.0) {
        return None;
    }
    Some((edf * var / q_hi, edf * var / q_lo))
}

/// Interval of the deviation `sigma` (u/s): the square roots of [`chi2_interval`] of `sigma^2`.
pub fn sigma_interval(sigma: f64, edf: f64, confidence: f64) -> Option<(f64, f64)> {
    let (lo, hi) = chi2_interval(sigma * sigma, edf, confidence)?;
    Some((lo.sqrt(), hi.sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative agreement expected between two evaluations of the same closed form.
    const EXACT: f64 = 1e-12;
    /// Tables 1 to 3 of the paper are fits printed to 3 or 4 digits; the exact sums they summarize
    /// should agree with them to about this, far out in `r`.
    const TABLE_FIT: f64 = 1e-3;
    /// The flicker PM row of table 2 (790, 410; 9950, 6520) carries only 2 to 3 digits.
    const TABLE_FIT_FPM: f64 = 1e-2;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    /// The exact sum without the `J_MAX` cut-off, fully overlapped: modified (`F = 1`) or
    /// unmodified (`F = m` for flicker PM, otherwise the large-`m` limit `F = infinity`).
    fn inv_edf_uncut(alpha: i32, d: u32, m: u64, modified: bool, n_phase: u64) -> f64 {
        let (mf, df) = (m as f64, f64::from(d));
        let f = match (modified, alpha) {
            (true, _) => Filter::Finite(1.0),
            (false, 1) => Filter::Finite(mf),
            (false, _) => Filter::Infinite,
        };
        let span = if modified {
            mf + mf * df
        } else {
            1.0 + mf * df
        };
        let m_terms = 1.0 + (n_phase as f64 - span).floor();
        let j_terms = m_terms.min((df + 1.0) * mf) as u64;
        basic_sum(j_terms, m_terms, mf, f, alpha, d) / (sz(0.0, f, alpha, d).powi(2) * m_terms)
    }

    #[test]
    fn tables_summarize_the_exact_sum() {
        // Far out in r (M/S = 100) with S = m = 200 the paper switches to its tables; the uncut
        // sum (J = (d+1) m lags) is what they approximate; unmodified flicker PM goes through
        // tables 2 and 3 together. Measured: all within 4e-4, unmodified flicker PM 4e-3.
        let m = 200u64;
        for d in 2..=3u32 {
            for alpha in [2, 1, 0, -1, -2, -3, -4] {
                if alpha + 2 * d as i32 <= 1 {
                    continue;
                }
                let n = m * (d as u64) + 100 * m;
                for modified in [false, true] {
                    if !modified && alpha == 2 {
                        continue; // case 4 is a closed form, not a table
                    }
                    let f = if modified { 1 } else { m };
                    let table = 1.0 / greenhall_edf(alpha, d, m, f, m as f64, n).unwrap();
                    let exact = inv_edf_uncut(alpha, d, m, modified, n);
                    let tol = if alpha == 1 && !modified {
                        TABLE_FIT_FPM
                    } else {
                        TABLE_FIT
                    };
                    assert!(
                        rel(table, exact) < tol,
                        "alpha {alpha} d {d} modified {modified}: table {table} exact {exact}"
                    );
                }
            }
        }
    }

    #[test]
    fn flicker_pm_normalization_matches_table3() {
        // sz(0, m, 1, d) grows as b0 + b1 ln m (table 3); derived by hand for d = 2:
        // 12 ln m + 24 - 4 ln 2 - 6 = 12 ln m + 15.227.
        for d in 1..=3u32 {
            let (b0, b1) = table3(d).unwrap();
            let m = 1000.0;
            let exact = sz(0.0, Filter::Finite(m), 1, d).abs();
            assert!(rel(exact, b0 + b1 * f64::ln(m)) < 1e-3, "d {d}: {exact}");
        }
    }

    #[test]
    fn white_fm_non_overlapped_is_the_closed_form() {
        // Non-overlapped AVAR of white FM: successive second differences m (ybar_{k+1} - ybar_k)
        // correlate -1/2 at lag 1 and not beyond, so Var(sum z^2) = 2 sigma^4 (M + (M-1)/2) and
        // edf = 2 M^2 / (3M - 1) (hand derivation), about 2M/3 rather than the M differences.
        // With m (d+1) > J_MAX the paper's filter is F = infinity, which is exactly this model.
        for (m, blocks) in [(64u64, 10u64), (64, 50), (1000, 200)] {
            let n = m * blocks + 1;
            let mt = (blocks - 1) as f64; // M = 1 + floor((N - 1 - 2m)/m) = blocks - 1
            let expect = 2.0 * mt * mt / (3.0 * mt - 1.0);
            let got = edf(Stat::Avar, 0, m, m, n).unwrap();
            assert!(rel(got, expect) < EXACT, "m {m}: {got} vs {expect}");
        }
    }

    #[test]
    fn white_fm_strided_is_the_exact_covariance_sum() {
        // docs/theory.md section 4: edf = 2 AVAR^2 / Var(AVAR_hat) = M^2 c(0)^2 / sum_{k,l} c(k-l)^2
        // for Gaussian differences z_k taken every `stride` samples. For white FM (unit variance
        // per sample) c(h) = 2m - 3|h| for |h| <= m and -(2m - |h|) for m <= |h| <= 2m (the
        // autocorrelation of the -1/+1 window of length 2m). With m (d+1) > J_MAX the paper's
        // filter is F = infinity, sampled Brownian phase, which is this process exactly, and its
        // lags reach 3m > 2m, so nothing is cut off.
        let m = 64u64;
        let n = 64 * 40 + 1;
        let c = |h: i64| -> f64 {
            let (h, m) = (h.abs(), m as i64);
            if h <= m {
                (2 * m - 3 * h) as f64
            } else if h <= 2 * m {
                -((2 * m - h) as f64)
            } else {
                0.0
            }
        };
        let mut last = f64::INFINITY;
        for stride in [1u64, 2, 8, 32, 64] {
            let mt = 1 + (n - 1 - 2 * m) / stride; // differences that fit
            let mut sum = 0.0;
            for k in 0..mt as i64 {
                for l in 0..mt as i64 {
                    sum += c((k - l) * stride as i64).powi(2);
                }
            }
            let exact = (mt as f64 * c(0)).powi(2) / sum;
            let got = edf(Stat::Avar, 0, m, stride, n).unwrap();
            // Full overlap has J = 3m = 192 > J_MAX lags: the paper's table 2 takes over.
            let tol = if 3 * m / stride > J_MAX {
                TABLE_FIT
            } else {
                EXACT
            };
            assert!(rel(got, exact) < tol, "stride {stride}: {got} vs {exact}");
            // Sparser differences never add degrees of freedom.
            assert!(got <= last, "stride {stride}: {got} > {last}");
            last = got;
        }
    }

    #[test]
    fn white_pm_non_overlapped_is_the_closed_form() {
        // Non-overlapped AVAR of white PM: z_k = x_{k+2} - 2x_{k+1} + x_k (in units of m) has
        // correlations -4/6 and 1/6 at lags 1 and 2, so
        // 1/edf = (M + 2(M-1)(4/9) + 2(M-2)(1/36)) / M^2 = (35/18 - 1/M)/M (hand derivation).
        for (m, blocks) in [(1u64, 1000u64), (8, 30), (100, 3)] {
            let n = m * blocks + 1;
            let mt = (blocks - 1) as f64;
            let inv =
                (mt + 2.0 * (mt - 1.0) * 4.0 / 9.0 + 2.0 * (mt - 2.0).max(0.0) / 36.0) / (mt * mt);
            let got = edf(Stat::Avar, 2, m, m, n).unwrap();
            assert!(rel(got, 1.0 / inv) < EXACT, "m {m}: {got} vs {}", 1.0 / inv);
        }
    }

    #[test]
    fn rejects_what_the_paper_does_not_define() {
        assert_eq!(greenhall_edf(-2, 1, 4, 4, 4.0, 1000), None); // alpha + 2d <= 1
        assert_eq!(greenhall_edf(-3, 2, 4, 4, 4.0, 1000), None);
        assert_eq!(greenhall_edf(0, 2, 4, 2, 4.0, 1000), None); // F neither 1 nor m
        assert_eq!(edf(Stat::Avar, 0, 10, 1, 20), None); // N < L = 21
        assert!(edf(Stat::Avar, 0, 10, 1, 21).is_some());
        assert_eq!(chi2_interval(1.0, 0.0, 0.95), None);
        assert_eq!(chi2_interval(1.0, 10.0, 1.0), None);
        assert_eq!(chi2_interval(f64::NAN, 10.0, 0.9), None);
    }

    #[test]
    fn chi2_interval_matches_tabulated_quantiles() {
        // chi2 quantiles for 10 degrees of freedom (standard tables, e.g. NIST SP 1065 table 4):
        // chi2_{0.025}(10) = 3.247, chi2_{0.975}(10) = 20.483.
        let (lo, hi) = chi2_interval(1.0, 10.0, 0.95).unwrap();
        assert!(rel(lo, 10.0 / 20.483) < 1e-4, "{lo}");
        assert!(rel(hi, 10.0 / 3.247) < 1e-4, "{hi}");
    }
}
