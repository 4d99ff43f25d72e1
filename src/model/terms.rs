//! Closed forms of the Allan variance for the five-term model (docs/theory.md section 2, the seed
//! paper's formula (3), IEEE Std 952-1997 annex C).

use std::f64::consts::{LN_2, PI};

/// The five terms in the order of the coefficient vector `c = (Q^2, N^2, B^2, K^2, R^2)`.
pub const TERM_NAMES: [&str; 5] = ["Q", "N", "B", "K", "R"];

/// The basis functions of the five-term model at `tau_s`: `AVAR(tau) = sum_i c_i * basis_i(tau)`
/// with `c = (Q^2, N^2, B^2, K^2, R^2)` (docs/theory.md section 2).
pub fn basis(tau_s: f64) -> [f64; 5] {
    [
        3.0 / (tau_s * tau_s),
        1.0 / tau_s,
        2.0 * LN_2 / PI,
        tau_s / 3.0,
        tau_s * tau_s / 2.0,
    ]
}

/// Five-term AVAR in u^2/s^2 for coefficients `(Q, N, B, K, R)` (not squared).
pub fn avar(coef: [f64; 5], tau_s: f64) -> f64 {
    basis(tau_s)
        .iter()
        .zip(coef.iter())
        .map(|(b, c)| b * c * c)
        .sum()
}

// ---------------------------------------------------------------------------------------------
// Exact discrete-time closed forms, for increments sampled at tau0 (the simulator's output).
//
// Derivation. Let `x_k` be the phase at `t = k tau0` and `D_k(m) = x_{k+2m} - 2 x_{k+m} + x_k` the
// second difference, so that `AVAR(m tau0) = E[D^2] / (2 tau^2)` (docs/theory.md section 1). When the
// increments are stationary with phase structure function `S(n) = Var(x_{k+n} - x_k)`, writing
// `D = A - B` with `A`, `B` the two consecutive m-blocks gives `Var D = 2 S(m) - 2 Cov(A, B)` and
// `S(2m) = 2 S(m) + 2 Cov(A, B)`, hence
//
//     AVAR(m tau0) = (4 S(m) - S(2m)) / (2 tau^2)                                (*)
//
// ([`avar_from_structure`]). Which terms differ from the continuous-time formulas:
// - white phase Q: `S(n) = 2 Q^2` for `n >= 1`, so (*) gives `3 Q^2 / tau^2` at every m (exact).
// - white rate N, increments `N sqrt(tau0) w_k`: `S(n) = N^2 n tau0`, (*) gives `N^2 / tau` (exact).
// - rate random walk K, flicker bank, Gauss-Markov, ramp R: the simulator integrates the
//   continuous-time rate exactly over each step (the increment is the integral, drawn from its
//   exact joint Gaussian law), so the phase points ARE samples of the continuous-time phase and
//   the continuous formulas hold at every m, m = 1 included. Only a rectangle-rule simulation
//   (`d_k = tau0 * rate_k`) departs from them, e.g. [`rate_random_walk_rectangle_avar`].
// - the unit's first-order output filter on white rate: [`filtered_white_rate_avar`].
// - warm-up: deterministic and localised at the start, so the estimate depends on the record
//   length; [`warmup_avar`] is the exact value of the overlapping estimator on a record.
// ---------------------------------------------------------------------------------------------

/// `AVAR(m tau0)` from the phase structure function `S(n) = Var(x_{k+n} - x_k)` (u^2) of a
/// process with stationary increments: `(4 S(m) - S(2m)) / (2 tau^2)` (derivation above).
pub fn avar_from_structure(s: impl Fn(u64) -> f64, m: u64, tau0_s: f64) -> f64 {
    let tau = m as f64 * tau0_s;
    (4.0 * s(m) - s(2 * m)) / (2.0 * tau * tau)
}

/// Quantization with the remainder carried: `Q = lsb / sqrt(12)` in u (docs/theory.md section 2).
pub fn quantization_q(lsb_u: f64) -> f64 {
    lsb_u / 12f64.sqrt()
}

/// White phase noise (Q in u): `3 Q^2 / tau^2`, exact at every m (docs/theory.md section 2).
pub fn white_phase_avar(q_u: f64, tau_s: f64) -> f64 {
    3.0 * q_u * q_u / (tau_s * tau_s)
}

/// White rate noise (N in u/sqrt(s)): `N^2 / tau`, exact at every m.
pub fn white_rate_avar(n: f64, tau_s: f64) -> f64 {
    n * n / tau_s
}

/// Flicker rate noise (B in u/s): `(2 ln2 / pi) B^2`, flat (docs/theory.md section 2).
pub fn flicker_avar(b: f64) -> f64 {
    2.0 * LN_2 / PI * b * b
}

/// Rate random walk (K in u/s/sqrt(s)) with increments integrated exactly: `K^2 tau / 3` at
/// every m (docs/theory.md section 2).
pub fn rate_random_walk_avar(k: f64, tau_s: f64) -> f64 {
    k * k * tau_s / 3.0
}

/// Rate random walk sampled by the rectangle rule, `d_k = tau0 * w_k` with `w_k` a discrete
/// random walk of step `K sqrt(tau0)`: the second difference is `tau0 K sqrt(tau0)` times a
/// triangular sum of the steps with weights `1..m..1`, whose squares add to `m (2 m^2 + 1) / 3`,
/// so `AVAR = K^2 tau0 (2 m^2 + 1) / (6 m) = K^2 tau / 3 + K^2 tau0 / (6 m)` (1.5 times the
/// continuous value at m = 1). Not what the simulator does; kept to document the difference.
pub fn rate_random_walk_rectangle_avar(k: f64, tau0_s: f64, m: u64) -> f64 {
    let mf = m as f64;
    k * k * tau0_s * (2.0 * mf * mf + 1.0) / (6.0 * mf)
}

/// Rate ramp (R in u/s^2): `R^2 tau^2 / 2`; the second difference of `R t^2 / 2` is `R tau^2`
/// exactly, so this holds at every m.
pub fn rate_ramp_avar(r: f64, tau_s: f64) -> f64 {
    r * r * tau_s * tau_s / 2.0
}

/// `1 - (3 - 4 e^{-x} + e^{-2x}) / (2x)`, accurate for small `x` too (power series
/// `sum_{n>=3} (-1)^{n+1} (2^n - 4) x^{n-1} / (2 n!)` below 0.5, where the direct form cancels).
fn gm_shape(x: f64) -> f64 {
    if x < 0.5 {
        let mut sum = 0.0;
        let mut pow2 = 4.0; // 2^n at n = 2
        let mut xn_fact = x * x / 2.0; // x^n / n! at n = 2
        for n in 3..40 {
            pow2 *= 2.0;
            xn_fact *= x / n as f64;
            let sign = if n % 2 == 1 { 1.0 } else { -1.0 };
            sum += sign * (pow2 - 4.0) * xn_fact / (2.0 * x);
        }
        sum
    } else {
        1.0 - (3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp()) / (2.0 * x)
    }
}

/// First-order Gauss-Markov rate noise of stationary sd `sigma` (u/s) and correlation time
/// `tau_c_s` (docs/theory.md section 3): `(2 s^2 T / tau) (1 - (T / 2tau)(3 - 4 e^{-tau/T} + e^{-2tau/T}))`.
/// Exact at every m for the simulator's exactly integrated increments.
pub fn gauss_markov_avar(sigma: f64, tau_c_s: f64, tau_s: f64) -> f64 {
    let x = tau_s / tau_c_s;
    2.0 * sigma * sigma * gm_shape(x) / x
}

/// Sinusoidal rate `A sin(2 pi f0 t + phi)` (A in u/s, f0 in Hz), averaged over the phase
/// (docs/theory.md section 3): `A^2 sin^4(pi f0 tau) / (pi f0 tau)^2`. Holds at every m since the
/// increments are exact integrals; a finite record departs from it by O(1 / (f0 * duration)).
pub fn sinusoid_avar(amplitude: f64, frequency_hz: f64, tau_s: f64) -> f64 {
    let x = PI * frequency_hz * tau_s;
    let s = x.sin();
    amplitude * amplitude * s * s * s * s / (x * x)
}

/// White rate noise N passed through the unit's first-order output filter
/// `y_k = a y_{k-1} + (1 - a) d_k`, `a = e^{-tau0/T}`, on the increments. The filtered increments
/// are AR(1) with `gamma(h) = N^2 tau0 (1-a)/(1+a) a^|h|`, so `S(n) = N^2 tau0 (n - 2a(1-a^n)/(1-a^2))`
/// and (*) gives `N^2 / tau - N^2 a (3 - 4 a^m + a^{2m}) / ((1 - a^2) m^2 tau0)`.
pub fn filtered_white_rate_avar(n: f64, time_constant_s: f64, tau0_s: f64, m: u64) -> f64 {
    let a = (-tau0_s / time_constant_s).exp();
    let mf = m as f64;
    let am = a.powf(mf);
    let one_minus_a2 = -(-2.0 * tau0_s / time_constant_s).exp_m1();
    n * n / (mf * tau0_s)
        - n * n * a * (3.0 - 4.0 * am + am * am) / (one_minus_a2 * mf * mf * tau0_s)
}

/// Gain `|H|^2` of the output filter `y_k = a y_{k-1} + (1 - a) d_k` at `frequency_hz`: a
/// sinusoid's AVAR is multiplied by it (steady state).
pub fn output_filter_power_gain(time_constant_s: f64, tau0_s: f64, frequency_hz: f64) -> f64 {
    let a = (-tau0_s / time_constant_s).exp();
    let w = 2.0 * PI * frequency_hz * tau0_s;
    // |1 - a e^{-iw}|^2 = (1 - a)^2 + 4 a sin^2(w/2)
    let s = (w / 2.0).sin();
    (1.0 - a) * (1.0 - a) / ((1.0 - a) * (1.0 - a) + 4.0 * a * s * s)
}

/// Warm-up bias `A e^{-t/T}` from power-on at `t = 0` (A in u/s): the overlapping estimator on a
/// record of `n_increments` gives exactly
/// `A^2 T^2 (1 - e^{-tau/T})^4 (1 - psi^M) / ((1 - psi) 2 tau^2 M)`, `psi = e^{-2 tau0/T}`,
/// `M = n - 2m + 1`: each second difference is `-A T e^{-k tau0/T} (1 - e^{-tau/T})^2`, a
/// geometric sequence in k. Deterministic; grows like tau^2 for tau << T, fades as the record
/// lengthens (docs/theory.md section 3: localised in time). Returns 0 when `M < 1`.
pub fn warmup_avar(
    amplitude: f64,
    time_constant_s: f64,
    tau0_s: f64,
    m: u64,
    n_increments: u64,
) -> f64 {
    if n_increments < 2 * m {
        return 0.0;
    }
    let count = (n_increments - 2 * m + 1) as f64;
    let tau = m as f64 * tau0_s;
    let one_minus_u = -(-tau / time_constant_s).exp_m1();
    let one_minus_psi = -(-2.0 * tau0_s / time_constant_s).exp_m1();
    let one_minus_psi_m = -(-2.0 * tau0_s * count / time_constant_s).exp_m1();
    let at = amplitude * time_constant_s;
    at * at * one_minus_u.powi(4) * one_minus_psi_m / (one_minus_psi * 2.0 * tau * tau * count)
}

/// The overlapped AVAR (u^2/s^2) at cluster `m`, on a record of `n_increments`, of the rate steps
/// alone: `y_n = sum_i s_i [n >= p_i]`, sizes `sizes` (u/s) at sample indices `positions`
/// (docs/theory.md section 1 applied to this deterministic signal; section 3 for the jumps). Each
/// step adds to the difference of neighbouring cluster means a triangle in the start index `k`,
/// of height `s_i` and base `2m` ending at `p_i`. Past 64 points per triangle side the sum over
/// `k` is taken at the midpoints of runs of `m / 64` starts (the summand is piecewise quadratic,
/// so the relative error is below 1e-4). Returns 0 when there is no difference to take.
pub fn steps_avar(positions: &[u64], sizes: &[f64], m: u64, n_increments: u64) -> f64 {
    if m == 0 || n_increments < 2 * m || positions.len() != sizes.len() {
        return 0.0;
    }
    let k_max = n_increments - 2 * m; // differences k = 0 ..= k_max
    let mf = m as f64;
    let tri = |k: f64, p: u64| {
        let u = k + 2.0 * mf - p as f64;
        if u <= 0.0 || u >= 2.0 * mf {
            0.0
        } else if u <= mf {
            u / mf
        } else {
            (2.0 * mf - u) / mf
        }
    };
    // Windows of nonzero terms, (p - 2m, p) clipped to the record, merged.
    let mut wins: Vec<(u64, u64)> = positions
        .iter()
        .filter_map(|&p| {
            let lo = (p + 1).saturating_sub(2 * m);
            let hi = p.saturating_sub(1).min(k_max);
            (p >= 1 && lo <= hi).then_some((lo, hi))
        })
        .collect();
    wins.sort_unstable();
    let mut merged: Vec<(u64, u64)> = Vec::new();
    for w in wins {
        match merged.last_mut() {
            Some(last) if w.0 <= last.1 + 1 => last.1 = last.1.max(w.1),
            _ => merged.push(w),
        }
    }
    let h = (m / 64).max(1);
    let mut sum = 0.0;
    for (lo, hi) in merged {
        let mut a = lo;
        while a <= hi {
            let b = (a + h - 1).min(hi);
            let k = (a + b) as f64 / 2.0;
            let d: f64 = positions
                .iter()
                .zip(sizes)
                .map(|(&p, &s)| s * tri(k, p))
                .sum();
            sum += d * d * (b - a + 1) as f64;
            a = b + 1;
        }
    }
    sum / (2.0 * (k_max + 1) as f64)
}

/// Bias jumps at Poisson times (mean interval `M` s) with Gaussian sizes of rms `s` (u/s): the
/// rate is a compound Poisson walk whose increments are independent with variance `s^2 / M` per
/// second, the same second-order law as a rate random walk with `K^2 = s^2 / M`, so
/// `AVAR = (s^2 / M) tau / 3` (docs/theory.md section 3; the estimate is far from Gaussian when few jumps).
pub fn bias_jumps_avar(mean_interval_s: f64, rms_size: f64, tau_s: f64) -> f64 {
    rms_size * rms_size / mean_interval_s * tau_s / 3.0
}
