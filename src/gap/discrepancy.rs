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
//! (docs/gap.md "Rounding after a filter (session 12)"). Where the model carries the rounding
//! (`sigma >= MIN_SIGMA_STEPS L`) and the block means resolve where the mean falls
//! ([`super::rounding::grid_cosines`]), the bound is therefore
//! `4 (max(|A_1|, GRID_FLOOR) exp(-x / 2) + |A_2| exp(-2 x))` ([`GRID_FLOOR`]): a unit whose
//! mean sits a quarter step off the grid, or wanders over several steps, needs little of it.
//! Below `MIN_SIGMA_STEPS` the model carries the rounding only where that scaled bound is
//! small ([`floor_holds`], down to `MIN_SIGMA_STEPS_ON_GRID`); elsewhere it leaves the rounding
//! out and the whole bound is kept. The block means see the mean's position over whole blocks
//! only; what moves it faster (a sinusoid, the unit's own noise) lowers the true `|A_p|`
//! further, so the bound stays an upper one except where blocks at opposite positions differ
//! in their spread, which the floor covers.

use super::rounding::{
    grid_cosines, GridPosition, GRID_HARMONICS, MIN_SIGMA_STEPS, MIN_SIGMA_STEPS_ON_GRID,
};
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
/// The smallest share of the first harmonic's bound kept when the block means place the mean
/// on the grid (module doc): the blocks' positions are averages over each block, and the
/// estimate of `|A_1|` from some 30-300 of them is uncertain by about this much.
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
    /// the grid, when it scaled the bound (module doc); None: the bound for the worst place.
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

/// The relative bound when the run's averages of `cos(2 pi p mu / L)` are `a1` and `a2`:
/// `4 (max(|a1|, GRID_FLOOR) exp(-x / 2) + |a2| exp(-2 x))`, `x = 4 pi^2 sigma_steps^2`
/// (module doc), capped at [`MAX_DISCREPANCY`].
pub fn relative_bound_on_grid(sigma_steps: f64, a1: f64, a2: f64) -> f64 {
    if !sigma_steps.is_finite() || sigma_steps <= 0.0 {
        return MAX_DISCREPANCY;
    }
    let x = 4.0 * PI * PI * sigma_steps * sigma_steps;
    let a1 = if a1.is_finite() { a1.abs() } else { 1.0 };
    let a2 = if a2.is_finite() { a2.abs() } else { 1.0 };
    (4.0 * (a1.max(GRID_FLOOR) * (-0.5 * x).exp() + a2 * (-2.0 * x).exp())).min(MAX_DISCREPANCY)
}

/// Whether the rounding model averaged over the mean's position (the filter's floor,
/// `GapProblem::set_filter_floor`) describes a channel with filtered noise `sigma_steps` steps
/// whose block means give the run's averages `harmonics` of `cos(2 pi p mu / L)`: always from
/// [`MIN_SIGMA_STEPS`] on; down to [`MIN_SIGMA_STEPS_ON_GRID`] when the bound on what it drops,
/// scaled by where the mean falls ([`relative_bound_on_grid`]), is no larger than the worst
/// case's at `MIN_SIGMA_STEPS` (docs/gap.md, "The floor on the grid (session 14)": with the
/// mean a quarter step off the grid the averaged model is within 3.5% of simulation at 0.3
/// filtered sigmas per step, and 20% off at a fifth of a step, where this bound is 0.21).
pub fn floor_holds(sigma_steps: f64, harmonics: Option<&[f64]>) -> bool {
    if sigma_steps >= MIN_SIGMA_STEPS {
        return true;
    }
    sigma_steps >= MIN_SIGMA_STEPS_ON_GRID
        && harmonics.is_some_and(|a| {
            a.len() >= 2
                && relative_bound_on_grid(sigma_steps, a[0], a[1])
                    <= relative_bound(MIN_SIGMA_STEPS)
        })
}

/// The run's averages of `cos(2 pi p mu / L)` when the block means `grid` place the mean on
/// the grid of step `step` (u/s) and the averaged model holds there ([`floor_holds`]) for a
/// filtered sample noise `sigma` (u/s) of white rate `N^2 = n2` (u^2/s): the one decision
/// behind both the floor (`GapProblem::set_filter_floor`) and the scaled bound
/// ([`rounding_discrepancy`]). None: no grid, below [`MIN_SIGMA_STEPS_ON_GRID`], the position
/// not resolved, or the floor does not hold.
pub fn floor_harmonics(
    grid: Option<&GridPosition>,
    step: f64,
    sigma: f64,
    n2: f64,
) -> Option<[f64; GRID_HARMONICS]> {
    let sigma_steps = sigma / step;
    grid.filter(|_| sigma_steps >= MIN_SIGMA_STEPS_ON_GRID)
        .and_then(|g| grid_cosines(g, step, sigma * sigma, n2))
        .filter(|a| floor_holds(sigma_steps, Some(a)))
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
    let harmonics = floor_harmonics(grid, step, sigma, n2);
    let bound = match harmonics {
        Some(a) => relative_bound_on_grid(sigma_steps, a[0], a[1]),
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
    fn the_floor_holds_below_min_sigma_steps_only_where_the_grid_says_so() {
        // 0.3 filtered sigmas per step: x = 3.553, exp(-x / 2) = 0.1693, exp(-2 x) = 0.00082.
        // A quarter step off the grid (A_1 = 0, A_2 = -1): 4 (0.1 * 0.1693 + 0.00082) = 0.071,
        // below the worst case at 0.4 steps, 4 exp(-2 pi^2 0.16) = 0.170.
        let quarter = [0.0, -1.0];
        assert!((relative_bound_on_grid(0.3, 0.0, -1.0) - 0.0710).abs() < 5e-4);
        assert!((relative_bound(MIN_SIGMA_STEPS) - 0.1700).abs() < 5e-4);
        assert!(floor_holds(0.3, Some(&quarter)));
        // A fifth of a step off (A_1 = cos(0.4 pi) = 0.309, A_2 = -0.809): 0.212, where
        // simulation has the averaged model 12-20% off (docs/gap.md).
        let fifth = [(0.4 * PI).cos(), (0.8 * PI).cos()];
        assert!((relative_bound_on_grid(0.3, fifth[0], fifth[1]) - 0.212).abs() < 2e-3);
        assert!(!floor_holds(0.3, Some(&fifth)));
        // Without the grid, or below MIN_SIGMA_STEPS_ON_GRID, only from MIN_SIGMA_STEPS on.
        assert!(!floor_holds(0.3, None));
        assert!(!floor_holds(0.2, Some(&quarter)));
        assert!(floor_holds(0.45, None));
    }

    #[test]
    fn the_mean_a_quarter_step_off_the_grid_needs_little_of_it() {
        let (lp, tau0, n2, sigma) = first_order_unit();
        let grid_at = |steps: f64, step: f64| GridPosition {
            block_means: vec![steps * step; 64],
            block_s: 100.0,
        };
        // 0.45 filtered sigmas per step: x = 4 pi^2 0.2025, exp(-x / 2) = 0.01838.
        let step = sigma / 0.45;
        let on = rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(3.0, step)))
            .expect("the mean on a step");
        assert!((on.bound - 4.0 * 0.01838).abs() < 2e-4, "{}", on.bound);
        assert!((on.grid_first_harmonic.unwrap() - 1.0).abs() < 1e-6);
        // A quarter step off: the block mean holds the rounding's mean error, -(L / pi)
        // exp(-x / 2) = -0.0059 steps, taken back out; |A_1| = |cos(2 pi 0.25)| = 0, kept at
        // the floor, 4 * 0.1 * 0.01838 = 0.0074, below MIN_DISCREPANCY.
        assert!(rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(-2.25, step))).is_none());
        // At 0.35 steps, below MIN_SIGMA_STEPS: with the mean on a step the model holds no
        // rounding and the whole bound stays (0.356); a quarter step off, the floor holds
        // (`floor_holds`) and the bound is the grid's, 4 (0.1 exp(-x / 2) + exp(-2 x)) = 0.036
        // (x = 4.836; the blocks hold the output's mean, 0.25 - exp(-x / 2) / pi = 0.222 steps,
        // which the inversion takes back to the quarter step).
        let step = sigma / 0.35;
        let d = rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(3.0, step)))
            .expect("dead band");
        assert_eq!(d.bound, relative_bound(d.sigma_steps));
        assert!(d.grid_first_harmonic.is_none());
        let out = 0.25 - (-0.5 * 4.0 * PI * PI * 0.35f64.powi(2)).exp() / PI;
        let d = rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(out, step)))
            .expect("a quarter step off");
        assert!((d.bound - 0.0359).abs() < 2e-3, "{d:?}");
        assert!(d.grid_first_harmonic.is_some_and(|a| a < 0.05), "{d:?}");
        // Below MIN_SIGMA_STEPS_ON_GRID the whole bound stays wherever the mean falls.
        let step = sigma / 0.2;
        let d = rounding_discrepancy(&lp, tau0, step, n2, Some(&grid_at(0.25, step)))
            .expect("deep in the dead band");
        assert_eq!(d.bound, MAX_DISCREPANCY);
    }
}
