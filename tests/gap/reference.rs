//! The diagnosis of a real recording: the ADIS16405 static run (../shared/reference/imu,
//! PROVENANCE.md there: 100 Hz, 1 000 000 samples, gyro in deg/s, LSB 0.05 deg/s). Ignored by
//! default; `.ci/run` runs it when the reference folder is there.
//!
//! Expected numbers: the white rate noise "about 2.3 deg/sqrt(h)" of PROVENANCE.md (0.0383
//! deg/sqrt(s)); the verdict and effects are this crate's own result on gyro x, kept as a
//! regression (docs/gap.md, "Real recording").

use allanscope::gap::{
    diagnose, DiagnoseOptions, DiagnosisRecord, EffectKind, EffectParams, GapConfig, GapEvidence,
    Verdict,
};
use std::io::BufReader;
use std::path::PathBuf;

const TAU0: f64 = 0.01;
/// PROVENANCE.md: white noise about 2.3 deg/sqrt(h) = 2.3 / 60 deg/sqrt(s); "about" taken as 15%.
const N_PROVENANCE: f64 = 2.3 / 60.0;
const TOL_N: f64 = 0.15;

/// Gyro x of the recording (3.8 MB, too large for fixtures/): the test is ignored by default
/// and fails, rather than passing unchecked, when run without it.
fn load_gyro_x() -> Vec<f64> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/reference/imu/adis16405_imu1_static_100hz.csv.xz");
    assert!(
        path.is_file(),
        "{} does not exist: this test needs the shared reference recording",
        path.display()
    );
    let file = std::fs::File::open(&path).expect("open reference");
    let mut raw = Vec::new();
    lzma_rs::xz_decompress(&mut BufReader::new(file), &mut raw).expect("xz");
    let text = String::from_utf8(raw).expect("utf8");
    let mut out = Vec::with_capacity(1_000_000);
    for line in text.lines() {
        if line.starts_with('#') || line.starts_with("gyro") {
            continue;
        }
        let first = line.split(',').next().unwrap_or("");
        // Rate samples in deg/s become increments in deg.
        out.push(first.trim().parse::<f64>().expect("number") * TAU0);
    }
    out
}

#[test]
#[ignore = "needs ../shared/reference (a 3.8 MB recording); .ci/run runs it when present"]
fn adis16405_gyro_x_diagnosis() {
    let inc = load_gyro_x();
    assert_eq!(inc.len(), 1_000_000);
    let mut ev = GapEvidence::from_increments(GapConfig::new(TAU0), &inc);
    let d = diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis");
    let rec = DiagnosisRecord::new("gyro_x_dps", &d, None, true);
    eprintln!("{}", rec.to_json_line());
    let n = d.final_coef[1];
    assert!(((n - N_PROVENANCE) / N_PROVENANCE).abs() < TOL_N, "N {n}");
    // This crate's result (docs/gap.md): the five terms alone miss by far (G in the hundreds:
    // at 100 Hz the short taus have thousands of degrees of freedom), and the first stationary
    // effect named is a moving average of two samples, as the ADIS16405's decimating average
    // from its 819.2 Hz internal rate would give (a start transient may be named before it: the
    // effects in time are listed first). With the first-order filter alone the gap stayed near
    // 30 and a 22.6 Hz sinusoid stood in for the FIR's shape; with the moving average it falls
    // below 3 and no sinusoid is named.
    assert!(d.gap_before > 100.0, "gap before {}", d.gap_before);
    let filter = d
        .effects
        .iter()
        .find(|e| !matches!(e.params.kind(), EffectKind::Warmup | EffectKind::BiasJumps))
        .expect("a stationary effect");
    assert_eq!(
        filter.params,
        EffectParams::MovingAverage {
            taps: 2,
            stages: 1,
            decimation: 1
        }
    );
    assert!(
        filter.gap_after < 3.0,
        "gap after the filter {}",
        filter.gap_after
    );
    assert!(d
        .effects
        .iter()
        .all(|e| e.params.kind() != EffectKind::Sinusoid));
    assert_ne!(d.verdict, Verdict::Consistent, "{d:?}");
}
