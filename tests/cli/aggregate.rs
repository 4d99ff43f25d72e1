//! `allanscope aggregate` on JSON-lines files (the real binary): the seed paper's MA4 table 2
//! (the seed paper, docs/theory.md section 6) from three runs' final `fit` records, and the errors a user can make.

use std::path::{Path, PathBuf};
use std::process::Command;

use allanscope::sink::records::{AggregateRecord, Record};
use serde_json::json;

/// The table prints 3 decimals and so do its per-run values (see tests/model/aggregate_table2.rs):
/// a figure recomputed from the printed runs matches within the two roundings.
const PRINTED: f64 = 0.001 + 1e-9;
/// Student's t quantile t_{0.975, 2} = 4.302653 (any t table), for n = 3 runs.
const T975_DF2: f64 = 4.302_652_729_911_275;
/// Rounding of the last printed digit of the quantile above.
const QUANTILE_TOL: f64 = 1e-9;

/// MA4 runs of the seed paper's table 2 (docs/theory.md section 6) in Q, N, B, K, R order, in the table's display units (the fit
/// record carries m/s units; the scale factors 1e-4, 1e-4, 1e-4, 1e-6, 1e-8 are applied below).
const MA4: [[Option<f64>; 5]; 3] = [
    [Some(5.955), None, Some(0.294), Some(2.052), Some(5.327)],
    [
        Some(6.905),
        Some(2.917),
        Some(0.436),
        Some(2.220),
        Some(6.751),
    ],
    [
        Some(7.741),
        Some(2.706),
        Some(0.477),
        Some(2.413),
        Some(5.982),
    ],
];
const SCALE: [f64; 5] = [1e-4, 1e-4, 1e-4, 1e-6, 1e-8];
/// Printed means and sds, Q..R.
const MEAN: [f64; 5] = [6.867, 2.811, 0.403, 2.228, 6.020];
const SD: [f64; 5] = [0.893, 0.149, 0.096, 0.181, 0.713];

fn fit_record(values: &[Option<f64>; 5], final_: bool, run: Option<usize>) -> serde_json::Value {
    let mut coef = serde_json::Map::new();
    for (i, name) in ["Q", "N", "B", "K", "R"].iter().enumerate() {
        let v = values[i].map(|v| v * SCALE[i]);
        coef.insert(
            (*name).into(),
            json!({"value": v, "lo": 0.0, "hi": 1.0, "determined": v.is_some()}),
        );
    }
    let mut r = json!({"type": "fit", "channel": "a4", "unit": "m/s", "final": final_,
        "t_data": 10800.0, "coef": coef, "gof": 1.0, "method": "model"});
    if let Some(run) = run {
        r["run"] = json!(run);
    }
    r
}

fn write_lines(path: &Path, recs: &[serde_json::Value]) {
    let text: String = recs.iter().map(|r| format!("{r}\n")).collect();
    std::fs::write(path, text).expect("write test input");
}

fn tmp_dir(name: &str) -> PathBuf {
    crate::common::fresh_dir(name)
}

fn run_aggregate(args: &[&Path]) -> (i32, Vec<AggregateRecord>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .arg("aggregate")
        .args(args)
        .output()
        .expect("run allanscope");
    let recs = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| match Record::from_line(l) {
            Ok(Some(Record::Aggregate(a))) => a,
            other => panic!("not an aggregate record: {other:?}: {l}"),
        })
        .collect();
    (
        out.status.code().unwrap_or(-1),
        recs,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn ma4_table2_from_three_result_files() {
    let dir = tmp_dir("agg-ma4");
    let mut files = Vec::new();
    for (r, run) in MA4.iter().enumerate() {
        let p = dir.join(format!("run{r}.jsonl"));
        // An interim fit with other values first: only the final one may count.
        let interim = [Some(99.0); 5];
        write_lines(
            &p,
            &[
                json!({"type": "curve", "channel": "a4"}),
                fit_record(&interim, false, None),
                fit_record(run, true, None),
                json!({"type": "summary"}),
            ],
        );
        files.push(p);
    }
    let paths: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
    let (code, recs, err) = run_aggregate(&paths);
    assert_eq!(code, 0, "stderr: {err}");
    assert_eq!(recs.len(), 5, "one record per coefficient");
    for (i, name) in ["Q", "N", "B", "K", "R"].iter().enumerate() {
        let r = recs.iter().find(|r| r.coef == *name).expect("coef record");
        assert_eq!(r.channel, "a4");
        assert_eq!(r.unit, "m/s");
        // N was "-" in run 1 (the seed paper, docs/theory.md section 6): n = 2.
        assert_eq!(r.n, if *name == "N" { 2 } else { 3 });
        let mean = r.mean.expect("mean") / SCALE[i];
        let sd = r.sd.expect("sd") / SCALE[i];
        assert!((mean - MEAN[i]).abs() <= PRINTED, "{name} mean {mean}");
        assert!((sd - SD[i]).abs() <= PRINTED, "{name} sd {sd}");
        let ci_z = r.ci_z.expect("ci_z");
        let se = r.sd.unwrap() / (r.n as f64).sqrt();
        assert!((ci_z[1] - r.mean.unwrap() - 1.96 * se).abs() <= 1e-12 * SCALE[i]);
        if r.n == 3 {
            let ci_t = r.ci_t.expect("ci_t");
            let t = (ci_t[1] - r.mean.unwrap()) / se;
            assert!((t - T975_DF2).abs() < QUANTILE_TOL, "{name}: t {t}");
        }
    }
    // docs/theory.md section 2's worked check: MA4's R gives 6.020 +- 0.807 = [5.213, 6.827].
    let r = recs.iter().find(|r| r.coef == "R").unwrap();
    let ci = r.ci_z.unwrap();
    assert!((ci[0] / 1e-8 - 5.213).abs() <= PRINTED && (ci[1] / 1e-8 - 6.827).abs() <= PRINTED);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn one_file_with_several_runs_counts_as_those_runs() {
    // `analyze A B C` writes one stream with run indices: the same table as three files.
    let dir = tmp_dir("agg-runs");
    let p = dir.join("all.jsonl");
    let recs: Vec<_> = MA4
        .iter()
        .enumerate()
        .map(|(r, run)| fit_record(run, true, Some(r)))
        .collect();
    write_lines(&p, &recs);
    let (code, out, err) = run_aggregate(&[&p]);
    assert_eq!(code, 0, "stderr: {err}");
    let r = out.iter().find(|r| r.coef == "R").expect("R");
    assert_eq!(r.n, 3);
    assert!((r.mean.unwrap() / 1e-8 - 6.020).abs() <= PRINTED);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn inputs_without_fits_are_usage_errors() {
    let dir = tmp_dir("agg-bad");
    let empty = dir.join("curves.jsonl");
    write_lines(&empty, &[json!({"type": "curve", "channel": "a4"})]);
    let (code, _, err) = run_aggregate(&[&empty]);
    assert_eq!(code, 2, "stderr: {err}");
    assert!(
        err.contains("curves.jsonl"),
        "message names the file: {err}"
    );
    let garbage = dir.join("garbage.jsonl");
    std::fs::write(&garbage, "not json\n").unwrap();
    let (code, _, err) = run_aggregate(&[&garbage]);
    assert_eq!(code, 2, "stderr: {err}");
    assert!(err.contains("line 1"), "message names the line: {err}");
    let (code, _, err) = run_aggregate(&[&dir.join("missing.jsonl")]);
    assert_eq!(code, 2, "stderr: {err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn analyze_then_aggregate() {
    // Two runs of `analyze` on the same 2-minute VOG4 capture (fixtures/captures): identical
    // fits, so every determined coefficient aggregates to its own value with sd 0.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let input = root.join("fixtures/captures/vog4_2min_seed7.csv");
    let dir = tmp_dir("agg-analyze");
    let mut files = Vec::new();
    for r in 0..2 {
        let out = dir.join(format!("run{r}.jsonl"));
        let st = Command::new(env!("CARGO_BIN_EXE_allanscope"))
            .args([
                "analyze", "--tau0", "0.004", "--unit", "arcsec", "--stats", "avar",
            ])
            .arg(&input)
            .arg("--out")
            .arg(&out)
            .status()
            .expect("run analyze");
        assert!(st.success());
        files.push(out);
    }
    let text = std::fs::read_to_string(&files[0]).unwrap();
    let fit: serde_json::Value = text
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .rfind(|v| v["type"] == "fit" && v["final"] == true)
        .expect("final fit");
    let paths: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
    let (code, recs, err) = run_aggregate(&paths);
    assert_eq!(code, 0, "stderr: {err}");
    let mut determined = 0;
    for r in &recs {
        let c = &fit["coef"][r.coef.as_str()];
        match c["value"].as_f64() {
            Some(v) => {
                determined += 1;
                assert_eq!(r.n, 2);
                assert_eq!(r.mean, Some(v));
                assert_eq!(r.sd, Some(0.0));
            }
            None => assert_eq!((r.n, r.mean), (0, None)),
        }
    }
    // N and B dominate a 2-minute FOG curve (the seed paper (docs/theory.md section 6): VOG4's N and B are determined).
    assert!(determined >= 2, "{recs:?}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs whose channel is in different units (one analysed in deg, another in rad) are not
/// averaged under the first run's unit: `aggregate` refuses them (exit 2), naming the run and
/// both units, and writes no aggregate record; so does `analyze A B` before its run-to-run
/// records.
#[test]
fn runs_in_different_units_are_not_aggregated() {
    let dir = tmp_dir("agg-units");
    let mut files = Vec::new();
    for (r, unit) in ["deg", "rad", "deg"].iter().enumerate() {
        let mut rec = fit_record(&MA4[r], true, None);
        rec["channel"] = json!("gx");
        rec["unit"] = json!(unit);
        let p = dir.join(format!("agg{r}.jsonl"));
        write_lines(&p, &[rec]);
        files.push(p);
    }
    let paths: Vec<&Path> = files.iter().map(|p| p.as_path()).collect();
    let (code, recs, err) = run_aggregate(&paths);
    assert_eq!(code, 2, "stderr: {err}");
    let expected = format!(
        "{}: channel gx is in rad where {} has it in deg: the runs cannot be aggregated; \
         analyse them with one --unit",
        files[1].display(),
        files[0].display()
    );
    assert!(err.contains(&expected), "{err}");
    assert!(recs.is_empty(), "{recs:?}");
    // The runs of one unit still aggregate: 0 and 2, both deg (n = 2 for B: 0.294, 0.477).
    let (code, recs, err) = run_aggregate(&[paths[0], paths[2]]);
    assert_eq!(code, 0, "stderr: {err}");
    let b = recs.iter().find(|a| a.coef == "B").expect("B");
    assert_eq!((b.n, b.unit.as_str()), (2, "deg"));
    assert!((b.mean.unwrap() - 0.3855e-4).abs() < 1e-12, "{b:?}");

    // `analyze A B`: Kalibr's imu0.csv, whose `omega_x` is in rad/s by its format, and a file
    // of the same values under a header that is not Kalibr's (no unit: `u`).
    let mut csvs = Vec::new();
    for (name, accel) in [("imu0.csv", "alpha"), ("plain.csv", "a")] {
        let mut s = 1u64;
        let mut text = format!("timestamp,omega_x,omega_y,omega_z,{accel}_x,{accel}_y,{accel}_z\n");
        for i in 0..6000u64 {
            text += &format!("{}", 1_385_030_208_736_607_488u64 + i * 5_000_000);
            for _ in 0..6 {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                text += &format!(
                    ",{:e}",
                    ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1e-3
                );
            }
            text.push('\n');
        }
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        csvs.push(p);
    }
    let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args([
            "analyze",
            "--channels",
            "omega_x",
            "--stats",
            "avar",
            "--json",
        ])
        .args(&csvs)
        .output()
        .expect("run analyze");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    let expected = format!(
        "{}: channel omega_x is in u where {} has it in rad: the runs cannot be aggregated",
        csvs[1].display(),
        csvs[0].display()
    );
    assert!(err.contains(&expected), "{err}");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("\"type\":\"aggregate\""), "{text}");
    // Each run's own records are written (they are right in their unit).
    let fits = text
        .lines()
        .filter(|l| l.contains("\"type\":\"fit\"") && l.contains("\"final\":true"))
        .count();
    assert_eq!(fits, 2, "{text}");
}
