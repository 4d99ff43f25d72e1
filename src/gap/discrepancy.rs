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
//!
//! The error's terms are each linear in `exp(i 2 pi p mu / L)`, `mu` the unit's mean rate, so
//! over a run whose mean moves on the grid (a turn-on bias anywhere between two steps, a drift,
//! a warm-up, jumps) they are multiplied by the run's average `A_p` of `cos(2 pi p mu / L)`
//! (docs/gap.md "Rounding after a filter (session 12)"). Where the block means resolve where
//! the mean falls ([`super::rounding::grid_cosines`]) and the filtered noise is at least
//! [`MIN_SIGMA_STEPS_ON_GRID`] steps, the model holds those terms itself
//! ([`super::rounding::rounding_avar_on_grid`], `GapProblem`'s floor; docs/gap.md, "The grid
//! model wired (session 15)"), down into the dead band and wherever the mean sits. What is left
//! is the error of the `A_p` estimated from some tens of block means, each an average over its
//! block: [`grid_residual_bound`], the first harmonic's bound with `|A_1|` replaced by
//! [`GRID_FLOOR`]. Elsewhere (no step read off the values, too few blocks, the mean moving
//! faster than a block can place it, or deeper in the dead band) the model is the averaged one
//! and the whole bound is kept; below [`super::rounding::MIN_SIGMA_STEPS`] it then leaves the
//! rounding out altogether.

use super::rounding::{grid_cosines, GridPosition, GRID_HARMONICS, MIN_SIGMA_STEPS_ON_GRID};
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
/// The uncertainty of the run's `|A_1|` as the block means estimate it, as a share of the
/// first harmonic's bound kept when the grid model holds the mean-dependent terms (module doc):
/// the blocks' positions are averages over each block, and some 30-300 of them estimate `A_1`
/// to about this.
pub const GRID_FLOOR: f64 = 0.1;

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
    /// `|A_1|`, the run's average of `cos(2 pi mu / L)` as the block means place the mean on
    /// the grid, when the grid model holds the terms that depend on it and only the residual
    /// bound is carried (module doc); None: the averaged model and the bound for the worst
    /// place.
    pub grid_first_harmonic: Option<f64>,
}

/// The relative bound `4 exp(-2 pi^2 sigma_steps^2)` on the rounding model's error (module
/// doc), capped at [`MAX_DISCREPANCY`].
pub fn relative_bound(sigma_steps: f64) -> f64 {
    if !sigma_steps.is_finite() || sigma_steps <= 0.0 {
        return MAX_DISCREPANCY;
    }
    (4.0 * (-2.0 * PI * PI * sigma_steps * sigma_steps).exp()).min(MAX_DISCREPANCY)
}

/// The relative bound left when the grid model ([`super::rounding::rounding_avar_on_grid`])
/// holds the terms that depend on where the mean falls: the first harmonic's,
/// `4 GRID_FLOOR exp(-x / 2)`, `x = 4 pi^2 sigma_steps^2` (module doc), capped at
/// [`MAX_DISCREPANCY`]. 0.068 at 0.3 filtered sigmas per step, 0.0074 at 0.45.
pub fn grid_residual_bound(sigma_steps: f64) -> f64 {
    if !sigma_steps.is_finite() || sigma_steps <= 0.0 {
        return MAX_DISCREPANCY;
    }
    let x = 4.0 * PI * PI * sigma_steps * sigma_steps;
    (4.0 * GRID_FLOOR * (-0.5 * x).exp()).min(MAX_DISCREPANCY)
}

/// The run's averages of `cos(2 pi p mu / L)` when the block means `grid` place the mean on
/// the grid of step `step` (u/s) for a filtered sample noise `sigma` (u/s) of white rate
/// `N^2 = n2` (u^2/s) at or above [`MIN_SIGMA_STEPS_ON_GRID`] steps: the one decision behind
/// the floor (`GapProblem::set_filter_floor` keeps the grid model there) and the residual
/// bound ([`rounding_discrepancy`]). None: no grid, below `MIN_SIGMA_STEPS_ON_GRID`, or the
/// position not resolved.
pub fn floor_harmonics(
    grid: Option<&GridPosition>,
    step: f64,
    sigma: f64,
    n2: f64,
    memory_s: f64,
) -> Option<[f64; GRID_HARMONICS]> {
    let sigma_steps = sigma / step;
    grid.filter(|_| sigma_steps >= MIN_SIGMA_STEPS_ON_GRID)
        .and_then(|g| grid_cosines(g, step, sigma * sigma, n2, memory_s))
}

/// The discrepancy of a channel whose rate samples, filtered by `lp` (white rate `N^2 = n2`,
/// u^2/s, at `tau0_s`), are rounded to `step` (u/s), with the run's block means `grid` when
/// known: `None` when the bound is below [`MIN_DISCREPANCY`] or the inputs cannot say.
pub fn rounding_discrepancy(
    lp: &LowPass,
    tau0_s: f64,
    step: f64,
    n2: f64,
    grid: Option<&GridPosition>,
) -> Option<RoundingDiscrepancy> {
    if !(step > 0.0 && step.is_finite() && tau0_s > 0.0 && n2.is_finite() && n2 >= 0.0) {
        return None;
    }
    let sigma = super::rounding::filtered_sigma(lp, tau0_s, n2);
    let sigma_steps = sigma / step;
    let harmonics = floor_harmonics(grid, step, sigma, n2, lp.memory_s(tau0_s));
    let bound = match harmonics {
        Some(_) => grid_residual_bound(sigma_steps),
        None => relative_bound(sigma_steps),
    };
    if bound < MIN_DISCREPANCY {
        return None;
    }
    Some(RoundingDiscrepancy {
        sigma_steps,
        bound,
        tau_full_s: MEMORIES * lp.memory_s(tau0_s).max(tau0_s),
        grid_first_harmonic: harmonics.map(|a| a[0].abs()),
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

    /// A first order of 10 samples at 200 Hz on white rate `N^2 = 1e-4`: the filter, tau0 (s),
    /// `N^2` and the filtered sample's sigma, `N sqrt(rho_0 / tau0)` with a first order's
    /// `rho_0 = (1 - a) / (1 + a)`, `a = exp(-tau0 / T)`.
    fn first_order_unit() -> (LowPass, f64, f64, f64) {
        let (t, tau0, n2): (f64, f64, f64) = (0.05, 0.005, 1e-4);
        let a = (-tau0 / t).exp();
        let sigma = (n2 * (1.0 - a) / (1.0 + a) / tau0).sqrt();
        (LowPass::FirstOrder { time_constant_s: t }, tau0, n2, sigma)
    }

    #[test]
    fn a_fine_step_adds_nothing_and_a_coarse_one_holds_to_ten_memories() {
        let (lp, tau0, n2, sigma) = first_order_unit();
        assert!(rounding_discrepancy(&lp, tau0, sigma / 2.0, n2, None).is_none());
        let d = rounding_discrepancy(&lp, tau0, sigma / 0.35, n2, None).expect("dead band");
        assert!((d.sigma_steps - 0.35).abs() < 0.01, "{}", d.sigma_steps);
        let full = d.tau_full_s;
        let sd = d.sd(&[full / 4.0, full, 4.0 * full]);
        assert!((sd[0] - d.bound).abs() < 1e-12 && (sd[1] - d.bound).abs() < 1e-12);
        assert!((sd[2] - d.bound / 4.0).abs() < 1e-12);
        let c = d.covariance(&[full / 2.0, full]);
        // One octave apart: correlation exp(-1/2).
        assert!((c[(0, 1)] / (sd[0] * sd[1]) - (-0.5f64).exp()).abs() < 1e-12);
    }

    #[test]
    fn the_residual_on_the_grid_is_the_first_harmonic_at_the_grid_floor() {
        // 4 GRID_FLOOR exp(-x / 2), x = 4 pi^2 s^2: at 0.3 steps x = 3.553, exp(-x / 2) =
        // 0.1693, 0.0677 (the worst case's bound there is 0.677); at 0.45 steps 0.00735.
        assert!((grid_residual_bound(0.3) - 0.0677).abs() < 5e-4);
        assert!((relative_bound(0.3) - 0.677).abs() < 2e-3);
        assert!((grid_residual_bound(0.45) - 0.00735).abs() < 5e-5);
        assert_eq!(grid_residual_bound(0.0), MAX_DISCREPANCY);
        assert_eq!(grid_residual_bound(f64::NAN), MAX_DISCREPANCY);
    }

    #[test]
    fn where_the_block_means_place_the_mean_only_the_residual_is_carried() {
        let (lp, tau0, n2, sigma) = first_order_unit();
        let grid_at = |steps: f64, step: f64| GridPosition {
            block_means: vec![steps * step; 64],
            block_s: 100.0,
            flicker_b2: 0.0,
        };
        // 0.45 filtered sigmas per step: without the block means the worst case,
        // 4 exp(-x / 2) = 0.0735 (x = 4 pi^2 0.2025); with them, on a step or a quarter step
        // off, the grid model holds the rest and the residual 0.0074 is below MIN_DISCREPANCY.
        let step = sigma / 0.45;
        let worst = rounding_discrepancy(&lp, tau0, step, n2, None).expect("worst case");
        assert!((worst.bound - 0.0735).abs() < 3e-4, "{}", worst.bound);
        assert!(worst.grid_first_harmonic.is_none());
        assert!(rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(3.0, step))).is_none());
        assert!(rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(-2.25, step))).is_none());
        // At 0.35 steps, in the dead band: without the block means the whole bound, 0.356;
        // with them the residual 4 * 0.1 exp(-x / 2) = 0.0356 (x = 4.836) wherever the mean
        // falls, with |A_1| read as 1 on a step and 0 a quarter step off (the blocks hold the
        // output's mean, 0.25 - exp(-x / 2) / pi = 0.222 steps, which the inversion takes back
        // to the quarter step).
        let step = sigma / 0.35;
        let d = rounding_discrepancy(&lp, tau0, step, n2, None).expect("dead band");
        assert!((d.bound - 0.356).abs() < 2e-3, "{d:?}");
        let d = rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(3.0, step)))
            .expect("on a step");
        assert!((d.bound - 0.0356).abs() < 2e-3, "{d:?}");
        assert!(d.grid_first_harmonic.is_some_and(|a| a > 0.99), "{d:?}");
        let out = 0.25 - (-0.5 * 4.0 * PI * PI * 0.35f64.powi(2)).exp() / PI;
        let d = rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(out, step)))
            .expect("a quarter step off");
        assert!((d.bound - 0.0356).abs() < 2e-3, "{d:?}");
        assert!(d.grid_first_harmonic.is_some_and(|a| a < 0.05), "{d:?}");
        // Below MIN_SIGMA_STEPS_ON_GRID the whole bound stays wherever the mean falls.
        let step = sigma / 0.2;
        let d = rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(0.25, step)))
            .expect("deep in the dead band");
        assert_eq!(d.bound, MAX_DISCREPANCY);
    }
}
