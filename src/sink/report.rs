//! A test report as one self-contained HTML page a lead can sign: a PASS/FAIL banner from the
//! datasheet limits, the runs and whether each input was read to its end, the limits with their
//! units, the Allan-deviation figures (one panel per channel unit, runs labelled by file), the
//! noise model (the seed paper's table 2 layout per channel when there are several runs: runs
//! as rows, the five coefficients as columns, then mean, 95% interval of the mean and sd) and
//! the IEEE 952 read-outs beside it, the final diagnosis in words with each effect's parameters
//! named and in units (interim diagnoses in a small time table), the dynamic Allan view where
//! interim curves exist, the decoder's health, and a signature block. Print CSS keeps tables and
//! figures whole on A4.

use std::fmt::Write;

use crate::gap::record::RecordedEffect;
use crate::gap::DiagnosisRecord;
use crate::model::aggregate::{aggregate_channels, RunCoefs};
use crate::model::limits::LimitResult;
use crate::model::terms::TERM_NAMES;
use crate::sink::dynamic::render_dynamic_svg;
use crate::sink::plot::{
    coef_units, effect_name, escape as esc, ratio_text, render_svg, tick, Series,
};
use crate::sink::records::{
    AggregateRecord, FitRecord, HealthRecord, ReadoutRecord, TimeColumnRecord,
};
use crate::sink::results::{Labelled, ResultFile, Results};

fn opt(v: Option<f64>) -> String {
    v.map_or("&ndash;".into(), tick)
}

/// A run: its file and its `run` index inside the file.
type RunKey = (usize, Option<usize>);

/// The seed paper's column order in table 2.
const PAPER_ORDER: [usize; 5] = [4, 3, 2, 1, 0];

/// The overall verdict of the limits over every run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Banner {
    Pass,
    Fail,
    /// Some limit straddles its interval, none fails.
    Undecided,
    /// No limit was given.
    NoLimits,
}

/// PASS when every judged limit passes, FAIL when any fails, else undecided.
pub fn banner_of(res: &Results) -> Banner {
    let verdicts: Vec<&str> = res.limits.iter().map(|l| l.rec.verdict.name()).collect();
    let summary_pass: Vec<Option<bool>> = res.summaries.iter().map(|s| s.rec.record.pass).collect();
    if verdicts.is_empty() && summary_pass.iter().all(Option::is_none) {
        Banner::NoLimits
    } else if verdicts.contains(&"fail") || summary_pass.contains(&Some(false)) {
        Banner::Fail
    } else if verdicts.iter().all(|v| *v == "pass") && !summary_pass.is_empty() {
        Banner::Pass
    } else {
        Banner::Undecided
    }
}

const CSS: &str = "
body{font-family:Helvetica,Arial,sans-serif;max-width:1120px;margin:1.5em auto;color:#111;font-size:14px;line-height:1.35}
h1{font-size:24px;margin:0 0 .3em} h2{font-size:19px;border-bottom:2px solid #333;padding-bottom:2px;margin-top:1.6em}
h3{font-size:16px;margin:1.2em 0 .3em}
table{border-collapse:collapse;margin:.4em 0 1.2em}
td,th{border:1px solid #999;padding:3px 8px;text-align:right;vertical-align:top}
th{background:#eee} td.l,th.l{text-align:left} caption{text-align:left;font-weight:bold;padding:4px 0}
tr.stat td{background:#f6f6f6}
.banner{font-size:30px;font-weight:bold;padding:14px 20px;border:4px solid;margin:.6em 0 1em}
.banner small{display:block;font-size:14px;font-weight:normal;margin-top:4px}
.b-pass{color:#005a32;border-color:#005a32;background:#e5f5e0}
.b-fail{color:#a50f15;border-color:#a50f15;background:#fee0d2}
.b-und{color:#7a4b00;border-color:#b07000;background:#fff3d6}
.b-none{color:#333;border-color:#777;background:#f0f0f0}
.warn{color:#a50f15;font-weight:bold}
.pass{color:#005a32;font-weight:bold} .fail{color:#a50f15;font-weight:bold} .und{color:#7a4b00;font-weight:bold}
.meta{color:#444} svg{max-width:100%;height:auto;display:block;margin:.5em 0}
.sign table{width:100%} .sign td{height:2.6em;text-align:left;width:25%}
.small{font-size:12px;color:#444}
@page{size:A4;margin:14mm}
@media print{body{max-width:none;margin:0;font-size:11px} h2{break-after:avoid} table,svg,.banner,.sign{break-inside:avoid}
 .banner,th,tr.stat td,.b-pass,.b-fail,.b-und{-webkit-print-color-adjust:exact;print-color-adjust:exact}}
";

/// Renders the page. `generated` is the date and time written under the title.
pub fn render_html(files: &[ResultFile], title: &str, generated: &str) -> String {
    let res = Results::from_files(files);
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>{CSS}</style></head><body>\n<h1>{t}</h1>\n<p class=\"meta\">Files: {f}. Written {g} by allanscope {v}.</p>\n",
        t = esc(title),
        f = esc(&files.iter().map(|f| f.name.as_str()).collect::<Vec<_>>().join(", ")),
        g = esc(generated),
        v = env!("CARGO_PKG_VERSION")
    );
    banner(&mut h, &res);
    runs_table(&mut h, &res);
    limits_table(&mut h, &res);
    figures(&mut h, &res);
    noise_model(&mut h, &res);
    diagnosis(&mut h, &res);
    dynamic_view(&mut h, &res);
    health(&mut h, &res);
    h.push_str(
        "<h2>Sign-off</h2>\n<div class=\"sign\"><table><tr><th class=\"l\">role</th><th class=\"l\">name</th><th class=\"l\">signature</th><th class=\"l\">date</th></tr>\n\
         <tr><td>Tested by</td><td></td><td></td><td></td></tr>\n<tr><td>Checked by</td><td></td><td></td><td></td></tr>\n<tr><td>Approved by</td><td></td><td></td><td></td></tr></table></div>\n\
         <p class=\"small\">Written by allanscope from its JSON-lines records; coefficients in the units of THEORY.md section 2 (u = the channel's unit), 95% intervals in brackets.</p>\n</body></html>\n",
    );
    h
}

fn banner(h: &mut String, res: &Results) {
    let b = banner_of(res);
    let (class, word, note) = match b {
        Banner::Pass => (
            "b-pass",
            "PASS",
            "every datasheet limit is met at 97.5% one-sided confidence",
        ),
        Banner::Fail => (
            "b-fail",
            "FAIL",
            "at least one datasheet limit is exceeded (table below)",
        ),
        Banner::Undecided => (
            "b-und",
            "NOT DECIDED",
            "no limit fails, but some interval straddles its limit: more data needed",
        ),
        Banner::NoLimits => (
            "b-none",
            "NO LIMITS JUDGED",
            "no datasheet limits were given (--limits or a stand config's [[limits]])",
        ),
    };
    let warn: Vec<String> = res
        .summaries
        .iter()
        .filter_map(|s| {
            let c = &s.rec.completion;
            c.is_warning()
                .then(|| format!("{}: {}", s.label, c.phrase()))
        })
        .collect();
    let _ = write!(
        h,
        "<div class=\"banner {class}\" data-verdict=\"{word}\">{word}<small>{note}</small>"
    );
    // The limits that decided the banner, named: those exceeded, and those left undecided.
    let named = |verdict: &str| -> Vec<String> {
        res.limits
            .iter()
            .filter(|l| l.rec.verdict.name() == verdict)
            .map(|l| {
                let interval = match (l.rec.lo, l.rec.hi) {
                    (Some(lo), Some(hi)) => format!(" [{}, {}]", tick(lo), tick(hi)),
                    _ => String::new(),
                };
                format!(
                    "{} {} {} {} {} (measured {}{interval}{})",
                    esc(&l.rec.channel),
                    esc(l.rec.coef.name()),
                    if l.rec.bound == "min" { "&ge;" } else { "&le;" },
                    tick(l.rec.limit),
                    esc(&limit_unit(res, &l.rec)),
                    match l.rec.value {
                        Some(v) => tick(v),
                        None => "not determined".into(),
                    },
                    if res.summaries.len() > 1 {
                        format!(", {}", esc(&l.label))
                    } else {
                        String::new()
                    }
                )
            })
            .collect()
    };
    let failed = named("fail");
    if !failed.is_empty() {
        let _ = write!(h, "<small>failed: {}</small>", failed.join("; "));
    }
    let undecided = named("undecided");
    if !undecided.is_empty() {
        let _ = write!(
            h,
            "<small>not decided (the interval straddles the limit): {}</small>",
            undecided.join("; ")
        );
    }
    for w in &warn {
        let _ = write!(h, "<small class=\"warn\">{}</small>", esc(w));
    }
    h.push_str("</div>\n");
}

fn runs_table(h: &mut String, res: &Results) {
    if res.summaries.is_empty() {
        // The `diagnose` command writes diagnoses only, by design; other records without a
        // summary are a run that stopped before writing its last record.
        if !(res.curves.is_empty() && res.fits.is_empty()) {
            h.push_str("<p class=\"warn\">No summary record: the run may have been cut short before its end.</p>\n");
        } else if !res.diagnoses.is_empty() {
            h.push_str("<p class=\"meta\">Diagnosis records only (the output of <code>allanscope diagnose</code>): no curves, fit or summary to show.</p>\n");
        }
        return;
    }
    h.push_str("<h2>Runs</h2>\n<table><tr><th class=\"l\">run</th><th class=\"l\">input</th><th>data (s)</th><th>&#964;0 (s)</th><th class=\"l\">channels</th><th>unreadable rows</th><th class=\"l\">input read</th></tr>\n");
    for s in &res.summaries {
        let v = &s.rec.record;
        let c = &s.rec.completion;
        let chans = v.channels.join(", ");
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td><td class=\"l\">{}</td><td>{}</td><td class=\"l{}\">{}{}</td></tr>",
            esc(&s.label),
            esc(&v.input),
            tick(v.t_data),
            tick(v.tau0),
            esc(&chans),
            v.bad_rows,
            if c.is_warning() { " warn" } else { "" },
            esc(&c.phrase()),
            v.time_column.as_ref().map(time_column_note).unwrap_or_default()
        );
    }
    h.push_str("</table>\n");
}

/// What a text input's time column found (summary `time_column`), under the run's "input read".
fn time_column_note(tc: &TimeColumnRecord) -> String {
    let name = esc(&tc.name);
    let text = if !tc.used {
        format!("time column `{name}` not used: its step is not &tau;0")
    } else {
        format!(
            "time column `{name}`: {} jumps = {} missing samples (gaps), {} steps backwards, {} off-step",
            tc.gaps,
            tc.missing_samples,
            tc.backwards,
            tc.irregular + tc.discontinuities
        )
    };
    format!(
        "<br><span class=\"small\">{}</span>",
        text.replace('`', "&quot;")
    )
}

fn limits_table(h: &mut String, res: &Results) {
    if res.limits.is_empty() {
        return;
    }
    let several = res.summaries.len() > 1;
    h.push_str("<h2>Datasheet limits</h2>\n<table><tr>");
    if several {
        h.push_str("<th class=\"l\">run</th>");
    }
    h.push_str("<th class=\"l\">channel</th><th>coefficient</th><th class=\"l\">over</th><th class=\"l\">bound</th><th>limit</th><th class=\"l\">unit</th><th>value</th><th>95% interval</th><th class=\"l\">verdict</th></tr>\n");
    for l in &res.limits {
        let v = &l.rec;
        let verdict = v.verdict.name();
        let class = match verdict {
            "pass" => "pass",
            "fail" => "fail",
            _ => "und",
        };
        h.push_str("<tr>");
        if several {
            let _ = write!(h, "<td class=\"l\">{}</td>", esc(&l.label));
        }
        let note = v
            .note
            .as_deref()
            .map(|n| format!("<br><span class=\"small\">{}</span>", esc(n)))
            .unwrap_or_default();
        let _ = writeln!(
            h,
            "<td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td><td>{}</td><td>[{}, {}]</td><td class=\"l {class}\">{}{note}</td></tr>",
            esc(&v.channel),
            esc(v.coef.name()),
            esc(v.over.name()),
            esc(&v.bound),
            tick(v.limit),
            esc(&limit_unit(res, v)),
            opt(v.value),
            opt(v.lo),
            opt(v.hi),
            esc(&verdict.to_uppercase())
        );
    }
    h.push_str("</table>\n");
}

/// A limit's unit; `native` spelt out as the coefficient's unit for the channel's unit.
fn limit_unit(res: &Results, l: &LimitResult) -> String {
    if l.unit != "native" {
        return l.unit.clone();
    }
    match res.fits.iter().find(|f| f.rec.channel == l.channel) {
        Some(f) => coef_units(&f.rec.unit)[l.coef.index()].clone(),
        None => "native".into(),
    }
}

fn figures(h: &mut String, res: &Results) {
    let finals: Vec<&Labelled<_>> = res
        .curves
        .iter()
        .filter(|c| c.rec.r#final && c.rec.stat.name() == "avar")
        .collect();
    if finals.is_empty() {
        return;
    }
    let several = res.several_runs();
    let series: Vec<Series> = finals
        .iter()
        .map(|c| Series {
            curve: &c.rec,
            run_label: if several {
                c.label.clone()
            } else {
                String::new()
            },
            fit: res.fit_of(c),
            diagnosis: res.diagnosis_of(c),
        })
        .collect();
    h.push_str("<h2>Allan deviation</h2>\n");
    if !several {
        h.push_str(&render_svg(
            series,
            "Final Allan deviation curves, fitted model and diagnosis",
        ));
        return;
    }
    // Several runs: one figure per channel, its runs overlaid and named by file (the seed
    // paper's figure 2), so each run's model and asymptotes stay readable.
    let mut channels: Vec<String> = Vec::new();
    for s in &series {
        if !channels.contains(&s.curve.channel) {
            channels.push(s.curve.channel.clone());
        }
    }
    let mut series = series;
    for ch in channels {
        let (mine, rest): (Vec<Series>, Vec<Series>) =
            series.into_iter().partition(|s| s.curve.channel == ch);
        series = rest;
        let unit = mine[0].curve.unit.clone();
        h.push_str(&render_svg(
            mine,
            &format!("{ch} [{unit}]: the runs overlaid"),
        ));
    }
}

/// The scale of a table-2 column: a power of ten that brings the largest value into [1, 10).
fn column_scale(values: &[f64]) -> i32 {
    let m = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if m > 0.0 && m.is_finite() {
        m.log10().floor() as i32
    } else {
        0
    }
}

fn scaled(v: Option<f64>, e: i32) -> String {
    match v {
        Some(x) => format!("<span data-value=\"{x:e}\">{:.3}</span>", x / 10f64.powi(e)),
        None => "&ndash;".into(),
    }
}

fn noise_model(h: &mut String, res: &Results) {
    let finals: Vec<&Labelled<FitRecord>> = res.fits.iter().filter(|f| f.rec.r#final).collect();
    if finals.is_empty() {
        return;
    }
    h.push_str("<h2>Noise model</h2>\n");
    let several = res.several_runs();
    if !several {
        single_run_fits(h, &finals);
        readouts_table(h, &finals, false);
        return;
    }
    // The aggregate records written with the runs; computed here as `aggregate` would when the
    // files came from separate analyses.
    let mut aggs: Vec<AggregateRecord> = res.aggregates.iter().map(|a| a.rec.clone()).collect();
    if aggs.is_empty() {
        let mut runs: Vec<(RunKey, Vec<RunCoefs>)> = Vec::new();
        for f in &finals {
            let rc = f.rec.run_coefs();
            match runs.iter_mut().find(|(k, _)| *k == (f.file, f.run)) {
                Some((_, v)) => v.push(rc),
                None => runs.push(((f.file, f.run), vec![rc])),
            }
        }
        let runs: Vec<Vec<RunCoefs>> = runs.into_iter().map(|(_, v)| v).collect();
        aggs = aggregate_channels(&runs)
            .iter()
            .map(AggregateRecord::new)
            .collect();
    }
    h.push_str("<p>The seed paper's table 2 layout: one table per channel, one row per run (named by its file), the coefficients as columns scaled by the power of ten in the heading; &ndash; = not determined. The mean, the 95% interval of the mean (mean &plusmn; 1.96 sd/&radic;n, as the paper; the Student interval below it) and the sd are over the runs that determined the coefficient.</p>\n");
    let mut channels: Vec<(String, String)> = Vec::new();
    for f in &finals {
        let k = (f.rec.channel.clone(), f.rec.unit.clone());
        if !channels.contains(&k) {
            channels.push(k);
        }
    }
    for (ch, unit) in channels {
        let rows: Vec<&&Labelled<FitRecord>> =
            finals.iter().filter(|f| f.rec.channel == ch).collect();
        let agg_of = |k: &str| aggs.iter().find(|a| a.channel == ch && a.coef == k);
        let units = coef_units(&unit);
        let value = |f: &FitRecord, i: usize| -> Option<f64> {
            let c = f.coef.by_index(i);
            c.value.filter(|_| c.determined)
        };
        let scales: Vec<i32> = PAPER_ORDER
            .iter()
            .map(|&i| {
                let mut v: Vec<f64> = rows.iter().filter_map(|f| value(&f.rec, i)).collect();
                if let Some(m) =
                    agg_of(TERM_NAMES[i]).and_then(|a| a.mean.filter(|m| m.is_finite()))
                {
                    v.push(m);
                }
                column_scale(&v)
            })
            .collect();
        let _ = write!(
            h,
            "<table class=\"table2\" data-channel=\"{}\"><caption>{} [{}]</caption><tr><th class=\"l\">run</th>",
            esc(&ch),
            esc(&ch),
            esc(&unit)
        );
        for (c, &i) in PAPER_ORDER.iter().enumerate() {
            let e = scales[c];
            let sc = if e == 0 {
                String::new()
            } else {
                format!("&#215;10<sup>{e}</sup> ")
            };
            let _ = write!(
                h,
                "<th data-coef=\"{}\">{}<br><span class=\"small\">{sc}{}</span></th>",
                TERM_NAMES[i],
                TERM_NAMES[i],
                esc(&units[i])
            );
        }
        h.push_str("</tr>\n");
        for f in &rows {
            let _ = write!(h, "<tr><td class=\"l\">{}</td>", esc(&f.label));
            for (c, &i) in PAPER_ORDER.iter().enumerate() {
                let _ = write!(h, "<td>{}</td>", scaled(value(&f.rec, i), scales[c]));
            }
            h.push_str("</tr>\n");
        }
        let stat_row = |h: &mut String,
                        name: &str,
                        key: &str,
                        cell: &dyn Fn(&AggregateRecord, i32) -> String| {
            let _ = write!(
                h,
                "<tr class=\"stat\" data-row=\"{key}\"><td class=\"l\">{name}</td>"
            );
            for (c, &i) in PAPER_ORDER.iter().enumerate() {
                let txt = agg_of(TERM_NAMES[i]).map_or("&ndash;".into(), |a| cell(a, scales[c]));
                let _ = write!(h, "<td>{txt}</td>");
            }
            h.push_str("</tr>\n");
        };
        // As JSON shows it: a bound that is not finite is `null`, shown as a dash.
        let fin = |v: f64| v.is_finite().then_some(v);
        let pair = |v: Option<[f64; 2]>, e: i32| match v {
            Some([lo, hi]) => format!("[{}; {}]", scaled(fin(lo), e), scaled(fin(hi), e)),
            None => "&ndash;".into(),
        };
        stat_row(h, "mean", "mean", &|a, e| scaled(a.mean.and_then(fin), e));
        stat_row(h, "95% interval of the mean", "ci_z", &|a, e| {
            pair(a.ci_z, e)
        });
        stat_row(h, "Student 95% interval", "ci_t", &|a, e| pair(a.ci_t, e));
        stat_row(h, "sd (1 sigma)", "sd", &|a, e| {
            scaled(a.sd.and_then(fin), e)
        });
        stat_row(h, "runs determined (n)", "n", &|a, _| a.n.to_string());
        // The mean and its interval again in datasheet units, as a lead quotes them.
        if let Some(iu) = crate::model::units::IncrementUnit::parse(&unit) {
            let f = crate::model::units::datasheet_factors(&iu);
            let du = crate::model::units::datasheet_units(iu.kind);
            let _ = write!(
                h,
                "<tr class=\"stat\" data-row=\"datasheet\"><td class=\"l\">mean [95%] in datasheet units</td>"
            );
            for &i in &PAPER_ORDER {
                let cell = agg_of(TERM_NAMES[i])
                    .and_then(|a| {
                        let m = a.mean.filter(|m| m.is_finite())? * f[i];
                        let ci = a
                            .ci_z
                            .filter(|p| p.iter().all(|x| x.is_finite()))
                            .map(|[lo, hi]| format!(" [{}, {}]", tick(lo * f[i]), tick(hi * f[i])));
                        Some(format!(
                            "<span data-value=\"{m:e}\">{}</span>{}<br><span class=\"small\">{}</span>",
                            tick(m),
                            ci.unwrap_or_default(),
                            esc(du[i])
                        ))
                    })
                    .unwrap_or_else(|| "&ndash;".into());
                let _ = write!(h, "<td>{cell}</td>");
            }
            h.push_str("</tr>\n");
        }
        h.push_str("</table>\n");
    }
    readouts_table(h, &finals, true);
}

/// The IEEE 952 read-outs of each final fit (model::readout): one row per channel (and run, runs
/// of a channel together), ARW, bias instability and RRW as columns, each cell the value with its
/// 95% interval, its unit (datasheet where the channel's unit is known) and the curve point the
/// read-out went through. The numbers are also in `data-` attributes for a program to read.
fn readouts_table(h: &mut String, finals: &[&Labelled<FitRecord>], several: bool) {
    if finals.iter().all(|f| f.rec.readouts.is_none()) {
        return;
    }
    h.push_str("<h3>IEEE 952 read-outs</h3>\n<p>Read from the Allan-deviation curve itself (IEEE Std 952-1997 annex C), to compare with the fit: the line of slope &minus;1/2 through the curve point where the curve runs closest to that slope, read at &tau; = 1 s (angle or velocity random walk); the curve's minimum / 0.664 (bias instability; the minimum's &tau; given); the line of slope +1/2 through its closest point, read at &tau; = 3 s (rate random walk). Under each value: its unit and the curve point used; the 95% interval is that point's, carried along the line.</p>\n<table class=\"readouts\"><tr><th class=\"l\">channel</th>");
    if several {
        h.push_str("<th class=\"l\">run</th>");
    }
    h.push_str("<th>random walk (ARW / VRW)<br><span class=\"small\">&minus;1/2 line at &tau; = 1 s</span></th><th>bias instability<br><span class=\"small\">minimum / 0.664</span></th><th>rate random walk (RRW)<br><span class=\"small\">+1/2 line at &tau; = 3 s</span></th></tr>\n");
    // Runs of one channel together, channels in the order first seen.
    let mut order: Vec<&str> = Vec::new();
    for f in finals {
        if !order.contains(&f.rec.channel.as_str()) {
            order.push(&f.rec.channel);
        }
    }
    for ch in order {
        for f in finals.iter().filter(|f| f.rec.channel == ch) {
            let Some(ro) = f.rec.readouts.as_deref() else {
                continue;
            };
            let _ = write!(
                h,
                "<tr data-channel=\"{c}\"><td class=\"l\"><b>{c}</b></td>",
                c = esc(&f.rec.channel)
            );
            if several {
                let _ = write!(h, "<td class=\"l\">{}</td>", esc(&f.label));
            }
            let cells: [(&str, Option<&ReadoutRecord>, &str, &str); 3] = [
                (
                    "arw",
                    ro.arw.as_ref(),
                    "no &minus;1/2 slope on the curve",
                    "point",
                ),
                (
                    "bias_instability",
                    ro.bias_instability.as_ref(),
                    "no minimum inside the curve",
                    "minimum",
                ),
                (
                    "rrw",
                    ro.rrw.as_ref(),
                    "no +1/2 slope on the curve",
                    "point",
                ),
            ];
            for (key, r, absent, point) in cells {
                match r {
                    Some(r) => {
                        let (v, lo, hi, unit) = match &r.datasheet {
                            Some(d) => (d.value.unwrap_or(f64::NAN), d.lo, d.hi, d.unit.clone()),
                            None => (r.value, r.lo, r.hi, r.unit.clone()),
                        };
                        let _ = write!(
                            h,
                            "<td data-readout=\"{key}\" data-value=\"{v:e}\" data-lo=\"{lo:e}\" data-hi=\"{hi:e}\" data-unit=\"{u}\" data-tau=\"{t:e}\">{} [{}, {}]<br><span class=\"small\">{u}; {point} at &tau; = {} s</span></td>",
                            tick(v),
                            tick(lo),
                            tick(hi),
                            tick(r.tau),
                            u = esc(&unit),
                            t = r.tau
                        );
                    }
                    None => {
                        let _ = write!(
                            h,
                            "<td data-readout=\"{key}\" class=\"l small\">{absent}</td>"
                        );
                    }
                }
            }
            h.push_str("</tr>\n");
        }
    }
    h.push_str("</table>\n");
}

fn single_run_fits(h: &mut String, fits: &[&Labelled<FitRecord>]) {
    h.push_str("<table class=\"fits\"><tr><th class=\"l\">channel</th><th class=\"l\">term</th><th>value</th><th>95% interval</th><th class=\"l\">unit</th><th>datasheet value</th><th>95% interval</th><th class=\"l\">datasheet unit</th></tr>\n");
    for f in fits {
        let units = coef_units(&f.rec.unit);
        for (i, k) in TERM_NAMES.iter().enumerate() {
            let c = f.rec.coef.by_index(i);
            let determined = c.determined && c.value.is_some();
            let ds = f.rec.datasheet.as_ref().map(|d| d.by_index(i));
            let (dv, dlo, dhi, du) = match ds {
                Some(d) => (opt(d.value), opt(d.lo), opt(d.hi), esc(&d.unit)),
                None => (
                    "&ndash;".into(),
                    "&ndash;".into(),
                    "&ndash;".into(),
                    String::new(),
                ),
            };
            let first = if i == 0 {
                format!(
                    "<td class=\"l\" rowspan=\"5\"><b>{}</b><br><span class=\"small\">gof {}</span></td>",
                    esc(&f.rec.channel),
                    f.rec.gof.map_or("&ndash;".into(), |g| format!("{g:.2}"))
                )
            } else {
                String::new()
            };
            let _ = writeln!(
                h,
                "<tr>{first}<td class=\"l\">{k}</td><td>{}</td><td>[{}, {}]</td><td class=\"l\">{}</td><td>{dv}</td><td>{}</td><td class=\"l\">{du}</td></tr>",
                if determined { opt(c.value) } else { "not determined".into() },
                opt(c.lo),
                opt(c.hi),
                esc(&units[i]),
                if dlo.starts_with('&') && dhi.starts_with('&') {
                    "&ndash;".to_string()
                } else {
                    format!("[{dlo}, {dhi}]")
                }
            );
        }
    }
    h.push_str("</table>\n");
}

/// An effect's name and parameters in words and units, rates in datasheet units beside the
/// record's u/s (sink::effect_text).
pub fn effect_words(effect: &RecordedEffect, unit: &str) -> String {
    crate::sink::effect_text::effect_line(effect, unit, &tick)
}

fn diagnosis(h: &mut String, res: &Results) {
    if res.diagnoses.is_empty() {
        return;
    }
    let several = res.several_runs();
    h.push_str("<h2>Sim-to-real gap (diagnosis)</h2>\n<p>The gap statistic is near 1 when the model explains the curve. Final diagnosis of each channel; effect parameters named, rates in datasheet units with the channel's own unit in brackets:</p>\n<table class=\"diagnosis\"><tr>");
    if several {
        h.push_str("<th class=\"l\">run</th>");
    }
    h.push_str("<th class=\"l\">channel</th><th class=\"l\">verdict</th><th>gap before</th><th>gap after</th><th class=\"l\">effects (in the order added; gap after each)</th><th class=\"l\">where the base model misses</th></tr>\n");
    // The final (or last) diagnosis per run and channel.
    let mut keys: Vec<(usize, Option<usize>, String)> = Vec::new();
    for d in &res.diagnoses {
        let k = (d.file, d.run, d.rec.channel.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    // The channel's unit: its curve's, else the one the record names (`diagnose` writes no curve).
    let unit_of = |d: &Labelled<DiagnosisRecord>| {
        res.curves
            .iter()
            .find(|c| c.file == d.file && c.rec.channel == d.rec.channel)
            .map(|c| c.rec.unit.clone())
            .or_else(|| d.rec.unit.clone())
            .unwrap_or_else(|| "u".to_string())
    };
    let mut interim: Vec<&Labelled<DiagnosisRecord>> = Vec::new();
    for (file, run, ch) in &keys {
        let mine: Vec<&Labelled<DiagnosisRecord>> = res
            .diagnoses
            .iter()
            .filter(|d| d.file == *file && d.run == *run && &d.rec.channel == ch)
            .collect();
        let Some(last) = mine
            .iter()
            .rev()
            .find(|d| d.rec.is_final)
            .or(mine.last())
            .copied()
        else {
            continue;
        };
        // Interim diagnoses, less one written at the same data time as the final (its copy).
        interim.extend(mine.iter().filter(|d| {
            let copy_of_final = last.rec.is_final && d.rec.t_data == last.rec.t_data;
            !std::ptr::eq(**d, last) && !copy_of_final
        }));
        let d = &last.rec;
        let unit = unit_of(last);
        let effects: Vec<String> = d
            .effects
            .iter()
            .map(|e| {
                format!(
                    "{} (gap {:.2})",
                    esc(&effect_words(&e.effect, &unit)),
                    e.gap_after
                )
            })
            .collect();
        // The four regions the model misses most; the count of the others.
        let mut worst: Vec<&crate::gap::record::RegionRecord> = d.regions.iter().collect();
        worst.sort_by(|a, b| {
            b.worst_ratio
                .ln()
                .abs()
                .total_cmp(&a.worst_ratio.ln().abs())
        });
        let more = worst.len().saturating_sub(4);
        worst.truncate(4);
        worst.sort_by(|a, b| a.tau_lo.total_cmp(&b.tau_lo));
        let mut regions: Vec<String> = worst
            .iter()
            .map(|r| {
                let taus = if r.tau_lo == r.tau_hi {
                    format!("&#964; = {} s", tick(r.tau_lo))
                } else {
                    format!("&#964; {}&ndash;{} s", tick(r.tau_lo), tick(r.tau_hi))
                };
                format!(
                    "{taus}: data {} the model (&#215;{} at worst)",
                    if r.sign > 0 { "above" } else { "below" },
                    ratio_text(r.worst_ratio)
                )
            })
            .collect();
        if more > 0 {
            regions.push(format!("and {more} more, closer to the model"));
        }
        let verdict = serde_json::to_value(d.verdict)
            .ok()
            .and_then(|v| v.as_str().map(String::from))
            .unwrap_or_default();
        let shape = d
            .residual_shape
            .as_ref()
            .map(|s| {
                format!(
                    "<br><span class=\"small\">what is left unexplained: {}</span>",
                    esc(s)
                )
            })
            .unwrap_or_default();
        let _ = writeln!(
            h,
            "<tr>{}<td class=\"l\">{}</td><td class=\"l\"><b>{}</b>{shape}</td><td>{:.2}</td><td>{:.2}</td><td class=\"l\">{}</td><td class=\"l\">{}</td></tr>",
            if several {
                format!("<td class=\"l\">{}</td>", esc(&last.label))
            } else {
                String::new()
            },
            esc(ch),
            esc(&verdict),
            d.gap_before,
            d.gap_after,
            if effects.is_empty() { "none".into() } else { effects.join("<br>") },
            if regions.is_empty() { "nowhere".into() } else { regions.join("<br>") }
        );
    }
    h.push_str("</table>\n");
    interim_table(h, &interim, several);
}

/// The interim diagnoses as a small time table: one row per data time (per run), one column
/// per channel, each cell the verdict, the gap before and after and the effects' names. At
/// most [`INTERIM_ROWS`] rows per run: a long run shows every k-th time, and says so.
fn interim_table(h: &mut String, interim: &[&Labelled<DiagnosisRecord>], several: bool) {
    if interim.is_empty() {
        return;
    }
    let mut channels: Vec<&str> = Vec::new();
    let mut runs: Vec<(usize, Option<usize>)> = Vec::new();
    for d in interim {
        if !channels.contains(&d.rec.channel.as_str()) {
            channels.push(&d.rec.channel);
        }
        if !runs.contains(&(d.file, d.run)) {
            runs.push((d.file, d.run));
        }
    }
    h.push_str("<h3>Interim diagnoses</h3>\n<p class=\"small\">Each cell: the verdict, the gap before &rarr; after the effects, and the effects added.</p>\n<table class=\"interim small\"><tr>");
    if several {
        h.push_str("<th class=\"l\">run</th>");
    }
    h.push_str("<th>data (s)</th>");
    for c in &channels {
        let _ = write!(h, "<th class=\"l\">{}</th>", esc(c));
    }
    h.push_str("</tr>\n");
    let mut thinned = 0usize;
    for key in runs {
        let mine: Vec<&&Labelled<DiagnosisRecord>> =
            interim.iter().filter(|d| (d.file, d.run) == key).collect();
        let mut times: Vec<f64> = mine.iter().map(|d| d.rec.t_data).collect();
        times.sort_by(f64::total_cmp);
        times.dedup();
        let step = times.len().div_ceil(INTERIM_ROWS).max(1);
        if step > 1 {
            thinned = thinned.max(step);
        }
        let label = mine.first().map(|d| d.label.clone()).unwrap_or_default();
        for (n, t) in times.iter().enumerate() {
            // Every step-th time, and always the last.
            if n % step != 0 && n + 1 != times.len() {
                continue;
            }
            h.push_str("<tr>");
            if several {
                let _ = write!(h, "<td class=\"l\">{}</td>", esc(&label));
            }
            let _ = write!(h, "<td>{}</td>", tick(*t));
            for c in &channels {
                match mine
                    .iter()
                    .find(|d| d.rec.t_data == *t && d.rec.channel == *c)
                {
                    Some(d) => {
                        let verdict = serde_json::to_value(d.rec.verdict)
                            .ok()
                            .and_then(|v| v.as_str().map(String::from))
                            .unwrap_or_default();
                        let kinds: Vec<&str> = d
                            .rec
                            .effects
                            .iter()
                            .map(|e| effect_name(e.effect.kind_name()))
                            .collect();
                        let _ = write!(
                            h,
                            "<td class=\"l\">{} {:.2}&rarr;{:.2}{}</td>",
                            esc(&verdict),
                            d.rec.gap_before,
                            d.rec.gap_after,
                            if kinds.is_empty() {
                                String::new()
                            } else {
                                format!("<br>{}", esc(&kinds.join(", ")))
                            }
                        );
                    }
                    None => h.push_str("<td>&ndash;</td>"),
                }
            }
            h.push_str("</tr>\n");
        }
    }
    h.push_str("</table>\n");
    if thinned > 1 {
        let _ = writeln!(
            h,
            "<p class=\"small\">Every {thinned}th interim time shown (and the last); the JSON lines hold them all.</p>"
        );
    }
}

/// Rows of the interim-diagnosis table per run.
const INTERIM_ROWS: usize = 24;

fn dynamic_view(h: &mut String, res: &Results) {
    let finals: Vec<_> = res
        .curves
        .iter()
        .filter(|c| c.rec.r#final && c.rec.stat.name() == "avar")
        .collect();
    let mut first = true;
    for c in finals {
        let all = res.history_of(c);
        if all.len() < 3 {
            continue;
        }
        if first {
            h.push_str("<h2>Where in the run (dynamic Allan view)</h2>\n<p>Each column is the stretch of the run between two interim records; its colour is that stretch's Allan deviation divided by the whole run's, at each &#964;. Red: noisier than the run as a whole; blue: quieter.</p>\n");
            first = false;
        }
        let label = res.curve_caption(c);
        h.push_str(&render_dynamic_svg(&all, &label));
    }
}

fn health(h: &mut String, res: &Results) {
    if res.health.is_empty() {
        return;
    }
    h.push_str("<h2>Decoder health</h2>\n<table><tr><th class=\"l\">run</th><th>frames</th><th>checksum errors</th><th>resynchronisations</th><th>missing</th><th>duplicated</th><th>bytes skipped</th></tr>\n");
    // The last health record of each run.
    let mut last: Vec<&Labelled<HealthRecord>> = Vec::new();
    for hl in &res.health {
        match last
            .iter_mut()
            .find(|x| x.file == hl.file && x.run == hl.run)
        {
            Some(x) => *x = hl,
            None => last.push(hl),
        }
    }
    for hl in last {
        let v = &hl.rec;
        let bad = v.crc_errors > 0 || v.missing > 0 || v.duplicates > 0;
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td>{}</td><td{c}>{}</td><td>{}</td><td{c}>{}</td><td{c}>{}</td><td>{}</td></tr>",
            esc(&hl.label),
            v.frames,
            v.crc_errors,
            v.resyncs,
            v.missing,
            v.duplicates,
            v.bytes_skipped,
            c = if bad { " class=\"warn\"" } else { "" }
        );
    }
    h.push_str("</table>\n");
}
