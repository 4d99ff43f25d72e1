//! The `analyze` command end to end, through the built binary: records parsed back field by
//! field against docs/records.md, interim records with `--every`, several runs with `aggregate`
//! records, and exit statuses for bad input.

use crate::common::{exe, parse_lines_of, stdout_of};
use std::path::PathBuf;
use std::process::Output;

use allanscope::allan::batch::{oavar, phase_from_increments};
use allanscope::sink::records::Record;

fn tmp(name: &str) -> PathBuf {
    crate::common::tmp_in("cli", name)
}

fn records(out: &Output) -> Vec<Record> {
    crate::common::records_of(out)
}

/// White rate noise of 0.5 u/sqrt(s) as increments at tau0 = 0.01 s (seeded LCG + Box-Muller).
fn white_increments(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    let mut u = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let (a, b) = (u(), u());
            0.5 * 0.1 * (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
        })
        .collect()
}

fn write_csv(name: &str, cols: &[(&str, &[f64])]) -> PathBuf {
    let p = tmp(name);
    let mut s = String::from("# test data\n");
    s += &cols.iter().map(|c| c.0).collect::<Vec<_>>().join(",");
    s.push('\n');
    for i in 0..cols[0].1.len() {
        let row: Vec<String> = cols.iter().map(|c| format!("{:e}", c.1[i])).collect();
        s += &row.join(",");
        s.push('\n');
    }
    std::fs::write(&p, s).unwrap();
    p
}

#[test]
fn curve_fit_and_summary_records_follow_the_contract() {
    let d = white_increments(20_000, 1);
    let e = white_increments(20_000, 2);
    let csv = write_csv("a.csv", &[("gx", &d), ("gy", &e)]);
    let out = exe()
        .args([
            "analyze",
            csv.to_str().unwrap(),
            "--tau0",
            "0.01",
            "--unit",
            "arcsec",
        ])
        .args(["--overlap", "full", "--every", "50"])
        .output()
        .unwrap();
    let recs = records(&out);
    let curves: Vec<_> = recs
        .iter()
        .filter_map(|r| {
            if let Record::Curve(c) = r {
                Some(c)
            } else {
                None
            }
        })
        .collect();
    // 200 s of data, interim every 50 data-seconds: at 50, 100, 150 and 200 s, then final.
    let interim: Vec<f64> = curves
        .iter()
        .filter(|c| !c.r#final)
        .map(|c| c.t_data)
        .collect();
    assert_eq!(interim.len(), 4 * 2 * 3, "{interim:?}");
    assert!(interim
        .iter()
        .all(|t| [50.0, 100.0, 150.0, 200.0].contains(t)));
    let finals: Vec<_> = curves.iter().filter(|c| c.r#final).collect();
    assert_eq!(finals.len(), 6, "2 channels x avar, hvar, mvar");
    let gx = finals
        .iter()
        .find(|c| c.channel == "gx" && c.stat.name() == "avar")
        .unwrap();
    assert_eq!(gx.unit, "arcsec");
    assert_eq!(gx.t_data, 200.0);
    // The final AVAR equals the batch formula; sigma in u/s, tau in s, arrays parallel.
    let x = phase_from_increments(&d);
    for (i, &tau) in gx.tau.iter().enumerate() {
        let m = (tau / 0.01).round() as usize;
        assert_eq!(gx.m[i] as usize, m);
        let b = oavar(&[&x], m, 0.01).unwrap();
        assert_eq!(gx.count[i], b.count);
        assert!((gx.sigma[i] - b.var.sqrt()).abs() <= 1e-12 * gx.sigma[i]);
        let (lo, hi) = (gx.lo[i].unwrap(), gx.hi[i].unwrap());
        assert!(
            lo < gx.sigma[i] && gx.sigma[i] < hi,
            "interval brackets sigma"
        );
        assert!(gx.edf[i].unwrap() > 0.0);
    }
    // White rate noise: ADEV = N / sqrt(tau) with N = 0.5 u/sqrt(s), within the 95% interval
    // at all but (rarely) one tau.
    let outside = gx
        .tau
        .iter()
        .enumerate()
        .filter(|(i, &t)| {
            let truth = 0.5 / t.sqrt();
            truth < gx.lo[*i].unwrap() || truth > gx.hi[*i].unwrap()
        })
        .count();
    assert!(outside <= 1, "{outside} taus exclude the truth");
    // The fit finds N near 0.5 and says so.
    let fit = recs
        .iter()
        .find_map(|r| match r {
            Record::Fit(f) if f.channel == "gx" && f.r#final => Some(f),
            _ => None,
        })
        .unwrap();
    let n = &fit.coef.N;
    assert!(n.determined);
    let v = n.value.unwrap();
    assert!((v - 0.5).abs() < 0.03, "N = {v}");
    assert!(n.lo.unwrap() <= v && v <= n.hi.unwrap());
    let Some(Record::Summary(s)) = recs.last() else {
        panic!("summary last")
    };
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(s.samples, [20_001, 20_001]);
    assert_eq!(s.t_data, 200.0);
}

#[test]
fn rate_and_phase_columns_give_the_increments_curve() {
    let d = white_increments(5_000, 3);
    let rate: Vec<f64> = d.iter().map(|v| v / 0.01).collect();
    let phase: Vec<f64> = phase_from_increments(&d);
    let sig = |args: &[&str]| -> Vec<f64> {
        let recs = records(
            &exe()
                .args(args)
                .args(["--tau0", "0.01", "--fit", "none"])
                .output()
                .unwrap(),
        );
        recs.into_iter()
            .find_map(|r| match r {
                Record::Curve(c) if c.stat.name() == "avar" => Some(c.sigma),
                _ => None,
            })
            .unwrap()
    };
    let a = sig(&[
        "analyze",
        write_csv("i.csv", &[("c", &d)]).to_str().unwrap(),
    ]);
    let b = sig(&[
        "analyze",
        write_csv("r.csv", &[("c", &rate)]).to_str().unwrap(),
        "--rate",
    ]);
    let c = sig(&[
        "analyze",
        write_csv("p.csv", &[("c", &phase)]).to_str().unwrap(),
        "--phase",
    ]);
    for i in 0..a.len() {
        assert!((a[i] - b[i]).abs() < 1e-9 * a[i] && (a[i] - c[i]).abs() < 1e-9 * a[i]);
    }
}

#[test]
fn several_runs_give_aggregate_records() {
    let runs: Vec<PathBuf> = (0..3)
        .map(|k| {
            write_csv(
                &format!("run{k}.csv"),
                &[("g", &white_increments(30_000, 10 + k))],
            )
        })
        .collect();
    let mut cmd = exe();
    cmd.arg("analyze");
    for r in &runs {
        cmd.arg(r);
    }
    let recs = records(&cmd.args(["--tau0", "0.01"]).output().unwrap());
    let agg: Vec<_> = recs
        .iter()
        .filter_map(|r| {
            if let Record::Aggregate(a) = r {
                Some(a)
            } else {
                None
            }
        })
        .collect();
    assert_eq!(agg.len(), 5, "one per coefficient");
    let n = agg.iter().find(|a| a.coef == "N").unwrap();
    assert_eq!(n.n, 3);
    let (mean, sd) = (n.mean.unwrap(), n.sd.unwrap());
    assert!((mean - 0.5).abs() < 0.03, "{mean}");
    // Student (4.303) and the paper's 1.96: both centred on the mean, the Student one wider.
    let (t, z) = (n.ci_t.unwrap(), n.ci_z.unwrap());
    assert!((t[1] - mean - 4.303 * sd / 3f64.sqrt()).abs() < 1e-3 * sd);
    assert!((z[1] - mean - 1.96 * sd / 3f64.sqrt()).abs() < 1e-9 * sd.max(1e-300));
}

#[test]
fn bad_input_exits_2_with_a_message_and_bad_rows_are_counted() {
    let csv = write_csv("b.csv", &[("c", &white_increments(100, 4))]);
    let out = exe()
        .args(["analyze", csv.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "missing --tau0");
    assert!(String::from_utf8_lossy(&out.stderr).contains("--tau0"));
    let out = exe()
        .args(["analyze", "/nonexistent/x.csv", "--tau0", "1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/x.csv"));
    let out = exe()
        .args([
            "analyze",
            csv.to_str().unwrap(),
            "--tau0",
            "1",
            "--overlap",
            "x",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    // A damaged row becomes a gap and is counted; the rest is analyzed.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    lines.insert(50, "1.2.3");
    std::fs::write(&csv, lines.join("\n")).unwrap();
    let recs = records(
        &exe()
            .args(["analyze", csv.to_str().unwrap(), "--tau0", "1"])
            .output()
            .unwrap(),
    );
    let Some(Record::Summary(s)) = recs.last() else {
        panic!()
    };
    assert_eq!(s.bad_rows, 1);
    assert_eq!(s.segments, [2]);
}

#[test]
fn plot_draws_each_channel_with_its_intervals_and_model() {
    let csv = write_csv(
        "plot.csv",
        &[
            ("gx", &white_increments(20_000, 5)),
            ("gy", &white_increments(20_000, 6)),
        ],
    );
    let jsonl = tmp("plot.jsonl");
    stdout_of(
        exe()
            .args(["analyze", csv.to_str().unwrap(), "--tau0", "0.01"])
            .args(["--unit", "arcsec", "--out"])
            .arg(&jsonl),
    );
    let svg = tmp("plot.svg");
    stdout_of(exe().args(["plot", jsonl.to_str().unwrap(), "-o", svg.to_str().unwrap()]));
    let text = std::fs::read_to_string(&svg).unwrap();
    let recs: Vec<Record> = std::fs::read_to_string(&jsonl)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let points: usize = recs
        .iter()
        .filter_map(|r| match r {
            Record::Curve(c) if c.r#final && c.stat.name() == "avar" => Some(c.tau.len()),
            _ => None,
        })
        .sum();
    // One interval bar per point, two data lines and two model lines (one panel: one unit).
    assert_eq!(text.matches("class=\"interval\"").count(), points);
    assert_eq!(text.matches("class=\"curve\"").count(), 2);
    assert_eq!(text.matches("class=\"model\"").count(), 2);
    assert_eq!(text.matches("class=\"panel\"").count(), 1);
    assert!(text.contains("Allan deviation &#963;(&#964;) (arcsec/s)"));
    assert!(text.contains(">gx<") && text.contains(">gy<"));
    // Nothing to plot is a usage error.
    let out = exe()
        .args([
            "plot",
            jsonl.to_str().unwrap(),
            "-o",
            tmp("nothing.svg").to_str().unwrap(),
            "--channels",
            "zz",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("no final `avar` curve records"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!tmp("nothing.svg").exists(), "nothing written");
}

#[test]
fn report_is_one_page_with_plots_tables_and_health() {
    let jsonl = tmp("report.jsonl");
    let capture = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/captures/siu8_stand_5min_seed1.siu8"
    );
    stdout_of(
        exe()
            .args(["analyze", capture, "--format", "siu8", "--out"])
            .arg(&jsonl),
    );
    let html = tmp("report.html");
    stdout_of(exe().args([
        "report",
        jsonl.to_str().unwrap(),
        "-o",
        html.to_str().unwrap(),
    ]));
    let text = std::fs::read_to_string(&html).unwrap();
    // Two units (arcsec gyros, m/s accelerometers): one figure of two panels; eight channels
    // of five terms in the fit table; health.
    assert_eq!(text.matches("<svg").count(), 1);
    assert_eq!(text.matches("class=\"panel\"").count(), 2);
    assert_eq!(text.matches("rowspan=\"5\"").count(), 8);
    assert!(text.contains("<h2>Decoder health</h2>"));
    assert!(text.contains("<td>75000</td><td>0</td>"));
    assert!(!text.contains("src=\"http"), "self-contained");
}

#[test]
fn every_upper_bound_respects_what_the_curve_allows() {
    // The 5-minute fixture leaves most terms undetermined. Each coefficient's upper bound must
    // stay below the slope bound of the curve's own 97.5% limits (c_i basis_i(tau) <= hi(tau)^2
    // at every tau), apart from rounding: no chi-squared interval with nu << 1 running off.
    let capture = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fixtures/captures/siu8_stand_5min_seed1.siu8"
    );
    let recs = records(
        &exe()
            .args(["analyze", capture, "--format", "siu8"])
            .output()
            .unwrap(),
    );
    let mut checked = 0;
    for r in &recs {
        let Record::Fit(f) = r else { continue };
        let curve = recs
            .iter()
            .find_map(|c| match c {
                Record::Curve(c) if c.channel == f.channel && c.stat.name() == "avar" => Some(c),
                _ => None,
            })
            .unwrap();
        for (i, name) in ["Q", "N", "B", "K", "R"].iter().enumerate() {
            let c = f.coef.by_index(i);
            if c.determined {
                continue;
            }
            let hi = c.hi.unwrap();
            let bound = curve
                .tau
                .iter()
                .zip(&curve.hi)
                .filter_map(|(t, h)| {
                    Some(h.as_ref()?.powi(2) / allanscope::model::terms::basis(*t)[i])
                })
                .fold(f64::INFINITY, f64::min);
            assert!(
                hi * hi <= bound * (1.0 + 1e-6),
                "{} {name}: hi {hi:e}, bound {:e}",
                f.channel,
                bound.sqrt()
            );
            checked += 1;
        }
    }
    assert!(checked >= 16, "{checked}");
}

#[test]
fn diagnoses_of_several_runs_carry_their_run_index() {
    let a = write_csv("diag-run0.csv", &[("g", &white_increments(20_000, 21))]);
    let b = write_csv("diag-run1.csv", &[("g", &white_increments(20_000, 22))]);
    let args = |inputs: &[&PathBuf]| {
        let mut v: Vec<String> = inputs.iter().map(|p| p.display().to_string()).collect();
        v.extend(["--tau0", "0.01", "--diagnose"].map(String::from));
        parse_lines_of(exe().arg("analyze").args(&v))
    };
    let recs = args(&[&a, &b]);
    let diag: Vec<&serde_json::Value> = recs.iter().filter(|r| r["type"] == "diagnosis").collect();
    assert_eq!(diag.len(), 2, "one final diagnosis per run");
    // Each run's diagnosis carries its index, like the run's curves and its summary.
    for (i, d) in diag.iter().enumerate() {
        assert_eq!(d["run"], i, "{d}");
    }
    let summaries: Vec<&serde_json::Value> =
        recs.iter().filter(|r| r["type"] == "summary").collect();
    assert_eq!(summaries[1]["run"], 1);
    // One run: no index, as in the other records.
    let one = args(&[&a]);
    let d = one.iter().find(|r| r["type"] == "diagnosis").unwrap();
    assert!(d.get("run").is_none(), "{d}");
}
