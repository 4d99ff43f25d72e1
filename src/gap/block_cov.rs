//! The noise model of the time-domain tests: the covariance of the first differences of the
//! block-mean rate under the five-term model plus stationary effects, from the generalised
//! covariance of the phase (avar_cov.rs's table). Used by [`super::warmup`], [`super::steps`]
//! and [`super::oracle`].

use super::effects::EffectParams;
use nalgebra::DMatrix;

/// Generalised covariance `G(t)` of the phase (u^2) under the five-term model `c` plus
/// stationary effects (avar_cov.rs's table; Gauss-Markov `-S(t)/2` with the structure
/// function `S(t) = 2 s^2 T^2 (t/T - 1 + e^{-t/T})`; sinusoid `A^2 cos(w t) / (2 w^2)`). Valid
/// under filters that annihilate polynomials of degree <= 1, such as a second difference.
fn phase_gcov(c: &[f64; 5], effects: &[EffectParams], t: f64) -> f64 {
    let at = t.abs();
    let mut g = if at == 0.0 { c[0] } else { 0.0 };
    g += -c[1] * at / 2.0;
    if at > 0.0 {
        g += c[2] / (2.0 * std::f64::consts::PI) * at * at * at.ln();
    }
    g += c[3] * at * at * at / 12.0;
    for e in effects {
        match *e {
            EffectParams::GaussMarkov { sigma, tau_c_s } => {
                let x = at / tau_c_s;
                g -= sigma * sigma * tau_c_s * tau_c_s * (x - 1.0 + (-x).exp());
            }
            EffectParams::Sinusoid {
                amplitude,
                frequency_hz,
            } => {
                let w = 2.0 * std::f64::consts::PI * frequency_hz;
                g += amplitude * amplitude * (w * at).cos() / (2.0 * w * w);
            }
            // Narrow-band noise as its continuous-time damped cosine `sigma^2 e^{-a t} cos(w t)`
            // (`a = pi width`): `-sigma^2 Re(t / p - (1 - e^{-p t}) / p^2)`, `p = a - i w` (the
            // Gauss-Markov term's form at `w = 0`); exact for blocks long against `tau0`.
            EffectParams::BandNoise {
                frequency_hz,
                sigma,
                width_hz,
            } => {
                g -= sigma * sigma * band_structure(width_hz, frequency_hz, at);
            }
            _ => {}
        }
    }
    g
}

/// `Re(t / p - (1 - e^{-p t}) / p^2)` with `p = pi width - i 2 pi f` (half the phase's
/// structure function of the band per unit variance).
fn band_structure(width_hz: f64, frequency_hz: f64, t: f64) -> f64 {
    let (pr, pi_) = (
        std::f64::consts::PI * width_hz,
        -2.0 * std::f64::consts::PI * frequency_hz,
    );
    let d = pr * pr + pi_ * pi_;
    // 1/p
    let (ir, ii) = (pr / d, -pi_ / d);
    // 1/p^2
    let (jr, ji) = (ir * ir - ii * ii, 2.0 * ir * ii);
    // e^{-p t}
    let e = (-pr * t).exp();
    let (er, ei) = (e * (pi_ * t).cos(), -e * (pi_ * t).sin());
    // t/p - (1 - e^{-pt}) / p^2
    let (ar, ai) = (1.0 - er, -ei);
    t * ir - (ar * jr - ai * ji)
}

/// Covariance (u^2/s^2) of the first differences of block-mean rates `d_i = b_{i+1} - b_i`
/// (second differences of phase at lag `tb`, divided by `tb`) at lags `0..n`.
fn block_diff_acov(c: &[f64; 5], effects: &[EffectParams], tb: f64, n: usize) -> Vec<f64> {
    const A: [f64; 3] = [1.0, -2.0, 1.0];
    (0..n)
        .map(|h| {
            let mut v = 0.0;
            for (i, ai) in A.iter().enumerate() {
                for (j, aj) in A.iter().enumerate() {
                    v += ai * aj * phase_gcov(c, effects, (h as f64 + j as f64 - i as f64) * tb);
                }
            }
            v / (tb * tb)
        })
        .collect()
}

/// Whether block means can carry the time-domain tests: at least 24 blocks, none missing.
pub fn usable_block_means(block_means: &[f64]) -> bool {
    block_means.len() >= 24 && block_means.iter().all(|v| v.is_finite())
}

/// Covariance matrix (u^2/s^2) of the `n_blocks - 1` first differences of the block-mean rate
/// under the model `c` plus stationary `effects` (`block_diff_acov`, a Toeplitz matrix): the
/// noise model of [`fit_warmup`](super::warmup::fit_warmup) and [`detect_steps`](super::steps::detect_steps). `None` below 3 blocks.
pub fn block_diff_covariance(
    n_blocks: usize,
    block_s: f64,
    c: &[f64; 5],
    effects: &[EffectParams],
) -> Option<DMatrix<f64>> {
    if n_blocks < 3 {
        return None;
    }
    let n = n_blocks - 1;
    let acov = block_diff_acov(c, effects, block_s, n);
    Some(DMatrix::from_fn(n, n, |i, j| acov[i.abs_diff(j)]))
}
