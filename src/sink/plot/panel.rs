//! One panel of the figure: the curves of one channel unit with their legend lines (terms,
//! model, diagnosis), heading, axes, labels, clipping and slope key; the panel grows to hold a
//! long legend.

use std::borrow::Cow;
use std::fmt::Write;

use super::axes::{draw_grid, draw_slope_key, Axes};
use super::band::{band_values, draw_band, hatch_pattern, BandKind};
use super::curves::{draw_regions, draw_series};
use super::fit_terms::determined_terms;
use super::legend::{Dash, LegendLine};
use super::text::{
    capitalise, coef_units, effect_names, escape, sig4, sigma_unit, unit_kind, verdict_word,
};
use super::{Series, BOTTOM, COLOURS, LEFT, LEGEND_W, PANEL_H, TOP, W};
use crate::gap::record::EnsembleRecord;
use crate::model::terms::TERM_NAMES;
use crate::sink::band_words::{ensemble_of, outside_count, percent};

/// The ensemble band of a series' diagnosis, drawn on an AVAR panel only.
fn band_of<'a>(s: &Series<'a>, stat: &str) -> Option<&'a EnsembleRecord> {
    s.diagnosis.filter(|_| stat == "avar").and_then(ensemble_of)
}

/// Draws one panel at vertical offset `y_off`; returns its height.
pub(super) fn render_panel(svg: &mut String, series: &[Series], y_off: f64) -> f64 {
    let unit = series[0].curve.unit.clone();
    let stat = series[0].curve.stat.name();
    // Data range: every point and interval, and the model lines (over the measured taus only).
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    for s in series {
        xs.extend(s.curve.tau.iter().copied());
        ys.extend(s.curve.sigma.iter().copied());
        ys.extend(s.curve.lo.iter().flatten().copied());
        // An upper bound of a few differences can be decades above the curve: the range
        // holds it up to 3 sigma, the bar is clipped there.
        ys.extend(
            s.curve
                .hi
                .iter()
                .zip(&s.curve.sigma)
                .filter_map(|(h, y)| h.map(|h| h.min(3.0 * y))),
        );
        // An ensemble band is drawn whole.
        if let Some(d) = s.diagnosis.filter(|_| stat == "avar") {
            ys.extend(band_values(d));
        }
    }
    let pos = |v: Vec<f64>| -> Vec<f64> {
        v.into_iter()
            .filter(|x| *x > 0.0 && x.is_finite())
            .collect()
    };
    let (xs, ys) = (pos(xs), pos(ys));
    // Legend lines first: the panel grows to hold them.
    let mut legend: Vec<LegendLine> = Vec::new();
    let several_runs = series.iter().any(|s| !s.run_label.is_empty());
    // The hatching of the base bands, one pattern per panel.
    let hatch = format!("hatch{}", y_off as i64);
    // More than four curves: the legend names them only (their terms are in the report's
    // tables), so it stays beside the plot.
    let compact = series.len() > 4;
    for (i, s) in series.iter().enumerate() {
        let name = if several_runs && !s.run_label.is_empty() {
            format!("{} \u{2014} {}", s.curve.channel, s.run_label)
        } else {
            s.curve.channel.clone()
        };
        legend.push(LegendLine::Curve(i, name));
        if compact {
            continue;
        }
        if let Some(f) = s.fit.filter(|_| stat == "avar") {
            let units = coef_units(&unit);
            for t in determined_terms(f) {
                let iv = match (t.lo, t.hi) {
                    (Some(lo), Some(hi)) => format!(" [{}, {}]", sig4(lo), sig4(hi)),
                    _ => String::new(),
                };
                legend.push(LegendLine::Text(format!(
                    "{} = {}{iv} {}",
                    TERM_NAMES[t.index],
                    sig4(t.value),
                    units[t.index]
                )));
                if let Some((v, u)) = &t.datasheet {
                    legend.push(LegendLine::Small(format!("    = {} {u}", sig4(*v))));
                }
            }
            let gof = f.gof.map(|g| format!(", gof {g:.2}")).unwrap_or_default();
            legend.push(LegendLine::Style(
                i,
                Dash::Model,
                format!("five-term model{gof}"),
            ));
        }
        if let Some(d) = s
            .diagnosis
            .filter(|d| !d.model_effects.is_empty() && !d.effects.is_empty())
        {
            let names = effect_names(d);
            legend.push(LegendLine::Style(
                i,
                Dash::Effects,
                format!("model + {} (gap {:.2})", names.join(" + "), d.gap_after),
            ));
        }
        // With an ensemble band the base band shows where the five terms miss; the shading
        // of the misses (of the same colour as the twin's band) is left out.
        if let (Some(d), Some(_)) = (s.diagnosis, band_of(s, stat)) {
            legend.push(LegendLine::Text(format!(
                "diagnosis: gap {:.2} \u{2192} {:.2}, {}",
                d.gap_before,
                d.gap_after,
                verdict_word(d)
            )));
        } else if let Some(d) = s.diagnosis.filter(|d| !d.regions.is_empty()) {
            legend.push(LegendLine::Shade(
                i,
                format!(
                    "base model misses (gap {:.2}, {})",
                    d.gap_before,
                    verdict_word(d)
                ),
            ));
        }
        if let (Some(e), Some(d)) = (band_of(s, stat), s.diagnosis) {
            let n = d.model_tau.len();
            let names = effect_names(d);
            let twin = if names.is_empty() {
                "twin (no effect kept)".to_string()
            } else {
                format!("twin (+ {})", names.join(" + "))
            };
            for (kind, what, share) in [
                (
                    BandKind::Base,
                    "five terms alone".to_string(),
                    e.outside_base,
                ),
                (BandKind::Twin, twin, e.outside_twin),
            ] {
                legend.push(LegendLine::Band(
                    i,
                    kind,
                    format!("{what}: 2.5\u{2013}97.5% of {} runs", e.runs),
                    hatch.clone(),
                ));
                legend.push(LegendLine::Small(format!(
                    "    measured outside at {} of {n} taus ({})",
                    outside_count(share, n),
                    percent(share)
                )));
            }
        }
        legend.push(LegendLine::Gap);
    }
    if compact {
        if series.iter().any(|s| s.fit.is_some()) && stat == "avar" {
            legend.push(LegendLine::Style(
                6,
                Dash::Model,
                "five-term model of each curve".into(),
            ));
        }
        if series
            .iter()
            .any(|s| s.diagnosis.is_some_and(|d| !d.effects.is_empty()))
        {
            legend.push(LegendLine::Style(
                6,
                Dash::Effects,
                "model with the diagnosed effects".into(),
            ));
        }
        if let Some(i) = series.iter().position(|s| band_of(s, stat).is_some()) {
            legend.push(LegendLine::Band(
                i,
                BandKind::Base,
                "simulated five terms alone, 2.5\u{2013}97.5%".into(),
                hatch.clone(),
            ));
            legend.push(LegendLine::Band(
                i,
                BandKind::Twin,
                "simulated twin (with effects), 2.5\u{2013}97.5%".into(),
                hatch.clone(),
            ));
        }
    }
    let legend_h: f64 = legend.iter().map(LegendLine::height).sum::<f64>() + 24.0;
    let slope_key_h = 150.0;
    let panel_h = PANEL_H.max(TOP + legend_h + slope_key_h + BOTTOM);
    let top = y_off + TOP;
    // The plot area keeps its size; a long legend lengthens the panel below it.
    let ph = PANEL_H - TOP - BOTTOM;
    let pw = W - LEFT - LEGEND_W;
    // Panel heading.
    let dev = match stat {
        "hvar" => "Hadamard deviation",
        "mvar" => "modified Allan deviation",
        _ => "Allan deviation",
    };
    let _ = writeln!(
        svg,
        r#"<text class="panel" x="{}" y="{:.1}" text-anchor="middle" font-size="15">{} in {}: {dev}</text>"#,
        LEFT + pw / 2.0,
        y_off + 26.0,
        capitalise(unit_kind(&unit)),
        escape(&unit)
    );
    if xs.is_empty() || ys.is_empty() {
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="middle">no data</text>"#,
            LEFT + pw / 2.0,
            top + ph / 2.0
        );
        return panel_h;
    }
    let lmin = |v: &[f64]| {
        v.iter()
            .fold(f64::INFINITY, |a, &b| a.min(b))
            .log10()
            .floor() as i32
    };
    let lmax = |v: &[f64]| v.iter().fold(0.0f64, |a, &b| a.max(b)).log10().ceil() as i32;
    let ax = Axes {
        x0: lmin(&xs),
        x1: lmax(&xs).max(lmin(&xs) + 1),
        y0: lmin(&ys),
        y1: lmax(&ys).max(lmin(&ys) + 1),
        top,
        pw,
        ph,
    };
    let clip = format!("clip{}", y_off as i64);
    let _ = writeln!(
        svg,
        r#"<clipPath id="{clip}"><rect x="{LEFT}" y="{top}" width="{pw}" height="{ph}"/></clipPath>"#
    );
    draw_grid(svg, &ax);
    // Shaded regions of the diagnoses, under everything else.
    for (i, s) in series.iter().enumerate() {
        if let Some(d) = s.diagnosis.filter(|_| band_of(s, stat).is_none()) {
            draw_regions(svg, &ax, d, COLOURS[i % COLOURS.len()], &clip);
        }
    }
    // The ensemble bands, base under twin, behind the curves.
    if series.iter().any(|s| band_of(s, stat).is_some()) {
        hatch_pattern(svg, &hatch);
        for kind in [BandKind::Base, BandKind::Twin] {
            for (i, s) in series.iter().enumerate() {
                if let (Some(d), true) = (s.diagnosis, band_of(s, stat).is_some()) {
                    let col = COLOURS[i % COLOURS.len()];
                    draw_band(svg, &ax, d, kind, &s.curve.channel, col, &hatch, &clip);
                }
            }
        }
    }
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" text-anchor="middle">averaging time &#964; (s)</text>"#,
        LEFT + pw / 2.0,
        top + ph + 44.0
    );
    // Curves made from an ensemble band (owned, not read) have no intervals.
    let intervals = if series.iter().any(|s| matches!(s.curve, Cow::Borrowed(_))) {
        ", 95% intervals"
    } else {
        ""
    };
    let _ = writeln!(
        svg,
        r#"<text class="ylabel" transform="translate(22,{}) rotate(-90)" text-anchor="middle">{dev} &#963;(&#964;) ({}){intervals}</text>"#,
        top + ph / 2.0,
        escape(&sigma_unit(&unit))
    );
    // Each term's asymptote is labelled once per panel (runs of one unit overlap).
    let mut labelled = [false; 5];
    for (i, s) in series.iter().enumerate() {
        draw_series(svg, &ax, i, s, &clip, series.len() <= 3, &mut labelled);
    }
    let _ = writeln!(
        svg,
        r#"<rect x="{LEFT}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
    );
    // Legend and slope key on the right.
    let lx = W - LEGEND_W + 18.0;
    let mut ly = top + 6.0;
    for l in &legend {
        l.draw(svg, lx, ly);
        ly += l.height();
    }
    draw_slope_key(svg, &ax, lx, ly + 10.0);
    panel_h
}
