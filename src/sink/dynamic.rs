//! The dynamic Allan view ("where in the run"): time on x, tau on y, each cell coloured by the
//! Allan deviation of that stretch of the run against the whole run's.
//!
//! The interim `curve` records of a run are cumulative: at `t_data` the record holds
//! `sigma^2 = S / count`, the mean of `count` squared second differences over the data so far
//! (docs/theory.md section 1). The differences added between two records are those that ended
//! between them, so the AVAR of that window is `(S_b - S_a) / (count_b - count_a)` with
//! `S = sigma^2 * count` (exact up to the rounding of the printed sigma, whose 17 digits leave
//! about 1e-13 of relative error after the subtraction for windows a tenth of the run).

use std::fmt::Write;

use crate::sink::plot::{escape, W};
use crate::sink::records::CurveRecord;

/// One window's AVAR at each tau of the curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Window {
    /// Data-seconds at its start and end.
    pub t0: f64,
    pub t1: f64,
    /// Allan deviation in the window per tau (u/s); `None` where too few differences ended in it.
    pub sigma: Vec<Option<f64>>,
}

/// The least number of differences a cell needs, and the least window length in units of the
/// tau (a window shorter than 2 tau holds no difference of its own; 3 keeps a few).
const MIN_DIFFS: u64 = 4;
const MIN_WINDOW_TAUS: f64 = 3.0;

/// The windows between successive records of one channel's AVAR curve (interim and final, in
/// `t_data` order, same taus). Records whose taus differ from the last one's are skipped.
pub fn windows(curves: &[&CurveRecord]) -> Vec<Window> {
    let mut sorted: Vec<&CurveRecord> = curves.to_vec();
    sorted.sort_by(|a, b| a.t_data.total_cmp(&b.t_data));
    sorted.dedup_by(|b, a| a.t_data == b.t_data);
    let Some(last) = sorted.last() else {
        return Vec::new();
    };
    let taus = last.tau.clone();
    let sums = |c: &CurveRecord| -> Option<Vec<(f64, u64)>> {
        // Curves grow taus as data comes in: map each of the final taus, absent = no data yet.
        Some(
            taus.iter()
                .map(|t| {
                    c.tau.iter().position(|x| x == t).map_or((0.0, 0), |j| {
                        (c.sigma[j] * c.sigma[j] * c.count[j] as f64, c.count[j])
                    })
                })
                .collect(),
        )
    };
    let mut out = Vec::new();
    let mut prev: (f64, Vec<(f64, u64)>) = (0.0, vec![(0.0, 0); taus.len()]);
    for c in sorted {
        let Some(now) = sums(c) else { continue };
        let sigma = taus
            .iter()
            .zip(now.iter().zip(&prev.1))
            .map(|(tau, ((s1, n1), (s0, n0)))| {
                let dn = n1.saturating_sub(*n0);
                let ds = s1 - s0;
                (dn >= MIN_DIFFS && c.t_data - prev.0 >= MIN_WINDOW_TAUS * tau && ds > 0.0)
                    .then(|| (ds / dn as f64).sqrt())
            })
            .collect();
        out.push(Window {
            t0: prev.0,
            t1: c.t_data,
            sigma,
        });
        prev = (c.t_data, now);
    }
    out
}

/// Diverging colour for `log2(ratio)` clamped to [-1, 1]: blue (quieter than the run) through
/// white to vermilion (noisier), readable by the colour-blind and in grey.
fn colour(l: f64) -> String {
    let l = l.clamp(-1.0, 1.0);
    let (to, a) = if l < 0.0 {
        ([0x21, 0x66, 0xAC], -l)
    } else {
        ([0xB2, 0x18, 0x2B], l)
    };
    let mix = |c: u8| (255.0 + (c as f64 - 255.0) * a).round() as u8;
    format!("#{:02x}{:02x}{:02x}", mix(to[0]), mix(to[1]), mix(to[2]))
}

/// The view of one channel as an SVG panel: `curves` are its AVAR records (interim and final),
/// `label` names the channel and run.
pub fn render_dynamic_svg(curves: &[&CurveRecord], label: &str) -> String {
    const H: f64 = 330.0;
    const L: f64 = 90.0;
    const T: f64 = 40.0;
    const PH: f64 = 230.0;
    let pw = W - L - 230.0;
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="Helvetica, Arial, sans-serif" font-size="13"><rect width="{W}" height="{H}" fill="white"/>"#
    );
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="22" text-anchor="middle" font-size="15">{}: Allan deviation per stretch of the run / whole run</text>"#,
        L + pw / 2.0,
        escape(label)
    );
    let ws = windows(curves);
    let last = curves
        .iter()
        .max_by(|a, b| a.t_data.total_cmp(&b.t_data))
        .copied();
    let (Some(last), true) = (last, ws.len() >= 2) else {
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="middle">fewer than two interim records: run with --every S to see where in the run</text></svg>"#,
            L + pw / 2.0,
            T + PH / 2.0
        );
        return svg;
    };
    let taus = &last.tau;
    let t_end = last.t_data.max(1e-9);
    let n = taus.len();
    let row_h = PH / n as f64;
    // Rows: tau ascending upwards.
    for (w, win) in ws.iter().enumerate() {
        let x0 = L + win.t0 / t_end * pw;
        let x1 = L + win.t1 / t_end * pw;
        for (j, s) in win.sigma.iter().enumerate() {
            let y = T + PH - (j + 1) as f64 * row_h;
            let fill = match (s, last.sigma.get(j)) {
                (Some(s), Some(f)) if *f > 0.0 => colour((s / f).log2()),
                _ => "#d9d9d9".into(),
            };
            let ratio = match (s, last.sigma.get(j)) {
                (Some(s), Some(f)) if *f > 0.0 => format!("{:.3}", s / f),
                _ => "none".into(),
            };
            let _ = writeln!(
                svg,
                r#"<rect class="cell" data-window="{w}" data-tau="{}" data-ratio="{ratio}" x="{x0:.1}" y="{y:.1}" width="{:.1}" height="{:.1}" fill="{fill}"/>"#,
                taus[j],
                (x1 - x0).max(0.5),
                row_h
            );
        }
    }
    let _ = writeln!(
        svg,
        r#"<rect x="{L}" y="{T}" width="{pw}" height="{PH}" fill="none" stroke="black"/>"#
    );
    // Tau labels at the decades inside the taus, placed by log-interpolating between the rows
    // (rows are one per tau, not uniform in log tau when the taus are not), with a tick mark;
    // time labels at the window ends.
    let centre = |j: usize| T + PH - (j as f64 + 0.5) * row_h;
    let y_of = |v: f64| -> Option<f64> {
        let j = taus.windows(2).position(|w| w[0] <= v && v <= w[1])?;
        let (a, b) = (taus[j].ln(), taus[j + 1].ln());
        let f = if b > a { (v.ln() - a) / (b - a) } else { 0.0 };
        Some(centre(j) - f * row_h)
    };
    let (lo, hi) = (
        taus[0].log10().ceil() as i32,
        taus[n - 1].log10().floor() as i32,
    );
    let mut decades: Vec<(f64, f64)> = (lo..=hi)
        .filter_map(|k| {
            let v = 10f64.powi(k);
            y_of(v).or((n == 1).then(|| centre(0))).map(|y| (v, y))
        })
        .collect();
    if decades.is_empty() {
        // Less than a decade of taus: its two ends.
        decades = vec![(taus[0], centre(0)), (taus[n - 1], centre(n - 1))];
    }
    for (v, y) in decades {
        let _ = writeln!(
            svg,
            r#"<line x1="{}" y1="{y:.1}" x2="{L}" y2="{y:.1}" stroke="black"/><text class="tau-label" x="{}" y="{y:.1}" text-anchor="end" dominant-baseline="middle" font-size="11">{}</text>"#,
            L - 4.0,
            L - 6.0,
            crate::sink::plot::tick(v)
        );
    }
    for win in &ws {
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{}" text-anchor="middle" font-size="11">{}</text>"#,
            L + win.t1 / t_end * pw,
            T + PH + 16.0,
            crate::sink::plot::tick(win.t1)
        );
    }
    let _ = writeln!(
        svg,
        r#"<text x="{}" y="{}" text-anchor="middle">time into the run (data-seconds; each column: the differences that ended in it)</text>"#,
        L + pw / 2.0,
        T + PH + 40.0
    );
    let _ = writeln!(
        svg,
        r#"<text transform="translate(24,{}) rotate(-90)" text-anchor="middle">&#964; (s)</text>"#,
        T + PH / 2.0
    );
    // Colour key.
    let kx = W - 200.0;
    let _ = writeln!(
        svg,
        r#"<text x="{kx}" y="{}" font-size="12" font-weight="bold">stretch / whole run</text>"#,
        T + 6.0
    );
    for (i, r) in [2.0, 1.5, 1.0, 0.75, 0.5].iter().enumerate() {
        let y = T + 18.0 + i as f64 * 24.0;
        let _ = writeln!(
            svg,
            r##"<rect x="{kx}" y="{y}" width="28" height="18" fill="{}" stroke="#999" stroke-width="0.5"/><text x="{}" y="{}" font-size="12">&#215;{r}{}</text>"##,
            colour(f64::log2(*r)),
            kx + 36.0,
            y + 13.0,
            if i == 0 {
                " or more"
            } else if i == 4 {
                " or less"
            } else {
                ""
            }
        );
    }
    let _ = writeln!(
        svg,
        r##"<rect x="{kx}" y="{}" width="28" height="18" fill="#d9d9d9"/><text x="{}" y="{}" font-size="12">too few differences</text>"##,
        T + 18.0 + 5.0 * 24.0,
        kx + 36.0,
        T + 31.0 + 5.0 * 24.0
    );
    svg.push_str("</svg>\n");
    svg
}

/// The `height` attribute of an SVG this module or [`crate::sink::plot`] wrote.
fn svg_height(svg: &str) -> f64 {
    svg.split_once("height=\"")
        .and_then(|(_, r)| r.split_once('"'))
        .and_then(|(h, _)| h.parse().ok())
        .unwrap_or(0.0)
}

/// Several SVGs of width [`W`] one under the other, as one SVG (each kept as a nested `<svg>`).
pub fn stack(parts: &[String]) -> String {
    let total: f64 = parts.iter().map(|p| svg_height(p)).sum();
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{total}\" viewBox=\"0 0 {W} {total}\">\n"
    );
    let mut y = 0.0;
    for p in parts {
        let h = svg_height(p);
        let inner = p.replacen("<svg ", &format!("<svg x=\"0\" y=\"{y}\" "), 1);
        out.push_str(&inner);
        y += h;
    }
    out.push_str("</svg>\n");
    out
}
