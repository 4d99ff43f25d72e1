//! The fit's uncertainty: intervals of the coefficients by inverting a test under the trial
//! value, the Satterthwaite chi-squared interval, the Fisher standard deviations, and the
//! goodness of fit with the full covariance between taus.

#[allow(unused_imports)]
use super::*;

/// `c' t c` for a symmetric `t` (its upper triangle is read).
pub(super) fn quad_form(t: &[[f64; 5]; 5], c: &[f64; 5]) -> f64 {
    let mut q = 0.0;
    for a in 0..5 {
        let mut row = 0.0;
        for b in a + 1..5 {
            row += t[a][b] * c[b];
        }
        q += c[a] * (t[a][a] * c[a] + 2.0 * row);
    }
    q
}

/// Term `i`, at `ci`, is the largest of the five at one fitted tau or more, the others at `c`.
pub(super) fn dominates(x: &DMatrix<f64>, i: usize, ci: f64, c: &[f64; 5]) -> bool {
    ci > 0.0
        && (0..x.nrows()).any(|k| {
            let own = x[(k, i)] * ci;
            (0..5).all(|t| t == i || x[(k, t)] * c[t] <= own)
        })
}

/// One coefficient's interval from [`inverted_intervals`], in `c_i` (squared units).
#[derive(Debug, Clone, Copy)]
pub(super) struct Inverted {
    pub(super) lo: f64,
    /// `None`: no finite upper end (the term's own noise at any trial value is as large as it).
    pub(super) hi: Option<f64>,
    /// The profile model at `c_i = lo`.
    pub(super) c_at_lo: [f64; 5],
}

/// 95% intervals by test inversion, with the variance under the null (docs/theory.md section 4: the
/// variance of the estimates follows from the model; here from the trial model, not the fitted
/// one, as in Wilson's score interval for a proportion). For each term `i` and trial value `t`:
/// the other terms take their profile values `c_-i(t) = c_hat_-i + Cov(c_-i, c_i) / Var(c_i)
/// (t - c_hat_i)` (the maximum of the estimator's Gaussian approximation given `c_i = t`),
/// clipped at zero; the estimate's variance there is `r' S(c(t)) r` (`r` the row of the linear
/// map `c = G y`, `S` the analytic covariance of the AVAR estimates, exactly quadratic in `c`);
/// `t` is accepted when `(c_hat_i - t)^2 <= 1.96^2 r' S(c(t)) r`. Near zero the fitted model's
/// variance understates the variance at the truth when the estimate came out low; this does
/// not. A term held at zero by the NNLS uses the row of the unconstrained weighted fit (weights
/// `edf / (2 AVAR_model^2)`, all allowed terms free) and its estimate counts as 0.
pub(super) fn inverted_intervals(
    prob: &Problem,
    g: &DMatrix<f64>,
    s: &DMatrix<f64>,
    c: &[f64; 5],
    cov_c: &[[f64; 5]; 5],
    tensors: &[[[f64; 5]; 5]],
    free_rows: bool,
) -> [Option<Inverted>; 5] {
    let j = prob.tau.len();
    let mut out = [None; 5];
    if tensors.len() != j * (j + 1) / 2 {
        return out;
    }
    // The unconstrained weighted fit's map, for terms the NNLS holds at zero.
    let held: Vec<usize> = (0..5)
        .filter(|&i| prob.allowed[i] && !(c[i] > 0.0 && g.row(i).iter().any(|v| *v != 0.0)))
        .collect();
    let free = if !free_rows && held.is_empty() {
        None
    } else {
        free_map(prob, c).map(|gf| {
            let cov = &gf * s * gf.transpose();
            (gf, cov)
        })
    };
    for i in 0..5 {
        if !prob.allowed[i] {
            continue;
        }
        let is_held = held.contains(&i);
        let (row, dir): (Vec<f64>, [f64; 5]) = if free_rows || is_held {
            let Some((gf, cov)) = free.as_ref() else {
                continue;
            };
            let cii = cov[(i, i)];
            if !(cii.is_finite() && cii > 0.0) {
                continue;
            }
            (
                gf.row(i).iter().copied().collect(),
                std::array::from_fn(|t| {
                    if prob.allowed[t] {
                        cov[(t, i)] / cii
                    } else {
                        0.0
                    }
                }),
            )
        } else {
            let cii = cov_c[i][i];
            if !(cii.is_finite() && cii > 0.0) {
                continue;
            }
            (
                g.row(i).iter().copied().collect(),
                std::array::from_fn(|t| cov_c[t][i] / cii),
            )
        };
        // v = sum_kl r_k r_l T_kl: the estimate's variance is c' v c for any model c.
        let mut v = [[0.0; 5]; 5];
        let mut idx = 0;
        for k in 0..j {
            for l in k..j {
                let w = if k == l { 1.0 } else { 2.0 } * row[k] * row[l];
                let t = &tensors[idx];
                idx += 1;
                if w == 0.0 {
                    continue;
                }
                // The upper triangle (T is symmetric, and T[4][4] = 0: the ramp enters only
                // through the means).
                for a in 0..4 {
                    for b in a..5 {
                        v[a][b] += w * t[a][b];
                    }
                }
            }
        }
        let upper = v;
        for (a, row) in v.iter_mut().enumerate() {
            for (b, x) in row.iter_mut().enumerate().take(a) {
                *x = upper[b][a];
            }
        }
        let ci = if is_held { 0.0 } else { c[i] };
        let profile = |t: f64| -> [f64; 5] {
            std::array::from_fn(|a| {
                if a == i {
                    t
                } else {
                    (c[a] + dir[a] * (t - ci)).max(0.0)
                }
            })
        };
        let var_at = |m: &[f64; 5]| -> f64 { quad_form(&v, m).max(0.0) };
        // Accepted where f <= 0.
        let f = |t: f64| (ci - t) * (ci - t) - Z95 * Z95 * var_at(&profile(t));
        let var_hat = var_at(&profile(ci));
        if !(var_hat.is_finite() && var_hat > 0.0) {
            continue;
        }
        let bisect = |mut a: f64, mut b: f64| -> f64 {
            // f(a) <= 0 < f(b); returns the accepted end.
            // To 1e-7 of the end: far below the interval's own uncertainty.
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if f(m) <= 0.0 {
                    a = m;
                } else {
                    b = m;
                }
                if (b - a).abs() <= 1e-7 * b.abs().max(a.abs()) {
                    break;
                }
            }
            a
        };
        let lo = if ci > 0.0 && f(0.0) > 0.0 {
            bisect(ci, 0.0)
        } else {
            0.0
        };
        // The first rejected value above the estimate, in doubling steps, then bisection.
        let mut step = Z95 * var_hat.sqrt();
        let mut accepted = ci;
        let mut hi = None;
        for _ in 0..200 {
            let t = ci + step;
            if !t.is_finite() {
                break;
            }
            if f(t) > 0.0 {
                hi = Some(bisect(accepted, t));
                break;
            }
            accepted = t;
            step *= 2.0;
        }
        out[i] = Some(Inverted {
            lo,
            hi,
            c_at_lo: profile(lo),
        });
    }
    out
}

/// The linear map of the unconstrained weighted least-squares fit with every allowed term free
/// (weights `edf / (2 AVAR_model^2)` at the model `c`), 5 x J (zero rows for disallowed terms).
pub(super) fn free_map(prob: &Problem, c: &[f64; 5]) -> Option<DMatrix<f64>> {
    let j = prob.tau.len();
    let cols: Vec<usize> = (0..5).filter(|&t| prob.allowed[t]).collect();
    if cols.len() > j {
        return None;
    }
    let mut model = model_values(&prob.x, c);
    floor_model(&mut model, &prob.y);
    let sw: Vec<f64> = (0..j)
        .map(|r| (prob.edf[r] / (2.0 * model[r] * model[r])).sqrt())
        .collect();
    let mut a = DMatrix::from_fn(j, cols.len(), |r, k| prob.x[(r, cols[k])] * sw[r]);
    let mut scale = vec![0.0; cols.len()];
    for (k, sc) in scale.iter_mut().enumerate() {
        let n = a.column(k).norm();
        *sc = if n > 0.0 { 1.0 / n } else { 0.0 };
        a.column_mut(k).scale_mut(*sc);
    }
    let ata = a.transpose() * &a;
    let inv = ata
        .clone()
        .cholesky()
        .map(|ch| ch.inverse())
        .or_else(|| ata.pseudo_inverse(1e-13).ok())?;
    let gp = inv * a.transpose();
    let mut g = DMatrix::zeros(5, j);
    for (k, &t) in cols.iter().enumerate() {
        for r in 0..j {
            g[(t, r)] = gp[(k, r)] * sw[r] * scale[k];
        }
    }
    Some(g)
}

/// Chi-squared interval for `c` with Satterthwaite degrees of freedom `nu = 2 c^2 / var`.
pub(super) fn chi2_interval(c: f64, var: f64) -> (f64, f64) {
    let nu = 2.0 * c * c / var;
    if nu > 1e6 {
        let h = Z95 * var.sqrt();
        return (c - h, c + h);
    }
    let lo = nu * c / chi2_quantile(nu, 0.975);
    let hi = nu * c / chi2_quantile(nu, 0.025);
    if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (0.0, c + Z95 * var.sqrt())
    }
}

/// Standard deviation of each allowed `c_i` from the Fisher information `X' S^-1 X` of the full
/// model (all allowed terms free): the scale of an upper bound for a term held at zero.
pub(super) fn fisher_sd(prob: &Problem, s_inv: Option<&DMatrix<f64>>) -> [f64; 5] {
    let cols: Vec<usize> = (0..5).filter(|&t| prob.allowed[t]).collect();
    let mut out = [0.0; 5];
    let Some(s_inv) = s_inv else {
        return out;
    };
    let xp = prob.x.select_columns(&cols);
    // Column scaling for conditioning.
    let sc: Vec<f64> = (0..cols.len())
        .map(|k| 1.0 / xp.column(k).norm().max(f64::MIN_POSITIVE))
        .collect();
    let xs = DMatrix::from_fn(xp.nrows(), xp.ncols(), |r, k| xp[(r, k)] * sc[k]);
    let f = xs.transpose() * s_inv * &xs;
    if let Ok(inv) = f.pseudo_inverse(1e-12) {
        for (k, &t) in cols.iter().enumerate() {
            out[t] = inv[(k, k)].max(0.0).sqrt() * sc[k];
        }
    }
    out
}

/// Inverse of a symmetric positive (semi)definite matrix: Cholesky, with a small ridge when the
/// strong correlation between neighbouring taus makes it numerically singular.
pub(super) fn spd_inverse(s: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = s.nrows();
    // Work on the correlation matrix so the ridge is relative.
    let d: Vec<f64> = (0..n)
        .map(|i| s[(i, i)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let corr = DMatrix::from_fn(n, n, |i, j| s[(i, j)] / (d[i] * d[j]));
    for ridge in [0.0, 1e-12, 1e-10, 1e-8, 1e-6] {
        let mut m = corr.clone();
        for i in 0..n {
            m[(i, i)] += ridge;
        }
        if let Some(ch) = m.cholesky() {
            let inv = ch.inverse();
            return Some(DMatrix::from_fn(n, n, |i, j| inv[(i, j)] / (d[i] * d[j])));
        }
    }
    None
}

/// `e' S^-1 e / tr(S^-1 P S P')` with `e = y - X c` and `P = I - X G` (the expectation of the
/// numerator when the model is right, to first order): about 1 for a correct model.
pub(super) fn gof(
    prob: &Problem,
    g: &DMatrix<f64>,
    s: &DMatrix<f64>,
    s_inv: Option<&DMatrix<f64>>,
    model: &DVector<f64>,
) -> f64 {
    let j = prob.y.len();
    let Some(s_inv) = s_inv else {
        return f64::NAN;
    };
    let e = &prob.y - model;
    let num = (e.transpose() * s_inv * &e)[0];
    let p = DMatrix::<f64>::identity(j, j) - &prob.x * g;
    let den = (s_inv * &p * s * p.transpose()).trace();
    if den > 1e-9 {
        num / den
    } else {
        f64::NAN
    }
}
