//! The fit on exact model curves (no noise): every method that is exact for the model must give the
//! coefficients back; the `coef` JSON has docs/records.md's shape.
#![allow(clippy::needless_range_loop)]

use crate::common::fit::model_curve;
use allanscope::model::fit::{fit, FitMethod, FitOptions, Fitter};
use allanscope::sink::records::CoefRecord;

/// Exact data, exact model: only rounding separates the fit from the truth (docs/theory.md section 2).
const EXACT_REL_TOL: f64 = 1e-9;

/// The seed paper's MA4 run-3 magnitudes (the seed paper's table 2 (docs/theory.md section 6), m/s units), tau0 = 0.004 s, 3 hours.
const MA4: [f64; 5] = [7.741e-4, 2.706e-4, 0.477e-4, 2.413e-6, 5.982e-8];

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn exact_curve_recovers_all_five_terms() {
    let tau0 = 0.004;
    let n = (3.0 * 3600.0 / tau0) as usize;
    let pts = model_curve(MA4, tau0, n, n / 2);
    let r = fit(&pts, &FitOptions::default()).unwrap();
    for i in 0..5 {
        assert!(
            rel(r.coef[i].value, MA4[i]) < EXACT_REL_TOL,
            "term {i}: {} vs {}",
            r.coef[i].value,
            MA4[i]
        );
        assert!(r.coef[i].lo <= MA4[i] && MA4[i] <= r.coef[i].hi);
    }
    // Zero residual: gof 0.
    assert!(r.gof.abs() < 1e-12, "gof {}", r.gof);
}

#[test]
fn exact_curve_with_absent_terms_and_options() {
    let tau0 = 0.01;
    let n = 1 << 20;
    // Q and R absent.
    let truth = [0.0, 0.05, 0.01, 1e-3, 0.0];
    let pts = model_curve(truth, tau0, n, n / 2);
    let r = fit(&pts, &FitOptions::default()).unwrap();
    for i in [1, 2, 3] {
        assert!(rel(r.coef[i].value, truth[i]) < EXACT_REL_TOL, "term {i}");
        assert!(r.coef[i].determined, "term {i} should be determined");
    }
    for i in [0, 4] {
        // Absent terms come out as (numerically) zero and not determined.
        assert!(
            r.c[i]
                * pts
                    .iter()
                    .map(|p| allanscope::model::terms::basis(p.tau_s)[i])
                    .fold(0.0, f64::max)
                < 1e-9 * pts[0].var.min(pts.last().unwrap().var),
            "term {i}: c = {}",
            r.c[i]
        );
        assert!(!r.coef[i].determined);
    }
    // Restricting the terms and the tau range still recovers the truth exactly.
    let opts = FitOptions {
        terms: [false, true, true, true, false],
        tau_min_s: Some(0.1),
        tau_max_s: Some(1000.0),
        ..FitOptions::default()
    };
    let r = fit(&pts, &opts).unwrap();
    assert_eq!(
        r.n_points,
        pts.iter()
            .filter(|p| p.tau_s >= 0.1 && p.tau_s <= 1000.0)
            .count()
    );
    for i in [1, 2, 3] {
        assert!(
            rel(r.coef[i].value, truth[i]) < EXACT_REL_TOL,
            "restricted term {i}"
        );
    }
    assert_eq!(r.c[0], 0.0);
    assert_eq!(r.c[4], 0.0);
    // The paper's method and the log-log fit are also exact on exact data.
    for method in [FitMethod::Paper, FitMethod::LogLog] {
        let r = fit(
            &pts,
            &FitOptions {
                method,
                ..FitOptions::default()
            },
        )
        .unwrap();
        for i in [1, 2, 3] {
            assert!(
                rel(r.coef[i].value, truth[i]) < 1e-6,
                "{method:?} term {i}: {} vs {}",
                r.coef[i].value,
                truth[i]
            );
        }
    }
    // The slope read-out only bounds each term from above (each line lies under the curve).
    let r = fit(
        &pts,
        &FitOptions {
            method: FitMethod::Slopes,
            ..FitOptions::default()
        },
    )
    .unwrap();
    for i in [1, 2, 3] {
        assert!(r.coef[i].value >= truth[i] * (1.0 - 1e-12));
    }
}

#[test]
fn coef_json_has_contract_shape() {
    let tau0 = 0.004;
    let n = (3.0 * 3600.0 / tau0) as usize;
    let pts = model_curve(MA4, tau0, n, n / 2);
    let mut fitter = Fitter::new();
    let r = fitter.fit(&pts, &FitOptions::default()).unwrap();
    let coef = serde_json::to_value(CoefRecord::new(&r)).unwrap();
    for (i, name) in ["Q", "N", "B", "K", "R"].iter().enumerate() {
        let o = &coef[*name];
        let lo = o["lo"].as_f64().unwrap();
        let hi = o["hi"].as_f64().unwrap();
        assert!(lo <= MA4[i] && MA4[i] <= hi, "{name}: [{lo}, {hi}]");
        match o["determined"].as_bool() {
            Some(true) => assert!(rel(o["value"].as_f64().unwrap(), MA4[i]) < EXACT_REL_TOL),
            Some(false) => assert!(o["value"].is_null()),
            None => panic!("{name}: determined missing"),
        }
    }
    // One 3-hour run pins Q, N, B; K and R dominate only the last one or two octaves, whose
    // estimates have a few degrees of freedom, so their honest intervals reach down to zero.
    for (name, det) in [
        ("Q", true),
        ("N", true),
        ("B", true),
        ("K", false),
        ("R", false),
    ] {
        assert_eq!(coef[name]["determined"].as_bool(), Some(det), "{name}");
    }
    assert!(r.gof.is_finite());
    // Undetermined terms print null.
    let mut pts2 = model_curve([0.0, 0.05, 0.01, 1e-3, 0.0], 0.01, 1 << 20, 1 << 19);
    pts2.truncate(pts2.len() - 1);
    let r2 = fitter.fit(&pts2, &FitOptions::default()).unwrap();
    let coef2 = serde_json::to_value(CoefRecord::new(&r2)).unwrap();
    assert!(coef2["Q"]["value"].is_null());
    assert_eq!(coef2["Q"]["determined"].as_bool(), Some(false));
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let pts = model_curve(MA4, 0.004, 1000, 1);
    assert!(fit(&pts, &FitOptions::default()).is_err()); // one point
    let pts = model_curve(MA4, 0.004, 100_000, 1 << 10);
    let none = FitOptions {
        terms: [false; 5],
        ..FitOptions::default()
    };
    assert!(fit(&pts, &none).is_err());
    let mut bad = pts.clone();
    bad[3].tau_s *= 1.5; // inconsistent tau0
    assert!(fit(&bad, &FitOptions::default()).is_err());
    let mut nan = pts.clone();
    nan[2].var = f64::NAN; // skipped, the rest fits
    assert!(fit(&nan, &FitOptions::default()).is_ok());
    assert!("bogus".parse::<FitMethod>().is_err());
    assert_eq!("paper".parse::<FitMethod>(), Ok(FitMethod::Paper));
}
