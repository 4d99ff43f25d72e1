//! The rounding of each rate sample after a unit's low-pass filter, as AVAR (docs/gap.md,
//! "Rounding after a filter"). A MEMS part filters its rate, then rounds each delivered sample
//! to a step `L` (u/s). When the filtered sample's noise `sigma` is large against the step the
//! rounding error is white, `L^2 / 12` per sample ([`super::quantization`]'s rate floor); when
//! it is not, successive errors are correlated, because the filtered samples they round are.
//!
//! For a Gaussian filtered rate with sample variance `sigma^2` and autocorrelation `rho_k`, the
//! error `e = L round(s / L) - s` is the sawtooth `(L / pi) sum_n (-1)^n sin(2 pi n s / L) / n`,
//! and averaging over where the unit's mean rate falls between two steps gives its
//! autocovariance
//!
//! `R_e(k) = L^2 / (2 pi^2) sum_{n >= 1} n^-2 [exp(-x (1 - rho_k) n^2) - exp(-x n^2)]`,
//! `x = 4 pi^2 sigma^2 / L^2`
//!
//! (Widrow and Kollar, "Quantization Noise", 2008, ch. 4-6: the characteristic function of the
//! pair `(s_i, s_j)`; the second term removes the constant mean error). `R_e(0)` is `L^2 / 12`
//! less that term, and for `sigma >> L` every `R_e(k > 0)` vanishes: the white floor. What the
//! average over the mean leaves out is the error's correlation with the signal,
//! `E[s_i e_j] = 2 sigma^2 rho_k sum_n (-1)^n cos(2 pi n mu / L) exp(-x n^2 / 2)`, which depends
//! on where the mean `mu` falls: at most 1.4% of the filtered variance at `sigma = L / 2`, 8.5%
//! at `sigma = 0.4 L`, 22% at `L / 3` (the rounding then holds the output on one step: a dead
//! band). So the model is used while `sigma >= MIN_SIGMA_STEPS L` ([`MIN_SIGMA_STEPS`]).
//! Checked by simulation (a moving average of 8 or 25 taps, one or two stages, `L` = 1-3.5
//! filtered sigmas, the mean at a quarter step): the AVAR of the rounded output is the
//! filtered rate's plus this within 3% at every cluster size, where the white floor is off by
//! up to a factor 3.

use crate::model::lowpass::{avar_from_autocovariance, LowPass};
use std::f64::consts::PI;

/// The filtered sample's noise, in steps, below which the rounding's correlation with the
/// signal (the dead band) is no longer small and the model is not used.
pub const MIN_SIGMA_STEPS: f64 = 0.4;

/// `sum_{n >= 1} exp(-n^2 x) / n^2` for `x >= 0`: below 0.5 by its Poisson (theta-function)
/// form `pi^2 / 6 - sqrt(pi x) + x / 2` (the next term is of order `exp(-pi^2 / x)`, below
/// 1e-9 there), above by the series.
fn theta_sum(x: f64) -> f64 {
    let x = x.max(0.0);
    if x < 0.5 {
        return PI * PI / 6.0 - (PI * x).sqrt() + 0.5 * x;
    }
    let mut s = 0.0;
    for n in 1..64u32 {
        let n2 = (n * n) as f64;
        // below e^-700 the term is nothing beside the first, and libm's underflow path is slow
        // (a fifth of a filtered, rounded unit's diagnosis)
        if n2 * x > 700.0 {
            break;
        }
        let t = (-n2 * x).exp() / n2;
        s += t;
        if t < 1e-18 {
            break;
        }
    }
    s
}

/// The filtered rate sample's standard deviation (u/s) for a unit white rate `N^2 = n2`
/// (u^2/s) through `lp`.
pub fn filtered_sigma(lp: &LowPass, tau0_s: f64, n2: f64) -> f64 {
    let rho0 = lp.autocorrelation(tau0_s).first().copied().unwrap_or(1.0);
    (n2.max(0.0) * rho0 / tau0_s).sqrt()
}

/// The AVAR (u^2/s^2) at each cluster size of `ms` of the error of rounding to the step
/// `step` (u/s) the rate of a unit with white rate `N^2 = n2` (u^2/s) filtered by `lp`,
/// averaged over where the unit's mean falls between two steps (see the module doc). Sums of `n`
/// errors have variance `n R_0 + 2 sum_{0<k<n} (n - k) R_k` (in samples), and
/// `AVAR(m) = (4 S(m) - S(2m)) / (2 m^2)`.
pub fn rounding_avar(lp: &LowPass, tau0_s: f64, step: f64, n2: f64, ms: &[u64]) -> Vec<f64> {
    rounding_avar_on_grid(lp, tau0_s, step, n2, None, ms)
}

/// Harmonics of the mean's position on the grid the model keeps: the `p`-th is damped by at
/// least `exp(-x p^2 / 4)`, below 1e-12 of the step's square at `p = 8` once `x >= 1.7`
/// (`sigma >= 0.21 L`, [`GRID_MIN_X`]), and [`MIN_SIGMA_STEPS_ON_GRID`] is above that.
pub const GRID_HARMONICS: usize = 8;

/// The smallest `x = 4 pi^2 sigma^2 / L^2` at which [`rounding_avar_on_grid`] keeps the
/// harmonics ([`GRID_HARMONICS`]); below, their truncated series says nothing (every one is
/// kept undamped as `sigma -> 0`) and the model is the averaged one. A fit's search for its
/// `N` passes through such values on the way.
pub const GRID_MIN_X: f64 = 1.7;

/// The filtered sample's noise, in steps, down to which [`rounding_avar_on_grid`] matches
/// simulated runs when the block means say where the mean falls on the grid
/// ([`grid_cosines`]): within 1% at 0.25 steps, 2% at 0.2 (docs/gap.md, "Rounding after a
/// filter (session 12)"; docs/repro/session12/rr_grid.py). The diagnosis uses it down to here
/// wherever the block means resolve the mean's position (`discrepancy::floor_harmonics`;
/// docs/gap.md, "The grid model wired (session 15)").
pub const MIN_SIGMA_STEPS_ON_GRID: f64 = 0.25;

/// The largest variance, in steps squared, of a block mean's estimate of the mean's position,
/// times `2 pi^2`, at which the block means are said to resolve it: the first harmonic's
/// average is then damped by the estimate's noise by at most `exp(-0.25)` before it is
/// corrected ([`grid_cosines`]).
const MAX_GRID_BLUR: f64 = 0.25;

/// Bins per step in which the blocks' positions on the grid are pooled ([`grid_cosines`]).
const GRID_BINS: usize = 256;

/// Where a unit's mean falls on the rounding grid, as the run shows it: the mean rate of each
/// block of the run (u/s, in time order) and the blocks' length (s). The mean may drift over
/// the run; each block holds its own position ([`grid_cosines`]). Within a block it still
/// wanders with the unit's flicker rate noise `flicker_b2` (`B^2`, u^2/s^2; 0 when not known),
/// which spreads the samples' positions about the block's ([`within_block_wander`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GridPosition {
    pub block_means: Vec<f64>,
    pub block_s: f64,
    pub flicker_b2: f64,
}

/// `ln(f_c T_b) + C` with the variance of flicker about its `T_b`-block mean behind a first
/// order of cut-off `f_c`, `(B^2 / 2 pi) int_0^inf (1 - sinc^2(pi f T_b)) / (f (1 + (f /
/// f_c)^2)) df`, equal to `(B^2 / 2 pi) (ln(f_c T_b) + C)` once `f_c T_b >= 10` (numerical
/// quadrature: 0.9175 at 10, 0.9151 at 100 and 1000; docs/gap.md, "The mean wanders within a
/// block (session 17)").
const WANDER_LN_CONST: f64 = 0.915;

/// The variance (u^2/s^2) of the unit's slow rate about its block mean within the blocks of
/// `grid`, seen through a filter of memory `memory_s` (s): the flicker rate noise `B^2`
/// (`S(f) = B^2 / (2 pi f)`, the five-term model's convention) between the block's frequency
/// and the filter's cut-off `1 / (2 pi T)`, `(B^2 / 2 pi) max(0, ln(T_b / (2 pi T)) + C)`
/// ([`WANDER_LN_CONST`]). Faster flicker is filtered with the white rate and is small beside it;
/// the rate random walk's share, `K^2 T_b / 6`, is left out (the curve's `K` is the least
/// certain of the five at the blocks' length, and a wrong one would erase the grid's terms).
pub fn within_block_wander(grid: &GridPosition, memory_s: f64) -> f64 {
    if !(grid.flicker_b2 > 0.0 && grid.block_s > 0.0 && memory_s > 0.0) {
        return 0.0;
    }
    let span = (grid.block_s / (2.0 * PI * memory_s)).ln() + WANDER_LN_CONST;
    grid.flicker_b2 / (2.0 * PI) * span.max(0.0)
}

/// `sum_{n >= 1} (-1)^n sin(2 pi n v) exp(-x n^2 / 2) / (pi n)` and its derivative in `v`:
/// the mean rounding error, in steps, of a Gaussian sample of mean `v` steps
/// (`x = 4 pi^2 sigma^2 / L^2`; the sawtooth's Fourier series, module doc); `w[n - 1]` is
/// `exp(-x n^2 / 2)`. The harmonics' sines and cosines by the angle-addition recurrence.
fn mean_error_steps(v: f64, w: &[f64]) -> (f64, f64) {
    let (s1, c1) = (2.0 * PI * v).sin_cos();
    let (mut sn, mut cn) = (s1, c1);
    let (mut e, mut de) = (0.0, 0.0);
    for (k, &wn) in w.iter().enumerate() {
        let nf = (k + 1) as f64;
        let sign = if k % 2 == 0 { -1.0 } else { 1.0 };
        e += sign * sn * wn / (PI * nf);
        de += sign * 2.0 * cn * wn;
        (sn, cn) = (sn * c1 + cn * s1, cn * c1 - sn * s1);
    }
    (e, de)
}

/// The averages over the run's blocks of `cos(2 pi p mu_b / L)`, `p = 1..=GRID_HARMONICS`, with
/// `mu_b` the mean of block `b` against the grid of step `L = step` (u/s), for a filtered
/// sample noise `sigma = sqrt(sigma2)`: None when the block means do not resolve it.
///
/// A block's mean rate is `mu_b + E[e | mu_b]`, the rounding's mean error
/// `(L / pi) sum_n (-1)^n sin(2 pi n mu / L) exp(-x n^2 / 2)` ([`mean_error_steps`]), which is
/// increasing in `mu_b` (its derivative is a theta function, positive), so `mu_b` is found by
/// Newton's method from the block's mean, modulo `L`. Each block mean carries the noise of a
/// `T_b`-second average of the white rate, variance `N^2 / T_b`, that is `N^2 / (T_b f'^2)` on
/// `mu_b` (`f'` the derivative above), which damps the average of `cos(p phi)` by
/// `exp(-2 pi^2 p^2 var / L^2)`; that factor is taken back out, and the averages are clamped to
/// [-1, 1]. Not resolved: no blocks, or the damping of the first harmonic in some block beyond
/// `exp(-MAX_GRID_BLUR)`.
pub fn grid_cosines(
    grid: &GridPosition,
    step: f64,
    sigma2: f64,
    n2: f64,
    memory_s: f64,
) -> Option<[f64; GRID_HARMONICS]> {
    if grid.block_means.is_empty() || !(grid.block_s > 0.0 && step > 0.0 && sigma2 > 0.0) {
        return None;
    }
    let x = 4.0 * PI * PI * sigma2 / (step * step);
    let w: Vec<f64> = (1..=GRID_HARMONICS)
        .map(|n| (-0.5 * x * (n * n) as f64).exp())
        .take_while(|&wn| wn > 1e-16)
        .collect();
    let var_mean = n2.max(0.0) / grid.block_s / (step * step);
    let mut acc = [0.0; GRID_HARMONICS];
    let mut count = 0usize;
    // The blocks' positions pooled in bins of 1/GRID_BINS step, each at its blocks' mean
    // position (the inversion below is smooth, so that moves each average by the bin's
    // spread squared at most), and inverted once per bin.
    let mut bins = [(0.0f64, 0usize); GRID_BINS];
    for &m in &grid.block_means {
        if !m.is_finite() {
            continue;
        }
        let u = m / step - (m / step).round();
        let b = (((u + 0.5) * GRID_BINS as f64) as usize).min(GRID_BINS - 1);
        bins[b].0 += u;
        bins[b].1 += 1;
    }
    // the previous bin's position on the grid, its solution and the slope there
    let mut prev: Option<(f64, f64, f64)> = None;
    for &(sum_u, n_b) in bins.iter().filter(|b| b.1 > 0) {
        let u = sum_u / n_b as f64;
        // Newton's method on the increasing f(v) = v + E[e](v) = u over [-1/2, 1/2], kept in
        // the bracket (f(+-1/2) = +-1/2), from the previous bin's solution carried along the
        // tangent there (the bins come in increasing order; a start outside the bracket is
        // replaced by the bin's own position, the start before session 17)
        let (mut lo, mut hi) = (-0.5, 0.5);
        let mut v = prev.map_or(u, |(u0, v0, s0)| v0 + (u - u0) / s0.max(1e-12));
        if !(v > lo && v < hi) {
            v = u;
        }
        let mut slope = 1.0;
        for _ in 0..30 {
            let (e, de) = mean_error_steps(v, &w);
            let f = v + e - u;
            slope = 1.0 + de;
            if f > 0.0 {
                hi = v;
            } else {
                lo = v;
            }
            let next = v - f / slope.max(1e-12);
            let next = if next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
            if (next - v).abs() < 1e-12 {
                v = next;
                break;
            }
            v = next;
        }
        prev = Some((u, v, slope));
        let blur = 2.0 * PI * PI * var_mean / (slope * slope).max(1e-12);
        if blur > MAX_GRID_BLUR {
            return None;
        }
        let (s1, c1) = (2.0 * PI * v).sin_cos();
        let (mut sp, mut cp) = (s1, c1);
        let damp = blur.exp();
        for (p, a) in acc.iter_mut().enumerate() {
            *a += n_b as f64 * cp * damp.powi(((p + 1) * (p + 1)) as i32);
            (sp, cp) = (sp * c1 + cp * s1, cp * c1 - sp * s1);
        }
        count += n_b;
    }
    if count == 0 {
        return None;
    }
    // Each sample's position is its block's plus the slow wander within the block, Gaussian
    // of variance `w2` steps^2: the average of cos(2 pi p mu) over the samples is the block's
    // times exp(-2 pi^2 p^2 w2).
    let w2 = within_block_wander(grid, memory_s) / (step * step);
    let mut out = acc.map(|a| (a / count as f64).clamp(-1.0, 1.0));
    for (p, o) in out.iter_mut().enumerate() {
        let pf = (p + 1) as f64;
        *o *= (-2.0 * PI * PI * pf * pf * w2).exp();
    }
    Some(out)
}

/// Relative size below which a term of the mean-dependent part is left out: a harmonic whose
/// weight `|A_p| exp(-x p^2 / 4)` is smaller, and lags whose correlation is smaller (each pair
/// sum is of order `x r` there). The model's resolution is a few 1e-3 of the step's square.
const GRID_NEGLIGIBLE: f64 = 1e-7;

/// The harmonic `p` of the mean-dependent part of the rounding error's autocovariance at a lag
/// where the filtered samples' correlation is `r` is
/// `sum_{n + m = p; n, m != 0} [exp(-x/2 (n^2 + m^2 + 2 n m r)) - exp(-x/2 (n^2 + m^2))] / (n m)`,
/// this function's first part less [`pair_sum_e2`]. The first exponent is
/// `-x p^2 / 2 + x n m (1 - r)`, so for `n m < 0` the terms decay as `exp(-x |n m| (1 - r))`:
/// the sum runs while that is above `e^-45`. At `r = 1` (lag 0) it is
/// `exp(-x p^2 / 2) sum 1 / (n m) = -2 exp(-x p^2 / 2) / p^2` (the Fourier coefficient of the
/// squared sawtooth).
///
/// The terms are symmetric in `n <-> m`, so the half `n < p / 2` is summed twice (and the
/// middle term `n = m = p / 2` once), from the largest term outward, and the exponent,
/// quadratic in `n`, is stepped by the recurrence `e_{n-1} = e_n q_n`,
/// `q_{n-1} = q_n exp(-2 x (1 - r))` (two products a term instead of an `exp`: this sum is most
/// of the diagnosis's time on a rounded channel).
fn pair_sum_e1(p: usize, x: f64, r: f64) -> f64 {
    let pi = p as i64;
    let one_minus = (1.0 - r).max(0.0);
    let top = -0.5 * x * (p * p) as f64;
    if one_minus < 1e-12 {
        return -2.0 * top.exp() / (p * p) as f64;
    }
    let c = x * one_minus;
    let nn = ((45.0 / c).sqrt().ceil() as i64 + pi + 2).min(4000);
    // n from the last below p / 2 down to -nn; the exponent of n is top + c n (p - n), and
    // from n to n - 1 it changes by c (2 n - p - 1)
    let mut n = (pi - 1).div_euclid(2);
    let mut e = (top + c * (n * (pi - n)) as f64).exp();
    let mut q = (c * (2 * n - pi - 1) as f64).exp();
    let damp = (-2.0 * c).exp();
    let mut half = 0.0;
    while n >= -nn && e > 0.0 {
        if n != 0 {
            half += e / (n * (pi - n)) as f64;
        }
        e *= q;
        q *= damp;
        n -= 1;
    }
    let mid = if p.is_multiple_of(2) {
        let h = (pi / 2) as f64;
        (top + c * h * h).exp() / (h * h)
    } else {
        0.0
    };
    2.0 * half + mid
}

/// `sum_{n + m = p; n, m != 0} exp(-x/2 (n^2 + m^2)) / (n m)`, the lag-independent part of the
/// harmonic `p`'s pair sum ([`pair_sum_e1`]); `n^2 + m^2 >= 2 n^2 - 2 |n| p`, so `|n|` up to
/// `sqrt(90 / x) + p` reaches `e^-45`.
fn pair_sum_e2(p: usize, x: f64) -> f64 {
    let pi = p as i64;
    let nn = ((90.0 / x).sqrt().ceil() as i64 + pi + 2).min(4000);
    let mut s = 0.0;
    for n in -nn..=nn + pi {
        let m = pi - n;
        if n == 0 || m == 0 {
            continue;
        }
        s += (-0.5 * x * ((n * n + m * m) as f64)).exp() / (n * m) as f64;
    }
    s
}

/// The AVAR (u^2/s^2) at each cluster size of `ms` that the rounding to the step `step` (u/s)
/// adds to the rate of a unit with white rate `N^2 = n2` (u^2/s) filtered by `lp`: the
/// rounding error's own AVAR, and, when `grid` resolves where the unit's mean falls between
/// two steps ([`grid_cosines`]), the terms that depend on it, so that the rounded output's AVAR
/// is the filtered rate's plus this. None or unresolved: the error's AVAR averaged over the
/// mean's position ([`rounding_avar`]).
///
/// With `s = mu + g`, `g` Gaussian of variance `sigma^2` and correlation `r_k` between samples
/// `k` apart, and the error `e(s) = sum_{n != 0} c_n exp(i 2 pi n s / L)`,
/// `c_n = L (-1)^n / (2 pi i n)` (the sawtooth), the pair's characteristic function gives
/// (Widrow and Kollar 2008, ch. 4-6, for the method):
/// - the error with the signal: `E[g_i e_j] = 2 sigma^2 r_k sum_{p >= 1} (-1)^p
///   cos(2 pi p mu / L) exp(-x p^2 / 2)`, twice in the output's covariance (`e_i g_j` too), so
///   a multiple `4 sum_p (-1)^p A_p exp(-x p^2 / 2)` of the filtered rate's own AVAR (with the
///   mean on a step and `sigma = 0.35 L` that is -0.36: the dead band holds the output);
/// - the error's covariance, `sum_{n, m} c_n c_m exp(i 2 pi (n + m) mu / L)
///   [exp(-x/2 (n^2 + m^2 + 2 n m r_k)) - exp(-x/2 (n^2 + m^2))]`: the terms `n + m = 0` are
///   the averaged model, and each `p = n + m != 0` adds `2 A_p (-L^2 (-1)^p / (4 pi^2))`
///   times the pair sum ([`pair_sum_e1`] less [`pair_sum_e2`]);
///
/// with `A_p` the run's average of `cos(2 pi p mu_b / L)` over its blocks ([`grid_cosines`]):
/// every term is linear in `exp(i 2 pi p mu / L)`, so the blocks' mixture is the average of
/// their covariances.
pub fn rounding_avar_on_grid(
    lp: &LowPass,
    tau0_s: f64,
    step: f64,
    n2: f64,
    grid: Option<&GridPosition>,
    ms: &[u64],
) -> Vec<f64> {
    rounding_avar_with(&lp.autocorrelation(tau0_s), lp, tau0_s, step, n2, grid, ms)
}

/// [`rounding_avar_on_grid`] with the filter's autocorrelation `rho` ([`LowPass::autocorrelation`]
/// of `lp` at `tau0_s`) given, as a problem keeps it.
pub fn rounding_avar_with(
    rho: &[f64],
    lp: &LowPass,
    tau0_s: f64,
    step: f64,
    n2: f64,
    grid: Option<&GridPosition>,
    ms: &[u64],
) -> Vec<f64> {
    let rho0 = rho.first().copied().unwrap_or(1.0);
    let sigma2 = n2.max(0.0) * rho0 / tau0_s;
    let x = 4.0 * PI * PI * sigma2 / (step * step);
    let c = step * step / (2.0 * PI * PI);
    let tail = theta_sum(x);
    // harmonics that matter: |A_p| exp(-x p^2 / 4) above GRID_NEGLIGIBLE (none once the
    // filtered noise is above about 1.3 steps: the averaged model is then the whole of it)
    let harmonics: Vec<(usize, f64)> = if (-0.25 * x).exp() > GRID_NEGLIGIBLE && x >= GRID_MIN_X {
        grid.and_then(|g| grid_cosines(g, step, sigma2, n2, lp.memory_s(tau0_s)))
            .map(|a| {
                (1..=GRID_HARMONICS)
                    .map(|p| (p, a[p - 1]))
                    .filter(|&(p, a)| {
                        a.abs() * (-0.25 * x * (p * p) as f64).exp() > GRID_NEGLIGIBLE
                    })
                    .collect()
            })
            .unwrap_or_default()
    } else {
        Vec::new()
    };
    // the lag-independent half of each harmonic's pair sum
    let e2: Vec<f64> = harmonics.iter().map(|&(p, _)| pair_sum_e2(p, x)).collect();
    let r: Vec<f64> = rho
        .iter()
        .map(|&v| {
            let rk = v / rho0;
            let mut cov = c * (theta_sum(x * (1.0 - rk).max(0.0)) - tail);
            // at r = 0 each pair sum is 0; below GRID_NEGLIGIBLE it is of order x r
            if rk.abs() > GRID_NEGLIGIBLE {
                for (&(p, a), &e2p) in harmonics.iter().zip(&e2) {
                    let sign = if p % 2 == 0 { 1.0 } else { -1.0 };
                    cov -= 2.0 * a * sign * step * step / (4.0 * PI * PI)
                        * (pair_sum_e1(p, x, rk) - e2p);
                }
            }
            cov
        })
        .collect();
    // the errors' AVAR of averages of m samples (unit sample time: S(n) in samples)
    let mut out = avar_from_autocovariance(&r, 1.0, ms);
    if !harmonics.is_empty() {
        let cross: f64 = 4.0
            * harmonics
                .iter()
                .map(|&(p, a)| {
                    let sign = if p % 2 == 0 { 1.0 } else { -1.0 };
                    sign * a * (-0.5 * x * (p * p) as f64).exp()
                })
                .sum::<f64>();
        let signal: Vec<f64> = rho.iter().map(|&v| sigma2 * v / rho0).collect();
        for (o, s) in out
            .iter_mut()
            .zip(avar_from_autocovariance(&signal, 1.0, ms))
        {
            *o += cross * s;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`pair_sum_e1`] term by term, each with its own `exp`.
    fn pair_sum_e1_direct(p: usize, x: f64, r: f64) -> f64 {
        let pi = p as i64;
        let top = -0.5 * x * (p * p) as f64;
        (-4000..=4000 + pi)
            .filter(|&n| n != 0 && n != pi)
            .map(|n| {
                let nm = (n * (pi - n)) as f64;
                (top + x * nm * (1.0 - r)).exp() / nm
            })
            .sum()
    }

    #[test]
    fn the_pair_sum_by_recurrence_is_the_direct_sum() {
        for p in 1..=GRID_HARMONICS {
            for x in [1.7, 2.5, 4.8, 9.0, 30.0] {
                for r in [0.999_99, 0.9, 0.5, 0.1, 1e-3, -0.3] {
                    let (fast, direct) = (pair_sum_e1(p, x, r), pair_sum_e1_direct(p, x, r));
                    let scale = (-0.25 * x * (p * p) as f64).exp();
                    assert!(
                        (fast - direct).abs() <= 1e-12 * scale.max(direct.abs()),
                        "p {p} x {x} r {r}: {fast} against {direct}"
                    );
                }
            }
        }
        // At r = 1 the closed form: -2 exp(-x p^2 / 2) / p^2.
        assert!((pair_sum_e1(3, 2.0, 1.0) + 2.0 * (-9.0f64).exp() / 9.0).abs() < 1e-18);
    }

    /// [`grid_cosines`] with each block inverted by bisection on its own, every block kept.
    fn grid_cosines_by_bisection(grid: &GridPosition, step: f64, sigma2: f64, n2: f64) -> Vec<f64> {
        let x = 4.0 * PI * PI * sigma2 / (step * step);
        let w: Vec<f64> = (1..=GRID_HARMONICS)
            .map(|n| (-0.5 * x * (n * n) as f64).exp())
            .collect();
        let var_mean = n2 / grid.block_s / (step * step);
        let mut acc = [0.0; GRID_HARMONICS];
        for &m in &grid.block_means {
            let u = m / step - (m / step).round();
            let (mut lo, mut hi) = (-0.5f64, 0.5f64);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid + mean_error_steps(mid, &w).0 > u {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let v = 0.5 * (lo + hi);
            let slope = 1.0 + mean_error_steps(v, &w).1;
            let blur = 2.0 * PI * PI * var_mean / (slope * slope);
            for (p, a) in acc.iter_mut().enumerate() {
                let pf = (p + 1) as f64;
                *a += (2.0 * PI * pf * v).cos() * (blur * pf * pf).exp();
            }
        }
        acc.iter()
            .map(|a| (a / grid.block_means.len() as f64).clamp(-1.0, 1.0))
            .collect()
    }

    #[test]
    fn the_grid_cosines_are_those_of_each_block_inverted_alone() {
        // block means spread over the grid, one per bin at most (no pooling), drifting across
        // steps, at three noise levels of the filtered sample (x from 1.7 to 9)
        let step = 0.01;
        let block_means: Vec<f64> = (0..200)
            .map(|k| step * (3.0 + 0.9973 * k as f64 / 200.0 + 2.0 * ((k % 7) as f64)) - 0.5 * step)
            .collect();
        let grid = GridPosition {
            block_means,
            block_s: 40.0,
            flicker_b2: 0.0,
        };
        for sigma_steps in [0.21, 0.3, 0.48] {
            let sigma2 = (sigma_steps * step) * (sigma_steps * step);
            let n2 = 1e-6;
            let got = grid_cosines(&grid, step, sigma2, n2, 0.05).expect("resolved");
            let want = grid_cosines_by_bisection(&grid, step, sigma2, n2);
            for p in 0..GRID_HARMONICS {
                // the pooling moves a block by at most a bin's width, 1/256 step, and each
                // cosine by 2 pi p / 256 times that bin's share; here one block per bin
                assert!(
                    (got[p] - want[p]).abs() < 2e-3,
                    "sigma {sigma_steps} p {}: {} against {}",
                    p + 1,
                    got[p],
                    want[p]
                );
            }
        }
    }

    #[test]
    fn the_wander_within_a_block_is_the_filtered_flickers_variance_about_the_block_mean() {
        // (B^2 / 2 pi) int_0^inf (1 - sinc^2(pi f T_b)) / (f (1 + (f / f_c)^2)) df by the
        // midpoint rule in ln f, against the closed form with WANDER_LN_CONST, for a first
        // order of memory T (f_c = 1 / (2 pi T)) and blocks 10^2-10^4 memories long
        let b2 = 4e-6;
        for (memory_s, block_s) in [(0.05f64, 8.0f64), (0.01, 30.0), (0.002, 20.0)] {
            let fc = 1.0 / (2.0 * PI * memory_s);
            let (lo, hi, n) = ((1e-6 / block_s).ln(), (1e4 * fc).ln(), 200_000);
            let h = (hi - lo) / n as f64;
            let quad: f64 = (0..n)
                .map(|i| {
                    let f = (lo + (i as f64 + 0.5) * h).exp();
                    let x = PI * f * block_s;
                    let sinc2 = if x > 1e-8 { (x.sin() / x).powi(2) } else { 1.0 };
                    (1.0 - sinc2) / (1.0 + (f / fc).powi(2)) * h
                })
                .sum::<f64>()
                * b2
                / (2.0 * PI);
            let grid = GridPosition {
                block_means: vec![0.0],
                block_s,
                flicker_b2: b2,
            };
            let w = within_block_wander(&grid, memory_s);
            assert!(
                (w / quad - 1.0).abs() < 0.005,
                "T {memory_s} T_b {block_s}: {w} against {quad}"
            );
        }
        // no flicker, or a block within the filter's memory: no wander
        let none = GridPosition {
            block_means: vec![0.0],
            block_s: 0.01,
            flicker_b2: b2,
        };
        assert_eq!(within_block_wander(&none, 0.05), 0.0);
    }
}
