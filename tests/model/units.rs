//! Datasheet units of every increment unit the tool accepts, against hand computations, and the
//! IEEE 952 read-outs (model::readout) of simulated runs against the closed forms of docs/theory.md
//! section 2, through the `fit` record `analyze` writes.

use allanscope::model::units::{
    datasheet, datasheet_units, increment_unit_label, IncrementUnit, SensorKind,
};
use serde_json::Value;

/// Relative tolerance of a hand computation done with rounded decimal constants below (they
/// carry 10 or more significant digits).
const HAND_REL: f64 = 1e-9;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= HAND_REL * b.abs()
}

/// Native coefficients all 1 (u, u/sqrt(s), u/s, u/s/sqrt(s), u/s^2) in datasheet units, by
/// hand: a unit of `d` deg is `3600 d` arcsec; `1/sqrt(s) = 60/sqrt(h)`; `1/s = 3600/h`.
#[test]
fn every_angle_unit_against_hand_computation() {
    // d = the unit in degrees: deg 1, rad 180/pi = 57.29577951308232, mrad 0.05729577951308232,
    // arcsec 1/3600.
    let cases: [(&str, [f64; 5]); 4] = [
        ("deg", [3600.0, 60.0, 3600.0, 216_000.0, 12_960_000.0]),
        (
            "rad",
            [
                206_264.806_247_096_36,
                3_437.746_770_784_939,
                206_264.806_247_096_36,
                12_375_888.374_825_78,
                742_553_302.489_547,
            ],
        ),
        (
            "mrad",
            [
                206.264_806_247_096_36,
                3.437_746_770_784_939,
                206.264_806_247_096_36,
                12_375.888_374_825_78,
                742_553.302_489_547,
            ],
        ),
        ("arcsec", [1.0, 1.0 / 60.0, 1.0, 60.0, 3600.0]),
    ];
    for (unit, want) in cases {
        let u = IncrementUnit::parse(unit).unwrap();
        assert_eq!(u.kind, SensorKind::Gyro, "{unit}");
        let d = datasheet([1.0; 5], &u);
        assert_eq!(
            d.units,
            ["arcsec", "deg/sqrt(h)", "deg/h", "deg/h/sqrt(h)", "deg/h^2"]
        );
        for (i, (got, want)) in d.values.iter().zip(want).enumerate() {
            assert!(close(*got, want), "{unit} {i}: {got} vs {want}");
        }
    }
}

#[test]
fn every_velocity_unit_against_hand_computation() {
    // d = the unit in m/s: m/s 1, ft/s 0.3048, g (g*s) 9.80665, mg 9.80665e-3; micro-g is
    // 9.80665e-6 m/s^2 (standard gravity), so 1 m/s^2 = 101971.6212977928 micro-g.
    let ug = 101_971.621_297_792_8;
    let cases: [(&str, [f64; 5]); 4] = [
        ("m/s", [1.0, 60.0, ug, 60.0 * ug, 3600.0 * ug]),
        (
            "ft/s",
            [
                0.3048,
                18.288,
                31_080.950_171_567_25,
                1_864_857.010_294_035,
                111_891_420.617_642_1,
            ],
        ),
        ("g", [9.80665, 588.399, 1e6, 6e7, 3.6e9]),
        ("mg", [9.80665e-3, 0.588_399, 1e3, 6e4, 3.6e6]),
    ];
    for (unit, want) in cases {
        let u = IncrementUnit::parse(unit).unwrap();
        assert_eq!(u.kind, SensorKind::Accel, "{unit}");
        let d = datasheet([1.0; 5], &u);
        assert_eq!(d.units, datasheet_units(SensorKind::Accel));
        for (i, (got, want)) in d.values.iter().zip(want).enumerate() {
            assert!(close(*got, want), "{unit} {i}: {got} vs {want}");
        }
    }
    assert_eq!(IncrementUnit::parse("g*s"), IncrementUnit::parse("g"));
    assert_eq!(IncrementUnit::parse("furlong"), None);
}

fn run_analyze(tag: &str, model: &str, duration: &str, extra: &[&str]) -> Vec<Value> {
    let m = crate::common::tmp_in(tag, "model.toml");
    std::fs::write(&m, model).unwrap();
    let csv = crate::common::tmp_in(tag, "sim.csv");
    let _ = std::fs::remove_file(&csv);
    let st = crate::common::exe()
        .args([
            "simulate",
            "--model",
            m.to_str().unwrap(),
            "--duration",
            duration,
        ])
        .args([
            "--seed",
            "7",
            "--format",
            "csv",
            "-o",
            csv.to_str().unwrap(),
        ])
        .status()
        .unwrap();
    assert!(st.success());
    let out = crate::common::exe()
        .args(["analyze", csv.to_str().unwrap(), "--tau0", "0.01"])
        .args(extra)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn final_fit(recs: &[Value]) -> &Value {
    recs.iter()
        .find(|r| r["type"] == "fit" && r["final"] == true)
        .expect("a final fit")
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// A gyro in deg: white rate N and rate random walk K (crossing at tau = sqrt(3) N / K = 5 s),
/// 40 minutes at 100 Hz. The ARW read-out (the -1/2 line at 1 s) and the RRW read-out (the +1/2
/// line at 3 s) against the simulated N and K; the fit's datasheet block (value, lo, hi) against
/// `coef` times the hand factors (N: 60 deg/sqrt(h) per deg/sqrt(s); K: 216000).
#[test]
fn readouts_and_datasheet_of_a_simulated_gyro() {
    let (n, k) = (0.01, 0.01 * 3f64.sqrt() / 5.0);
    let model =
        format!("rate_hz = 100.0\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = {n}\nK = {k}\n");
    let recs = run_analyze("readout-gyro", &model, "40min", &["--unit", "deg"]);
    let fit = final_fit(&recs);
    let ro = &fit["readouts"];
    let arw = &ro["arw"];
    // Where the white term dominates 10-fold and more, sigma(1 s) = N (closed form); the 95%
    // interval of the point read contains it, and the estimate lies within 5% (edf ~ 1e4 at 1 s).
    assert!(f(&arw["lo"]) <= n && n <= f(&arw["hi"]), "{arw}");
    assert!((f(&arw["value"]) / n - 1.0).abs() < 0.05, "{arw}");
    assert_eq!(arw["unit"], "deg/sqrt(s)");
    assert!((f(&arw["datasheet"]["value"]) - 60.0 * f(&arw["value"])).abs() < 1e-12);
    assert_eq!(arw["datasheet"]["unit"], "deg/sqrt(h)");
    // sigma_K(tau) = K sqrt(tau / 3): the +1/2 line read at 3 s is K. The point read lies where
    // K dominates, but N still adds N^2/tau there (at 8x the crossing, 1/8 of the variance), so
    // the read-out is high by at most 1/8 in variance: within [K, 1.07 K] * its noise.
    let rrw = &ro["rrw"];
    assert!(f(&rrw["tau"]) > 5.0, "{rrw}");
    assert!(f(&rrw["lo"]) <= 1.07 * k && k <= f(&rrw["hi"]), "{rrw}");
    assert_eq!(rrw["datasheet"]["unit"], "deg/h/sqrt(h)");
    // The datasheet block: value, lo and hi of N and K by the hand factors.
    for (c, factor, unit) in [
        ("N", 60.0, "deg/sqrt(h)"),
        ("K", 216_000.0, "deg/h/sqrt(h)"),
    ] {
        let (d, nat) = (&fit["datasheet"][c], &fit["coef"][c]);
        assert_eq!(d["unit"], unit);
        for key in ["value", "lo", "hi"] {
            assert!(
                (f(&d[key]) / (factor * f(&nat[key])) - 1.0).abs() < HAND_REL,
                "{c} {key}: {d} vs {nat}"
            );
        }
    }
    // The fitted N agrees with the read-out within their intervals.
    assert!(f(&fit["coef"]["N"]["lo"]) <= f(&arw["hi"]));
    // No flicker: the minimum is where N and K meet, and the record says the bias-instability
    // read-out is no flicker floor (the fitted flicker is a small share of the variance there;
    // a true share of 0, up to the fit's noise).
    let bi = &ro["bias_instability"];
    assert!(f(&bi["flicker_share"]) < 0.3, "{bi}");
}

/// An accelerometer in m/s: white rate N and flicker B, with K so the curve has a minimum. The
/// bias instability read-out is the curve's minimum over sqrt(2 ln2/pi) = 0.6643; the closed
/// form at that tau is sqrt(N^2/tau + 0.4413 B^2 + K^2 tau/3) (docs/theory.md section 2), and its
/// 95% interval must contain the closed form's value divided by 0.6643. Datasheet: micro-g.
#[test]
fn bias_instability_readout_of_a_simulated_accelerometer() {
    let (n, b, k) = (1e-4, 2e-5, 2e-7);
    let model = format!(
        "rate_hz = 100.0\n[[channel]]\nname = \"ax\"\nunit = \"m/s\"\nN = {n}\nB = {b}\nK = {k}\n"
    );
    let recs = run_analyze("readout-accel", &model, "40min", &["--unit", "m/s"]);
    let fit = final_fit(&recs);
    let bi = &fit["readouts"]["bias_instability"];
    let tau = f(&bi["tau"]);
    let c = 2.0 * std::f64::consts::LN_2 / std::f64::consts::PI;
    let closed = (n * n / tau + c * b * b + k * k * tau / 3.0).sqrt() / c.sqrt();
    assert!(
        f(&bi["lo"]) <= closed && closed <= f(&bi["hi"]),
        "{bi} vs {closed}"
    );
    // The floor is B itself within the N and K contributions at the minimum (< 30% here).
    assert!((f(&bi["value"]) / b - 1.0).abs() < 0.3, "{bi}");
    assert_eq!(bi["unit"], "m/s/s");
    // The flicker's share of the variance at the read-out's tau, against the closed form with
    // the true terms (0.83 at 328 s; the fit's share is noisier than the curve, 0.59 on this
    // seed): a floor, read as B, not as a bound (records::FLICKER_FLOOR_SHARE, 0.5).
    let share = c * b * b / (n * n / tau + c * b * b + k * k * tau / 3.0);
    assert!(
        (f(&bi["flicker_share"]) - share).abs() < 0.3,
        "{bi} vs {share}"
    );
    assert!(f(&bi["flicker_share"]) >= 0.5, "{bi}");
    assert_eq!(bi["datasheet"]["unit"], "micro-g");
    assert!((f(&bi["datasheet"]["value"]) / (f(&bi["value"]) / 9.80665e-6) - 1.0).abs() < HAND_REL);
}

/// `--rate --unit deg/s`: the increment unit is deg, so records say `deg` (curves in deg/s, not
/// "deg/s/s") and the datasheet is in deg/sqrt(h).
#[test]
fn rate_unit_names_the_increment() {
    assert_eq!(increment_unit_label("deg/s", true), "deg");
    let csv = crate::common::tmp_in("rate-unit", "rate.csv");
    let mut text = String::from("gz\n");
    for i in 0..4000u32 {
        // A deterministic zigzag of rates (deg/s): enough for a fit record.
        text.push_str(&format!("{}\n", ((i * 7919) % 101) as f64 / 100.0 - 0.5));
    }
    std::fs::write(&csv, text).unwrap();
    let out = crate::common::exe()
        .args(["analyze", csv.to_str().unwrap(), "--tau0", "0.01", "--rate"])
        .args(["--unit", "deg/s"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let recs: Vec<Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let curve = recs.iter().find(|r| r["type"] == "curve").unwrap();
    assert_eq!(curve["unit"], "deg");
    let fit = final_fit(&recs);
    assert_eq!(fit["datasheet"]["N"]["unit"], "deg/sqrt(h)");
}

/// An accelerometer counted in mg: its increment is mg*s, so N reads in mg*sqrt(s) (mg/sqrt(Hz))
/// and the flicker floor in mg, not "mg/sqrt(s)" and "mg/s". The read-out of N lies within 5%
/// of the simulated value and its datasheet figure is N * 9.80665e-3 * 60 m/s/sqrt(h).
#[test]
fn an_accelerometer_in_mg_reads_in_mg_seconds() {
    let n = 0.08;
    let model = format!("rate_hz = 100.0\n[[channel]]\nname = \"ax\"\nunit = \"mg\"\nN = {n}\n");
    let recs = run_analyze("readout-mg", &model, "20min", &["--unit", "mg"]);
    let fit = final_fit(&recs);
    let arw = &fit["readouts"]["arw"];
    assert_eq!(arw["unit"], "mg*sqrt(s)");
    assert!((f(&arw["value"]) / n - 1.0).abs() < 0.05, "{arw}");
    let si = f(&arw["value"]) * 9.80665e-3 * 60.0;
    assert!(
        (f(&arw["datasheet"]["value"]) / si - 1.0).abs() < HAND_REL,
        "{arw}"
    );
    assert_eq!(arw["datasheet"]["unit"], "m/s/sqrt(h)");
}
