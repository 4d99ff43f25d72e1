//! The noise-model section: the seed paper's table 2 layout for several runs (runs as rows, the
//! five coefficients as columns scaled by a power of ten, then mean, 95% interval of the mean and
//! sd), the single run's fit table, and the IEEE 952 read-outs beside it.

use super::*;

/// The seed paper's column order in table 2.
pub(super) const PAPER_ORDER: [usize; 5] = [4, 3, 2, 1, 0];

/// The scale of a table-2 column: a power of ten that brings the largest value into [1, 10).
pub(super) fn column_scale(values: &[f64]) -> i32 {
    let m = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if m > 0.0 && m.is_finite() {
        m.log10().floor() as i32
    } else {
        0
    }
}

pub(super) fn scaled(v: Option<f64>, e: i32) -> String {
    match v {
        Some(x) => format!("<span data-value=\"{x:e}\">{:.3}</span>", x / 10f64.powi(e)),
        None => "&ndash;".into(),
    }
}

pub(super) fn noise_model(h: &mut String, res: &Results) {
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
        // Runs whose channel is in different units have no mean (`aggregate` refuses them);
        // each run's row is still shown.
        aggs = aggregate_channels(&runs)
            .unwrap_or_default()
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
            "<table class=\"table2\" data-channel=\"{}\"><caption>{}</caption><tr><th class=\"l\">run</th>",
            esc(&ch),
            esc(&crate::sink::channel_with_unit(&ch, &unit))
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
pub(super) fn readouts_table(h: &mut String, finals: &[&Labelled<FitRecord>], several: bool) {
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
                            "<td data-readout=\"{key}\" data-value=\"{v:e}\" data-lo=\"{lo:e}\" data-hi=\"{hi:e}\" data-unit=\"{u}\" data-tau=\"{t:e}\">{} [{}, {}]<br><span class=\"small\">{u}; {point} at &tau; = {} s{bound}</span></td>",
                            tick(v),
                            tick(lo),
                            tick(hi),
                            tick(r.tau),
                            u = esc(&unit),
                            t = r.tau,
                            bound = r
                                .upper_bound_reason()
                                .map(|why| format!("<br><b>an upper bound on B</b>: {why}"))
                                .unwrap_or_default()
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

pub(super) fn single_run_fits(h: &mut String, fits: &[&Labelled<FitRecord>]) {
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
