//! The HTML report parsed back: the banner's verdict for a failing and a passing limit, the
//! limits' unit column, the seed paper's table 2 layout with the aggregate records' values and
//! the runs named by file, "interrupted" when the summary says the input was not read to its
//! end, and the effects in words with their units.

use allanscope::model::aggregate::{aggregate_channels, RunCoefs};
use allanscope::sink::records::ReadoutsRecord;
use allanscope::sink::report::render_html;
use allanscope::sink::results::ResultFile;
use serde_json::{json, Value};

use crate::plot::{fit_of, model_curve};

fn summary(input: &str, run: Option<usize>, limits: Value, pass: Option<bool>) -> Value {
    let mut s = json!({"type": "summary", "input": input, "channels": ["g4"], "tau0": 0.004,
        "t_data": 3600.0, "samples": [900000], "segments": [1], "bad_rows": 0, "overlap": "16",
        "elapsed_s": 1.0, "limits": limits, "read_to_end": true});
    if let Some(r) = run {
        s["run"] = json!(r);
    }
    if let Some(p) = pass {
        s["pass"] = json!(p);
    }
    s
}

fn limit(verdict: &str, value: f64) -> Value {
    json!({"channel": "g4", "coef": "N", "over": "run", "bound": "max", "limit": 0.3,
           "unit": "native", "value": value, "lo": 0.95 * value, "hi": 1.05 * value, "verdict": verdict})
}

fn one_run(limits: Value, pass: Option<bool>) -> Vec<ResultFile> {
    let c = model_curve("g4", "arcsec", [0.0, 0.254, 0.225, 0.0, 0.0], 12);
    let f = fit_of("g4", "arcsec", [0.0, 0.254, 0.225, 0.0, 0.0]);
    vec![ResultFile {
        name: "vog4.jsonl".into(),
        records: vec![
            serde_json::to_value(&c).unwrap(),
            serde_json::to_value(&f).unwrap(),
            summary("vog4.csv", None, limits, pass),
        ],
    }]
}

/// The `data-verdict` of the banner.
fn banner(html: &str) -> &str {
    let i = html.find("class=\"banner").expect("a banner");
    let rest = &html[i..];
    let j = rest.find("data-verdict=\"").unwrap() + 14;
    rest[j..].split('"').next().unwrap()
}

#[test]
fn the_banner_says_fail_for_a_failing_limit_and_pass_for_a_passing_one() {
    let html = render_html(
        &one_run(json!([limit("fail", 0.35)]), Some(false)),
        "t",
        "now",
    );
    assert_eq!(banner(&html), "FAIL");
    // The failed limit named in the banner, with its unit spelt out (native -> arcsec/sqrt(s)).
    assert!(
        html.contains("failed: g4 N &le; 0.3 arcsec/sqrt(s) (measured 0.35 [0.3325, 0.3675])"),
        "{html}"
    );
    assert!(
        html.contains("<td class=\"l\">arcsec/sqrt(s)</td>"),
        "unit column"
    );
    let html = render_html(
        &one_run(json!([limit("pass", 0.254)]), Some(true)),
        "t",
        "now",
    );
    assert_eq!(banner(&html), "PASS");
    assert!(!html.contains("failed:"));
    let html = render_html(&one_run(json!([limit("undecided", 0.3)]), None), "t", "now");
    assert_eq!(banner(&html), "NOT DECIDED");
    // The undecided limit named, with the interval that straddles it.
    assert!(
        html.contains("not decided (the interval straddles the limit): g4 N &le; 0.3 arcsec/sqrt(s) (measured 0.3 [0.285, 0.315])"),
        "{html}"
    );
    let html = render_html(&one_run(json!([]), None), "t", "now");
    assert_eq!(banner(&html), "NO LIMITS JUDGED");
}

#[test]
fn an_interrupted_run_is_shown_as_interrupted() {
    let mut files = one_run(json!([]), None);
    let s = files[0].records.last_mut().unwrap();
    s["read_to_end"] = json!(false);
    s["stopped_by"] = json!("SIGINT");
    let html = render_html(&files, "t", "now");
    assert!(html.contains("INTERRUPTED (SIGINT): input not read to its end"));
    // In the banner, not only in the runs table.
    let b = &html[html.find("class=\"banner").unwrap()..];
    assert!(b[..b.find("</div>").unwrap()].contains("INTERRUPTED"));
    // A run read to its end says so and nothing is flagged.
    let html = render_html(&one_run(json!([]), None), "t", "now");
    assert!(!html.contains("INTERRUPTED") && !html.contains("INCOMPLETE"));
    assert!(html.contains("read to its end"));
}

/// The seed paper's VOG4 runs (SEED.md table 2): N, B, K per run; R only in run 1.
const RUNS: [[Option<f64>; 5]; 3] = [
    [
        None,
        Some(0.273),
        Some(0.248),
        Some(0.811e-2),
        Some(0.891e-4),
    ],
    [None, Some(0.210), Some(0.213), Some(2.978e-2), None],
    [None, Some(0.278), Some(0.213), Some(1.691e-2), None],
];

fn fit_record(run: usize, v: [Option<f64>; 5]) -> Value {
    let term = |x: Option<f64>| json!({"value": x, "lo": x.map(|x| 0.9 * x), "hi": x.map(|x| 1.1 * x), "determined": x.is_some()});
    json!({"type": "fit", "channel": "g4", "unit": "arcsec", "final": true, "t_data": 10800.0,
           "coef": {"Q": term(v[0]), "N": term(v[1]), "B": term(v[2]), "K": term(v[3]), "R": term(v[4])},
           "gof": 1.0, "method": "paper", "run": run})
}

/// The `data-value`s of one row of the table, in column order.
fn row_values(table: &str, row_start: &str) -> Vec<Option<f64>> {
    let i = table
        .find(row_start)
        .unwrap_or_else(|| panic!("row {row_start}"));
    let row = &table[i..i + table[i..].find("</tr>").unwrap()];
    row.split("<td>")
        .skip(1)
        .map(|cell| {
            cell.find("data-value=\"").map(|j| {
                cell[j + 12..]
                    .split('"')
                    .next()
                    .unwrap()
                    .parse::<f64>()
                    .unwrap()
            })
        })
        .collect()
}

#[test]
fn several_runs_give_table_2_with_the_aggregate_records_values() {
    let runs: Vec<Vec<RunCoefs>> = RUNS
        .iter()
        .map(|v| {
            vec![RunCoefs {
                channel: "g4".into(),
                unit: "arcsec".into(),
                values: *v,
            }]
        })
        .collect();
    let mut records: Vec<Value> = Vec::new();
    for (r, v) in RUNS.iter().enumerate() {
        records.push(fit_record(r, *v));
        records.push(summary(
            &format!("/data/vog4_run{}.siu8", r + 1),
            Some(r),
            json!([]),
            None,
        ));
    }
    for a in aggregate_channels(&runs).unwrap() {
        let s = a.stats.as_ref();
        records.push(
            json!({"type": "aggregate", "channel": a.channel, "unit": a.unit, "coef": a.coef,
            "n": s.map_or(0, |s| s.n), "mean": s.map(|s| s.mean), "sd": s.and_then(|s| s.sd),
            "ci_t": s.and_then(|s| s.ci_t), "ci_z": s.and_then(|s| s.ci_z)}),
        );
    }
    let aggs: Vec<Value> = records
        .iter()
        .filter(|r| r["type"] == "aggregate")
        .cloned()
        .collect();
    let html = render_html(
        &[ResultFile {
            name: "three.jsonl".into(),
            records,
        }],
        "t",
        "now",
    );
    let t0 = html
        .find("<table class=\"table2\" data-channel=\"g4\"")
        .expect("table 2 for g4");
    let table = &html[t0..t0 + html[t0..].find("</table>").unwrap()];
    assert!(table.contains("<caption>g4 [arcsec]</caption>"), "caption");
    // Columns in the paper's order, R K B N Q.
    let heads: Vec<&str> = table
        .match_indices("data-coef=\"")
        .map(|(i, _)| &table[i + 11..i + 12])
        .collect();
    assert_eq!(heads, ["R", "K", "B", "N", "Q"]);
    let order = [4usize, 3, 2, 1, 0];
    // Runs named by their input files, each row the fit's values ("-" where not determined).
    for (r, v) in RUNS.iter().enumerate() {
        let got = row_values(
            table,
            &format!("<tr><td class=\"l\">vog4_run{}.siu8</td>", r + 1),
        );
        let want: Vec<Option<f64>> = order.iter().map(|&i| v[i]).collect();
        assert_eq!(got, want, "run {}", r + 1);
    }
    // Mean and sd rows carry the aggregate records' numbers exactly.
    let agg = |k: &str, f: &str| {
        aggs.iter()
            .find(|a| a["coef"] == k)
            .and_then(|a| a[f].as_f64())
    };
    let mean = row_values(table, "data-row=\"mean\"");
    let sd = row_values(table, "data-row=\"sd\"");
    for (c, &i) in order.iter().enumerate() {
        let k = ["Q", "N", "B", "K", "R"][i];
        assert_eq!(mean[c], agg(k, "mean"), "mean of {k}");
        assert_eq!(sd[c], agg(k, "sd"), "sd of {k}");
    }
    // SEED.md: VOG4 N mean 0.254, sd 0.038; B mean 0.225 (printed 3 decimals at the column's
    // scale: N and B in units of 1e-1 arcsec).
    assert!((mean[3].unwrap() - 0.2537).abs() < 5e-4 && (sd[3].unwrap() - 0.038).abs() < 5e-4);
    assert!(
        table.contains(">2.537</span>"),
        "N mean printed at 1e-1 scale"
    );
    // The interval of the mean: [lo; hi] from ci_z.
    let ci = agg_pair(&aggs, "N", "ci_z");
    let i = table.find("data-row=\"ci_z\"").unwrap();
    let row = &table[i..i + table[i..].find("</tr>").unwrap()];
    assert!(
        row.contains(&format!("data-value=\"{:e}\"", ci[0])),
        "{row}"
    );
    assert!(row.contains(&format!("data-value=\"{:e}\"", ci[1])));
    // The means again in datasheet units (arcsec: N/60 is deg/sqrt(h), B in arcsec/s is deg/h).
    let ds = row_values(table, "data-row=\"datasheet\"");
    let near = |a: Option<f64>, b: Option<f64>| (a.unwrap() / b.unwrap() - 1.0).abs() < 1e-12;
    assert!(
        near(ds[3], agg("N", "mean").map(|m| m / 60.0)),
        "N in deg/sqrt(h): {ds:?}"
    );
    assert!(near(ds[2], agg("B", "mean")), "B in deg/h: {ds:?}");
    let i = table.find("data-row=\"datasheet\"").unwrap();
    let row = &table[i..i + table[i..].find("</tr>").unwrap()];
    assert!(
        row.contains("deg/sqrt(h)") && row.contains("deg/h"),
        "{row}"
    );
}

fn agg_pair(aggs: &[Value], k: &str, f: &str) -> [f64; 2] {
    let a = aggs.iter().find(|a| a["coef"] == k).unwrap();
    [a[f][0].as_f64().unwrap(), a[f][1].as_f64().unwrap()]
}

#[test]
fn effects_are_named_with_units_and_only_the_final_diagnosis_is_in_the_main_table() {
    let mut files = one_run(json!([]), None);
    let d = |t: f64, fin: bool, f: f64| {
        json!({"type": "diagnosis", "channel": "g4", "gap_before": 5.0, "gap_after": 0.9,
            "verdict": "explained", "regions": [], "final": fin, "t_data": t,
            "effects": [{"kind": "sinusoid", "params": {"amplitude": 0.3, "frequency": f}, "gap_after": 0.9},
                        {"kind": "gauss_markov", "params": {"sigma": 0.5, "tau_c": 2.0}, "gap_after": 0.8}]})
    };
    files[0].records.push(d(1800.0, false, 0.7));
    // What the final diagnosis set aside: said under its verdict, rates in deg/h (x 1 from
    // arcsec/s).
    let mut fin = d(3600.0, true, 0.8);
    fin["outliers"] = json!({"count": 2, "rate": 0.001, "rms_size": 0.5, "max_size": 0.7});
    fin["stuck"] = json!({"stretches": 2, "seconds": 90.0, "longest_s": 60.0, "first_at_s": 600.0});
    files[0].records.push(fin);
    let html = render_html(&files, "t", "now");
    let main = &html[html.find("<table class=\"diagnosis\"").unwrap()..];
    let main = &main[..main.find("</table>").unwrap()];
    assert!(
        main.contains(
            "sinusoid: amplitude = 0.3 deg/h (0.3 arcsec/s), frequency = 0.8 Hz (period 1.25 s)"
        ),
        "{main}"
    );
    assert!(main.contains(
        "correlated (Gauss-Markov) noise: sigma = 0.5 deg/h (0.5 arcsec/s), correlation time = 2 s"
    ));
    assert!(
        main.contains(
            "set aside before the curve: 2 outliers replaced (rms 0.5 deg/h (0.5 arcsec/s), the \
             largest 0.7 deg/h (0.7 arcsec/s)); 2 stuck stretches taken out as gaps (90 s in all, \
             the longest 60 s, the first at 600 s)"
        ),
        "{main}"
    );
    assert!(
        !main.contains("0.7 Hz"),
        "the interim diagnosis is not in the main table"
    );
    assert!(!main.contains('{'), "no JSON");
    let interim = &html[html.find("<table class=\"interim").expect("interim table")..];
    assert!(interim[..interim.find("</table>").unwrap()].contains("<td>1800</td>"));
}

/// A warm-up found in the block means alone leaves the gap as it was: the report says where it
/// was seen and that the gap is unchanged; an effect that lowered the gap keeps its gap.
#[test]
fn an_effect_seen_in_time_alone_is_said_to_leave_the_gap() {
    let mut files = one_run(json!([]), None);
    files[0].records.push(json!({"type": "diagnosis", "channel": "g4", "gap_before": 2.5,
        "gap_after": 1.2, "verdict": "explained", "regions": [], "final": true, "t_data": 3600.0,
        "effects": [{"kind": "sinusoid", "params": {"amplitude": 0.3, "frequency": 0.8}, "gap_after": 1.2},
                    {"kind": "warmup", "params": {"amplitude": 0.5, "time_constant": 300.0}, "gap_after": 1.2}]}));
    let html = render_html(&files, "t", "now");
    let main = &html[html.find("<table class=\"diagnosis\"").unwrap()..];
    let main = &main[..main.find("</table>").unwrap()];
    assert!(main.contains("(period 1.25 s) (gap 1.20)"), "{main}");
    assert!(
        main.contains("(seen in the block means over time; gap 1.20 unchanged)"),
        "{main}"
    );
}

/// The read-out cell `key` of `channel`'s row in the read-outs table: its `data-` attributes
/// (value, lo, hi, unit, tau) by name, and its text under `text`.
fn readout_cell(html: &str, channel: &str, key: &str) -> std::collections::HashMap<String, String> {
    let t = &html[html
        .find("<table class=\"readouts\"")
        .expect("a read-outs table")..];
    let t = &t[..t.find("</table>").unwrap()];
    let tag = format!("<tr data-channel=\"{channel}\">");
    let row = t[t.find(&tag).unwrap_or_else(|| panic!("no {tag} in\n{t}"))..]
        .split("</tr>")
        .next()
        .unwrap();
    let at = format!("<td data-readout=\"{key}\"");
    let cell = &row[row.find(&at).unwrap_or_else(|| panic!("no {at} in {row}"))..];
    let (open, rest) = cell.split_once('>').unwrap();
    let mut out: std::collections::HashMap<String, String> = open
        .split(" data-")
        .skip(1)
        .filter_map(|kv| {
            let (k, v) = kv.split_once("=\"")?;
            Some((k.to_string(), v.trim_end_matches('"').to_string()))
        })
        .collect();
    out.insert(
        "text".into(),
        rest.split("</td>").next().unwrap().to_string(),
    );
    out
}

#[test]
fn the_ieee_952_readouts_are_shown_with_units_intervals_and_taus() {
    use allanscope::allan::CurvePoint;
    use allanscope::model::readout::readouts;
    // The exact curve of N = 0.254 arcsec/sqrt(s), B = 0.225 arcsec/s (the seed paper's VOG4)
    // from 4 ms to 8 s: white rate noise dominates at the shortest tau (N^2/tau = 16 against
    // 0.664^2 B^2 = 0.022), so the -1/2 line through it reads N at 1 s within 0.2%, i.e.
    // ARW = 0.254/60 = 0.004233 deg/sqrt(h); the curve still falls at 8 s, so there is no
    // minimum inside it (no bias-instability read-out) and no +1/2 slope.
    let c = model_curve("g4", "arcsec", [0.0, 0.254, 0.225, 0.0, 0.0], 12);
    let points: Vec<CurvePoint> = (0..c.tau.len())
        .map(|i| CurvePoint {
            m: c.m[i],
            tau_s: c.tau[i],
            var: c.sigma[i] * c.sigma[i],
            count: c.count[i],
            edf: 100.0,
            alpha: 0,
            sigma_lo: c.lo[i].unwrap(),
            sigma_hi: c.hi[i].unwrap(),
            stride: 1,
            n_phase: c.count[i] + 2 * c.m[i],
        })
        .collect();
    let mut f = fit_of("g4", "arcsec", [0.0, 0.254, 0.225, 0.0, 0.0]);
    f.readouts = Some(Box::new(ReadoutsRecord::new(
        &readouts(&points),
        "arcsec",
        None,
    )));
    let files = vec![ResultFile {
        name: "vog4.jsonl".into(),
        records: vec![
            serde_json::to_value(&c).unwrap(),
            serde_json::to_value(&f).unwrap(),
            summary("vog4.csv", None, json!([]), None),
        ],
    }];
    let html = render_html(&files, "t", "now");
    assert!(html.contains("<h3>IEEE 952 read-outs</h3>"), "{html}");
    let arw = readout_cell(&html, "g4", "arw");
    assert_eq!(arw["unit"], "deg/sqrt(h)", "{arw:?}");
    let num = |k: &str| arw[k].parse::<f64>().unwrap();
    let v = num("value");
    assert!((v / (0.254 / 60.0) - 1.0).abs() < 0.002, "{arw:?}");
    // The interval is the point's (0.9 and 1.1 of sigma in model_curve), carried to 1 s.
    assert!(
        (num("lo") / v - 0.9).abs() < 1e-3 && (num("hi") / v - 1.1).abs() < 1e-3,
        "{arw:?}"
    );
    assert_eq!(num("tau"), 0.004, "read at the shortest tau: {arw:?}");
    // What a person reads: the value, its interval, the unit and the point used.
    assert!(
        arw["text"].contains("deg/sqrt(h); point at &tau; = 0.004 s"),
        "{arw:?}"
    );
    let bi = readout_cell(&html, "g4", "bias_instability");
    assert!(bi["text"].contains("no minimum inside the curve"), "{bi:?}");
    let rrw = readout_cell(&html, "g4", "rrw");
    assert!(rrw["text"].contains("no +1/2 slope"), "{rrw:?}");
}

/// The runs table says what a time column found, and a file of `diagnose` records (no summary
/// by design) is not called a run cut short.
#[test]
fn the_runs_table_shows_the_time_column_and_diagnose_output_is_not_called_cut_short() {
    let mut files = one_run(json!([]), None);
    let s = files[0].records.last_mut().unwrap();
    s["time_column"] = json!({"name": "time", "used": true, "unit": "s", "gaps": 2,
        "missing_samples": 10, "backwards": 1, "irregular": 0, "discontinuities": 0});
    let html = render_html(&files, "t", "now");
    let runs = &html[html.find("<h2>Runs</h2>").unwrap()..];
    let runs = &runs[..runs.find("</table>").unwrap()];
    assert!(
        runs.contains("time column &quot;time&quot;: 2 jumps = 10 missing samples (gaps), 1 steps backwards, 0 off-step"),
        "{runs}"
    );
    let diag = vec![ResultFile {
        name: "g4_diagnosis.jsonl".into(),
        records: vec![
            json!({"type": "diagnosis", "channel": "g4", "unit": "arcsec",
            "gap_before": 1.1, "gap_after": 1.1, "verdict": "consistent", "regions": [],
            "effects": [], "final": true}),
        ],
    }];
    let html = render_html(&diag, "t", "now");
    assert!(!html.contains("cut short"), "{html}");
    assert!(html.contains("Diagnosis records only"), "{html}");
    assert!(html.contains("<table class=\"diagnosis\">"));
}

/// `diagnose --ensemble` output reported: the figure carries both bands, and the words say
/// how far the five terms alone miss and how far the twin matches, from the record's shares
/// (0.75 and 1/12 of 12 taus), with the rate a run of the model itself would show by chance
/// with 20 runs (2 (0.475 + 1) / 21 = 14%). The same record without `ensemble` gives neither.
#[test]
fn the_ensemble_band_is_drawn_and_said_in_words() {
    let page = |rec: Value| {
        render_html(
            &[ResultFile {
                name: "diag.jsonl".into(),
                records: vec![rec],
            }],
            "t",
            "now",
        )
    };
    let html = page(crate::plot::ensemble_diagnosis(true));
    assert!(html.contains("class=\"band-base\""));
    assert!(html.contains("class=\"band-twin\""));
    assert!(html.contains(
        "<b>g4</b>: the measured curve is outside the base band at 75% of taus (9 of 12); \
         outside the twin's at 8% (1 of 12). Bands of 20 simulated runs each (a run of the \
         model itself would be outside at about 14% by chance); the twin is the five terms \
         with Gauss-Markov."
    ));
    let bare = page(crate::plot::ensemble_diagnosis(false));
    assert!(!bare.contains("band-"));
    assert!(!bare.contains("ensemble band"));
    assert!(!bare.contains("<h2>Allan deviation</h2>"));
}
