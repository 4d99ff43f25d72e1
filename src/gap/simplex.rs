//! A two-parameter Nelder-Mead simplex search for a minimum (Nelder and Mead, "A simplex method
//! for function minimization", Computer Journal 7, 1965; the standard coefficients: reflection
//! 1, expansion 2, contraction 1/2, shrink 1/2, as in Press et al., Numerical Recipes, section
//! 10.5). The second-order filter's scan ([`super::filter_scan`]) polishes its best grid point
//! with it: the fit's `r' S^-1 r` has a narrow valley along which natural frequency and damping
//! trade off, which coordinate-wise golden sections cross but do not follow.

/// The lowest point found and its value, after at most `max_evals` evaluations of `f` from the
/// simplex `x0`, `x0 + (step[0], 0)`, `x0 + (0, step[1])`; it stops early once the simplex's
/// values all lie within `f_tol` of its best. Non-finite values are taken as worse than any
/// finite one.
pub(crate) fn nelder_mead_2d(
    f: impl Fn([f64; 2]) -> f64,
    x0: [f64; 2],
    step: [f64; 2],
    max_evals: usize,
    f_tol: f64,
) -> ([f64; 2], f64) {
    let val = |x: [f64; 2]| {
        let v = f(x);
        if v.is_nan() {
            f64::INFINITY
        } else {
            v
        }
    };
    let mut pts = [x0, [x0[0] + step[0], x0[1]], [x0[0], x0[1] + step[1]]];
    let mut fs = [val(pts[0]), val(pts[1]), val(pts[2])];
    let mut evals = 3;
    let at =
        |a: [f64; 2], b: [f64; 2], t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
    while evals + 2 <= max_evals {
        // Order: best, middle, worst.
        let mut idx = [0usize, 1, 2];
        idx.sort_by(|&a, &b| fs[a].total_cmp(&fs[b]));
        pts = [pts[idx[0]], pts[idx[1]], pts[idx[2]]];
        fs = [fs[idx[0]], fs[idx[1]], fs[idx[2]]];
        if fs[2] - fs[0] <= f_tol {
            break;
        }
        let c = at(pts[0], pts[1], 0.5);
        // Reflect the worst through the centroid of the other two.
        let xr = at(pts[2], c, 2.0);
        let fr = val(xr);
        evals += 1;
        if fr < fs[0] {
            let xe = at(pts[2], c, 3.0);
            let fe = val(xe);
            evals += 1;
            (pts[2], fs[2]) = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < fs[1] {
            (pts[2], fs[2]) = (xr, fr);
        } else {
            // Contract toward the better of the worst and its reflection.
            let (xc, fc) = if fr < fs[2] {
                let x = at(c, xr, 0.5);
                (x, val(x))
            } else {
                let x = at(c, pts[2], 0.5);
                (x, val(x))
            };
            evals += 1;
            if fc < fs[2].min(fr) {
                (pts[2], fs[2]) = (xc, fc);
            } else {
                // Shrink toward the best.
                for i in 1..3 {
                    pts[i] = at(pts[0], pts[i], 0.5);
                    fs[i] = val(pts[i]);
                }
                evals += 2;
            }
        }
    }
    let best = (0..3).min_by(|&a, &b| fs[a].total_cmp(&fs[b])).unwrap_or(0);
    (pts[best], fs[best])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock's valley `100 (y - x^2)^2 + (1 - x)^2` (minimum 0 at (1, 1)), from (-1.2, 1),
    /// the classic start: reached within 1e-4 in both coordinates.
    #[test]
    fn follows_a_curved_valley() {
        let f = |p: [f64; 2]| 100.0 * (p[1] - p[0] * p[0]).powi(2) + (1.0 - p[0]).powi(2);
        let (x, v) = nelder_mead_2d(f, [-1.2, 1.0], [0.1, 0.1], 2000, 1e-14);
        assert!(
            (x[0] - 1.0).abs() < 1e-4 && (x[1] - 1.0).abs() < 1e-4,
            "{x:?}"
        );
        assert!(v < 1e-8, "{v}");
    }

    /// A narrow straight valley at 45 degrees (a ratio of curvatures of 1e4), as the
    /// second-order filter's frequency and damping make: coordinate steps stall on it, the
    /// simplex reaches the minimum (0.3, -0.2) within 1e-3.
    #[test]
    fn follows_a_narrow_diagonal_valley() {
        let f = |p: [f64; 2]| {
            let (u, v) = (p[0] - 0.3 + p[1] + 0.2, p[0] - 0.3 - (p[1] + 0.2));
            1e4 * u * u + v * v
        };
        let (x, _) = nelder_mead_2d(f, [0.0, 0.0], [0.05, 0.05], 400, 1e-12);
        assert!(
            (x[0] - 0.3).abs() < 1e-3 && (x[1] + 0.2).abs() < 1e-3,
            "{x:?}"
        );
    }
}
