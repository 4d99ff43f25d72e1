//! An effect of a diagnosis (docs/records.md, `effects`: `{kind, params}`) as a person reads it:
//! its name, and each parameter named, with its unit, rates in the channel's datasheet unit
//! (deg/h for a gyro, micro-g for an accelerometer; model::units) beside the native u/s the record
//! holds. The terminal table (sink::table) and the report (sink::report) both word effects
//! through [`effect_parts`], so the two never disagree.
//!
//! The record's parameters (docs/records.md): rates (`sigma`, `amplitude`, `rms_size`) in u/s,
//! times (`tau_c`, `time_constant`) in s, `frequency` in Hz, `coefficient` in u/s per deg C, and
//! `count`. A kind this version does not know (a newer writer's, [`RecordedEffect::Unknown`]) is
//! shown by its record names and values.

use crate::gap::record::RecordedEffect;
use crate::model::units::{datasheet_factors, datasheet_units, native_units, IncrementUnit};

/// What a parameter measures, which decides its unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dim {
    /// u/s.
    Rate,
    /// u/s per deg C.
    RatePerC,
    /// u/s per deg C^2 (a temperature's second order).
    RatePerC2,
    /// deg C.
    Celsius,
    /// s.
    Time,
    /// Hz.
    Freq,
    /// A count.
    Count,
    /// A pure number (a damping ratio).
    Plain,
}

/// A parameter: its record key, its name for a person, and what it measures.
type ParamSpec = (&'static str, &'static str, Dim);

/// The kinds the diagnosis writes: a person's name for the kind, and its parameters.
fn known(kind: &str) -> Option<(&'static str, &'static [ParamSpec])> {
    Some(match kind {
        "gauss_markov" => (
            "correlated (Gauss-Markov) noise",
            &[
                ("sigma", "sigma", Dim::Rate),
                ("tau_c", "correlation time", Dim::Time),
            ],
        ),
        "sinusoid" => (
            "sinusoid",
            &[
                ("amplitude", "amplitude", Dim::Rate),
                ("frequency", "frequency", Dim::Freq),
            ],
        ),
        "band_noise" => (
            "narrow-band random noise (resonance)",
            &[
                ("sigma", "rms", Dim::Rate),
                ("frequency", "centre", Dim::Freq),
                ("width", "width (half power)", Dim::Freq),
            ],
        ),
        "output_filter" => (
            "output low-pass filter",
            &[("time_constant", "time constant", Dim::Time)],
        ),
        "moving_average" => (
            "output moving average (FIR)",
            &[
                ("taps", "taps", Dim::Count),
                ("stages", "stages", Dim::Count),
            ],
        ),
        "second_order_filter" => (
            "output second-order low-pass filter",
            &[
                ("natural_frequency", "natural frequency", Dim::Freq),
                ("damping", "damping", Dim::Plain),
            ],
        ),
        "zero_phase_filter" => (
            "zero-phase (forward-backward) low-pass filter",
            &[("time_constant", "time constant", Dim::Time)],
        ),
        "fir_filter" => (
            "output linear-phase FIR low-pass (windowed sinc)",
            &[
                ("cutoff", "cut-off", Dim::Freq),
                ("taps", "taps", Dim::Count),
            ],
        ),
        "butterworth_filter" => (
            "output Butterworth low-pass",
            &[
                ("order", "order", Dim::Count),
                ("cutoff", "cut-off (half power)", Dim::Freq),
            ],
        ),
        "warmup" => (
            "warm-up drift",
            &[
                ("amplitude", "amplitude", Dim::Rate),
                ("time_constant", "time constant", Dim::Time),
            ],
        ),
        "bias_jumps" => (
            "bias jumps",
            &[
                ("count", "count", Dim::Count),
                ("rms_size", "rms size", Dim::Rate),
            ],
        ),
        // The second order and the lag only when the record has them (session 51).
        "temperature" => (
            "temperature sensitivity",
            &[
                ("coefficient", "coefficient", Dim::RatePerC),
                ("quadratic", "second order", Dim::RatePerC2),
                ("reference_c", "about", Dim::Celsius),
                (
                    "lag",
                    "unit's temperature lagging the recorded one by",
                    Dim::Time,
                ),
            ],
        ),
        _ => return None,
    })
}

/// A person's name for an effect kind of the record (`warmup`: "warm-up drift"); an unknown
/// kind with its underscores as spaces.
pub fn kind_words(kind: &str) -> String {
    known(kind).map_or_else(|| kind.replace('_', " "), |(name, _)| name.to_string())
}

/// One parameter as shown: `name`, and its value with unit(s) (`0.541 deg/h (0.541 arcsec/s)`).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamText {
    pub name: String,
    pub value: String,
}

/// The effect's name and its parameters; `unit` is the channel's unit (`u` or empty when not
/// known: rates are then in `u/s` only), `number` formats a value.
pub fn effect_parts(
    effect: &RecordedEffect,
    unit: &str,
    number: &dyn Fn(f64) -> String,
) -> (String, Vec<ParamText>) {
    let kind = effect.kind_name();
    // The record's parameters by name, in its order; NaN stands for `null`.
    let params: Vec<(&str, f64)> = match effect {
        RecordedEffect::Known(p) => p.record_params(),
        RecordedEffect::Unknown(o) => o
            .params
            .iter()
            .map(|(k, v)| (k.as_str(), v.unwrap_or(f64::NAN)))
            .collect(),
    };
    let param = |key: &str| {
        params
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| *v)
            .filter(|v| v.is_finite())
    };
    // A value as the record shows it: `null` where it is not a number.
    let shown = |v: f64| {
        if v.is_finite() {
            number(v)
        } else {
            "null".to_string()
        }
    };
    let u = if unit.is_empty() { "u" } else { unit };
    let ds = datasheet_rate(u);
    let ru = &native_units(u)[2];
    // `lo`, `hi` (a kind with one rate, e.g. temperature): that rate's 95% interval.
    let bounds = (param("lo"), param("hi"));
    let rate = |v: f64, per: &str| -> String {
        let iv = |f: f64| match bounds {
            (Some(lo), Some(hi)) => format!(" [{}, {}]", number(lo * f), number(hi * f)),
            _ => String::new(),
        };
        match ds {
            Some((f, du)) => format!(
                "{}{} {du}{per} ({}{} {ru}{per})",
                number(v * f),
                iv(f),
                number(v),
                iv(1.0)
            ),
            None => format!("{}{} {ru}{per}", number(v), iv(1.0)),
        }
    };
    let Some((mut name, keys)) = known(kind).map(|(n, k)| (n.to_string(), k)) else {
        let kv = params
            .iter()
            .map(|(k, v)| ParamText {
                name: k.to_string(),
                value: shown(*v),
            })
            .collect();
        return (kind.replace('_', " "), kv);
    };
    // The second order's bilinear form (`bilinear: true`) is said in its name, not as a number.
    let bilinear = kind == "second_order_filter" && param("bilinear").is_some_and(|b| b != 0.0);
    if bilinear {
        name += " (bilinear biquad, zeros at Nyquist: scipy's butter, PX4's LowPassFilter2p)";
    }
    // The sampled form (`zero`): a filter run faster than the output and read every so many
    // samples, said in its name with its zero.
    let zero = param("zero").filter(|_| kind == "second_order_filter");
    if let Some(c) = zero {
        name += &format!(
            " (run faster than the output and read every few samples: zero at z = -{})",
            number(c)
        );
    }
    // The average, FIR or Butterworth run faster than the output (`decimation`): said in its
    // name, with the CIC decimator named when an average's taps are the decimation.
    let decimation = param("decimation").filter(|&d| {
        matches!(kind, "moving_average" | "fir_filter" | "butterworth_filter") && d > 1.0
    });
    if let Some(d) = decimation {
        name += &format!(
            " run at {d:.0} times the output rate and read every {} sample{}",
            crate::input::sampling_step::ordinal(d as usize),
            if kind == "butterworth_filter" {
                ""
            } else {
                ", taps counted there"
            }
        );
        if let (Some(t), Some(st)) = (param("taps"), param("stages")) {
            if t == d && st >= 2.0 {
                name += &format!(" (a sinc^{st:.0} CIC decimator)");
            }
        }
    }
    // A rate per deg C^2 without the interval of the kind's one rate.
    let rate_per_c2 = |v: f64| -> String {
        match ds {
            Some((f, du)) => format!(
                "{} {du} per deg C^2 ({} {ru} per deg C^2)",
                number(v * f),
                number(v)
            ),
            None => format!("{} {ru} per deg C^2", number(v)),
        }
    };
    let optional = |key: &str| kind == "temperature" && key != "coefficient";
    let mut out = Vec::new();
    for (key, pname, dim) in keys {
        if optional(key) && param(key).is_none() {
            continue;
        }
        let text = match (dim, param(key)) {
            (_, None) => "?".to_string(),
            (Dim::Count, Some(x)) if x >= 0.0 && x.fract() == 0.0 => format!("{x:.0}"),
            (Dim::Count, Some(x)) => number(x),
            (Dim::Plain, Some(x)) => number(x),
            (Dim::Rate, Some(x)) => rate(x, ""),
            (Dim::RatePerC, Some(x)) => rate(x, " per deg C"),
            (Dim::RatePerC2, Some(x)) => rate_per_c2(x),
            (Dim::Celsius, Some(x)) => format!("{} deg C", number(x)),
            (Dim::Time, Some(x)) => format!("{} s", number(x)),
            (Dim::Freq, Some(x)) if x > 0.0 => {
                format!("{} Hz (period {} s)", number(x), number(1.0 / x))
            }
            (Dim::Freq, Some(x)) => format!("{} Hz", number(x)),
        };
        out.push(ParamText {
            name: pname.to_string(),
            value: text,
        });
    }
    // Parameters a later writer added are kept, by record name (`lo`, `hi` of a kind with one
    // rate are shown with it).
    let one_rate = keys
        .iter()
        .filter(|(_, _, d)| matches!(d, Dim::Rate | Dim::RatePerC))
        .count()
        == 1;
    for (k, v) in &params {
        let with_rate =
            (*k == "lo" || *k == "hi") && one_rate && bounds.0.is_some() && bounds.1.is_some();
        let said = keys.iter().any(|(key, _, _)| key == k)
            || (bilinear && *k == "bilinear")
            || (zero.is_some() && *k == "zero");
        if !with_rate && !said {
            // a decimation is a count of samples (`32`, not `32.0`)
            let value = if *k == "decimation" && v.is_finite() && v.fract() == 0.0 {
                format!("{v:.0}")
            } else {
                shown(*v)
            };
            out.push(ParamText {
                name: k.replace('_', " "),
                value,
            });
        }
    }
    (name, out)
}

/// A rate in datasheet units: the factor and unit of the bias-instability coefficient (u/s),
/// when `unit` is one `model::units` knows.
fn datasheet_rate(unit: &str) -> Option<(f64, &'static str)> {
    IncrementUnit::parse(unit).map(|iu| (datasheet_factors(&iu)[2], datasheet_units(iu.kind)[2]))
}

/// A rate `v` (u/s) in the channel's datasheet unit beside the native one, `2.10 deg/h
/// (5.83e-4 deg/s)`, or in u/s alone when `unit` is not known.
pub fn rate_words(v: f64, unit: &str, number: &dyn Fn(f64) -> String) -> String {
    let u = if unit.is_empty() { "u" } else { unit };
    let ru = &native_units(u)[2];
    match datasheet_rate(u) {
        Some((f, du)) => format!("{} {du} ({} {ru})", number(v * f), number(v)),
        None => format!("{} {ru}", number(v)),
    }
}

/// `name [p1 v1, p2 v2]` (`pair` " ", the terminal's form) or `name [p1 = v1, p2 = v2]` (" = ",
/// the report's), or the name alone when it has no parameters.
pub fn effect_bracketed(
    effect: &RecordedEffect,
    unit: &str,
    number: &dyn Fn(f64) -> String,
    pair: &str,
) -> String {
    let (name, list) = name_and_list(effect, unit, number, pair);
    list.map_or(name.clone(), |l| format!("{name} [{l}]"))
}

/// `name: p1 = v1, p2 = v2` in one line.
pub fn effect_line(effect: &RecordedEffect, unit: &str, number: &dyn Fn(f64) -> String) -> String {
    let (name, list) = name_and_list(effect, unit, number, " = ");
    list.map_or(name.clone(), |l| format!("{name}: {l}"))
}

/// The effect's name and its parameters `p1{pair}v1, p2{pair}v2` (`None` when it has none).
fn name_and_list(
    effect: &RecordedEffect,
    unit: &str,
    number: &dyn Fn(f64) -> String,
    pair: &str,
) -> (String, Option<String>) {
    let (name, ps) = effect_parts(effect, unit, number);
    let list: Vec<String> = ps
        .iter()
        .map(|p| format!("{}{pair}{}", p.name, p.value))
        .collect();
    (name, (!list.is_empty()).then(|| list.join(", ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gap::EffectParams;

    fn line(taps: u32, stages: u32, decimation: u32) -> String {
        let e = RecordedEffect::Known(EffectParams::MovingAverage {
            taps,
            stages,
            decimation,
        });
        effect_line(&e, "deg", &|v| format!("{v}"))
    }

    /// A moving average run faster than the output says so in its name, and a CIC (taps the
    /// decimation) is named as one with its order; an output-rate average reads as before.
    #[test]
    fn a_decimated_average_is_named_with_its_rate() {
        assert_eq!(
            line(8, 3, 8),
            "output moving average (FIR) run at 8 times the output rate and read every 8th \
             sample, taps counted there (a sinc^3 CIC decimator): taps = 8, stages = 3, decimation = 8"
        );
        assert_eq!(
            line(5, 2, 3),
            "output moving average (FIR) run at 3 times the output rate and read every 3rd \
             sample, taps counted there: taps = 5, stages = 2, decimation = 3"
        );
        assert_eq!(
            line(16, 2, 1),
            "output moving average (FIR): taps = 16, stages = 2"
        );
        // the decimation is a count whatever the numbers' format (a terminal table's three
        // digits wrote `32.0`)
        let e = RecordedEffect::Known(EffectParams::MovingAverage {
            taps: 750,
            stages: 2,
            decimation: 32,
        });
        assert!(
            effect_line(&e, "deg", &|v| format!("{v:.1}")).ends_with("decimation = 32"),
            "{}",
            effect_line(&e, "deg", &|v| format!("{v:.1}"))
        );
    }

    /// A temperature sensitivity says its second order (u/s per deg C^2, about its reference)
    /// and its lag (s) when the record has them, and nothing of them when it has not.
    #[test]
    fn a_temperature_says_its_second_order_and_lag_when_it_has_them() {
        let straight = EffectParams::Temperature {
            coefficient: 0.2,
            lo: 0.1,
            hi: 0.3,
            quadratic: None,
            lag: None,
        };
        assert_eq!(
            effect_line(&RecordedEffect::Known(straight), "arcsec", &|v| format!(
                "{v}"
            )),
            "temperature sensitivity: coefficient = 0.2 [0.1, 0.3] deg/h per deg C \
             (0.2 [0.1, 0.3] arcsec/s per deg C)"
        );
        let bent = EffectParams::Temperature {
            coefficient: 0.2,
            lo: 0.1,
            hi: 0.3,
            quadratic: Some(crate::gap::effects::TemperatureQuadratic {
                coefficient: 0.004,
                lo: 0.003,
                hi: 0.005,
                reference_c: 22.5,
            }),
            lag: Some(crate::gap::effects::TemperatureLag {
                time_constant: 1800.0,
                lo: 1500.0,
                hi: 2100.0,
            }),
        };
        let text = effect_line(&RecordedEffect::Known(bent), "arcsec", &|v| format!("{v}"));
        assert!(
            text.ends_with(
                "second order = 0.004 deg/h per deg C^2 (0.004 arcsec/s per deg C^2), \
                 about = 22.5 deg C, unit's temperature lagging the recorded one by = 1800 s"
            ),
            "{text}"
        );
    }

    /// A FIR is named as one, its cut-off in Hz and its taps counted.
    #[test]
    fn a_fir_is_named_with_its_cutoff_and_taps() {
        let e = RecordedEffect::Known(EffectParams::FirFilter {
            cutoff_hz: 131.0,
            decimation: 1,
            taps: 47,
        });
        assert_eq!(
            effect_line(&e, "deg", &|v| format!("{v}")),
            "output linear-phase FIR low-pass (windowed sinc): cut-off = 131 Hz (period 0.007633587786259542 s), \
             taps = 47"
        );
        // run at twice the output rate (a half-band decimator)
        let e = RecordedEffect::Known(EffectParams::FirFilter {
            cutoff_hz: 250.0,
            decimation: 2,
            taps: 31,
        });
        assert_eq!(
            effect_line(&e, "deg", &|v| format!("{v}")),
            "output linear-phase FIR low-pass (windowed sinc) run at 2 times the output rate and \
             read every 2nd sample, taps counted there: cut-off = 250 Hz (period 0.004 s), \
             taps = 31, decimation = 2"
        );
    }

    /// A Butterworth is named with its order and its half-power cut-off.
    #[test]
    fn a_butterworth_is_named_with_its_order_and_cutoff() {
        let e = RecordedEffect::Known(EffectParams::ButterworthFilter {
            cutoff_hz: 25.0,
            decimation: 1,
            order: 4,
        });
        assert_eq!(
            effect_line(&e, "deg", &|v| format!("{v}")),
            "output Butterworth low-pass: order = 4, cut-off (half power) = 25 Hz (period 0.04 s)"
        );
        // run at 16 times the output rate
        let e = RecordedEffect::Known(EffectParams::ButterworthFilter {
            cutoff_hz: 25.0,
            decimation: 16,
            order: 3,
        });
        assert_eq!(
            effect_line(&e, "deg", &|v| format!("{v}")),
            "output Butterworth low-pass run at 16 times the output rate and read every 16th \
             sample: order = 3, cut-off (half power) = 25 Hz (period 0.04 s), decimation = 16"
        );
    }
}
