//! Run-to-run statistics against the seed paper's table 2 (the seed paper, docs/theory.md section 6), computed from its per-run
//! values, "-" runs included, plus the datasheet-unit conversions of docs/theory.md section 2.

use allanscope::model::aggregate::{aggregate, run_stats};
use allanscope::model::units::{datasheet, quantization_ratio, IncrementUnit};

/// The table prints 3 decimals and so do its per-run values, which the paper averaged unrounded:
/// a figure recomputed from the printed runs matches when within the two roundings (half a unit
/// in the last place each), e.g. MA4's B mean 0.40233 against the printed 0.403.
const PRINTED: f64 = 0.001 + 1e-9;

fn matches(x: f64, printed: f64) -> bool {
    (x - printed).abs() <= PRINTED
}

/// MA4 (the seed paper's table 2 (docs/theory.md section 6)), columns R, K, B, N, Q as printed; `None` is "-".
const MA4_RUNS: [[Option<f64>; 5]; 3] = [
    [Some(5.327), Some(2.052), Some(0.294), None, Some(5.955)],
    [
        Some(6.751),
        Some(2.220),
        Some(0.436),
        Some(2.917),
        Some(6.905),
    ],
    [
        Some(5.982),
        Some(2.413),
        Some(0.477),
        Some(2.706),
        Some(7.741),
    ],
];
/// Printed mean, sd and 95% interval for R, K, B, N, Q.
const MA4_MEAN: [f64; 5] = [6.020, 2.228, 0.403, 2.811, 6.867];
const MA4_SD: [f64; 5] = [0.713, 0.181, 0.096, 0.149, 0.893];
const MA4_CI: [[f64; 2]; 5] = [
    [5.213, 6.823],
    [2.023, 2.432],
    [0.294, 0.511],
    [2.605, 3.017],
    [5.856, 7.873],
];

const VOG4_RUNS: [[Option<f64>; 5]; 3] = [
    [Some(0.891), Some(0.811), Some(0.248), Some(0.273), None],
    [None, Some(2.978), Some(0.213), Some(0.210), None],
    [None, Some(1.691), Some(0.213), Some(0.278), None],
];
const VOG4_MEAN: [Option<f64>; 5] = [Some(0.891), Some(1.826), Some(0.225), Some(0.254), None];
const VOG4_SD: [Option<f64>; 5] = [None, Some(1.090), Some(0.020), Some(0.038), None];
const VOG4_CI: [Option<[f64; 2]>; 5] = [
    None,
    Some([0.593, 3.054]),
    Some([0.202, 0.248]),
    Some([0.211, 0.297]),
    None,
];

/// Which printed interval ends our recomputation reproduces (columns R, K, B, N, Q; [lo, hi]).
/// The paper's upper ends run low in four columns (by 0.0013 to 0.006) while the lower ends match:
/// its intervals are not symmetric about its own means, so those ends are misprints or were
/// computed from different (unrounded) values; we keep the formula and list the exceptions.
const MA4_CI_MATCH: [[bool; 2]; 5] = [
    [true, false], // R: 6.827 vs printed 6.823 (docs/theory.md section 2's worked check)
    [true, true],  // K: [2.0239, 2.4328] vs [2.023, 2.432] (within the roundings)
    [true, true],  // B
    [true, false], // N: 3.018 vs 3.017
    [true, false], // Q: 7.878 vs 7.873
];
const VOG4_CI_MATCH: [[bool; 2]; 5] = [
    [true, true],
    [true, false], // K: 3.060 vs 3.054
    [true, true],
    [true, true],
    [true, true],
];

#[test]
fn ma4_table2_reproduced() {
    let st = aggregate(&MA4_RUNS);
    // Columns of the runs are R, K, B, N, Q (the paper's order).
    let expect_n = [3, 3, 3, 2, 3];
    for i in 0..5 {
        let s = st[i].expect("determined somewhere");
        assert_eq!(s.n, expect_n[i], "column {i}");
        assert!(
            matches(s.mean, MA4_MEAN[i]),
            "mean {i}: {} vs {}",
            s.mean,
            MA4_MEAN[i]
        );
        assert!(
            matches(s.sd.unwrap(), MA4_SD[i]),
            "sd {i}: {:?} vs {}",
            s.sd,
            MA4_SD[i]
        );
        let ci = s.ci_z.unwrap();
        for e in 0..2 {
            assert_eq!(
                matches(ci[e], MA4_CI[i][e]),
                MA4_CI_MATCH[i][e],
                "MA4 column {i} end {e}: computed {} printed {}",
                ci[e],
                MA4_CI[i][e]
            );
        }
    }
    // docs/theory.md section 2's worked check: R = 6.020 +- 0.807 = [5.213, 6.827] (1.96 * 0.7128 /
    // sqrt 3 = 0.8066).
    let r = st[0].unwrap();
    let ci = r.ci_z.unwrap();
    assert!((ci[0] - 5.2134).abs() < 1e-4 && (ci[1] - 6.8266).abs() < 1e-4);
    // The Student interval with n = 3 (t = 4.303) is 4.303/1.96 = 2.195 times as wide.
    let ct = r.ci_t.unwrap();
    let ratio = (ct[1] - ct[0]) / (ci[1] - ci[0]);
    assert!(
        (ratio - 4.302_652_729_749_464 / 1.96).abs() < 1e-6,
        "ratio {ratio}"
    );
}

#[test]
fn vog4_table2_reproduced() {
    let st = aggregate(&VOG4_RUNS);
    for i in 0..5 {
        match (st[i], VOG4_MEAN[i]) {
            (None, None) => {}
            (Some(s), Some(m)) => {
                assert!(matches(s.mean, m), "mean {i}: {} vs {m}", s.mean);
                match (s.sd, VOG4_SD[i]) {
                    (None, None) => assert_eq!(s.n, 1),
                    (Some(a), Some(b)) => assert!(matches(a, b), "sd {i}: {a} vs {b}"),
                    other => panic!("sd {i}: {other:?}"),
                }
                if let (Some(ci), Some(p)) = (s.ci_z, VOG4_CI[i]) {
                    for e in 0..2 {
                        assert_eq!(
                            matches(ci[e], p[e]),
                            VOG4_CI_MATCH[i][e],
                            "VOG4 {i} end {e}: {}",
                            ci[e]
                        );
                    }
                }
            }
            other => panic!("column {i}: {other:?}"),
        }
    }
    // Q never determined ("-" in every run), R once: mean only.
    assert!(st[4].is_none());
    assert_eq!(st[0].unwrap().n, 1);
    assert!(st[0].unwrap().ci_z.is_none());
}

#[test]
fn single_and_empty_inputs() {
    assert!(run_stats(&[None, None]).is_none());
    let s = run_stats(&[Some(2.0), None]).unwrap();
    assert_eq!((s.n, s.mean, s.sd), (1, 2.0, None));
    // Two runs 1 and 3: mean 2, sd sqrt(2), t_{0.975,1} = 12.706.
    let s = run_stats(&[Some(1.0), Some(3.0)]).unwrap();
    assert!((s.sd.unwrap() - 2f64.sqrt()).abs() < 1e-12);
    let half = s.ci_t.unwrap()[1] - 2.0;
    assert!((half - 12.706_204_736 * 1.0).abs() < 1e-6, "half {half}");
}

#[test]
fn datasheet_units() {
    // the seed paper (docs/theory.md section 6): VOG4 N = 0.254 arcsec/sqrt(s) -> 0.254/60 deg/sqrt(h); B 0.225 arcsec/s = deg/h.
    let d = datasheet(
        [0.0, 0.254, 0.225, 1.826e-2, 0.891e-4],
        &IncrementUnit::parse("arcsec").unwrap(),
    );
    assert!((d.values[1] - 0.254 / 60.0).abs() < 1e-15);
    assert!((d.values[2] - 0.225).abs() < 1e-15);
    // 1 arcsec/s/sqrt(s) = 60 deg/h/sqrt(h); 1 arcsec/s^2 = 3600 deg/h^2 (unit algebra).
    assert!((d.values[3] - 1.826e-2 * 60.0).abs() < 1e-12);
    assert!((d.values[4] - 0.891e-4 * 3600.0).abs() < 1e-12);
    // MA4: B = 0.403e-4 m/s^2 = 4.109 micro-g; N = 2.811e-4 m/s/sqrt(s) = 0.01687 m/s/sqrt(h).
    let d = datasheet(
        [6.867e-4, 2.811e-4, 0.403e-4, 2.228e-6, 6.020e-8],
        &IncrementUnit::parse("m/s").unwrap(),
    );
    assert!((d.values[2] - 0.403e-4 / 9.80665e-6).abs() < 1e-12);
    assert!((d.values[1] - 2.811e-4 * 60.0).abs() < 1e-15);
    // the seed paper (docs/theory.md section 6): MA4's Q 6.867e-4 m/s against its LSB 2.104e-4 m/s: Q / (LSB/sqrt 12) = 11.31.
    let ratio = quantization_ratio(6.867e-4, 2.104e-4);
    assert!((ratio - 6.867 / 2.104 * 12f64.sqrt()).abs() < 1e-12);
    assert!((ratio - 11.306).abs() < 1e-3, "ratio {ratio}");
}
