//! Non-negative least squares for small dense problems: minimise `||A x - b||_2` subject to
//! `x >= 0` by the active-set method of Lawson and Hanson ("Solving Least Squares Problems", 1974,
//! chapter 23, algorithm NNLS). docs/theory.md section 2: the five-term model is linear in
//! `c = (Q^2, N^2, B^2, K^2, R^2) >= 0`, so a weighted fit is exactly this problem.
//!
//! Sized for the model fit (a handful of columns, tens of rows); the inner least-squares
//! subproblems are solved by Householder QR on the passive columns. Scaling of the columns is left
//! to the caller (the solution's sign pattern does not depend on it, the conditioning does).

use nalgebra::{DMatrix, DVector};

/// Why a problem could not be solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NnlsError {
    #[error("nnls: A has {rows} rows but b has {b_len} entries")]
    Shape { rows: usize, b_len: usize },
    #[error("nnls: A or b holds a non-finite value")]
    NonFinite,
}

/// The solution of one NNLS problem.
#[derive(Debug, Clone, PartialEq)]
pub struct NnlsSolution {
    /// The minimiser, every entry `>= 0`.
    pub x: DVector<f64>,
    /// `||A x - b||_2`.
    pub residual_norm: f64,
    /// `true` for the columns left free (the passive set); the others are held at zero.
    pub passive: Vec<bool>,
    /// Outer iterations used (columns moved into the passive set).
    pub iterations: usize,
}

/// Unconstrained least squares on the columns `cols` of `a` by Householder QR.
///
/// Returns the coefficients of those columns, or `None` when a column is numerically dependent
/// on the ones before it (its diagonal entry of R falls below `rel_tol` of the column's norm).
fn least_squares_on(
    a: &DMatrix<f64>,
    b: &DVector<f64>,
    cols: &[usize],
    rel_tol: f64,
) -> Option<Vec<f64>> {
    let m = a.nrows();
    let p = cols.len();
    if p == 0 {
        return Some(Vec::new());
    }
    if p > m {
        return None;
    }
    // Working copies: columns of A_P (column-major in a Vec) and the right-hand side.
    let mut r: Vec<Vec<f64>> = cols
        .iter()
        .map(|&j| a.column(j).iter().copied().collect())
        .collect();
    let norms: Vec<f64> = r
        .iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();
    let mut y: Vec<f64> = b.iter().copied().collect();
    for k in 0..p {
        // Householder vector for r[k][k..].
        let alpha_norm = r[k][k..].iter().map(|v| v * v).sum::<f64>().sqrt();
        if alpha_norm <= rel_tol * norms[k] || alpha_norm == 0.0 {
            return None;
        }
        let alpha = if r[k][k] > 0.0 {
            -alpha_norm
        } else {
            alpha_norm
        };
        let mut v: Vec<f64> = r[k][k..].to_vec();
        v[0] -= alpha;
        let vnorm2: f64 = v.iter().map(|t| t * t).sum();
        if vnorm2 > 0.0 {
            for col in r.iter_mut().skip(k) {
                let dot: f64 = v.iter().zip(&col[k..]).map(|(p, q)| p * q).sum();
                let f = 2.0 * dot / vnorm2;
                for (ci, vi) in col[k..].iter_mut().zip(&v) {
                    *ci -= f * vi;
                }
            }
            let dot: f64 = v.iter().zip(&y[k..]).map(|(p, q)| p * q).sum();
            let f = 2.0 * dot / vnorm2;
            for (yi, vi) in y[k..].iter_mut().zip(&v) {
                *yi -= f * vi;
            }
        }
    }
    // Back substitution R x = (Q' b)[..p].
    let mut x = vec![0.0; p];
    for k in (0..p).rev() {
        let mut s = y[k];
        for j in k + 1..p {
            s -= r[j][k] * x[j];
        }
        x[k] = s / r[k][k];
    }
    Some(x)
}

/// Solve `min ||A x - b||_2` subject to `x >= 0` (Lawson-Hanson).
///
/// Always terminates: the outer loop is capped at `3 * ncols + 10` passes (finite-precision
/// safeguard; Lawson and Hanson prove termination in exact arithmetic).
pub fn nnls(a: &DMatrix<f64>, b: &DVector<f64>) -> Result<NnlsSolution, NnlsError> {
    let (m, n) = a.shape();
    if b.len() != m {
        return Err(NnlsError::Shape {
            rows: m,
            b_len: b.len(),
        });
    }
    if a.iter().chain(b.iter()).any(|v| !v.is_finite()) {
        return Err(NnlsError::NonFinite);
    }
    // Tolerances: the dual (gradient) test is relative to the scale of A'b; a column counts as
    // dependent when QR leaves less than 1e-10 of its norm.
    let a_max = a.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let b_norm = b.norm();
    let dual_tol = 10.0 * f64::EPSILON * (m.max(n) as f64) * a_max * b_norm.max(f64::MIN_POSITIVE);
    let dep_tol = 1e-10;

    let mut x = DVector::<f64>::zeros(n);
    let mut passive = vec![false; n];
    let mut excluded = vec![false; n];
    let max_outer = 3 * n + 10;
    let mut iterations = 0;

    while iterations < max_outer {
        let resid = b - a * &x;
        let w = a.transpose() * &resid;
        // Most positive dual among the free (zero) columns.
        let mut t = None;
        let mut best = dual_tol;
        for j in 0..n {
            if !passive[j] && !excluded[j] && w[j] > best {
                best = w[j];
                t = Some(j);
            }
        }
        let Some(t) = t else { break };
        iterations += 1;
        passive[t] = true;
        let mut cols: Vec<usize> = (0..n).filter(|&j| passive[j]).collect();
        let Some(mut z) = least_squares_on(a, b, &cols, dep_tol) else {
            // Column t is numerically in the span of the passive ones: it cannot lower the
            // residual, so leave it at zero for good.
            passive[t] = false;
            excluded[t] = true;
            continue;
        };
        // Inner loop: step back towards x until the subproblem solution is feasible.
        let mut inner = 0;
        while z.iter().any(|&v| v <= 0.0) && inner <= n {
            inner += 1;
            let mut alpha = f64::INFINITY;
            let mut blocking = None;
            for (k, &j) in cols.iter().enumerate() {
                if z[k] <= 0.0 {
                    let denom = x[j] - z[k];
                    let step = if denom > 0.0 { x[j] / denom } else { 0.0 };
                    if step < alpha {
                        alpha = step;
                        blocking = Some(j);
                    }
                }
            }
            let alpha = alpha.clamp(0.0, 1.0);
            for (k, &j) in cols.iter().enumerate() {
                x[j] += alpha * (z[k] - x[j]);
            }
            if let Some(j) = blocking {
                x[j] = 0.0;
            }
            for &j in &cols {
                if x[j] <= 0.0 {
                    x[j] = 0.0;
                    passive[j] = false;
                }
            }
            cols = (0..n).filter(|&j| passive[j]).collect();
            match least_squares_on(a, b, &cols, dep_tol) {
                Some(zz) => z = zz,
                None => break,
            }
        }
        for j in 0..n {
            x[j] = 0.0;
        }
        for (k, &j) in cols.iter().enumerate() {
            x[j] = z[k].max(0.0);
            if x[j] == 0.0 {
                passive[j] = false;
            }
        }
    }
    let residual_norm = (b - a * &x).norm();
    Ok(NnlsSolution {
        x,
        residual_norm,
        passive,
        iterations,
    })
}
