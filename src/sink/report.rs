//! A test report as one self-contained HTML page: the Allan-deviation plot of each unit
//! (inline SVG), the noise-model coefficients with their 95% intervals in native and datasheet
//! units, run-to-run statistics, the decoder's health, the diagnosis of the sim-to-real gap and
//! the datasheet verdicts, all read from the JSON lines allanscope wrote.

use std::fmt::Write;

use serde_json::Value;

use crate::sink::plot::{render_svg, Series};
use crate::sink::records::{CurveRecord, FitRecord};

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn num(v: &Value) -> String {
    match v.as_f64() {
        Some(0.0) => "0".into(),
        Some(x) if (1e-3..1e4).contains(&x.abs()) => format!("{x:.4}"),
        Some(x) => format!("{x:.4e}"),
        None => "&ndash;".into(),
    }
}

/// One input file's records.
pub struct ReportInput {
    pub name: String,
    pub records: Vec<Value>,
}

fn of_type<'a>(records: &'a [Value], t: &str) -> impl Iterator<Item = &'a Value> + 'a {
    let t = t.to_string();
    records
        .iter()
        .filter(move |r| r.get("type").and_then(Value::as_str) == Some(t.as_str()))
}

/// Renders the report.
pub fn render_html(inputs: &[ReportInput], title: &str) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>\n\
         body{{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#222}}\n\
         table{{border-collapse:collapse;margin:0.5em 0 1.5em}}\n\
         td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\n\
         th{{background:#f2f2f2}} td.l,th.l{{text-align:left}}\n\
         .pass{{color:#0a0;font-weight:bold}} .fail{{color:#c00;font-weight:bold}} .und{{color:#b70}}\n\
         </style></head><body>\n<h1>{t}</h1>\n",
        t = esc(title)
    );
    for input in inputs {
        let recs = &input.records;
        let _ = writeln!(h, "<h2>{}</h2>", esc(&input.name));
        if let Some(s) = of_type(recs, "summary").last() {
            let _ =
                writeln!(
                h,
                "<p>{} s of data at tau0 = {} s; channels {}; overlap {}; {} unreadable rows.</p>",
                num(&s["t_data"]),
                num(&s["tau0"]),
                esc(&s["channels"].as_array().map(|a| {
                    a.iter().filter_map(Value::as_str).collect::<Vec<_>>().join(", ")
                }).unwrap_or_default()),
                esc(s["overlap"].as_str().unwrap_or("?")),
                s["bad_rows"].as_u64().unwrap_or(0)
            );
            if let Some(p) = s.get("pass").and_then(Value::as_bool) {
                let _ = writeln!(
                    h,
                    "<p>Datasheet limits: <span class=\"{}\">{}</span></p>",
                    if p { "pass" } else { "fail" },
                    if p { "PASS" } else { "FAIL" }
                );
            }
            if let Some(limits) = s.get("limits").and_then(Value::as_array) {
                if !limits.is_empty() {
                    h.push_str("<table><tr><th class=\"l\">channel</th><th>coef</th><th class=\"l\">limit</th><th>value</th><th>95% interval</th><th class=\"l\">verdict</th></tr>\n");
                    for l in limits {
                        let verdict = l["verdict"].as_str().unwrap_or("?");
                        let class = match verdict {
                            "pass" => "pass",
                            "fail" => "fail",
                            _ => "und",
                        };
                        let _ = writeln!(
                            h,
                            "<tr><td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td><td>{}</td><td>[{}, {}]</td><td class=\"l {class}\">{}</td></tr>",
                            esc(l["channel"].as_str().unwrap_or("")),
                            esc(l["coef"].as_str().unwrap_or("")),
                            esc(&l["limit"].to_string()),
                            num(&l["value"]),
                            num(&l["lo"]),
                            num(&l["hi"]),
                            esc(verdict)
                        );
                    }
                    h.push_str("</table>\n");
                }
            }
        }
        // Plots: one per unit, final AVAR curves with the fitted models.
        let curves: Vec<CurveRecord> = of_type(recs, "curve")
            .filter_map(|v| serde_json::from_value::<CurveRecord>(v.clone()).ok())
            .filter(|c| c.r#final && c.stat.name() == "avar")
            .collect();
        let fits: Vec<FitRecord> = of_type(recs, "fit")
            .filter_map(|v| serde_json::from_value::<FitRecord>(v.clone()).ok())
            .filter(|f| f.r#final)
            .collect();
        let mut units: Vec<&str> = curves.iter().map(|c| c.unit.as_str()).collect();
        units.dedup();
        units.sort_unstable();
        units.dedup();
        for unit in units {
            let series: Vec<Series> = curves
                .iter()
                .filter(|c| c.unit == unit)
                .map(|c| Series {
                    curve: c,
                    fit: fits
                        .iter()
                        .find(|f| f.channel == c.channel && f.run == c.run),
                })
                .collect();
            let svg = render_svg(&series, &format!("{} ({unit})", input.name));
            h.push_str(&svg);
        }
        if !fits.is_empty() {
            h.push_str("<h3>Noise model (95% intervals; &ndash; = not determined)</h3>\n<table><tr><th class=\"l\">channel</th>");
            for k in ["Q", "N", "B", "K", "R"] {
                let _ = write!(h, "<th>{k}</th>");
            }
            h.push_str("<th>gof</th></tr>\n");
            for f in &fits {
                let _ = write!(
                    h,
                    "<tr><td class=\"l\">{} [{}]</td>",
                    esc(&f.channel),
                    esc(&f.unit)
                );
                for k in ["Q", "N", "B", "K", "R"] {
                    let c = &f.coef[k];
                    let ds = f
                        .datasheet
                        .as_ref()
                        .and_then(|d| d.get(k))
                        .filter(|d| !d["value"].is_null())
                        .map(|d| {
                            format!(
                                "<br><small>{} {}</small>",
                                num(&d["value"]),
                                esc(d["unit"].as_str().unwrap_or(""))
                            )
                        })
                        .unwrap_or_default();
                    let _ = write!(
                        h,
                        "<td>{}<br><small>[{}, {}]</small>{ds}</td>",
                        num(&c["value"]),
                        num(&c["lo"]),
                        num(&c["hi"])
                    );
                }
                let _ = writeln!(
                    h,
                    "<td>{}</td></tr>",
                    f.gof.map(|g| format!("{g:.2}")).unwrap_or("&ndash;".into())
                );
            }
            h.push_str("</table>\n");
        }
        let agg: Vec<&Value> = of_type(recs, "aggregate").collect();
        if !agg.is_empty() {
            h.push_str("<h3>Run to run (the seed paper's table 2)</h3>\n<table><tr><th class=\"l\">channel</th><th>coef</th><th>n</th><th>mean</th><th>sd</th><th>Student 95%</th><th>mean &plusmn; 1.96 sd/&radic;n</th></tr>\n");
            for a in agg {
                let pair = |v: &Value| match v.as_array() {
                    Some(p) if p.len() == 2 => format!("[{}, {}]", num(&p[0]), num(&p[1])),
                    _ => "&ndash;".into(),
                };
                let _ = writeln!(
                    h,
                    "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                    esc(a["channel"].as_str().unwrap_or("")),
                    esc(a["coef"].as_str().unwrap_or("")),
                    a["n"].as_u64().unwrap_or(0),
                    num(&a["mean"]),
                    num(&a["sd"]),
                    pair(&a["ci_t"]),
                    pair(&a["ci_z"])
                );
            }
            h.push_str("</table>\n");
        }
        let diags: Vec<&Value> = of_type(recs, "diagnosis").collect();
        if !diags.is_empty() {
            h.push_str("<h3>Sim-to-real gap</h3>\n<table><tr><th class=\"l\">channel</th><th class=\"l\">verdict</th><th>gap before</th><th>gap after</th><th class=\"l\">effects</th><th class=\"l\">where the model misses</th></tr>\n");
            for d in diags {
                let effects: Vec<String> = d["effects"]
                    .as_array()
                    .map(|a| {
                        a.iter()
                            .map(|e| {
                                format!("{} {}", e["kind"].as_str().unwrap_or("?"), e["params"])
                            })
                            .collect()
                    })
                    .unwrap_or_default();
                let regions: Vec<String> = d["regions"]
                    .as_array()
                    .map(|a| {
                        a.iter()
                            .map(|r| {
                                format!(
                                    "{}..{} s {} (x{})",
                                    num(&r["tau_lo"]),
                                    num(&r["tau_hi"]),
                                    if r["sign"].as_f64().unwrap_or(0.0) > 0.0 {
                                        "above"
                                    } else {
                                        "below"
                                    },
                                    num(&r["worst_ratio"])
                                )
                            })
                            .collect()
                    })
                    .unwrap_or_default();
                let _ = writeln!(
                    h,
                    "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td></tr>",
                    esc(d["channel"].as_str().unwrap_or("")),
                    esc(d["verdict"].as_str().unwrap_or("")),
                    num(&d["gap_before"]),
                    num(&d["gap_after"]),
                    esc(&effects.join("; ")),
                    esc(&regions.join("; "))
                );
            }
            h.push_str("</table>\n");
        }
        if let Some(hl) = of_type(recs, "health").last() {
            let _ = writeln!(
                h,
                "<h3>Decoder health</h3>\n<p>{} frames, {} checksum errors, {} resynchronisations, {} missing, {} duplicated, {} bytes skipped.</p>",
                hl["frames"], hl["crc_errors"], hl["resyncs"], hl["missing"], hl["duplicates"], hl["bytes_skipped"]
            );
        }
    }
    h.push_str("<p><small>Written by allanscope from its JSON-lines records.</small></p>\n</body></html>\n");
    h
}
