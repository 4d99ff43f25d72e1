//! The covariance of the AVAR estimates when the unit's white rate noise passes through an
//! output filter (docs/gap.md, "Low-pass filters beyond first order"): the exact correction to
//! the five-term covariance of [`AvarCovariance`](crate::model::avar_cov::AvarCovariance), which
//! takes `N` unfiltered.
//!
//! # Derivation
//!
//! A linear time-invariant filter `h` on the increments commutes with the second difference of
//! the phase, so the cross-covariance of two second differences of the filtered white rate is
//! the unfiltered one convolved with the filter's two-sided autocorrelation `r_q` (`r_0 = rho_0`,
//! `r_{+-k} = rho_k`, `sum r = 1`; [`LowPass::autocorrelation`]). The white rate's generalised
//! phase covariance is `G_N(t) = -N^2 tau0 |t| / 2` (lags in samples), so the filtered one is
//! `G_N` with `|t|` replaced by `phi(t) = sum_q r_q |t - q|`. Their difference
//! `e(t) = phi(t) - |t|` vanishes once `|t|` exceeds the filter's support (`r` is symmetric), so
//! the second differences' cross-covariance at lag `h` changes only near the nine kinks
//! `kappa = j m2 - i m1` (`i, j` in 0..3, weights `a_i a_j` of `(1, -2, 1)`):
//!
//! ```text
//! delta(h) = -(N^2 tau0 / 2) sum_kappa a_i a_j e(h - kappa)
//! ```
//!
//! With `c12(h)` the unfiltered cross-covariance of the five terms
//! ([`second_difference_cov`]), the Gaussian moments of docs/theory.md section 5 give the
//! correction
//!
//! ```text
//! dCov = g sum_{h in gZ} n(h) [2 delta (2 c12 + delta) + 4 R^2 tau1^2 tau2^2 delta]
//!        / (4 tau1^2 tau2^2 M1 M2)
//! ```
//!
//! where `n(h)` counts the full-overlap pairs at lag `h`, `M1`, `M2` the full-overlap counts of
//! the spans, and the strided estimates meet only on the lattice `gZ`, `g = gcd(s1, s2)` (as
//! [`AvarCovariance::matrix_strided`](crate::model::avar_cov::AvarCovariance::matrix_strided)
//! treats white phase noise, whose cross-covariance is local to the kinks too). The sum is
//! exact: it runs over every lag where `e` is above `1e-12` of its peak.

use crate::model::avar_cov::{second_difference_cov, CovPoint};
use crate::model::lowpass::LowPass;
use nalgebra::DMatrix;

/// Lags of `e(t)` below this fraction of its peak are left out.
const E_TAIL: f64 = 1e-12;
/// Weights of the second difference.
const A: [f64; 3] = [1.0, -2.0, 1.0];

/// `e(t) = sum_q r_q |t - q| - |t|` for `t = 0..=W` (symmetric in `t`), cut where it has
/// decayed below [`E_TAIL`] of its peak.
fn excess(lp: &LowPass, tau0_s: f64) -> Vec<f64> {
    let rho = lp.autocorrelation(tau0_s);
    let k = rho.len().saturating_sub(1) as i64;
    // Two-sided r over q = -k..=k, renormalised to sum 1 (the IIR tails are cut at 1e-15).
    let mut r: Vec<f64> = (-k..=k).map(|q| rho[q.unsigned_abs() as usize]).collect();
    let total: f64 = r.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return vec![0.0];
    }
    for v in r.iter_mut() {
        *v /= total;
    }
    // Prefix sums of r_q and q r_q in index order.
    let n = r.len();
    let mut p0 = vec![0.0; n + 1];
    let mut p1 = vec![0.0; n + 1];
    for (i, v) in r.iter().enumerate() {
        let q = i as i64 - k;
        p0[i + 1] = p0[i] + v;
        p1[i + 1] = p1[i] + q as f64 * v;
    }
    let (s0, s1) = (p0[n], p1[n]);
    let mut e: Vec<f64> = (0..=k)
        .map(|t| {
            // sum_{q <= t} r_q (t - q) + sum_{q > t} r_q (q - t)
            let i = (t + k + 1) as usize; // entries with q <= t
            let (a0, a1) = (p0[i], p1[i]);
            let tf = t as f64;
            (tf * a0 - a1) + ((s1 - a1) - tf * (s0 - a0)) - tf
        })
        .collect();
    let peak = e.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    while e.len() > 1 && e.last().is_some_and(|v| v.abs() <= E_TAIL * peak) {
        e.pop();
    }
    e
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a.max(1)
    } else {
        gcd(b, a % b)
    }
}

/// The correction to add to the five-term covariance `Cov(AVAR_hat_i, AVAR_hat_j)` (u^4/s^4)
/// when `N` is filtered by `lp`; `points`, `strides` and `c = (Q^2, N^2, B^2, K^2, R^2)` as for
/// `matrix_strided`, sampling step `tau0_s`.
pub fn filter_cov_correction(
    tau0_s: f64,
    points: &[CovPoint],
    strides: &[u64],
    c: &[f64; 5],
    lp: &LowPass,
) -> DMatrix<f64> {
    let n = points.len();
    let mut out = DMatrix::zeros(n, n);
    let e = excess(lp, tau0_s);
    let w = e.len() as i64 - 1;
    if w <= 0 || c[1] <= 0.0 {
        return out;
    }
    let scale = [1.0, tau0_s, tau0_s * tau0_s, tau0_s.powi(3)];
    let cs: [f64; 4] = std::array::from_fn(|t| c[t] * scale[t]);
    let e_at = |t: i64| -> f64 {
        let a = t.unsigned_abs() as i64;
        if a > w {
            0.0
        } else {
            e[a as usize]
        }
    };
    let st = |k: usize| strides.get(k).copied().unwrap_or(1).max(1);
    for i in 0..n {
        for j in i..n {
            let (p1, p2) = (points[i], points[j]);
            let (m1, m2) = (p1.m as i64, p2.m as i64);
            let (big1, big2) = (p1.count as i64, p2.count as i64);
            let g = gcd(st(i), st(j)) as i64;
            let mut kinks: Vec<(i64, f64)> = Vec::with_capacity(9);
            for (ii, ai) in A.iter().enumerate() {
                for (jj, aj) in A.iter().enumerate() {
                    kinks.push((jj as i64 * m2 - ii as i64 * m1, ai * aj));
                }
            }
            // The lags within `w` of a kink, merged, on the lattice gZ.
            let mut spans: Vec<(i64, i64)> = kinks.iter().map(|&(k, _)| (k - w, k + w)).collect();
            spans.sort_unstable();
            let mut merged: Vec<(i64, i64)> = Vec::new();
            for s in spans {
                match merged.last_mut() {
                    Some(last) if s.0 <= last.1 + 1 => last.1 = last.1.max(s.1),
                    _ => merged.push(s),
                }
            }
            let (mut quad, mut lin) = (0.0, 0.0);
            for (lo, hi) in merged {
                let mut h = lo.div_euclid(g) * g;
                if h < lo {
                    h += g;
                }
                while h <= hi {
                    // pairs (k, l) with k - l = h, 0 <= k < M1, 0 <= l < M2
                    let cnt = (big2.min(big1 - h) - 0.max(-h)).max(0) as f64;
                    if cnt > 0.0 {
                        let d: f64 = -0.5
                            * cs[1]
                            * kinks.iter().map(|&(k, wt)| wt * e_at(h - k)).sum::<f64>();
                        if d != 0.0 {
                            let gs = second_difference_cov(h, p1.m, p2.m);
                            let c12: f64 = (0..4).map(|t| cs[t] * gs[t]).sum();
                            quad += cnt * d * (2.0 * c12 + d);
                            lin += cnt * d;
                        }
                    }
                    h += g;
                }
            }
            let tau1 = m1 as f64 * tau0_s;
            let tau2 = m2 as f64 * tau0_s;
            let t12 = tau1 * tau1 * tau2 * tau2;
            let v = g as f64 * (2.0 * quad + 4.0 * c[4] * t12 * lin)
                / (4.0 * t12 * big1 as f64 * big2 as f64);
            out[(i, j)] = v;
            out[(j, i)] = v;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `e(t)` of the moving average of two taps by hand: `r = (1/4, 1/2, 1/4)` at q = -1, 0, 1,
    /// so `e(0) = 1/2` and `e(t) = 0` for `|t| >= 1`.
    #[test]
    fn excess_of_two_taps() {
        let e = excess(
            &LowPass::MovingAverage {
                taps: 2,
                stages: 1,
                decimation: 1,
            },
            0.01,
        );
        assert!((e[0] - 0.5).abs() < 1e-12, "{e:?}");
        assert!(e.iter().skip(1).all(|v| v.abs() < 1e-12), "{e:?}");
    }

    /// Brute force: the increments' covariance `N^2 tau0 rho_|k-l|` as a matrix, each second
    /// difference as a weight vector over the increments, `Cov(AVAR_1, AVAR_2) = sum_{k,l}
    /// 2 (b_k' Sigma b_l)^2 / (4 tau1^2 tau2^2 M1 M2)` (Gaussian moments), against the five-term
    /// matrix with `N` unfiltered plus the correction. White phase and flicker in too, so the
    /// cross terms are checked; full overlap, and a stride of 2 on the longer cluster.
    #[test]
    fn matches_brute_force() {
        use crate::model::avar_cov::AvarCovariance;
        let tau0 = 0.01;
        let n_inc = 160usize;
        let c = [0.3f64.powi(2), 2.0f64.powi(2), 0.0, 0.0, 0.0];
        for lp in [
            LowPass::FirstOrder {
                time_constant_s: 0.03,
            },
            LowPass::MovingAverage {
                taps: 4,
                stages: 2,
                decimation: 1,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 6.0,
                damping: 0.4,
                form: crate::model::lowpass::SecondOrderForm::PoleMapped,
            },
        ] {
            let rho = lp.autocorrelation(tau0);
            let cov_inc = |k: usize, l: usize| {
                let d = k.abs_diff(l);
                let f = c[1] * tau0 * rho.get(d).copied().unwrap_or(0.0);
                f
            };
            // Second difference of the phase as weights on the increments (phase x_t = sum of
            // increments before t; white phase Q added on x separately).
            let dvec = |k: usize, m: usize| {
                let mut b = vec![0.0; n_inc];
                for (i, a) in A.iter().enumerate() {
                    for v in b.iter_mut().take(k + i * m) {
                        *v += a;
                    }
                }
                b
            };
            let cov_d = |k1: usize, m1: usize, k2: usize, m2: usize| {
                let (b1, b2) = (dvec(k1, m1), dvec(k2, m2));
                let mut s = 0.0;
                for (x, bx) in b1.iter().enumerate() {
                    if *bx == 0.0 {
                        continue;
                    }
                    for (y, by) in b2.iter().enumerate() {
                        if *by != 0.0 {
                            s += bx * by * cov_inc(x, y);
                        }
                    }
                }
                // white phase: x_t has its own error of variance Q^2 at each t
                for (i, ai) in A.iter().enumerate() {
                    for (j, aj) in A.iter().enumerate() {
                        if k1 + i * m1 == k2 + j * m2 {
                            s += ai * aj * c[0];
                        }
                    }
                }
                s
            };
            for &(m1, m2, s2) in &[(1u64, 3u64, 1u64), (2, 5, 1), (3, 8, 2), (6, 6, 1)] {
                let big1 = n_inc as u64 - 2 * m1 + 1;
                let big2 = n_inc as u64 - 2 * m2 + 1;
                let mut brute = 0.0;
                for k1 in 0..big1 as usize {
                    for k2 in (0..big2 as usize).step_by(s2 as usize) {
                        let v = cov_d(k1, m1 as usize, k2, m2 as usize);
                        brute += 2.0 * v * v;
                    }
                }
                let (t1, t2) = (m1 as f64 * tau0, m2 as f64 * tau0);
                let n2 = (big2 as usize).div_ceil(s2 as usize) as f64;
                brute /= 4.0 * t1 * t1 * t2 * t2 * big1 as f64 * n2;
                let pts = [
                    CovPoint { m: m1, count: big1 },
                    CovPoint { m: m2, count: big2 },
                ];
                let strides = [1, s2];
                let five = AvarCovariance::new().matrix_strided(tau0, &pts, &strides, &c);
                let corr = filter_cov_correction(tau0, &pts, &strides, &c, &lp);
                let ours = five[(0, 1)] + corr[(0, 1)];
                // Exact at full overlap; a stride puts the pairs on a lattice whose count per
                // lag the sums take as the full overlap's times g / (s1 s2).
                let tol = if s2 == 1 { 1e-9 } else { 0.02 };
                assert!(
                    (ours / brute - 1.0).abs() < tol,
                    "{lp:?} m {m1},{m2} stride {s2}: {ours} vs brute {brute} (unfiltered {})",
                    five[(0, 1)]
                );
            }
        }
    }
}
