//! Greenhall's edf and the chi-squared interval against Stable32's confidence intervals.
//!
//! Each row of a Stable32 table (fixtures/stable32, see its ORIGIN.md) gives the cluster `m`, the
//! number of differences `#`, the noise exponent `Alpha` Stable32 identified, and `MinSigma`,
//! `Sigma`, `MaxSigma` at confidence 0.683. Given Stable32's Alpha and Sigma, our edf and interval
//! must reproduce MinSigma and MaxSigma to [`CI_TOL`] relative. The `#` column pins the
//! convention for `N` (phase points) and for the stride: `# = 1 + floor((N - L) / stride)` with
//! `L = m/F + m d`, stride 1 for the overlapped statistics and `m` for ADEV and HDEV.
//!
//! Measured worst relative errors of Min/Max Sigma per table, exact chi-squared quantiles at
//! confidence 0.683 (first test) / with Stable32's inferred quantile rule (second test):
//! phasedat adev 3.6e-4/1.3e-4, oadev 3.7e-4/1.5e-4, hdev 5.6e-4/1.6e-4, ohdev 3.8e-4/8.8e-5,
//! mdev 4.4e-4/1.1e-4; gps ADEV 5.2e-4/1.8e-4, OADEV 1.5e-4/1.9e-4, HDEV 5.3e-4/1.2e-4,
//! OHDEV 1.6e-4/1.6e-4, MDEV 3.9e-4/1.0e-4; Cs5071A adev 5.3e-4/2.0e-4, oadev 3.0e-4/2.5e-4,
//! hdev 4.4e-4/7.2e-5, ohdev 3.6e-4/1.2e-4, mdev 5.8e-4/2.2e-4; tic oadev 4.9e-4/4.8e-5,
//! hdev 3.9e-4/1.7e-4, ohdev 3.7e-4/3.5e-5, mdev 3.9e-4/1.0e-4; ocxo adev 4.0e-4/5.1e-5,
//! oadev 3.4e-4/1.2e-4, hdev 3.0e-4/7.8e-5, ohdev 5.3e-4/1.9e-4, mdev 5.2e-4/9.6e-5.
//! The printed columns carry 5 significant digits (about 5e-5 relative each).

use std::path::PathBuf;

use allanscope::allan::edf::{edf, sigma_interval};
use allanscope::allan::Stat;

/// The target of the issue: Min/Max Sigma to 1e-3 relative.
const CI_TOL: f64 = 1e-3;
/// With Stable32's own quantile rule (below), what is left: three 5-digit printed numbers per
/// comparison (up to 1e-4) and a few rows at edf < 10 that reach 2.5e-4.
const STABLE32_RULE_TOL: f64 = 3e-4;
/// The exact one-sigma confidence, erf(1/sqrt 2), which fits Stable32's small-edf rows better
/// than its printed "0.683".
const ONE_SIGMA: f64 = 0.682_689_492_137_085_9;
/// Stable32's "Confidence Factor = 0.683" (one sigma).
const CONFIDENCE: f64 = 0.683;

struct Row {
    m: u64,
    count: u64,
    alpha: i32,
    min: f64,
    sigma: f64,
    max: f64,
}

fn read_table(rel_path: &str) -> Vec<Row> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/stable32")
        .join(rel_path);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    // Latin-1 headers; the data rows are ASCII.
    let text = String::from_utf8_lossy(&bytes);
    text.lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let c: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(c.len(), 7, "{rel_path}: row {l:?}");
            Row {
                m: c[0].parse().unwrap(),
                count: c[2].parse().unwrap(),
                alpha: c[3].parse().unwrap(),
                min: c[4].parse().unwrap(),
                sigma: c[5].parse().unwrap(),
                max: c[6].parse().unwrap(),
            }
        })
        .collect()
}

/// Overlapped (stride 1) or non-overlapped (stride m) estimator.
#[derive(Clone, Copy)]
enum Overlap {
    Full,
    None,
}

/// `# = 1 + floor((N - L) / stride)` (Greenhall and Riley's M), `L = m/F + m d`.
fn expected_count(stat: Stat, m: u64, stride: u64, n_phase: u64) -> u64 {
    let f = if stat == Stat::Mvar { 1 } else { m };
    let span = m / f + m * u64::from(stat.diff_order());
    1 + (n_phase - span) / stride
}

/// Worst relative error of Min/Max Sigma over one table, after checking every `#`; `interval`
/// maps (sigma, edf) to (MinSigma, MaxSigma).
fn worst_error(
    rel_path: &str,
    stat: Stat,
    overlap: Overlap,
    n_phase: u64,
    interval: &dyn Fn(f64, f64) -> (f64, f64),
) -> f64 {
    let rows = read_table(rel_path);
    assert!(rows.len() >= 8, "{rel_path}: only {} rows", rows.len());
    let mut worst = 0.0f64;
    for row in &rows {
        let stride = match overlap {
            Overlap::Full => 1,
            Overlap::None => row.m,
        };
        assert_eq!(
            expected_count(stat, row.m, stride, n_phase),
            row.count,
            "{rel_path}: m {} count",
            row.m
        );
        let e = edf(stat, row.alpha, row.m, stride, n_phase)
            .unwrap_or_else(|| panic!("{rel_path}: no edf at m {}", row.m));
        let (lo, hi) = interval(row.sigma, e);
        for (got, want) in [(lo, row.min), (hi, row.max)] {
            worst = worst.max(((got - want) / want).abs());
        }
    }
    worst
}

struct Table {
    path: &'static str,
    stat: Stat,
    overlap: Overlap,
    n_phase: u64,
}

const fn t(path: &'static str, stat: Stat, overlap: Overlap, n_phase: u64) -> Table {
    Table {
        path,
        stat,
        overlap,
        n_phase,
    }
}

/// N from each header's "Phase Data Points ... of N" (ocxo: 19982 frequency points, so 19983
/// phase points); every `#` in the tables agrees with it.
const TABLES: &[Table] = &[
    t(
        "phasedat/phase_dat_adev_octave.txt",
        Stat::Avar,
        Overlap::None,
        1001,
    ),
    t(
        "phasedat/phase_dat_oadev_octave.txt",
        Stat::Avar,
        Overlap::Full,
        1001,
    ),
    t(
        "phasedat/phase_dat_hdev_octave.txt",
        Stat::Hvar,
        Overlap::None,
        1001,
    ),
    t(
        "phasedat/phase_dat_ohdev_octave.txt",
        Stat::Hvar,
        Overlap::Full,
        1001,
    ),
    t(
        "phasedat/phase_dat_mdev_octave.txt",
        Stat::Mvar,
        Overlap::Full,
        1001,
    ),
    t(
        "gps/stable32_ADEV_decade.txt",
        Stat::Avar,
        Overlap::None,
        241218,
    ),
    t(
        "gps/stable32_OADEV_octave.txt",
        Stat::Avar,
        Overlap::Full,
        241218,
    ),
    t(
        "gps/stable32_HDEV_octave.txt",
        Stat::Hvar,
        Overlap::None,
        241218,
    ),
    t(
        "gps/stable32_OHDEV_octave.txt",
        Stat::Hvar,
        Overlap::Full,
        241218,
    ),
    t(
        "gps/stable32_MDEV_octave.txt",
        Stat::Mvar,
        Overlap::Full,
        241218,
    ),
    t("Cs5071A/adev_decade.txt", Stat::Avar, Overlap::None, 556990),
    t(
        "Cs5071A/oadev_decade.txt",
        Stat::Avar,
        Overlap::Full,
        556990,
    ),
    t("Cs5071A/hdev_decade.txt", Stat::Hvar, Overlap::None, 556990),
    t(
        "Cs5071A/ohdev_decade.txt",
        Stat::Hvar,
        Overlap::Full,
        556990,
    ),
    t("Cs5071A/mdev_decade.txt", Stat::Mvar, Overlap::Full, 556990),
    t(
        "Keysight53230A_ti_noise_floor/tic_oadev.txt",
        Stat::Avar,
        Overlap::Full,
        55688,
    ),
    t(
        "Keysight53230A_ti_noise_floor/tic_hdev.txt",
        Stat::Hvar,
        Overlap::None,
        55688,
    ),
    t(
        "Keysight53230A_ti_noise_floor/tic_ohdev.txt",
        Stat::Hvar,
        Overlap::Full,
        55688,
    ),
    t(
        "Keysight53230A_ti_noise_floor/tic_mdev.txt",
        Stat::Mvar,
        Overlap::Full,
        55688,
    ),
    t("ocxo/adev_octave.txt", Stat::Avar, Overlap::None, 19983),
    t("ocxo/oadev_octave.txt", Stat::Avar, Overlap::Full, 19983),
    t("ocxo/hdev_octave.txt", Stat::Hvar, Overlap::None, 19983),
    t("ocxo/ohdev_octave.txt", Stat::Hvar, Overlap::Full, 19983),
    t("ocxo/mdev_octave.txt", Stat::Mvar, Overlap::Full, 19983),
];

fn check_all(tol: f64, interval: &dyn Fn(f64, f64) -> (f64, f64)) {
    let mut failures = Vec::new();
    for tab in TABLES {
        let worst = worst_error(tab.path, tab.stat, tab.overlap, tab.n_phase, interval);
        eprintln!("{:48} worst relative error {worst:.2e}", tab.path);
        if worst >= tol {
            failures.push(format!("{}: {worst:.2e}", tab.path));
        }
    }
    assert!(failures.is_empty(), "beyond {tol}: {failures:?}");
}

#[test]
fn stable32_confidence_intervals_are_reproduced() {
    check_all(CI_TOL, &|sigma, e| {
        sigma_interval(sigma, e, CONFIDENCE).expect("valid interval")
    });
}

/// Stable32's interval rule as inferred here from its tables (an inference, not documentation).
/// Against the exact interval, every row with edf > 100 (from 103 up) is narrowed by the same
/// factor 0.9944 +- 0.0005 in the normal quantile, at both ends, and no row with edf <= 100 (up to
/// 98) is. That is the Wilson-Hilferty form `chi2_p ~ edf (1 - 2/(9 edf) + z sqrt(2/(9 edf)))^3`
/// with `z = 0.99446`, the quantile of a 68% (not 68.3%) two-sided interval. Below 100 the exact
/// quantiles at erf(1/sqrt 2) fit best. The library keeps the exact quantiles.
fn stable32_interval(sigma: f64, e: f64) -> (f64, f64) {
    const LARGE_EDF: f64 = 100.0;
    /// Standard normal quantile of 0.84.
    const Z_68: f64 = 0.994_457_883_209_753;
    if e <= LARGE_EDF {
        return sigma_interval(sigma, e, ONE_SIGMA).expect("valid interval");
    }
    let c = (2.0 / (9.0 * e)).sqrt();
    let q = |z: f64| e * (1.0 - 2.0 / (9.0 * e) + z * c).powi(3);
    (sigma * (e / q(Z_68)).sqrt(), sigma * (e / q(-Z_68)).sqrt())
}

#[test]
fn stable32_quantile_rule_pins_the_edf() {
    // With Stable32's own quantiles the differences left are near the 5-digit printing of Sigma,
    // MinSigma and MaxSigma, so our edf agrees with Stable32's to a fraction of a percent.
    check_all(STABLE32_RULE_TOL, &stable32_interval);
}
