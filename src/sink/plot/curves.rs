//! What is drawn for one curve: its markers, points and 95% intervals, the fitted five-term model
//! over the measured taus, each determined term's asymptote, the model with the diagnosed
//! effects, and the shaded taus where the base model misses.

use std::fmt::Write;

use super::axes::{polyline, Axes};
use super::fit_terms::{determined_terms, fit_coefs};
use super::text::{escape, ratio_text};
use super::{Series, COLOURS, LEFT, SLOPES};
use crate::gap::DiagnosisRecord;
use crate::model::terms::{avar as model_avar, basis, TERM_NAMES};
use crate::sink::records::FitRecord;

/// The markers, one shape per curve, at (x, y) with radius r.
pub(super) fn marker(svg: &mut String, i: usize, x: f64, y: f64, col: &str) {
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
/// The taus where the base model misses, shaded from half a step before the first tau of a
/// region to half a step after its last (geometric midpoints to the neighbouring taus).
pub(super) fn draw_regions(
    svg: &mut String,
    ax: &Axes,
    d: &DiagnosisRecord,
    col: &str,
    clip: &str,
) {
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
pub(super) fn draw_series(
    svg: &mut String,
    ax: &Axes,
    i: usize,
    s: &Series,
    clip: &str,
    asymptotes: bool,
    labelled: &mut [bool; 5],
) {
    let col = COLOURS[i % COLOURS.len()];
    let c = &*s.curve;
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
pub(super) fn draw_asymptotes(
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
