//! The fit's chi-squared quantile (`model::fit::chi2_quantile`, the curve's 97.5% limits and the
//! Satterthwaite intervals) against statrs' bracketing `inverse_cdf`, against the CDF itself,
//! and against closed forms.

use allanscope::model::fit::chi2_quantile;
use statrs::distribution::{ChiSquared, Continuous, ContinuousCDF, Normal};

/// Degrees of freedom 0.5 .. 1e7, about six per decade, plus the integers near the switch
/// points of the algorithm.
fn grid() -> Vec<f64> {
    let mut v: Vec<f64> = (0..=85)
        .map(|k| 0.5 * 10f64.powf(k as f64 / 6.0))
        .filter(|nu| *nu <= 1.0e7 * (1.0 + 1e-12))
        .collect();
    v.extend([
        1.0, 2.0, 3.0, 4.0, 19.0, 20.0, 21.0, 39.0, 40.0, 41.0, 3999.0, 4000.0, 4001.0,
    ]);
    v.extend([1.0e7]);
    v
}

#[test]
fn matches_statrs_inverse_cdf_to_1e10() {
    let mut worst = (0.0, 0.0, 0.0);
    for nu in grid() {
        let d = ChiSquared::new(nu).unwrap();
        for p in [0.025, 0.975] {
            let q = chi2_quantile(nu, p);
            let r = d.inverse_cdf(p);
            if r < 1e-3 {
                // statrs stops its search on an absolute step of ~1e-16 (seen: 1.7e-7 relative
                // off at nu = 0.5, x = 5e-7); the tiny quantiles are checked in `reference`.
                continue;
            }
            let rel = ((q - r) / r).abs();
            if rel > worst.0 {
                worst = (rel, nu, p);
            }
            assert!(
                rel <= 1e-10,
                "nu = {nu}, p = {p}: {q} vs statrs {r} (rel {rel:e})"
            );
        }
    }
    eprintln!(
        "worst relative difference {:e} at nu = {}, p = {}",
        worst.0, worst.1, worst.2
    );
}

/// The CDF at the returned quantile is `p` to 1e-10 of the quantile's own scale: the error in
/// `x` that `F(x) - p` implies, `(F(x) - p) / f(x)`, is below 1e-10 x. Independent of how
/// statrs inverts.
#[test]
fn cdf_at_quantile_is_p() {
    for nu in grid() {
        let d = ChiSquared::new(nu).unwrap();
        for p in [0.025, 0.975, 0.5, 1e-6, 1.0 - 1e-6] {
            let q = chi2_quantile(nu, p);
            assert!(q > 0.0 && q.is_finite(), "nu = {nu}, p = {p}: {q}");
            let implied = (d.cdf(q) - p) / (q * d.pdf(q));
            assert!(
                implied.abs() <= 1e-10,
                "nu = {nu}, p = {p}: x = {q}, implied relative error {implied:e}"
            );
        }
    }
}

/// Quantiles to 22 digits from a 40-digit evaluation (mpmath: the power series of `P(a, x)`,
/// bisection in `ln x` to 1e-25), across every path of the algorithm: tiny quantiles of small
/// `nu`, the iteration from Wilson-Hilferty's start (`nu < 40`), Cornish-Fisher plus a Halley
/// step (`40 <= nu < 20000`), and the expansion alone (`nu >= 20000`).
#[test]
fn reference() {
    let table: [(f64, f64, f64); 22] = [
        (0.5, 0.025, 5.273_202_591_259_992e-7),
        (0.5, 0.975, 3.433_235_299_960_776),
        (0.25, 0.025, 1.888_026_839_695_763_3e-13),
        (0.25, 0.975, 2.269_062_834_124_689),
        (0.1, 0.025, 1.063_132_377_982_856_2e-32),
        (0.1, 0.975, 1.134_347_523_507_717_5),
        (1.0, 0.025, 9.820_691_171_752_56e-4),
        (1.0, 0.975, 5.023_886_187_314_889),
        (3.0, 0.025, 0.215_795_282_623_897_87),
        (3.0, 0.975, 9.348_403_604_496_148),
        (41.0, 0.025, 25.214_518_638_112_51),
        (41.0, 0.975, 60.560_571_734_843_754),
        (200.0, 0.025, 162.727_982_501_846_28),
        (200.0, 0.975, 241.057_895_506_310_92),
        (2000.0, 0.025, 1_877.946_036_815_390_4),
        (2000.0, 0.975, 2_125.842_302_449_775_5),
        (19999.0, 0.025, 19_608.914_734_548_09),
        (19999.0, 0.975, 20_392.873_849_970_68),
        (20001.0, 0.025, 19_610.895_134_737_647),
        (20001.0, 0.975, 20_394.893_449_783_85),
        (100000.0, 0.025, 99_125.373_300_647_35),
        (100000.0, 0.975, 100_878.415_305_665_57),
    ];
    for (nu, p, exact) in table {
        let q = chi2_quantile(nu, p);
        let rel = ((q - exact) / exact).abs();
        assert!(
            rel <= 1e-13,
            "nu = {nu}, p = {p}: {q} vs {exact} (rel {rel:e})"
        );
    }
}

#[test]
fn closed_forms() {
    // nu = 2: exponential with mean 2, x = -2 ln(1 - p); also just off 2, where the general
    // path runs (the quantile moves with nu by about dx/dnu ~ 1 there).
    for p in [0.025, 0.5, 0.975] {
        let exact = -2.0 * (1.0f64 - p).ln();
        assert!((chi2_quantile(2.0, p) - exact).abs() <= 1e-15 * exact);
        for nu in [2.0 * (1.0 - 1e-9), 2.0 * (1.0 + 1e-9)] {
            let q = chi2_quantile(nu, p);
            assert!(
                ((q - exact) / exact).abs() < 1e-8,
                "nu = {nu}, p = {p}: {q} vs {exact}"
            );
        }
    }
    // nu = 1: the square of a normal quantile, x = z_{(1 + p)/2}^2.
    let n = Normal::new(0.0, 1.0).unwrap();
    for p in [0.025, 0.5, 0.975] {
        let z = n.inverse_cdf(0.5 * (1.0 + p));
        let exact = z * z;
        let q = chi2_quantile(1.0, p);
        assert!(
            ((q - exact) / exact).abs() <= 1e-10,
            "p = {p}: {q} vs {exact}"
        );
    }
    // nu = 4: F(x) = 1 - exp(-x/2) (1 + x/2).
    for p in [0.025, 0.975] {
        let x = chi2_quantile(4.0, p);
        let f = 1.0 - (-x / 2.0).exp() * (1.0 + x / 2.0);
        let pdf = x / 4.0 * (-x / 2.0).exp();
        assert!(
            ((f - p) / (x * pdf)).abs() <= 1e-12,
            "p = {p}: x = {x}, F = {f}"
        );
    }
    // Tabulated: chi2_{0.975}(10) = 20.483177350807388, chi2_{0.025}(10) = 3.246972780236841.
    assert!((chi2_quantile(10.0, 0.975) / 20.483_177_350_807_388 - 1.0).abs() < 1e-12);
    assert!((chi2_quantile(10.0, 0.025) / 3.246_972_780_236_841 - 1.0).abs() < 1e-12);
}

#[test]
fn bad_arguments_give_nan_not_panic() {
    for (nu, p) in [
        (0.0, 0.5),
        (-1.0, 0.5),
        (f64::NAN, 0.5),
        (f64::INFINITY, 0.5),
        (3.0, 0.0),
        (3.0, 1.0),
        (3.0, f64::NAN),
    ] {
        assert!(chi2_quantile(nu, p).is_nan(), "nu = {nu}, p = {p}");
    }
    // Tiny degrees of freedom: the lower quantile underflows to 0, never NaN.
    let q = chi2_quantile(1e-6, 0.025);
    assert!(q >= 0.0 && q.is_finite());
}
