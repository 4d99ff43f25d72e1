//! Sums of a smooth lag function over long integer ranges: Euler-Maclaurin ends and
//! Gauss-Legendre panels graded towards the kinks, on vectors of [`NV`] products (weighted and
//! unweighted by the pair count).

/// Products accumulated at each lag: `g_t g_u` for `t <= u` over (N, B, K), then `g_t`.
pub(super) const NV: usize = 9;
/// The products weighted by the pair count `n(h)` (entries `0..NV`), then unweighted
/// (`NV..2 NV`): the unweighted sums are what a growing count adds to the old range.
pub(super) type Vals = [f64; 2 * NV];

pub(super) fn add(acc: &mut Vals, v: &Vals, w: f64) {
    for (a, b) in acc.iter_mut().zip(v) {
        *a += w * b;
    }
}

/// 8-point Gauss-Legendre nodes and weights on [-1, 1].
pub(super) const GL_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
pub(super) const GL_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// Points summed exactly at each end of a long stretch.
pub(super) const END_EXACT: i64 = 8;
/// Growth factor of the graded panels away from each breakpoint.
pub(super) const PANEL_GROWTH: f64 = 4.0;

pub(super) fn gauss_panel(lo: f64, hi: f64, f: &dyn Fn(f64) -> Vals, acc: &mut Vals) {
    if hi <= lo {
        return;
    }
    let half = 0.5 * (hi - lo);
    let c = 0.5 * (hi + lo);
    for (x, wt) in GL_X.iter().zip(GL_W) {
        add(acc, &f(c - half * x), wt * half);
        add(acc, &f(c + half * x), wt * half);
    }
}

/// Euler-Maclaurin ends: `(F(a) + F(b))/2 + (F'(b) - F'(a))/12`, derivatives by central
/// differences.
pub(super) fn euler_maclaurin_ends(a: f64, b: f64, f: &dyn Fn(f64) -> Vals, acc: &mut Vals) {
    let fa = f(a);
    let fb = f(b);
    let (fa_m, fa_p, fb_m, fb_p) = (f(a - 1.0), f(a + 1.0), f(b - 1.0), f(b + 1.0));
    for k in 0..2 * NV {
        let da = (fa_p[k] - fa_m[k]) / 2.0;
        let db = (fb_p[k] - fb_m[k]) / 2.0;
        acc[k] += (fa[k] + fb[k]) / 2.0 + (db - da) / 12.0;
    }
}

/// `sum_{h=p}^{q} F(h)` for `F` smooth on `[p, q]` (integers, `p <= q`), whose nearest
/// non-smooth points lie `s_lo` below `p` and `s_hi` above `q` (infinite: none).
///
/// Ends within `END_EXACT` of a kink are summed point by point; the rest by Euler-Maclaurin,
/// `sum = integral + (F(a) + F(b))/2 + (F'(b) - F'(a))/12`, with the integral on 8-point
/// Gauss-Legendre panels whose width is at most `PANEL_GROWTH - 1` times their distance to
/// the nearest kink (graded towards kinks, one panel across a stretch far from any).
pub(super) fn sum_graded(
    p: i64,
    q: i64,
    s_lo: f64,
    s_hi: f64,
    f: &dyn Fn(f64) -> Vals,
    acc: &mut Vals,
) {
    if q - p < 4 * END_EXACT + 8 {
        for h in p..=q {
            add(acc, &f(h as f64), 1.0);
        }
        return;
    }
    let e_lo = if s_lo < END_EXACT as f64 {
        END_EXACT
    } else {
        0
    };
    let e_hi = if s_hi <= END_EXACT as f64 {
        END_EXACT
    } else {
        0
    };
    for h in (p..p + e_lo).chain(q - e_hi + 1..=q) {
        add(acc, &f(h as f64), 1.0);
    }
    let a = (p + e_lo) as f64;
    let b = (q - e_hi) as f64;
    euler_maclaurin_ends(a, b, f, acc);
    // Distance of a point x to the nearest kink on each side.
    let d_lo = |x: f64| s_lo + (x - p as f64);
    let d_hi = |x: f64| s_hi + (q as f64 - x);
    let mid = if s_lo.is_infinite() && s_hi.is_infinite() {
        0.5 * (a + b)
    } else if s_lo.is_infinite() {
        a
    } else if s_hi.is_infinite() {
        b
    } else {
        // Where the two distances are equal.
        (0.5 * (a + b + s_hi - s_lo)).clamp(a, b)
    };
    let g = PANEL_GROWTH - 1.0;
    let mut x = a;
    while x < mid {
        let next = (x + g * d_lo(x).max(1.0)).min(mid);
        gauss_panel(x, next, f, acc);
        x = next;
    }
    let mut x = b;
    while x > mid {
        let next = (x - g * d_hi(x).max(1.0)).max(mid);
        gauss_panel(next, x, f, acc);
        x = next;
    }
}
