//! The counter's sawtooth as part of the base model. A unit that counts its angle with carry
//! at a coarse LSB while its rate holds nearly still (a ring-laser gyro on a bench, with
//! Earth's rate on its axis) outputs `Quant(theta + x) - theta`, `x` the white angle noise
//! before the counter (its dither). That error is the sawtooth of [`super::limit_cycle`]: a
//! line at `f = |rate| / LSB` and all its harmonics, each damped by the dither and widened by
//! the angle's random walk and the rate's slow wander. A named sinusoid catches the first
//! harmonic only, as a pure line; the harmonics and the widths are left as a band, a resonant
//! filter or a gap with nothing named (docs/gap.md, "The counter's sawtooth in the base model
//! (session 23)").
//!
//! Here the whole sawtooth is one fixed AVAR part ([`Sawtooth::avar`]) of every model of the
//! curve, its shape set by the LSB, the line's frequency and the dither, found by a small scan
//! ([`GapProblem::set_sawtooth`](super::problem::GapProblem::set_sawtooth)); its amplitudes are
//! the counter's own (no free amplitude), so a curve without the line never takes it.
//!
//! The angle error's autocovariance at lag `t > 0` (the white part at lag 0, `x` and the
//! sawtooth's incoherent share, is white phase noise, the Q column's):
//!
//! `R(t) = sum_n A_n cos(2 pi n f t) exp(-gamma_n t - 2 pi^2 n^2 s^2 t^2)`,
//!
//! with `A_n = LSB^2 / (2 n^2 pi^2) exp(-4 pi^2 n^2 sigma^2 / LSB^2)` (the sawtooth
//! `LSB (1/2 - frac(u / LSB))` has harmonic amplitudes `LSB / (n pi)`; a Gaussian dither of
//! standard deviation `sigma` multiplies the `n`-th by its characteristic function
//! `exp(-2 pi^2 n^2 sigma^2 / LSB^2)` in each of the two samples), `gamma_n = 2 pi^2 n^2 N^2 /
//! LSB^2` (the phase diffusion of [`super::limit_cycle::line_half_width`]) and `s` the rate's
//! wander over the LSB (Hz; a Gaussian spread of the line's frequency over the run: the slow
//! rate's and the flicker's between the sample and the block, which move the angle within the
//! lags the line lives over). With the rate near zero or wandering over many LSB per second the
//! same `R` is the quantization error of a counter whose per-sample change is small against its
//! LSB, the quantization-limited case ([`super::quant_limit`]): since session 24 it lets such a
//! unit's curve be read whole (docs/gap.md, "The whole curve of a quantization-limited counter
//! (session 24)"). The
//! AVAR of a phase process of autocovariance `R` is
//! `(6 R(0) - 8 R(tau) + 2 R(2 tau)) / (2 tau^2)` (IEEE Std 1139 / NIST SP 1065 eq. 10's
//! second difference, taken in expectation).
//!
//! Behind a low-pass (a unit that filters its rate before it counts the angle) the random walk
//! that widens each harmonic is that of the *filtered* rate: its variance over a lag of `k`
//! samples is `N^2 S(k)`, `S(k) = tau0 (k rho_0 + 2 sum_{0<j<k} (k - j) rho_j)` with the
//! filter's autocorrelation `rho` ([`LowPass::autocorrelation`]), in place of `N^2 k tau0`:
//! `gamma_n t` becomes `2 pi^2 n^2 N^2 S(t / tau0) / LSB^2`. Over lags short against the
//! filter's memory the angle hardly moves, and the error stays correlated for many samples
//! though the unfiltered per-sample change is an LSB or more (docs/gap.md, "The counter behind
//! a filter (session 25)").

use crate::model::lowpass::{LowPass, SumVariance};

/// The counter's sawtooth at one line frequency and dither.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sawtooth {
    /// The counter's LSB (u).
    pub lsb: f64,
    /// The line's frequency `|rate| / LSB` (Hz), before aliasing (the AVAR is taken at
    /// multiples of `tau0`, where the alias gives the same values).
    pub frequency_hz: f64,
    /// The white angle noise before the counter, standard deviation (u).
    pub dither: f64,
    /// The white rate `N` (u/sqrt(s)) whose random walk of the angle widens each harmonic.
    pub n_arw: f64,
    /// The rate's wander over the run, standard deviation (u/s): the slow rate's and the flicker's
    /// between the sample and the block mean.
    pub rate_wander: f64,
    /// The unit's low-pass before the counter, through which the white rate walks the angle
    /// (None: no filter, the walk's variance `N^2 t`).
    pub filter: Option<LowPass>,
}

/// Shape parameters fitted (dither, frequency, wander; the width's `N` is the fit's); each
/// costs the fit's expectation a share, as a candidate's shape does
/// ([`super::problem::GlsFit::expected`]).
pub const SAWTOOTH_SHAPES: usize = 3;
/// The dither's grid, 0 to this many LSB (beyond, `A_1` is under `e^-8` of its undamped
/// value: no line is left), in this many steps; each round refines it within a step.
pub const SAWTOOTH_MAX_DITHER: f64 = 0.45;
pub const SAWTOOTH_DITHER_STEPS: u32 = 18;
/// The least drop of `r' S^-1 r` on the dither's grid that the rounds refine (a unit with no
/// line drops nothing there).
pub const SAWTOOTH_GRID_DROP: f64 = 1.0;
/// The least share of the base model's excess misfit (`r' S^-1 r` over its expectation) the
/// dither's grid must take for the rounds to refine it, and the least share the refined
/// sawtooth must take to be kept (with [`SAWTOOTH_MIN_DROP`]). On rlg units the sawtooth takes
/// 99.9% (`G` 7165 -> 1.5); on filtered MEMS units with values on a grid, where the five terms
/// miss the filter, 1-40% (session 23, docs/gap.md).
pub const SAWTOOTH_GRID_SHARE: f64 = 0.1;
pub const SAWTOOTH_MIN_SHARE: f64 = 0.75;
/// The largest gap `G` the base model may keep with the sawtooth in, with the covariance of the
/// five terms fitted beside it, for it to be kept: on rlg units 0.8-1.9 (with the plain fit's
/// covariance 17-51 on draws 37 and 39 of seed 221, which is why it is read after the
/// rebuild); a filtered unit's five terms, which the sawtooth cannot mend, stay in the
/// thousands (bartfog seed 221 draw 8, in its pass with the filter's covariance: 80% of a
/// misfit of 19 million taken, `G` about 2e5 left).
pub const SAWTOOTH_MAX_GAP: f64 = 10.0;
/// The rate's wander is searched up to this many times its spread over the scales a block mean
/// hides and beyond ([`GapProblem::set_sawtooth`](super::problem::GapProblem::set_sawtooth)).
pub const SAWTOOTH_WANDER_SPAN: f64 = 2.0;
/// The line's frequency is searched within this share of `|mean rate| / LSB`.
pub const SAWTOOTH_FREQ_SPAN: f64 = 5e-3;
/// Evaluations of each golden-section search.
pub const SAWTOOTH_GOLDEN_STEPS: usize = 14;
/// Rounds of the three searches at most, and the relative drop of `r' S^-1 r` under which a
/// round ends them.
pub const SAWTOOTH_ROUNDS: usize = 4;
pub const SAWTOOTH_ROUND_TOL: f64 = 1e-3;
/// The least drop of the base model's `r' S^-1 r` that keeps the sawtooth: the sinusoid's
/// `lr_crit` (7 per parameter, docs/gap.md "Calibration") for its two shape parameters.
pub const SAWTOOTH_MIN_DROP: f64 = 14.0;

/// Most harmonics summed: beyond, an undithered sawtooth's harmonics hold under 1% of its
/// power and each is 64^2 times as wide as the first.
pub const MAX_HARMONICS: u32 = 64;
/// Harmonics whose power is under this share of the undamped first one's are left out.
const NEGLIGIBLE: f64 = 1e-9;

impl Sawtooth {
    /// The power `A_n` (u^2) of harmonic `n` after the dither.
    fn power(&self, n: u32) -> f64 {
        let nf = n as f64;
        let pi2 = std::f64::consts::PI * std::f64::consts::PI;
        let r = self.dither / self.lsb;
        self.lsb * self.lsb / (2.0 * nf * nf * pi2) * (-4.0 * pi2 * nf * nf * r * r).exp()
    }

    /// The harmonics that carry power: `1..=n_max`.
    fn n_max(&self) -> u32 {
        let first = self.lsb * self.lsb / (2.0 * std::f64::consts::PI.powi(2));
        (1..=MAX_HARMONICS)
            .take_while(|&n| self.power(n) > NEGLIGIBLE * first)
            .last()
            .unwrap_or(0)
    }

    /// The coherent part of the angle error's variance, `R(0+)` (u^2).
    pub fn coherent_variance(&self) -> f64 {
        (1..=self.n_max()).map(|n| self.power(n)).sum()
    }

    /// The angle error's autocovariance at lag `t_s > 0` (u^2), the module's `R(t)`, for a
    /// unit without a filter (the white rate's walk `N^2 t_s`).
    pub fn autocovariance(&self, t_s: f64) -> f64 {
        self.autocovariance_walked(t_s, t_s)
    }

    /// `R(t_s)` with the white rate's walk of the angle over the lag `N^2 walk_s` (u^2; `walk_s`
    /// in s: `t_s` without a filter, `S(t_s / tau0)` behind one).
    fn autocovariance_walked(&self, t_s: f64, walk_s: f64) -> f64 {
        let pi = std::f64::consts::PI;
        let diff = 2.0 * pi * pi * (self.n_arw / self.lsb).powi(2);
        let spread = 2.0 * pi * pi * (self.rate_wander / self.lsb).powi(2);
        (1..=self.n_max())
            .map(|n| {
                let nf = n as f64;
                let damp = (-(diff * nf * nf * walk_s) - spread * nf * nf * t_s * t_s).exp();
                self.power(n) * (2.0 * pi * nf * self.frequency_hz * t_s).cos() * damp
            })
            .sum()
    }

    /// The sawtooth's AVAR (u^2/s^2) at cluster sizes `ms` of `tau0_s`.
    pub fn avar(&self, tau0_s: f64, ms: &[u64]) -> Vec<f64> {
        let r0 = self.coherent_variance();
        let walk = Walk::new(self.filter, tau0_s);
        ms.iter()
            .map(|&m| {
                let tau = m as f64 * tau0_s;
                let v = 6.0 * r0 - 8.0 * self.autocovariance_walked(tau, walk.at(m))
                    + 2.0 * self.autocovariance_walked(2.0 * tau, walk.at(2 * m));
                (v / (2.0 * tau * tau)).max(0.0)
            })
            .collect()
    }
}

/// The variance (per unit `N^2`, in s) of the angle's change over `k` samples from white rate
/// through a unit's low-pass: `S(k) = tau0 (k rho_0 + 2 sum_{0<j<k} (k - j) rho_j)`, the
/// variance of a sum of `k` filtered increments ([`SumVariance`] of the filter's
/// autocorrelation, [`LowPass::white_rate_avar`]'s `S`); `k tau0` without a filter.
struct Walk {
    tau0_s: f64,
    filtered: Option<SumVariance>,
}

impl Walk {
    fn new(filter: Option<LowPass>, tau0_s: f64) -> Self {
        let filtered = filter
            .map(|lp| lp.autocorrelation(tau0_s))
            .filter(|rho| !rho.is_empty())
            .map(|rho| SumVariance::new(&rho, tau0_s));
        Walk { tau0_s, filtered }
    }

    /// `S(k)` (s).
    fn at(&self, k: u64) -> f64 {
        match &self.filtered {
            Some(s) => s.at(k),
            None => k as f64 * self.tau0_s,
        }
    }
}

/// The least of `eval` over `[lo, hi]` by golden-section search (`steps` evaluations after
/// the two first; a unimodal function's minimum to within `0.618^steps` of the span; Kiefer
/// 1953, Press et al., "Numerical Recipes", 3rd ed., section 10.2), with the argument's
/// payload. `ctx` is handed to each evaluation.
pub fn golden_min<C, T>(
    ctx: &mut C,
    lo: f64,
    hi: f64,
    steps: usize,
    mut eval: impl FnMut(&mut C, f64) -> (f64, T),
) -> (f64, T) {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (lo, hi);
    let mut x1 = b - g * (b - a);
    let mut x2 = a + g * (b - a);
    let mut f1 = eval(ctx, x1);
    let mut f2 = eval(ctx, x2);
    for _ in 0..steps {
        if f1.0 <= f2.0 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = eval(ctx, x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = eval(ctx, x2);
        }
    }
    if f1.0 <= f2.0 {
        f1
    } else {
        f2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_golden_search_finds_a_parabolas_vertex() {
        let (v, x) = golden_min(&mut (), -1.0, 3.0, 30, |_, x| {
            ((x - 1.3) * (x - 1.3) + 2.0, x)
        });
        assert!((x - 1.3).abs() < 1e-5, "{x}");
        assert!((v - 2.0).abs() < 1e-9);
    }

    /// With no dither, walk or wander the sawtooth's variance is all coherent: `LSB^2 / 12`
    /// (the uniform error), less the harmonics beyond the sum's end (`sum_{n > 64} 1 / n^2`
    /// of `LSB^2 / (2 pi^2)`, 0.94% of the whole).
    #[test]
    fn an_undithered_sawtooth_holds_the_uniform_errors_variance() {
        let s = Sawtooth {
            lsb: 2.0,
            frequency_hz: 3.0,
            dither: 0.0,
            n_arw: 0.0,
            rate_wander: 0.0,
            filter: None,
        };
        // sum_{n >= 1} 1 / n^2 = pi^2 / 6
        let pi2 = std::f64::consts::PI.powi(2);
        let head: f64 = (1..=MAX_HARMONICS).map(|n| 1.0 / (n as f64).powi(2)).sum();
        let tail = (pi2 / 6.0 - head) * 4.0 / (2.0 * pi2);
        assert!((s.coherent_variance() + tail - 4.0 / 12.0).abs() < 1e-12);
        assert!(tail > 0.009 * 4.0 / 12.0 && tail < 0.01 * 4.0 / 12.0);
        // a whole period later the error repeats
        assert!((s.autocovariance(1.0 / 3.0) - s.coherent_variance()).abs() < 1e-9);
    }

    /// At a cluster time of whole periods the line cancels out of the second difference of an
    /// undamped sawtooth; at half a period the first harmonic's AVAR is
    /// `(6 + 8 + 2) A_1 / (2 tau^2)` = `8 A_1 / tau^2`.
    #[test]
    fn the_avar_of_one_harmonic_is_the_second_difference_of_a_cosine() {
        let lsb = 1.0;
        // a dither that leaves the first harmonic alone in practice (A_2 / A_1 = e^-30 / 4)
        let s = Sawtooth {
            lsb,
            frequency_hz: 5.0,
            dither: (30.0f64 / (12.0 * std::f64::consts::PI.powi(2))).sqrt(),
            n_arw: 0.0,
            rate_wander: 0.0,
            filter: None,
        };
        let a1 = s.power(1);
        let tau0 = 0.01;
        let v = s.avar(tau0, &[10, 20]);
        assert!(v[1] < 1e-12 * a1);
        let want = 8.0 * a1 / (0.1f64 * 0.1);
        assert!((v[0] - want).abs() < 1e-6 * want, "{} {}", v[0], want);
    }
    /// A counter behind a first-order filter, simulated: white rate (unit `N`, `tau0` 1 s)
    /// through `y_k = a y_{k-1} + (1 - a) w_k` with `T` = 8 samples, its sum counted with
    /// carry at 1.1 unfiltered per-sample noise (the filtered angle moves 0.23 LSB a
    /// sample). The error's autocovariance at lags 1-32 is the sawtooth's `R` with the
    /// filtered walk within 4 standard errors; with the unfiltered walk `N^2 k tau0` it is
    /// far off (lag 1: the error correlated at a fifth of its variance, the plain walk's
    /// model at 1e-7 of it).
    #[test]
    fn behind_a_filter_the_walk_is_the_filtered_rates() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(25);
        let (tau0, t_f, lsb): (f64, f64, f64) = (1.0, 8.0, 1.1);
        let a = (-tau0 / t_f).exp();
        let n = 400_000;
        let (mut y, mut theta) = (0.0f64, 0.0f64);
        let e: Vec<f64> = (0..n)
            .map(|_| {
                let (u1, u2) = (rng.random::<f64>().max(1e-300), rng.random::<f64>());
                let w = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                y = a * y + (1.0 - a) * w;
                theta += y * tau0;
                (theta / lsb).round() * lsb - theta
            })
            .collect();
        let st = Sawtooth {
            lsb,
            frequency_hz: 0.0,
            dither: 0.0,
            n_arw: 1.0,
            rate_wander: 0.0,
            filter: Some(LowPass::FirstOrder {
                time_constant_s: t_f,
            }),
        };
        let walk = Walk::new(st.filter, tau0);
        let c0 = lsb * lsb / 12.0;
        for k in [1u64, 2, 4, 8, 16, 32] {
            let ku = k as usize;
            let c: f64 = (0..n - ku).map(|i| e[i] * e[i + ku]).sum::<f64>() / (n - ku) as f64;
            let want = st.autocovariance_walked(k as f64 * tau0, walk.at(k));
            // The error decorrelates over some 40 samples here: ~n / 80 independent.
            let se = c0 / ((n / 80) as f64).sqrt();
            assert!((c - want).abs() < 4.0 * se, "lag {k}: {c} vs {want}");
            if k == 1 {
                let plain = st.autocovariance(k as f64 * tau0);
                assert!(c > 0.2 * c0 && plain < 1e-6 * c0, "{c} {plain}");
            }
        }
    }
}
