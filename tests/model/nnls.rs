//! Lawson-Hanson NNLS against brute-force enumeration of active sets (the optimum of an NNLS
//! problem is the unconstrained least-squares solution on its support, so the best feasible
//! subset solution is the answer), on seeded random problems and on degenerate ones.

use allanscope::model::nnls::nnls;
use nalgebra::{DMatrix, DVector};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Relative agreement of residual norms and solutions between NNLS and brute force
/// (both are backward-stable QR solves; 1e-9 leaves room for conditioning ~1e4).
const REL_TOL: f64 = 1e-9;

/// Brute force: for every subset S, least squares on S (via SVD); keep the feasible one with the
/// smallest residual.
fn brute_force(a: &DMatrix<f64>, b: &DVector<f64>) -> (DVector<f64>, f64) {
    let n = a.ncols();
    let mut best = (DVector::zeros(n), b.norm());
    for mask in 1u32..(1 << n) {
        let cols: Vec<usize> = (0..n).filter(|j| mask & (1 << j) != 0).collect();
        let sub = a.select_columns(&cols);
        let svd = sub.clone().svd(true, true);
        let Ok(z) = svd.solve(b, 1e-12) else { continue };
        if z.iter().any(|&v| v < 0.0) {
            continue;
        }
        let mut x = DVector::zeros(n);
        for (k, &j) in cols.iter().enumerate() {
            x[j] = z[k];
        }
        let r = (b - a * &x).norm();
        if r < best.1 * (1.0 - 1e-14) {
            best = (x, r);
        }
    }
    best
}

#[test]
fn nnls_matches_brute_force_on_random_problems() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(20240601);
    let mut n_active_seen = 0;
    for trial in 0..400 {
        let rows = 6 + trial % 25;
        let cols = 1 + trial % 5;
        let a = DMatrix::from_fn(rows, cols, |_, _| rng.random::<f64>() * 2.0 - 1.0);
        let b = DVector::from_fn(rows, |_, _| rng.random::<f64>() * 2.0 - 1.0);
        let sol = nnls(&a, &b).unwrap();
        let (xb, rb) = brute_force(&a, &b);
        assert!(sol.x.iter().all(|&v| v >= 0.0));
        assert!(
            (sol.residual_norm - rb).abs() <= REL_TOL * rb.max(1e-300),
            "trial {trial}: residual {} vs brute force {rb}",
            sol.residual_norm
        );
        let dx = (&sol.x - &xb).norm();
        assert!(
            dx <= REL_TOL * xb.norm().max(1.0) * 1e3,
            "trial {trial}: x differs by {dx}"
        );
        n_active_seen += sol.passive.iter().filter(|p| !**p).count();
    }
    // The random problems must exercise the constraint, not only interior solutions.
    assert!(
        n_active_seen > 100,
        "only {n_active_seen} active constraints seen"
    );
}

#[test]
fn nnls_exact_nonnegative_solution_is_recovered() {
    // b = A x_true with x_true >= 0: residual 0 and x = x_true.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
    let a = DMatrix::from_fn(20, 5, |_, _| rng.random::<f64>());
    let x_true = DVector::from_vec(vec![1.0, 0.0, 2.5, 0.0, 0.3]);
    let b = &a * &x_true;
    let sol = nnls(&a, &b).unwrap();
    assert!((&sol.x - &x_true).norm() <= REL_TOL * x_true.norm());
}

#[test]
fn nnls_collinear_columns() {
    // Columns 0 and 1 identical, column 2 = 2 * column 0: the residual is unique, x is not.
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let base = DVector::from_fn(15, |_, _| rng.random::<f64>() + 0.1);
    let other = DVector::from_fn(15, |_, _| rng.random::<f64>() - 0.5);
    let mut a = DMatrix::zeros(15, 4);
    a.set_column(0, &base);
    a.set_column(1, &base);
    a.set_column(2, &(&base * 2.0));
    a.set_column(3, &other);
    let b = &base * 3.0 + &other * 0.5;
    let sol = nnls(&a, &b).unwrap();
    // Exact fit exists (3 * base + 0.5 * other), so the residual must vanish.
    assert!(
        sol.residual_norm <= 1e-10 * b.norm(),
        "residual {}",
        sol.residual_norm
    );
    let combo = sol.x[0] + sol.x[1] + 2.0 * sol.x[2];
    assert!((combo - 3.0).abs() <= 1e-9, "combined weight {combo}");
    assert!((sol.x[3] - 0.5).abs() <= 1e-9);
    let (_, rb) = brute_force(&a, &b);
    assert!(sol.residual_norm <= rb + 1e-12);
}

#[test]
fn nnls_degenerate_inputs() {
    // All-negative correlation: the answer is x = 0 and residual ||b||.
    let a = DMatrix::from_row_slice(3, 2, &[1.0, 2.0, 1.0, 1.0, 0.0, 3.0]);
    let b = DVector::from_vec(vec![-1.0, -1.0, -1.0]);
    let sol = nnls(&a, &b).unwrap();
    assert_eq!(sol.x, DVector::zeros(2));
    assert!((sol.residual_norm - 3f64.sqrt()).abs() < 1e-15);
    // Zero column and zero rhs.
    let a = DMatrix::from_row_slice(3, 2, &[0.0, 1.0, 0.0, 2.0, 0.0, 3.0]);
    let sol = nnls(&a, &DVector::zeros(3)).unwrap();
    assert_eq!(sol.x, DVector::zeros(2));
    // More columns than rows, and a shape error, and NaN.
    let a = DMatrix::from_row_slice(2, 4, &[1.0, 0.0, 1.0, 2.0, 0.0, 1.0, 1.0, -1.0]);
    let b = DVector::from_vec(vec![1.0, 2.0]);
    let sol = nnls(&a, &b).unwrap();
    assert!(sol.residual_norm < 1e-12);
    assert!(nnls(&a, &DVector::zeros(3)).is_err());
    assert!(nnls(&a, &DVector::from_vec(vec![f64::NAN, 1.0])).is_err());
}
