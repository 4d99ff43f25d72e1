//! Power-law noise identification at one cluster size by the lag-1 autocorrelation (W. J. Riley
//! and C. A. Greenhall, "Power law noise identification using the lag 1 autocorrelation", 18th
//! EFTF, 2004), giving the `alpha` that [`super::edf`] needs (docs/theory.md section 4).
//!
//! At cluster `m` the method looks at the `m`-averaged frequency `ybar`, successive blocks `m`
//! samples apart, and at its first and second differences (the second and third differences of
//! phase). The lag-1 autocorrelation `r1` of a series says how it is correlated with the next
//! block: for power-law noise with `S_y ~ f^alpha`, `delta = r1 / (1 + r1)` is about `-alpha/2`
//! once the series is stationary. Each difference lowers `alpha` by 2.
//!
//! The streaming accumulators do not keep the data; they supply the three autocorrelations
//! ([`Lag1`]) computed as [`lag1_batch`] does. This module only turns them into an exponent, and
//! [`lag1_batch`] is the slow reference on a phase array.

use super::Stat;

/// Fewest non-overlapping blocks of `m` samples a series must span before [`lag1_batch`] reports
/// its autocorrelation. Riley and Greenhall ask for at least about 30 points; the sampling
/// spread of `r1` is about `1/sqrt(blocks)`, so with fewer the rounding below is a coin toss.
pub const MIN_BLOCKS: usize = 30;

/// Riley and Greenhall's stopping threshold: the series is taken as stationary, and differencing
/// stops, once `delta = r1/(1+r1)` falls below 1/4 (halfway between white FM, 0, and flicker FM,
/// 1/2).
const DELTA_STATIONARY: f64 = 0.25;

/// Lag-1 autocorrelations at one cluster size `m`: `r1[d]` belongs to the `d`-times differenced
/// overlapping averaged-frequency series (`d = 0`: `ybar_k`; `d = 1`: `ybar_{k+m} - ybar_k`, the
/// second difference of phase; `d = 2`: the third difference), at lag `m` samples. `None` where
/// the series is too short or constant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Lag1 {
    pub r1: [Option<f64>; 3],
}

/// An identified power-law exponent of `S_y(f) ~ f^alpha` at one cluster size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseEstimate {
    /// `p` rounded and clamped to what the edf supports for this `dmax` (+2 white PM, +1 flicker
    /// PM, 0 white FM, -1 flicker FM, -2 random-walk FM; -3 and -4 only with `dmax = 2`).
    pub alpha: i32,
    /// The unrounded estimate `p = -2 (delta + d)`.
    pub p: f64,
    /// Number of differences taken before the series looked stationary.
    pub d: usize,
}

/// The most differences of the averaged-frequency series worth taking for a statistic: the
/// statistic's own phase difference order minus one (1 for AVAR and MVAR, 2 for HVAR), as Riley
/// and Greenhall use `dmax` = 2 or 3 on phase.
pub fn dmax_for(stat: Stat) -> usize {
    stat.diff_order() as usize - 1
}

/// Riley and Greenhall's rule on averaged-frequency data: starting at `d = 0`, take
/// `delta = r1[d] / (1 + r1[d])`; while `delta >= 1/4` and `d < dmax`, difference once more;
/// then `p = -2 (delta + d)` and `alpha = round(p)`, clamped to `[-2 dmax, 2]` (the range the
/// matching statistic's edf is defined for). `dmax` above 2 is taken as 2. Returns `None` when an
/// autocorrelation the rule needs is missing or not finite.
pub fn alpha_from_lag1(lag: &Lag1, dmax: usize) -> Option<NoiseEstimate> {
    let dmax = dmax.min(lag.r1.len() - 1);
    let mut d = 0;
    loop {
        let r1 = lag.r1[d].filter(|r| r.is_finite())?;
        // r1 = -1 (a series that flips sign every block) would be the limit delta -> -inf: the
        // smoothest phase noise there is, so white PM after clamping.
        let delta = if r1 <= -1.0 {
            f64::NEG_INFINITY
        } else {
            r1 / (1.0 + r1)
        };
        if delta < DELTA_STATIONARY || d == dmax {
            let p = -2.0 * (delta + d as f64);
            let alpha_min = -2 * dmax as i32;
            let alpha = if p.is_finite() {
                (p.round() as i32).clamp(alpha_min, 2)
            } else {
                2
            };
            return Some(NoiseEstimate { alpha, p, d });
        }
        d += 1;
    }
}

/// Lag-`m` autocorrelation of a series with its mean removed:
/// `sum_{k < n-m} (u_k - u_mean)(u_{k+m} - u_mean) / sum_{k < n} (u_k - u_mean)^2`
/// (Riley and Greenhall's equation (2), with the lag counted in samples of an overlapping series).
fn lag_autocorrelation(u: &[f64], m: usize) -> Option<f64> {
    let n = u.len();
    if m == 0 || n < MIN_BLOCKS * m {
        return None;
    }
    let mean = u.iter().sum::<f64>() / n as f64;
    let den: f64 = u.iter().map(|v| (v - mean) * (v - mean)).sum();
    let num: f64 = u
        .iter()
        .zip(&u[m..])
        .map(|(a, b)| (a - mean) * (b - mean))
        .sum();
    let r = num / den;
    (den > 0.0 && r.is_finite()).then_some(r)
}

/// The three autocorrelations of [`Lag1`] straight from phase points (any unit; the `tau` scale
/// cancels): `ybar_k ~ x_{k+m} - x_k` for `k = 0 .. N-m-1`, then differences at lag `m`, each
/// series's autocorrelation at lag `m` with its own mean removed, no detrending (differencing
/// removes frequency offset and drift). `r1[d]` is `None` when its series spans fewer than
/// [`MIN_BLOCKS`] blocks of `m` samples, or is constant.
pub fn lag1_batch(phase: &[f64], m: usize) -> Lag1 {
    let mut out = Lag1::default();
    if m == 0 || phase.len() <= m {
        return out;
    }
    let lag_diff = |u: &[f64]| -> Vec<f64> {
        u.iter()
            .zip(&u[m.min(u.len())..])
            .map(|(a, b)| b - a)
            .collect()
    };
    let mut series = lag_diff(phase);
    for slot in out.r1.iter_mut() {
        *slot = lag_autocorrelation(&series, m);
        if series.len() <= m {
            break;
        }
        series = lag_diff(&series);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rule_on_textbook_autocorrelations() {
        // Expected lag-1 autocorrelations of the undifferenced averaged frequency
        // (Riley and Greenhall 2004, table 1 in terms of delta): white PM r1 = -1/2 (delta = -1,
        // alpha 2); flicker PM r1 = -1/3 (delta = -1/2, alpha 1); white FM 0; flicker FM and
        // random-walk FM are non-stationary (r1 near 1), and their first differences behave like
        // flicker PM and white FM, giving -1 and -2.
        let cases = [
            ([Some(-0.5), None, None], 2, 0),
            ([Some(-1.0 / 3.0), None, None], 1, 0),
            ([Some(0.0), None, None], 0, 0),
            ([Some(0.9), Some(-1.0 / 3.0), None], -1, 1),
            ([Some(0.95), Some(0.0), None], -2, 1),
        ];
        for (r1, alpha, d) in cases {
            let est = alpha_from_lag1(&Lag1 { r1 }, 1).unwrap();
            assert_eq!((est.alpha, est.d), (alpha, d), "{r1:?}");
        }
        // With dmax = 1 a third difference is never asked for, and -3 is clamped to -2.
        let est = alpha_from_lag1(
            &Lag1 {
                r1: [Some(0.9), Some(0.9), None],
            },
            1,
        )
        .unwrap();
        assert_eq!((est.alpha, est.d), (-2, 1));
        // With dmax = 2 (HVAR): flicker walk FM, -3, has a second difference like flicker PM.
        let lag = Lag1 {
            r1: [Some(0.99), Some(0.9), Some(-1.0 / 3.0)],
        };
        assert_eq!(alpha_from_lag1(&lag, 2).unwrap().alpha, -3);
        // A missing autocorrelation the rule needs gives no estimate.
        assert_eq!(
            alpha_from_lag1(
                &Lag1 {
                    r1: [Some(0.9), None, None]
                },
                1
            ),
            None
        );
    }

    #[test]
    fn batch_on_a_constant_rate_is_undefined() {
        // Phase of a constant rate: ybar is constant, its autocorrelation undefined.
        let phase: Vec<f64> = (0..1000).map(|k| 0.5 * k as f64).collect();
        assert_eq!(lag1_batch(&phase, 2).r1[0], None);
    }

    #[test]
    fn batch_on_an_alternating_phase() {
        // x_k = (-1)^k: with m = 1, ybar_k = x_{k+1} - x_k = 2(-1)^(k+1) alternates, so its lag-1
        // autocorrelation is exactly -(n-1)/n with n = 999 (hand derivation: the mean 2/999 left by
        // the odd length cancels, since u_k + u_{k+1} = 0).
        let phase: Vec<f64> = (0..1000)
            .map(|k| if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let r = lag1_batch(&phase, 1).r1[0].unwrap();
        let n = 999.0;
        assert!((r + (n - 1.0) / n).abs() < 1e-12, "{r}");
    }
}
