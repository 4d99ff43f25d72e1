//! The legend's lines: a curve's name with its colour and marker, text and small text lines, the
//! model's and the effects' line styles, the shading of misses, the ensemble bands, and gaps
//! between curves.

use std::fmt::Write;

use super::band::{band_style, BandKind};
use super::curves::marker;
use super::text::escape;
use super::COLOURS;

pub(super) enum Dash {
    Model,
    Effects,
}

pub(super) enum LegendLine {
    Curve(usize, String),
    Text(String),
    Small(String),
    Style(usize, Dash, String),
    Shade(usize, String),
    /// An ensemble band: the curve's index, which band, the words, and the id of the panel's
    /// hatching pattern.
    Band(usize, BandKind, String, String),
    Gap,
}

impl LegendLine {
    pub(super) fn height(&self) -> f64 {
        match self {
            LegendLine::Curve(..) => 19.0,
            LegendLine::Text(_)
            | LegendLine::Style(..)
            | LegendLine::Shade(..)
            | LegendLine::Band(..) => 15.0,
            LegendLine::Small(_) => 13.0,
            LegendLine::Gap => 8.0,
        }
    }

    pub(super) fn draw(&self, svg: &mut String, x: f64, y: f64) {
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
                let look = format!(
                    r#"fill="{col}" fill-opacity="0.13" stroke="{col}" stroke-width="0.5""#
                );
                swatch(svg, x, y, &look, t)
            }
            LegendLine::Band(i, kind, t, hatch) => {
                let (fill, edge, dash) = band_style(*kind, COLOURS[i % COLOURS.len()], hatch);
                let look = format!(r#"{fill} stroke="{edge}" stroke-width="0.9"{dash}"#);
                swatch(svg, x, y, &look, t)
            }
            LegendLine::Gap => Ok(()),
        };
    }
}

/// A legend line of a filled swatch (its attributes `look`) and its words `t`.
fn swatch(svg: &mut String, x: f64, y: f64, look: &str, t: &str) -> std::fmt::Result {
    let _ = writeln!(
        svg,
        r#"<rect x="{x:.1}" y="{:.1}" width="26" height="11" {look}/>"#,
        y - 5.5
    );
    writeln!(
        svg,
        r#"<text class="legend" x="{:.1}" y="{:.1}" font-size="11.5">{}</text>"#,
        x + 34.0,
        y + 4.0,
        escape(t)
    )
}
