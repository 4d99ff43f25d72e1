//! The ensemble band of a diagnosis (`diagnose --ensemble N`, docs/gap.md "The ensemble band")
//! drawn behind the measured curve: per tau of the record's `model_tau`, the 2.5% to 97.5%
//! points of the simulated ADEV of the five terms alone (`base`: grey hatching between dashed
//! grey edges) and of the twin with its accepted effects (`twin`: the curve's colour, filled,
//! solid edges), and the words that say how much of the measured curve lies outside each.

use std::fmt::Write;

use super::axes::{polyline, Axes};
use super::text::escape;
use crate::gap::record::EnsembleRecord;
use crate::gap::DiagnosisRecord;

/// The grey of the base band (its hatching and edges).
const BASE_GREY: &str = "#6e6e6e";
/// The fill opacity of the twin's band.
const TWIN_OPACITY: f64 = 0.22;

/// Which of the two bands.
#[derive(Clone, Copy)]
pub(super) enum BandKind {
    Base,
    Twin,
}

/// The hatching pattern of the base band, defined once per panel (`id` unique in the figure).
pub(super) fn hatch_pattern(svg: &mut String, id: &str) {
    let _ = writeln!(
        svg,
        r#"<pattern id="{id}" width="6" height="6" patternUnits="userSpaceOnUse" patternTransform="rotate(45)"><rect width="6" height="6" fill="{BASE_GREY}" fill-opacity="0.08"/><line x1="0" y1="0" x2="0" y2="6" stroke="{BASE_GREY}" stroke-width="1.6" stroke-opacity="0.45"/></pattern>"#
    );
}

/// A band's look: its fill attributes, its edges' colour and their dash attribute (the base
/// band hatched grey with dashed edges, the twin's filled in the curve's colour `col`).
pub(super) fn band_style<'c>(
    kind: BandKind,
    col: &'c str,
    hatch: &str,
) -> (String, &'c str, &'static str) {
    match kind {
        BandKind::Base => (
            format!(r#"fill="url(#{hatch})""#),
            BASE_GREY,
            r#" stroke-dasharray="5 3""#,
        ),
        BandKind::Twin => (
            format!(r#"fill="{col}" fill-opacity="{TWIN_OPACITY}""#),
            col,
            "",
        ),
    }
}

/// The ensemble of a diagnosis when it has one with the record's taus.
pub(super) fn ensemble_of(d: &DiagnosisRecord) -> Option<&EnsembleRecord> {
    d.ensemble
        .as_ref()
        .filter(|e| !d.model_tau.is_empty() && e.runs > 0)
}

/// Every band value of a diagnosis (u/s), for the panel's range.
pub(super) fn band_values(d: &DiagnosisRecord) -> Vec<f64> {
    ensemble_of(d)
        .map(|e| {
            [&e.base_lo, &e.base_hi, &e.twin_lo, &e.twin_hi]
                .iter()
                .flat_map(|v| v.iter().copied())
                .collect()
        })
        .unwrap_or_default()
}

/// One band as a closed polygon: its upper edge left to right, its lower edge back; taus where
/// either edge is not a positive number are left out. Then both edges as lines over it.
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_band(
    svg: &mut String,
    ax: &Axes,
    d: &DiagnosisRecord,
    kind: BandKind,
    channel: &str,
    col: &str,
    hatch: &str,
    clip: &str,
) {
    let Some(e) = ensemble_of(d) else {
        return;
    };
    let (lo, hi, name) = match kind {
        BandKind::Base => (&e.base_lo, &e.base_hi, "base"),
        BandKind::Twin => (&e.twin_lo, &e.twin_hi, "twin"),
    };
    let ok = |v: f64| v > 0.0 && v.is_finite();
    let pts: Vec<(f64, f64, f64)> = d
        .model_tau
        .iter()
        .zip(lo.iter().zip(hi))
        .filter(|(t, (l, h))| **t > 0.0 && ok(**l) && ok(**h))
        .map(|(t, (l, h))| (*t, *l, *h))
        .collect();
    if pts.len() < 2 {
        return;
    }
    let upper = polyline(ax, pts.iter().map(|p| (p.0, p.2)));
    let lower = polyline(ax, pts.iter().rev().map(|p| (p.0, p.1)));
    let (fill, edge, dash) = band_style(kind, col, hatch);
    let ch = escape(channel);
    let _ = writeln!(
        svg,
        r#"<polygon class="band-{name}" data-channel="{ch}" data-runs="{}" points="{upper} {lower}" {fill} stroke="none" clip-path="url(#{clip})"/>"#,
        e.runs
    );
    for (edge_name, line) in [("hi", &upper), ("lo", &lower)] {
        let _ = writeln!(
            svg,
            r#"<polyline class="band-{name}-{edge_name}" data-channel="{ch}" points="{line}" fill="none" stroke="{edge}" stroke-width="0.9"{dash} clip-path="url(#{clip})"/>"#
        );
    }
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
