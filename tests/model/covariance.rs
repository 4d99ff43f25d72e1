//! The analytic covariance of AVAR estimates between taus (src/model/avar_cov/): closed forms of
//! each term's AVAR, quadrature against the lag-by-lag sum, and the whole matrix against a dense
//! computation from the phase's own covariance matrix.

use allanscope::allan::CurvePoint;
use allanscope::model::avar_cov::{
    clear_shared_cache, cov_points, flicker_far_field, pair_sums, pair_sums_advanced,
    pair_sums_exact, second_difference_cov, AvarCovariance, CovPoint, PairSums,
};
use nalgebra::DMatrix;
use std::f64::consts::{LN_2, PI};

/// Agreement of two evaluations of the same algebra in floating point.
const ALGEBRA_TOL: f64 = 1e-9;
/// Quadrature (graded Gauss-Legendre + Euler-Maclaurin) against the exact lag sum.
const QUADRATURE_TOL: f64 = 1e-6;
/// The far-field series against the direct sum, limited by the direct sum's cancellation.
const SERIES_TOL: f64 = 1e-8;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

#[test]
fn generalized_covariances_reproduce_avar_closed_forms() {
    // Var D_m = 2 tau^2 AVAR(tau) with tau = m (tau0 = 1) and unit coefficients; closed forms of
    // docs/theory.md section 2: 3/tau^2, 1/tau, 2 ln2/pi, tau/3.
    for m in [1u64, 2, 7, 64, 1000, 1 << 20] {
        let tau = m as f64;
        let v = second_difference_cov(0, m, m);
        let expect = [
            2.0 * tau * tau * 3.0 / (tau * tau),
            2.0 * tau * tau / tau,
            2.0 * tau * tau * 2.0 * LN_2 / PI,
            2.0 * tau * tau * tau / 3.0,
        ];
        for t in 0..4 {
            assert!(
                rel(v[t], expect[t]) < ALGEBRA_TOL,
                "m {m} term {t}: {} vs {}",
                v[t],
                expect[t]
            );
        }
    }
}

/// The flicker linear sum `sum_h n(h) g_B(h)` is the residual of a cancelling sum (over all lags
/// it is 0): the quadrature leaves about 1e-7 of its absolute scale, which can be 1e-3 of the
/// residual (measured before and after the live update was added: m1 = 1, m2 = 16, N = 30000
/// gives 1261.29 against the exact 1261.93). It weights only the ramp x flicker cross term.
const FLICKER_LIN_TOL: f64 = 1e-3;

fn check_sums(a: &PairSums, b: &PairSums, tol: f64, what: &str) {
    check_sums_lin(a, b, tol, tol * 10.0, what)
}

fn check_sums_lin(a: &PairSums, b: &PairSums, tol: f64, lin_tol: f64, what: &str) {
    // Compare each entry relative to the scale of its row/column (entries can cancel to ~0).
    for t in 0..4 {
        for u in 0..4 {
            let scale = (a.quad[t][t].abs() * a.quad[u][u].abs()).sqrt().max(1e-300);
            let d = (a.quad[t][u] - b.quad[t][u]).abs() / scale;
            assert!(
                d < tol,
                "{what}: quad[{t}][{u}] {} vs {}",
                a.quad[t][u],
                b.quad[t][u]
            );
        }
        // The linear sums nearly cancel for terms whose spectrum vanishes at f = 0; scale by
        // the absolute sum instead.
        let scale = (a.quad[t][t].abs() * 1e3)
            .sqrt()
            .max(b.lin[t].abs())
            .max(1e-300);
        let d = (a.lin[t] - b.lin[t]).abs() / scale;
        let lt = if t == 2 { lin_tol } else { tol * 10.0 };
        assert!(d < lt, "{what}: lin[{t}] {} vs {}", a.lin[t], b.lin[t]);
    }
}

#[test]
fn quadrature_matches_exact_lag_sum() {
    // (m1, m2, N increments): M = N - 2m + 1 for contiguous data.
    let cases = [
        (1u64, 1u64, 50u64),
        (1, 2, 1000),
        (3, 17, 5000),
        (16, 16, 100_000),
        (1, 256, 100_000),
        (64, 1024, 200_000),
        (1000, 2000, 8001),
        (4096, 32768, 65536),
        (32768, 32768, 65536),
    ];
    for (m1, m2, n) in cases {
        let (big1, big2) = (n - 2 * m1 + 1, n - 2 * m2 + 1);
        let q = pair_sums(m1, m2, big1, big2);
        let e = pair_sums_exact(m1, m2, big1, big2);
        check_sums(&q, &e, QUADRATURE_TOL, &format!("m1 {m1} m2 {m2} N {n}"));
    }
}

/// Dense reference: phase covariance matrix of the five-term model with Q, N, K random and a rate
/// ramp R as a mean, for phase points x_0..x_n (x_0 anchored: rate walk and phase walk start at 0).
fn phase_cov(n: usize, tau0: f64, c: &[f64; 5]) -> (DMatrix<f64>, Vec<f64>) {
    let mut s = DMatrix::zeros(n + 1, n + 1);
    for i in 0..=n {
        for j in 0..=n {
            let (ti, tj) = (i as f64 * tau0, j as f64 * tau0);
            let (lo, hi) = (ti.min(tj), ti.max(tj));
            let mut v = 0.0;
            if i == j {
                v += c[0]; // white phase, sd Q
            }
            v += c[1] * lo; // random walk of phase (white rate): Cov = N^2 min(s, t)
            v += c[3] * (lo * lo * hi / 2.0 - lo.powi(3) / 6.0); // integrated Brownian rate
            s[(i, j)] = v;
        }
    }
    let mean = (0..=n)
        .map(|i| c[4].sqrt() * (i as f64 * tau0).powi(2) / 2.0)
        .collect();
    (s, mean)
}

/// AVAR_hat(m) = x' A_m x.
fn avar_form(n: usize, m: usize, tau0: f64) -> DMatrix<f64> {
    let mut a = DMatrix::zeros(n + 1, n + 1);
    let count = n + 1 - 2 * m;
    let tau = m as f64 * tau0;
    let norm = 1.0 / (2.0 * tau * tau * count as f64);
    for k in 0..count {
        let idx = [k, k + m, k + 2 * m];
        let w = [1.0, -2.0, 1.0];
        for (p, wp) in idx.iter().zip(w) {
            for (q, wq) in idx.iter().zip(w) {
                a[(*p, *q)] += norm * wp * wq;
            }
        }
    }
    a
}

#[test]
fn covariance_matrix_matches_dense_gaussian_algebra() {
    // For Gaussian x with covariance S and mean mu:
    // Cov(x'A x, x'B x) = 2 tr(A S B S) + 4 mu' A S B mu.
    let n = 48;
    let tau0 = 0.01;
    let ms = [1usize, 2, 3, 5, 8, 13, 24];
    let c = [
        0.3f64.powi(2),
        0.7f64.powi(2),
        0.0,
        2.0f64.powi(2),
        5.0f64.powi(2),
    ];
    let (s, mu) = phase_cov(n, tau0, &c);
    let mu = nalgebra::DVector::from_vec(mu);
    let forms: Vec<DMatrix<f64>> = ms.iter().map(|&m| avar_form(n, m, tau0)).collect();
    let pts: Vec<CovPoint> = ms
        .iter()
        .map(|&m| CovPoint {
            m: m as u64,
            count: (n + 1 - 2 * m) as u64,
        })
        .collect();
    let mut cov = AvarCovariance::new();
    let got = cov.matrix(tau0, &pts, &c);
    for i in 0..ms.len() {
        for j in 0..ms.len() {
            let as_ = &forms[i] * &s;
            let bs = &forms[j] * &s;
            let expect =
                2.0 * (&as_ * &bs).trace() + 4.0 * (mu.transpose() * &as_ * &forms[j] * &mu)[0];
            let scale = (got[(i, i)] * got[(j, j)]).sqrt();
            assert!(
                (got[(i, j)] - expect).abs() < 1e-9 * scale,
                "m {} m {}: {} vs {}",
                ms[i],
                ms[j],
                got[(i, j)],
                expect
            );
        }
    }
    // The mean of each estimate is the model: E x'Ax = tr(A S) + mu'A mu.
    for (i, &m) in ms.iter().enumerate() {
        let e = (&forms[i] * &s).trace() + (mu.transpose() * &forms[i] * &mu)[0];
        let model = allanscope::model::terms::avar(c.map(f64::sqrt), m as f64 * tau0);
        assert!(rel(e, model) < ALGEBRA_TOL, "mean at m {m}: {e} vs {model}");
    }
}

#[test]
fn white_fm_edf_matches_known_large_sample_form() {
    // White FM, M >> m: Var(AVAR_hat) -> AVAR^2 * 2 / (3M/(2m)) (edf = 3M/(2m), Howe, Allan and
    // Barnes 1981); at m = 64, M = 1e6 the finite-m correction is < 1e-3.
    let (m, big) = (64u64, 1_000_000u64);
    let mut cov = AvarCovariance::new();
    let pts = [CovPoint { m, count: big }];
    let v = cov.matrix(1.0, &pts, &[0.0, 1.0, 0.0, 0.0, 0.0])[(0, 0)];
    let avar = 1.0 / m as f64;
    let edf = 2.0 * avar * avar / v;
    let expect = 3.0 * big as f64 / (2.0 * m as f64);
    assert!(rel(edf, expect) < 2e-3, "edf {edf} vs {expect}");
}

/// Full-overlap octave points m = 1 .. 2^18 of an `n`-increment run.
fn octave_grid(n: u64) -> Vec<CovPoint> {
    octave_grid_to(n, 19)
}

/// Full-overlap octave points m = 1 .. 2^(levels - 1) of an `n`-increment run.
fn octave_grid_to(n: u64, levels: u32) -> Vec<CovPoint> {
    (0..levels)
        .map(|k| {
            let m = 1u64 << k;
            CovPoint {
                m,
                count: n - 2 * m + 1,
            }
        })
        .collect()
}

#[test]
fn count_tolerance_reuse_is_accurate() {
    // Octave grid of a 2^20-increment run, then the same grid 2% further into the run: sums reused
    // and scaled must match a fresh computation to 1e-3 relative (module doc of avar_cov).
    let c = [1e-2, 1.0, 0.5, 1e-3, 1e-6];
    let mut live = AvarCovariance::with_count_tolerance(0.02);
    let n0 = 1u64 << 20;
    live.matrix(0.01, &octave_grid(n0), &c);
    let n1 = n0 + n0 / 50;
    let reused = live.matrix(0.01, &octave_grid(n1), &c);
    let fresh = AvarCovariance::new().matrix(0.01, &octave_grid(n1), &c);
    for i in 0..19 {
        for j in 0..19 {
            let scale = (fresh[(i, i)] * fresh[(j, j)]).sqrt();
            // (The top octaves' counts move by more than 2% here, so those pairs are recomputed.)
            let d = (reused[(i, j)] - fresh[(i, j)]).abs() / scale;
            assert!(
                d < 1e-3,
                "({i}, {j}): {} vs {}",
                reused[(i, j)],
                fresh[(i, j)]
            );
        }
    }
}

#[test]
fn far_field_series_matches_direct_flicker_covariance() {
    // The series of avar_cov::flicker_series against the direct nine-term sum of G_B, where the
    // series is used (|h| >= 16 max(m1, m2)) and a little inside (8 max: still convergent). The
    // direct sum cancels terms of size m^2 ln|h| down to m^4 / h^2, so it is itself accurate only
    // to about 1e-16 h^2 ln|h| / min(m1, m2)^2 relative: the comparison stops at
    // |h| = 37.5 max(m1, m2), and further out the series is checked against 50-digit values (mpmath, the same nine-term sum).
    for (m1, m2) in [(1u64, 1u64), (1, 2), (3, 17), (64, 64), (1 << 10, 1 << 12)] {
        let s = m1.max(m2) as f64;
        for f in [8.0, 16.0, 37.5] {
            for sign in [1.0, -1.0] {
                let h = (sign * f * s).round();
                let direct = second_difference_cov(h as i64, m1, m2)[2];
                let series = flicker_far_field(h, m1, m2);
                assert!(
                    rel(series, direct) < SERIES_TOL,
                    "m1 {m1} m2 {m2} h {h}: {series} vs {direct}"
                );
            }
        }
    }
}

#[test]
#[allow(clippy::excessive_precision)] // the reference digits as mpmath printed them
fn far_field_series_matches_high_precision_values() {
    // (h, m1, m2, g_B): sum_{i,j} a_i a_j G_B(h + i m1 - j m2), G_B(t) = t^2 ln|t| / (2 pi), in
    // 50-digit arithmetic (mpmath).
    let refs: [(f64, u64, u64, f64); 8] = [
        (1000.0, 1, 1, -3.1831020449415432106e-7),
        (-1000.0, 1, 1, -3.1831020449415432106e-7),
        (1700.0, 3, 17, -0.00029127157507837216237),
        (-272.0, 3, 17, -0.010140298934425855117),
        (8388608.0, 1, 1048576, -0.0065633211557657711289),
        (-16777216.0, 1, 1048576, -0.0011033283904895785357),
        (1024.0, 64, 64, -5.1129699829090014802),
        (1000000000.0, 1024, 4096, -5.5998011426974124079e-6),
    ];
    for (h, m1, m2, g) in refs {
        let series = flicker_far_field(h, m1, m2);
        assert!(
            rel(series, g) < ALGEBRA_TOL,
            "h {h} m1 {m1} m2 {m2}: {series} vs {g}"
        );
    }
}

#[test]
fn incremental_sums_match_exact_lag_sum() {
    // The live cache's update (counts grown by d at both estimates, one contiguous segment): it
    // reproduces the fresh quadrature at the final counts to rounding (the update is an identity
    // of the pair count), and the lag-by-lag sum to the quadrature's tolerance. Small steps,
    // large steps, and pairs whose clusters are as long as the record (top octaves).
    let cases: [(u64, u64, u64, &[u64]); 7] = [
        (1, 1, 200, &[1, 7, 250, 5000]),
        (1, 16, 10_000, &[250, 250, 250, 20_000]),
        (4, 256, 3000, &[1, 100, 2048, 100_000]),
        (64, 1024, 3000, &[250, 250, 200_000]),
        (1024, 4096, 8193, &[250, 3000, 60_000]),
        (16384, 32768, 65537, &[250, 1000, 10_000]),
        (16, 16, 100_000, &[250; 8]),
    ];
    for (m1, m2, n0, steps) in cases {
        let mut n = n0;
        let mut counts = vec![(n - 2 * m1 + 1, n - 2 * m2 + 1)];
        for d in steps {
            n += d;
            counts.push((n - 2 * m1 + 1, n - 2 * m2 + 1));
        }
        let adv = pair_sums_advanced(m1, m2, &counts).expect("counts move together");
        let (c1, c2) = *counts.last().unwrap();
        let fresh = pair_sums(m1, m2, c1, c2);
        let what = format!("m1 {m1} m2 {m2} N {n}");
        check_sums(
            &adv,
            &fresh,
            QUADRATURE_TOL,
            &format!("advanced/fresh {what}"),
        );
        let exact = pair_sums_exact(m1, m2, c1, c2);
        check_sums_lin(
            &adv,
            &exact,
            QUADRATURE_TOL,
            FLICKER_LIN_TOL,
            &format!("advanced/exact {what}"),
        );
    }
}

#[test]
fn shared_cache_keeps_each_count_apart() {
    // Two threads fit two runs of different lengths at once, twice each, through the
    // process-wide cache of pair sums: every entry is the one `pair_sums` computes for its own
    // counts (a cache keyed without the counts would hand one run the other's sums, 2% apart).
    clear_shared_cache();
    let c = [0.0, 1.0, 0.0, 0.0, 0.0];
    let runs = [1u64 << 16, (1u64 << 16) + (1 << 16) / 50];
    let got: Vec<(u64, DMatrix<f64>)> = std::thread::scope(|s| {
        let hs: Vec<_> = runs
            .iter()
            .map(|&n| {
                s.spawn(move || {
                    let first = AvarCovariance::new().matrix(1.0, &octave_grid_to(n, 15), &c);
                    let again = AvarCovariance::new().matrix(1.0, &octave_grid_to(n, 15), &c);
                    assert_eq!(
                        first, again,
                        "n = {n}: a cached pair differs from its first value"
                    );
                    (n, again)
                })
            })
            .collect();
        hs.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (n, m) in got {
        let pts = octave_grid_to(n, 15);
        for (i, a) in pts.iter().enumerate() {
            for (j, b) in pts.iter().enumerate().skip(i) {
                let s = pair_sums(a.m, b.m, a.count, b.count);
                // White rate alone at tau0 = 1: Cov = 2 quad_NN / (4 m1^2 m2^2 M1 M2).
                let t12 = (a.m * a.m * b.m * b.m) as f64;
                let want = 2.0 * s.quad[1][1] / (4.0 * t12 * a.count as f64 * b.count as f64);
                assert!(
                    rel(m[(i, j)], want) < 1e-15,
                    "n = {n} ({i}, {j}): {} vs {want}",
                    m[(i, j)]
                );
            }
        }
    }
}

#[test]
fn live_matrix_equals_fresh_matrix() {
    // A cache advanced over 40 refits (+250 increments each) gives the matrix a fresh cache gives
    // at the final counts, to the quadrature's tolerance.
    let c = [1e-2, 1.0, 0.5, 1e-3, 1e-6];
    let mut live = AvarCovariance::new();
    let mut n = 1u64 << 20;
    for _ in 0..40 {
        live.matrix(0.01, &octave_grid(n), &c);
        n += 250;
    }
    let got = live.matrix(0.01, &octave_grid(n), &c);
    let fresh = AvarCovariance::new().matrix(0.01, &octave_grid(n), &c);
    for i in 0..19 {
        for j in 0..19 {
            let scale = (fresh[(i, i)] * fresh[(j, j)]).sqrt();
            let d = (got[(i, j)] - fresh[(i, j)]).abs() / scale;
            assert!(
                d < QUADRATURE_TOL,
                "({i}, {j}): {} vs {}",
                got[(i, j)],
                fresh[(i, j)]
            );
        }
    }
}

#[test]
fn strided_levels_get_their_full_span() {
    // Bounded overlap L = 16 on 10_000 increments: m = 64 has stride 4, so
    // floor((10000 - 128)/4) + 1 = 2469 differences spanning the full count 10000 - 128 + 1 = 9873;
    // m = 8 has stride 1 and keeps its own count (9985).
    let pt = |m: u64, count: u64, stride: u64| CurvePoint {
        m,
        tau_s: m as f64 * 0.01,
        var: 1.0,
        count,
        edf: 1.0,
        alpha: 0,
        sigma_lo: f64::NAN,
        sigma_hi: f64::NAN,
        stride,
        n_phase: 10_001,
    };
    let pts = [pt(1, 9999, 1), pt(8, 9985, 1), pt(64, 2469, 4)];
    let cp = cov_points(&pts);
    assert_eq!(cp[0].count, 9999);
    assert_eq!(cp[1].count, 9985);
    assert_eq!(cp[2].count, 9873);
}
