//! Effects the five-term model leaves out (docs/theory.md section 3), as streaming generators of the
//! increment (u) over one step: sinusoid, warm-up, bias jumps, the unit's output filter and the
//! temperature profile with its temperature-driven bias. Gauss-Markov noise is
//! [`super::noise::IntegratedGaussMarkov`].
//!
//! No per-sample trigonometry or exponentials: sinusoids advance by a rotation recurrence
//! (renormalised every [`RENORM_EVERY`] steps) and exponentials by a constant factor, both set
//! up once with `sin`/`cos`/`exp` from std (the only platform-dependent math, and only at set-up).

use std::f64::consts::PI;

use rand_distr::{Distribution, Exp1, StandardNormal};

use super::SimRng;

/// Steps between renormalisations of a rotation's `(cos, sin)` pair. Each step's rounding moves
/// the radius by ~1e-16; one Newton step every 256 keeps it at 1 to ~1e-14.
pub const RENORM_EVERY: u32 = 256;
/// An exponential below this is set to zero, so that it never runs into subnormal numbers
/// (slow on most CPUs).
const EXP_FLOOR: f64 = 1e-250;

/// `(cos theta_k, sin theta_k)` with `theta_k = omega k tau0 + phase`, advanced by rotation.
#[derive(Debug, Clone)]
pub struct Rotation {
    cos: f64,
    sin: f64,
    /// `1 - cos(delta)` and `sin(delta)`, `delta = omega tau0`.
    one_minus_cos_d: f64,
    sin_d: f64,
    since_renorm: u32,
}

impl Rotation {
    pub fn new(omega_rad_s: f64, tau0_s: f64, phase_rad: f64) -> Self {
        let delta = omega_rad_s * tau0_s;
        let half = (delta / 2.0).sin();
        Self {
            cos: phase_rad.cos(),
            sin: phase_rad.sin(),
            one_minus_cos_d: 2.0 * half * half,
            sin_d: delta.sin(),
            since_renorm: 0,
        }
    }

    /// `cos(theta_{k-1}) - cos(theta_k)`, then advance to `theta_k`; written without the
    /// cancellation of the plain difference when `delta` is small.
    #[inline]
    pub fn step_cos_drop(&mut self) -> f64 {
        let drop = self.cos * self.one_minus_cos_d + self.sin * self.sin_d;
        let c = self.cos - drop;
        let s = self.sin - (self.sin * self.one_minus_cos_d - self.cos * self.sin_d);
        self.cos = c;
        self.sin = s;
        self.since_renorm += 1;
        if self.since_renorm >= RENORM_EVERY {
            self.since_renorm = 0;
            // one Newton step towards 1 / sqrt(c^2 + s^2)
            let f = (3.0 - (c * c + s * s)) / 2.0;
            self.cos *= f;
            self.sin *= f;
        }
        drop
    }

    /// `sin(theta_k)` at the current step.
    pub fn sin(&self) -> f64 {
        self.sin
    }
}

/// Sinusoidal rate `A sin(2 pi f t + phase)` (A in u/s, f in Hz, phase in rad); the increment
/// is its exact integral `(A / omega)(cos theta_{k-1} - cos theta_k)`.
/// AVAR: [`crate::model::terms::sinusoid_avar`].
#[derive(Debug, Clone)]
pub struct SinusoidGen {
    scale: f64,
    rot: Rotation,
}

impl SinusoidGen {
    pub fn new(amplitude: f64, frequency_hz: f64, phase_rad: f64, tau0_s: f64) -> Self {
        let omega = 2.0 * PI * frequency_hz;
        Self {
            scale: amplitude / omega,
            rot: Rotation::new(omega, tau0_s, phase_rad),
        }
    }

    #[inline]
    pub fn step(&mut self) -> f64 {
        self.scale * self.rot.step_cos_drop()
    }
}

/// A decaying exponential `e^{-t/T}` sampled at the steps, with the exact integral over a step.
#[derive(Debug, Clone)]
pub struct Decay {
    value: f64,
    factor: f64,
    /// `T (1 - e^{-tau0/T})`: the integral over one step per unit of the value at its start.
    integral_per_value: f64,
}

impl Decay {
    pub fn new(time_constant_s: f64, tau0_s: f64) -> Self {
        let x = tau0_s / time_constant_s;
        Self {
            value: 1.0,
            factor: (-x).exp(),
            integral_per_value: -time_constant_s * (-x).exp_m1(),
        }
    }

    /// The integral of `e^{-t/T}` over the step, then advance.
    #[inline]
    pub fn step(&mut self) -> f64 {
        let integral = self.value * self.integral_per_value;
        self.value *= self.factor;
        if self.value < EXP_FLOOR {
            self.value = 0.0;
        }
        integral
    }

    /// `e^{-t_k/T}` at the current step.
    pub fn value(&self) -> f64 {
        self.value
    }
}

/// Warm-up bias `A e^{-t/T}` (u/s) after power-on at `t = 0`. Deterministic; AVAR on a record:
/// [`crate::model::terms::warmup_avar`].
#[derive(Debug, Clone)]
pub struct WarmupGen {
    amplitude: f64,
    decay: Decay,
}

impl WarmupGen {
    pub fn new(amplitude: f64, time_constant_s: f64, tau0_s: f64) -> Self {
        Self {
            amplitude,
            decay: Decay::new(time_constant_s, tau0_s),
        }
    }

    #[inline]
    pub fn step(&mut self) -> f64 {
        self.amplitude * self.decay.step()
    }
}

/// Bias jumps: the rate steps by a Gaussian size (rms `rms_size` u/s) at Poisson times (mean
/// interval `mean_interval_s`). A jump inside a step splits that step's increment at the jump
/// time. AVAR: [`crate::model::terms::bias_jumps_avar`] (a rate random walk in second moments).
#[derive(Debug, Clone)]
pub struct BiasJumpsGen {
    mean_interval_s: f64,
    rms_size: f64,
    level: f64,
    next_jump_s: f64,
}

impl BiasJumpsGen {
    pub fn new(mean_interval_s: f64, rms_size: f64, rng: &mut SimRng) -> Self {
        let wait: f64 = Exp1.sample(rng);
        Self {
            mean_interval_s,
            rms_size,
            level: 0.0,
            next_jump_s: wait * mean_interval_s,
        }
    }

    /// The increment over `(t_prev, t_prev + tau0]`.
    #[inline]
    pub fn step(&mut self, t_prev_s: f64, tau0_s: f64, rng: &mut SimRng) -> f64 {
        let t_end = t_prev_s + tau0_s;
        if self.next_jump_s > t_end {
            return self.level * tau0_s;
        }
        let mut sum = 0.0;
        let mut cursor = t_prev_s;
        while self.next_jump_s <= t_end {
            let tj = self.next_jump_s.max(cursor);
            sum += self.level * (tj - cursor);
            cursor = tj;
            let size: f64 = StandardNormal.sample(rng);
            self.level += self.rms_size * size;
            let wait: f64 = Exp1.sample(rng);
            self.next_jump_s += wait * self.mean_interval_s;
        }
        sum + self.level * (t_end - cursor)
    }
}

/// The unit's own first-order low-pass on its output increments,
/// `y_k = a y_{k-1} + (1 - a) d_k` with `a = e^{-tau0/T}` (DC gain 1). Starts in its input's
/// stationary state ([`OutputFilter::start_stationary`]; at the first input when not called), so
/// a large constant (gravity) causes no transient.
#[derive(Debug, Clone)]
pub struct OutputFilter {
    a: f64,
    one_minus_a: f64,
    state: Option<f64>,
}

impl OutputFilter {
    pub fn new(time_constant_s: f64, tau0_s: f64) -> Self {
        let x = tau0_s / time_constant_s;
        Self {
            a: (-x).exp(),
            one_minus_a: -(-x).exp_m1(),
            state: None,
        }
    }

    /// Starts the filter in the stationary state of the input `level + white_sd * e_k` (u per
    /// step, `e_k` standard normal): the output's mean `level` plus its white part,
    /// `white_sd sqrt((1 - a) / (1 + a))` times one draw of `normal` (the variance of
    /// `sum_j (1 - a) a^j e_j`). No-op when the filter has started already. See
    /// [`super::lowpass::LowPassGen::start_stationary`] for why.
    pub fn start_stationary(&mut self, level: f64, white_sd: f64, mut normal: impl FnMut() -> f64) {
        if self.state.is_none() {
            let sd = white_sd * (self.one_minus_a / (1.0 + self.a)).sqrt();
            self.state = Some(if sd != 0.0 {
                level + sd * normal()
            } else {
                level
            });
        }
    }

    /// Whether the filter has had its first input.
    pub fn is_started(&self) -> bool {
        self.state.is_some()
    }

    #[inline]
    pub fn step(&mut self, d: f64) -> f64 {
        let y = match self.state {
            Some(prev) => self.a * prev + self.one_minus_a * d,
            None => d,
        };
        self.state = Some(y);
        y
    }
}

/// Parameters of the unit's temperature (degC):
/// `T(t) = final + (start - final) e^{-t/tau} + amplitude sin(2 pi t / period)`.
#[derive(Debug, Clone, PartialEq)]
pub struct TemperatureProfile {
    pub start_c: f64,
    pub final_c: f64,
    pub time_constant_s: f64,
    pub sine_amplitude_c: f64,
    pub sine_period_s: f64,
    /// Temperature at which the temperature-driven bias is zero.
    pub reference_c: f64,
}

/// The running temperature: its value at the end of each step and the integral of
/// `T(t) - reference` over the step (degC s), which channels scale by their coefficient (u/s
/// per degC) to get their temperature-driven increment.
#[derive(Debug, Clone)]
pub struct TemperatureState {
    final_c: f64,
    offset_c: f64,
    settle_c: f64,
    decay: Decay,
    sine_amplitude_c: f64,
    sine_scale: f64,
    rot: Option<Rotation>,
    tau0_s: f64,
}

impl TemperatureState {
    pub fn new(p: &TemperatureProfile, tau0_s: f64) -> Self {
        let rot = (p.sine_amplitude_c != 0.0).then(|| {
            let omega = 2.0 * PI / p.sine_period_s;
            Rotation::new(omega, tau0_s, 0.0)
        });
        Self {
            final_c: p.final_c,
            offset_c: p.final_c - p.reference_c,
            settle_c: p.start_c - p.final_c,
            decay: Decay::new(p.time_constant_s, tau0_s),
            sine_amplitude_c: p.sine_amplitude_c,
            sine_scale: p.sine_amplitude_c * p.sine_period_s / (2.0 * PI),
            rot,
            tau0_s,
        }
    }

    /// Advance one step: `(temperature at the step's end in degC, integral of T - reference
    /// over the step in degC s)`.
    #[inline]
    pub fn step(&mut self) -> (f64, f64) {
        let mut integral = self.offset_c * self.tau0_s + self.settle_c * self.decay.step();
        let mut temp = self.final_c + self.settle_c * self.decay.value();
        if let Some(rot) = &mut self.rot {
            integral += self.sine_scale * rot.step_cos_drop();
            temp += self.sine_amplitude_c * rot.sin();
        }
        (temp, integral)
    }
}

#[cfg(test)]
mod tests {
    use super::Rotation;

    /// The rotation recurrence against direct `cos` after a million steps (250 Hz, 1.3 Hz: 1.1
    /// hours, 5200 turns): the phase error stays below 1e-9 rad.
    #[test]
    fn rotation_stays_on_phase() {
        let (omega, tau0, phase) = (2.0 * std::f64::consts::PI * 1.3, 0.004, 0.7);
        let mut rot = Rotation::new(omega, tau0, phase);
        let n = 1_000_000u64;
        let mut sum_drop = 0.0;
        for _ in 0..n {
            sum_drop += rot.step_cos_drop();
        }
        // the drops telescope: cos(phase) - cos(theta_n)
        let theta = omega * tau0 * n as f64 + phase;
        assert!((sum_drop - (phase.cos() - theta.cos())).abs() < 1e-9);
        assert!(
            (rot.sin() - theta.sin()).abs() < 1e-9,
            "{} vs {}",
            rot.sin(),
            theta.sin()
        );
    }
}
