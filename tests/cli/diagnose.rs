//! `diagnose` through the binary: a simulated gyro with a hidden Gauss-Markov term, judged on
//! its own run and on a held-out run of the same model; a clean run is consistent.

use crate::common::{exe, first_record, parse_lines_of, simulate_to, stdout_of, write_vog4_model};

use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    crate::common::tmp_in("diag", name)
}

/// The seed paper's VOG4 terms (table 2 means) with or without a Gauss-Markov term.
fn model(gm: bool) -> std::path::PathBuf {
    let p = tmp(if gm { "gm.toml" } else { "clean.toml" });
    let effect = if gm {
        "gauss_markov = { sigma = 0.6, tau_c = 1.5 }\n"
    } else {
        ""
    };
    write_vog4_model(&p, effect);
    p
}

/// Thirty minutes of `model`'s run as text columns.
fn simulate(model: &std::path::Path, seed: u64, name: &str) -> std::path::PathBuf {
    let out = tmp(name);
    let seed = seed.to_string();
    simulate_to(
        model,
        &["--duration", "30min", "--seed", &seed, "--format", "csv"],
        &out,
    );
    out
}

fn diagnosis(args: &[&str]) -> serde_json::Value {
    first_record(exe().arg("diagnose").args(args).args(["--tau0", "0.004"]))
}

#[test]
fn names_a_hidden_gauss_markov_term_and_holds_on_a_held_out_run() {
    let m = model(true);
    let run = simulate(&m, 8, "gm8.csv");
    let held = simulate(&m, 9, "gm9.csv");
    let d = diagnosis(&[run.to_str().unwrap(), "--holdout", held.to_str().unwrap()]);
    assert_eq!(d["type"], "diagnosis");
    assert_eq!(d["channel"], "g4");
    assert_eq!(d["verdict"], "explained", "{d}");
    let e = &d["effects"][0];
    assert_eq!(e["kind"], "gauss_markov", "{d}");
    // Truth sigma 0.6 arcsec/s, tau_c 1.5 s; the tolerances are 25% and 10%, this
    // 30-minute run is shorter than the 3-hour runs they are set for: 25% on both.
    let (s, t) = (
        e["params"]["sigma"].as_f64().unwrap(),
        e["params"]["tau_c"].as_f64().unwrap(),
    );
    assert!((s / 0.6 - 1.0).abs() < 0.25, "sigma {s}");
    assert!((t / 1.5 - 1.0).abs() < 0.25, "tau_c {t}");
    let (before, after) = (
        d["gap_before"].as_f64().unwrap(),
        d["gap_after"].as_f64().unwrap(),
    );
    assert!(before > 3.0 && after < 1.7, "{before} -> {after}");
    // The effect fitted on run 8 closes the gap on run 9 as well as run 9's own fit of the
    // same effect does (run 9 may be harder than run 8: G scatters from run to run).
    let h = &d["holdout"];
    let (hb, ha) = (
        h["gap_before"].as_f64().unwrap(),
        h["gap_after"].as_f64().unwrap(),
    );
    let own = diagnosis(&[held.to_str().unwrap()]);
    let own_gm = own["effects"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "gauss_markov")
        .expect("run 9 names the same effect");
    let own_after = own_gm["gap_after"].as_f64().unwrap();
    assert!(hb > 3.0, "held-out gap before {hb}");
    assert!(
        ha <= 1.25 * own_after,
        "held-out gap after {ha} vs its own fit's {own_after}"
    );
}

#[test]
fn a_clean_run_is_consistent() {
    let run = simulate(&model(false), 3, "clean3.csv");
    let d = diagnosis(&[run.to_str().unwrap()]);
    assert_eq!(d["verdict"], "consistent", "{d}");
    assert_eq!(d["effects"].as_array().unwrap().len(), 0);
    assert!(d["gap_before"].as_f64().unwrap() < 1.7);
}

/// `--unit` names the increment's unit; with `--rate` the rate's unit (`arcsec/s`) means the
/// same: the record says `arcsec` (the table's parameters are then in arcsec/s, not arcsec/s/s)
/// and the diagnosis is the one `--unit arcsec` gives.
#[test]
fn a_rate_unit_with_rate_names_the_increment_unit() {
    let run = simulate(&model(false), 3, "clean3_rate.csv");
    let path = run.to_str().unwrap();
    let per_s = diagnosis(&[path, "--rate", "--unit", "arcsec/s"]);
    let plain = diagnosis(&[path, "--rate", "--unit", "arcsec"]);
    assert_eq!(per_s["unit"], "arcsec", "{per_s}");
    assert_eq!(per_s["gap_before"], plain["gap_before"]);
    assert_eq!(per_s["unit"], plain["unit"]);
}

#[test]
fn the_stream_carries_diagnosis_records_refreshed_with_the_fits() {
    let run = simulate(&model(true), 8, "gm8-stream.csv");
    let recs: Vec<serde_json::Value> = parse_lines_of(exe().args([
        "analyze",
        run.to_str().unwrap(),
        "--tau0",
        "0.004",
        "--diagnose",
        "--every",
        "600",
    ]))
    .into_iter()
    .filter(|v| v["type"] == "diagnosis")
    .collect();
    // 30 minutes, every 600 s: interim at 600, 1200 and 1800 s, then the final one.
    assert_eq!(recs.len(), 4);
    assert_eq!(recs.iter().filter(|r| r["final"] == true).count(), 1);
    let last = recs.last().unwrap();
    let batch = diagnosis(&[run.to_str().unwrap()]);
    assert_eq!(last["verdict"], batch["verdict"]);
    assert_eq!(last["effects"][0]["kind"], batch["effects"][0]["kind"]);
    let (a, b) = (
        last["gap_before"].as_f64().unwrap(),
        batch["gap_before"].as_f64().unwrap(),
    );
    assert!((a - b).abs() <= 1e-9 * b, "stream {a} vs diagnose {b}");
}

/// `analyze --diagnose` and `diagnose` plan and read their input the same way: on one file with
/// `inf`, `-inf` and `nan` among its values (each a missing step, `inf` counted invalid), both
/// see the same samples and gaps, so their final diagnoses of the channel are the same record.
#[test]
fn analyze_and_diagnose_read_the_same_gaps() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/captures/vog4_2min_seed7.csv");
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 30_001, "a header and 30,000 rows");
    lines[1_000] = "inf";
    lines[5_000] = "nan";
    lines[20_000] = "-inf";
    let file = tmp("with_inf.csv");
    std::fs::write(&file, lines.join("\n") + "\n").unwrap();
    let path = file.to_str().unwrap();

    let recs = parse_lines_of(exe().args(["analyze", path, "--tau0", "0.004", "--diagnose"]));
    let summary = recs.iter().rfind(|r| r["type"] == "summary").unwrap();
    // The three missing steps cut the run into four stretches; `inf` and `-inf` are counted.
    assert_eq!(summary["segments"], serde_json::json!([4]));
    assert_eq!(summary["invalid_values"], 2);
    let from_analyze = recs
        .iter()
        .rfind(|r| r["type"] == "diagnosis" && r["final"] == true)
        .expect("a final diagnosis from analyze");

    let from_diagnose = diagnosis(&[path]);
    assert_eq!(from_diagnose["channel"], "g4");
    assert_eq!(&from_diagnose, from_analyze);
}

/// A model file of one channel (`channel`: its keys) in a chamber whose temperature settles
/// from `start_c` to `final_c` with time constant `tc_s` while it cycles `amp_c` degC every
/// `period_s` s (`[start_c, final_c, tc_s, amp_c, period_s]`).
fn chamber_unit(name: &str, tau0_s: f64, chamber: [f64; 5], channel: &str) -> PathBuf {
    let [start_c, final_c, tc_s, amp_c, period_s] = chamber;
    let p = tmp(name);
    std::fs::write(
        &p,
        format!(
            "tau0_s = {tau0_s}\n[temperature]\nstart_c = {start_c}\nfinal_c = {final_c}\n\
             time_constant_s = {tc_s}\nsine_amplitude_c = {amp_c}\nsine_period_s = {period_s}\n\
             [[channel]]\n{channel}"
        ),
    )
    .unwrap();
    p
}

/// The 25 Hz flicker-dominated gyro of the chamber tests (rad), its channel's lines before its
/// temperature coefficient or effects.
const GYRO25: &str = "name = \"g\"\nunit = \"rad\"\nN = 1.22e-4\nB = 2.9e-5\nK = 1.0e-6\n\
                      flicker_band_s = [0.04, 1.0e5]\n";

/// 2026 s of the 25 Hz unit `truth` (rad) simulated at `seed` into `name`.
fn chamber_csv(truth: &std::path::Path, name: &str, seed: u64) -> PathBuf {
    let csv = tmp(name);
    let seed = seed.to_string();
    simulate_to(
        truth,
        &["--duration", "2026s", "--seed", &seed, "--format", "csv"],
        &csv,
    );
    csv
}

/// [`chamber_csv`] and its diagnosis.
fn chamber_run(truth: &std::path::Path, name: &str, seed: u64) -> serde_json::Value {
    let csv = chamber_csv(truth, name, seed);
    first_record(exe().arg("diagnose").args([
        csv.to_str().unwrap(),
        "--tau0",
        "0.04",
        "--unit",
        "rad",
    ]))
}

/// [`chamber_csv`] at `seed` into `STEM.csv`, diagnosed into `STEM.jsonl` and reported into
/// `STEM.html`: the diagnosis record and the report's text.
fn chamber_report(truth: &std::path::Path, stem: &str, seed: u64) -> (serde_json::Value, String) {
    let csv = chamber_csv(truth, &format!("{stem}.csv"), seed);
    let (out, html) = (tmp(&format!("{stem}.jsonl")), tmp(&format!("{stem}.html")));
    for f in [&out, &html] {
        let _ = std::fs::remove_file(f);
    }
    stdout_of(
        exe()
            .arg("diagnose")
            .arg(&csv)
            .args(["--tau0", "0.04", "--unit", "rad", "--out"])
            .arg(&out),
    );
    let text = std::fs::read_to_string(&out).unwrap();
    let d = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    stdout_of(exe().arg("report").arg(&out).arg("-o").arg(&html));
    (d, std::fs::read_to_string(&html).unwrap())
}

/// A temperature logged more slowly than the rates (a 1 Hz `temperature_c` beside 100 Hz
/// increments, the other rows empty), or missing at a few rows, is still used: each step
/// without one takes the last known value, and the diagnosis names `temperature` as with the
/// full column. Before, one missing temperature value dropped the whole temperature without
/// a word and a sinusoid was named instead (docs/gap.md, "Temperature"). A 100 Hz MEMS-like
/// gyro (N 0.005 deg/sqrt(s), B 1.4e-3 deg/s), 2 hours, bias 0.005 deg/s per degC while the
/// unit warms from 25 to 45 degC and cycles 1.5 degC every 900 s (seed 9108: coefficient
/// within 3% with the whole column).
#[test]
fn a_temperature_logged_slowly_is_held_between_its_values() {
    let truth = chamber_unit(
        "temp-slow.toml",
        0.01,
        [25.0, 45.0, 2400.0, 1.5, 900.0],
        "name = \"gz\"\nunit = \"deg\"\nN = 5.0e-3\nB = 1.4e-3\nK = 1.4e-5\n\
         flicker_band_s = [0.01, 1.0e5]\ntemperature_coefficient = 0.005\n",
    );
    let full = tmp("temp-slow-full.csv");
    simulate_to(
        &truth,
        &["--duration", "2h", "--seed", "9108", "--format", "csv"],
        &full,
    );
    let text = std::fs::read_to_string(&full).unwrap();
    let mut out = String::with_capacity(text.len());
    for (i, line) in text.lines().enumerate() {
        // The header, then the temperature on every 100th row only (1 Hz).
        let (rate, temp) = line.split_once(',').expect("two columns");
        let keep = i == 0 || (i - 1) % 100 == 0;
        out += &format!("{rate},{}\n", if keep { temp } else { "" });
    }
    let slow = tmp("temp-slow-1hz.csv");
    std::fs::write(&slow, out).unwrap();
    let run = exe()
        .args([
            "diagnose",
            slow.to_str().unwrap(),
            "--tau0",
            "0.01",
            "--unit",
            "deg",
        ])
        .output()
        .unwrap();
    assert!(run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("the temperature is missing at 712800 of 720000 steps"),
        "{err}"
    );
    let d: serde_json::Value =
        serde_json::from_str(String::from_utf8_lossy(&run.stdout).lines().next().unwrap()).unwrap();
    let t = d["effects"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "temperature")
        .unwrap_or_else(|| panic!("no temperature effect: {d}"));
    let c = t["params"]["coefficient"].as_f64().unwrap();
    let (lo, hi) = (
        t["params"]["lo"].as_f64().unwrap(),
        t["params"]["hi"].as_f64().unwrap(),
    );
    assert!((c / 0.005 - 1.0).abs() < 0.1, "coefficient {c}");
    assert!(lo < 0.005 && 0.005 < hi, "[{lo}, {hi}]");
    assert!(
        !d["effects"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["kind"] == "sinusoid"),
        "{d}"
    );
}

/// A temperature found in time is kept on that evidence where the curve does not show it
/// (session 35): a 34-minute 25 Hz MEMS gyro whose bias follows a chamber settling from 22 to
/// 30 degC while cycling 2.5 degC every 1043 s, 7.7e-5 rad/s per degC (a blind check's
/// low-cost gyro, redrawn by the simulator). On seed 2 the coefficient's `|z|` is far above
/// 4 but the curve's gap (1.23) does not fall with it in, and the bookkeeping dropped it: the
/// run was `consistent`. Now it is named with the gap left as it was, its interval covering
/// the truth.
#[test]
fn a_temperature_the_curve_does_not_show_is_kept_on_its_time_domain_evidence() {
    let truth = chamber_unit(
        "temp-kept.toml",
        0.04,
        [22.0, 30.0, 1500.0, 2.5, 1043.0],
        &format!("{GYRO25}temperature_coefficient = 7.7e-5\n"),
    );
    let d = chamber_run(&truth, "temp-kept.csv", 2);
    let effects = d["effects"].as_array().unwrap();
    let t = effects
        .iter()
        .find(|e| e["kind"] == "temperature")
        .unwrap_or_else(|| panic!("no temperature effect: {d}"));
    let (lo, hi) = (
        t["params"]["lo"].as_f64().unwrap(),
        t["params"]["hi"].as_f64().unwrap(),
    );
    assert!(lo < 7.7e-5 && 7.7e-5 < hi, "[{lo}, {hi}]");
    // Kept in time: the gap is the one before it, and never above the base model's.
    let g0 = d["gap_before"].as_f64().unwrap();
    assert_eq!(t["gap_after"].as_f64().unwrap(), g0, "{d}");
    assert_eq!(d["verdict"], "explained", "{d}");
}

/// A chamber that only settles gives the temperature-driven bias a warm-up's shape, `c (T_end +
/// (T_0 - T_end) e^{-t/T})`: the block means cannot tell the two apart, and the diagnosis says
/// so in `alternatives` instead of choosing silently (session 37; docs/gap.md, "Alternatives").
/// The 25 Hz gyro of the test above, 3e-4 rad/s per degC, in a chamber settling from 22 to 30
/// degC over 1500 s without cycling, 2026 s. On seeds 7 and 4 the temperature is named and a
/// warm-up is listed beside it (on 7 the settling's own, amplitude `c (22 - 30)`; on 4 the one
/// fitting the block means best), and the report says it; on seed 1 the warm-up test named a
/// warm-up and the temperature is listed, its interval covering the truth. With the chamber's cycles (2.5 degC every 1043 s, seed 2
/// of the test above) no warm-up is listed: the cycles tell them apart.
#[test]
fn a_temperature_that_only_settles_is_listed_beside_the_warm_up_it_cannot_be_told_from() {
    let channel = GYRO25;
    let settle = chamber_unit(
        "temp-settle.toml",
        0.04,
        [22.0, 30.0, 1500.0, 0.0, 1043.0],
        &format!("{channel}temperature_coefficient = 3.0e-4\n"),
    );
    let kinds = |effects: &serde_json::Value| -> Vec<String> {
        effects
            .as_array()
            .unwrap()
            .iter()
            .map(|e| e["kind"].as_str().unwrap().to_string())
            .collect()
    };
    let param = |e: &serde_json::Value, k: &str| e["params"][k].as_f64().unwrap();

    // The warm-up listed in the temperature's place (the only one), with its parameters.
    let listed_warmup = |d: &serde_json::Value| -> (f64, f64) {
        let alts = d["alternatives"].as_array().unwrap();
        let w = alts
            .iter()
            .find(|a| kinds(&a["effects"]) == ["warmup"])
            .unwrap_or_else(|| panic!("no warm-up listed: {d}"));
        let w = &w["effects"][0];
        (param(w, "amplitude"), param(w, "time_constant"))
    };

    // Seed 7: the temperature named; the curve prefers the warm-up of the settling's own time
    // constant, whose amplitude is `c (22 - 30)`.
    let d = chamber_run(&settle, "temp-settle-7.csv", 7);
    assert_eq!(kinds(&d["effects"]), ["temperature"], "{d}");
    let c = param(&d["effects"][0], "coefficient");
    let (amp, tc) = listed_warmup(&d);
    assert!((tc / 1500.0 - 1.0).abs() < 0.02, "time constant {tc}");
    let expected = c * (22.0 - 30.0);
    assert!(
        (amp / expected - 1.0).abs() < 0.05,
        "amplitude {amp}, c dT {expected}"
    );

    // Seed 4: the temperature named; the curve prefers the warm-up that fits the block means
    // best (1153 s), whose change over the run is that of the temperature-driven bias within
    // the noise (30%); the report says it.
    let (d, page) = chamber_report(&settle, "temp-settle-4", 4);
    assert_eq!(kinds(&d["effects"]), ["temperature"], "{d}");
    let c = param(&d["effects"][0], "coefficient");
    let (amp, tc) = listed_warmup(&d);
    let run_s = 2026.0;
    assert!(tc > 80.0 && tc <= run_s, "time constant {tc}");
    let change = amp * -(-run_s / tc).exp_m1();
    let expected = c * (22.0 - 30.0) * -(-run_s / 1500.0).exp_m1();
    assert!(
        (change / expected - 1.0).abs() < 0.3,
        "change over the run {change}, the temperature's {expected}"
    );
    assert!(
        page.contains("about as well: warm-up drift [amplitude ")
            && page.contains("in place of temperature sensitivity (gap "),
        "the report does not say the alternative"
    );

    // Seed 1: a warm-up named, the temperature listed in its place.
    let d = chamber_run(&settle, "temp-settle-1.csv", 1);
    assert_eq!(kinds(&d["effects"]), ["warmup"], "{d}");
    let t = d["alternatives"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| kinds(&a["effects"]) == ["temperature"])
        .unwrap_or_else(|| panic!("no temperature listed: {d}"));
    let t = &t["effects"][0];
    assert!(param(t, "lo") < 3.0e-4 && 3.0e-4 < param(t, "hi"), "{t}");

    // Cycling: the temperature named, no warm-up listed.
    let cycling = chamber_unit(
        "temp-settle-cycling.toml",
        0.04,
        [22.0, 30.0, 1500.0, 2.5, 1043.0],
        &format!("{channel}temperature_coefficient = 7.7e-5\n"),
    );
    let d = chamber_run(&cycling, "temp-settle-cycling.csv", 2);
    assert!(
        kinds(&d["effects"]).contains(&"temperature".to_string()),
        "{d}"
    );
    assert!(
        d["alternatives"]
            .as_array()
            .unwrap()
            .iter()
            .all(|a| !kinds(&a["effects"]).contains(&"warmup".to_string())),
        "{d}"
    );
}

/// A chamber warming so slowly (22 degC toward 60 with a time constant of 40 000 s: 1.86 degC
/// in the 2026 s run, bent from a straight line by 0.2% of that) that the bias it drives is a
/// rate ramp: no temperature is named, and the record's `temperature_check` says why
/// (`straight`) with an interval that covers the truth (3e-4 rad/s per degC); the report says
/// it in words beside the effects (session 38; before, nothing was said of the temperature).
#[test]
fn a_temperature_that_changes_as_a_straight_line_is_said_not_determined() {
    let ramp = chamber_unit(
        "temp-ramp.toml",
        0.04,
        [22.0, 60.0, 40_000.0, 0.0, 1043.0],
        &format!("{GYRO25}temperature_coefficient = 3.0e-4\n"),
    );
    let (d, page) = chamber_report(&ramp, "temp-ramp-1", 1);
    assert_eq!(d["effects"].as_array().unwrap().len(), 0, "{d}");
    let t = &d["temperature_check"];
    assert_eq!(t["outcome"], "straight", "{t}");
    assert!((t["change_c"].as_f64().unwrap() - 1.86).abs() < 0.02, "{t}");
    let (lo, hi) = (
        t["interval"][0].as_f64().unwrap(),
        t["interval"][1].as_f64().unwrap(),
    );
    assert!(lo < 3.0e-4 && 3.0e-4 < hi, "{t}");
    assert!(
        page.contains("temperature not determined: it changed as a straight line (bend 0.19"),
        "the report does not say why no temperature is named"
    );
}

/// `--holdout` judges a temperature with the held-out file's own temperature column (session
/// 36; before, the temperature's offset was never added on the held-out run and its record
/// always said `carried: false`). The unit of the test above fitted on seed 2, where its
/// temperature is kept in time: held fixed on seed 3 of the same unit it carries (in time, the
/// held-out gap left as it was); on seed 4 of the same unit with no temperature coefficient it
/// does not, and its curve's gap with it in says why (1.5 -> 4.5 through this binary).
#[test]
fn a_temperature_carries_to_a_held_out_run_of_its_unit_and_not_to_another() {
    let unit = |name: &str, coef: &str| {
        chamber_unit(
            name,
            0.04,
            [22.0, 30.0, 1500.0, 2.5, 1043.0],
            &format!("{GYRO25}temperature_coefficient = {coef}\n"),
        )
    };
    let (with, without) = (unit("temp-ho.toml", "7.7e-5"), unit("temp-ho0.toml", "0.0"));
    let run = chamber_csv(&with, "temp-ho-2.csv", 2);
    for (held, carried) in [
        (chamber_csv(&with, "temp-ho-3.csv", 3), true),
        (chamber_csv(&without, "temp-ho0-4.csv", 4), false),
    ] {
        let d = first_record(exe().arg("diagnose").args([
            run.to_str().unwrap(),
            "--holdout",
            held.to_str().unwrap(),
            "--tau0",
            "0.04",
            "--unit",
            "rad",
        ]));
        let h = &d["holdout"];
        let t = h["effects"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["kind"] == "temperature")
            .unwrap_or_else(|| panic!("no held-out temperature: {d}"));
        assert_eq!(t["carried"], carried, "{h}");
        assert_eq!(h["carried"], carried, "{h}");
        let before = h["gap_before"].as_f64().unwrap();
        assert_eq!(h["gap_after"].as_f64().unwrap(), before, "{h}");
        if carried {
            assert_eq!(
                t["gap_after"].as_f64().unwrap(),
                before,
                "kept in time: {h}"
            );
        } else {
            assert!(t["gap_after"].as_f64().unwrap() > 2.0 * before, "{h}");
        }
    }
}

/// The other side of keeping the temperature in time (a review, session 35): the same unit
/// with no temperature coefficient but a sinusoid of its own (1e-4 rad/s every 1300 s) beside
/// the chamber's 1043-s cycle. Over 34 minutes the two are alike, and the coefficient's `|z|`
/// reaches 4-5; the curve's gap does not fall with the temperature in. Kept on time alone at
/// that `|z|` it was named (seeds 2 and 11 of 16); now the time-domain evidence alone must
/// reach twice the threshold (`TEMPERATURE_Z_ALONE`), and it is not named.
#[test]
fn an_unrelated_slow_sinusoid_is_not_named_temperature_on_time_alone() {
    for (seed, phase) in [(2, 4.798), (11, 1.257)] {
        let truth = chamber_unit(
            &format!("temp-sine-{seed}.toml"),
            0.04,
            [22.0, 30.0, 1500.0, 2.5, 1043.0],
            &format!(
                "{GYRO25}sinusoid = {{ amplitude = 1.0e-4, frequency = 0.000769, phase = {phase} }}\n"
            ),
        );
        let d = chamber_run(&truth, &format!("temp-sine-{seed}.csv"), seed);
        assert!(
            !d["effects"]
                .as_array()
                .unwrap()
                .iter()
                .any(|e| e["kind"] == "temperature"),
            "seed {seed}: {d}"
        );
    }
}

/// A uniform draw in [-0.5, 0.5) from a 64-bit LCG (deterministic white noise).
fn uniform(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
}

/// Writes `text` to `p` and diagnoses it as rate samples; the output and its standard error.
fn diagnose_rates(p: &std::path::Path, text: &str) -> (std::process::Output, String) {
    std::fs::write(p, text).unwrap();
    let out = exe()
        .args(["diagnose", p.to_str().unwrap(), "--rate", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    (out, err)
}

/// A recording with a channel that never moves (a stuck or unconnected axis: every rate sample
/// 1.25) and a cell that reads `inf`: the stuck channel is not diagnosed, and the warning says
/// why with its rate (its curve is the rounding of the running sum, which was diagnosed
/// `unexplained` with invented sinusoids and `G` of 3e8 before); the `inf` is counted as a gap
/// and said; the moving channels are diagnosed from the same rows.
#[test]
fn a_stuck_channel_is_said_and_not_diagnosed() {
    let p = tmp("stuck.csv");
    let mut text = String::from("time,g,stuck,h\n");
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    for i in 0..20_000u64 {
        let (a, b) = (uniform(&mut state), uniform(&mut state));
        let h = if i == 777 {
            "inf".to_string()
        } else {
            format!("{b:.6}")
        };
        text += &format!("{:.2},{a:.6},1.25,{h}\n", i as f64 * 0.01);
    }
    let (out, err) = diagnose_rates(&p, &text);
    assert!(
        err.contains("channel stuck") && err.contains("a rate of 1.25 u/s throughout"),
        "{err}"
    );
    assert!(err.contains("1 values infinite"), "{err}");
    let recs = crate::common::pipeline::parse_lines(&out.stdout);
    let chans: Vec<&str> = recs
        .iter()
        .filter(|r| r["type"] == "diagnosis")
        .map(|r| r["channel"].as_str().unwrap())
        .collect();
    assert_eq!(chans, ["g", "h"]);
    // White rate of uniform samples: its curve is the five terms' N alone, sd 1/sqrt(12) per
    // sample of 10 ms, N^2 = sd^2 tau0: N within 5% of sqrt(0.01 / 12) = 0.02887 u/sqrt(s).
    for r in recs.iter().filter(|r| r["type"] == "diagnosis") {
        let n = r["base_coef"][1].as_f64().unwrap();
        assert!((n / (0.01f64 / 12.0).sqrt() - 1.0).abs() < 0.05, "{r}");
    }
}

/// A recording that begins before the unit sends data: white noise of mean 0.5 whose first 10 s
/// are rows of 0 (`g`) or empty cells (`h`), 20 minutes at 100 Hz. Both are `consistent`, with
/// no effect, the white rate within 5% of the closed form; `g`'s zeros are a stuck stretch at 0 s.
/// Before (session 29), both were a warm-up (`g` with bias jumps): the zeros came before the
/// stuck filter's first 1000 pairs, and the first block of the time tests held 24 of its 512
/// samples, its mean's sd 4.6 times a block's.
#[test]
fn a_recording_that_begins_before_the_data_is_not_a_warm_up() {
    let p = tmp("late_start.csv");
    let mut text = String::from("time,g,h\n");
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    for i in 0..120_000u64 {
        let x: f64 = (0..4).map(|_| uniform(&mut state)).sum::<f64>() + 0.5;
        if i < 1000 {
            text += &format!("{:.2},0.000000,\n", i as f64 * 0.01);
        } else {
            text += &format!("{:.2},{x:.6},{x:.6}\n", i as f64 * 0.01);
        }
    }
    let (out, err) = diagnose_rates(&p, &text);
    assert!(err.contains("channel g: 1 stretch(es)"), "{err}");
    let recs = crate::common::pipeline::parse_lines(&out.stdout);
    for c in ["g", "h"] {
        let r = recs
            .iter()
            .find(|r| r["type"] == "diagnosis" && r["channel"] == c)
            .unwrap_or_else(|| panic!("no record of {c}"));
        assert_eq!(r["verdict"], "consistent", "{r}");
        assert_eq!(r["effects"].as_array().map(Vec::len), Some(0), "{r}");
        // Four uniform draws: sd 1/sqrt(3) per 10-ms sample, N = sd sqrt(tau0).
        let n = r["base_coef"][1].as_f64().unwrap();
        assert!((n / (0.01f64 / 3.0).sqrt() - 1.0).abs() < 0.05, "{r}");
        let stuck = &r["stuck"];
        match c {
            "g" => {
                assert_eq!(stuck["stretches"], 1, "{r}");
                assert_eq!(stuck["first_at_s"], 0.0, "{r}");
                assert!(
                    (stuck["seconds"].as_f64().unwrap() - 10.0).abs() < 1e-9,
                    "{r}"
                );
            }
            _ => assert!(stuck.is_null(), "{r}"),
        }
    }
}

/// A channel logged at half the file's rate (a value on every other row, as a merged file of a
/// 100-Hz gyro and a 50-Hz accelerometer has): no curve can be made, and the warning says why
/// with the counts (10000 samples in 10000 stretches) instead of "run too short?"; the
/// full-rate channel beside it is diagnosed.
#[test]
fn a_channel_on_every_other_row_is_said_not_called_short() {
    let p = tmp("half_rate.csv");
    let mut text = String::from("time,g,h\n");
    let mut state: u64 = 0x51f1_5e5d_1234_abcd;
    for i in 0..20_000u64 {
        let x = uniform(&mut state);
        let h = if i % 2 == 0 {
            format!("{x:.6}")
        } else {
            String::new()
        };
        text += &format!("{:.2},{x:.6},{h}\n", i as f64 * 0.01);
    }
    let (out, err) = diagnose_rates(&p, &text);
    assert!(
        err.contains("channel h: diagnose: its 10000 samples come in 10000 stretches"),
        "{err}"
    );
    let recs = crate::common::pipeline::parse_lines(&out.stdout);
    let chans: Vec<&str> = recs
        .iter()
        .filter(|r| r["type"] == "diagnosis")
        .map(|r| r["channel"].as_str().unwrap())
        .collect();
    assert_eq!(chans, ["g"]);
}

/// A channel that froze at 0.37 for 60 s of a 20-minute run, beside the same noise unfrozen:
/// the stretch is found and taken out as a gap (`stuck`: one stretch of 60 s at 600 s), and the
/// frozen channel is diagnosed as its twin (the same white rate within 2%, `consistent`, no
/// effect). Before, the frozen stretch was named three bias jumps (`explained`).
#[test]
fn a_frozen_stretch_is_taken_out_as_a_gap() {
    let p = tmp("frozen.csv");
    let mut text = String::from("time,g,f\n");
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    for i in 0..120_000u64 {
        // The sum of four uniform draws (near-Gaussian white noise, sd 1/sqrt(3)).
        let x: f64 = (0..4).map(|_| uniform(&mut state)).sum();
        let f = if (60_000..66_000).contains(&i) {
            "0.370000".to_string()
        } else {
            format!("{x:.6}")
        };
        text += &format!("{:.2},{x:.6},{f}\n", i as f64 * 0.01);
    }
    let (out, err) = diagnose_rates(&p, &text);
    assert!(err.contains("channel f: 1 stretch(es)"), "{err}");
    let recs = crate::common::pipeline::parse_lines(&out.stdout);
    let rec = |c: &str| {
        recs.iter()
            .find(|r| r["type"] == "diagnosis" && r["channel"] == c)
            .unwrap_or_else(|| panic!("no record of {c}"))
            .clone()
    };
    let (g, f) = (rec("g"), rec("f"));
    assert!(g.get("stuck").is_none(), "{g}");
    let st = &f["stuck"];
    assert_eq!(st["stretches"], 1, "{f}");
    assert!(
        (st["seconds"].as_f64().unwrap() - 60.0).abs() < 0.02,
        "{st}"
    );
    assert!(
        (st["first_at_s"].as_f64().unwrap() - 600.0).abs() < 0.02,
        "{st}"
    );
    for r in [&g, &f] {
        assert_eq!(r["verdict"], "consistent", "{r}");
        assert_eq!(r["effects"].as_array().unwrap().len(), 0, "{r}");
    }
    let n = |r: &serde_json::Value| r["base_coef"][1].as_f64().unwrap();
    assert!((n(&f) / n(&g) - 1.0).abs() < 0.02, "{} vs {}", n(&f), n(&g));
}

/// A held-out run is matched by channel name: one with none of the input's channels is a usage
/// error naming both sets (it used to judge nothing and say nothing: exit 0, no `holdout`).
#[test]
fn a_held_out_run_without_the_input_s_channels_is_a_usage_error() {
    let run = simulate(&model(false), 3, "named_g4.csv");
    let text = std::fs::read_to_string(&run).expect("csv");
    let (head, body) = text.split_once('\n').expect("a header");
    assert!(head.contains("g4"), "{head}");
    let held = tmp("named_g5.csv");
    std::fs::write(&held, format!("{}\n{body}", head.replace("g4", "g5"))).expect("write");
    let out = exe()
        .args(["diagnose", run.to_str().unwrap(), "--holdout"])
        .arg(&held)
        .args(["--tau0", "0.004", "--json"])
        .output()
        .expect("run");
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--holdout") && err.contains("g4") && err.contains("g5"),
        "{err}"
    );
    let line = err
        .lines()
        .find(|l| l.starts_with("allanscope:"))
        .expect("the error line");
    assert!(!line.contains("  "), "{line}");
    assert!(out.stdout.is_empty(), "{out:?}");
}

/// A column of accumulated velocity (the running sum of increments near 0.049 m/s, gravity at
/// 200 Hz) read without `--phase` is said to look like one, with where it went; with `--phase`
/// it is read as the phase it is and nothing is said; its increments are not taken for one.
#[test]
fn a_phase_column_read_as_increments_is_said() {
    let (mut v, mut text, mut incs) = (0.0, String::from("vz\n"), String::from("dvz\n"));
    for i in 0..40_000u64 {
        let d = 0.049 + ((i * 7919 % 1000) as f64 / 1000.0 - 0.5) * 1e-4;
        v += d;
        text += &format!("{v:.9e}\n");
        incs += &format!("{d:.9e}\n");
    }
    let (phase, inc) = (tmp("vz_phase.csv"), tmp("dvz.csv"));
    std::fs::write(&phase, text).unwrap();
    std::fs::write(&inc, incs).unwrap();
    let run_as = |command: &str, path: &std::path::Path, extra: &[&str]| {
        let out = exe()
            .args([
                command,
                path.to_str().unwrap(),
                "--tau0",
                "0.005",
                "--unit",
                "m/s",
            ])
            .args(extra)
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let run = |path: &std::path::Path, extra: &[&str]| run_as("diagnose", path, extra);
    let said = "channel vz: its values move steadily from 4.8950e-2 to 1.9600e3";
    let err = run(&phase, &[]);
    assert!(
        err.matches(said).count() == 1 && err.contains("give --phase if it is one"),
        "{err}"
    );
    assert!(!run(&phase, &["--phase"]).contains("move steadily"));
    assert!(!run(&inc, &[]).contains("move steadily"));
    // `analyze` reads text through the same reader and says it too, once.
    let err = run_as("analyze", &phase, &[]);
    assert_eq!(err.matches(said).count(), 1, "{err}");
    assert!(!run_as("analyze", &phase, &["--phase"]).contains("move steadily"));
}

/// A counter whose step changes from 0.01 to 0.025 deg at row 20 000 of 40 000 (200 Hz, a
/// range switched) is said, with both steps and about when (after the last whole window of
/// 4096 values with the old step, 81.92 s); the same counts at one step say nothing.
#[test]
fn a_step_that_changes_during_the_run_is_said() {
    let (mut switched, mut steady) = (String::from("g\n"), String::from("g\n"));
    let mut x = 1u64;
    for i in 0..40_000u64 {
        // counts -3..=3 from a linear congruential generator (Knuth's MMIX constants)
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let k = ((x >> 33) % 7) as f64 - 3.0;
        let q = if i < 20_000 { 0.01 } else { 0.025 };
        switched += &format!("{}\n", k * q);
        steady += &format!("{}\n", k * 0.01);
    }
    let (a, b) = (tmp("step_switch.csv"), tmp("step_steady.csv"));
    std::fs::write(&a, switched).unwrap();
    std::fs::write(&b, steady).unwrap();
    let run = |path: &std::path::Path| {
        let out = exe()
            .args([
                "diagnose",
                path.to_str().unwrap(),
                "--tau0",
                "0.005",
                "--unit",
                "deg",
            ])
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let err = run(&a);
    let said = "channel g: the values' step changed during the run (";
    assert_eq!(err.matches(said).count(), 1, "{err}");
    assert!(err.contains("(0.0100 -> 0.0250 after about 82 s)"), "{err}");
    assert!(err.contains("judged with one step, 0.0100"), "{err}");
    assert!(!run(&b).contains("step changed"));
    // `analyze --diagnose` reads the same evidence and says it once, with its final records
    // (not with each interim one), in the values' unit: rate samples' steps as rates.
    let analyze = |path: &std::path::Path, extra: &[&str]| {
        let out = exe()
            .arg("analyze")
            .arg(path)
            .args(["--tau0", "0.005", "--diagnose", "--every", "50"])
            .args(extra)
            .output()
            .unwrap();
        assert!(out.status.success());
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let err = analyze(&a, &["--unit", "deg"]);
    assert_eq!(err.matches(said).count(), 1, "{err}");
    assert!(err.contains("(0.0100 -> 0.0250 after about 82 s)"), "{err}");
    let err = analyze(&a, &["--unit", "deg/s", "--rate"]);
    assert!(err.contains("(0.0100 -> 0.0250 after about 82 s)"), "{err}");
    assert!(!analyze(&b, &["--unit", "deg"]).contains("step changed"));
}
