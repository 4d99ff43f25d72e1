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
/// `step` (u/s) the rate of a unit with white rate `N^2 = n2` (u^2/s) filtered by `lp` (see the
/// module doc). Sums of `n` errors have variance `n R_0 + 2 sum_{0<k<n} (n - k) R_k` (in
/// samples), and `AVAR(m) = (4 S(m) - S(2m)) / (2 m^2)`.
pub fn rounding_avar(lp: &LowPass, tau0_s: f64, step: f64, n2: f64, ms: &[u64]) -> Vec<f64> {
    let rho = lp.autocorrelation(tau0_s);
    let rho0 = rho.first().copied().unwrap_or(1.0);
    let sigma2 = n2.max(0.0) * rho0 / tau0_s;
    let x = 4.0 * PI * PI * sigma2 / (step * step);
    let c = step * step / (2.0 * PI * PI);
    let tail = theta_sum(x);
    let r: Vec<f64> = rho
        .iter()
        .map(|&v| c * (theta_sum(x * (1.0 - v / rho0).max(0.0)) - tail))
        .collect();
    // the errors' AVAR of averages of m samples (unit sample time: S(n) in samples)
    avar_from_autocovariance(&r, 1.0, ms)
}
