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

use std::fmt::Write;

use crate::gap::DiagnosisRecord;
use crate::model::terms::{avar as model_avar, basis, TERM_NAMES};
use crate::sink::records::{CurveRecord, FitRecord};

/// One curve to draw: its record, its run's label, and its fit and diagnosis when known.
pub struct Series<'a> {
    pub curve: &'a CurveRecord,
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

pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A number for a label: 4 significant digits, plain between 1e-3 and 1e4.
pub fn sig4(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&x.abs()) {
        let d = (3 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.d$}")
    } else {
        format!("{x:.3e}")
    }
}

/// A number for an axis tick: at most 4 significant digits, trailing zeros dropped.
pub fn tick(x: f64) -> String {
    let t = sig4(x);
    let (m, e) = match t.split_once('e') {
        Some((m, e)) => (m.to_string(), format!("e{e}")),
        None => (t.clone(), String::new()),
    };
    if m.contains('.') {
        format!("{}{e}", m.trim_end_matches('0').trim_end_matches('.'))
    } else {
        t
    }
}

/// A decade label: `10^k` written plainly for |k| <= 3, else as `1e{k}`.
fn decade_label(k: i32) -> String {
    match k {
        -3..=-1 => format!("{}", 10f64.powi(k)),
        0..=3 => format!("{}", 10f64.powi(k) as i64),
        _ => format!("1e{k}"),
    }
}

/// The native unit of each coefficient `(Q, N, B, K, R)` for a channel in `u`
/// (THEORY.md section 2).
pub fn coef_units(u: &str) -> [String; 5] {
    [
        u.to_string(),
        format!("{u}/sqrt(s)"),
        format!("{u}/s"),
        format!("{u}/s/sqrt(s)"),
        format!("{u}/s^2"),
    ]
}

/// What a channel unit measures, for a panel's heading.
pub fn unit_kind(u: &str) -> &'static str {
    let base = u.split('/').next().unwrap_or(u);
    match base {
        "deg" | "rad" | "mrad" | "urad" | "arcsec" | "arcmin" => "gyros (angle increments)",
        "m" if u.starts_with("m/s") => "accelerometers (velocity increments)",
        "ft" | "g" | "mg" | "ug" | "micro-g" => "accelerometers (velocity increments)",
        _ => "channels",
    }
}

/// The fitted model's coefficients `(Q, N, B, K, R)`: every fitted term (from `model_c`),
/// or the determined ones where an older record lacks it.
fn fit_coefs(f: &FitRecord) -> [f64; 5] {
    if f.model_c.len() == 5 {
        std::array::from_fn(|i| f.model_c[i].max(0.0).sqrt())
    } else {
        std::array::from_fn(|i| f.coef.by_index(i).value.unwrap_or(0.0))
    }
}

/// One determined coefficient of a fit: value and 95% interval in the native unit, and the
/// datasheet value and unit when the record has them.
pub struct TermValue {
    pub index: usize,
    pub value: f64,
    pub lo: Option<f64>,
    pub hi: Option<f64>,
    pub datasheet: Option<(f64, String)>,
}

/// The determined terms of a fit.
pub fn determined_terms(f: &FitRecord) -> Vec<TermValue> {
    TERM_NAMES
        .iter()
        .enumerate()
        .filter_map(|(i, k)| {
            let c = f.coef.get(k)?;
            let v = c.value?;
            if !c.determined {
                return None;
            }
            let ds = f.datasheet.as_ref().and_then(|d| {
                let e = d.get(k)?;
                Some((e.value?, e.unit.clone()))
            });
            Some(TermValue {
                index: i,
                value: v,
                lo: c.lo,
                hi: c.hi,
                datasheet: ds,
            })
        })
        .collect()
}

/// The log-log scale of one panel.
struct Axes {
    x0: i32,
    x1: i32,
    y0: i32,
    y1: i32,
    /// Top of the plot area (px).
    top: f64,
    pw: f64,
    ph: f64,
}

impl Axes {
    fn px(&self, x: f64) -> f64 {
        LEFT + (x.log10() - self.x0 as f64) / (self.x1 - self.x0) as f64 * self.pw
    }
    fn py(&self, y: f64) -> f64 {
        self.top + self.ph - (y.log10() - self.y0 as f64) / (self.y1 - self.y0) as f64 * self.ph
    }
    /// Pixels per decade, x and y.
    fn ppd(&self) -> (f64, f64) {
        (
            self.pw / (self.x1 - self.x0) as f64,
            self.ph / (self.y1 - self.y0) as f64,
        )
    }
}

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
        let c = format!("{} [{}]", s.curve.channel, s.curve.unit);
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

/// The markers, one shape per curve, at (x, y) with radius r.
fn marker(svg: &mut String, i: usize, x: f64, y: f64, col: &str) {
    let r = 3.2;
    let _ = match i % 4 {
        0 => writeln!(
            svg,
            r#"<circle cx="{x:.1}" cy="{y:.1}" r="{r}" fill="{col}"/>"#
        ),
        1 => writeln!(
            svg,
            r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{col}"/>"#,
            x - r,
            y - r,
            2.0 * r,
            2.0 * r
        ),
        2 => writeln!(
            svg,
            r#"<polygon points="{:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" fill="{col}"/>"#,
            x,
            y - 1.3 * r,
            x - 1.2 * r,
            y + r,
            x + 1.2 * r,
            y + r
        ),
        _ => writeln!(
            svg,
            r#"<polygon points="{:.1},{:.1} {:.1},{:.1} {:.1},{:.1} {:.1},{:.1}" fill="none" stroke="{col}" stroke-width="1.5"/>"#,
            x,
            y - 1.4 * r,
            x + 1.4 * r,
            y,
            x,
            y + 1.4 * r,
            x - 1.4 * r,
            y
        ),
    };
}

/// Draws one panel at vertical offset `y_off`; returns its height.
fn render_panel(svg: &mut String, series: &[Series], y_off: f64) -> f64 {
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
            let names: Vec<&str> = d.effects.iter().map(|e| e.effect.kind_name()).collect();
            let names: Vec<&str> = names.iter().map(|k| effect_name(k)).collect();
            legend.push(LegendLine::Style(
                i,
                Dash::Effects,
                format!("model + {} (gap {:.2})", names.join(" + "), d.gap_after),
            ));
        }
        if let Some(d) = s.diagnosis.filter(|d| !d.regions.is_empty()) {
            legend.push(LegendLine::Shade(
                i,
                format!(
                    "base model misses (gap {:.2}, {})",
                    d.gap_before,
                    verdict_word(d)
                ),
            ));
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
        if let Some(d) = s.diagnosis {
            draw_regions(svg, &ax, d, COLOURS[i % COLOURS.len()], &clip);
        }
    }
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" text-anchor="middle">averaging time &#964; (s)</text>"#,
        LEFT + pw / 2.0,
        top + ph + 44.0
    );
    let _ = writeln!(
        svg,
        r#"<text class="ylabel" transform="translate(22,{}) rotate(-90)" text-anchor="middle">{dev} &#963;(&#964;) ({}), 95% intervals</text>"#,
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

/// An effect kind of the diagnosis record, as a person names it.
pub fn effect_name(kind: &str) -> &str {
    match kind {
        "gauss_markov" => "Gauss-Markov",
        "output_filter" => "output filter",
        "warmup" => "warm-up",
        "bias_jumps" => "bias jumps",
        "temperature" => "temperature",
        k => k,
    }
}

/// A ratio of deviations: two decimals, three when it is within 1% of 1.
pub fn ratio_text(r: f64) -> String {
    if (r - 1.0).abs() < 0.01 {
        format!("{r:.3}")
    } else {
        format!("{r:.2}")
    }
}

/// The unit of sigma for a channel in `u`: `u/s` (`(m/s)/s` for a compound unit).
pub fn sigma_unit(u: &str) -> String {
    if u.contains('/') {
        format!("({u})/s")
    } else {
        format!("{u}/s")
    }
}

fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}

fn verdict_word(d: &DiagnosisRecord) -> String {
    serde_json::to_value(d.verdict)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_default()
}

fn draw_grid(svg: &mut String, ax: &Axes) {
    let grid = |lo: i32, hi: i32| -> Vec<(f64, bool)> {
        (lo..=hi)
            .flat_map(|k| (1..10).map(move |j| (k, j)))
            .filter(|&(k, j)| k < hi || j == 1)
            .map(|(k, j)| (10f64.powi(k) * j as f64, j == 1))
            .collect()
    };
    let style = |major: bool| {
        if major {
            ("#b0b0b0", 1.0)
        } else {
            ("#e6e6e6", 0.7)
        }
    };
    let (top, bottom, right) = (ax.top, ax.top + ax.ph, LEFT + ax.pw);
    for (v, major) in grid(ax.x0, ax.x1) {
        let (stroke, wd) = style(major);
        let _ = writeln!(
            svg,
            r#"<line x1="{0:.1}" y1="{top:.1}" x2="{0:.1}" y2="{bottom:.1}" stroke="{stroke}" stroke-width="{wd}"/>"#,
            ax.px(v)
        );
    }
    for (v, major) in grid(ax.y0, ax.y1) {
        let (stroke, wd) = style(major);
        let _ = writeln!(
            svg,
            r#"<line x1="{LEFT}" y1="{0:.1}" x2="{right:.1}" y2="{0:.1}" stroke="{stroke}" stroke-width="{wd}"/>"#,
            ax.py(v)
        );
    }
    for k in ax.x0..=ax.x1 {
        let _ = writeln!(
            svg,
            r#"<text class="xtick" x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            ax.px(10f64.powi(k)),
            bottom + 20.0,
            decade_label(k)
        );
    }
    for k in ax.y0..=ax.y1 {
        let _ = writeln!(
            svg,
            r#"<text class="ytick" x="{}" y="{:.1}" text-anchor="end" dominant-baseline="middle">{}</text>"#,
            LEFT - 8.0,
            ax.py(10f64.powi(k)),
            decade_label(k)
        );
    }
}

/// The taus where the base model misses, shaded from half a step before the first tau of a
/// region to half a step after its last (geometric midpoints to the neighbouring taus).
fn draw_regions(svg: &mut String, ax: &Axes, d: &DiagnosisRecord, col: &str, clip: &str) {
    let t = &d.model_tau;
    for (n, r) in d.regions.iter().enumerate() {
        let edge = |tau: f64, dir: i32| -> f64 {
            let i = t.iter().position(|x| (x / tau - 1.0).abs() < 1e-9);
            match i {
                Some(i) => {
                    let j = i as i64 + dir as i64;
                    if j >= 0 && (j as usize) < t.len() {
                        (t[i] * t[j as usize]).sqrt()
                    } else {
                        tau * 2f64.powf(0.5 * dir as f64)
                    }
                }
                None => tau * 2f64.powf(0.5 * dir as f64),
            }
        };
        let (a, b) = (ax.px(edge(r.tau_lo, -1)), ax.px(edge(r.tau_hi, 1)));
        let _ = writeln!(
            svg,
            r#"<rect class="region" data-tau-lo="{}" data-tau-hi="{}" x="{a:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{col}" fill-opacity="0.13" clip-path="url(#{clip})"/>"#,
            r.tau_lo,
            r.tau_hi,
            ax.top,
            (b - a).max(1.0),
            ax.ph
        );
        // Neighbouring regions' labels on alternate rows, so they never overlap.
        let word = if r.sign > 0 { "above" } else { "below" };
        let _ = writeln!(
            svg,
            r##"<text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle" fill="#222" stroke="white" stroke-width="3" paint-order="stroke">{word} &#215;{}</text>"##,
            (a + b) / 2.0,
            ax.top + 14.0 + 13.0 * (n % 3) as f64,
            ratio_text(r.worst_ratio)
        );
    }
}

/// A polyline through `(tau, sigma)` points, skipping non-positive values.
fn polyline(ax: &Axes, pts: impl Iterator<Item = (f64, f64)>) -> String {
    pts.filter(|(t, y)| *t > 0.0 && *y > 0.0 && y.is_finite())
        .map(|(t, y)| format!("{:.1},{:.1}", ax.px(t), ax.py(y)))
        .collect::<Vec<_>>()
        .join(" ")
}

fn draw_series(
    svg: &mut String,
    ax: &Axes,
    i: usize,
    s: &Series,
    clip: &str,
    asymptotes: bool,
    labelled: &mut [bool; 5],
) {
    let col = COLOURS[i % COLOURS.len()];
    let c = s.curve;
    let _ = writeln!(
        svg,
        r#"<polyline class="curve" data-channel="{}" data-run="{}" points="{}" fill="none" stroke="{col}" stroke-width="1.6"/>"#,
        escape(&c.channel),
        escape(&s.run_label),
        polyline(ax, c.tau.iter().copied().zip(c.sigma.iter().copied()))
    );
    for (j, (t, y)) in c.tau.iter().zip(&c.sigma).enumerate() {
        if *t <= 0.0 || *y <= 0.0 {
            continue;
        }
        let x = ax.px(*t);
        if let (Some(Some(lo)), Some(Some(hi))) = (c.lo.get(j), c.hi.get(j)) {
            if *lo > 0.0 {
                let _ = writeln!(
                    svg,
                    r#"<line class="interval" x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="{col}" stroke-width="1" clip-path="url(#{clip})"/>"#,
                    ax.py(*lo),
                    ax.py(*hi)
                );
            }
        }
        marker(svg, i, x, ax.py(*y), col);
    }
    let (t_lo, t_hi) = c
        .tau
        .iter()
        .filter(|t| **t > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), &t| (a.min(t), b.max(t)));
    if t_lo.partial_cmp(&t_hi) != Some(std::cmp::Ordering::Less) {
        return;
    }
    // The five-term model, over the measured taus only (AVAR only: the fit is of AVAR).
    if let Some(f) = s.fit.filter(|_| c.stat.name() == "avar") {
        let coef = fit_coefs(f);
        let n = 160;
        let taus = (0..=n).map(|k| t_lo * (t_hi / t_lo).powf(k as f64 / n as f64));
        let _ = writeln!(
            svg,
            r#"<polyline class="model" data-tau-lo="{t_lo}" data-tau-hi="{t_hi}" points="{}" fill="none" stroke="{col}" stroke-width="1.4" stroke-dasharray="7 4" clip-path="url(#{clip})"/>"#,
            polyline(ax, taus.map(|t| (t, model_avar(coef, t).sqrt())))
        );
        if asymptotes {
            draw_asymptotes(svg, ax, f, (t_lo, t_hi), col, clip, labelled);
        }
    }
    if let Some(d) = s
        .diagnosis
        .filter(|d| !d.effects.is_empty() && c.stat.name() == "avar")
    {
        let _ = writeln!(
            svg,
            r#"<polyline class="model-effects" points="{}" fill="none" stroke="{col}" stroke-width="2" stroke-dasharray="2 3" clip-path="url(#{clip})"/>"#,
            polyline(
                ax,
                d.model_tau
                    .iter()
                    .copied()
                    .zip(d.model_effects.iter().copied())
            )
        );
    }
}

/// Each determined term's asymptote `sigma_i(tau) = sqrt(c_i basis_i(tau))` (dotted, thin) over
/// the measured taus, labelled with the term and its slope where that term's share of the
/// model is largest.
fn draw_asymptotes(
    svg: &mut String,
    ax: &Axes,
    f: &FitRecord,
    (t_lo, t_hi): (f64, f64),
    col: &str,
    clip: &str,
    labelled: &mut [bool; 5],
) {
    let coef = fit_coefs(f);
    let n = 60;
    for t in determined_terms(f) {
        let k = t.index;
        let c = coef[k];
        if c <= 0.0 {
            continue;
        }
        let taus: Vec<f64> = (0..=n)
            .map(|j| t_lo * (t_hi / t_lo).powf(j as f64 / n as f64))
            .collect();
        let sig = |tau: f64| (basis(tau)[k]).sqrt() * c;
        let _ = writeln!(
            svg,
            r#"<polyline class="asymptote" data-term="{}" points="{}" fill="none" stroke="{col}" stroke-width="1" stroke-dasharray="1 3" clip-path="url(#{clip})"/>"#,
            TERM_NAMES[k],
            polyline(ax, taus.iter().map(|&tau| (tau, sig(tau))))
        );
        // Where the term's share of the model is largest, inside the plot.
        let best = taus
            .iter()
            .copied()
            .filter(|&tau| {
                let y = ax.py(sig(tau));
                y > ax.top + 12.0 && y < ax.top + ax.ph - 6.0
            })
            .max_by(|a, b| {
                let share = |tau: f64| sig(tau).powi(2) / model_avar(coef, tau).max(1e-300);
                share(*a).total_cmp(&share(*b))
            });
        if let Some(tau) = best.filter(|_| !labelled[k]) {
            labelled[k] = true;
            let _ = writeln!(
                svg,
                r##"<text class="asymptote-label" x="{:.1}" y="{:.1}" font-size="12" font-weight="bold" fill="#222" text-anchor="middle" stroke="white" stroke-width="3" paint-order="stroke">{} (slope {})</text>"##,
                ax.px(tau).clamp(LEFT + 50.0, LEFT + ax.pw - 50.0),
                ax.py(sig(tau)) + 18.0,
                TERM_NAMES[k],
                SLOPES[k]
            );
        }
    }
}

/// A fan of the five slopes at the panel's own scale, with the term each belongs to.
fn draw_slope_key(svg: &mut String, ax: &Axes, x: f64, y: f64) {
    let (px_dec, py_dec) = ax.ppd();
    // Long enough to read, short enough that slope 1 rises at most 56 px.
    let len = (0.6 * px_dec).min(56.0 * px_dec / py_dec).max(20.0);
    let _ = writeln!(
        svg,
        r#"<text x="{x:.1}" y="{:.1}" font-size="12" font-weight="bold">slopes (this plot's scale)</text>"#,
        y + 4.0
    );
    let oy = y + 70.0;
    let ox = x + 10.0;
    let slopes: [f64; 5] = [-1.0, -0.5, 0.0, 0.5, 1.0];
    for (k, s) in slopes.iter().enumerate() {
        // One decade in tau is px_dec pixels; s decades in sigma is s * py_dec pixels.
        let dx = len;
        let dy: f64 = -s * py_dec * (len / px_dec);
        let (ex, ey) = (ox + dx, oy + dy);
        let _ = writeln!(
            svg,
            r##"<line class="slope-guide" data-slope="{s}" x1="{ox:.1}" y1="{oy:.1}" x2="{ex:.1}" y2="{ey:.1}" stroke="#555" stroke-width="1.2"/>"##
        );
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" font-size="11" dominant-baseline="middle">{} {}</text>"#,
            ex + 5.0,
            ey,
            SLOPES[k],
            ["Q", "N", "B", "K", "R"][k]
        );
    }
}

enum Dash {
    Model,
    Effects,
}

enum LegendLine {
    Curve(usize, String),
    Text(String),
    Small(String),
    Style(usize, Dash, String),
    Shade(usize, String),
    Gap,
}

impl LegendLine {
    fn height(&self) -> f64 {
        match self {
            LegendLine::Curve(..) => 19.0,
            LegendLine::Text(_) | LegendLine::Style(..) | LegendLine::Shade(..) => 15.0,
            LegendLine::Small(_) => 13.0,
            LegendLine::Gap => 8.0,
        }
    }

    fn draw(&self, svg: &mut String, x: f64, y: f64) {
        let tx = x + 34.0;
        let _ = match self {
            LegendLine::Curve(i, name) => {
                let col = COLOURS[i % COLOURS.len()];
                let _ = writeln!(
                    svg,
                    r#"<line x1="{x:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="{col}" stroke-width="1.6"/>"#,
                    x + 26.0
                );
                marker(svg, *i, x + 13.0, y, col);
                writeln!(
                    svg,
                    r#"<text class="legend" x="{tx:.1}" y="{:.1}" font-weight="bold">{}</text>"#,
                    y + 4.5,
                    escape(name)
                )
            }
            LegendLine::Text(t) => writeln!(
                svg,
                r#"<text class="legend" x="{tx:.1}" y="{:.1}" font-size="11.5">{}</text>"#,
                y + 4.0,
                escape(t)
            ),
            LegendLine::Small(t) => writeln!(
                svg,
                r##"<text class="legend" x="{tx:.1}" y="{:.1}" font-size="10.5" fill="#444">{}</text>"##,
                y + 3.0,
                escape(t)
            ),
            LegendLine::Style(i, dash, t) => {
                let col = COLOURS[i % COLOURS.len()];
                let (da, w) = match dash {
                    Dash::Model => ("7 4", 1.4),
                    Dash::Effects => ("2 3", 2.0),
                };
                let _ = writeln!(
                    svg,
                    r#"<line x1="{x:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="{col}" stroke-width="{w}" stroke-dasharray="{da}"/>"#,
                    x + 26.0
                );
                writeln!(
                    svg,
                    r#"<text class="legend" x="{tx:.1}" y="{:.1}" font-size="11.5">{}</text>"#,
                    y + 4.0,
                    escape(t)
                )
            }
            LegendLine::Shade(i, t) => {
                let col = COLOURS[i % COLOURS.len()];
                let _ = writeln!(
                    svg,
                    r#"<rect x="{x:.1}" y="{:.1}" width="26" height="11" fill="{col}" fill-opacity="0.13" stroke="{col}" stroke-width="0.5"/>"#,
                    y - 5.5
                );
                writeln!(
                    svg,
                    r#"<text class="legend" x="{tx:.1}" y="{:.1}" font-size="11.5">{}</text>"#,
                    y + 4.0,
                    escape(t)
                )
            }
            LegendLine::Gap => Ok(()),
        };
    }
}
