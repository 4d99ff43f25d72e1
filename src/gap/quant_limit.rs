//! Quantization-limited units (docs/gap.md, "Quantization-limited units"): when is the
//! quantization of a unit's increments the white phase noise `Q^2 = LSB^2 / 12` that the
//! five-term model assumes, and where on the tau axis is it not.
//!
//! A counter that quantizes the integrated angle (with carry) leaves the error
//! `e_k = Quant(theta_k) - theta_k`. Written as the Fourier series of the sawtooth,
//! `e = sum_n (-1)^n LSB / (pi n) sin(2 pi n theta / LSB)`, and with the change of `theta`
//! between samples `k` apart Gaussian of variance `v_k`, its autocovariance is
//! `c_k = sum_{n >= 1} LSB^2 / (2 pi^2 n^2) exp(-2 pi^2 n^2 v_k / LSB^2)` (Gray and Neuhoff,
//! "Quantization", IEEE Trans. IT 44 (1998), section on dithered and noisy quantizers;
//! Widrow's characteristic-function condition). `c_0 = LSB^2 / 12`; the error is white when
//! `c_1` is negligible, i.e. when the per-sample change is not small against the LSB.
//!
//! With white rate noise `N` and white phase noise of variance `Q_x^2` (beyond the
//! quantization's) the change is `v_k = k N^2 tau0 + 2 Q_x^2`. The ratio
//! `r = sqrt(v_1) / LSB` decides: at `r >= R_WHITE` the lag-one correlation
//! `exp(-2 pi^2 r^2)` is below 0.7% and the quantization is white. Below it the error
//! decorrelates only after `k_q` samples, where `exp(-2 pi^2 v_k / LSB^2) <= e^-8`; at
//! shorter taus the curve lies below the model's `3 Q^2 / tau^2` and the five-term model cannot
//! describe it (a slow wander, not white phase noise). The diagnosis then says so plainly and
//! uses only the taus from `k_q tau0` on, where the quantization is white again.
//!
//! Rate samples rounded each on its own (no carry) leave an error that follows the slow part
//! of the rate when the rate noise is small against the LSB; it does not decorrelate with the
//! lag, so only the plain statement holds there (the restricted taus may still misfit).

use std::f64::consts::PI;

/// `r` at and above which the quantization counts as white (lag-one correlation
/// `exp(-2 pi^2 r^2)` below 0.7%).
pub const R_WHITE: f64 = 0.5;
/// Log of the correlation left at the first tau used (`e^-8`).
const DECORRELATED_LN: f64 = 8.0;

/// A unit whose quantization is not white at the shortest taus.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuantizationLimit {
    /// The increments' LSB (u).
    pub lsb: f64,
    /// `r`: the per-sample rms change of the unquantized phase over the LSB.
    pub ratio: f64,
    /// The shortest tau (s) where the quantization error is white again (`k_q tau0`).
    pub tau_white_s: f64,
    /// `k_q`: cluster size (samples) of `tau_white_s`.
    pub m_white: u64,
}

/// The check, from the increments' `lsb` (u), the fitted white phase noise `q2` (`Q^2`,
/// quantization included, u^2) and white rate noise `n2` (`N^2`, u^2/s) at `tau0_s`: `None`
/// when the quantization is white (or there is no LSB or no noise to judge by).
pub fn quantization_limit(lsb: f64, q2: f64, n2: f64, tau0_s: f64) -> Option<QuantizationLimit> {
    if !(lsb.is_finite() && lsb > 0.0 && tau0_s > 0.0) {
        return None;
    }
    let qx2 = (q2 - lsb * lsb / 12.0).max(0.0);
    let step = n2.max(0.0) * tau0_s;
    let v1 = step + 2.0 * qx2;
    let ratio = v1.sqrt() / lsb;
    if !ratio.is_finite() || ratio >= R_WHITE {
        return None;
    }
    // exp(-2 pi^2 (k step + 2 qx2) / lsb^2) <= e^-8.
    let need = DECORRELATED_LN * lsb * lsb / (2.0 * PI * PI) - 2.0 * qx2;
    let m_white = if step > 0.0 {
        (need / step).ceil().clamp(1.0, 1e15) as u64
    } else {
        u64::MAX
    };
    Some(QuantizationLimit {
        lsb,
        ratio,
        tau_white_s: m_white as f64 * tau0_s,
        m_white,
    })
}

/// The quantization error's autocovariance at a phase change of variance `v` (u^2):
/// `sum_n LSB^2 / (2 pi^2 n^2) exp(-2 pi^2 n^2 v / LSB^2)` (module doc), summed until the
/// terms are below 1e-12 of the first (the tail past 10 000 terms, left only near `v = 0`,
/// added in closed form).
pub fn error_autocovariance(lsb: f64, v: f64) -> f64 {
    let a = 2.0 * PI * PI * v.max(0.0) / (lsb * lsb);
    let mut s = 0.0;
    let terms = 10_000u32;
    for n in 1..=terms {
        let nf = n as f64;
        let t = (-a * nf * nf).exp() / (nf * nf);
        s += t;
        if t < 1e-12 {
            return s * lsb * lsb / (2.0 * PI * PI);
        }
    }
    // The tail beyond `terms` (only reached for `v` near 0): at most `sum_{n > M} 1 / n^2`,
    // about `1 / M` times its decay.
    let m = terms as f64;
    s += (-a * m * m).exp() / m;
    s * lsb * lsb / (2.0 * PI * PI)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// The closed form: `c_0 = LSB^2 / 12` (the sum of `1 / n^2` is `pi^2 / 6`).
    #[test]
    fn zero_lag_is_the_uniform_variance() {
        let c0 = error_autocovariance(0.3, 0.0);
        assert!((c0 - 0.09 / 12.0).abs() < 1e-6 * c0, "{c0}");
    }

    /// Simulation: a random-walk phase quantized with carry, `r = 0.1`; the error's lag-k
    /// covariance matches the closed form within 4 standard errors.
    #[test]
    fn error_covariance_matches_simulation() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let (lsb, sd) = (1.0, 0.1);
        let n = 400_000;
        let mut theta = 0.0;
        let e: Vec<f64> = (0..n)
            .map(|_| {
                let (u1, u2) = (rng.random::<f64>().max(1e-300), rng.random::<f64>());
                theta += sd * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                (theta / lsb).round() * lsb - theta
            })
            .collect();
        for k in [1usize, 10, 50] {
            let c: f64 = (0..n - k).map(|i| e[i] * e[i + k]).sum::<f64>() / (n - k) as f64;
            let want = error_autocovariance(lsb, k as f64 * sd * sd);
            // Samples decorrelate after ~1 / (2 pi^2 sd^2) = 5 steps: ~n / 10 independent.
            let se = lsb * lsb / 12.0 / ((n / 10) as f64).sqrt();
            assert!((c - want).abs() < 4.0 * se, "lag {k}: {c} vs {want}");
        }
    }

    /// The decision: a fine LSB (rate noise 2 LSB per sample) is white; a coarse one (0.05
    /// LSB) is limited and white again from `k_q = 8 / (2 pi^2 0.05^2) = 163` samples; white
    /// phase noise of 1 LSB beyond the quantization dithers it white.
    #[test]
    fn decides_by_the_per_sample_change() {
        let lsb = 1.0;
        let tau0 = 0.01;
        let q2q = lsb * lsb / 12.0;
        let n_for = |r: f64| (r * lsb) * (r * lsb) / tau0;
        assert_eq!(quantization_limit(lsb, q2q, n_for(2.0), tau0), None);
        let l = quantization_limit(lsb, q2q, n_for(0.05), tau0).expect("limited");
        assert!((l.ratio - 0.05).abs() < 1e-12);
        assert_eq!(l.m_white, 163);
        assert!((l.tau_white_s - 1.63).abs() < 1e-9);
        assert_eq!(quantization_limit(lsb, q2q + 1.0, n_for(0.05), tau0), None);
        assert_eq!(quantization_limit(0.0, q2q, 1.0, tau0), None);
    }
}
