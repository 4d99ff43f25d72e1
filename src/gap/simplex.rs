//! A Nelder-Mead simplex search for a minimum, in two parameters or more (Nelder and Mead, "A simplex method
//! for function minimization", Computer Journal 7, 1965; the standard coefficients: reflection
//! 1, expansion 2, contraction 1/2, shrink 1/2, as in Press et al., Numerical Recipes, section
//! 10.5). The second-order filter's scan ([`super::filter_scan`]) polishes its best grid point
//! with it: the fit's `r' S^-1 r` has a narrow valley along which natural frequency and damping
//! trade off, which coordinate-wise golden sections cross but do not follow.

/// The lowest point found and its value, after at most `max_evals` evaluations of `f` in `N`
/// parameters from the simplex `x0` and `x0` plus each step along its axis (`x0 + (step[0], 0)`,
/// `x0 + (0, step[1])` in two); it stops early once the simplex's values all lie within `f_tol`
/// of its best. Non-finite values are taken as worse than any finite one.
pub(crate) fn nelder_mead<const N: usize>(
    f: impl Fn([f64; N]) -> f64,
    x0: [f64; N],
    step: [f64; N],
    max_evals: usize,
    f_tol: f64,
) -> ([f64; N], f64) {
    let val = |x: [f64; N]| {
        let v = f(x);
        if v.is_nan() {
            f64::INFINITY
        } else {
            v
        }
    };
    let at = |a: [f64; N], b: [f64; N], t: f64| -> [f64; N] {
        std::array::from_fn(|i| a[i] + t * (b[i] - a[i]))
    };
    let mut pts: Vec<[f64; N]> = (0..=N)
        .map(|k| {
            let mut p = x0;
            if k > 0 {
                p[k - 1] += step[k - 1];
            }
            p
        })
        .collect();
    let mut fs: Vec<f64> = pts.iter().map(|&p| val(p)).collect();
    let mut evals = N + 1;
    while evals + 2 <= max_evals {
        // Order: best first, worst last.
        let mut idx: Vec<usize> = (0..=N).collect();
        idx.sort_by(|&a, &b| fs[a].total_cmp(&fs[b]));
        pts = idx.iter().map(|&i| pts[i]).collect();
        fs = idx.iter().map(|&i| fs[i]).collect();
        if fs[N] - fs[0] <= f_tol {
            break;
        }
        // The centroid of all but the worst, as running means.
        let mut c = pts[0];
        for (i, p) in pts.iter().enumerate().take(N).skip(1) {
            c = at(c, *p, 1.0 / (i + 1) as f64);
        }
        // Reflect the worst through the centroid of the others.
        let xr = at(pts[N], c, 2.0);
        let fr = val(xr);
        evals += 1;
        if fr < fs[0] {
            let xe = at(pts[N], c, 3.0);
            let fe = val(xe);
            evals += 1;
            (pts[N], fs[N]) = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < fs[N - 1] {
            (pts[N], fs[N]) = (xr, fr);
        } else {
            // Contract toward the better of the worst and its reflection.
            let (xc, fc) = if fr < fs[N] {
                let x = at(c, xr, 0.5);
                (x, val(x))
            } else {
                let x = at(c, pts[N], 0.5);
                (x, val(x))
            };
            evals += 1;
            if fc < fs[N].min(fr) {
                (pts[N], fs[N]) = (xc, fc);
            } else {
                // Shrink toward the best.
                for i in 1..=N {
                    pts[i] = at(pts[0], pts[i], 0.5);
                    fs[i] = val(pts[i]);
                }
                evals += N;
            }
        }
    }
    let best = (0..=N)
        .min_by(|&a, &b| fs[a].total_cmp(&fs[b]))
        .unwrap_or(0);
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
        let (x, v) = nelder_mead(f, [-1.2, 1.0], [0.1, 0.1], 2000, 1e-14);
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
        let (x, _) = nelder_mead(f, [0.0, 0.0], [0.05, 0.05], 400, 1e-12);
        assert!(
            (x[0] - 0.3).abs() < 1e-3 && (x[1] + 0.2).abs() < 1e-3,
            "{x:?}"
        );
    }

    /// In three parameters: a narrow valley along the diagonal of two of them with a third
    /// coupled to it (the sampled second order's frequency, damping and zero), minimum at
    /// (0.3, -0.2, 0.48), reached within 1e-3 from (0, 0, 0.3).
    #[test]
    fn follows_a_valley_in_three_parameters() {
        let f = |p: [f64; 3]| {
            let (u, v) = (p[0] - 0.3 + p[1] + 0.2, p[0] - 0.3 - (p[1] + 0.2));
            let w = p[2] - 0.48 - 0.5 * (p[0] - 0.3);
            1e4 * u * u + v * v + 1e2 * w * w
        };
        let (x, _) = nelder_mead(f, [0.0, 0.0, 0.3], [0.05, 0.05, 0.05], 3000, 1e-14);
        assert!(
            (x[0] - 0.3).abs() < 1e-3 && (x[1] + 0.2).abs() < 1e-3 && (x[2] - 0.48).abs() < 1e-3,
            "{x:?}"
        );
    }
}
