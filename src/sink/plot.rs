//! Allan-deviation plots as SVG, for test reports: log-log axes with decade grid lines, each
//! channel's deviation with its 95% interval as bars, and the fitted five-term model as a
//! dashed line with its terms' asymptotes listed in the legend.
//!
//! The SVG is written directly (text as `<text>` elements), so no font library is needed to
//! draw it; a viewer renders the text with its own fonts.

use std::fmt::Write;

use crate::model::terms::avar as model_avar;
use crate::sink::records::{CurveRecord, FitRecord};

/// One channel's curve and, if known, its fit.
pub struct Series<'a> {
    pub curve: &'a CurveRecord,
    pub fit: Option<&'a FitRecord>,
}

const W: f64 = 960.0;
const H: f64 = 640.0;
const LEFT: f64 = 90.0;
const RIGHT: f64 = 230.0;
const TOP: f64 = 50.0;
const BOTTOM: f64 = 70.0;
/// Colour-blind-safe palette (Okabe and Ito).
const COLOURS: [&str; 8] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442",
];

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A decade label: `10^k` written plainly for |k| <= 3, else as `1e{k}`.
fn decade_label(k: i32) -> String {
    match k {
        -3..=-1 => format!("{}", 10f64.powi(k)),
        0..=3 => format!("{}", 10f64.powi(k) as i64),
        _ => format!("1e{k}"),
    }
}

/// The fitted model's coefficients `(Q, N, B, K, R)`: every fitted term (from `model_c`),
/// or the determined ones where an older record lacks it.
fn fit_coefs(f: &FitRecord) -> [f64; 5] {
    if f.model_c.len() == 5 {
        std::array::from_fn(|i| f.model_c[i].max(0.0).sqrt())
    } else {
        ["Q", "N", "B", "K", "R"].map(|k| f.coef[k]["value"].as_f64().unwrap_or(0.0))
    }
}

/// Renders the plot. `title` goes on top; the y label names the statistic and unit.
pub fn render_svg(series: &[Series], title: &str) -> String {
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    for s in series {
        xs.extend(s.curve.tau.iter().copied());
        ys.extend(s.curve.sigma.iter().copied());
        ys.extend(s.curve.lo.iter().flatten().copied());
        ys.extend(s.curve.hi.iter().flatten().copied());
    }
    let pos = |v: &Vec<f64>| -> Vec<f64> {
        v.iter()
            .copied()
            .filter(|x| *x > 0.0 && x.is_finite())
            .collect()
    };
    let (xs, ys) = (pos(&xs), pos(&ys));
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="13">"#
    );
    let _ = writeln!(svg, r#"<rect width="{W}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="28" text-anchor="middle" font-size="16">{}</text>"#,
        (LEFT + W - RIGHT) / 2.0,
        escape(title)
    );
    if xs.is_empty() || ys.is_empty() {
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="middle">no data</text>"#,
            W / 2.0,
            H / 2.0
        );
        svg.push_str("</svg>\n");
        return svg;
    }
    let lmin = |v: &[f64]| {
        v.iter()
            .fold(f64::INFINITY, |a, &b| a.min(b))
            .log10()
            .floor() as i32
    };
    let lmax = |v: &[f64]| v.iter().fold(0.0f64, |a, &b| a.max(b)).log10().ceil() as i32;
    let (x0, x1) = (lmin(&xs), lmax(&xs).max(lmin(&xs) + 1));
    let (y0, y1) = (lmin(&ys), lmax(&ys).max(lmin(&ys) + 1));
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    let px = |x: f64| LEFT + (x.log10() - x0 as f64) / (x1 - x0) as f64 * pw;
    let py = |y: f64| TOP + ph - (y.log10() - y0 as f64) / (y1 - y0) as f64 * ph;
    // Grid: decades (solid) and 2..9 within each (faint), then the decade labels.
    let grid = |lo: i32, hi: i32| -> Vec<(f64, bool)> {
        (lo..=hi)
            .flat_map(|k| (1..10).map(move |j| (k, j)))
            .filter(|&(k, j)| k < hi || j == 1)
            .map(|(k, j)| (10f64.powi(k) * j as f64, j == 1))
            .collect()
    };
    let style = |major: bool| {
        if major {
            ("#bbbbbb", 1.0)
        } else {
            ("#eeeeee", 0.7)
        }
    };
    for (v, major) in grid(x0, x1) {
        let (stroke, wd) = style(major);
        let _ = writeln!(
            svg,
            r#"<line x1="{0:.1}" y1="{TOP}" x2="{0:.1}" y2="{1}" stroke="{stroke}" stroke-width="{wd}"/>"#,
            px(v),
            TOP + ph
        );
    }
    for (v, major) in grid(y0, y1) {
        let (stroke, wd) = style(major);
        let _ = writeln!(
            svg,
            r#"<line x1="{LEFT}" y1="{0:.1}" x2="{1}" y2="{0:.1}" stroke="{stroke}" stroke-width="{wd}"/>"#,
            py(v),
            LEFT + pw
        );
    }
    for k in x0..=x1 {
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{}" text-anchor="middle">{}</text>"#,
            px(10f64.powi(k)),
            TOP + ph + 20.0,
            decade_label(k)
        );
    }
    for k in y0..=y1 {
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{:.1}" text-anchor="end" dominant-baseline="middle">{}</text>"#,
            LEFT - 8.0,
            py(10f64.powi(k)),
            decade_label(k)
        );
    }
    let _ = writeln!(
        svg,
        r#"<rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
    );
    // One unit for the axis when the series share it; otherwise each legend entry names its own.
    let first_unit = series.first().map(|s| s.curve.unit.as_str()).unwrap_or("u");
    let mixed = series.iter().any(|s| s.curve.unit != first_unit);
    let unit = if mixed { "unit" } else { first_unit };
    let stat = series
        .first()
        .map(|s| s.curve.stat.name())
        .unwrap_or("avar");
    let dev = match stat {
        "hvar" => "Hadamard deviation",
        "mvar" => "modified Allan deviation",
        _ => "Allan deviation",
    };
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" text-anchor="middle">averaging time tau (s)</text>"#,
        LEFT + pw / 2.0,
        H - 22.0
    );
    let _ = writeln!(
        svg,
        r#"<text transform="translate(24,{}) rotate(-90)" text-anchor="middle">{dev} ({}/s), 95% intervals</text>"#,
        TOP + ph / 2.0,
        escape(unit)
    );
    // Series.
    let mut legend_y = TOP + 10.0;
    for (i, s) in series.iter().enumerate() {
        let col = COLOURS[i % COLOURS.len()];
        let c = s.curve;
        let pts: Vec<(f64, f64)> = c
            .tau
            .iter()
            .zip(&c.sigma)
            .filter(|(t, y)| **t > 0.0 && **y > 0.0)
            .map(|(t, y)| (px(*t), py(*y)))
            .collect();
        let path: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        let _ = writeln!(
            svg,
            r#"<polyline points="{}" fill="none" stroke="{col}" stroke-width="1.5"/>"#,
            path.join(" ")
        );
        for (j, (x, y)) in pts.iter().enumerate() {
            if let (Some(Some(lo)), Some(Some(hi))) = (c.lo.get(j), c.hi.get(j)) {
                if *lo > 0.0 {
                    let _ = writeln!(
                        svg,
                        r#"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="{col}" stroke-width="1"/>"#,
                        py(*lo),
                        py(*hi)
                    );
                }
            }
            let _ = writeln!(
                svg,
                r#"<circle cx="{x:.1}" cy="{y:.1}" r="2.8" fill="{col}"/>"#
            );
        }
        let _ = writeln!(
            svg,
            r#"<line x1="{}" y1="{legend_y:.1}" x2="{}" y2="{legend_y:.1}" stroke="{col}" stroke-width="2"/>"#,
            W - RIGHT + 15.0,
            W - RIGHT + 40.0
        );
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{:.1}">{}</text>"#,
            W - RIGHT + 46.0,
            legend_y + 4.0,
            escape(&if mixed {
                format!("{} [{}]", c.channel, c.unit)
            } else {
                c.channel.clone()
            })
        );
        legend_y += 18.0;
        if let Some(f) = s.fit {
            if stat == "avar" {
                let coef = fit_coefs(f);
                let n = 120;
                let (a, b) = (x0 as f64, x1 as f64);
                let mut line = Vec::new();
                for k in 0..=n {
                    let t = 10f64.powf(a + (b - a) * k as f64 / n as f64);
                    let y = model_avar(coef, t).sqrt();
                    if y > 0.0 && y.log10() >= y0 as f64 && y.log10() <= y1 as f64 {
                        line.push(format!("{:.1},{:.1}", px(t), py(y)));
                    }
                }
                let _ = writeln!(
                    svg,
                    r#"<polyline points="{}" fill="none" stroke="{col}" stroke-width="1.2" stroke-dasharray="6 4"/>"#,
                    line.join(" ")
                );
                for (k, name) in ["Q", "N", "B", "K", "R"].iter().enumerate() {
                    if let Some(v) = f.coef[*name]["value"].as_f64() {
                        let _ = writeln!(
                            svg,
                            r#"<text x="{}" y="{:.1}" font-size="11">{name} = {:.4e}</text>"#,
                            W - RIGHT + 46.0,
                            legend_y + 2.0,
                            v
                        );
                        legend_y += 14.0;
                        let _ = k;
                    }
                }
                let gof = f
                    .gof
                    .map(|g| format!("{g:.2}"))
                    .unwrap_or_else(|| "-".into());
                let _ = writeln!(
                    svg,
                    r#"<text x="{}" y="{:.1}" font-size="11">model (dashed), gof {gof}</text>"#,
                    W - RIGHT + 46.0,
                    legend_y + 2.0
                );
                legend_y += 20.0;
            }
        }
    }
    svg.push_str("</svg>\n");
    svg
}
