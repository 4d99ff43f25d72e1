//! Noise-model files (TOML, `config/models/`): parsed into a checked [`SimModel`] before anything
//! is simulated. Every problem is reported with the file and the key (all of them, the first as
//! the error's key); unknown keys are rejected.
//!
//! ```toml
//! rate_hz = 250.0                 # or tau0_s = 0.004 (exactly one of them)
//! description = "free text"       # optional
//!
//! [stand]                         # optional: Earth rate and gravity on each sensor axis
//! latitude_deg = 56.8
//! gravity_m_s2 = 9.8166           # optional; default WGS-84 normal gravity at the latitude
//!
//! [temperature]                   # optional: the unit's temperature, also output per step
//! start_c = 20.0                  # T(t) = final + (start - final) e^{-t/time_constant}
//! final_c = 32.0                  #        + sine_amplitude sin(2 pi t / sine_period)
//! time_constant_s = 900.0
//! sine_amplitude_c = 0.5          # optional, default 0
//! sine_period_s = 3600.0          # required when sine_amplitude_c is not 0
//! reference_c = 32.0              # optional, default final_c: zero temperature-driven bias
//!
//! [[channel]]
//! name = "g4"                     # CSV column name
//! unit = "arcsec"                 # u; an axis needs an angle or velocity unit (model::units)
//! lsb = 0.004                     # optional: quantization step of the integrated signal (u)
//! axis = "down"                   # optional: up|down|north|south|east|west or [east, north, up]
//! bias = 0.0                      # u/s, default 0
//! Q = 0.0                         # u            white phase
//! N = 0.254                       # u/sqrt(s)    white rate
//! B = 0.225                       # u/s          flicker rate
//! K = 1.826e-2                    # u/s/sqrt(s)  rate random walk
//! R = 0.891e-4                    # u/s^2        rate ramp
//! flicker_band_s = [0.004, 1.0e4] # optional: tau range where B is flat; default [tau0, 1e6 tau0]
//! temperature_coefficient = 0.01  # optional: u/s per degC of T(t) - reference_c
//! temperature_quadratic = 1e-4    # optional: u/s per degC^2 of (T(t) - reference_c)^2
//! gauss_markov = [{ sigma = 0.1, tau_c = 2.0 }]                     # u/s, s (table or list)
//! sinusoid = [{ amplitude = 0.05, frequency = 1.3, phase = 0.0 }]   # u/s, Hz, rad (table or list)
//! band_noise = [{ sigma = 0.3, frequency = 20.7, width = 2.0 }]     # u/s, Hz (< Nyquist), Hz
//! output_filter = { time_constant = 0.01 }                          # s
//! moving_average = { taps = 16, stages = 2 }     # or, in place of output_filter (one filter):
//!   # ... and optionally decimation = 8 (run 8 times faster than the output, taps counted there,
//!   # read every 8th sample: taps = decimation is a CIC decimator)
//! second_order_filter = { natural_frequency = 20.0, damping = 0.7 }  # Hz, 1
//!   # ... and optionally bilinear = true (the digital biquad), or zero = 0.27 / decimation = 5
//!   # (run faster than the output and read every few samples; model::lowpass::SecondOrderForm)
//! zero_phase_filter = { time_constant = 0.01 }   # s, forward-backward first order
//! fir_filter = { taps = 47, cutoff = 131.0 }      # a linear-phase FIR: Hamming-windowed sinc, Hz
//!   # One filter per channel, or a moving_average with one output_filter or second_order_filter
//!   # behind it at the output rate (a CIC decimator and a consumer part's low-pass:
//!   # model::lowpass::LowPass::Cascade)
//! warmup = { amplitude = 0.5, time_constant = 600.0 }               # u/s, s
//! bias_jumps = { mean_interval = 1800.0, rms_size = 0.01 }          # s, u/s
//! rate_lsb = 0.01                 # optional: each rate sample rounded to this step (u/s), no carry
//! outliers = { rate = 1.0e-3, size = 5.0 }                          # 1/s, u/s
//! ```
//!
//! This file holds the checked types and the entry points; `parse` reads the top level, the
//! stand and the temperature, `channel` one `[[channel]]` table (its terms, effects and filter),
//! `keys` is the key walker both use. What the stand puts on an axis is `sim::stand_rate`; the
//! closed-form AVAR of a model is `sim::model_avar`.

use std::path::Path;

use crate::toml_check::{Collector, ConfigErrors};

pub use super::band_noise::BandNoise;
use super::effects::TemperatureProfile;
use super::noise::FlickerBank;
use crate::model::lowpass::LowPass;

mod channel;
mod keys;
mod parse;

pub use super::stand_rate::{normal_gravity_m_s2, EARTH_RATE_RAD_S};
use crate::model::units::IncrementUnit;
/// Arcseconds per radian.
pub use crate::model::units::ARCSEC_PER_RAD;
/// Default upper end of the flicker band in units of tau0 (six decades).
pub const FLICKER_BAND_DECADES_DEFAULT: f64 = 6.0;

/// A checked noise model: the sampling step, the stand, the temperature, the channels.
#[derive(Debug, Clone, PartialEq)]
pub struct SimModel {
    /// Sampling step in seconds.
    pub tau0_s: f64,
    pub stand: Option<Stand>,
    pub temperature: Option<TemperatureProfile>,
    pub channels: Vec<ChannelModel>,
}

/// The test stand: where it is, so Earth rate and gravity can be projected on each axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stand {
    pub latitude_deg: f64,
    /// Local gravity in m/s^2.
    pub gravity_m_s2: f64,
}

/// One channel's noise model.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelModel {
    pub name: String,
    pub unit: String,
    /// Quantization step of the integrated signal (u); counts are whole LSBs with the remainder
    /// carried.
    pub lsb: Option<f64>,
    /// Constant bias in u/s (the stand's projection is added on top).
    pub bias: f64,
    /// White phase, u.
    pub q: f64,
    /// White rate, u/sqrt(s).
    pub n: f64,
    /// Flicker rate, u/s.
    pub b: f64,
    /// Rate random walk, u/s/sqrt(s).
    pub k: f64,
    /// Rate ramp, u/s^2.
    pub r: f64,
    /// The tau range (s) where the flicker bank is flat.
    pub flicker_band_s: (f64, f64),
    /// The bank realising `b` (None when `b == 0`).
    pub flicker: Option<FlickerBank>,
    /// Sensor axis in the local level frame (east, north, up), unit length.
    pub axis_enu: Option<[f64; 3]>,
    /// What the unit measures (`None`: neither an angle nor a velocity; cannot take an `axis`).
    pub kind: Option<IncrementUnit>,
    /// u/s per degC.
    pub temperature_coefficient: f64,
    /// u/s per degC^2: the bias's second-order dependence, `q (T - reference_c)^2`.
    pub temperature_quadratic: f64,
    pub gauss_markov: Vec<GaussMarkov>,
    pub sinusoids: Vec<Sinusoid>,
    /// Narrow-band random noise terms ([`super::band_noise`]), added before the filter.
    pub band_noise: Vec<BandNoise>,
    pub output_filter: Option<OutputFilterSpec>,
    /// A low-pass beyond first order (moving average, second order, zero phase), in place of
    /// `output_filter` ([`crate::model::lowpass`]; docs/gap.md, "Low-pass filters beyond first
    /// order").
    pub lowpass: Option<LowPass>,
    pub warmup: Option<Warmup>,
    pub bias_jumps: Option<BiasJumps>,
    /// Each rate sample rounded to this step (u/s), no remainder carried (MEMS parts): a white
    /// rate noise of `rate_lsb^2 tau0 / 12` (docs/gap.md, "Rate-sample quantization").
    pub rate_lsb: Option<f64>,
    /// Isolated spikes on single rate samples.
    pub outliers: Option<Outliers>,
}

/// Isolated outliers: on each step, with probability `rate_per_s * tau0`, the rate sample gets
/// a spike of random sign and magnitude `size (1 + E)`, `E` exponential of mean 1 (at least
/// `size`, rms `sqrt(5) size`): u/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outliers {
    pub rate_per_s: f64,
    pub size: f64,
}

/// First-order Gauss-Markov rate noise: stationary sd `sigma` (u/s), correlation time `tau_c_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussMarkov {
    pub sigma: f64,
    pub tau_c_s: f64,
}

/// Sinusoidal rate `amplitude sin(2 pi frequency t + phase)`: u/s, Hz, rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoid {
    pub amplitude: f64,
    pub frequency_hz: f64,
    pub phase_rad: f64,
}

/// The unit's first-order low-pass of its own output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputFilterSpec {
    pub time_constant_s: f64,
}

/// Bias `amplitude e^{-t/time_constant}` after power-on: u/s, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Warmup {
    pub amplitude: f64,
    pub time_constant_s: f64,
}

/// Bias steps at Poisson times: mean interval (s), rms size (u/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasJumps {
    pub mean_interval_s: f64,
    pub rms_size: f64,
}

impl SimModel {
    /// Read and check a model file.
    pub fn load(path: &Path) -> anyhow::Result<SimModel> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Collector::unreadable(path, &e).into_errors(WHAT))?;
        Ok(Self::from_toml_str(&text, path)?)
    }

    /// Parse and check a model given as TOML text; `file` names it in errors, every problem
    /// once with its line and key (`crate::toml_check`).
    pub fn from_toml_str(text: &str, file: &Path) -> Result<SimModel, ConfigErrors> {
        let mut c = Collector::new(file, text);
        let Some(table) = c.parse(text) else {
            return Err(c.into_errors(WHAT));
        };
        let model = parse::parse_model(&table, &mut c);
        match (c.is_empty(), model) {
            (true, Some(m)) => Ok(m),
            _ => {
                if c.is_empty() {
                    c.bad("(model)", "invalid model");
                }
                Err(c.into_errors(WHAT))
            }
        }
    }
}

/// What a model file's errors are called.
const WHAT: &str = "model file";
