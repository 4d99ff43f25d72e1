//! The fit on a real MEMS recording: the ADIS16405 static capture of
//! ../shared/reference/imu (100 Hz, 1,000,000 samples, gyro rates in deg/s; PROVENANCE.md
//! there). The gyro columns go through the analysis as rate samples (increment = rate * tau0,
//! unit deg), and the angle random walk N (deg/sqrt(s)) times 60 is compared with the
//! datasheet's 2 deg/sqrt(h) (PROVENANCE.md measured about 2.3 on gyro X).
//!
//! Ignored by default (the recording is 3.8 MB); `.ci/run` runs it when the reference folder is
//! there, and run without it the test fails instead of passing unchecked.

use std::io::Read;
use std::path::PathBuf;

use allanscope::allan::accum::{AccumConfig, StatSet};
use allanscope::allan::Stat;
use allanscope::analysis::{AnalysisOptions, ChannelSetup, InputKind, RunAnalysis};
use allanscope::input::Chunk;
use allanscope::model::fit::{FitOptions, FitResult};

const TAU0_S: f64 = 0.01;
/// The ADIS16405 datasheet's angle random walk, deg/sqrt(h) (PROVENANCE.md).
const DATASHEET_ARW: f64 = 2.0;
/// PROVENANCE.md's own white-noise level of gyro X, deg/sqrt(h).
const MEASURED_ARW: f64 = 2.3;
/// "Near": within 30% of the datasheet figure (a typical value, not a bound; the three axes of
/// this unit measure 2.3-2.5), and within 10% of the independent measurement.
const DATASHEET_TOL: f64 = 0.30;
/// gof of a model that holds is about 1 (sd ~0.4 over simulated runs, docs/fit.md); the long-tau
/// fits here give 0.9-2.1. Far above: the short-tau fit that cannot follow the filter.
const GOF_HOLDS_MAX: f64 = 3.0;
const GOF_MISFIT_MIN: f64 = 100.0;
const MEASURED_TOL: f64 = 0.10;
/// Shortest tau fitted: past the reach of the unit's internal filter (see the test).
const TAU_MIN_S: f64 = 0.5;

/// The recording (3.8 MB, too large for fixtures/): the test is ignored by default and fails,
/// rather than passing unchecked, when run without it.
fn reference() -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/reference/imu/adis16405_imu1_static_100hz.csv.xz");
    assert!(
        p.is_file(),
        "{} does not exist: this test needs the shared reference recording",
        p.display()
    );
    p
}

/// The three gyro columns, row-major, deg/s.
fn read_gyro(path: &PathBuf) -> Vec<f64> {
    let mut xz = std::io::BufReader::new(std::fs::File::open(path).expect("open"));
    let mut csv = Vec::new();
    lzma_rs::xz_decompress(&mut xz, &mut csv).expect("xz");
    let mut text = String::new();
    csv.as_slice().read_to_string(&mut text).expect("utf-8");
    let mut out = Vec::with_capacity(3_000_000);
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().expect("header");
    assert!(
        header.starts_with("gyro_x_dps,gyro_y_dps,gyro_z_dps"),
        "{header}"
    );
    for line in lines {
        let mut f = line.split(',');
        for _ in 0..3 {
            out.push(f.next().and_then(|v| v.parse().ok()).unwrap_or(f64::NAN));
        }
    }
    out
}

/// Fits of the three gyro axes through the analysis (two-pass noise type, bounded overlap).
fn fit_axes(values: &[f64], fit: FitOptions) -> Vec<(String, FitResult)> {
    let mut accum = AccumConfig::new(TAU0_S);
    accum.stats = StatSet::only(Stat::Avar);
    let opts = AnalysisOptions {
        accum,
        kind: InputKind::Rate,
        every_s: None,
        fit: Some(fit),
        run: None,
        limits: Vec::new(),
        diagnose: false,
    };
    let setups = ["gyro_x", "gyro_y", "gyro_z"]
        .iter()
        .enumerate()
        .map(|(i, n)| ChannelSetup {
            name: (*n).into(),
            unit: "deg".into(),
            column: i,
            counts_lsb: None,
        })
        .collect();
    let mut run = RunAnalysis::new("adis16405", setups, opts);
    let mut out = Vec::new();
    run.push_chunk(
        &Chunk::Rows {
            values: values.to_vec(),
            width: 3,
        },
        &mut out,
    );
    run.records(true);
    run.last_fits()
        .into_iter()
        .map(|(name, _, f)| (name, f.expect("fit")))
        .collect()
}

fn report(what: &str, fits: &[(String, FitResult)]) -> Vec<f64> {
    let to_dph = 60.0; // deg/sqrt(s) -> deg/sqrt(h)
    fits.iter()
        .map(|(name, f)| {
            let n = &f.coef[1];
            println!(
                "{what} {name}: N = {:.3} deg/sqrt(h) [{:.3}, {:.3}] determined {}, \
                 B = {:.1} deg/h (determined {}), gof {:.2}",
                n.value * to_dph,
                n.lo * to_dph,
                n.hi * to_dph,
                n.determined,
                f.coef[2].value * 3600.0,
                f.coef[2].determined,
                f.gof
            );
            assert!(n.determined, "{what} {name}: N not determined");
            n.value * to_dph
        })
        .collect()
}

#[test]
#[ignore = "needs ../shared/reference (a 3.8 MB recording); .ci/run runs it when present"]
fn adis16405_arw_near_datasheet() {
    let path = reference();
    let values = read_gyro(&path);
    assert_eq!(values.len(), 3_000_000, "1,000,000 rows (PROVENANCE.md)");
    // Every tau: the unit's internal filtering pulls ADEV below the white-noise line at 10 ms
    // and lifts it 10% around 0.1 s, which the five-term model cannot follow; with the short
    // taus' large edf the fit bends to them and gof says the model does not hold (~1e3).
    let all_fits = fit_axes(&values, FitOptions::default());
    let all = report("all taus", &all_fits);
    // From 0.5 s on, past the filter's reach: the ARW the datasheet means.
    let long = fit_axes(
        &values,
        FitOptions {
            tau_min_s: Some(TAU_MIN_S),
            ..FitOptions::default()
        },
    );
    let arw = report("tau >= 0.5 s", &long);
    // Gyro X against PROVENANCE.md's measurement; every axis near the datasheet.
    assert!(
        (arw[0] / MEASURED_ARW - 1.0).abs() <= MEASURED_TOL,
        "gyro X ARW {} deg/sqrt(h)",
        arw[0]
    );
    for (i, a) in arw.iter().enumerate() {
        assert!(
            (a / DATASHEET_ARW - 1.0).abs() <= DATASHEET_TOL,
            "axis {i}: ARW {a} deg/sqrt(h)"
        );
    }
    assert_eq!(all.len(), 3);
    for ((name, a), (_, l)) in all_fits.iter().zip(&long) {
        assert!(a.gof > GOF_MISFIT_MIN, "{name}: all-tau gof {}", a.gof);
        assert!(l.gof < GOF_HOLDS_MAX, "{name}: long-tau gof {}", l.gof);
    }
}
