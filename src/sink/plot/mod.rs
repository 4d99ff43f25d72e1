//! Allan-deviation figures as SVG, fit for a test report (the seed paper's figures 1 to 3, IEEE
//! Std 952-1997 annex C's log-log reading): one panel per channel unit, so gyros and
//! accelerometers never share an axis; per curve the deviation with its 95% intervals, the
//! fitted five-term model drawn over the measured taus only, each determined term's asymptote
//! labelled, and where a diagnosis exists, the taus where the base model misses shaded and the
//! model with the diagnosed effects as a second line. A fan of slope guides (-1, -1/2, 0, +1/2,
//! +1, at the panel's own scale) sits beside the legend.
//!
//! The SVG is written as text (no font library); a viewer renders the text with its own fonts.
//! Colours are Okabe and Ito's colour-blind-safe set, and every curve also has its own marker
//! shape, so curves stay apart in grey print.
//!
//! This file lays out the figure (title, one panel per unit); `panel` draws one panel and its
//! legend lines, `curves` what belongs to one curve (markers, intervals, model lines, asymptotes,
//! the shaded misses of a diagnosis), `band` the ensemble band of a diagnosis behind the
//! curve, `axes` the log-log scale, grid, ticks and slope key, `legend` the legend's lines,
//! `fit_terms` the determined terms read from a fit record, `series` the curves a figure draws
//! from result files (shared by `plot` and the report) and `text` the words and numbers of
//! labels (shared with the report and the dynamic plot).

use std::borrow::Cow;
use std::fmt::Write;

use crate::gap::DiagnosisRecord;
use crate::sink::records::{CurveRecord, FitRecord};

mod axes;
mod band;
mod curves;
mod fit_terms;
mod legend;
mod panel;
mod series;
mod text;

use panel::render_panel;

pub use crate::sink::band_words::{band_sentence, chance_share, outside_count, percent};
pub use fit_terms::{determined_terms, TermValue};
pub use series::{figure_series, final_curves, measured_curve};
pub use text::{
    coef_units, effect_name, effect_names, escape, ratio_text, sig4, sigma_unit, tick, unit_kind,
};

/// One curve to draw: its record, its run's label, and its fit and diagnosis when known. The
/// record is borrowed from the results, or owned when made from a diagnosis's ensemble band
/// ([`measured_curve`]).
pub struct Series<'a> {
    pub curve: Cow<'a, CurveRecord>,
    /// The run's name (a file name) when several runs are overlaid, else empty.
    pub run_label: String,
    pub fit: Option<&'a FitRecord>,
    pub diagnosis: Option<&'a DiagnosisRecord>,
}

/// Figure width (px) and the margins of each panel's plot area.
pub const W: f64 = 1100.0;
const PANEL_H: f64 = 620.0;
const LEFT: f64 = 90.0;
const LEGEND_W: f64 = 370.0;
const TOP: f64 = 56.0;
const BOTTOM: f64 = 62.0;
const TITLE_H: f64 = 36.0;

/// Colour-blind-safe palette (Okabe and Ito), yellow left out (too pale on white).
pub const COLOURS: [&str; 7] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000",
];
/// The asymptotes' labels: the term and its slope on the log-log plot.
const SLOPES: [&str; 5] = ["\u{2212}1", "\u{2212}\u{bd}", "0", "+\u{bd}", "+1"];
/// Groups curves into panels, one per channel unit, in the order units first appear.
pub fn panels_by_unit<'a>(series: Vec<Series<'a>>) -> Vec<Vec<Series<'a>>> {
    let mut panels: Vec<Vec<Series>> = Vec::new();
    for s in series {
        match panels.iter_mut().find(|p| p[0].curve.unit == s.curve.unit) {
            Some(p) => p.push(s),
            None => panels.push(vec![s]),
        }
    }
    panels
}

/// The default title: the channels, their unit and the files, e.g. `g4 [arcsec] - run1.jsonl`.
pub fn default_title(series: &[Series], files: &[String]) -> String {
    let mut chans: Vec<String> = Vec::new();
    for s in series {
        let c = crate::sink::channel_with_unit(&s.curve.channel, &s.curve.unit);
        if !chans.contains(&c) {
            chans.push(c);
        }
    }
    let chans = if chans.len() > 4 {
        format!("{} channels", chans.len())
    } else {
        chans.join(", ")
    };
    format!("{chans} \u{2014} {}", files.join(", "))
}

/// Renders the figure: `title` on top, then one panel per channel unit.
pub fn render_svg(series: Vec<Series>, title: &str) -> String {
    let panels = panels_by_unit(series);
    let mut body = String::new();
    let mut y = TITLE_H;
    for p in &panels {
        y += render_panel(&mut body, p, y);
    }
    let h = y.max(TITLE_H + 100.0);
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{h}" viewBox="0 0 {W} {h}" font-family="Helvetica, Arial, sans-serif" font-size="13">"#
    );
    let _ = writeln!(svg, r#"<rect width="{W}" height="{h}" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r#"<text class="title" x="{}" y="24" text-anchor="middle" font-size="17" font-weight="bold">{}</text>"#,
        W / 2.0,
        escape(title)
    );
    if panels.is_empty() {
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="middle">no data</text>"#,
            W / 2.0,
            TITLE_H + 50.0
        );
    }
    svg.push_str(&body);
    svg.push_str("</svg>\n");
    svg
}
