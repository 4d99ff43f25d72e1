//! The simulator: turns a noise model ([`model_file::SimModel`], read from `config/models/`)
//! into a stream of per-step increments, effects and stand included, for captures and for
//! checking the estimators against closed forms.
//!
//! Layout: [`noise`] holds the five-term generators (docs/theory.md section 2), [`effects`] the
//! effects of docs/theory.md section 3, [`model_file`] the checked model, [`writer`] the text-column
//! output. Frame encoding is left to the frame layer, which can drive [`Simulator::next_step`].
//!
//! Per channel and step the signal is built in this order: rate-domain terms integrated over
//! the step (bias, stand, N, K, R, B, Gauss-Markov, sinusoids, narrow-band noise, warm-up, bias jumps, temperature
//! bias) -> the unit's output filter (first order, or one of [`lowpass`]) -> outliers (spikes on single rate samples) -> white phase Q
//! -> rounding of the rate sample (`rate_lsb`, no carry) -> quantization with the remainder
//! carried (integer counts when `lsb` is set). Each channel draws from its own Xoshiro256++ stream
//! (seeded with `seed`, then jumped 2^128 steps per channel index), so adding a channel does not
//! change the others.
//!
//! Determinism: per-step arithmetic is IEEE `+ - * /` and `round` only, so the same seed gives
//! the same numbers on every platform, except through (a) set-up constants computed with
//! `exp`/`sin`/`cos`/`powf` from std (filter and ARMA coefficients, rotation steps, the flicker
//! bank) and (b) rand_distr's normal and exponential samplers, whose rare tail and wedge paths
//! call `ln`/`exp`. Both can differ in the last bit between math libraries; quantized channels
//! (integer counts) hide such differences except with vanishing probability.

pub mod band_noise;
pub mod effects;
pub mod lowpass;
pub mod model_avar;
pub mod model_file;
pub mod model_write;
pub mod noise;
pub mod stand_rate;
pub mod writer;

use rand::RngExt;
use rand::SeedableRng;
use rand_distr::{Distribution, Exp1, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use effects::{BiasJumpsGen, OutputFilter, SinusoidGen, TemperatureState, WarmupGen};
pub use model_file::{ChannelModel, SimModel};
use noise::{FlickerState, IntegratedGaussMarkov, RateRandomWalk, WhitePhase};
pub use writer::{simulate_to_writer, OutputFormat};

pub mod capture;

/// The random generator of every channel stream.
pub type SimRng = Xoshiro256PlusPlus;

/// One step of every channel, borrowed from the simulator until the next call.
#[derive(Debug, Clone, Copy)]
pub struct Step<'a> {
    /// 1 for the first step (the increments over `(0, tau0]`).
    pub index: u64,
    /// Time at the end of the step, s.
    pub time_s: f64,
    /// The increment of each channel over the step in u (`count * lsb` when quantized).
    pub increments: &'a [f64],
    /// The whole-LSB count of each quantized channel, None for the others.
    pub counts: &'a [Option<i64>],
    /// The unit's temperature at the end of the step, degC, when the model has a profile.
    pub temperature_c: Option<f64>,
}

/// Streaming generator of a whole model, constant memory.
#[derive(Debug, Clone)]
pub struct Simulator {
    tau0_s: f64,
    channels: Vec<ChannelSim>,
    temperature: Option<TemperatureState>,
    index: u64,
    increments: Vec<f64>,
    counts: Vec<Option<i64>>,
    temperature_c: Option<f64>,
}

impl Simulator {
    /// A simulator of `model` from power-on, seeded with `seed`.
    pub fn new(model: &SimModel, seed: u64) -> Self {
        let mut rng = SimRng::seed_from_u64(seed);
        let channels = model
            .channels
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let ch = ChannelSim::new(c, model.stand_rate(i), model.tau0_s, rng.clone());
                rng.jump();
                ch
            })
            .collect::<Vec<_>>();
        let n = channels.len();
        Self {
            tau0_s: model.tau0_s,
            channels,
            temperature: model
                .temperature
                .as_ref()
                .map(|p| TemperatureState::new(p, model.tau0_s)),
            index: 0,
            increments: vec![0.0; n],
            counts: vec![None; n],
            temperature_c: None,
        }
    }

    /// Sampling step, s.
    pub fn tau0_s(&self) -> f64 {
        self.tau0_s
    }

    /// Advance one step and return every channel's output over it.
    pub fn next_step(&mut self) -> Step<'_> {
        let (temp, temp_integral) = match &mut self.temperature {
            Some(t) => {
                let (c, i) = t.step();
                (Some(c), i)
            }
            None => (None, 0.0),
        };
        let t_prev = self.index as f64 * self.tau0_s;
        self.index += 1;
        for ((ch, inc), count) in self
            .channels
            .iter_mut()
            .zip(self.increments.iter_mut())
            .zip(self.counts.iter_mut())
        {
            let (v, c) = ch.step(self.index, t_prev, temp_integral);
            *inc = v;
            *count = c;
        }
        self.temperature_c = temp;
        Step {
            index: self.index,
            time_s: self.index as f64 * self.tau0_s,
            increments: &self.increments,
            counts: &self.counts,
            temperature_c: self.temperature_c,
        }
    }

    /// Fill `out` with the next `out.len()` increments (u) of channel `ch` alone, advancing the
    /// whole simulator; a convenience for tests and benchmarks.
    pub fn fill_channel(&mut self, ch: usize, out: &mut [f64]) {
        for v in out.iter_mut() {
            *v = self.next_step().increments[ch];
        }
    }
}

/// One channel's generators and state.
#[derive(Debug, Clone)]
struct ChannelSim {
    rng: SimRng,
    tau0_s: f64,
    /// (bias + stand) * tau0, u per step.
    const_inc: f64,
    /// N sqrt(tau0), u per step.
    white_rate: f64,
    rrw: Option<RateRandomWalk>,
    /// R tau0^2 / 2: the ramp's increment over step k is this times (2k - 1).
    ramp_half: f64,
    flicker: Option<FlickerState>,
    gms: Vec<IntegratedGaussMarkov>,
    sins: Vec<SinusoidGen>,
    bands: Vec<band_noise::BandNoiseGen>,
    warmup: Option<WarmupGen>,
    jumps: Option<BiasJumpsGen>,
    temp_coeff: f64,
    /// u/s per degC^2 of `(T - reference)^2`.
    temp_quad: f64,
    filter: Option<OutputFilter>,
    /// A low-pass beyond first order, in the output filter's place (the model file allows one).
    lowpass: Option<lowpass::LowPassGen>,
    white_phase: Option<WhitePhase>,
    /// Outliers: (probability per step, size in u per step).
    outliers: Option<(f64, f64)>,
    /// Rate-sample rounding: (step of the increment in u, its inverse).
    rate_round: Option<(f64, f64)>,
    /// (lsb, 1/lsb, remainder in u)
    quant: Option<(f64, f64, f64)>,
}

#[inline]
fn normal(rng: &mut SimRng) -> f64 {
    StandardNormal.sample(rng)
}

impl ChannelSim {
    fn new(c: &ChannelModel, stand_rate: f64, tau0_s: f64, mut rng: SimRng) -> Self {
        let rrw = (c.k > 0.0).then(|| {
            let first = normal(&mut rng);
            RateRandomWalk::new(c.k, tau0_s, first)
        });
        let flicker = c
            .flicker
            .as_ref()
            .map(|bank| FlickerState::new(bank, tau0_s, || normal(&mut rng)));
        let gms = c
            .gauss_markov
            .iter()
            .filter(|g| g.sigma > 0.0)
            .map(|g| {
                let a = normal(&mut rng);
                let b = normal(&mut rng);
                IntegratedGaussMarkov::new(g.sigma, g.tau_c_s, tau0_s, a, b)
            })
            .collect();
        let sins = c
            .sinusoids
            .iter()
            .map(|s| SinusoidGen::new(s.amplitude, s.frequency_hz, s.phase_rad, tau0_s))
            .collect();
        // Drawn after every earlier generator's start, so that a model without bands draws
        // exactly what it drew before.
        let bands = c
            .band_noise
            .iter()
            .filter(|b| b.sigma > 0.0)
            .map(|b| {
                let x = normal(&mut rng);
                let y = normal(&mut rng);
                band_noise::BandNoiseGen::new(b, tau0_s, x, y)
            })
            .collect();
        let warmup = c
            .warmup
            .map(|w| WarmupGen::new(w.amplitude, w.time_constant_s, tau0_s));
        let jumps = c
            .bias_jumps
            .filter(|j| j.rms_size > 0.0)
            .map(|j| BiasJumpsGen::new(j.mean_interval_s, j.rms_size, &mut rng));
        let white_phase = (c.q > 0.0).then(|| {
            let first = normal(&mut rng);
            WhitePhase::new(c.q, first)
        });
        Self {
            tau0_s,
            const_inc: (c.bias + stand_rate) * tau0_s,
            white_rate: c.n * tau0_s.sqrt(),
            rrw,
            ramp_half: c.r * tau0_s * tau0_s / 2.0,
            flicker,
            gms,
            sins,
            bands,
            warmup,
            jumps,
            temp_coeff: c.temperature_coefficient,
            temp_quad: c.temperature_quadratic,
            filter: c
                .output_filter
                .map(|f| OutputFilter::new(f.time_constant_s, tau0_s)),
            lowpass: c
                .lowpass
                .as_ref()
                .and_then(|lp| lowpass::LowPassGen::new(lp, tau0_s)),
            white_phase,
            outliers: c
                .outliers
                .filter(|o| o.rate_per_s > 0.0)
                .map(|o| (o.rate_per_s * tau0_s, o.size * tau0_s)),
            rate_round: c.rate_lsb.map(|l| (l * tau0_s, 1.0 / (l * tau0_s))),
            quant: c.lsb.map(|l| (l, 1.0 / l, 0.0)),
            rng,
        }
    }

    /// The output over step `k` (1-based) starting at `t_prev_s`: (increment in u, count).
    #[inline]
    fn step(&mut self, k: u64, t_prev_s: f64, temp_integral: f64) -> (f64, Option<i64>) {
        // a local copy keeps the generator's state in registers across the draws
        let mut local = self.rng.clone();
        let rng = &mut local;
        let mut d = self.const_inc;
        let mut white = 0.0;
        if self.white_rate != 0.0 {
            white = self.white_rate * normal(rng);
            d += white;
        }
        if let Some(g) = &mut self.rrw {
            d += g.step(normal(rng));
        }
        if self.ramp_half != 0.0 {
            d += self.ramp_half * (2 * k - 1) as f64;
        }
        if let Some(f) = &mut self.flicker {
            d += f.step(|| normal(rng));
        }
        for g in &mut self.gms {
            d += g.step(normal(rng));
        }
        for s in &mut self.sins {
            d += s.step();
        }
        for b in &mut self.bands {
            let (w1, w2) = (normal(rng), normal(rng));
            d += b.step(w1, w2);
        }
        if let Some(w) = &mut self.warmup {
            d += w.step();
        }
        if let Some(j) = &mut self.jumps {
            d += j.step(t_prev_s, self.tau0_s, rng);
        }
        if self.temp_coeff != 0.0 {
            d += self.temp_coeff * temp_integral;
        }
        // The second order over the step: `q (T - ref)^2` integrated as the square of the
        // step's mean times the step. The temperature moves over minutes against a step of
        // milliseconds, and the left-out term, `q tau0 var_step(T)`, is below 1e-9 of it.
        if self.temp_quad != 0.0 {
            let mean = temp_integral / self.tau0_s;
            d += self.temp_quad * mean * mean * self.tau0_s;
        }
        // The filter (one per channel in a model file; a cascade is one generator) starts in the stationary state
        // of this input's level and the white rate (LowPassGen::start_stationary), from a side
        // stream of this channel's generator (a long jump away: the channels are plain jumps
        // apart), so the main stream draws what it drew before.
        if self.filter.as_ref().is_some_and(|f| !f.is_started())
            || self.lowpass.as_ref().is_some_and(|f| !f.is_started())
        {
            let mut side = self.rng.clone();
            side.long_jump();
            let mut draw = || normal(&mut side);
            let level = d - white;
            if let Some(f) = &mut self.filter {
                f.start_stationary(level, self.white_rate, &mut draw);
            }
            if let Some(f) = &mut self.lowpass {
                f.start_stationary(level, self.white_rate, &mut draw);
            }
        }
        if let Some(f) = &mut self.filter {
            d = f.step(d);
        }
        if let Some(f) = &mut self.lowpass {
            let dec = f.decimation();
            if dec == 1 {
                d = f.step(d);
            } else {
                // Run at the internal rate (LowPassGen::decimation): the slower parts are
                // constant over the step, the white rate is drawn for each internal sample with
                // about sqrt(D) times the step's standard deviation (LowPassGen::white_scale;
                // the first is this step's draw), and the last internal output is the step's.
                let level = d - white;
                let sd = f.white_scale();
                let mut y = f.step(level + sd * white);
                for _ in 1..dec {
                    let w = if self.white_rate != 0.0 {
                        self.white_rate * normal(rng)
                    } else {
                        0.0
                    };
                    y = f.step(level + sd * w);
                }
                d = y;
            }
        }
        if let Some((p, size)) = self.outliers {
            let u: f64 = rng.random();
            if u < p {
                let e: f64 = Exp1.sample(rng);
                let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
                d += sign * size * (1.0 + e);
            }
        }
        if let Some(q) = &mut self.white_phase {
            d += q.step(normal(rng));
        }
        if let Some((step, inv)) = self.rate_round {
            // round half away from zero, as the quantizer below
            let x = d * inv;
            d = (x + 0.5f64.copysign(x)).trunc() * step;
        }
        self.rng = local;
        match &mut self.quant {
            Some((lsb, inv, rem)) => {
                *rem += d;
                // round half away from zero by truncation (a native conversion, no libm call)
                let x = *rem * *inv;
                let count = (x + 0.5f64.copysign(x)) as i64;
                let v = count as f64 * *lsb;
                *rem -= v;
                (v, Some(count))
            }
            None => (d, None),
        }
    }
}
