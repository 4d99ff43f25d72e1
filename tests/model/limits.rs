//! Datasheet limits (src/model/limits.rs): the TOML form, unit conversions against docs/theory.md
//! section 2, and verdicts with the fit's intervals on the seed paper's VOG4 and MA4 figures.
#![allow(clippy::needless_range_loop)]

use allanscope::model::aggregate::{aggregate_channels, RunCoefs};
use allanscope::model::fit::{fit, FitOptions};
use allanscope::model::limits::{
    channel_matches, conversion, decide, judge, judge_runs, sd_interval, ChannelFit, Coef,
    LimitSpec, Scope, Verdict,
};
use allanscope::model::units::{datasheet, IncrementUnit};
use serde::Deserialize;

/// Unit factors are products of exact decimal constants: only rounding separates them.
const UNIT_TOL: f64 = 1e-12;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StandLimits {
    limits: Vec<LimitSpec>,
}

const DOC_TOML: &str = r#"
[[limits]]
channel = "g*"
coef = "N"
max = 0.3
unit = "arcsec/sqrt(s)"

[[limits]]
channel = "g4"
coef = "N"
max = 0.005
unit = "deg/sqrt(h)"

[[limits]]
channel = "a4"
coef = "B"
over = "runs_sd"
max = 5e-4
unit = "m/s^2"
"#;

#[test]
fn toml_form_of_the_module_doc() {
    let cfg: StandLimits = toml::from_str(DOC_TOML).expect("parses");
    assert_eq!(cfg.limits.len(), 3);
    assert_eq!(cfg.limits[0].coef, Coef::N);
    assert_eq!(cfg.limits[0].max, Some(0.3));
    assert_eq!(cfg.limits[0].over, Scope::Run);
    assert_eq!(cfg.limits[2].over, Scope::RunsSd);
    assert!(cfg.limits.iter().all(|l| l.problems().is_empty()));
    // Unknown keys and coefficients are rejected; a bound-less or unit-less spec is a problem.
    assert!(toml::from_str::<StandLimits>(
        "[[limits]]\nchannel = \"g4\"\ncoef = \"N\"\nmax = 1\nmaximum = 2\n"
    )
    .is_err());
    assert!(toml::from_str::<StandLimits>("[[limits]]\nchannel = \"g4\"\ncoef = \"X\"\n").is_err());
    let bad: StandLimits =
        toml::from_str("[[limits]]\nchannel = \"g4\"\ncoef = \"N\"\nunit = \"furlong\"\n").unwrap();
    let keys: Vec<&str> = bad.limits[0].problems().iter().map(|p| p.0).collect();
    assert_eq!(keys, ["max", "unit"]);
}

#[test]
fn unit_conversions_match_theory_section_2() {
    // docs/theory.md section 2 and model::units::datasheet: gyro in arcsec, accelerometer in m/s.
    let native = [1.0, 1.0, 1.0, 1.0, 1.0];
    let gyro = datasheet(native, &IncrementUnit::parse("arcsec").unwrap());
    let accel = datasheet(native, &IncrementUnit::parse("m/s").unwrap());
    let coefs = [Coef::Q, Coef::N, Coef::B, Coef::K, Coef::R];
    for i in 0..5 {
        let g = conversion("arcsec", coefs[i], Some(gyro.units[i])).unwrap();
        assert!(
            rel(g, gyro.values[i]) < UNIT_TOL,
            "gyro {}: {g}",
            gyro.units[i]
        );
        let a = conversion("m/s", coefs[i], Some(accel.units[i])).unwrap();
        assert!(
            rel(a, accel.values[i]) < UNIT_TOL,
            "accel {}: {a}",
            accel.units[i]
        );
    }
    // A rate-sampled gyro in deg: N in deg/sqrt(s) times 60 is deg/sqrt(h).
    assert!(
        rel(
            conversion("deg", Coef::N, Some("deg/sqrt(h)")).unwrap(),
            60.0
        ) < UNIT_TOL
    );
    // The native unit and a wrong dimension.
    assert_eq!(conversion("u", Coef::B, None).unwrap(), 1.0);
    assert!(conversion("arcsec", Coef::N, Some("deg/h")).is_err());
    assert!(conversion("u", Coef::N, Some("deg/sqrt(h)")).is_err());
}

#[test]
fn patterns_and_rule() {
    assert!(channel_matches("g*", "g4") && !channel_matches("g*", "a4"));
    assert!(channel_matches("?4", "a4") && !channel_matches("?4", "a44"));
    assert!(channel_matches("a4", "a4") && !channel_matches("a4", "a"));
    assert_eq!(decide("max", 1.0, 0.5, 0.9), Verdict::Pass);
    assert_eq!(decide("max", 1.0, 0.5, 1.1), Verdict::Undecided);
    assert_eq!(decide("max", 1.0, 1.1, 1.3), Verdict::Fail);
    assert_eq!(decide("min", 1.0, 1.1, 1.3), Verdict::Pass);
    assert_eq!(decide("min", 1.0, 0.5, 0.9), Verdict::Fail);
}

#[test]
fn vog4_arw_against_its_datasheet() {
    // The seed paper's VOG4 means (the seed paper's table 2 (docs/theory.md section 6); Q = LSB 0.004/sqrt(12)) as an exact 3-hour
    // curve at tau0 = 4 ms: the fit returns N = 0.254 arcsec/sqrt(s) with its 95% interval, which
    // lies well inside the datasheet's 0.3 (the seed paper, docs/theory.md section 6) and straddles 0.254 itself.
    let truth = [0.004 / 12f64.sqrt(), 0.254, 0.225, 1.826e-2, 0.891e-4];
    let tau0 = 0.004;
    let n = (3.0 * 3600.0 / tau0) as usize;
    let pts = crate::common::fit::model_curve(truth, tau0, n, n / 4);
    let f = fit(&pts, &FitOptions::default()).unwrap();
    let e = f.coef[1];
    assert!(
        e.lo < 0.254 && 0.254 < e.hi && e.hi < 0.3,
        "N interval [{}, {}]",
        e.lo,
        e.hi
    );
    let spec = |max: f64, unit: &str| LimitSpec {
        channel: "g*".into(),
        coef: Coef::N,
        max: Some(max),
        min: None,
        unit: Some(unit.into()),
        over: Scope::Run,
        origin: None,
    };
    let fits = [ChannelFit {
        channel: "g4",
        unit: "arcsec",
        fit: Some(&f),
    }];
    let j = judge(&[spec(0.3, "arcsec/sqrt(s)")], &fits);
    assert_eq!(j.results[0].verdict, Verdict::Pass);
    assert_eq!(j.pass, Some(true));
    // 0.3 arcsec/sqrt(s) is 0.005 deg/sqrt(h): the same verdict in datasheet units, reported in them.
    let j = judge(&[spec(0.005, "deg/sqrt(h)")], &fits);
    let r = &j.results[0];
    assert_eq!(r.verdict, Verdict::Pass);
    assert!(rel(r.value.unwrap(), 0.254 / 60.0) < 1e-9);
    let j = judge(&[spec(0.254, "arcsec/sqrt(s)")], &fits);
    assert_eq!((j.results[0].verdict, j.pass), (Verdict::Undecided, None));
    let j = judge(&[spec(0.2, "arcsec/sqrt(s)")], &fits);
    assert_eq!((j.results[0].verdict, j.pass), (Verdict::Fail, Some(false)));
    // A limit on a channel that is not there is reported, not dropped.
    let mut s = spec(0.3, "arcsec/sqrt(s)");
    s.channel = "x*".into();
    let j = judge(&[s], &fits);
    assert_eq!((j.results[0].verdict, j.pass), (Verdict::Invalid, None));
    // The summary's field: [{channel, coef, limit, value, lo, hi, verdict}].
    let j = judge(&[spec(0.3, "arcsec/sqrt(s)")], &fits);
    let v = serde_json::to_value(&j.results[0]).unwrap();
    for key in ["channel", "coef", "limit", "value", "lo", "hi", "verdict"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    assert_eq!(v["verdict"], "pass");
    // The summary's typed `limits` write the bytes the untyped records wrote (each result a
    // JSON map, keys in alphabetical order, `note` only when there is one), for a pass and
    // for an invalid limit with its note.
    let mut s = spec(0.3, "arcsec/sqrt(s)");
    s.channel = "x*".into();
    let both = judge(&[spec(0.3, "arcsec/sqrt(s)"), s], &fits);
    assert!(both.results.iter().any(|r| r.note.is_some()));
    for r in &both.results {
        let typed = serde_json::to_string(r).unwrap();
        let untyped = serde_json::to_string(&serde_json::to_value(r).unwrap()).unwrap();
        assert_eq!(typed, untyped);
    }
}

#[test]
fn run_to_run_limits_on_table_2() {
    // sd interval with n = 3: chi-squared with 2 dof has quantiles -2 ln(1 - p), so the interval
    // is sd * sqrt(2 / (-2 ln 0.025)) .. sd * sqrt(2 / (-2 ln 0.975)).
    let (lo, hi) = sd_interval(1.0, 3).unwrap();
    assert!(rel(lo, (1.0 / -(0.025f64.ln())).sqrt()) < 1e-9);
    assert!(rel(hi, (1.0 / -(0.975f64.ln())).sqrt()) < 1e-9);
    // MA4's B runs 0.294, 0.436, 0.477 (1e-4 m/s^2): sd 0.096e-4, upper bound 0.096e-4 * 6.29,
    // within the datasheet's run-to-run 5e-4 m/s^2 (the seed paper, docs/theory.md section 6): pass.
    let run = |b: f64, n: Option<f64>| {
        vec![
            RunCoefs {
                channel: "a4".into(),
                unit: "m/s".into(),
                values: [None, None, Some(b * 1e-4), None, None],
            },
            RunCoefs {
                channel: "g4".into(),
                unit: "arcsec".into(),
                values: [None, n, None, None, None],
            },
        ]
    };
    let runs = [
        run(0.294, Some(0.273)),
        run(0.436, Some(0.210)),
        run(0.477, Some(0.278)),
    ];
    let agg = aggregate_channels(&runs).unwrap();
    let specs: Vec<LimitSpec> = toml::from_str::<StandLimits>(
        r#"
[[limits]]
channel = "a4"
coef = "B"
over = "runs_sd"
max = 5e-4
unit = "m/s^2"

[[limits]]
channel = "g4"
coef = "N"
over = "runs_mean"
max = 0.3
"#,
    )
    .unwrap()
    .limits;
    let j = judge_runs(&specs, &agg);
    assert_eq!(j.results.len(), 2);
    let b = &j.results[0];
    assert_eq!(b.verdict, Verdict::Pass);
    assert!(b.hi.unwrap() < 6.1e-5 && b.hi.unwrap() > 5.9e-5, "{b:?}");
    // VOG4's N over its three runs: mean 0.254, Student interval 0.254 +- 4.303 * 0.038 / sqrt(3)
    // = [0.160, 0.348], which straddles 0.3: undecided (the paper's 1.96 interval would pass).
    let n = &j.results[1];
    assert_eq!(n.verdict, Verdict::Undecided);
    assert!((n.hi.unwrap() - 0.348).abs() < 2e-3, "{n:?}");
    assert_eq!(j.pass, None);
    // Per-run judging ignores run-to-run specs.
    assert!(judge(&specs, &[]).results.is_empty());
}
