//! The words of a diagnosis's ensemble band (`diagnose --ensemble N`, docs/gap.md "The ensemble
//! band"): how much of the measured curve lies outside the base band and the twin's, as shares
//! and counts of the record's taus, and the share expected outside by chance. The plot's legend
//! (sink::plot, behind the `plot` feature), the report and the terminal table (always built) word
//! the band through these, so the three never disagree.

use crate::gap::record::EnsembleRecord;
use crate::gap::DiagnosisRecord;

/// The ensemble of a diagnosis when it has one with the record's taus.
pub fn ensemble_of(d: &DiagnosisRecord) -> Option<&EnsembleRecord> {
    d.ensemble
        .as_ref()
        .filter(|e| !d.model_tau.is_empty() && e.runs > 0)
}

/// A share (0 to 1) as a whole percentage; a share above 0 that rounds to 0 is "under 1%".
pub fn percent(share: f64) -> String {
    if !share.is_finite() {
        "n/a".into()
    } else if share > 0.0 && share < 0.005 {
        "under 1%".into()
    } else {
        format!("{:.0}%", 100.0 * share)
    }
}

/// The taus of the record (its `model_tau`) that lie outside a band, from the share.
pub fn outside_count(share: f64, n_taus: usize) -> usize {
    if share.is_finite() {
        (share * n_taus as f64).round() as usize
    } else {
        0
    }
}

/// The share of taus at which one more run of the simulated model itself is expected outside a
/// band of `runs` runs, by chance. Its rank among the runs at one tau is uniform over the
/// `runs + 1` places, and the band's edges are the empirical 2.5% and 97.5% points interpolated
/// at `x = 0.025 (runs - 1)` places from each end (gap::ensemble), so each side holds about
/// `(x + 1) / (runs + 1)` of it: 14% in all for 20 runs, 7% for 100, 5% only as runs grow.
pub fn chance_share(runs: usize) -> f64 {
    if runs < 2 {
        return f64::NAN;
    }
    let x = 0.025 * (runs - 1) as f64;
    2.0 * (x + 1.0) / (runs + 1) as f64
}

/// How far the measured curve leaves the two bands, in words: e.g. "outside the base band at
/// 69% of taus (42 of 61); outside the twin's at 2% (1 of 61)".
pub fn band_sentence(d: &DiagnosisRecord) -> Option<String> {
    let e = ensemble_of(d)?;
    let n = d.model_tau.len();
    Some(format!(
        "outside the base band at {} of taus ({} of {n}); outside the twin's at {} ({} of {n})",
        percent(e.outside_base),
        outside_count(e.outside_base, n),
        percent(e.outside_twin),
        outside_count(e.outside_twin, n)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A uniform draw in [0, 1) from a splitmix64 state.
    fn uniform(state: &mut u64) -> f64 {
        *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The empirical `p` point of sorted `v`, interpolated as gap::ensemble does.
    fn quantile(v: &[f64], p: f64) -> f64 {
        let x = p * (v.len() - 1) as f64;
        let (i, f) = (x.floor() as usize, x.fract());
        v[i] + f * (v[(i + 1).min(v.len() - 1)] - v[i])
    }

    /// One more draw falls outside the band of `runs` draws as often as `chance_share` says:
    /// 40000 trials each (sd of the share below 0.002).
    #[test]
    fn chance_share_is_the_rate_of_a_fresh_run_outside_the_band() {
        let mut s = 7u64;
        for runs in [20usize, 100] {
            let trials = 40_000;
            let mut outside = 0;
            for _ in 0..trials {
                let mut v: Vec<f64> = (0..runs).map(|_| uniform(&mut s)).collect();
                v.sort_by(f64::total_cmp);
                let y = uniform(&mut s);
                if y < quantile(&v, 0.025) || y > quantile(&v, 0.975) {
                    outside += 1;
                }
            }
            let share = outside as f64 / trials as f64;
            let want = chance_share(runs);
            assert!(
                (share - want).abs() < 0.008,
                "{runs} runs: {share} vs {want}"
            );
        }
        assert!((chance_share(20) - 0.1405).abs() < 1e-3);
    }

    #[test]
    fn shares_read_as_whole_percentages() {
        assert_eq!(percent(0.6885245901639344), "69%");
        assert_eq!(percent(1.0 / 61.0), "2%");
        assert_eq!(percent(0.004), "under 1%");
        assert_eq!(percent(0.0), "0%");
        assert_eq!(outside_count(0.6885245901639344, 61), 42);
    }
}
