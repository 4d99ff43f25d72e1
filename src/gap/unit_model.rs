//! The fitted unit as a simulator model (`diagnose --model-out`): the five terms with the
//! effects in (`Diagnosis::final_coef`), the quantization step, the sampling step and every
//! accepted effect with its parameters, as a [`SimModel`] that `simulate --model` reads. This
//! closes the loop of the sim-to-real gap: the twin can be simulated and diagnosed again.
//!
//! What the record's parameters do not fix is chosen plainly: a sinusoid's phase is 0, bias
//! jumps become a Poisson process with the run's mean interval (`t_run / count`) and the
//! record's rms size, outliers a spike process with the run's rate and the simulator's size law
//! fitted to the record's rms size, rounded rate samples (`rate_lsb`) in place of a counter when
//! the curve says so (the rounding's white rate taken out of N), the counter's dither as the
//! white angle noise when the base model carries its sawtooth, the flicker band is the
//! simulator's default (six decades from `tau0`).
//!
//! A sinusoid is named as the curve sees it, at the output, after the unit's filter; the
//! simulator writes its sinusoids before the filter, so the model file carries the named
//! amplitude divided by the accepted filter's gain `|H(f)|` at the sinusoid's frequency
//! ([`input_amplitude`]; docs/gap.md, "Sinusoids behind a filter in the model file").

use crate::model::lowpass::LowPass;
use crate::model::terms;
use crate::model::units::IncrementUnit;
use crate::sim::effects::TemperatureProfile;
use crate::sim::model_file::{
    BandNoise, BiasJumps, ChannelModel, GaussMarkov, Outliers, OutputFilterSpec, SimModel,
    Sinusoid, Warmup, FLICKER_BAND_DECADES_DEFAULT,
};
use crate::sim::noise::FlickerBank;

use super::diagnose::Diagnosis;
use super::effects::EffectParams;
use super::quantization::QuantKind;

/// What is known of one channel besides its diagnosis.
#[derive(Debug, Clone)]
pub struct ChannelFacts {
    pub name: String,
    pub unit: String,
    /// Quantization step of the increments (u), when the values are whole multiples of one.
    pub lsb: Option<f64>,
    /// Mean rate over the run (u/s), written as the model's constant bias.
    pub bias: f64,
    /// Temperature coefficient (u/s per degC) when a temperature effect was accepted.
    pub temperature_coefficient: f64,
    /// Its second order (u/s per degC^2, about the model's reference temperature), when the
    /// accepted effect has one.
    pub temperature_quadratic: f64,
}

/// The channel model of a diagnosed channel.
pub fn fitted_channel(facts: &ChannelFacts, d: &Diagnosis, tau0_s: f64) -> ChannelModel {
    let [q, n, b, k, r] = d.final_coef;
    // Rate samples rounded on their own (gap::quantization): the fitted N holds the rounding's
    // white rate `N_q`, which the model file adds back from `rate_lsb`; there is no counter.
    let rate_q = d
        .quantization
        .filter(|f| f.kind == QuantKind::Rate && facts.lsb.is_some());
    let (lsb, rate_lsb, n) = match rate_q {
        Some(f) => (
            None,
            Some(f.rate_lsb),
            (n * n - f.n_q * f.n_q).max(0.0).sqrt(),
        ),
        None => (facts.lsb, None, n),
    };
    // The fitted Q holds the quantization's white phase (LSB / sqrt(12)); the model file adds
    // it back from `lsb`, so only the excess is written.
    // A counter whose sawtooth the base model carries: its white angle noise before the counter
    // is the sawtooth's dither, which sets how far the twin's counter cycles (the fitted Q holds
    // the dither and the counter's incoherent share less its coherent one).
    let q_model = match (lsb, d.sawtooth) {
        (Some(_), Some(st)) => st.dither,
        (Some(l), None) => (q * q - terms::quantization_q(l).powi(2)).max(0.0).sqrt(),
        (None, _) => q,
    };
    let band = (tau0_s, tau0_s * 10f64.powf(FLICKER_BAND_DECADES_DEFAULT));
    let mut ch = ChannelModel {
        name: facts.name.clone(),
        unit: facts.unit.clone(),
        lsb,
        bias: facts.bias,
        q: q_model,
        n,
        b,
        k,
        r,
        flicker_band_s: band,
        flicker: (b > 0.0).then(|| FlickerBank::design(b, band.0, band.1)),
        axis_enu: None,
        kind: IncrementUnit::parse(&facts.unit),
        temperature_coefficient: facts.temperature_coefficient,
        temperature_quadratic: facts.temperature_quadratic,
        gauss_markov: Vec::new(),
        sinusoids: Vec::new(),
        band_noise: Vec::new(),
        output_filter: None,
        lowpass: None,
        warmup: None,
        bias_jumps: None,
        rate_lsb,
        // The simulator's spikes are `size (1 + E)`, rms `sqrt(5) size`. A heavy-tailed white
        // noise's far samples are no spike process (their law is the noise's: the twin's white
        // rate is Gaussian at the fitted N, as the curve they were taken from).
        outliers: (d.outliers.count > 0 && !d.outliers.heavy_tail() && d.t_data_s > 0.0).then(
            || Outliers {
                rate_per_s: d.outliers.count as f64 / d.t_data_s,
                size: d.outliers.rms_size() / 5f64.sqrt(),
            },
        ),
    };
    // The unit's filter: the one the whole curve named when the curve was judged beyond its
    // stretch (super::filter_shape; the filter named there, if any, fitted only its tail).
    let filters: Vec<EffectParams> = match &d.filter_shape {
        Some(f) => f.named.iter().map(|e| e.params).collect(),
        None => d
            .effects
            .iter()
            .map(|e| e.params)
            .filter(|p| p.kind().is_filter())
            .collect(),
    };
    let filter = EffectParams::unit_filter(filters.iter());
    // A line attributed to the counter's limit cycle (super::limit_cycle) is the counter's,
    // which the twin's own counter (its `lsb` and `bias`) draws: drawn again as the unit's, the
    // twin's line was twice the run's (session 53).
    let others = d
        .effects
        .iter()
        .enumerate()
        .filter(|(i, _)| !d.limit_cycles.iter().any(|c| c.effect == *i))
        .map(|(_, e)| e.params)
        .filter(|p| !p.kind().is_filter());
    for p in filters.iter().copied().chain(others) {
        match p {
            EffectParams::GaussMarkov { sigma, tau_c_s } => {
                ch.gauss_markov.push(GaussMarkov { sigma, tau_c_s })
            }
            EffectParams::Sinusoid {
                amplitude,
                frequency_hz,
            } => ch.sinusoids.push(Sinusoid {
                amplitude: input_amplitude(amplitude, frequency_hz, filter.as_ref(), tau0_s),
                frequency_hz,
                phase_rad: 0.0,
            }),
            // Named at the output like a sinusoid: its rms before the filter is the named one
            // over the filter's gain at its centre (exact for a band narrow against the
            // filter's response).
            EffectParams::BandNoise {
                frequency_hz,
                sigma,
                width_hz,
            } => ch.band_noise.push(BandNoise {
                sigma: input_amplitude(sigma, frequency_hz, filter.as_ref(), tau0_s),
                frequency_hz,
                width_hz,
            }),
            // A first order alone is the model file's output filter; the filters named, in
            // cascade, are one (below).
            EffectParams::OutputFilter { time_constant_s } if filter == p.lowpass() => {
                ch.output_filter = Some(OutputFilterSpec { time_constant_s })
            }
            EffectParams::OutputFilter { .. }
            | EffectParams::MovingAverage { .. }
            | EffectParams::SecondOrderFilter { .. }
            | EffectParams::ZeroPhaseFilter { .. }
            | EffectParams::FirFilter { .. }
            | EffectParams::ButterworthFilter { .. } => ch.lowpass = filter,
            EffectParams::Warmup {
                amplitude,
                time_constant_s,
            } => {
                ch.warmup = Some(Warmup {
                    amplitude,
                    time_constant_s,
                })
            }
            EffectParams::BiasJumps { count, rms_size } if count > 0 => {
                ch.bias_jumps = Some(BiasJumps {
                    mean_interval_s: d.t_data_s / count as f64,
                    rms_size,
                })
            }
            EffectParams::BiasJumps { .. } => {}
            // The coefficient comes with the facts (it needs the recorded temperature's
            // profile, which the record does not hold).
            EffectParams::Temperature { .. } => {}
        }
    }
    ch
}

/// Least amplitude gain `|H(f)|` a named sinusoid is divided by: a line the filter all but
/// removes (near a moving average's zero) cannot be told from the curve, and its input amplitude
/// is then kept at most 100 times the one seen.
pub const MIN_SINUSOID_GAIN: f64 = 0.01;

/// The amplitude (u/s) of a sinusoid before the unit's output filter `filter`, from the
/// amplitude seen after it at `frequency_hz`: `amplitude / |H(f)|` with the filter's exact
/// discrete gain on the increments ([`LowPass::power_gain`]: the sinusoid's increments are a
/// sampled sinusoid at `f`, which a linear filter scales by `|H(e^{i 2 pi f tau0})|`), `|H|`
/// held at least [`MIN_SINUSOID_GAIN`]. Without a filter the amplitude is unchanged.
pub fn input_amplitude(
    amplitude: f64,
    frequency_hz: f64,
    filter: Option<&LowPass>,
    tau0_s: f64,
) -> f64 {
    match filter {
        Some(lp) => {
            let g = lp.power_gain(tau0_s, frequency_hz).max(0.0).sqrt();
            amplitude / g.max(MIN_SINUSOID_GAIN)
        }
        None => amplitude,
    }
}

/// The model file of a diagnosed unit: its channels and, when one was fitted, its temperature
/// profile. Without a profile no channel can carry a temperature coefficient (the model file
/// would be refused), so the coefficients are dropped; without a coefficient the profile is.
pub fn fitted_unit(
    tau0_s: f64,
    mut channels: Vec<ChannelModel>,
    temperature: Option<TemperatureProfile>,
) -> SimModel {
    let temperature = temperature.filter(|_| {
        channels
            .iter()
            .any(|c| c.temperature_coefficient != 0.0 || c.temperature_quadratic != 0.0)
    });
    if temperature.is_none() {
        channels.iter_mut().for_each(|c| {
            c.temperature_coefficient = 0.0;
            c.temperature_quadratic = 0.0;
        });
    }
    SimModel {
        tau0_s,
        stand: None,
        temperature,
        channels,
    }
}
