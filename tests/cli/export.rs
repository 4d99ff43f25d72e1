//! `export`: one simulated unit (a gyro in deg, an accelerometer in m/s, 100 Hz) analyzed, then
//! exported to every format; each number checked against the conversion done by hand from the
//! fit record (docs/export.md), and the Kalibr and OpenVINS files parsed as YAML with the keys
//! those tools read.

use serde_json::Value;
use yaml_rust2::YamlLoader;

use crate::common;

/// Relative tolerance of a conversion by hand against the file's printed number (`{:e}` prints
/// the shortest exact representation, so only the hand arithmetic's rounding is left).
const REL: f64 = 1e-12;

/// Writes the results of the simulated unit once per test process; returns its path.
fn results() -> std::path::PathBuf {
    static ONCE: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    ONCE.get_or_init(make_results).clone()
}

fn make_results() -> std::path::PathBuf {
    let res = common::tmp_in("export", "results.jsonl");
    let model = common::tmp_in("export", "model.toml");
    std::fs::write(
        &model,
        "rate_hz = 100.0\n\
         [[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = 0.005\nB = 0.002\nK = 2e-4\n\
         [[channel]]\nname = \"ax\"\nunit = \"m/s\"\nN = 1e-3\nB = 2e-4\nK = 2e-5\n",
    )
    .unwrap();
    let csv = common::tmp_in("export", "sim.csv");
    let _ = std::fs::remove_file(&csv);
    let st = common::exe()
        .args([
            "simulate",
            "--model",
            model.to_str().unwrap(),
            "--duration",
            "20min",
        ])
        .args([
            "--seed",
            "3",
            "--format",
            "csv",
            "-o",
            csv.to_str().unwrap(),
        ])
        .status()
        .unwrap();
    assert!(st.success());
    let tmp = res.with_extension("part");
    let _ = std::fs::remove_file(&tmp);
    let st = common::exe()
        .args(["analyze", csv.to_str().unwrap(), "--tau0", "0.01"])
        .args(["--unit", "deg", "--out", tmp.to_str().unwrap()])
        .status()
        .unwrap();
    assert!(st.success());
    // The accelerometer's unit: analyze labels every text column with one --unit, so the
    // accelerometer's records are relabelled m/s here as a stand config would give them.
    let text = std::fs::read_to_string(&tmp).unwrap();
    let fixed: Vec<String> = text
        .lines()
        .map(|l| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            if v["channel"] == "ax" {
                v["unit"] = "m/s".into();
                v.as_object_mut().unwrap().remove("datasheet");
                v.as_object_mut().unwrap().remove("readouts");
            }
            v.to_string()
        })
        .collect();
    std::fs::write(&res, fixed.join("\n") + "\n").unwrap();
    res
}

/// The final `fit` record of channel `ch`.
fn final_fit(res: &std::path::Path, ch: &str) -> Value {
    let text = std::fs::read_to_string(res).unwrap();
    text.lines()
        .rev()
        .map(|l| serde_json::from_str::<Value>(l).unwrap())
        .find(|v| v["type"] == "fit" && v["final"] == true && v["channel"] == ch)
        .unwrap()
}

fn fit_coef(res: &std::path::Path, ch: &str, c: &str) -> f64 {
    let fit = final_fit(res, ch);
    let e = &fit["coef"][c];
    e["value"]
        .as_f64()
        .unwrap_or_else(|| e["hi"].as_f64().unwrap())
}

fn export(to: &str, name: &str, extra: &[&str]) -> (std::process::Output, std::path::PathBuf) {
    let res = results();
    let out = common::tmp_in("export", name);
    let _ = std::fs::remove_file(&out);
    let o = common::exe()
        .args([
            "export",
            res.to_str().unwrap(),
            "--to",
            to,
            "-o",
            out.to_str().unwrap(),
        ])
        .args(extra)
        .output()
        .unwrap();
    (o, out)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= REL * b.abs()
}

#[test]
fn kalibr_yaml_by_hand() {
    let (o, path) = export("kalibr", "imu.yaml", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Kalibr takes N and K only: no warning about B, which it does not hold.
    assert!(
        !String::from_utf8_lossy(&o.stderr).contains("B is not determined"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let res = results();
    let y = &YamlLoader::load_from_str(&std::fs::read_to_string(&path).unwrap()).unwrap()[0];
    let num = |k: &str| y[k].as_f64().unwrap_or_else(|| panic!("{k}: {:?}", y[k]));
    // Gyro in deg: N deg/sqrt(s) * pi/180 = rad/s/sqrt(Hz); K deg/s/sqrt(s) * pi/180 =
    // rad/s^2/sqrt(Hz). Accelerometer in m/s: N and K as they are (m/s^2/sqrt(Hz), m/s^3/sqrt(Hz)).
    let d2r = std::f64::consts::PI / 180.0;
    assert!(close(
        num("gyroscope_noise_density"),
        fit_coef(&res, "gx", "N") * d2r
    ));
    assert!(close(
        num("gyroscope_random_walk"),
        fit_coef(&res, "gx", "K") * d2r
    ));
    assert!(close(
        num("accelerometer_noise_density"),
        fit_coef(&res, "ax", "N")
    ));
    assert!(close(
        num("accelerometer_random_walk"),
        fit_coef(&res, "ax", "K")
    ));
    assert_eq!(num("update_rate"), 100.0);
    assert_eq!(y["rostopic"].as_str(), Some("/imu0"));
    // Simulation truth within a factor: N 0.005 deg/sqrt(s) = 8.727e-5 rad/s/sqrt(Hz).
    assert!((num("gyroscope_noise_density") / (0.005 * d2r) - 1.0).abs() < 0.1);
    // Never overwritten without --force; replaced with it.
    let (again, _) = (
        common::exe()
            .args(["export", res.to_str().unwrap(), "--to", "kalibr"])
            .args(["-o", path.to_str().unwrap()])
            .output()
            .unwrap(),
        (),
    );
    assert_eq!(again.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&again.stderr).contains("--force"));
    let forced = common::exe()
        .args(["export", res.to_str().unwrap(), "--to", "kalibr", "--force"])
        .args(["-o", path.to_str().unwrap()])
        .status()
        .unwrap();
    assert!(forced.success());
}

#[test]
fn openvins_and_vins_by_hand() {
    let res = results();
    let d2r = std::f64::consts::PI / 180.0;
    let (o, path) = export("openvins", "kalibr_imu_chain.yaml", &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&path).unwrap();
    // OpenVINS reads it with OpenCV, whose first line is `%YAML:1.0`; the rest is plain YAML.
    let body = text
        .strip_prefix("%YAML:1.0\n")
        .expect("OpenCV YAML header");
    let y = &YamlLoader::load_from_str(body).unwrap()[0]["imu0"];
    assert!(close(
        y["gyroscope_noise_density"].as_f64().unwrap(),
        fit_coef(&res, "gx", "N") * d2r
    ));
    assert!(close(
        y["accelerometer_random_walk"].as_f64().unwrap(),
        fit_coef(&res, "ax", "K")
    ));
    assert_eq!(y["T_i_b"].as_vec().unwrap().len(), 4);
    // The IMU intrinsics OpenVINS (2.7 on) requires under imu0, as an ideal IMU: identity
    // Tw, R_IMUtoGYRO, Ta, R_IMUtoACC, zero Tg; the model name its configs use.
    let matrix = |k: &str| -> Vec<Vec<f64>> {
        y[k].as_vec()
            .unwrap_or_else(|| panic!("imu0.{k} in\n{text}"))
            .iter()
            .map(|r| {
                r.as_vec()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect()
            })
            .collect()
    };
    let identity = vec![
        vec![1.0, 0.0, 0.0],
        vec![0.0, 1.0, 0.0],
        vec![0.0, 0.0, 1.0],
    ];
    for k in ["Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC"] {
        assert_eq!(matrix(k), identity, "{k}");
    }
    assert_eq!(matrix("Tg"), vec![vec![0.0; 3]; 3]);
    assert_eq!(y["model"].as_str(), Some("kalibr"));
    assert_eq!(y["update_rate"].as_f64(), Some(100.0));
    let (o, path) = export("vins", "vins.yaml", &[]);
    assert!(o.status.success());
    let text = std::fs::read_to_string(&path).unwrap();
    let y = &YamlLoader::load_from_str(text.strip_prefix("%YAML:1.0\n").unwrap()).unwrap()[0];
    assert!(close(
        y["acc_n"].as_f64().unwrap(),
        fit_coef(&res, "ax", "N")
    ));
    assert!(close(
        y["gyr_w"].as_f64().unwrap(),
        fit_coef(&res, "gx", "K") * d2r
    ));
}

#[test]
fn kf_gins_by_hand() {
    let res = results();
    let (o, path) = export(
        "kf-gins",
        "kf-gins.yaml",
        &["--gyro", "gx", "--accel", "ax"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let y = &YamlLoader::load_from_str(&std::fs::read_to_string(&path).unwrap()).unwrap()[0]
        ["imunoise"];
    let first = |k: &str| y[k].as_vec().unwrap()[0].as_f64().unwrap();
    // arw: N deg/sqrt(s) * 60 = deg/sqrt(h); vrw: N m/s/sqrt(s) * 60 = m/s/sqrt(h);
    // gbstd: B deg/s * 3600 = deg/h; abstd: B m/s^2 / 1e-5 = mGal (one channel: all three axes).
    assert!(close(first("arw"), fit_coef(&res, "gx", "N") * 60.0));
    assert!(close(first("vrw"), fit_coef(&res, "ax", "N") * 60.0));
    assert!((first("gbstd") / (fit_coef(&res, "gx", "B") * 3600.0) - 1.0).abs() < REL);
    assert!((first("abstd") / (fit_coef(&res, "ax", "B") / 1e-5) - 1.0).abs() < REL);
    assert_eq!(y["arw"].as_vec().unwrap().len(), 3);
    assert!(y["corrtime"].as_f64().unwrap() > 0.0);
    // KF-GINS refuses an imunoise block without the scale-factor keys: present, zero (not
    // measured), and the user is told.
    for k in ["gsstd", "asstd"] {
        let v: Vec<f64> = y[k]
            .as_vec()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(v, [0.0; 3], "{k}");
    }
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("gsstd"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // One channel of each kind where KF-GINS takes three axes: said on each line and warned
    // (a review's unit with a dead gyro axis left out had x's value on all three, unsaid); a
    // B the fit left undetermined is said to be its upper bound on its own line.
    let text = std::fs::read_to_string(&path).unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let line = |k: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with(k))
            .unwrap()
    };
    assert!(
        line("arw:").contains("the largest over gx on every axis"),
        "{text}"
    );
    assert!(
        line("abstd:").contains("the largest over ax on every axis"),
        "{text}"
    );
    assert!(
        err.contains("gx: 1 channel(s) where KF-GINS takes three axes"),
        "{err}"
    );
    for (ch, key) in [("gx", "gbstd:"), ("ax", "abstd:")] {
        let undetermined = final_fit(&res, ch)["coef"]["B"]["value"].is_null();
        assert_eq!(
            line(key).contains("not determined: its upper 95% bound"),
            undetermined,
            "{ch}: {}",
            line(key)
        );
        assert_eq!(
            err.contains(&format!("{ch}: B is not determined")),
            undetermined,
            "{err}"
        );
    }
    // A channel that is not in the file is named.
    let (o, _) = export("kf-gins", "kf-bad.yaml", &["--gyro", "gz"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("gz"));
}

#[test]
fn curves_csv_and_stable32_table() {
    let res = results();
    let (o, path) = export("csv", "curves.csv", &[]);
    assert!(o.status.success());
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("channel,unit,stat,tau_s,sigma,lo,hi,edf,count,alpha")
    );
    // The first avar row of gx equals the curve record's first point.
    let curve: Value = std::fs::read_to_string(&res)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap())
        .find(|v| v["type"] == "curve" && v["final"] == true && v["channel"] == "gx")
        .unwrap();
    let row: Vec<&str> = lines
        .find(|l| l.starts_with("gx,deg,avar,"))
        .unwrap()
        .split(',')
        .collect();
    assert_eq!(
        row[3].parse::<f64>().unwrap(),
        curve["tau"][0].as_f64().unwrap()
    );
    assert_eq!(
        row[4].parse::<f64>().unwrap(),
        curve["sigma"][0].as_f64().unwrap()
    );
    let (o, path) = export("stable32", "table.txt", &[]);
    assert!(o.status.success());
    let table = std::fs::read_to_string(&path).unwrap();
    // The test suite's own Stable32 reader parses it: AF, tau, count, alpha, min, sigma, max.
    assert!(table.contains("# Sigma Type: Overlapping Allan"));
    let rows = common::read_stable32(&path);
    assert!(!rows.is_empty());
    assert_eq!(rows[0].af, 1);
    assert!((rows[0].sigma / curve["sigma"][0].as_f64().unwrap() - 1.0).abs() < 5e-5);
}

/// An IMU format from results without a gyro channel: exit 2, and the message names the input
/// and the channels its fits have, so the user sees why none was taken.
#[test]
fn a_missing_kind_names_the_input_and_its_fits() {
    let text = std::fs::read_to_string(results()).unwrap();
    let accel_only: String = text
        .lines()
        .filter(|l| {
            let v: Value = serde_json::from_str(l).unwrap();
            v["channel"] != "gx"
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let res = common::tmp_in("export", "accel_only.jsonl");
    std::fs::write(&res, accel_only).unwrap();
    let out = common::tmp_in("export", "accel_only.yaml");
    let _ = std::fs::remove_file(&out);
    let o = common::exe()
        .args(["export", res.to_str().unwrap(), "--to", "kalibr", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("accel_only.jsonl: this format needs gyro channels")
            && err.contains("(its fits: ax [m/s])"),
        "{err}"
    );
    let said = err
        .lines()
        .filter(|l| l.starts_with("allanscope: "))
        .count();
    assert_eq!(said, 1, "the error once: {err}");
    assert!(!out.exists());
}

/// `diagnose` writes diagnosis records alone: exporting them is refused (exit 2) with what to
/// run instead, not only "no final fit records".
#[test]
fn diagnose_output_is_refused_with_what_to_run() {
    let res = common::tmp_in("export", "diagnoses.jsonl");
    std::fs::write(
        &res,
        "{\"type\":\"diagnosis\",\"channel\":\"gx\",\"gap_before\":1.0,\"gap_after\":1.0,\
         \"verdict\":\"consistent\",\"regions\":[],\"effects\":[],\"final\":true}\n",
    )
    .unwrap();
    let out = common::tmp_in("export", "from_diagnoses.yaml");
    let _ = std::fs::remove_file(&out);
    for to in ["kalibr", "csv"] {
        let o = common::exe()
            .args(["export", res.to_str().unwrap(), "--to", to])
            .args(["-o", out.to_str().unwrap()])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{to}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("it holds 1 diagnosis record, as `diagnose` writes")
                && err.contains("`allanscope analyze INPUT --out FILE`"),
            "{to}: {err}"
        );
        assert!(!out.exists(), "{to}");
    }
}
