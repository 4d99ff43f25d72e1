//! Candidate effects of the diagnosis (docs/theory.md section 3) and their AVAR columns: for a fixed
//! shape parameter each effect's AVAR is linear in its amplitude squared (docs/theory.md section 5),
//! so a candidate is a column generator `shape -> column` plus the parameter names of
//! docs/records.md's `diagnosis` record.

use crate::model::lowpass::{LowPass, SecondOrderForm};
use crate::model::terms;
use crate::sim::band_noise::band_noise_avar;
use serde::{Deserialize, Serialize};

/// The kinds of effect docs/records.md names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EffectKind {
    GaussMarkov,
    Sinusoid,
    OutputFilter,
    Warmup,
    BiasJumps,
    /// A bias following the unit's temperature (only when the input carries one).
    Temperature,
    /// Low-pass filters beyond first order (docs/gap.md, "Low-pass filters beyond first
    /// order"): cascaded moving averages (FIR decimation, the Bartlett window), a second-order
    /// low-pass, a zero-phase (forward-backward) first-order filter.
    MovingAverage,
    SecondOrderFilter,
    ZeroPhaseFilter,
    /// A linear-phase FIR low-pass, the Hamming-windowed sinc (docs/gap.md, "A linear-phase
    /// FIR low-pass (session 46)").
    FirFilter,
    /// Narrow-band random noise: white noise through a resonator, a second-order Gauss-Markov
    /// rate with the damped-cosine autocovariance (docs/gap.md, "Narrow-band noise";
    /// [`crate::sim::band_noise`]).
    BandNoise,
    /// An n-th order digital Butterworth low-pass ([`LowPass::Butterworth`]; docs/gap.md,
    /// "An n-th order Butterworth (session 54)").
    ButterworthFilter,
}

impl EffectKind {
    pub const ALL: [EffectKind; 12] = [
        EffectKind::GaussMarkov,
        EffectKind::Sinusoid,
        EffectKind::OutputFilter,
        EffectKind::Warmup,
        EffectKind::BiasJumps,
        EffectKind::Temperature,
        EffectKind::MovingAverage,
        EffectKind::SecondOrderFilter,
        EffectKind::ZeroPhaseFilter,
        EffectKind::FirFilter,
        EffectKind::BandNoise,
        EffectKind::ButterworthFilter,
    ];

    /// Stationary effects are fitted on the curve as columns; warm-ups and jumps are found in
    /// time and enter the curve as fixed offsets.
    pub fn is_stationary(self) -> bool {
        matches!(
            self,
            EffectKind::GaussMarkov | EffectKind::Sinusoid | EffectKind::BandNoise
        ) || self.is_filter()
    }

    /// The unit's output filters: they reshape the N column instead of adding one.
    pub fn is_filter(self) -> bool {
        matches!(
            self,
            EffectKind::OutputFilter
                | EffectKind::MovingAverage
                | EffectKind::SecondOrderFilter
                | EffectKind::ZeroPhaseFilter
                | EffectKind::FirFilter
                | EffectKind::ButterworthFilter
        )
    }

    /// Whether filters of this kind and of `other` make a cascade ([`LowPass::Cascade`]): a
    /// moving average in front, a first or second order behind it. The diagnosis then names
    /// both, one effect each; any other two filters exclude each other.
    pub fn cascades_with(self, other: EffectKind) -> bool {
        let behind = |k: EffectKind| {
            matches!(
                k,
                EffectKind::OutputFilter
                    | EffectKind::SecondOrderFilter
                    | EffectKind::ButterworthFilter
            )
        };
        (self == EffectKind::MovingAverage && behind(other))
            || (other == EffectKind::MovingAverage && behind(self))
    }

    /// The `kind` string of the record.
    pub fn name(self) -> &'static str {
        match self {
            EffectKind::GaussMarkov => "gauss_markov",
            EffectKind::Sinusoid => "sinusoid",
            EffectKind::OutputFilter => "output_filter",
            EffectKind::Warmup => "warmup",
            EffectKind::BiasJumps => "bias_jumps",
            EffectKind::Temperature => "temperature",
            EffectKind::MovingAverage => "moving_average",
            EffectKind::SecondOrderFilter => "second_order_filter",
            EffectKind::ZeroPhaseFilter => "zero_phase_filter",
            EffectKind::FirFilter => "fir_filter",
            EffectKind::BandNoise => "band_noise",
            EffectKind::ButterworthFilter => "butterworth_filter",
        }
    }

    /// Parameters the effect adds to the five-term model (amplitude and shape; a filter only
    /// its shape, since it reshapes the N term: one, or two for the second order; the moving
    /// average's stage count is a discrete choice and not counted).
    pub fn n_params(self) -> usize {
        match self {
            EffectKind::OutputFilter
            | EffectKind::Temperature
            | EffectKind::MovingAverage
            | EffectKind::ZeroPhaseFilter => 1,
            // sigma, centre and width
            EffectKind::BandNoise => 3,
            _ => 2,
        }
    }
}

/// A fitted effect with docs/records.md's parameters (rate units u/s, times s, frequencies Hz).
///
/// As the record writes it: `{"kind": "gauss_markov", "params": {"sigma": .., "tau_c": ..}}`,
/// the parameters under their record names. The fields of each kind are declared in
/// alphabetical order of those names, the order every earlier version wrote them in (through a
/// sorted JSON map), so the records stay byte-identical. A number that is not finite (a
/// temperature interval not computed) is written `null` and read back as NaN.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "params", rename_all = "snake_case")]
pub enum EffectParams {
    GaussMarkov {
        #[serde(deserialize_with = "nullable_f64")]
        sigma: f64,
        #[serde(rename = "tau_c", deserialize_with = "nullable_f64")]
        tau_c_s: f64,
    },
    Sinusoid {
        #[serde(deserialize_with = "nullable_f64")]
        amplitude: f64,
        #[serde(rename = "frequency", deserialize_with = "nullable_f64")]
        frequency_hz: f64,
    },
    OutputFilter {
        #[serde(rename = "time_constant", deserialize_with = "nullable_f64")]
        time_constant_s: f64,
    },
    Warmup {
        #[serde(deserialize_with = "nullable_f64")]
        amplitude: f64,
        #[serde(rename = "time_constant", deserialize_with = "nullable_f64")]
        time_constant_s: f64,
    },
    BiasJumps {
        count: u64,
        #[serde(deserialize_with = "nullable_f64")]
        rms_size: f64,
    },
    /// u/s per degC, with its 95% interval; with a second order when the bias bends with the
    /// temperature (`coefficient` is then the slope at the second order's reference).
    Temperature {
        #[serde(deserialize_with = "nullable_f64")]
        coefficient: f64,
        #[serde(deserialize_with = "nullable_f64")]
        hi: f64,
        #[serde(deserialize_with = "nullable_f64")]
        lo: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        quadratic: Option<TemperatureQuadratic>,
        /// The unit's temperature lagging the one recorded (the coefficients are then the
        /// lagged temperature's).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        lag: Option<TemperatureLag>,
    },
    /// `decimation` (written only when above 1: the records of output-rate averages are as
    /// before) is [`LowPass::MovingAverage`]'s: `taps` then counts the internal samples.
    MovingAverage {
        #[serde(default = "one", skip_serializing_if = "is_one")]
        decimation: u32,
        stages: u32,
        taps: u32,
    },
    /// `bilinear` (written only when true: the records of the pole-mapped form are as before)
    /// and `zero` (written only for the sampled form) are the form
    /// [`LowPass::SecondOrder`] describes.
    SecondOrderFilter {
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        bilinear: bool,
        #[serde(deserialize_with = "nullable_f64")]
        damping: f64,
        #[serde(rename = "natural_frequency", deserialize_with = "nullable_f64")]
        natural_frequency_hz: f64,
        // last: the record's keys are in sorted order
        #[serde(default, skip_serializing_if = "Option::is_none")]
        zero: Option<f64>,
    },
    ZeroPhaseFilter {
        #[serde(rename = "time_constant", deserialize_with = "nullable_f64")]
        time_constant_s: f64,
    },
    /// [`LowPass::Fir`]: the cut-off (Hz), the decimation (written only above 1) and the taps.
    FirFilter {
        #[serde(rename = "cutoff", deserialize_with = "nullable_f64")]
        cutoff_hz: f64,
        #[serde(default = "one", skip_serializing_if = "is_one")]
        decimation: u32,
        taps: u32,
    },
    /// [`LowPass::Butterworth`]: the cut-off (Hz, half power), the decimation (written only
    /// above 1) and the order.
    ButterworthFilter {
        #[serde(rename = "cutoff", deserialize_with = "nullable_f64")]
        cutoff_hz: f64,
        #[serde(default = "one", skip_serializing_if = "is_one")]
        decimation: u32,
        order: u32,
    },
    /// Narrow-band noise: centre (Hz), rms (u/s), full width at half power (Hz).
    BandNoise {
        #[serde(rename = "frequency", deserialize_with = "nullable_f64")]
        frequency_hz: f64,
        #[serde(deserialize_with = "nullable_f64")]
        sigma: f64,
        #[serde(rename = "width", deserialize_with = "nullable_f64")]
        width_hz: f64,
    },
}

fn one() -> u32 {
    1
}

fn is_one(v: &u32) -> bool {
    *v == 1
}

/// Reads a number the writer may have printed as `null` (serde_json writes a non-finite f64 so)
/// back as NaN, so a record holding one still parses.
/// The second order of a temperature dependence: `q (T - reference)^2` beside the slope.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TemperatureQuadratic {
    /// `q`, u/s per degC^2.
    #[serde(deserialize_with = "nullable_f64")]
    pub coefficient: f64,
    /// Its 95% interval.
    #[serde(deserialize_with = "nullable_f64")]
    pub hi: f64,
    #[serde(deserialize_with = "nullable_f64")]
    pub lo: f64,
    /// The reference temperature (degC): the run's mean block temperature.
    #[serde(deserialize_with = "nullable_f64")]
    pub reference_c: f64,
}

/// A first-order lag of the unit's temperature behind the recorded one (a die behind the
/// chamber air): `dT_unit/dt = (T_recorded - T_unit) / time_constant`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TemperatureLag {
    /// s.
    #[serde(deserialize_with = "nullable_f64")]
    pub time_constant: f64,
    /// Its 95% profile interval (s).
    #[serde(deserialize_with = "nullable_f64")]
    pub hi: f64,
    #[serde(deserialize_with = "nullable_f64")]
    pub lo: f64,
}

pub fn nullable_f64<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

impl EffectParams {
    pub fn kind(&self) -> EffectKind {
        match self {
            EffectParams::GaussMarkov { .. } => EffectKind::GaussMarkov,
            EffectParams::Sinusoid { .. } => EffectKind::Sinusoid,
            EffectParams::OutputFilter { .. } => EffectKind::OutputFilter,
            EffectParams::Warmup { .. } => EffectKind::Warmup,
            EffectParams::BiasJumps { .. } => EffectKind::BiasJumps,
            EffectParams::Temperature { .. } => EffectKind::Temperature,
            EffectParams::MovingAverage { .. } => EffectKind::MovingAverage,
            EffectParams::SecondOrderFilter { .. } => EffectKind::SecondOrderFilter,
            EffectParams::ZeroPhaseFilter { .. } => EffectKind::ZeroPhaseFilter,
            EffectParams::FirFilter { .. } => EffectKind::FirFilter,
            EffectParams::BandNoise { .. } => EffectKind::BandNoise,
            EffectParams::ButterworthFilter { .. } => EffectKind::ButterworthFilter,
        }
    }

    /// The unit's filter named by `effects`: their filters in cascade ([`LowPass::compose`]; a
    /// moving average and a first or second order named as two effects are one filter).
    pub fn unit_filter<'a>(effects: impl IntoIterator<Item = &'a EffectParams>) -> Option<LowPass> {
        effects
            .into_iter()
            .filter_map(|p| p.lowpass())
            .fold(None, |acc, lp| Some(LowPass::compose(acc, lp)))
    }

    /// The filter of a filter effect (None for the others).
    pub fn lowpass(&self) -> Option<LowPass> {
        match *self {
            EffectParams::OutputFilter { time_constant_s } => {
                Some(LowPass::FirstOrder { time_constant_s })
            }
            EffectParams::MovingAverage {
                taps,
                stages,
                decimation,
            } => Some(LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            }),
            EffectParams::SecondOrderFilter {
                natural_frequency_hz,
                damping,
                bilinear,
                zero,
            } => Some(LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                form: match (bilinear, zero) {
                    (true, _) => SecondOrderForm::Bilinear,
                    (false, Some(zero)) => SecondOrderForm::Sampled { zero },
                    (false, None) => SecondOrderForm::PoleMapped,
                },
            }),
            EffectParams::ZeroPhaseFilter { time_constant_s } => {
                Some(LowPass::ZeroPhase { time_constant_s })
            }
            EffectParams::FirFilter {
                cutoff_hz,
                decimation,
                taps,
            } => Some(LowPass::Fir {
                taps,
                cutoff_hz,
                decimation,
            }),
            EffectParams::ButterworthFilter {
                cutoff_hz,
                decimation,
                order,
            } => Some(LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            }),
            _ => None,
        }
    }

    /// The effect of a filter (of a cascade, its back's: the diagnosis names each part as an
    /// effect of its own).
    pub fn from_lowpass(lp: LowPass) -> Self {
        match lp {
            LowPass::Cascade { back, .. } => Self::from_lowpass(back.lowpass()),
            LowPass::FirstOrder { time_constant_s } => {
                EffectParams::OutputFilter { time_constant_s }
            }
            LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            } => EffectParams::MovingAverage {
                taps,
                stages,
                decimation,
            },
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                form,
            } => EffectParams::SecondOrderFilter {
                natural_frequency_hz,
                damping,
                bilinear: form == SecondOrderForm::Bilinear,
                zero: match form {
                    SecondOrderForm::Sampled { zero } => Some(zero),
                    _ => None,
                },
            },
            LowPass::ZeroPhase { time_constant_s } => {
                EffectParams::ZeroPhaseFilter { time_constant_s }
            }
            LowPass::Fir {
                taps,
                cutoff_hz,
                decimation,
            } => EffectParams::FirFilter {
                cutoff_hz,
                decimation,
                taps,
            },
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            } => EffectParams::ButterworthFilter {
                cutoff_hz,
                decimation,
                order,
            },
        }
    }

    /// The effect of a stationary kind with one shape (s, Hz) and amplitude (u/s) from a
    /// column fit; filters beyond first order take their canonical form of
    /// [`effect_column`].
    pub fn from_shape(kind: EffectKind, shape: f64, amplitude: f64) -> Self {
        match kind {
            EffectKind::GaussMarkov => EffectParams::GaussMarkov {
                sigma: amplitude,
                tau_c_s: shape,
            },
            EffectKind::Sinusoid => EffectParams::Sinusoid {
                amplitude,
                frequency_hz: shape,
            },
            EffectKind::Warmup => EffectParams::Warmup {
                amplitude,
                time_constant_s: shape,
            },
            EffectKind::BiasJumps => EffectParams::BiasJumps {
                count: 0,
                rms_size: 0.0,
            },
            EffectKind::Temperature => EffectParams::Temperature {
                coefficient: amplitude,
                lo: f64::NAN,
                hi: f64::NAN,
                quadratic: None,
                lag: None,
            },
            EffectKind::OutputFilter
            | EffectKind::MovingAverage
            | EffectKind::SecondOrderFilter
            | EffectKind::ZeroPhaseFilter
            | EffectKind::FirFilter
            | EffectKind::ButterworthFilter => {
                EffectParams::from_lowpass(canonical_lowpass(kind, shape))
            }
            EffectKind::BandNoise => EffectParams::BandNoise {
                frequency_hz: shape,
                sigma: amplitude,
                width_hz: shape * super::band_noise::CANONICAL_RELATIVE_WIDTH,
            },
        }
    }

    /// The same effect with its amplitude (u/s) set to `amplitude`, its shape parameters kept
    /// (filters, jumps and the temperature unchanged).
    pub fn with_amplitude(&self, amplitude: f64) -> Self {
        let mut p = *self;
        match &mut p {
            EffectParams::GaussMarkov { sigma: a, .. }
            | EffectParams::BandNoise { sigma: a, .. }
            | EffectParams::Sinusoid { amplitude: a, .. }
            | EffectParams::Warmup { amplitude: a, .. } => *a = amplitude,
            _ => {}
        }
        p
    }

    /// The `params` of the record: each parameter's record name and value, in the record's
    /// (alphabetical) order; counts as whole numbers, NaN where the record has `null`.
    pub fn record_params(&self) -> Vec<(&'static str, f64)> {
        match *self {
            EffectParams::GaussMarkov { sigma, tau_c_s } => {
                vec![("sigma", sigma), ("tau_c", tau_c_s)]
            }
            EffectParams::Sinusoid {
                amplitude,
                frequency_hz,
            } => vec![("amplitude", amplitude), ("frequency", frequency_hz)],
            EffectParams::OutputFilter { time_constant_s }
            | EffectParams::ZeroPhaseFilter { time_constant_s } => {
                vec![("time_constant", time_constant_s)]
            }
            EffectParams::Warmup {
                amplitude,
                time_constant_s,
            } => vec![("amplitude", amplitude), ("time_constant", time_constant_s)],
            EffectParams::BiasJumps { count, rms_size } => {
                vec![("count", count as f64), ("rms_size", rms_size)]
            }
            EffectParams::Temperature {
                coefficient,
                hi,
                lo,
                quadratic,
                lag,
            } => {
                let mut v = vec![("coefficient", coefficient), ("hi", hi), ("lo", lo)];
                if let Some(q) = quadratic {
                    v.extend([("quadratic", q.coefficient), ("reference_c", q.reference_c)]);
                }
                if let Some(l) = lag {
                    v.push(("lag", l.time_constant));
                }
                v
            }
            EffectParams::MovingAverage {
                stages,
                taps,
                decimation,
            } => {
                let mut v = vec![("stages", f64::from(stages)), ("taps", f64::from(taps))];
                if decimation > 1 {
                    v.insert(0, ("decimation", f64::from(decimation)));
                }
                v
            }
            EffectParams::SecondOrderFilter {
                damping,
                natural_frequency_hz,
                bilinear,
                zero,
            } => {
                let mut v = vec![
                    ("damping", damping),
                    ("natural_frequency", natural_frequency_hz),
                ];
                if bilinear {
                    v.insert(0, ("bilinear", 1.0));
                }
                if let Some(c) = zero {
                    v.push(("zero", c));
                }
                v
            }
            EffectParams::BandNoise {
                frequency_hz,
                sigma,
                width_hz,
            } => vec![
                ("frequency", frequency_hz),
                ("sigma", sigma),
                ("width", width_hz),
            ],
            EffectParams::FirFilter {
                cutoff_hz,
                decimation,
                taps,
            } => {
                let mut v = vec![("cutoff", cutoff_hz)];
                if decimation > 1 {
                    v.push(("decimation", f64::from(decimation)));
                }
                v.push(("taps", f64::from(taps)));
                v
            }
            EffectParams::ButterworthFilter {
                cutoff_hz,
                decimation,
                order,
            } => {
                let mut v = vec![("cutoff", cutoff_hz)];
                if decimation > 1 {
                    v.push(("decimation", f64::from(decimation)));
                }
                v.push(("order", f64::from(order)));
                v
            }
        }
    }

    /// The shape parameter (s for times, Hz for the sinusoid and the second order's natural
    /// frequency, taps for the moving average), NaN for jumps and temperature.
    pub fn shape(&self) -> f64 {
        match *self {
            EffectParams::MovingAverage { taps, .. } => taps as f64,
            EffectParams::SecondOrderFilter {
                natural_frequency_hz,
                ..
            } => natural_frequency_hz,
            EffectParams::ZeroPhaseFilter { time_constant_s } => time_constant_s,
            EffectParams::FirFilter { cutoff_hz, .. }
            | EffectParams::ButterworthFilter { cutoff_hz, .. } => cutoff_hz,
            EffectParams::BandNoise { frequency_hz, .. } => frequency_hz,
            EffectParams::GaussMarkov { tau_c_s, .. } => tau_c_s,
            EffectParams::Sinusoid { frequency_hz, .. } => frequency_hz,
            EffectParams::OutputFilter { time_constant_s } => time_constant_s,
            EffectParams::Warmup {
                time_constant_s, ..
            } => time_constant_s,
            EffectParams::BiasJumps { .. } | EffectParams::Temperature { .. } => f64::NAN,
        }
    }

    /// Its amplitude (u/s; NaN for the filter, the rms size for jumps, u/s per degC for the
    /// temperature coefficient).
    pub fn amplitude(&self) -> f64 {
        match *self {
            EffectParams::GaussMarkov { sigma, .. } | EffectParams::BandNoise { sigma, .. } => {
                sigma
            }
            EffectParams::Sinusoid { amplitude, .. } => amplitude,
            EffectParams::OutputFilter { .. }
            | EffectParams::MovingAverage { .. }
            | EffectParams::SecondOrderFilter { .. }
            | EffectParams::ZeroPhaseFilter { .. }
            | EffectParams::FirFilter { .. }
            | EffectParams::ButterworthFilter { .. } => f64::NAN,
            EffectParams::Warmup { amplitude, .. } => amplitude,
            EffectParams::BiasJumps { rms_size, .. } => rms_size,
            EffectParams::Temperature { coefficient, .. } => coefficient,
        }
    }
}

/// Where an effect's column sits in the design: AVAR of unit amplitude at one shape.
#[derive(Debug, Clone, Copy)]
pub struct Grid {
    pub lo: f64,
    pub hi: f64,
    pub per_decade: f64,
}

impl Grid {
    /// The point of the least `score` over the grid (`None` where it cannot be formed; the
    /// first on ties), then over 40 times finer steps within a grid step around it (960 per
    /// decade, up to `cap`): a log-grid search for a time constant (the settling profile of a
    /// temperature, the warm-up that best fits block means). `None` when no point scores.
    pub fn refined_min(&self, cap: f64, score: impl Fn(f64) -> Option<f64>) -> Option<f64> {
        let better = |a: Option<(f64, f64)>, b: Option<(f64, f64)>| match (a, b) {
            (Some(a), Some(b)) => Some(if b.0 < a.0 { b } else { a }),
            (a, b) => a.or(b),
        };
        let at = |t: f64| score(t).map(|s| (s, t));
        let coarse = self.points().into_iter().map(at).fold(None, better)?;
        let fine = (-20..=20)
            .map(|k| coarse.1 * 10f64.powf(k as f64 / 960.0))
            .filter(|t| *t <= cap)
            .map(at)
            .fold(Some(coarse), better)?;
        Some(fine.1)
    }

    pub fn points(&self) -> Vec<f64> {
        if !(self.lo > 0.0 && self.hi > self.lo) {
            return Vec::new();
        }
        let n = ((self.hi / self.lo).log10() * self.per_decade)
            .ceil()
            .max(1.0) as usize;
        (0..=n)
            .map(|i| self.lo * (self.hi / self.lo).powf(i as f64 / n as f64))
            .collect()
    }
}

/// A filter kind with one shape: the first order and zero phase at time constant `shape` (s),
/// a one-stage moving average of `shape` taps, a critically damped second order at natural
/// frequency `shape` (Hz). The full parameters are in [`EffectParams::lowpass`].
pub fn canonical_lowpass(kind: EffectKind, shape: f64) -> LowPass {
    match kind {
        EffectKind::MovingAverage => LowPass::MovingAverage {
            taps: shape.round().clamp(1.0, u32::MAX as f64) as u32,
            stages: 1,
            decimation: 1,
        },
        EffectKind::SecondOrderFilter => LowPass::SecondOrder {
            natural_frequency_hz: shape,
            damping: 1.0,
            form: SecondOrderForm::PoleMapped,
        },
        EffectKind::ZeroPhaseFilter => LowPass::ZeroPhase {
            time_constant_s: shape,
        },
        // (the cut-off of a 31-tap window)
        EffectKind::FirFilter => LowPass::Fir {
            taps: 31,
            cutoff_hz: shape,
            decimation: 1,
        },
        // (the cut-off of a fourth order)
        EffectKind::ButterworthFilter => LowPass::Butterworth {
            order: 4,
            cutoff_hz: shape,
            decimation: 1,
        },
        _ => LowPass::FirstOrder {
            time_constant_s: shape,
        },
    }
}

/// The column an effect of unit amplitude adds at each cluster size `ms` (AVAR, u^2/s^2 per
/// (u/s)^2), docs/theory.md section 3 via [`crate::model::terms`]. For a filter it is the
/// replacement of the N column: filtered white rate of unit N (filters beyond first order in
/// their canonical form, [`canonical_lowpass`]; [`LowPass::white_rate_avar`] takes any).
pub fn effect_column(
    kind: EffectKind,
    shape: f64,
    ms: &[u64],
    tau0_s: f64,
    n_inc: u64,
) -> Vec<f64> {
    ms.iter()
        .map(|&m| {
            let tau = m as f64 * tau0_s;
            match kind {
                EffectKind::GaussMarkov => terms::gauss_markov_avar(1.0, shape, tau),
                EffectKind::Sinusoid => terms::sinusoid_avar(1.0, shape, tau),
                EffectKind::OutputFilter => {
                    terms::filtered_white_rate_avar(1.0, shape, tau0_s, m).max(0.0)
                }
                EffectKind::MovingAverage
                | EffectKind::SecondOrderFilter
                | EffectKind::ZeroPhaseFilter
                | EffectKind::FirFilter
                | EffectKind::ButterworthFilter => {
                    canonical_lowpass(kind, shape).white_rate_avar(tau0_s, &[m])[0]
                }
                EffectKind::Warmup => terms::warmup_avar(1.0, shape, tau0_s, m, n_inc),
                // In its canonical width (the full parameters: [`params_column`]).
                EffectKind::BandNoise => band_noise_avar(
                    1.0,
                    shape,
                    shape * super::band_noise::CANONICAL_RELATIVE_WIDTH,
                    tau0_s,
                    m,
                ),
                // Bias jumps have the second-order law of a rate random walk (terms.rs): the
                // K column already holds them, so they add no column. The temperature's AVAR is
                // the recorded temperature's own (gap::temperature), a fixed offset.
                EffectKind::BiasJumps | EffectKind::Temperature => 0.0,
            }
        })
        .collect()
}

/// The column of the effect `p` with all its shape parameters at unit amplitude (AVAR per
/// (u/s)^2 at each of `ms`): [`effect_column`] at `p`'s shape, the band with its own width.
pub fn params_column(p: &EffectParams, ms: &[u64], tau0_s: f64, n_inc: u64) -> Vec<f64> {
    match *p {
        EffectParams::BandNoise {
            frequency_hz,
            width_hz,
            ..
        } => super::band_noise::column(frequency_hz, width_hz, ms, tau0_s),
        _ => effect_column(p.kind(), p.shape(), ms, tau0_s, n_inc),
    }
}
