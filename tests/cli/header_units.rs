//! Text columns whose headers carry their unit in brackets (src/input/header_unit.rs): without
//! `--unit`, `gyro_x (deg/s)` and `acc_x[g]` are rate samples in deg/s and g, and give the same
//! records as the same column read with `--rate --unit deg` (or `g`) told by hand; `dtheta [deg]`
//! is increments in deg. A unit not known, rates mixed with increments, and headers that
//! contradict `--rate` or `--phase` are usage errors (exit 2) naming the column and its header.
//! `--unit` overrides the headers.

use crate::common::{exe, tmp_in};
use std::path::PathBuf;
use std::process::Output;

use allanscope::sink::records::CurveRecord;

/// A file of `header` over 400 rows of three deterministic, unequal columns with a time column
/// first (10 ms steps).
fn file(name: &str, header: &str) -> PathBuf {
    let mut s = format!("{header}\n");
    for i in 0..400 {
        let a = ((i * 37 % 101) as f64 - 50.0) * 1e-3;
        let b = ((i * 53 % 89) as f64 - 44.0) * 2e-3;
        let c = ((i * 29 % 83) as f64 - 41.0) * 5e-4;
        s += &format!("{:.2},{a:e},{b:e},{c:e}\n", i as f64 * 0.01);
    }
    let p = tmp_in("cli_header_units", name);
    std::fs::write(&p, s).unwrap();
    p
}

use crate::common::{analyze_avar as analyze, final_curve_records as curves};

fn curve<'a>(cs: &'a [CurveRecord], channel: &str) -> &'a CurveRecord {
    cs.iter()
        .find(|c| c.channel == channel)
        .unwrap_or_else(|| panic!("no curve of {channel}"))
}

fn usage_error(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
    assert!(out.stdout.is_empty(), "records written before the error");
}

#[test]
fn rates_and_increments_are_read_from_the_headers() {
    let p = file("rates.csv", "time (s),gyro_x (deg/s),acc_x[g],dtheta [deg]");
    // Two rate columns and one of increments: refused, naming both.
    usage_error(
        &analyze(&p, &[]),
        &["column 2 `gyro_x (deg/s)` holds rates and column 4 `dtheta [deg]` increments"],
    );
    // The rates alone.
    let picked = ["--columns", "gyro_x (deg/s),acc_x[g]"];
    let out = analyze(&p, &picked);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        err.contains("no --unit: units from the column headers: `gyro_x (deg/s)` rates in deg/s (unit deg), `acc_x[g]` rates in g (unit g); read as rate samples, as --rate (--unit U overrides the headers)"),
        "{err}"
    );
    let read = curves(&out);
    let gyro = curve(&read, "gyro_x (deg/s)");
    let acc = curve(&read, "acc_x[g]");
    assert_eq!((gyro.unit.as_str(), acc.unit.as_str()), ("deg", "g"));
    // Told by hand: the same numbers to the last bit.
    let told = |column: &str, unit: &str| {
        curves(&analyze(
            &p,
            &["--columns", column, "--rate", "--unit", unit],
        ))
        .remove(0)
    };
    assert_eq!(*gyro, told("gyro_x (deg/s)", "deg"));
    assert_eq!(*acc, told("acc_x[g]", "g"));
    // Rate samples, not increments: at m = 1, sigma of rate samples y is that of the
    // increments y * tau0 divided by tau0 (both in u/s), so read as increments it would be
    // 100 times larger at tau0 = 10 ms.
    let out = analyze(&p, &["--columns", "gyro_x (deg/s)", "--unit", "deg"]);
    let as_increments = curves(&out).remove(0);
    let ratio = as_increments.sigma[0] / gyro.sigma[0];
    assert!((ratio - 100.0).abs() < 1e-9, "{ratio}");
    // Told so: the header says rates and the options read increments (session 40: a review's
    // MEMS gyro came out 200 times too noisy with an INFO line only).
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("WARN")
            && err.contains(
                "column `gyro_x (deg/s)` holds rate samples by its header unit `deg/s`, but the \
                 options read increments"
            )
            && err.contains("add --rate if they are rates"),
        "{err}"
    );
    let told_rate = analyze(
        &p,
        &["--columns", "gyro_x (deg/s)", "--rate", "--unit", "deg"],
    );
    assert!(!String::from_utf8_lossy(&told_rate.stderr).contains("WARN"));

    // The increments alone: as `--unit deg`; `--phase` takes them too.
    let inc = ["--columns", "dtheta [deg]"];
    let read = curves(&analyze(&p, &inc));
    let mut told = inc.to_vec();
    told.extend(["--unit", "deg"]);
    assert_eq!(read, curves(&analyze(&p, &told)));
    assert_eq!(read[0].unit, "deg");
    let mut phase = inc.to_vec();
    phase.push("--phase");
    assert_eq!(curves(&analyze(&p, &phase))[0].unit, "deg");
}

/// A FOG's rate in deg/h is a rate in arcsec/s (1 deg/h turns 1 arcsec in 1 s): the records of
/// `wx [deg/h]` are those of the same column read with `--rate --unit arcsec`, in arcsec; a
/// navigation accelerometer's `[ug]` is read as `--rate --unit ug`, and its B comes out in ug
/// as that of `[mg]` in mg scaled by 1000.
#[test]
fn deg_per_hour_and_micro_g() {
    let p = file("fog.csv", "t,wx [deg/h],az [ug],ay [mg]");
    let out = analyze(&p, &["--columns", "wx [deg/h]"]);
    let read = curves(&out);
    assert_eq!(read[0].unit, "arcsec");
    let told = curves(&analyze(
        &p,
        &["--columns", "wx [deg/h]", "--rate", "--unit", "arcsec"],
    ));
    assert_eq!(read, told);
    let out = analyze(&p, &["--columns", "az [ug]"]);
    assert_eq!(curves(&out)[0].unit, "ug");
    let told = curves(&analyze(
        &p,
        &["--columns", "az [ug]", "--rate", "--unit", "ug"],
    ));
    assert_eq!(curves(&out), told);
}

/// Kalibr's imu0.csv (`timestamp` in ns, `omega_*` in rad/s, `alpha_*` in m/s^2, no unit in
/// the names): read in those units, as `--rate --unit rad` (and `m/s`) told by hand; the same
/// names in a header that is not Kalibr's whole carry no unit.
#[test]
fn kalibr_imu_csv_is_in_its_fixed_units() {
    let rows = |header: &str| {
        let mut s = format!("{header}\n");
        for i in 0..400u64 {
            let w = ((i * 37 % 101) as f64 - 50.0) * 1e-3;
            let a = ((i * 53 % 89) as f64 - 44.0) * 2e-3;
            let ns = 1_385_030_208_736_607_488u64 + i * 5_000_000;
            s += &format!("{ns},{w:e},{:e},{:e},{:e},{:e},{a:e}\n", -w, 2.0 * w, a, -a);
        }
        s
    };
    let p = tmp_in("cli_header_units", "imu0.csv");
    std::fs::write(
        &p,
        rows("timestamp,omega_x,omega_y,omega_z,alpha_x,alpha_y,alpha_z"),
    )
    .unwrap();
    let out = analyze(&p, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("`omega_x` rates in rad/s, by Kalibr's imu0.csv (unit rad)"),
        "{err}"
    );
    let read = curves(&out);
    assert_eq!(read.len(), 6);
    let told_w = curves(&analyze(
        &p,
        &["--columns", "omega_x", "--rate", "--unit", "rad"],
    ));
    assert_eq!(curve(&read, "omega_x"), &told_w[0]);
    let told_a = curves(&analyze(
        &p,
        &["--columns", "alpha_z", "--rate", "--unit", "m/s"],
    ));
    assert_eq!(curve(&read, "alpha_z"), &told_a[0]);
    // Without the alpha columns the header is not Kalibr's: no unit, increments in u (said).
    let q = tmp_in("cli_header_units", "omega_only.csv");
    std::fs::write(&q, rows("timestamp,omega_x,omega_y,omega_z,ax,ay,az")).unwrap();
    let out = analyze(&q, &[]);
    assert!(curves(&out).iter().all(|c| c.unit == "u"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(
            "no unit in the column headers and no --unit: the values are read as increments"
        ),
        "{err}"
    );
}

#[test]
fn headers_that_cannot_be_read_or_contradict_the_options_are_usage_errors() {
    // A magnetometer's column is no channel by its unit (said); picked, its unit is not one
    // allanscope knows.
    let p = file("mixed.csv", "t,w [rad s^-1],a [m s^-2],mag_x [uT]");
    let out = analyze(&p, &[]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        err.contains("column 4 `mag_x [uT]` holds a magnetic field, by its unit: not a channel"),
        "{err}"
    );
    let read = curves(&out);
    assert_eq!(read.len(), 2);
    usage_error(
        &analyze(&p, &["--columns", "w [rad s^-1],mag_x [uT]"]),
        &[
            "mixed.csv: column 4 `mag_x [uT]`: unit `uT` in its header is not one",
            "--unit U",
        ],
    );
    let p = file(
        "euroc.csv",
        "#timestamp [s],w [rad s^-1],a [m s^-2],b [m s^-2]",
    );
    usage_error(
        &analyze(&p, &["--phase"]),
        &["--phase, but column 2 `w [rad s^-1]` holds rates by its header unit `rad s^-1`"],
    );
    // `--rate` agrees with these headers.
    let read = curves(&analyze(&p, &["--rate"]));
    assert_eq!(read.len(), 3);
    assert_eq!(curve(&read, "w [rad s^-1]").unit, "rad");
    assert_eq!(curve(&read, "b [m s^-2]").unit, "m/s");
    let p = file("inc.csv", "t,dth_x [rad],dth_y [rad],dth_z [rad]");
    usage_error(
        &analyze(&p, &["--rate"]),
        &["--rate, but column 2 `dth_x [rad]` holds increments by its header unit `rad`"],
    );
    // `--unit` overrides the headers, and says so.
    let out = analyze(&p, &["--rate", "--unit", "mrad"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        err.contains("--unit mrad given: the units in the headers of `dth_x [rad]`"),
        "{err}"
    );
    assert!(
        err.contains(
            "holds increments by its header unit `rad`, but the options read rate samples"
        ) && err.contains("leave out --rate if they are increments"),
        "{err}"
    );
    assert!(curves(&out).iter().all(|c| c.unit == "mrad"));
}

/// `diagnose` reads the headers as `analyze` does.
#[test]
fn diagnose_reads_the_header_units() {
    let p = file("diag.csv", "t,gx [deg/s],gy [deg/s],gz [deg/s]");
    let out = exe()
        .arg("diagnose")
        .arg(&p)
        .args(["--channel", "gx [deg/s]", "--json"])
        .env("ALLANSCOPE_LOG", "info")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("read as rate samples, as --rate"), "{err}");
    let p = file("diag_bad.csv", "t,gx [deg/s],gy [rad/h],gz [deg/s]");
    let out = exe()
        .arg("diagnose")
        .arg(&p)
        .args(["--json"])
        .output()
        .unwrap();
    usage_error(&out, &["column 3 `gy [rad/h]`: unit `rad/h`"]);
}

/// White rate noise of N = 0.5 u/sqrt(s) sampled at 100 Hz for 20 minutes, as rate samples in
/// one column `gx`: each sample is N / sqrt(tau0) z = 5 z (u/s) for a standard normal z (seeded
/// LCG + Box-Muller).
fn white_rates(name: &str) -> PathBuf {
    const N: f64 = 0.5;
    const TAU0_S: f64 = 0.01;
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut u = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut text = String::from("gx\n");
    for _ in 0..120_000 {
        let (a, b) = (u(), u());
        let z = (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos();
        text += &format!("{:e}\n", N / TAU0_S.sqrt() * z);
    }
    let p = tmp_in("cli_header_units", name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The final fit's unit and N of a run of `white_rates` with `extra`.
fn fitted_n(p: &std::path::Path, extra: &[&str]) -> (String, f64, String) {
    let out = exe()
        .arg("analyze")
        .arg(p)
        .args(["--tau0", "0.01", "--stats", "avar", "--json"])
        .args(extra)
        .env("ALLANSCOPE_LOG", "info")
        .output()
        .unwrap();
    let fit = crate::common::records_of(&out)
        .into_iter()
        .find_map(|r| match r {
            allanscope::sink::records::Record::Fit(f) if f.r#final => Some(f),
            _ => None,
        })
        .expect("a final fit");
    let n = fit.coef.by_index(1).value.expect("N");
    (
        fit.unit,
        n,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Relative tolerance of N fitted to 120000 white rate samples: its AVAR at tau0 alone has
/// some 1e5 degrees of freedom (0.3% in N); 3% leaves room for the fit and no room for a
/// factor of the sampling rate.
const N_REL: f64 = 0.03;

/// `--unit deg/s` names a rate: the column is read as rate samples, as a header `gx [deg/s]`
/// is (before, as increments: N 1 / tau0 = 100 times too large). `--unit g` stays the
/// increment unit g*s it is documented as; `--phase` with a rate unit is refused.
#[test]
fn a_rate_unit_option_reads_rate_samples() {
    let p = white_rates("white_rates.csv");
    let (unit, n, err) = fitted_n(&p, &["--unit", "deg/s"]);
    assert_eq!(unit, "deg");
    assert!(
        (n / 0.5 - 1.0).abs() < N_REL,
        "N = {n} deg/sqrt(s), truth 0.5"
    );
    assert!(
        err.contains(
            "--unit deg/s is a rate: the columns are read as rate samples (u = deg); give \
             --unit deg for increments"
        ),
        "{err}"
    );
    // As `--rate --unit deg/s` (and `--rate --unit deg`) read it, to the last bit.
    assert_eq!(fitted_n(&p, &["--rate", "--unit", "deg/s"]).1, n);
    assert_eq!(fitted_n(&p, &["--rate", "--unit", "deg"]).1, n);
    // Other spellings of a rate: a MEMS accelerometer's m/s^2 (u = m/s), `dps`, `rad s^-1`.
    for (option, increment) in [("m/s^2", "m/s"), ("dps", "deg"), ("rad s^-1", "rad")] {
        let (unit, n_other, _) = fitted_n(&p, &["--unit", option]);
        assert_eq!((unit.as_str(), n_other), (increment, n), "--unit {option}");
    }
    // `g` as an option is the increment g*s (README): the same values as increments, N 100
    // times larger (sigma of an increment over tau0 = 0.01 s is that of the rate times 100).
    let (unit, n_g, _) = fitted_n(&p, &["--unit", "g"]);
    assert_eq!(unit, "g");
    assert!(
        (n_g / 50.0 - 1.0).abs() < N_REL,
        "N = {n_g} g*sqrt(s), as increments 50"
    );
    usage_error(
        &exe()
            .arg("analyze")
            .arg(&p)
            .args(["--tau0", "0.01", "--phase", "--unit", "deg/s"])
            .output()
            .unwrap(),
        &["--phase", "--unit deg/s is a rate"],
    );
}
