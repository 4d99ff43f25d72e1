//! `diagnose --model-out`: the fitted unit as a model file `simulate --model` reads, and the
//! round trip diagnose -> model file -> simulate -> diagnose giving back the effects and
//! parameters (issue 13, "Close the loop").

use crate::common::{self, exe, first_record, simulate_to, write_vog4_model};
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    common::tmp_in("model-out", name)
}

/// VOG4's terms (the seed paper's table 2 means) with a bias and one hidden effect.
fn model(name: &str, effect: &str) -> PathBuf {
    let p = tmp(name);
    write_vog4_model(&p, &format!("bias = 15.0\n{effect}\n"));
    p
}

/// One hour of `model`'s run.
fn simulate(model: &Path, seed: u64, name: &str) -> PathBuf {
    let out = tmp(name);
    simulate_to(
        model,
        &["--duration", "1h", "--seed", &seed.to_string()],
        &out,
    );
    out
}

/// The diagnosis record of `run`, writing the fitted unit to `model_out`.
fn diagnose(run: &Path, model_out: &Path) -> serde_json::Value {
    let _ = std::fs::remove_file(model_out);
    first_record(
        exe()
            .arg("diagnose")
            .arg(run)
            .args(["--tau0", "0.004", "--unit", "arcsec", "--model-out"])
            .arg(model_out),
    )
}

fn param(d: &serde_json::Value, kind: &str, key: &str) -> f64 {
    let e = d["effects"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == kind)
        .unwrap_or_else(|| panic!("no {kind} in {d}"));
    e["params"][key].as_f64().unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Runs the loop for one hidden effect: truth -> run -> diagnosis 1 -> twin model -> twin run
/// -> diagnosis 2. Returns both records and the twin model file.
fn round_trip(
    tag: &str,
    effect: &str,
    seed: u64,
) -> (serde_json::Value, serde_json::Value, String) {
    let truth = model(&format!("{tag}-truth.toml"), effect);
    let run = simulate(&truth, seed, &format!("{tag}-run.csv"));
    let twin = tmp(&format!("{tag}-twin.toml"));
    let d1 = diagnose(&run, &twin);
    let text = std::fs::read_to_string(&twin).unwrap();
    let twin_run = simulate(&twin, seed + 100, &format!("{tag}-twin.csv"));
    let d2 = diagnose(&twin_run, &tmp(&format!("{tag}-twin2.toml")));
    (d1, d2, text)
}

/// A sinusoid (0.3 arcsec/s at 0.8 Hz): named on the run and on the twin's run, with frequency
/// within 2% and amplitude within 10% of the truth both times (the blind benchmark's q90 errors
/// are 1.6% and 6.5% on 3-hour runs; this run is 1 hour), and the twin's five terms near the
/// truth's. The twin file carries the LSB read off the data (0.004) and the run's mean rate.
#[test]
fn a_sinusoid_survives_the_round_trip() {
    let (d1, d2, text) = round_trip(
        "sin",
        "sinusoid = { amplitude = 0.3, frequency = 0.8, phase = 0.0 }",
        3,
    );
    assert!(text.contains("lsb = 0.004\n"), "{text}");
    assert!(text.contains("[[channel.sinusoid]]"), "{text}");
    for d in [&d1, &d2] {
        assert_eq!(d["verdict"], "explained", "{d}");
        let (a, f) = (
            param(d, "sinusoid", "amplitude"),
            param(d, "sinusoid", "frequency"),
        );
        assert!(rel(f, 0.8) < 0.02, "frequency {f}");
        assert!(rel(a, 0.3) < 0.10, "amplitude {a}");
    }
    // The terms the run did not determine are named at the file's top with the record's
    // values and intervals (session 42); the determined N is not.
    let notes: Vec<&str> = text.lines().filter(|l| l.starts_with("# ")).collect();
    for (i, k) in ["Q", "N", "B", "K", "R"].iter().enumerate() {
        let t = &d1["final_terms"][*k];
        let loose = t["determined"] == false && d1["final_coef"][i].as_f64().unwrap() > 0.0;
        let said = format!(
            "{k} {:.3e} (95% interval [{:.3e}, {:.3e}]",
            d1["final_coef"][i].as_f64().unwrap(),
            t["lo"].as_f64().unwrap(),
            t["hi"].as_f64().unwrap()
        );
        assert_eq!(
            notes
                .iter()
                .any(|l| l.contains("not determined") && l.contains(&said)),
            loose,
            "{k}: {notes:?}"
        );
    }
    assert!(d1["final_terms"]["N"]["determined"] == true);
    // N is the best-determined term: within 3% of the truth on the twin's run.
    let n2 = d2["final_coef"][1].as_f64().unwrap();
    assert!(rel(n2, 0.254) < 0.03, "N {n2}");
    // The bias: the twin's mean rate is the run's (K wanders it by about 0.3 arcsec/s per hour).
    let m = allanscope::sim::SimModel::from_toml_str(&text, Path::new("twin.toml")).unwrap();
    assert!(
        (m.channels[0].bias - 15.0).abs() < 1.5,
        "bias {}",
        m.channels[0].bias
    );
}

/// A Gauss-Markov term (sigma 0.6 arcsec/s, tau_c 1.5 s): named on both runs, parameters within
/// 25% of the truth (as in cli_diagnose.rs), and the twin's within 25% of the first fit's.
#[test]
fn a_gauss_markov_term_survives_the_round_trip() {
    let (d1, d2, text) = round_trip("gm", "gauss_markov = { sigma = 0.6, tau_c = 1.5 }", 8);
    assert!(text.contains("[[channel.gauss_markov]]"), "{text}");
    for d in [&d1, &d2] {
        assert_eq!(d["verdict"], "explained", "{d}");
        let (s, t) = (
            param(d, "gauss_markov", "sigma"),
            param(d, "gauss_markov", "tau_c"),
        );
        assert!(rel(s, 0.6) < 0.25, "sigma {s}");
        assert!(rel(t, 1.5) < 0.25, "tau_c {t}");
    }
    let (s1, s2) = (
        param(&d1, "gauss_markov", "sigma"),
        param(&d2, "gauss_markov", "sigma"),
    );
    assert!(rel(s2, s1) < 0.25, "twin sigma {s2} vs fit {s1}");
}

/// An existing file is never replaced: exit 2 before any input is read, the file untouched.
#[test]
fn an_existing_model_file_is_kept() {
    let p = tmp("exists.toml");
    std::fs::write(&p, "keep me\n").unwrap();
    let out = exe()
        .args([
            "diagnose",
            "/nonexistent-input.csv",
            "--tau0",
            "0.004",
            "--model-out",
        ])
        .arg(&p)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("exists"));
    assert_eq!(std::fs::read_to_string(&p).unwrap(), "keep me\n");
}

/// A unit whose bias follows its temperature (the CSV's `temperature_c` column): the record
/// names `temperature` with the coefficient (0.2 arcsec/s per degC) within 10% and its interval,
/// and the twin file carries the coefficient and a settling profile of the recorded temperature
/// (20 -> 40 degC, time constant 1800 s; the chamber's 5 degC cycling is not in the profile).
#[test]
fn a_temperature_coefficient_survives_the_round_trip() {
    let truth = tmp("temp-truth.toml");
    std::fs::write(
        &truth,
        "rate_hz = 250\n[temperature]\nstart_c = 20.0\nfinal_c = 40.0\ntime_constant_s = 1800.0\n\
         sine_amplitude_c = 5.0\nsine_period_s = 600.0\n[[channel]]\nname = \"g4\"\n\
         unit = \"arcsec\"\nlsb = 0.004\nbias = 15.0\nN = 0.254\nB = 0.225\nK = 1.826e-2\n\
         flicker_band_s = [0.004, 1.0e4]\ntemperature_coefficient = 0.2\n",
    )
    .unwrap();
    let run = simulate(&truth, 4, "temp-run.csv");
    let twin = tmp("temp-twin.toml");
    let d = diagnose(&run, &twin);
    let c = param(&d, "temperature", "coefficient");
    let (lo, hi) = (
        param(&d, "temperature", "lo"),
        param(&d, "temperature", "hi"),
    );
    assert!(rel(c, 0.2) < 0.10, "coefficient {c}");
    assert!(lo < c && c < hi && hi - lo < 0.2, "[{lo}, {hi}]");
    // The same run as a logger writes it, the temperature in degF under `Temp (°F)`: read as
    // the unit's temperature, not a channel, and the same coefficient per degC (session 29:
    // the unit `°F` stopped the run with exit 2).
    let csv = std::fs::read_to_string(&run).unwrap();
    let mut f_text = String::from("g4,Temp (\u{b0}F)\n");
    for line in csv.lines().skip(1) {
        let (g, t) = line.split_once(',').unwrap();
        let t: f64 = t.parse().unwrap();
        f_text += &format!("{g},{:.9}\n", t * 1.8 + 32.0);
    }
    let f_run = tmp("temp-run-degf.csv");
    std::fs::write(&f_run, f_text).unwrap();
    let f = diagnose(&f_run, &tmp("temp-twin-degf.toml"));
    assert_eq!(f["channel"], "g4", "{f}");
    assert!(
        rel(param(&f, "temperature", "coefficient"), c) < 1e-4,
        "{f}"
    );
    // Its unit in a row of units under the header (`board_temp` then `degF`), and in the
    // header of a column the run renames (`--columns "g4,board_temp (°F)=temp"`): read in degF
    // both ways (session 31: the unit was lost to the bare or the new name, read as degC).
    let rows = |head: &str, file: &str| {
        let mut t = String::from(head);
        for line in csv.lines().skip(1) {
            let (g, c) = line.split_once(',').unwrap();
            let c: f64 = c.parse().unwrap();
            t += &format!("{g},{:.9}\n", c * 1.8 + 32.0);
        }
        let p = tmp(file);
        std::fs::write(&p, t).unwrap();
        p
    };
    let u_run = rows("g4,board_temp\narcsec,degF\n", "temp-run-units-row.csv");
    let u = diagnose(&u_run, &tmp("temp-twin-units-row.toml"));
    assert!(
        rel(param(&u, "temperature", "coefficient"), c) < 1e-4,
        "{u}"
    );
    let r_run = rows("g4,board_temp (\u{b0}F)\n", "temp-run-renamed.csv");
    let r = first_record(
        exe()
            .arg("diagnose")
            .arg(&r_run)
            .args(["--tau0", "0.004", "--unit", "arcsec"])
            .args(["--columns", "g4,board_temp (\u{b0}F)=temp"]),
    );
    assert!(
        rel(param(&r, "temperature", "coefficient"), c) < 1e-4,
        "{r}"
    );
    let text = std::fs::read_to_string(&twin).unwrap();
    let m = allanscope::sim::SimModel::from_toml_str(&text, Path::new("twin.toml")).unwrap();
    assert_eq!(m.channels[0].temperature_coefficient, c, "{text}");
    let t = m.temperature.as_ref().expect("a temperature profile");
    assert!(
        (t.final_c - 40.0).abs() < 1.0 && (t.start_c - 20.0).abs() < 2.0,
        "{t:?}"
    );
    // The twin simulates that temperature beside the channel (a settling only: the profile of
    // the model file has no phase for the chamber's cycling, and the settling alone is too weak
    // a regressor to name the coefficient again in one hour; docs/gap.md, "Temperature").
    let twin_run = simulate(&twin, 104, "temp-twin.csv");
    let head = std::fs::read_to_string(&twin_run).unwrap();
    assert!(head.starts_with("g4,temperature_c\n"), "{}", &head[..40]);
}

/// The loop closed within the intervals (issue 13's proof): the twin's truth is the first
/// diagnosis's parameters (what `--model-out` wrote), so the twin's diagnosis must name the
/// same effect and its 95% intervals (`effects[].intervals`) must hold those parameters. A
/// Gauss-Markov term on three seeds and a sinusoid on two (the simulator is deterministic, so
/// the seeds are fixed cases; the coverage over 50 seeds is in docs/gap.md, "Parameter
/// intervals").
#[test]
fn the_twin_gives_back_the_parameters_within_their_intervals() {
    let cases = [
        (
            "gm",
            "gauss_markov = { sigma = 0.6, tau_c = 1.5 }",
            8u64,
            "gauss_markov",
            ["sigma", "tau_c"],
        ),
        (
            "gm",
            "gauss_markov = { sigma = 0.6, tau_c = 1.5 }",
            21,
            "gauss_markov",
            ["sigma", "tau_c"],
        ),
        (
            "gm",
            "gauss_markov = { sigma = 0.6, tau_c = 1.5 }",
            22,
            "gauss_markov",
            ["sigma", "tau_c"],
        ),
        (
            "sin",
            "sinusoid = { amplitude = 0.3, frequency = 0.8, phase = 0.0 }",
            3,
            "sinusoid",
            ["amplitude", "frequency"],
        ),
        (
            "sin",
            "sinusoid = { amplitude = 0.3, frequency = 0.8, phase = 0.0 }",
            23,
            "sinusoid",
            ["amplitude", "frequency"],
        ),
    ];
    for (tag, effect, seed, kind, keys) in cases {
        let (d1, d2, _) = round_trip(&format!("iv-{tag}-{seed}"), effect, seed);
        let e2 = d2["effects"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["kind"] == kind)
            .unwrap_or_else(|| panic!("seed {seed}: the twin's run names no {kind}: {d2}"));
        for key in keys {
            let p1 = param(&d1, kind, key);
            let iv = &e2["intervals"][key];
            let (lo, hi) = (iv[0].as_f64().unwrap(), iv[1].as_f64().unwrap());
            assert!(
                lo <= p1 && p1 <= hi,
                "seed {seed}: {kind}.{key} {p1} of the first run outside the twin's [{lo}, {hi}]"
            );
        }
    }
}

/// `diagnose --ensemble N` (docs/gap.md, "The ensemble band"): on a unit with a Gauss-Markov
/// term (sigma 0.6 arcsec/s, tau_c 1.5 s, one hour), the measured curve leaves the band of 20
/// simulated runs of the five terms alone at most taus (measured: 69% of 61) and stays within
/// the twin's band (with the fitted term) at nearly all (measured: 1 tau of 61); the bands are
/// ordered and bracket the twin's median. `--ensemble 1` is refused (exit 2).
#[test]
fn the_ensemble_band_shows_the_twin_matching() {
    let truth = model(
        "ens-truth.toml",
        "gauss_markov = { sigma = 0.6, tau_c = 1.5 }",
    );
    let run = simulate(&truth, 8, "ens-run.csv");
    let d = first_record(exe().arg("diagnose").arg(&run).args([
        "--tau0",
        "0.004",
        "--unit",
        "arcsec",
        "--ensemble",
        "20",
    ]));
    let e = &d["ensemble"];
    assert_eq!(e["runs"], 20);
    let n = d["model_tau"].as_array().unwrap().len();
    for key in ["measured", "base_lo", "base_hi", "twin_lo", "twin_hi"] {
        assert_eq!(e[key].as_array().unwrap().len(), n, "{key}");
    }
    for i in 0..n {
        let (lo, hi) = (
            e["twin_lo"][i].as_f64().unwrap(),
            e["twin_hi"][i].as_f64().unwrap(),
        );
        assert!(lo > 0.0 && lo < hi, "tau {i}: twin band [{lo}, {hi}]");
    }
    let (ob, ot) = (
        e["outside_base"].as_f64().unwrap(),
        e["outside_twin"].as_f64().unwrap(),
    );
    assert!(ob >= 0.4, "outside the base band at only {ob}");
    assert!(ot <= 0.1, "outside the twin band at {ot}");
    let bad = exe()
        .arg("diagnose")
        .arg(&run)
        .args(["--tau0", "0.004", "--unit", "arcsec", "--ensemble", "1"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
}

/// A twin of rate columns (`time,ax [m/s^2]`, a MEMS logger's file): the model file keeps the
/// channel's name, and `simulate` heads the twin's column by the unit of the increments it
/// writes (`ax [m/s]`), so the twin's run reads back without `--unit` as increments in m/s. Read
/// by the old header it would have been rates, N 1/tau0 = 200 times too large. The twin's N is
/// within 5% of the truth (white rate noise N 1e-3 m/s/sqrt(s), 20 minutes at 200 Hz; the
/// estimate's own spread is about 0.2%).
#[test]
fn a_twin_of_rate_columns_reads_back_as_increments() {
    let n = 1e-3;
    let truth = tmp("rate-truth.toml");
    std::fs::write(
        &truth,
        format!("rate_hz = 200\n[[channel]]\nname = \"ax\"\nunit = \"m/s\"\nN = {n}\n"),
    )
    .unwrap();
    let inc = tmp("rate-inc.csv");
    simulate_to(&truth, &["--duration", "20min", "--seed", "3"], &inc);
    // The logger's file: a time column and the rates (m/s^2) the increments average.
    let mut text = String::from("time,ax [m/s^2]\n");
    for (i, v) in std::fs::read_to_string(&inc)
        .unwrap()
        .lines()
        .skip(1)
        .enumerate()
    {
        let v: f64 = v.parse().unwrap();
        text.push_str(&format!("{:.3},{:e}\n", i as f64 * 0.005, v / 0.005));
    }
    let rates = tmp("rate-run.csv");
    std::fs::write(&rates, text).unwrap();
    let twin = tmp("rate-twin.toml");
    let _ = std::fs::remove_file(&twin);
    let d1 = first_record(
        exe()
            .arg("diagnose")
            .arg(&rates)
            .arg("--model-out")
            .arg(&twin),
    );
    assert_eq!(d1["unit"], "m/s");
    assert!(std::fs::read_to_string(&twin)
        .unwrap()
        .contains("name = \"ax [m/s^2]\""));
    let twin_run = tmp("rate-twin.csv");
    simulate_to(&twin, &["--duration", "20min", "--seed", "4"], &twin_run);
    let head = std::fs::read_to_string(&twin_run).unwrap();
    assert_eq!(head.lines().next(), Some("ax [m/s]"));
    let d2 = first_record(
        exe()
            .arg("diagnose")
            .arg(&twin_run)
            .args(["--tau0", "0.005"]),
    );
    assert_eq!(
        (&d2["channel"], &d2["unit"]),
        (&"ax [m/s]".into(), &"m/s".into())
    );
    let n2 = d2["final_terms"]["N"]["value"].as_f64().unwrap();
    assert!(rel(n2, n) < 0.05, "the twin's N {n2} against {n}");
}

/// `--model-out` in a folder that does not exist is refused at the start (exit 2, the option,
/// the file and the folder named), as `-o` is: before, the whole diagnosis ran and then the
/// model file could not be created (exit 1).
#[test]
fn a_model_out_in_a_missing_folder_is_refused_before_the_diagnosis() {
    let run = tmp("missing-folder.csv");
    let mut text = String::from("gx\n");
    let mut s = 7u64;
    for _ in 0..20_000 {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        text += &format!(
            "{:e}\n",
            ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1e-3
        );
    }
    std::fs::write(&run, text).unwrap();
    let target = tmp("nodir").join("t.toml");
    let out = exe()
        .arg("diagnose")
        .arg(&run)
        .args(["--tau0", "0.004", "--model-out"])
        .arg(&target)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    let expected = format!(
        "--model-out {}: the folder {} does not exist",
        target.display(),
        tmp("nodir").display()
    );
    assert!(err.contains(&expected), "{err}");
    assert!(out.stdout.is_empty(), "diagnosed before the refusal");
    assert!(!tmp("nodir").exists());
}

/// `--model-out` with `--holdout` (session 53): the twin is the unit, so an effect this run
/// showed and the held-out run judged and disowned is left out of it, and the file says so.
/// VOG4 with a sinusoid (0.3 arcsec/s at 0.8 Hz): held out on a run of the same unit it
/// carries and the twin draws it; held out on a run of the unit without it, it does not carry
/// and the twin has no sinusoid.
#[test]
fn an_effect_the_held_out_run_disowns_is_left_out_of_the_twin() {
    let truth = model(
        "ho-truth.toml",
        "sinusoid = { amplitude = 0.3, frequency = 0.8, phase = 0.0 }",
    );
    let clean = model("ho-clean.toml", "");
    let run = simulate(&truth, 3, "ho-run.csv");
    let twin_of = |held: &Path, name: &str| -> (serde_json::Value, String) {
        let out = tmp(name);
        let _ = std::fs::remove_file(&out);
        let d = first_record(
            exe()
                .arg("diagnose")
                .arg(&run)
                .args(["--tau0", "0.004", "--unit", "arcsec", "--holdout"])
                .arg(held)
                .arg("--model-out")
                .arg(&out),
        );
        (d, std::fs::read_to_string(&out).unwrap())
    };
    let carried = |d: &serde_json::Value| {
        d["holdout"]["effects"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["kind"] == "sinusoid")
            .unwrap_or_else(|| panic!("the sinusoid judged: {d}"))["carried"]
            .as_bool()
            .unwrap()
    };
    let note = "left out, found on this run but not carried to the held-out run";
    let same = simulate(&truth, 5, "ho-same.csv");
    let (d, text) = twin_of(&same, "ho-twin-same.toml");
    assert!(rel(param(&d, "sinusoid", "frequency"), 0.8) < 0.02, "{d}");
    assert!(carried(&d), "{d}");
    assert!(text.contains("[[channel.sinusoid]]"), "{text}");
    assert!(!text.contains(note), "{text}");
    let other = simulate(&clean, 4, "ho-clean.csv");
    let (d, text) = twin_of(&other, "ho-twin-clean.toml");
    assert!(rel(param(&d, "sinusoid", "frequency"), 0.8) < 0.02, "{d}");
    assert!(!carried(&d), "{d}");
    assert!(!text.contains("[[channel.sinusoid]]"), "{text}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("# ") && l.contains(note) && l.ends_with(": sinusoid")),
        "{text}"
    );
}
