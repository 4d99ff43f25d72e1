//! Streaming generators of the five-term noise model (docs/theory.md section 2), each producing the
//! increment (u) over one step `tau0` from standard normal draws, in constant memory.
//!
//! Every rate-domain term is integrated exactly over the step (the increment is drawn from the
//! exact law of the integral), so the exact discrete closed forms in [`crate::model::terms`]
//! coincide with the continuous-time formulas at every cluster size. Per step and per term one
//! normal draw: the exactly integrated processes are written as ARMA recursions (a random walk
//! of rate integrated over the step gives ARIMA(0,1,1) increments, a Gauss-Markov rate gives
//! ARMA(1,1) increments). Per-sample arithmetic is `+ - * /` only; `exp`, `sqrt` and friends are
//! used at set-up.

use crate::model::terms;

/// White phase noise of sd `Q` (u): the increment is `e_k - e_{k-1}`, `AVAR = 3 Q^2 / tau^2`.
#[derive(Debug, Clone)]
pub struct WhitePhase {
    q_u: f64,
    prev: f64,
}

impl WhitePhase {
    /// `first` is the phase error at `t = 0`, a standard normal draw.
    pub fn new(q_u: f64, first: f64) -> Self {
        Self {
            q_u,
            prev: q_u * first,
        }
    }

    #[inline]
    pub fn step(&mut self, w: f64) -> f64 {
        let e = self.q_u * w;
        let d = e - self.prev;
        self.prev = e;
        d
    }
}

/// Rate random walk `K W(t)` integrated exactly over each step.
///
/// The second differences of the exactly sampled phase at m = 1 have variance `2/3 K^2 tau0^3`
/// and lag-one covariance `1/6 K^2 tau0^3`, nothing beyond (`K^2 tau0^3` times the cubic B-spline
/// 2/3, 1/6), so `d_k - d_{k-1} = s (e_k + theta e_{k-1})` with `theta = 2 - sqrt(3)` (root of
/// `theta / (1 + theta^2) = 1/4`) and `s^2 = 2/3 K^2 tau0^3 / (1 + theta^2) = K^2 tau0^3 (2 + sqrt 3) / 6`.
#[derive(Debug, Clone)]
pub struct RateRandomWalk {
    s: f64,
    s_theta: f64,
    prev_d: f64,
    prev_e: f64,
}

impl RateRandomWalk {
    /// `first` is a standard normal draw (the innovation before `t = 0`); the rate starts at 0
    /// on average.
    pub fn new(k: f64, tau0_s: f64, first: f64) -> Self {
        let sqrt3 = 3f64.sqrt();
        let s = k * tau0_s * tau0_s.sqrt() * ((2.0 + sqrt3) / 6.0).sqrt();
        Self {
            s,
            s_theta: s * (2.0 - sqrt3),
            prev_d: 0.0,
            prev_e: first,
        }
    }

    #[inline]
    pub fn step(&mut self, w: f64) -> f64 {
        let d = self.prev_d + self.s * w + self.s_theta * self.prev_e;
        self.prev_d = d;
        self.prev_e = w;
        d
    }
}

/// `e^{-x} - 1 + x`, accurate for small `x` (series) where the direct form cancels.
fn exp_rem2(x: f64) -> f64 {
    if x < 0.5 {
        let mut term = x * x / 2.0;
        let mut sum = 0.0;
        for n in 3..40 {
            sum += term;
            term *= -x / n as f64;
        }
        sum
    } else {
        x + (-x).exp_m1()
    }
}

/// First-order Gauss-Markov rate (stationary sd `sigma` u/s, correlation time `T` s),
/// integrated exactly over each step.
///
/// The increments are stationary Gaussian with `gamma(0) = 2 s^2 T^2 (x - 1 + phi)` and
/// `gamma(h) = s^2 T^2 (1 - phi)^2 phi^{h-1}` for `h >= 1` (`x = tau0 / T`, `phi = e^{-x}`), the
/// autocovariance of an ARMA(1,1): `v_k = d_k - phi d_{k-1}` is MA(1) with variance
/// `c0 = (1 + phi^2) gamma0 - 2 phi gamma1` and lag-one covariance `c1 = gamma1 - phi gamma0`, so
/// `v_k = s_e (e_k + theta e_{k-1})` with `theta / (1 + theta^2) = c1 / c0`, `|theta| < 1`.
/// AVAR: [`terms::gauss_markov_avar`] at every m.
#[derive(Debug, Clone)]
pub struct IntegratedGaussMarkov {
    phi: f64,
    s_e: f64,
    s_e_theta: f64,
    prev_d: f64,
    prev_e: f64,
}

impl IntegratedGaussMarkov {
    /// `first`, `second`: two standard normal draws for the stationary start.
    pub fn new(sigma: f64, tau_c_s: f64, tau0_s: f64, first: f64, second: f64) -> Self {
        let x = tau0_s / tau_c_s;
        let phi = (-x).exp();
        let one_minus_phi = -(-x).exp_m1();
        // in units of sigma^2 T^2
        let g0 = 2.0 * exp_rem2(x);
        let g1 = one_minus_phi * one_minus_phi;
        let c0 = (1.0 + phi * phi) * g0 - 2.0 * phi * g1;
        let c1 = g1 - phi * g0;
        let r = if c0 > 0.0 {
            (c1 / c0).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        let theta = 2.0 * r / (1.0 + (1.0 - 4.0 * r * r).max(0.0).sqrt());
        let scale = sigma * tau_c_s;
        let s_e = scale * (c0.max(0.0) / (1.0 + theta * theta)).sqrt();
        // stationary start: Cov(d_0, e_0) = s_e, Var(d_0) = gamma0
        let gamma0 = scale * scale * g0;
        let prev_d = s_e * first + (gamma0 - s_e * s_e).max(0.0).sqrt() * second;
        Self {
            phi,
            s_e,
            s_e_theta: s_e * theta,
            prev_d,
            prev_e: first,
        }
    }

    #[inline]
    pub fn step(&mut self, w: f64) -> f64 {
        let d = self.phi * self.prev_d + self.s_e * w + self.s_e_theta * self.prev_e;
        self.prev_d = d;
        self.prev_e = w;
        d
    }
}

/// One component of a flicker bank: a Gauss-Markov rate of sd `sigma` (u/s) and correlation
/// time `tau_c_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GmComponent {
    pub sigma: f64,
    pub tau_c_s: f64,
}

/// Flicker rate noise (B) as a bank of independent first-order Gauss-Markov rates with
/// log-spaced correlation times: equal variances per log-interval of `T` make the summed PSD
/// ~ 1/f between the extreme corners, hence a flat Allan curve
/// `(2 ln2 / pi) B^2` (docs/theory.md section 2). Its AVAR is exactly the sum of the components'
/// Gauss-Markov AVARs ([`FlickerBank::avar`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FlickerBank {
    pub components: Vec<GmComponent>,
}

/// Correlation times per decade of the bank. With [`FLICKER_MARGIN_DECADES`] = 0.5 this gives
/// 10 components for a 6-decade band and a max ADEV deviation of ~0.3% from flat (1 per decade:
/// ~1.2%; 1.5 per decade: ~0.2% with 12 components), measured from the closed form (the
/// `flicker_flatness` test pins it).
pub const FLICKER_COMPONENTS_PER_DECADE: f64 = 1.25;
/// Decades of correlation time added beyond each end of the band (the end components take
/// larger variances to make up for their missing neighbours).
pub const FLICKER_MARGIN_DECADES: f64 = 0.5;
/// The Gauss-Markov Allan deviation peaks at `tau = 1.893 T` (docs/theory.md section 3).
const GM_PEAK_TAU_OVER_T: f64 = 1.893;
/// Design grid: taus per decade over the band.
const FLICKER_GRID_PER_DECADE: f64 = 40.0;
/// Multiplicative (Richardson-Lucy) rounds fitting the variances to the flat target on the grid.
const FLICKER_FIT_ROUNDS: usize = 1500;

impl FlickerBank {
    /// A bank whose Allan curve is flat at `(2 ln2 / pi) B^2` for `tau` in
    /// `[tau_lo_s, tau_hi_s]`. Correlation times are log-spaced at
    /// [`FLICKER_COMPONENTS_PER_DECADE`] over `[tau_lo, tau_hi] / 1.893`, widened by
    /// [`FLICKER_MARGIN_DECADES`] each side. The variances start equal (equal variance per
    /// log-interval of `T` is what makes the summed PSD ~ 1/f) and are then fitted to the flat
    /// target on a log grid of taus by multiplicative Richardson-Lucy updates
    /// `v_i <- v_i sum_j K_ij (target / curve_j) / sum_j K_ij`, which keep them positive.
    pub fn design(b: f64, tau_lo_s: f64, tau_hi_s: f64) -> Self {
        let target = terms::flicker_avar(1.0);
        let t_lo = (tau_lo_s / GM_PEAK_TAU_OVER_T).log10() - FLICKER_MARGIN_DECADES;
        let t_hi = (tau_hi_s / GM_PEAK_TAU_OVER_T).log10() + FLICKER_MARGIN_DECADES;
        let n = ((t_hi - t_lo) * FLICKER_COMPONENTS_PER_DECADE)
            .ceil()
            .max(1.0) as usize
            + 1;
        let step = (t_hi - t_lo) / (n - 1) as f64;
        let tau_cs: Vec<f64> = (0..n).map(|i| 10f64.powf(t_lo + step * i as f64)).collect();
        let band_decades = (tau_hi_s / tau_lo_s).log10();
        let g = (band_decades * FLICKER_GRID_PER_DECADE).ceil().max(1.0) as usize + 1;
        let grid: Vec<f64> = (0..g)
            .map(|j| tau_lo_s * 10f64.powf(band_decades * j as f64 / (g - 1) as f64))
            .collect();
        // kernel[i][j]: AVAR of component i with unit variance at grid tau j
        let kernel: Vec<Vec<f64>> = tau_cs
            .iter()
            .map(|t| {
                grid.iter()
                    .map(|tau| terms::gauss_markov_avar(1.0, *t, *tau))
                    .collect()
            })
            .collect();
        let row_sums: Vec<f64> = kernel.iter().map(|r| r.iter().sum()).collect();
        let curve = |var: &[f64]| -> Vec<f64> {
            (0..g)
                .map(|j| var.iter().zip(&kernel).map(|(v, r)| v * r[j]).sum())
                .collect()
        };
        let mut var = vec![1.0; n];
        let mid = curve(&var)[g / 2];
        var.iter_mut().for_each(|v| *v = target / mid);
        for _ in 0..FLICKER_FIT_ROUNDS {
            let ratio: Vec<f64> = curve(&var).iter().map(|c| target / c).collect();
            for ((v, r), s) in var.iter_mut().zip(&kernel).zip(&row_sums) {
                let num: f64 = r.iter().zip(&ratio).map(|(k, q)| k * q).sum();
                *v *= num / s;
            }
        }
        let components = var
            .iter()
            .zip(&tau_cs)
            .map(|(v, t)| GmComponent {
                sigma: b * v.sqrt(),
                tau_c_s: *t,
            })
            .collect();
        Self { components }
    }

    /// The bank's AVAR at `tau_s` (u^2/s^2): the sum of its Gauss-Markov AVARs, exact at every
    /// cluster size for the simulated increments.
    pub fn avar(&self, tau_s: f64) -> f64 {
        self.components
            .iter()
            .map(|c| terms::gauss_markov_avar(c.sigma, c.tau_c_s, tau_s))
            .sum()
    }
}

/// The running state of a [`FlickerBank`]: one integrated Gauss-Markov recursion per component
/// ([`IntegratedGaussMarkov`]), stored as parallel arrays so the update loop vectorises.
#[derive(Debug, Clone)]
pub struct FlickerState {
    phi: Vec<f64>,
    s_e: Vec<f64>,
    s_e_theta: Vec<f64>,
    prev_d: Vec<f64>,
    prev_e: Vec<f64>,
    draws: Vec<f64>,
}

impl FlickerState {
    /// `draw` supplies standard normal draws for the stationary start (two per component).
    pub fn new(bank: &FlickerBank, tau0_s: f64, mut draw: impl FnMut() -> f64) -> Self {
        let parts: Vec<IntegratedGaussMarkov> = bank
            .components
            .iter()
            .map(|c| {
                let a = draw();
                let b = draw();
                IntegratedGaussMarkov::new(c.sigma, c.tau_c_s, tau0_s, a, b)
            })
            .collect();
        Self {
            phi: parts.iter().map(|p| p.phi).collect(),
            s_e: parts.iter().map(|p| p.s_e).collect(),
            s_e_theta: parts.iter().map(|p| p.s_e_theta).collect(),
            prev_d: parts.iter().map(|p| p.prev_d).collect(),
            prev_e: parts.iter().map(|p| p.prev_e).collect(),
            draws: vec![0.0; parts.len()],
        }
    }

    /// Number of normal draws one step needs.
    pub fn len(&self) -> usize {
        self.phi.len()
    }

    pub fn is_empty(&self) -> bool {
        self.phi.is_empty()
    }

    /// The summed increment over one step; `draw` gives one standard normal per component.
    #[inline]
    pub fn step(&mut self, mut draw: impl FnMut() -> f64) -> f64 {
        for w in self.draws.iter_mut() {
            *w = draw();
        }
        let n = self.phi.len();
        let (phi, s_e, s_t) = (&self.phi[..n], &self.s_e[..n], &self.s_e_theta[..n]);
        let (pd, pe, w) = (
            &mut self.prev_d[..n],
            &mut self.prev_e[..n],
            &self.draws[..n],
        );
        let mut sum = 0.0;
        for i in 0..n {
            let d = phi[i] * pd[i] + s_e[i] * w[i] + s_t[i] * pe[i];
            pd[i] = d;
            pe[i] = w[i];
            sum += d;
        }
        sum
    }
}
