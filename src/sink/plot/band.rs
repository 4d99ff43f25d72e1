//! The ensemble band of a diagnosis (`diagnose --ensemble N`, docs/gap.md "The ensemble band")
//! drawn behind the measured curve: per tau of the record's `model_tau`, the 2.5% to 97.5%
//! points of the simulated ADEV of the five terms alone (`base`: grey hatching between dashed
//! grey edges) and of the twin with its accepted effects (`twin`: the curve's colour, filled,
//! solid edges), and the words that say how much of the measured curve lies outside each.

use std::fmt::Write;

use super::axes::{polyline, Axes};
use super::text::escape;
use crate::gap::DiagnosisRecord;
use crate::sink::band_words::ensemble_of;

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
