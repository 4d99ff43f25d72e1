//! The terminal table (src/sink/table.rs) through its formatter, no terminal needed: a gyro and an
//! accelerometer fit with known coefficients, their read-outs, two datasheet limits and a
//! diagnosis, written as JSON lines into a `TableWriter`. Every number checked below is the
//! hand conversion of the record's native value into datasheet units (docs/theory.md section 2):
//! for a gyro in arcsec N/60 is deg/sqrt(h), B in arcsec/s is deg/h, K*60 is deg/h/sqrt(h); for
//! an accelerometer in m/s, N*60 is m/s/sqrt(h) and B/(9.80665e-6) is micro-g.

use allanscope::model::readout::{Readout, Readouts};
use allanscope::model::units::IncrementUnit;
use allanscope::sink::records::{
    CoefRecord, CoefValue, DatasheetRecord, FitRecord, ReadoutsRecord,
};
use allanscope::sink::table::{sig3, TableStyle, TableWriter};
use serde_json::json;
use std::io::Write;

/// A fit record of `channel` in `unit` with native coefficients `(value, lo, hi)`, Q..R.
fn fit(channel: &str, unit: &str, native: [(Option<f64>, f64, f64); 5]) -> FitRecord {
    let v = |i: usize| {
        let (value, lo, hi) = native[i];
        CoefValue {
            value,
            lo: Some(lo),
            hi: Some(hi),
            determined: value.is_some(),
        }
    };
    let coef = CoefRecord {
        Q: v(0),
        N: v(1),
        B: v(2),
        K: v(3),
        R: v(4),
    };
    let inc = IncrementUnit::parse(unit).unwrap();
    FitRecord {
        channel: channel.into(),
        unit: unit.into(),
        r#final: true,
        t_data: 3600.0,
        coef,
        gof: Some(1.04),
        method: "model".into(),
        model_c: vec![],
        datasheet: Some(DatasheetRecord::new(&coef, &inc)),
        readouts: None,
        q_over_lsb: None,
        run: None,
    }
}

fn gyro() -> FitRecord {
    let mut f = fit(
        "gx",
        "arcsec",
        [
            (None, 0.0, 0.002),
            (Some(0.25), 0.2, 0.3125),
            (Some(0.125), 0.0625, 0.5),
            (None, 0.0, 1.0),
            (None, 0.0, 0.01),
        ],
    );
    // ARW read at tau = 1 s itself; bias instability from a minimum of 0.0664 arcsec/s at 100 s.
    let r = Readouts {
        arw: Some(Readout {
            value: 0.24,
            lo: 0.18,
            hi: 0.30,
            tau: 1.0,
            sigma: 0.24,
            slope: -0.5,
        }),
        bias_instability: Some(Readout {
            value: 0.1,
            lo: 0.08,
            hi: 0.13,
            tau: 100.0,
            sigma: 0.0664,
            slope: 0.0,
        }),
        rrw: None,
    };
    // The fit behind it: N 0.24 arcsec/sqrt(s), B 0.02 arcsec/s. At 100 s the flicker is
    // 0.4413 * 0.02^2 / (0.24^2 / 100 + 0.4413 * 0.02^2) = 23% of the variance: the minimum is
    // no flicker floor and the read-out an upper bound on B.
    let c = [0.0, 0.24f64.powi(2), 0.02f64.powi(2), 0.0, 0.0];
    f.readouts = Some(Box::new(ReadoutsRecord::new(&r, "arcsec", Some(c))));
    f
}

/// An accelerometer whose curve the five-term model does not follow (`gof` 1456, as the ADIS
/// gyro's over all taus: docs/fit.md).
fn accel() -> FitRecord {
    let mut f = fit(
        "ax",
        "m/s",
        [
            (Some(1e-4), 0.9e-4, 1.1e-4),
            (Some(0.01), 0.009, 0.011),
            (Some(9.80665e-6), 4.903325e-6, 1.96133e-5),
            (None, 0.0, 1e-5),
            (None, 0.0, 1e-7),
        ],
    );
    f.gof = Some(1456.0);
    f
}

fn lines() -> Vec<String> {
    let limits = json!([
        {"channel": "gx", "coef": "N", "over": "run", "bound": "max", "limit": 0.005,
         "unit": "deg/sqrt(h)", "value": 0.25 / 60.0, "lo": 0.2 / 60.0, "hi": 0.3125 / 60.0,
         "verdict": "pass"},
        {"channel": "ax", "coef": "B", "over": "run", "bound": "max", "limit": 0.5,
         "unit": "micro-g", "value": 1.0, "lo": 0.5, "hi": 2.0, "verdict": "fail"},
    ]);
    let diagnosis = json!({"type": "diagnosis", "channel": "gx", "gap_before": 3.0,
        "gap_after": 1.1, "verdict": "explained", "regions": [{"tau_lo": 10.0, "tau_hi": 100.0,
        "sign": 1, "worst_ratio": 1.8}], "effects": [{"kind": "gauss_markov",
        "params": {"sigma": 0.1, "tau_c": 20.0}, "gap_after": 1.1}], "final": true});
    let summary = json!({"type": "summary", "input": "runs/unit7.csv", "channels": ["gx", "ax"],
        "tau0": 0.01, "t_data": 3600.0, "samples": [360000, 360000], "segments": [1, 3],
        "bad_rows": 0, "overlap": "16", "elapsed_s": 1.0, "limits": limits, "pass": false,
        "read_to_end": true});
    vec![
        // Curves are not shown; an interim fit is replaced by the final one.
        json!({"type": "curve", "channel": "gx"}).to_string(),
        {
            let mut f = gyro();
            f.r#final = false;
            f.coef.N.value = Some(9.0);
            serde_json::to_string(&f).unwrap()
        },
        serde_json::to_string(&gyro()).unwrap(),
        serde_json::to_string(&accel()).unwrap(),
        diagnosis.to_string(),
        summary.to_string(),
    ]
}

/// The line of `text` that starts (after its indent) with `start`.
fn row<'a>(text: &'a str, start: &str) -> &'a str {
    text.lines()
        .find(|l| l.trim_start().starts_with(start))
        .unwrap_or_else(|| panic!("no line starting with `{start}` in\n{text}"))
}

#[test]
fn the_table_shows_datasheet_units_intervals_readouts_limits_and_the_diagnosis() {
    let out = Shared::default();
    let mut w = TableWriter::new(out.clone(), TableStyle::default(), None);
    let all = lines();
    for l in &all[..all.len() - 1] {
        writeln!(w, "{l}").unwrap();
    }
    w.flush().unwrap();
    // Nothing is printed before the run's summary arrives.
    assert!(out.text().is_empty(), "{}", out.text());
    // The summary may arrive cut across writes, as a buffered writer hands it on.
    let last = all.last().unwrap();
    let (a, b) = last.split_at(last.len() / 2);
    write!(w, "{a}").unwrap();
    assert!(out.text().is_empty());
    writeln!(w, "{b}").unwrap();
    let t = out.text();
    assert!(!t.is_empty());
    drop(w);
    // Dropping the writer adds nothing more: the run was printed whole.
    assert_eq!(out.text(), t);
    println!("{t}");
    assert!(!t.contains('{'), "no JSON on a terminal:\n{t}");
    // Heading: the input, the data length, how it ended, the gaps (3 segments: 2 gaps).
    let head = t.lines().next().unwrap();
    assert!(head.starts_with("runs/unit7.csv: 60.0 min of data at tau0 = 10.0 ms, 2 channels, read to its end (2 gaps)"), "{head}");
    // Gyro: N = 0.25 arcsec/sqrt(s) = 0.25/60 deg/sqrt(h) = 0.00417 [0.00333, 0.00521].
    let n = row(&t, "N  angle random walk");
    assert!(n.contains("deg/sqrt(h)"), "{n}");
    assert!(n.contains("0.00417 [0.00333, 0.00521]"), "{n}");
    // Its IEEE 952 read-out: 0.24 arcsec/sqrt(s) at 1 s = 0.00400 deg/sqrt(h) [0.00300, 0.00500].
    assert!(n.contains("0.00400 [0.00300, 0.00500] at 1.00 s"), "{n}");
    // B = 0.125 arcsec/s = 0.125 deg/h; read-out 0.1 deg/h with the tau of the minimum.
    let b = row(&t, "B  bias instability");
    assert!(
        b.contains("deg/h ") && b.contains("0.125 [0.0625, 0.500]"),
        "{b}"
    );
    assert!(b.contains("0.100 [0.0800, 0.130] min at 100 s; an upper bound on B: the fitted flicker is 23% of the variance there"), "{b}");
    // K not determined: its 95% upper bound, 1.0 arcsec/s/sqrt(s) = 60 deg/h/sqrt(h).
    let k = row(&t, "K  rate random walk");
    assert!(
        k.contains("deg/h/sqrt(h)") && k.contains("not determined (< 60.0)"),
        "{k}"
    );
    assert!(k.contains("no +1/2 slope"), "{k}");
    assert!(row(&t, "Q  quantization").contains("not determined (< 0.00200)"));
    // The final fit replaced the interim one (whose N was 9).
    assert!(!t.contains("0.150 "), "{t}");
    assert_eq!(t.matches("gx [arcsec, gyro]").count(), 1, "{t}");
    // Accelerometer: N = 0.01 m/s/sqrt(s) = 0.6 m/s/sqrt(h); B = 1 micro-g.
    let an = row(&t, "N  velocity random walk");
    assert!(
        an.contains("m/s/sqrt(h)") && an.contains("0.600 [0.540, 0.660]"),
        "{an}"
    );
    let ab = t
        .lines()
        .find(|l| l.trim_start().starts_with("B  bias instability") && l.contains("micro-g"))
        .unwrap();
    assert!(ab.contains("1.00 [0.500, 2.00]"), "{ab}");
    // A gof far above 1 is said under its channel's terms, not under the gyro's (gof 1.04).
    let misfit = "gof 1456: the five-term model does not describe this curve";
    assert_eq!(t.matches(misfit).count(), 1, "{t}");
    let (gyro_part, accel_part) = t.split_at(t.find("ax [m/s").expect("accel block"));
    assert!(accel_part.contains(misfit) && !gyro_part.contains("does not describe"));
    // Limits per channel, and the overall verdict.
    assert!(
        row(&t, "limits:").contains("PASS N <= 0.00500 deg/sqrt(h)"),
        "{t}"
    );
    assert!(
        t.contains("FAIL B <= 0.500 micro-g (fit 1.00 [0.500, 2.00])"),
        "{t}"
    );
    assert!(t.contains("FAIL: 1 of 2 datasheet limits exceeded"), "{t}");
    // The diagnosis in one line, with the effect's parameters in units.
    let d = row(&t, "diagnosis:");
    assert!(
        d.contains("explained by correlated (Gauss-Markov) noise [sigma 0.100 deg/h (0.100 arcsec/s), correlation time 20.0 s] (gap 3.00 -> 1.10)"),
        "{d}"
    );
}

/// An output buffer the test can read while the writer holds it.
#[derive(Clone, Default)]
struct Shared(std::sync::Arc<std::sync::Mutex<Vec<u8>>>);

impl Shared {
    fn text(&self) -> String {
        String::from_utf8(self.0.lock().unwrap().clone()).unwrap()
    }
}

impl Write for Shared {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn records_without_a_summary_are_printed_when_the_writer_is_dropped() {
    // The `diagnose` command writes diagnoses only: they are shown at the end.
    let out = Shared::default();
    let mut w = TableWriter::new(out.clone(), TableStyle::default(), Some("hint".into()));
    writeln!(w, "{}", lines()[4]).unwrap();
    assert!(out.text().is_empty());
    drop(w);
    let t = out.text();
    assert!(
        t.starts_with("\ngx  diagnosis: explained by correlated (Gauss-Markov) noise"),
        "{t}"
    );
    assert!(t.trim_end().ends_with("hint"), "{t}");
}

/// A warm-up found in the block means alone leaves the curve's gap as it was (a review's FOG,
/// session 43: 1.089 before and after): the line says the gap is unchanged and where the
/// effect was seen, not "1.09 -> 1.09" as if the curve had been mended.
#[test]
fn an_effect_seen_in_time_alone_says_the_gap_is_unchanged() {
    let rec = json!({"type": "diagnosis", "channel": "gz", "gap_before": 1.089,
        "gap_after": 1.089, "verdict": "explained", "regions": [], "effects": [{"kind": "warmup",
        "params": {"amplitude": 0.027, "time_constant": 642.0}, "gap_after": 1.089}],
        "final": true});
    let d: allanscope::gap::record::DiagnosisRecord = serde_json::from_value(rec).unwrap();
    let line = allanscope::sink::table::diagnosis_line(&d, "arcsec", &TableStyle::default());
    assert!(
        line.contains(
            "(gap 1.09, unchanged: seen in the block means over time, not on the Allan curve)"
        ),
        "{line}"
    );
    assert!(!line.contains("->"), "{line}");
}

/// A CIC with a Butterworth behind it, named as two effects, is said to be one filter in series;
/// a low-pass named alone says nothing of the kind.
#[test]
fn a_decimator_and_a_low_pass_are_said_to_be_in_series() {
    let series = "the moving average and the low-pass are one filter in series, the average first";
    let cic = json!({"kind": "moving_average", "params": {"decimation": 8, "stages": 3,
        "taps": 8}, "gap_after": 0.86});
    let bw = json!({"kind": "second_order_filter", "params": {"bilinear": true,
        "damping": 0.70, "natural_frequency": 40.0}, "gap_after": 1276.0});
    for (effects, said) in [(vec![bw.clone(), cic], true), (vec![bw], false)] {
        let rec = json!({"type": "diagnosis", "channel": "g", "gap_before": 4749.0,
            "gap_after": 0.86, "verdict": "explained", "regions": [], "effects": effects,
            "final": true});
        let d: allanscope::gap::record::DiagnosisRecord = serde_json::from_value(rec).unwrap();
        let line = allanscope::sink::table::diagnosis_line(&d, "deg", &TableStyle::default());
        assert_eq!(line.contains(series), said, "{line}");
    }
}

#[test]
fn three_significant_digits() {
    assert_eq!(sig3(0.0041666), "0.00417");
    assert_eq!(sig3(0.125), "0.125");
    assert_eq!(sig3(60.0), "60.0");
    assert_eq!(sig3(1125.4), "1125");
    assert_eq!(sig3(6.86e-4), "6.86e-4");
    assert_eq!(sig3(2.5e6), "2.50e6");
    assert_eq!(sig3(-0.5), "-0.500");
    assert_eq!(sig3(0.0), "0");
}

#[test]
fn the_status_line_of_a_live_run() {
    use allanscope::sink::table::status_line;
    let n = vec![
        ("gx".to_string(), 0.25 / 60.0, "deg/sqrt(h)".to_string()),
        ("gy".to_string(), 0.255 / 60.0, "deg/sqrt(h)".to_string()),
    ];
    assert_eq!(
        status_line(12.4, 3000, 249.6, Some(2), &n),
        "12 s running, 3000 frames, 250 frames/s, 2 lost | N: gx 0.00417  gy 0.00425 deg/sqrt(h)"
    );
    // Channels of different units each carry theirs.
    let mixed = vec![
        n[0].clone(),
        ("ax".to_string(), 0.6, "m/s/sqrt(h)".to_string()),
    ];
    assert!(status_line(1.0, 1, 1.0, None, &mixed)
        .ends_with("N: gx 0.00417 deg/sqrt(h)  ax 0.600 m/s/sqrt(h)"));
}

#[test]
fn the_metrics_tap_keeps_the_newest_n_and_lost_frames_for_the_status_line() {
    use allanscope::sink::metrics::Metrics;
    use allanscope::sink::records::Record;
    let m = std::sync::Arc::new(Metrics::new());
    let tap = m.tap("dut", &[]);
    tap.observe(&Record::from(gyro()));
    // Not determined in a later fit: no longer shown.
    let mut acc = accel();
    tap.observe(&Record::from(acc.clone()));
    let latest = m.latest();
    // N = 0.25 arcsec/sqrt(s) = 0.25/60 deg/sqrt(h); 0.01 m/s/sqrt(s) = 0.6 m/s/sqrt(h).
    assert_eq!(latest.n.len(), 2);
    assert_eq!(latest.n[0].0, "gx");
    assert!((latest.n[0].1 - 0.25 / 60.0).abs() < 1e-15);
    assert_eq!(latest.n[0].2, "deg/sqrt(h)");
    assert!((latest.n[1].1 - 0.6).abs() < 1e-12);
    acc.coef.N.determined = false;
    tap.observe(&Record::from(acc));
    assert_eq!(m.latest().n.len(), 1);
    let h = allanscope::frame::Health {
        missing: 3,
        ..Default::default()
    };
    tap.health(&h);
    assert_eq!(m.latest().missing, vec![("dut".to_string(), 3)]);
}

/// A `diagnose` record (no fit beside it) names its unit: the effects' rates and the refitted
/// terms are shown in datasheet units, converted by hand here. Accelerometer in m/s: a rate of
/// 9.80665e-5 m/s/s is 10 micro-g, 4.903325e-6 m/s/s per deg C is 0.5 micro-g per deg C (its
/// interval [2.4516625e-6, 9.80665e-6] is [0.25, 1]). Gyro in
/// deg: 0.001 deg/s is 3.6 deg/h; N = 0.01 deg/sqrt(s) is 0.6 deg/sqrt(h) (x 60).
#[test]
fn the_diagnose_table_gives_effect_parameters_in_datasheet_units() {
    let rec = |ch: &str, unit: &str, effects: serde_json::Value| {
        json!({"type": "diagnosis", "channel": ch, "unit": unit, "gap_before": 4.0,
            "gap_after": 1.0, "verdict": "explained", "regions": [], "effects": effects,
            "final": true, "t_data": 600.0, "tau_span": [0.01, 60.0],
            "base_coef": [0.0, 0.01, 0.0, 0.0, 0.0], "final_coef": [0.0, 0.01, 0.0, 0.0, 0.0]})
    };
    let out = Shared::default();
    let mut w = TableWriter::new(out.clone(), TableStyle::default(), None);
    let a1 = rec(
        "a1",
        "m/s",
        json!([{"kind": "gauss_markov", "params": {"sigma": 9.80665e-5, "tau_c": 20.0}, "gap_after": 2.0},
               {"kind": "temperature", "params": {"coefficient": 4.903325e-6, "lo": 2.4516625e-6,
                "hi": 9.80665e-6}, "gap_after": 1.0}]),
    );
    let mut g1 = rec(
        "g1",
        "deg",
        json!([{"kind": "sinusoid", "params": {"amplitude": 0.001, "frequency": 0.5}, "gap_after": 1.0}]),
    );
    // What the diagnosis set aside, said after the effects: 0.001 deg/s is 3.6 deg/h.
    g1["outliers"] = json!({"count": 3, "rate": 0.005, "rms_size": 0.001, "max_size": 0.002});
    g1["stuck"] = json!({"stretches": 1, "seconds": 60.0, "longest_s": 60.0, "first_at_s": 600.0});
    // A first block far off (session 45): 0.002 deg/s is 7.2 deg/h, below the rest.
    g1["first_block"] =
        json!({"start_s": 0.0, "seconds": 8.192, "offset": -0.002, "p_value": 0.004});
    writeln!(w, "{a1}\n{g1}").unwrap();
    drop(w);
    let t = out.text();
    let a = row(&t, "a1 [m/s]  diagnosis:");
    assert!(
        a.contains("correlated (Gauss-Markov) noise [sigma 10.0 micro-g (9.81e-5 m/s/s), correlation time 20.0 s]"),
        "{a}"
    );
    assert!(
        a.contains("temperature sensitivity [coefficient 0.500 [0.250, 1.00] micro-g per deg C (4.90e-6 [2.45e-6, 9.81e-6] m/s/s per deg C)]"),
        "{a}"
    );
    let g = row(&t, "g1 [deg]  diagnosis:");
    assert!(
        g.contains(
            "; set aside: 3 outliers replaced (rms 3.60 deg/h (0.00100 deg/s), the largest 7.20 \
             deg/h (0.00200 deg/s)); 1 stuck stretch taken out as a gap (60.0 s in all, the first \
             at 600 s)"
        ),
        "{g}"
    );
    assert!(!row(&t, "a1 [m/s]  diagnosis:").contains("set aside"));
    assert!(
        g.contains(
            "; the block from 0 s to 8.19 s averages 7.20 deg/h (0.00200 deg/s) below the rest \
             of the run (p 0.00400): a start-up transient or one block's excursion of slower \
             noise, too short to name as a warm-up"
        ),
        "{g}"
    );
    assert!(!a.contains("the block from"), "{a}");
    // The gap's scale, once under the table.
    assert_eq!(
        t.matches(allanscope::sink::table::GAP_LEGEND).count(),
        1,
        "{t}"
    );
    assert!(
        g.contains(
            "sinusoid [amplitude 3.60 deg/h (0.00100 deg/s), frequency 0.500 Hz (period 2.00 s)]"
        ),
        "{g}"
    );
    assert!(
        t.contains("five-term model with the effects: N 0.600 deg/sqrt(h);"),
        "{t}"
    );
}

/// Three runs of one gyro in arcsec, N = 0.24, 0.25, 0.26 arcsec/sqrt(s) and B determined in
/// the first two only, then their `aggregate` records: the terminal shows the seed paper's table
/// 2 layout, runs as rows named by their inputs, R K B N Q as columns in datasheet units, then
/// mean, 95% interval, sd and n. By hand: N/60 is deg/sqrt(h): 0.00400, 0.00417, 0.00433; the
/// mean 0.25 is 0.00417, sd 0.01 is 1.67e-4, and mean +- 1.96 sd/sqrt(3) = [0.238684, 0.261316]
/// is [0.00398, 0.00436]; B in arcsec/s is deg/h.
fn three_runs() -> Vec<String> {
    let mut out = Vec::new();
    for (r, (n, b)) in [(0.24, Some(0.1)), (0.25, Some(0.12)), (0.26, None)]
        .into_iter()
        .enumerate()
    {
        let mut f = fit(
            "gx",
            "arcsec",
            [
                (None, 0.0, 0.002),
                (Some(n), 0.9 * n, 1.1 * n),
                (b, 0.05, 0.2),
                (None, 0.0, 1.0),
                (None, 0.0, 0.01),
            ],
        );
        f.run = Some(r);
        out.push(serde_json::to_string(&f).unwrap());
        out.push(
            json!({"type": "summary", "run": r, "input": format!("/data/stand/run{}.csv", r + 1),
                "channels": ["gx"], "tau0": 0.01, "t_data": 3600.0, "samples": [360000],
                "segments": [1], "bad_rows": 0, "overlap": "16", "elapsed_s": 1.0,
                "read_to_end": true})
            .to_string(),
        );
    }
    let half = 1.96 * 0.01 / 3f64.sqrt();
    for (coef, n, mean, sd, ci) in [
        ("Q", 0, None, None, None),
        (
            "N",
            3,
            Some(0.25),
            Some(0.01),
            Some([0.25 - half, 0.25 + half]),
        ),
        ("B", 2, Some(0.11), Some(0.0141421), Some([0.0904, 0.1296])),
        ("K", 0, None, None, None),
        ("R", 0, None, None, None),
    ] {
        out.push(
            json!({"type": "aggregate", "channel": "gx", "unit": "arcsec", "coef": coef, "n": n,
                "mean": mean, "sd": sd, "ci_t": null, "ci_z": ci})
            .to_string(),
        );
    }
    out
}

#[test]
fn several_runs_are_shown_in_the_table_2_layout() {
    let out = Shared::default();
    let mut w = TableWriter::new(out.clone(), TableStyle::default(), None);
    for l in three_runs() {
        writeln!(w, "{l}").unwrap();
    }
    drop(w);
    let t = out.text();
    let table = &t[t.find("Run to run").expect("a run-to-run table")..];
    let cells = |start: &str| -> Vec<String> {
        row(table, start)
            .split("  ")
            .map(|c| c.trim().to_string())
            .filter(|c| !c.is_empty())
            .collect()
    };
    assert_eq!(cells("run "), ["run", "R", "K", "B", "N", "Q"], "{table}");
    assert_eq!(
        cells("deg/h^2"),
        ["deg/h^2", "deg/h/sqrt(h)", "deg/h", "deg/sqrt(h)", "arcsec"],
        "{table}"
    );
    assert_eq!(
        cells("run1.csv"),
        ["run1.csv", "-", "-", "0.100", "0.00400", "-"]
    );
    assert_eq!(
        cells("run2.csv"),
        ["run2.csv", "-", "-", "0.120", "0.00417", "-"]
    );
    assert_eq!(
        cells("run3.csv"),
        ["run3.csv", "-", "-", "-", "0.00433", "-"]
    );
    assert_eq!(cells("mean"), ["mean", "-", "-", "0.110", "0.00417", "-"]);
    assert_eq!(
        cells("95% interval"),
        [
            "95% interval",
            "-",
            "-",
            "[0.0904, 0.130]",
            "[0.00398, 0.00436]",
            "-"
        ]
    );
    assert_eq!(cells("sd"), ["sd", "-", "-", "0.0141", "1.67e-4", "-"]);
    assert_eq!(
        cells("runs determined"),
        ["runs determined", "0", "0", "2", "3", "0"]
    );
}

/// The status line and log lines on one terminal (sink::status_area): a log line erases the
/// status line, is written, and the status line is drawn again under it; the line is cut to the
/// terminal's width less one column; once suspended (a table is coming) nothing is drawn again.
#[test]
fn log_lines_are_written_above_the_status_line_never_through_it() {
    use allanscope::sink::status_area::{StatusArea, CLEAR};
    let mut area = StatusArea::new();
    let mut out: Vec<u8> = Vec::new();
    let text = |o: &mut Vec<u8>| String::from_utf8(std::mem::take(o)).unwrap();
    // No status line yet: a log line goes out as it is.
    area.log(&mut out, b"INFO first\n").unwrap();
    assert_eq!(text(&mut out), "INFO first\n");
    // A 30-character line on a 21-column terminal keeps 20 characters.
    let line = "12 s running | N: g1 0.254 arcsec/sqrt(s)";
    area.draw(&mut out, line, 21).unwrap();
    assert_eq!(text(&mut out), format!("{CLEAR}{}", &line[..20]));
    // A log line: erase, the message, the status line again on the fresh line.
    area.log(&mut out, b"WARN frame 17: checksum\n").unwrap();
    assert_eq!(
        text(&mut out),
        format!("{CLEAR}WARN frame 17: checksum\n{}", &line[..20])
    );
    // A message that does not end its line leaves the cursor there: no redraw until the next
    // draw, and the next log line does not erase the message.
    area.log(&mut out, b"partial").unwrap();
    assert_eq!(text(&mut out), format!("{CLEAR}partial"));
    area.log(&mut out, b" rest\n").unwrap();
    assert_eq!(text(&mut out), " rest\n");
    area.draw(&mut out, "13 s running", 80).unwrap();
    assert_eq!(text(&mut out), format!("{CLEAR}13 s running"));
    // Suspended: erased once, then never drawn again; log lines plain.
    area.suspend(&mut out).unwrap();
    assert_eq!(text(&mut out), CLEAR);
    area.draw(&mut out, "14 s running", 80).unwrap();
    area.log(&mut out, b"INFO done\n").unwrap();
    assert_eq!(text(&mut out), "INFO done\n");
    assert!(area.is_suspended());
}

/// `diagnose --ensemble 20` on a terminal: the diagnosis line ends with how far the measured
/// curve lies outside each band, from the record's shares (0.75 and 1/12 of 12 taus); the same
/// record without `ensemble` says nothing of a band.
#[test]
fn the_diagnose_table_says_how_far_the_twin_matches() {
    let table = |rec: serde_json::Value| {
        let out = Shared::default();
        let mut w = TableWriter::new(out.clone(), TableStyle::default(), None);
        writeln!(w, "{rec}").unwrap();
        drop(w);
        out.text()
    };
    let t = table(crate::plot::ensemble_diagnosis(true));
    let g = row(&t, "g4 [arcsec]  diagnosis:");
    assert!(
        g.ends_with(
            "(gap 21.5 -> 1.10); against 20 simulated runs: outside the base band at 75% of \
             taus (9 of 12); outside the twin's at 8% (1 of 12)"
        ),
        "{g}"
    );
    let bare = table(crate::plot::ensemble_diagnosis(false));
    assert!(!bare.contains("simulated runs"), "{bare}");
    assert!(row(&bare, "g4 [arcsec]  diagnosis:").ends_with("(gap 21.5 -> 1.10)"));
}

/// The held-out run in words (session 39): which of the fitting run's effects carried, since
/// one carried in time (a warm-up, a temperature) leaves the held-out gap as it was; and which
/// the run could not judge (session 53).
#[test]
fn the_diagnose_table_says_which_effects_carried_to_the_held_out_run() {
    let rec = |holdout: serde_json::Value| {
        json!({"type": "diagnosis", "channel": "a4", "unit": "m/s", "gap_before": 1.6,
            "gap_after": 1.38, "verdict": "explained", "regions": [],
            "effects": [{"kind": "output_filter", "params": {"time_constant": 0.0305}, "gap_after": 1.39},
                        {"kind": "warmup", "params": {"amplitude": 9.19e-4, "time_constant": 699.0}, "gap_after": 1.38}],
            "final": true, "t_data": 7200.0, "tau_span": [0.004, 655.0],
            "base_coef": [6.87e-4, 2.8e-4, 0.0, 0.0, 0.0], "final_coef": [6.87e-4, 2.8e-4, 0.0, 0.0, 0.0],
            "holdout": holdout})
    };
    let both = |filter: bool, warm: bool| {
        json!({"gap_before": 1.41, "gap_after": 1.41, "carried": filter || warm, "effects": [
            {"kind": "output_filter", "gap_after": 1.52, "carried": filter, "delta_chi2": -10.0},
            {"kind": "warmup", "gap_after": 1.41, "carried": warm, "delta_chi2": 0.0}]})
    };
    for (holdout, words) in [
        (
            both(false, true),
            "on the held-out run gap 1.41 -> 1.41 (carried: warm-up drift; did not carry: output \
             low-pass filter)",
        ),
        (
            both(false, false),
            "on the held-out run gap 1.41 -> 1.41 (did not carry: output low-pass filter, \
             warm-up drift)",
        ),
        (
            json!({"gap_before": 1.41, "gap_after": 1.41, "carried": false}),
            "on the held-out run gap 1.41 -> 1.41 (did not carry)",
        ),
        // A warm-up the held-out run could not show (session 53): not `did not carry`.
        (
            json!({"gap_before": 1.41, "gap_after": 1.41, "carried": false,
                   "not_judged": ["warmup"]}),
            "on the held-out run gap 1.41 -> 1.41 (not judged there: warm-up drift)",
        ),
    ] {
        let out = Shared::default();
        let mut w = TableWriter::new(out.clone(), TableStyle::default(), None);
        writeln!(w, "{}", rec(holdout)).unwrap();
        drop(w);
        let t = out.text();
        let a = row(&t, "a4 [m/s]  diagnosis:");
        assert!(a.contains(words), "{a}");
    }
}

/// A channel named with its own unit in brackets (a logger's rates read as increments in m/s)
/// is headed with the increment unit said once, not a second bracket; an alternative that fits
/// better than the choice (`delta_chi2` < 0: a Gauss-Markov term just short of its threshold)
/// says it was short of the bar, one that fits worse does not.
#[test]
fn the_diagnose_table_heads_a_unit_in_the_name_and_says_an_alternative_fell_short() {
    let rec = |ch: &str, delta: f64| {
        json!({"type": "diagnosis", "channel": ch, "unit": "m/s", "gap_before": 1.2,
            "gap_after": 1.2, "verdict": "consistent", "regions": [], "effects": [],
            "final": true, "t_data": 600.0, "tau_span": [0.01, 60.0],
            "base_coef": [0.0, 0.01, 0.0, 0.0, 0.0], "final_coef": [0.0, 0.01, 0.0, 0.0, 0.0],
            "alternatives": [{"coef": [0.0, 0.01, 0.0, 0.0, 0.0], "delta_chi2": delta,
                "effects": [{"kind": "gauss_markov", "params": {"sigma": 1e-4, "tau_c": 20.0}}],
                "gap": 0.9}]})
    };
    let out = Shared::default();
    let mut w = TableWriter::new(out.clone(), TableStyle::default(), None);
    writeln!(w, "{}\n{}", rec("ax [m/s^2]", -9.55), rec("ay", 1.0)).unwrap();
    drop(w);
    let t = out.text();
    let ax = row(&t, "ax [m/s^2] (u = m/s)  diagnosis:");
    assert!(
        ax.contains("(gap 0.90, short of the bar to be named)"),
        "{ax}"
    );
    let ay = row(&t, "ay [m/s]  diagnosis:");
    assert!(
        ay.contains("(gap 0.90)") && !ay.contains("short of"),
        "{ay}"
    );
}
