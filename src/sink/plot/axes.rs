//! The log-log axes of one panel: the scale (decades to pixels), the grid with its ticks and
//! decade labels, polylines through `(tau, sigma)` points, and the fan of slope guides.

use std::fmt::Write;

use super::text::decade_label;
use super::{LEFT, SLOPES};

/// The log-log scale of one panel.
pub(super) struct Axes {
    pub(super) x0: i32,
    pub(super) x1: i32,
    pub(super) y0: i32,
    pub(super) y1: i32,
    /// Top of the plot area (px).
    pub(super) top: f64,
    pub(super) pw: f64,
    pub(super) ph: f64,
}

impl Axes {
    pub(super) fn px(&self, x: f64) -> f64 {
        LEFT + (x.log10() - self.x0 as f64) / (self.x1 - self.x0) as f64 * self.pw
    }
    pub(super) fn py(&self, y: f64) -> f64 {
        self.top + self.ph - (y.log10() - self.y0 as f64) / (self.y1 - self.y0) as f64 * self.ph
    }
    /// Pixels per decade, x and y.
    pub(super) fn ppd(&self) -> (f64, f64) {
        (
            self.pw / (self.x1 - self.x0) as f64,
            self.ph / (self.y1 - self.y0) as f64,
        )
    }
}
pub(super) fn draw_grid(svg: &mut String, ax: &Axes) {
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
/// A polyline through `(tau, sigma)` points, skipping non-positive values.
pub(super) fn polyline(ax: &Axes, pts: impl Iterator<Item = (f64, f64)>) -> String {
    pts.filter(|(t, y)| *t > 0.0 && *y > 0.0 && y.is_finite())
        .map(|(t, y)| format!("{:.1},{:.1}", ax.px(t), ax.py(y)))
        .collect::<Vec<_>>()
        .join(" ")
}
/// A fan of the five slopes at the panel's own scale, with the term each belongs to.
pub(super) fn draw_slope_key(svg: &mut String, ax: &Axes, x: f64, y: f64) {
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
