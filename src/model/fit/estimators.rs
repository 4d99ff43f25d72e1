//! The estimators of the five-term coefficients: the tau selection, the model-weighted NNLS
//! (default), the seed paper's reweighted fit, the slope read-out and the log-log fit.

#[allow(unused_imports)]
use super::*;

pub(super) fn model_values(x: &DMatrix<f64>, c: &[f64; 5]) -> DVector<f64> {
    x * DVector::from_column_slice(c)
}

pub(super) fn select(points: &[CurvePoint], opts: &FitOptions) -> Result<Problem, FitError> {
    if !opts.terms.iter().any(|t| *t) {
        return Err(FitError::NoTerms);
    }
    let lo = opts.tau_min_s.unwrap_or(0.0);
    let hi = opts.tau_max_s.unwrap_or(f64::INFINITY);
    let mut sel: Vec<&CurvePoint> = points
        .iter()
        .filter(|p| {
            p.tau_s >= lo
                && p.tau_s <= hi
                && p.m >= 1
                && p.count >= 1
                && p.tau_s.is_finite()
                && p.tau_s > 0.0
                && p.var.is_finite()
                && p.var > 0.0
        })
        .collect();
    sel.sort_by(|a, b| a.tau_s.total_cmp(&b.tau_s));
    sel.dedup_by(|a, b| a.m == b.m);
    let need = 2;
    if sel.len() < need {
        return Err(FitError::TooFewPoints {
            usable: sel.len(),
            need,
        });
    }
    let tau0_s = sel[0].tau_s / sel[0].m as f64;
    for p in &sel {
        let t0 = p.tau_s / p.m as f64;
        if (t0 - tau0_s).abs() > 1e-9 * tau0_s {
            return Err(FitError::InconsistentTau0(tau0_s, t0));
        }
    }
    let j = sel.len();
    let tau: Vec<f64> = sel.iter().map(|p| p.tau_s).collect();
    let y = DVector::from_iterator(j, sel.iter().map(|p| p.var));
    // A missing or silly edf falls back to the white-FM large-sample form 3M/(2m) (at least 1).
    let edf: Vec<f64> = sel
        .iter()
        .map(|p| {
            if p.edf.is_finite() && p.edf > 0.0 {
                p.edf
            } else {
                (1.5 * p.count as f64 / p.m as f64).max(1.0)
            }
        })
        .collect();
    let x = DMatrix::from_fn(
        j,
        5,
        |r, t| {
            if opts.terms[t] {
                basis(tau[r])[t]
            } else {
                0.0
            }
        },
    );
    // Covariance counts and strides from the whole curve (a strided level's span, see
    // `cov_points`).
    let all_cov = cov_points(points);
    let all_strides = strides(points);
    let index: Vec<Option<usize>> = sel
        .iter()
        .map(|p| points.iter().position(|q| std::ptr::eq(q, *p)))
        .collect();
    let cov_pts = sel
        .iter()
        .zip(&index)
        .map(|(p, i)| {
            i.map(|i| all_cov[i]).unwrap_or(CovPoint {
                m: p.m,
                count: p.count,
            })
        })
        .collect();
    let cov_strides = index
        .iter()
        .map(|i| i.map_or(1, |i| all_strides[i]))
        .collect();
    Ok(Problem {
        tau,
        y,
        edf,
        x,
        cov_pts,
        cov_strides,
        tau0_s,
        allowed: opts.terms,
    })
}

/// Weighted NNLS: minimise `sum_j w_j (z_j - (X c)_j)^2`, `c >= 0`, with the columns scaled to
/// unit norm for conditioning. Returns `c` and the linear map `G` with `c = G z` on the passive
/// set (zeros elsewhere).
pub(super) fn weighted_nnls(
    x: &DMatrix<f64>,
    z: &DVector<f64>,
    w: &[f64],
    allowed: &[bool; 5],
) -> Result<([f64; 5], DMatrix<f64>), FitError> {
    let sol = weighted_nnls_solve(x, z, w, allowed)?;
    Ok((sol.c, sol.map()))
}

/// A solved [`weighted_nnls`] whose map `G` is formed only when asked for (an iterated fit
/// needs the map of its last pass alone).
pub(super) struct WeightedSolution {
    pub(super) c: [f64; 5],
    /// The weighted, column-scaled design.
    pub(super) a: DMatrix<f64>,
    pub(super) sw: Vec<f64>,
    pub(super) scale: [f64; 5],
    pub(super) passive: [bool; 5],
}

pub(super) fn weighted_nnls_solve(
    x: &DMatrix<f64>,
    z: &DVector<f64>,
    w: &[f64],
    allowed: &[bool; 5],
) -> Result<WeightedSolution, FitError> {
    let j = x.nrows();
    let sw: Vec<f64> = w.iter().map(|v| v.max(0.0).sqrt()).collect();
    let mut a = DMatrix::from_fn(j, 5, |r, t| x[(r, t)] * sw[r]);
    let mut scale = [0.0; 5];
    for t in 0..5 {
        let n = a.column(t).norm();
        scale[t] = if allowed[t] && n > 0.0 { 1.0 / n } else { 0.0 };
        a.column_mut(t).scale_mut(scale[t]);
    }
    let b = DVector::from_fn(j, |r, _| z[r] * sw[r]);
    let sol = nnls(&a, &b)?;
    let mut c = [0.0; 5];
    for t in 0..5 {
        c[t] = sol.x[t] * scale[t];
    }
    Ok(WeightedSolution {
        c,
        a,
        sw,
        scale,
        passive: std::array::from_fn(|t| sol.passive[t]),
    })
}

impl WeightedSolution {
    /// `G` on the passive set: `(A_P' A_P)^-1 A_P' diag(sw)`, then the column scaling undone.
    fn map(&self) -> DMatrix<f64> {
        let (a, sw, scale, c) = (&self.a, &self.sw, &self.scale, &self.c);
        let j = a.nrows();
        let cols: Vec<usize> = (0..5).filter(|&t| self.passive[t] && c[t] > 0.0).collect();
        let mut g = DMatrix::zeros(5, j);
        if !cols.is_empty() {
            let ap = a.select_columns(&cols);
            let ata = ap.transpose() * &ap;
            let inv = ata
                .clone()
                .cholesky()
                .map(|ch| ch.inverse())
                .or_else(|| ata.pseudo_inverse(1e-13).ok());
            if let Some(inv) = inv {
                let gp = inv * ap.transpose();
                for (k, &t) in cols.iter().enumerate() {
                    for r in 0..j {
                        g[(t, r)] = gp[(k, r)] * sw[r] * scale[t];
                    }
                }
            }
        }
        g
    }
}

pub(super) fn converged(old: &[f64; 5], new: &[f64; 5], x: &DMatrix<f64>, tol: f64) -> bool {
    // Compare each term's largest contribution over the taus with the model there.
    let model = model_values(x, new);
    (0..5).all(|t| {
        (0..x.nrows()).all(|r| (x[(r, t)] * (new[t] - old[t])).abs() <= tol * model[r].abs())
    })
}

pub(super) fn floor_model(model: &mut DVector<f64>, y: &DVector<f64>) {
    let floor = 1e-12 * y.amax();
    for v in model.iter_mut() {
        *v = v.max(floor);
    }
}

/// docs/theory.md section 2: weights `edf_j / (2 AVAR_model(tau_j)^2)` at the current model, iterated.
pub(super) fn est_model(prob: &Problem, opts: &FitOptions) -> Result<Estimate, FitError> {
    // Start from the data's own weights, then move the weights to the model.
    let w0: Vec<f64> = (0..prob.y.len())
        .map(|r| prob.edf[r] / (2.0 * prob.y[r] * prob.y[r]))
        .collect();
    let mut sol = weighted_nnls_solve(&prob.x, &prob.y, &w0, &prob.allowed)?;
    let mut c = sol.c;
    let mut iterations = 0;
    for _ in 0..opts.max_iter {
        iterations += 1;
        let mut model = model_values(&prob.x, &c);
        floor_model(&mut model, &prob.y);
        let w: Vec<f64> = (0..prob.y.len())
            .map(|r| prob.edf[r] / (2.0 * model[r] * model[r]))
            .collect();
        sol = weighted_nnls_solve(&prob.x, &prob.y, &w, &prob.allowed)?;
        let done = converged(&c, &sol.c, &prob.x, opts.rel_tol);
        c = sol.c;
        if done {
            break;
        }
    }
    // The map of the last pass (the one that produced c).
    let g = sol.map();
    Ok(Estimate { c, g, iterations })
}

/// The seed paper's formulas (6)-(7) (the seed paper, docs/theory.md section 6).
pub(super) fn est_paper(prob: &Problem) -> Result<Estimate, FitError> {
    let j = prob.y.len();
    let w1: Vec<f64> = (0..j).map(|r| 1.0 / prob.y[r]).collect();
    let (c1, g1) = weighted_nnls(&prob.x, &prob.y, &w1, &prob.allowed)?;
    let mut model = model_values(&prob.x, &c1);
    floor_model(&mut model, &prob.y);
    let mut c = [0.0; 5];
    let mut g = DMatrix::zeros(5, j);
    for i in 0..5 {
        if c1[i] <= 0.0 {
            continue;
        }
        // P = term_i / (AVAR_hat * p^2), formula (7).
        let w: Vec<f64> = (0..j)
            .map(|r| prob.x[(r, i)] * c1[i] / (prob.y[r] * model[r]))
            .collect();
        let (ci, gi) = weighted_nnls(&prob.x, &prob.y, &w, &prob.allowed)?;
        c[i] = ci[i];
        g.set_row(i, &gi.row(i));
        if ci[i] <= 0.0 {
            // The per-term fit dropped it; keep the first-pass value rather than lose the term.
            c[i] = c1[i];
            g.set_row(i, &g1.row(i));
        }
    }
    Ok(Estimate {
        c,
        g,
        iterations: 2,
    })
}

/// IEEE Std 952 slope read-out: `c_i = min_j AVAR_hat_j / basis_i(tau_j)` (the line of the term's
/// slope that touches the curve from below).
pub(super) fn est_slopes(prob: &Problem) -> Estimate {
    let j = prob.y.len();
    let mut c = [0.0; 5];
    let mut g = DMatrix::zeros(5, j);
    for i in 0..5 {
        if !prob.allowed[i] {
            continue;
        }
        let mut best = (f64::INFINITY, 0);
        for r in 0..j {
            let v = prob.y[r] / prob.x[(r, i)];
            if v < best.0 {
                best = (v, r);
            }
        }
        c[i] = best.0;
        g[(i, best.1)] = 1.0 / prob.x[(best.1, i)];
    }
    Estimate {
        c,
        g,
        iterations: 1,
    }
}

/// Unweighted least squares of `ln AVAR` by Gauss-Newton steps, each an NNLS in `c`.
pub(super) fn est_loglog(prob: &Problem, opts: &FitOptions) -> Result<Estimate, FitError> {
    let j = prob.y.len();
    let w0: Vec<f64> = (0..j).map(|r| 1.0 / (prob.y[r] * prob.y[r])).collect();
    let (mut c, mut g) = weighted_nnls(&prob.x, &prob.y, &w0, &prob.allowed)?;
    let mut iterations = 0;
    for _ in 0..opts.max_iter {
        iterations += 1;
        let mut model = model_values(&prob.x, &c);
        floor_model(&mut model, &prob.y);
        // ln y ~ ln m + (X c - m)/m  =>  minimise sum ((m (1 + ln(y/m)) - X c) / m)^2.
        let z = DVector::from_fn(j, |r, _| model[r] * (1.0 + (prob.y[r] / model[r]).ln()));
        let w: Vec<f64> = (0..j).map(|r| 1.0 / (model[r] * model[r])).collect();
        let (c_new, g_new) = weighted_nnls(&prob.x, &z, &w, &prob.allowed)?;
        // dz/dy = m / y.
        let mut g_y = g_new;
        for r in 0..j {
            let f = model[r] / prob.y[r];
            for t in 0..5 {
                g_y[(t, r)] *= f;
            }
        }
        let done = converged(&c, &c_new, &prob.x, opts.rel_tol.max(1e-7));
        c = c_new;
        g = g_y;
        if done {
            break;
        }
    }
    Ok(Estimate { c, g, iterations })
}
