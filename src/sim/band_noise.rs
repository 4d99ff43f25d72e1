//! Narrow-band random noise (a resonance driven by white noise: a vibration of the stand or a
//! mode of the sensor) as a model-file term, its streaming generator and its exact Allan
//! variance (docs/gap.md, "Narrow-band noise (session 11)").
//!
//! The rate samples `y_k` (the mean rate over step `k`, u/s) of the term are a second-order
//! Gauss-Markov sequence with the exponentially damped cosine autocovariance
//!
//! `c_k = sigma^2 rho^|k| cos(theta k)`, `rho = exp(-pi w tau0)`, `theta = 2 pi f0 tau0`,
//!
//! (centre `f0` in Hz, `0 < f0 < 1 / (2 tau0)`; width `w` in Hz, the full width at half power of
//! each spectral peak when it is narrow; rms `sigma` in u/s). It is the real part of a complex
//! first-order autoregression `z_k = rho e^{i theta} z_{k-1} + e_k`, i.e. white noise through
//! a resonator whose pole pair is `rho e^{+-i theta}`. Being defined on the samples, it holds at
//! any centre below Nyquist: the two peaks at `+-f0` of its periodic spectrum overlap near 0 and
//! near Nyquist, and the autocovariance above is still exact (a continuous-time band above
//! Nyquist is seen at its alias). Its AVAR follows from the autocovariance exactly
//! ([`band_noise_avar`], the closed form of `crate::model::lowpass::avar_from_autocovariance`'s
//! sum).

use std::f64::consts::PI;

/// A narrow-band noise term of a channel: rms `sigma` (u/s), centre `frequency_hz`, width
/// `width_hz` (Hz).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandNoise {
    pub sigma: f64,
    pub frequency_hz: f64,
    pub width_hz: f64,
}

impl BandNoise {
    /// The pole `(rho, theta)` of its resonator at sampling step `tau0_s`.
    pub fn pole(&self, tau0_s: f64) -> (f64, f64) {
        pole(self.frequency_hz, self.width_hz, tau0_s)
    }
}

/// The pole `(rho, theta)` of a band at `frequency_hz` of width `width_hz` sampled at `tau0_s`:
/// `rho = exp(-pi w tau0)`, `theta = 2 pi f0 tau0` (rad per sample).
pub fn pole(frequency_hz: f64, width_hz: f64, tau0_s: f64) -> (f64, f64) {
    (
        (-PI * width_hz * tau0_s).exp(),
        2.0 * PI * frequency_hz * tau0_s,
    )
}

/// Lag-`k` autocovariance of the rate samples (u^2/s^2), `sigma^2 rho^|k| cos(theta k)`.
pub fn band_noise_autocovariance(
    sigma: f64,
    frequency_hz: f64,
    width_hz: f64,
    tau0_s: f64,
    k: u64,
) -> f64 {
    let (rho, theta) = pole(frequency_hz, width_hz, tau0_s);
    sigma * sigma * rho.powf(k as f64) * (theta * k as f64).cos()
}

/// `Re` of `V(n) = n + 2 sum_{k=1}^{n-1} (n - k) z^k` for `z = rho e^{i theta}`: the variance of
/// a sum of `n` rate samples per `sigma^2`. With `u = 1 - z`,
/// `sum_{k=1}^{n-1} (n - k) z^k = z (n u - 1 + z^n) / u^2` (a geometric series summed twice).
fn sum_variance(rho: f64, theta: f64, n: f64) -> f64 {
    // z, u = 1 - z, z^n as (re, im)
    let (zr, zi) = (rho * theta.cos(), rho * theta.sin());
    let (ur, ui) = (1.0 - zr, -zi);
    let rn = rho.powf(n);
    let (pr, pi_) = (rn * (theta * n).cos(), rn * (theta * n).sin());
    // a = n u - 1 + z^n
    let (ar, ai) = (n * ur - 1.0 + pr, n * ui + pi_);
    // b = z a
    let (br, bi) = (zr * ar - zi * ai, zr * ai + zi * ar);
    // u^2
    let (sr, si) = (ur * ur - ui * ui, 2.0 * ur * ui);
    let den = sr * sr + si * si;
    // Re(b / u^2) = Re(b conj(u^2)) / |u^2|^2
    let re = (br * sr + bi * si) / den;
    n + 2.0 * re
}

/// AVAR (u^2/s^2) of the band at cluster size `m` (tau = `m tau0`): for a stationary sequence,
/// `(4 V(m) - V(2m)) / (2 m^2)` with `V(n)` the variance of a sum of `n` samples (the identity
/// behind `avar_from_autocovariance`), `V` in closed form ([`sum_variance`]). Exact for every
/// `m`, centre and width.
pub fn band_noise_avar(sigma: f64, frequency_hz: f64, width_hz: f64, tau0_s: f64, m: u64) -> f64 {
    if m == 0 || sigma.is_nan() || sigma <= 0.0 {
        return 0.0;
    }
    let (rho, theta) = pole(frequency_hz, width_hz, tau0_s);
    let mf = m as f64;
    let v = 4.0 * sum_variance(rho, theta, mf) - sum_variance(rho, theta, 2.0 * mf);
    (sigma * sigma * v / (2.0 * mf * mf)).max(0.0)
}

/// Streaming generator of the band's increments (u per step): the rate sample `y_k` times
/// `tau0`, from the complex first-order recursion of the module doc, started in its stationary
/// law. Two normal draws per step; no trigonometry per step.
#[derive(Debug, Clone)]
pub struct BandNoiseGen {
    /// `rho cos theta`, `rho sin theta`.
    a: f64,
    b: f64,
    /// Innovation sd of each component, `sigma sqrt(1 - rho^2)`.
    s_e: f64,
    x: f64,
    y: f64,
    tau0_s: f64,
}

impl BandNoiseGen {
    /// `first`, `second`: two standard normal draws for the stationary start (each component
    /// has variance `sigma^2`).
    pub fn new(band: &BandNoise, tau0_s: f64, first: f64, second: f64) -> Self {
        let (rho, theta) = band.pole(tau0_s);
        Self {
            a: rho * theta.cos(),
            b: rho * theta.sin(),
            s_e: band.sigma * (1.0 - rho * rho).max(0.0).sqrt(),
            x: band.sigma * first,
            y: band.sigma * second,
            tau0_s,
        }
    }

    /// The increment over the next step, from two standard normal draws.
    #[inline]
    pub fn step(&mut self, w1: f64, w2: f64) -> f64 {
        let x = self.a * self.x - self.b * self.y + self.s_e * w1;
        let y = self.b * self.x + self.a * self.y + self.s_e * w2;
        self.x = x;
        self.y = y;
        x * self.tau0_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::lowpass::avar_from_autocovariance;

    /// The closed form against the autocovariance summed lag by lag (docs/gap.md's identity),
    /// over centres up to 0.45 of the sample rate and widths from 0.3% to 40% of it.
    #[test]
    fn closed_form_matches_the_autocovariance_sum() {
        let tau0 = 0.01;
        for &(f0, w) in &[
            (20.7, 2.0),
            (1.3, 0.05),
            (45.0, 3.0),
            (33.0, 40.0),
            (0.2, 0.3),
        ] {
            let (rho, _) = pole(f0, w, tau0);
            let lags = ((1e-18f64).ln() / rho.ln()).ceil() as usize + 2;
            let cov: Vec<f64> = (0..lags.max(4000))
                .map(|k| band_noise_autocovariance(0.7, f0, w, tau0, k as u64))
                .collect();
            let ms = [1u64, 2, 3, 5, 8, 13, 40, 100, 333, 1000];
            let want = avar_from_autocovariance(&cov, 1.0, &ms);
            for (&m, wv) in ms.iter().zip(&want) {
                let got = band_noise_avar(0.7, f0, w, tau0, m);
                assert!(
                    (got - wv).abs() <= 1e-9 * wv.abs().max(1e-6),
                    "f0 {f0} w {w} m {m}: {got} vs {wv}"
                );
            }
            // m = 1: the AVAR of single samples is sigma^2 (1 - c_1 / sigma^2)
            let c1 = band_noise_autocovariance(0.7, f0, w, tau0, 1) / 0.49;
            assert!((band_noise_avar(0.7, f0, w, tau0, 1) / 0.49 - (1.0 - c1)).abs() < 1e-12);
        }
    }
}
