//! Distribution functions shared by the stages: the chi-squared quantile behind every 95%
//! interval (the Allan curve's points, docs/theory.md section 1; the fit's coefficients, section 2).
//! Written here rather than taken from statrs, whose inverse CDF is a slow general-purpose
//! root search and loses digits at small degrees of freedom (tests/model/chi2_quantile.rs).

/// The `p` quantile of the chi-squared distribution with `nu > 0` degrees of freedom (NaN for
/// bad arguments; `0 < p < 1`). Chi-squared with `nu` is twice the gamma of shape `a = nu/2`,
/// so this inverts the regularised incomplete gamma `P(a, x) = p` (DiDonato & Morris 1986):
/// for `a >= CF_DIRECT_A` their Cornish-Fisher expansion (eq. 31, error `O(a^-3)` relative) is
/// the answer; below it, the expansion or Wilson-Hilferty's cube-root normal approximation
/// (the small-`x` form `P ~ x^a / Gamma(a + 1)` where that fails) starts Halley steps in
/// `ln x` on [`gamma_pq`], kept inside a bracket. `nu = 2` is the closed form `-2 ln(1 - p)`.
/// Tested against statrs' `inverse_cdf` to 1e-10 relative (tests/model/chi2_quantile.rs).
pub fn chi2_quantile(nu: f64, p: f64) -> f64 {
    if !(nu > 0.0 && nu.is_finite() && p > 0.0 && p < 1.0) {
        return f64::NAN;
    }
    if nu == 2.0 {
        return -2.0 * (-p).ln_1p();
    }
    // The normal quantile of p.
    let z = -std::f64::consts::SQRT_2 * statrs::function::erf::erfc_inv(2.0 * p);
    2.0 * gamma_quantile(0.5 * nu, p, z)
}

/// From this shape on (and for `|z| <= 3`) the Cornish-Fisher expansion alone is the quantile:
/// its relative error is about `0.03 a^-3` at `z = +-1.96` (measured against 30-digit
/// quantiles), 3e-14 here.
const CF_DIRECT_A: f64 = 1.0e4;

/// DiDonato & Morris (1986) eq. 31: the gamma(a) quantile from the normal quantile `s`.
fn gamma_quantile_cf(a: f64, s: f64) -> f64 {
    let ra = a.sqrt();
    let (s2, s3) = (s * s, s * s * s);
    let (s4, s5) = (s2 * s2, s2 * s3);
    a + s * ra + (s2 - 1.0) / 3.0 + (s3 - 7.0 * s) / (36.0 * ra)
        - (3.0 * s4 + 7.0 * s2 - 16.0) / (810.0 * a)
        + (9.0 * s5 + 256.0 * s3 - 433.0 * s) / (38880.0 * a * ra)
}

/// Quantile `x` of the gamma distribution of shape `a` (unit scale): `P(a, x) = p`, `z` the
/// normal quantile of `p`. See [`chi2_quantile`].
fn gamma_quantile(a: f64, p: f64, z: f64) -> f64 {
    if a >= CF_DIRECT_A && z.abs() <= 3.0 {
        return gamma_quantile_cf(a, z);
    }
    // Work on the smaller tail: r(u) = P(a, e^u) - p, or (1 - p) - Q(a, e^u).
    let upper = p > 0.5;
    let tail = if upper { 1.0 - p } else { p };
    let mut x = if a >= 20.0 {
        gamma_quantile_cf(a, z)
    } else {
        let k = 1.0 / (9.0 * a);
        let wh = 1.0 - k + z * k.sqrt();
        if wh > 0.1 {
            a * wh * wh * wh
        } else if !upper {
            // P(a, x) ~ x^a / Gamma(a + 1) for small x; 0 when even that underflows.
            let x = (p * statrs::function::gamma::gamma(a + 1.0)).powf(1.0 / a);
            if x == 0.0 {
                return 0.0;
            }
            x
        } else {
            a + 1.0
        }
    };
    if !(x.is_finite() && x > 0.0) {
        x = a.max(1e-3);
    }
    let mut u = x.ln();
    // Bracket in u: r(lo) < 0 < r(hi).
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for _ in 0..100 {
        let g = gamma_pq(a, x);
        let r = if upper {
            g.q_tail_residual(tail)
        } else {
            g.p - tail
        };
        if r == 0.0 {
            return x;
        }
        if r < 0.0 {
            lo = u;
        } else {
            hi = u;
        }
        // Halley in u = ln x: r' = x^a e^-x / Gamma(a) = g.d, r'' = (a - x) r'.
        let newton = r / g.d;
        let mut step = if g.d > 0.0 && g.d.is_finite() {
            let h = 1.0 - 0.5 * newton * (a - x);
            if h > 0.5 {
                newton / h
            } else {
                newton
            }
        } else {
            f64::NAN
        };
        if !step.is_finite() {
            step = if r < 0.0 { -1.0 } else { 1.0 };
        }
        let step = step.clamp(-2.0, 2.0);
        // Converged; or, from the Cornish-Fisher start (a >= 20), one Halley step of at most
        // 1e-6: its error is about a step^3 (cubic convergence; the CDF in u has the scale
        // 1/sqrt(a)), below 1e-13.
        if step.abs() <= 1e-14 || (a >= 20.0 && step.abs() <= 1e-6) {
            return (u - step).exp();
        }
        let mut next = u - step;
        if next <= lo || next >= hi {
            next = if lo.is_finite() && hi.is_finite() {
                0.5 * (lo + hi)
            } else if r < 0.0 {
                u + 2.0
            } else {
                u - 2.0
            };
        }
        u = next;
        x = u.exp();
        if hi - lo <= 1e-14 {
            return x;
        }
    }
    f64::NAN
}

/// `P(a, x)` and `Q(a, x) = 1 - P(a, x)` (regularised incomplete gamma), and
/// `d = x^a e^-x / Gamma(a)`, the derivative of `P` in `ln x`.
struct GammaPq {
    p: f64,
    q: f64,
    d: f64,
}

impl GammaPq {
    /// `(1 - p_target) - Q`: the residual `P - p_target` computed from the upper tail.
    fn q_tail_residual(&self, tail: f64) -> f64 {
        tail - self.q
    }
}

/// Regularised incomplete gamma by its power series (`x < a + 1`) or Legendre's continued
/// fraction for `Q` (otherwise), Numerical Recipes' split (Press et al., section 6.2); the
/// factor `x^a e^-x / Gamma(a + 1)` from Stirling's series for large `a` (no loss of digits
/// to `a ln x - ln Gamma(a)`).
fn gamma_pq(a: f64, x: f64) -> GammaPq {
    let lead = gamma_lead(a, x);
    let d = a * lead;
    if x < a + 1.0 {
        // P = lead * sum_n x^n / ((a+1)...(a+n)).
        let mut term = 1.0;
        let mut sum = 1.0;
        let mut n = a;
        for _ in 0..100_000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term <= 1e-17 * sum {
                break;
            }
        }
        let p = lead * sum;
        GammaPq { p, q: 1.0 - p, d }
    } else {
        // Q = d * 1/(x+1-a- 1(1-a)/(x+3-a- 2(2-a)/(x+5-a- ...))), modified Lentz.
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut dd = 1.0 / b;
        let mut h = dd;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            dd = an * dd + b;
            if dd.abs() < tiny {
                dd = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            dd = 1.0 / dd;
            let del = dd * c;
            h *= del;
            if (del - 1.0).abs() <= 1e-16 {
                break;
            }
        }
        let q = d * h;
        GammaPq { p: 1.0 - q, q, d }
    }
}

/// `x^a e^-x / Gamma(a + 1)`. For `a >= 20`: `exp(-a phi(x/a)) / (sqrt(2 pi a) Gamma*(a))` with
/// `phi(l) = l - 1 - ln l` and `Gamma*` Stirling's correction factor (DiDonato & Morris 1986,
/// section 2); below, directly from `ln Gamma`.
fn gamma_lead(a: f64, x: f64) -> f64 {
    if a < 20.0 {
        return (a * x.ln() - x - statrs::function::gamma::ln_gamma(a + 1.0)).exp();
    }
    let dlt = (x - a) / a;
    let phi = if dlt.abs() <= 0.5 {
        // l - 1 - ln l = d^2/(2 + d) - 2 t^3 sum_k t^(2k) / (2k + 3), t = d / (2 + d)
        // (ln(1 + d) = 2 atanh t): no cancellation near l = 1.
        let t = dlt / (2.0 + dlt);
        let t2 = t * t;
        let mut sum = 0.0;
        let mut pw = 1.0;
        for k in 0..40 {
            let term = pw / (2 * k + 3) as f64;
            sum += term;
            if term <= 1e-17 * sum {
                break;
            }
            pw *= t2;
        }
        dlt * dlt / (2.0 + dlt) - 2.0 * t * t2 * sum
    } else {
        let l = x / a;
        l - 1.0 - l.ln()
    };
    // ln Gamma*(a) = 1/(12a) - 1/(360a^3) + 1/(1260a^5) - 1/(1680a^7) + 1/(1188a^9).
    let r = 1.0 / a;
    let r2 = r * r;
    let ln_gstar = r
        * (1.0 / 12.0
            - r2 * (1.0 / 360.0 - r2 * (1.0 / 1260.0 - r2 * (1.0 / 1680.0 - r2 / 1188.0))));
    (-a * phi - ln_gstar).exp() / (2.0 * std::f64::consts::PI * a).sqrt()
}
