//! The Allan-deviation SVG parsed back: panels per unit, one curve per run, units in the
//! labels, pixel positions of points, model, asymptotes and slope guides against the log-log
//! mapping read from the tick labels, the model only over the measured taus; and the dynamic
//! view's windows against sums computed by hand.

use allanscope::allan::Stat;
use allanscope::gap::DiagnosisRecord;
use allanscope::model::terms::avar;
use allanscope::model::units::IncrementUnit;
use allanscope::sink::dynamic::windows;
use allanscope::sink::plot::{figure_series, final_curves, render_svg, Series};
use allanscope::sink::records::{CoefRecord, CoefValue, CurveRecord, DatasheetRecord, FitRecord};
use allanscope::sink::results::{ResultFile, Results};
use serde_json::json;
use std::borrow::Cow;

/// Pixel positions are written with one decimal: half a tenth of rounding, plus float noise.
const PX_TOL: f64 = 0.06;

/// A curve of the five-term model `coef` at octave taus from 4 ms, intervals +-10%.
pub fn model_curve(ch: &str, unit: &str, coef: [f64; 5], n_tau: usize) -> CurveRecord {
    let tau: Vec<f64> = (0..n_tau).map(|k| 0.004 * 2f64.powi(k as i32)).collect();
    let sigma: Vec<f64> = tau.iter().map(|&t| avar(coef, t).sqrt()).collect();
    CurveRecord {
        channel: ch.into(),
        unit: unit.into(),
        stat: Stat::Avar,
        t_data: 3600.0,
        r#final: true,
        lo: sigma.iter().map(|s| Some(0.9 * s)).collect(),
        hi: sigma.iter().map(|s| Some(1.1 * s)).collect(),
        edf: vec![Some(100.0); n_tau],
        count: vec![1000; n_tau],
        m: tau.iter().map(|t| (t / 0.004).round() as u64).collect(),
        alpha: vec![0; n_tau],
        tau,
        sigma,
        run: None,
    }
}

/// The fit record of `coef` with N and B determined.
pub fn fit_of(ch: &str, unit: &str, coef: [f64; 5]) -> FitRecord {
    let term = |v: f64, det: bool| CoefValue {
        value: det.then_some(v),
        lo: Some(0.98 * v),
        hi: Some(1.02 * v),
        determined: det,
    };
    let coef_rec = CoefRecord {
        Q: term(coef[0], false),
        N: term(coef[1], true),
        B: term(coef[2], true),
        K: term(coef[3], false),
        R: term(coef[4], false),
    };
    let datasheet = IncrementUnit::parse(unit).map(|u| DatasheetRecord::new(&coef_rec, &u));
    FitRecord {
        channel: ch.into(),
        unit: unit.into(),
        r#final: true,
        t_data: 3600.0,
        coef: coef_rec,
        gof: Some(1.02),
        method: "model".into(),
        model_c: coef.iter().map(|c| c * c).collect(),
        datasheet,
        readouts: None,
        q_over_lsb: None,
        run: None,
    }
}

/// `(attribute value)` of `name="..."` in one SVG element.
fn attr(el: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let i = el.find(&key)? + key.len();
    Some(el[i..].split('"').next()?.to_string())
}

fn num_attr(el: &str, name: &str) -> f64 {
    attr(el, name)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no number {name} in {el}"))
}

/// Every element whose start tag begins with `<tag` and has `class="cls"`, with its text.
fn elements<'a>(svg: &'a str, tag: &str, cls: &str) -> Vec<(&'a str, &'a str)> {
    let open = format!("<{tag} ");
    svg.match_indices(&open)
        .filter_map(|(i, _)| {
            let rest = &svg[i..];
            let end = rest.find('>')?;
            let el = &rest[..end];
            (attr(el, "class").as_deref() == Some(cls)).then(|| {
                let text = rest[end + 1..].split('<').next().unwrap_or("");
                (el, text)
            })
        })
        .collect()
}

fn points(el: &str) -> Vec<(f64, f64)> {
    attr(el, "points")
        .unwrap()
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect()
}

/// The log-log mapping of one panel from its decade tick labels: `(a, b)` with
/// `pixel = a + b log10(value)`.
fn mapping(ticks: &[(&str, &str)], coord: &str) -> (f64, f64) {
    let pts: Vec<(f64, f64)> = ticks
        .iter()
        .map(|(el, text)| (text.parse::<f64>().unwrap().log10(), num_attr(el, coord)))
        .collect();
    let (l0, p0) = pts[0];
    let (l1, p1) = pts[pts.len() - 1];
    let b = (p1 - p0) / (l1 - l0);
    (p0 - b * l0, b)
}

const G1: [f64; 5] = [0.0, 0.25, 0.2, 0.0, 0.0];
const G1_RUN2: [f64; 5] = [0.0, 0.27, 0.18, 0.0, 0.0];
const A1: [f64; 5] = [7e-4, 2.8e-4, 4e-5, 0.0, 0.0];

#[test]
fn gyros_and_accelerometers_get_their_own_panels_with_the_right_numbers() {
    let g1a = model_curve("g1", "arcsec", G1, 16);
    let g1b = model_curve("g1", "arcsec", G1_RUN2, 16);
    let a1 = model_curve("a1", "m/s", A1, 14);
    let (fa, fb, fc) = (
        fit_of("g1", "arcsec", G1),
        fit_of("g1", "arcsec", G1_RUN2),
        fit_of("a1", "m/s", A1),
    );
    // Interleaved on purpose: the panels must still separate the units.
    let series = vec![
        Series {
            curve: Cow::Borrowed(&g1a),
            run_label: "run1.jsonl".into(),
            fit: Some(&fa),
            diagnosis: None,
        },
        Series {
            curve: Cow::Borrowed(&a1),
            run_label: "run1.jsonl".into(),
            fit: Some(&fc),
            diagnosis: None,
        },
        Series {
            curve: Cow::Borrowed(&g1b),
            run_label: "run2.jsonl".into(),
            fit: Some(&fb),
            diagnosis: None,
        },
    ];
    let svg = render_svg(series, "test");
    let panels = elements(&svg, "text", "panel");
    assert_eq!(panels.len(), 2, "one panel per unit");
    assert!(panels[0].1.contains("Gyros") && panels[0].1.contains("arcsec"));
    assert!(panels[1].1.contains("ccelerometers") && panels[1].1.contains("m/s"));
    let ylabels = elements(&svg, "text", "ylabel");
    assert!(ylabels[0].1.contains("(arcsec/s)"), "{}", ylabels[0].1);
    assert!(ylabels[1].1.contains("((m/s)/s)"), "{}", ylabels[1].1);
    // Each panel's own mapping, from its tick labels (panel 1's ticks come first).
    let xt = elements(&svg, "text", "xtick");
    let yt = elements(&svg, "text", "ytick");
    // Within a panel x ticks go right and y ticks go up; the next panel starts over.
    let split_x = (1..xt.len())
        .find(|&i| num_attr(xt[i].0, "x") < num_attr(xt[i - 1].0, "x"))
        .unwrap();
    let split_y = (1..yt.len())
        .find(|&i| num_attr(yt[i].0, "y") > num_attr(yt[i - 1].0, "y"))
        .unwrap();
    let (xg, yg) = (mapping(&xt[..split_x], "x"), mapping(&yt[..split_y], "y"));
    let (xa, ya) = (mapping(&xt[split_x..], "x"), mapping(&yt[split_y..], "y"));
    let px = |m: (f64, f64), v: f64| m.0 + m.1 * v.log10();
    // One curve per run of g1, labelled by file; a1 alone in the second panel.
    let curves = elements(&svg, "polyline", "curve");
    assert_eq!(curves.len(), 3);
    let g1s: Vec<_> = curves
        .iter()
        .filter(|(el, _)| attr(el, "data-channel").as_deref() == Some("g1"))
        .collect();
    assert_eq!(g1s.len(), 2);
    let runs: Vec<String> = g1s
        .iter()
        .map(|(el, _)| attr(el, "data-run").unwrap())
        .collect();
    assert_eq!(runs, ["run1.jsonl", "run2.jsonl"]);
    for ((el, _), (rec, xm, ym)) in
        curves
            .iter()
            .zip([(&g1a, xg, yg), (&g1b, xg, yg), (&a1, xa, ya)])
    {
        let pts = points(el);
        assert_eq!(pts.len(), rec.tau.len());
        for ((x, y), (t, s)) in pts.iter().zip(rec.tau.iter().zip(&rec.sigma)) {
            assert!(
                (x - px(xm, *t)).abs() < PX_TOL,
                "x of tau {t}: {x} vs {}",
                px(xm, *t)
            );
            assert!(
                (y - px(ym, *s)).abs() < PX_TOL,
                "y of sigma {s}: {y} vs {}",
                px(ym, *s)
            );
        }
    }
    // The accelerometer's points all lie below the gyro panel's plot area.
    let gyro_bottom = yt[..split_y]
        .iter()
        .map(|(el, _)| num_attr(el, "y"))
        .fold(0.0, f64::max);
    assert!(points(curves[2].0)
        .iter()
        .all(|(_, y)| *y > gyro_bottom + 50.0));
    // The model: from the first measured tau to the last, on the five-term closed form.
    let models = elements(&svg, "polyline", "model");
    assert_eq!(models.len(), 3);
    for ((el, _), (rec, coef, xm, ym)) in models.iter().zip([
        (&g1a, G1, xg, yg),
        (&g1b, G1_RUN2, xg, yg),
        (&a1, A1, xa, ya),
    ]) {
        let pts = points(el);
        let (t0, t1) = (rec.tau[0], rec.tau[rec.tau.len() - 1]);
        assert!(
            (pts[0].0 - px(xm, t0)).abs() < PX_TOL,
            "model starts at the first tau"
        );
        assert!(
            (pts[pts.len() - 1].0 - px(xm, t1)).abs() < PX_TOL,
            "model ends at the last tau"
        );
        for (x, y) in pts {
            let tau = 10f64.powf((x - xm.0) / xm.1);
            assert!(
                tau >= t0 * (1.0 - 1e-3) && tau <= t1 * (1.0 + 1e-3),
                "model at tau {tau} outside [{t0}, {t1}]"
            );
            let want = px(ym, avar(coef, tau).sqrt());
            // x is rounded to 0.05 px, which moves the model by its slope (<= 1) times that.
            assert!(
                (y - want).abs() < 0.15,
                "model y at tau {tau}: {y} vs {want}"
            );
        }
    }
    // Asymptotes: N / sqrt(tau) and B sqrt(2 ln 2 / pi), labelled once per panel.
    let asym = elements(&svg, "polyline", "asymptote");
    let n_g1 = asym
        .iter()
        .find(|(el, _)| attr(el, "data-term").as_deref() == Some("N"))
        .unwrap();
    for (x, y) in points(n_g1.0) {
        let tau = 10f64.powf((x - xg.0) / xg.1);
        let want = px(yg, G1[1] / tau.sqrt());
        assert!(
            (y - want).abs() < 0.15,
            "N asymptote at tau {tau}: {y} vs {want}"
        );
    }
    let labels: Vec<&str> = elements(&svg, "text", "asymptote-label")
        .iter()
        .map(|(_, t)| *t)
        .collect();
    assert_eq!(
        labels.iter().filter(|t| t.starts_with("N (slope")).count(),
        2,
        "{labels:?}"
    );
    assert!(labels.contains(&"B (slope 0)"));
    // Legend: coefficients with units, intervals and datasheet units.
    assert!(
        svg.contains("N = 0.2500 [0.2450, 0.2550] arcsec/sqrt(s)"),
        "legend N"
    );
    assert!(svg.contains("= 0.004167 deg/sqrt(h)"));
    assert!(svg.contains("N = 2.800e-4 [2.744e-4, 2.856e-4] m/s/sqrt(s)"));
    // Slope guides at the panel's own scale: slope s rises s * (px per y decade) / (px per x
    // decade) pixels per pixel.
    let guides = elements(&svg, "line", "slope-guide");
    assert_eq!(guides.len(), 10, "five per panel");
    for (el, _) in &guides[..5] {
        let s = num_attr(el, "data-slope");
        let dx = num_attr(el, "x2") - num_attr(el, "x1");
        let dy = num_attr(el, "y2") - num_attr(el, "y1");
        let want = -s * yg.1.abs() / xg.1;
        assert!(
            (dy / dx - want).abs() < 0.01,
            "slope {s}: {} vs {want}",
            dy / dx
        );
    }
}

#[test]
fn the_diagnosis_is_shaded_and_the_model_with_effects_drawn() {
    let c = model_curve("g4", "arcsec", G1, 12);
    let f = fit_of("g4", "arcsec", G1);
    let effects: Vec<f64> = c.sigma.iter().map(|s| s * 1.01).collect();
    let d: DiagnosisRecord = serde_json::from_value(json!({
        "type": "diagnosis", "channel": "g4", "gap_before": 5.0, "gap_after": 0.9,
        "verdict": "explained",
        "regions": [{"tau_lo": c.tau[3], "tau_hi": c.tau[5], "sign": 1, "worst_ratio": 1.3}],
        "effects": [{"kind": "sinusoid", "params": {"amplitude": 0.3, "frequency": 0.8}, "gap_after": 0.9}],
        "final": true, "model_tau": c.tau, "model_base": c.sigma, "model_effects": effects
    }))
    .unwrap();
    let svg = render_svg(
        vec![Series {
            curve: Cow::Borrowed(&c),
            run_label: String::new(),
            fit: Some(&f),
            diagnosis: Some(&d),
        }],
        "t",
    );
    let xm = mapping(&elements(&svg, "text", "xtick"), "x");
    let px = |v: f64| xm.0 + xm.1 * v.log10();
    let regions = elements(&svg, "rect", "region");
    assert_eq!(regions.len(), 1);
    let (el, _) = regions[0];
    // From the geometric midpoint below the region's first tau to the one above its last.
    let (a, b) = (
        px((c.tau[2] * c.tau[3]).sqrt()),
        px((c.tau[5] * c.tau[6]).sqrt()),
    );
    assert!((num_attr(el, "x") - a).abs() < PX_TOL);
    assert!((num_attr(el, "width") - (b - a)).abs() < 2.0 * PX_TOL);
    assert!(svg.contains("above &#215;1.30"));
    let second = elements(&svg, "polyline", "model-effects");
    assert_eq!(second.len(), 1);
    assert_eq!(points(second[0].0).len(), c.tau.len());
    assert!(svg.contains("model + sinusoid (gap 0.90)"));
}

#[test]
fn dynamic_windows_are_the_differences_of_the_cumulative_sums() {
    // Cumulative records at 100 s and 200 s: S = sigma^2 count. At the first tau the first
    // window holds 100 differences of mean square 1, the second 100 more of mean square 4
    // (cumulative sigma^2 = 500/200 = 2.5), so the windows' deviations are 1 and 2.
    let mut a = model_curve("g1", "arcsec", G1, 2);
    a.t_data = 100.0;
    a.r#final = false;
    a.count = vec![100, 50];
    a.sigma = vec![1.0, 3.0];
    let mut b = a.clone();
    b.t_data = 200.0;
    b.r#final = true;
    b.count = vec![200, 150];
    b.sigma = vec![2.5f64.sqrt(), 1.0];
    let w = windows(&[&b, &a]);
    assert_eq!(w.len(), 2);
    assert_eq!(
        (w[0].t0, w[0].t1, w[1].t0, w[1].t1),
        (0.0, 100.0, 100.0, 200.0)
    );
    assert!((w[0].sigma[0].unwrap() - 1.0).abs() < 1e-12);
    assert!((w[1].sigma[0].unwrap() - 2.0).abs() < 1e-12);
    // Second tau: 50 differences of mean square 9, then S = 150 - 450 < 0: no value.
    assert!((w[0].sigma[1].unwrap() - 3.0).abs() < 1e-12);
    assert_eq!(w[1].sigma[1], None);
}

/// A `diagnose --ensemble 20` record of g4 (what `diagnose` writes: no curve record) at the 12
/// octave taus of `model_curve`: measured = the model G1, base band around a curve 20% lower
/// (9 of the 12 taus outside), twin band +-8% around the model (1 outside); with
/// `ensemble: false`, the same record without its band.
pub fn ensemble_diagnosis(ensemble: bool) -> serde_json::Value {
    let c = model_curve("g4", "arcsec", G1, 12);
    let base: Vec<f64> = c.sigma.iter().map(|s| 0.8 * s).collect();
    let mut d = json!({
        "type": "diagnosis", "channel": "g4", "gap_before": 21.5, "gap_after": 1.1,
        "verdict": "explained", "regions": [],
        "effects": [{"kind": "gauss_markov", "params": {"sigma": 0.6, "tau_c": 1.5}, "gap_after": 1.1}],
        "final": true, "t_data": 3600.0, "unit": "arcsec",
        "model_tau": c.tau, "model_base": base, "model_effects": c.sigma,
    });
    if ensemble {
        d["ensemble"] = json!({
            "runs": 20, "measured": c.sigma,
            "base_lo": base.iter().map(|s| 0.95 * s).collect::<Vec<_>>(),
            "base_hi": base.iter().enumerate().map(|(i, s)| if i < 3 { 1.3 * s } else { 1.05 * s }).collect::<Vec<_>>(),
            "twin_lo": c.sigma.iter().map(|s| 0.92 * s).collect::<Vec<_>>(),
            "twin_hi": c.sigma.iter().map(|s| 1.08 * s).collect::<Vec<_>>(),
            "outside_base": 0.75, "outside_twin": 1.0 / 12.0,
        });
    }
    d
}

/// The figure `plot` draws from result files (the library's choice of series).
fn figure_of(records: Vec<serde_json::Value>) -> String {
    let files = vec![ResultFile {
        name: "diag.jsonl".into(),
        records,
    }];
    let res = Results::from_files(&files);
    let all = |_: &str| true;
    let finals = final_curves(&res, "avar", &all);
    render_svg(figure_series(&res, &finals, "avar", &all, true), "t")
}

/// The two ensemble bands of a diagnosis (docs/gap.md, "The ensemble band") are drawn at the
/// record's numbers: each band's polygon runs along its upper edge at the record's taus and
/// back along its lower edge, at the pixels the panel's log-log mapping (read from the tick
/// labels) gives; the measured curve the band carries is the curve drawn; the legend says how
/// many taus lie outside each. A record without `ensemble` draws no band.
#[test]
fn the_ensemble_bands_are_drawn_at_the_records_numbers() {
    let rec = ensemble_diagnosis(true);
    let svg = figure_of(vec![rec.clone()]);
    let xm = mapping(&elements(&svg, "text", "xtick"), "x");
    let ym = mapping(&elements(&svg, "text", "ytick"), "y");
    let at = |t: f64, v: f64| (xm.0 + xm.1 * t.log10(), ym.0 + ym.1 * v.log10());
    let num = |k: &str| -> Vec<f64> {
        rec["ensemble"][k]
            .as_array()
            .or_else(|| rec[k].as_array())
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let tau = num("model_tau");
    let close = |got: &[(f64, f64)], want: &[(f64, f64)], what: &str| {
        assert_eq!(got.len(), want.len(), "{what}");
        for (k, (g, w)) in got.iter().zip(want).enumerate() {
            assert!(
                (g.0 - w.0).abs() < 2.0 * PX_TOL && (g.1 - w.1).abs() < 2.0 * PX_TOL,
                "{what} point {k}: {g:?} vs {w:?}"
            );
        }
    };
    for band in ["base", "twin"] {
        let polys = elements(&svg, "polygon", &format!("band-{band}"));
        assert_eq!(polys.len(), 1, "{band}");
        let (lo, hi) = (num(&format!("{band}_lo")), num(&format!("{band}_hi")));
        let mut want: Vec<(f64, f64)> = (0..tau.len()).map(|i| at(tau[i], hi[i])).collect();
        want.extend((0..tau.len()).rev().map(|i| at(tau[i], lo[i])));
        close(&points(polys[0].0), &want, band);
    }
    let measured = num("measured");
    let curve = elements(&svg, "polyline", "curve");
    assert_eq!(curve.len(), 1);
    let want: Vec<(f64, f64)> = (0..tau.len()).map(|i| at(tau[i], measured[i])).collect();
    close(&points(curve[0].0), &want, "measured curve");
    // Behind the curve: both bands come before it.
    let (b, t, c) = (
        svg.find("class=\"band-base\"").unwrap(),
        svg.find("class=\"band-twin\"").unwrap(),
        svg.find("class=\"curve\"").unwrap(),
    );
    assert!(b < t && t < c);
    assert!(svg.contains("measured outside at 9 of 12 taus (75%)"));
    assert!(svg.contains("measured outside at 1 of 12 taus (8%)"));
    assert!(svg.contains("twin (+ Gauss-Markov): 2.5\u{2013}97.5% of 20 runs"));
    // No intervals on a curve made from the band.
    assert!(!svg.contains("95% intervals"));

    // Without `ensemble`: a diagnosis alone has no curve to draw; beside a curve record it
    // draws no band, and the curve keeps its intervals.
    let bare = ensemble_diagnosis(false);
    let files = vec![ResultFile {
        name: "d.jsonl".into(),
        records: vec![bare.clone()],
    }];
    let res = Results::from_files(&files);
    let all = |_: &str| true;
    assert!(figure_series(&res, &[], "avar", &all, true).is_empty());
    let c = serde_json::to_value(model_curve("g4", "arcsec", G1, 12)).unwrap();
    let plain = figure_of(vec![c.clone(), bare]);
    assert!(!plain.contains("band-"), "a band without an ensemble");
    assert!(plain.contains("95% intervals"));
    // With one, beside the curve record: the bands behind that curve, no second curve.
    let banded = figure_of(vec![c, rec]);
    assert_eq!(elements(&banded, "polygon", "band-twin").len(), 1);
    assert_eq!(elements(&banded, "polyline", "curve").len(), 1);
}
