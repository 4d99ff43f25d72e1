//! Test-only simulation of the five-term model (the crate's simulator is written elsewhere):
//! increments of white rate N, rate random walk K (exact integrated Brownian motion), flicker rate
//! B approximated by a bank of 12 Gauss-Markov processes (exact OU increments), and white phase Q
//! added to the phase; then octave AVAR curves by the batch formula.
#![allow(dead_code)]

use allanscope::allan::batch::{oavar, phase_from_increments};
use allanscope::allan::CurvePoint;
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::{LN_2, PI};

/// Coefficients (Q, N, B, K) in native units; R is not simulated (0).
#[derive(Debug, Clone, Copy)]
pub struct Truth {
    pub q: f64,
    pub n: f64,
    pub b: f64,
    pub k: f64,
}

impl Truth {
    pub fn coef(&self) -> [f64; 5] {
        [self.q, self.n, self.b, self.k, 0.0]
    }
}

/// Flicker bank: 12 Gauss-Markov processes, correlation times 1 ms * 4^i (1 ms .. 4194 s), equal
/// variances. With tau0 = 0.01 s its AVAR is flat to 0.3% over 0.3 .. 300 s and within 7% over
/// 0.01 .. 655 s (closed form of docs/theory.md section 3, checked in `flicker_bank_is_flat`).
pub const BANK_T0_S: f64 = 1e-3;
pub const BANK_RATIO: f64 = 4.0;
pub const BANK_SIZE: usize = 12;

/// docs/theory.md section 3: AVAR of a first-order Gauss-Markov rate with variance s2, time T.
pub fn gm_avar(tau: f64, s2: f64, t: f64) -> f64 {
    2.0 * s2 * t / tau
        * (1.0 - (t / (2.0 * tau)) * (3.0 - 4.0 * (-tau / t).exp() + (-2.0 * tau / t).exp()))
}

pub fn bank_times() -> Vec<f64> {
    (0..BANK_SIZE)
        .map(|i| BANK_T0_S * BANK_RATIO.powi(i as i32))
        .collect()
}

/// Per-process variance that makes the bank's AVAR average (2 ln2/pi) B^2 over 0.3 .. 300 s.
pub fn bank_variance(b: f64) -> f64 {
    let ts = bank_times();
    let taus: Vec<f64> = (0..11)
        .map(|k| 0.3 * 2f64.powi(k))
        .filter(|t| *t <= 300.0)
        .collect();
    let mean: f64 = taus
        .iter()
        .map(|&tau| ts.iter().map(|&t| gm_avar(tau, 1.0, t)).sum::<f64>())
        .sum::<f64>()
        / taus.len() as f64;
    2.0 * LN_2 / PI * b * b / mean
}

/// Phase x_0..x_n (u) of the model, sampled every tau0 s.
pub fn simulate_phase(truth: &Truth, tau0: f64, n: usize, seed: u64) -> Vec<f64> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut g = move || -> f64 { rng.sample(StandardNormal) };
    let mut d = vec![0.0f64; n];
    // White rate: increments N(0, N^2 tau0).
    let sn = truth.n * tau0.sqrt();
    for v in d.iter_mut() {
        *v += sn * g();
    }
    // Rate random walk: rate w with Var(dw) = K^2 h; increment = w h + K J, (dW, J) jointly
    // Gaussian with Var dW = h, Var J = h^3/3, Cov = h^2/2.
    if truth.k > 0.0 {
        let h = tau0;
        let (l11, l21) = (h.sqrt(), h * h / 2.0 / h.sqrt());
        let l22 = (h.powi(3) / 3.0 - l21 * l21).sqrt();
        let mut w = 0.0;
        for v in d.iter_mut() {
            let (z1, z2) = (g(), g());
            let dw = l11 * z1;
            let j = l21 * z1 + l22 * z2;
            *v += w * h + truth.k * j;
            w += truth.k * dw;
        }
    }
    // Flicker bank: exact OU steps with the integral of the rate over each step.
    if truth.b > 0.0 {
        let s2 = bank_variance(truth.b);
        for t in bank_times() {
            let h = tau0;
            let a = (-h / t).exp();
            let sig2 = 2.0 * s2 / t; // diffusion of dy = -y/T dt + sigma dW
            let v11 = s2 * (1.0 - a * a);
            let v12 = sig2 * t * t * (1.0 - a) * (1.0 - a) / 2.0;
            let v22 = sig2 * t * t * (h - 2.0 * t * (1.0 - a) + t * (1.0 - a * a) / 2.0);
            let l11 = v11.sqrt();
            let l21 = v12 / l11;
            let l22 = (v22 - l21 * l21).max(0.0).sqrt();
            let mut y = s2.sqrt() * g();
            for v in d.iter_mut() {
                let (z1, z2) = (g(), g());
                let integ = y * t * (1.0 - a) + l21 * z1 + l22 * z2;
                y = y * a + l11 * z1;
                *v += integ;
            }
        }
    }
    let mut x = phase_from_increments(&d);
    if truth.q > 0.0 {
        for v in x.iter_mut() {
            *v += truth.q * g();
        }
    }
    x
}

/// Placeholder edf until Greenhall's algorithm is wired in: the white-FM approximation
/// `(3(N-1)/(2m) - 2(N-2)/N) * 4m^2/(4m^2+5)` (Stable32's simple form), at least 1.
pub fn edf_white_fm(n_phase: usize, m: usize) -> f64 {
    let nf = n_phase as f64;
    let mf = m as f64;
    ((3.0 * (nf - 1.0) / (2.0 * mf) - 2.0 * (nf - 2.0) / nf) * 4.0 * mf * mf
        / (4.0 * mf * mf + 5.0))
        .max(1.0)
}

/// Octave AVAR curve of phase `x` for m = 1, 2, 4, ... <= m_max.
pub fn octave_curve(x: &[f64], tau0: f64, m_max: usize) -> Vec<CurvePoint> {
    let mut out = Vec::new();
    let mut m = 1;
    while m <= m_max && 2 * m < x.len() {
        if let Some(p) = oavar(&[x], m, tau0) {
            out.push(CurvePoint {
                m: m as u64,
                tau_s: m as f64 * tau0,
                var: p.var,
                count: p.count,
                edf: edf_white_fm(x.len(), m),
                alpha: 0,
                sigma_lo: f64::NAN,
                sigma_hi: f64::NAN,
                stride: 1,
                n_phase: x.len() as u64,
            });
        }
        m *= 2;
    }
    out
}

/// The same grid filled with the exact model (no noise).
pub fn model_curve(coef: [f64; 5], tau0: f64, n_incr: usize, m_max: usize) -> Vec<CurvePoint> {
    let mut out = Vec::new();
    let mut m = 1;
    while m <= m_max && 2 * m <= n_incr {
        let tau = m as f64 * tau0;
        out.push(CurvePoint {
            m: m as u64,
            tau_s: tau,
            var: allanscope::model::terms::avar(coef, tau),
            count: (n_incr - 2 * m + 1) as u64,
            edf: edf_white_fm(n_incr + 1, m),
            alpha: 0,
            sigma_lo: f64::NAN,
            sigma_hi: f64::NAN,
            stride: 1,
            n_phase: n_incr as u64 + 1,
        });
        m *= 2;
    }
    out
}
