//! The known error of the rounding model after a filter, carried in the curve's covariance
//! (docs/gap.md, "The dead band as model discrepancy (session 13)").
//!
//! A MEMS part that filters its rate and then rounds each sample to a step `L` (u/s) leaves an
//! error whose AVAR [`super::rounding::rounding_avar`] gives averaged over where the unit's mean
//! falls between two steps. What that average drops is the error's correlation with the signal
//! and the cross harmonics, both set by the mean's position on the grid: their size, relative
//! to the filtered rate's own AVAR, is bounded by the first harmonic's
//! `4 exp(-x / 2)`, `x = 4 pi^2 sigma^2 / L^2` (the factor `4 sum_p (-1)^p A_p exp(-x p^2 / 2)`
//! of docs/gap.md "Rounding after a filter (session 12)" with `|A_1| <= 1`): 3% at
//! `sigma = L / 2`, 7% at `0.45 L`, 36% at `0.35 L`, where simulation measured 4-7% and 18-31%
//! with the mean on a step. Below [`super::rounding::MIN_SIGMA_STEPS`] the diagnosis leaves the
//! rounding out of the model altogether and the error is larger still; the bound is then capped
//! at [`MAX_DISCREPANCY`] (the curve's short taus say almost nothing).
//!
//! Rather than read that error as an effect (session 11 found every remaining false alarm of
//! the `accfilt` family there: a Gauss-Markov term, a sinusoid or a second filter invented
//! beside the unit's own first order), it is entered as what it is, a model discrepancy
//! (Kennedy and O'Hagan, "Bayesian calibration of computer models", J. R. Stat. Soc. B 63
//! (2001), section 4.3): a zero-mean Gaussian deviation of `ln AVAR` with standard deviation
//! `delta_i = d w_i` at each tau of the curve, smooth across taus (squared-exponential
//! correlation in `ln tau` with a length of [`LENGTH_OCTAVES`] octaves), added to the
//! covariance of `ln AVAR` that every fit and test of the diagnosis uses. `d` is the bound
//! above; `w_i` is 1 up to ten memories of the filter (the cut beyond which the diagnosis
//! already fits the covariance's five terms, where the error is white rate noise that the free
//! `N` takes in) and falls as `1 / tau` beyond. A channel whose bound is below
//! [`MIN_DISCREPANCY`] (the rounding fine against the noise) gets nothing.

use crate::model::lowpass::LowPass;
use nalgebra::DMatrix;
use std::f64::consts::PI;

/// Below this relative bound the discrepancy is left out (the rounding model is right within
/// the curve's own resolution there: `sigma >= 0.6 L`).
pub const MIN_DISCREPANCY: f64 = 0.01;
/// The largest standard deviation of `ln AVAR` the discrepancy takes (a factor `e` either way).
pub const MAX_DISCREPANCY: f64 = 1.0;
/// The correlation length of the discrepancy along the curve, in octaves of tau.
pub const LENGTH_OCTAVES: f64 = 1.0;
/// The discrepancy's full size holds up to this many memories of the filter.
const MEMORIES: f64 = 10.0;

/// The discrepancy found for a channel: docs/records.md's `quantization_limited` reuses its
/// numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundingDiscrepancy {
    /// The filtered rate sample's standard deviation over the step, `sigma / L`.
    pub sigma_steps: f64,
    /// `d`: the relative bound on the model's error at the short taus.
    pub bound: f64,
    /// The tau (s) up to which the bound holds in full (ten memories of the filter).
    pub tau_full_s: f64,
}

/// The relative bound `4 exp(-2 pi^2 sigma_steps^2)` on the rounding model's error (module
/// doc), capped at [`MAX_DISCREPANCY`].
pub fn relative_bound(sigma_steps: f64) -> f64 {
    if !sigma_steps.is_finite() || sigma_steps <= 0.0 {
        return MAX_DISCREPANCY;
    }
    (4.0 * (-2.0 * PI * PI * sigma_steps * sigma_steps).exp()).min(MAX_DISCREPANCY)
}

/// The discrepancy of a channel whose rate samples, filtered by `lp` (white rate `N^2 = n2`,
/// u^2/s, at `tau0_s`), are rounded to `step` (u/s): `None` when the bound is below
/// [`MIN_DISCREPANCY`] or the inputs cannot say.
pub fn rounding_discrepancy(
    lp: &LowPass,
    tau0_s: f64,
    step: f64,
    n2: f64,
) -> Option<RoundingDiscrepancy> {
    if !(step > 0.0 && step.is_finite() && tau0_s > 0.0 && n2.is_finite() && n2 >= 0.0) {
        return None;
    }
    let sigma = super::rounding::filtered_sigma(lp, tau0_s, n2);
    let sigma_steps = sigma / step;
    let bound = relative_bound(sigma_steps);
    if bound < MIN_DISCREPANCY {
        return None;
    }
    Some(RoundingDiscrepancy {
        sigma_steps,
        bound,
        tau_full_s: MEMORIES * lp.memory_s(tau0_s).max(tau0_s),
    })
}

impl RoundingDiscrepancy {
    /// The standard deviation of `ln AVAR` it adds at each tau of `taus` (s).
    pub fn sd(&self, taus: &[f64]) -> Vec<f64> {
        taus.iter()
            .map(|&t| self.bound * (self.tau_full_s / t).min(1.0))
            .collect()
    }

    /// Its covariance of `ln AVAR` at `taus` (s):
    /// `delta_i delta_j exp(-(log2 tau_i - log2 tau_j)^2 / (2 l^2))`.
    pub fn covariance(&self, taus: &[f64]) -> DMatrix<f64> {
        let sd = self.sd(taus);
        let l2 = LENGTH_OCTAVES * LENGTH_OCTAVES;
        DMatrix::from_fn(taus.len(), taus.len(), |i, j| {
            let d = (taus[i] / taus[j]).log2();
            sd[i] * sd[j] * (-d * d / (2.0 * l2)).exp()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_is_the_first_harmonic() {
        // 4 exp(-2 pi^2 s^2): 0.356 at 0.35 steps, 0.0288 at 0.5 (docs/gap.md's -0.36 with the
        // mean on a step at sigma = 0.35 L).
        assert!((relative_bound(0.35) - 0.3562).abs() < 1e-3);
        assert!((relative_bound(0.5) - 0.02877).abs() < 2e-5);
        assert_eq!(relative_bound(0.2), MAX_DISCREPANCY);
        assert_eq!(relative_bound(0.0), MAX_DISCREPANCY);
    }

    #[test]
    fn a_fine_step_adds_nothing_and_a_coarse_one_holds_to_ten_memories() {
        let lp = LowPass::FirstOrder {
            time_constant_s: 0.05,
        };
        let tau0 = 0.005;
        // sigma = N sqrt(rho_0 / tau0); rho_0 of a first order of a = exp(-tau0/T) is
        // (1 - a) / (1 + a) per sample of unit white rate.
        let a: f64 = (-tau0 / 0.05f64).exp();
        let n2 = 1e-4;
        let sigma = (n2 * (1.0 - a) / (1.0 + a) / tau0).sqrt();
        assert!(rounding_discrepancy(&lp, tau0, sigma / 2.0, n2).is_none());
        let d = rounding_discrepancy(&lp, tau0, sigma / 0.35, n2).expect("dead band");
        assert!((d.sigma_steps - 0.35).abs() < 0.01, "{}", d.sigma_steps);
        let full = d.tau_full_s;
        let sd = d.sd(&[full / 4.0, full, 4.0 * full]);
        assert!((sd[0] - d.bound).abs() < 1e-12 && (sd[1] - d.bound).abs() < 1e-12);
        assert!((sd[2] - d.bound / 4.0).abs() < 1e-12);
        let c = d.covariance(&[full / 2.0, full]);
        // One octave apart: correlation exp(-1/2).
        assert!((c[(0, 1)] / (sd[0] * sd[1]) - (-0.5f64).exp()).abs() < 1e-12);
    }
}
