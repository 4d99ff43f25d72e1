//! One `[[channel]]` table of a model file: its name and unit, the five terms, the flicker band,
//! the axis, and every effect (temperature coefficient, Gauss-Markov, sinusoids, narrow-band noise, output filter
//! or another low-pass, warm-up, bias jumps, rate quantization, outliers), into a
//! [`ChannelModel`].

use super::keys::Keys;
use super::{
    BandNoise, BiasJumps, ChannelModel, FlickerBank, GaussMarkov, IncrementUnit, LowPass, Outliers,
    OutputFilterSpec, Sinusoid, Warmup, FLICKER_BAND_DECADES_DEFAULT,
};
use crate::model::lowpass::{sampled_zero, SecondOrderForm, CONTINUOUS_DECIMATION};
use crate::toml_check::Collector;

fn parse_axis(v: &toml::Value, path: &str, errs: &mut Collector) -> Option<[f64; 3]> {
    let raw = match v {
        toml::Value::String(s) => match s.as_str() {
            "east" => [1.0, 0.0, 0.0],
            "west" => [-1.0, 0.0, 0.0],
            "north" => [0.0, 1.0, 0.0],
            "south" => [0.0, -1.0, 0.0],
            "up" => [0.0, 0.0, 1.0],
            "down" => [0.0, 0.0, -1.0],
            other => {
                errs.bad(
                    path,
                    format!("unknown direction `{other}` (allowed: up, down, north, south, east, west, or [east, north, up])"),
                );
                return None;
            }
        },
        toml::Value::Array(a) => {
            let nums: Vec<f64> = a
                .iter()
                .filter_map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)))
                .collect();
            if a.len() != 3 || nums.len() != 3 || nums.iter().any(|x| !x.is_finite()) {
                errs.bad(path, "expected three numbers [east, north, up]");
                return None;
            }
            [nums[0], nums[1], nums[2]]
        }
        other => {
            errs.bad(
                path,
                format!(
                    "expected a direction name or [east, north, up], found {}",
                    other.type_str()
                ),
            );
            return None;
        }
    };
    let norm = (raw[0] * raw[0] + raw[1] * raw[1] + raw[2] * raw[2]).sqrt();
    if norm == 0.0 {
        errs.bad(path, "must not be the zero vector");
        return None;
    }
    Some([raw[0] / norm, raw[1] / norm, raw[2] / norm])
}

pub(super) fn parse_channel(
    t: &toml::Table,
    path: &str,
    tau0_s: f64,
    has_temperature: bool,
    has_stand: bool,
    errs: &mut Collector,
) -> Option<ChannelModel> {
    let n_before = errs.problems().len();
    let mut k = Keys::new(t, path);
    let name = k.string("name", errs).unwrap_or("").to_string();
    if !t.contains_key("name") {
        errs.bad(k.path("name"), "missing");
    } else if name.is_empty() || name.contains([',', '"', '\n', '\r']) {
        errs.bad(
            k.path("name"),
            "must be non-empty, without commas, quotes or line breaks",
        );
    }
    let unit = k.string("unit", errs).unwrap_or("").to_string();
    if !t.contains_key("unit") {
        errs.bad(k.path("unit"), "missing");
    }
    let kind = IncrementUnit::parse(&unit);
    let lsb = k.num_pos("lsb", true, errs);
    let bias = k.num("bias", errs).unwrap_or(0.0);
    let q = k.num_pos("Q", false, errs).unwrap_or(0.0);
    let n = k.num_pos("N", false, errs).unwrap_or(0.0);
    let b = k.num_pos("B", false, errs).unwrap_or(0.0);
    let kk = k.num_pos("K", false, errs).unwrap_or(0.0);
    let r = k.num("R", errs).unwrap_or(0.0);
    let band_path = k.path("flicker_band_s");
    let flicker_band_s = match k.get("flicker_band_s") {
        None => (tau0_s, tau0_s * 10f64.powf(FLICKER_BAND_DECADES_DEFAULT)),
        Some(v) => {
            let nums: Vec<f64> = v
                .as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)))
                        .collect()
                })
                .unwrap_or_default();
            if nums.len() != 2 || !(nums[0] > 0.0 && nums[1] > nums[0] && nums[1].is_finite()) {
                errs.bad(
                    &band_path,
                    "expected [tau_lo_s, tau_hi_s] with 0 < tau_lo_s < tau_hi_s",
                );
                (tau0_s, tau0_s * 10f64.powf(FLICKER_BAND_DECADES_DEFAULT))
            } else {
                (nums[0], nums[1])
            }
        }
    };
    let axis_path = k.path("axis");
    let axis_enu = k.get("axis").and_then(|v| parse_axis(v, &axis_path, errs));
    if axis_enu.is_some() && kind.is_none() {
        errs.bad(
            &axis_path,
            format!(
                "an axis needs a unit of angle (arcsec, deg, rad, mrad) or velocity (m/s, ft/s, g, mg), not `{unit}`"
            ),
        );
    }
    if axis_enu.is_some() && !has_stand {
        errs.bad(
            &axis_path,
            "an axis needs a [stand] table (latitude) to project on",
        );
    }
    let temperature_coefficient = k.num("temperature_coefficient", errs).unwrap_or(0.0);
    if temperature_coefficient != 0.0 && !has_temperature {
        errs.bad(
            k.path("temperature_coefficient"),
            "needs a top-level [temperature] profile",
        );
    }
    let temperature_quadratic = k.num("temperature_quadratic", errs).unwrap_or(0.0);
    if temperature_quadratic != 0.0 && !has_temperature {
        errs.bad(
            k.path("temperature_quadratic"),
            "needs a top-level [temperature] profile",
        );
    }
    let mut gauss_markov = Vec::new();
    for (p, tt) in k.tables("gauss_markov", errs) {
        let mut e = Keys::new(tt, &p);
        let s = e.num_pos("sigma", false, errs);
        let sigma = e.required("sigma", s, errs);
        let tc = e.num_pos("tau_c", true, errs);
        let tau_c_s = e.required("tau_c", tc, errs);
        e.finish(errs);
        gauss_markov.push(GaussMarkov { sigma, tau_c_s });
    }
    let mut sinusoids = Vec::new();
    for (p, tt) in k.tables("sinusoid", errs) {
        let mut e = Keys::new(tt, &p);
        let a = e.num("amplitude", errs);
        let amplitude = e.required("amplitude", a, errs);
        let f = e.num_pos("frequency", true, errs);
        let frequency_hz = e.required("frequency", f, errs);
        let phase_rad = e.num("phase", errs).unwrap_or(0.0);
        e.finish(errs);
        sinusoids.push(Sinusoid {
            amplitude,
            frequency_hz,
            phase_rad,
        });
    }
    let mut band_noise = Vec::new();
    for (p, tt) in k.tables("band_noise", errs) {
        let mut e = Keys::new(tt, &p);
        let s = e.num_pos("sigma", false, errs);
        let sigma = e.required("sigma", s, errs);
        let f = e.num_pos("frequency", true, errs);
        let frequency_hz = e.required("frequency", f, errs);
        let w = e.num_pos("width", true, errs);
        let width_hz = e.required("width", w, errs);
        if f.is_some_and(|f| f >= 0.5 / tau0_s) {
            errs.bad(
                e.path("frequency"),
                format!(
                    "{} Hz is not below Nyquist ({} Hz at tau0 = {tau0_s} s); a band above it is seen at its alias",
                    frequency_hz,
                    0.5 / tau0_s
                ),
            );
        }
        e.finish(errs);
        band_noise.push(BandNoise {
            sigma,
            frequency_hz,
            width_hz,
        });
    }
    let output_filter = k.table("output_filter", errs).map(|(p, tt)| {
        let mut e = Keys::new(tt, &p);
        let tc = e.num_pos("time_constant", true, errs);
        let time_constant_s = e.required("time_constant", tc, errs);
        e.finish(errs);
        OutputFilterSpec { time_constant_s }
    });
    let mut output_filter = output_filter;
    let lowpass = parse_lowpass(&mut k, tau0_s, &mut output_filter, errs);
    let warmup = k.table("warmup", errs).map(|(p, tt)| {
        let mut e = Keys::new(tt, &p);
        let a = e.num("amplitude", errs);
        let amplitude = e.required("amplitude", a, errs);
        let tc = e.num_pos("time_constant", true, errs);
        let time_constant_s = e.required("time_constant", tc, errs);
        e.finish(errs);
        Warmup {
            amplitude,
            time_constant_s,
        }
    });
    let bias_jumps = k.table("bias_jumps", errs).map(|(p, tt)| {
        let mut e = Keys::new(tt, &p);
        let mi = e.num_pos("mean_interval", true, errs);
        let mean_interval_s = e.required("mean_interval", mi, errs);
        let rs = e.num_pos("rms_size", false, errs);
        let rms_size = e.required("rms_size", rs, errs);
        e.finish(errs);
        BiasJumps {
            mean_interval_s,
            rms_size,
        }
    });
    let rate_lsb = k.num_pos("rate_lsb", true, errs);
    let outliers = k.table("outliers", errs).map(|(p, tt)| {
        let mut e = Keys::new(tt, &p);
        let r = e.num_pos("rate", false, errs);
        let rate_per_s = e.required("rate", r, errs);
        if rate_per_s * tau0_s > 0.5 {
            errs.bad(
                e.path("rate"),
                format!("{rate_per_s} per second is more than one outlier every two samples"),
            );
        }
        let sz = e.num_pos("size", true, errs);
        let size = e.required("size", sz, errs);
        e.finish(errs);
        Outliers { rate_per_s, size }
    });
    k.finish(errs);
    if errs.problems().len() > n_before {
        return None;
    }
    let flicker = (b > 0.0).then(|| FlickerBank::design(b, flicker_band_s.0, flicker_band_s.1));
    Some(ChannelModel {
        name,
        unit,
        lsb,
        bias,
        q,
        n,
        b,
        k: kk,
        r,
        flicker_band_s,
        flicker,
        axis_enu,
        kind,
        temperature_coefficient,
        temperature_quadratic,
        gauss_markov,
        sinusoids,
        band_noise,
        output_filter,
        lowpass,
        warmup,
        bias_jumps,
        rate_lsb,
        outliers,
    })
}

/// `v`, the value of `table.key`, as a whole number (reported when it has a fraction; a value
/// already reported missing or out of range is clamped and judged no further).
fn whole(table: &str, key: &str, v: f64, errs: &mut Collector) -> u32 {
    if v.is_finite() && v.fract() != 0.0 {
        errs.bad(
            format!("{table}.{key}"),
            format!("must be a whole number, got {v}"),
        );
    }
    v.clamp(0.0, u32::MAX as f64) as u32
}

/// The keys `moving_average = {taps, stages}`, `second_order_filter = {natural_frequency,
/// damping}`, `zero_phase_filter = {time_constant}`, `fir_filter = {taps, cutoff}` and
/// `butterworth_filter = {order, cutoff}`: one filter per channel (`output_filter` included), or
/// a moving average with an `output_filter`, a `second_order_filter` or a `butterworth_filter`
/// behind it (a [`LowPass::Cascade`], which then holds the output filter: `output_filter` is
/// taken).
fn parse_lowpass(
    k: &mut Keys<'_>,
    tau0_s: f64,
    output_filter: &mut Option<OutputFilterSpec>,
    errs: &mut Collector,
) -> Option<LowPass> {
    let mut found: Vec<(String, LowPass)> = Vec::new();
    if let Some((p, tt)) = k.table("moving_average", errs) {
        let mut e = Keys::new(tt, &p);
        let t = e.num_pos("taps", true, errs);
        let taps = e.required("taps", t, errs);
        let stages = e.num_pos("stages", true, errs).unwrap_or(1.0);
        // run faster than the output and read every `decimation`-th sample (a CIC decimator:
        // taps = decimation)
        let decimation = e.num_pos("decimation", true, errs).unwrap_or(1.0);
        e.finish(errs);
        let lp = LowPass::MovingAverage {
            taps: whole(&p, "taps", taps, errs),
            stages: whole(&p, "stages", stages, errs),
            decimation: whole(&p, "decimation", decimation, errs),
        };
        found.push((p, lp));
    }
    if let Some((p, tt)) = k.table("second_order_filter", errs) {
        let mut e = Keys::new(tt, &p);
        let f = e.num_pos("natural_frequency", true, errs);
        let natural_frequency_hz = e.required("natural_frequency", f, errs);
        let z = e.num_pos("damping", true, errs);
        let damping = e.required("damping", z, errs);
        // The bilinear biquad (scipy's butter, PX4's LowPassFilter2p) in place of the
        // pole-mapped form (model::lowpass).
        let bilinear = e.boolean("bilinear", errs).unwrap_or(false);
        // The filter run faster than the output and sampled
        // (model::lowpass::SecondOrderForm::Sampled): its zero, or the decimation of a
        // pole-mapped filter run that many times faster, from which the zero follows.
        let zero = e.num_pos("zero", false, errs);
        let decimation = e.num("decimation", errs);
        let form = match (zero, decimation) {
            (Some(_), Some(_)) => {
                errs.bad(
                    e.path("decimation"),
                    "zero and decimation exclude each other (the decimation gives the zero)",
                );
                SecondOrderForm::PoleMapped
            }
            (Some(_), None) | (None, Some(_)) if bilinear => {
                let key = if zero.is_some() { "zero" } else { "decimation" };
                errs.bad(
                    e.path(key),
                    format!(
                        "the bilinear form has its zeros at Nyquist: bilinear = true and {key} \
                         exclude each other"
                    ),
                );
                SecondOrderForm::Bilinear
            }
            (Some(zero), None) => SecondOrderForm::Sampled { zero },
            (None, Some(d)) if (1.0..=CONTINUOUS_DECIMATION).contains(&d) => {
                SecondOrderForm::Sampled {
                    zero: sampled_zero(natural_frequency_hz, damping, tau0_s, d),
                }
            }
            (None, Some(d)) => {
                errs.bad(
                    e.path("decimation"),
                    format!("decimation {d} must be in [1, {CONTINUOUS_DECIMATION}]"),
                );
                SecondOrderForm::PoleMapped
            }
            (None, None) if bilinear => SecondOrderForm::Bilinear,
            (None, None) => SecondOrderForm::PoleMapped,
        };
        e.finish(errs);
        found.push((
            p,
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                form,
            },
        ));
    }
    if let Some((p, tt)) = k.table("zero_phase_filter", errs) {
        let mut e = Keys::new(tt, &p);
        let tc = e.num_pos("time_constant", true, errs);
        let time_constant_s = e.required("time_constant", tc, errs);
        e.finish(errs);
        found.push((p, LowPass::ZeroPhase { time_constant_s }));
    }
    if let Some((p, tt)) = k.table("fir_filter", errs) {
        let mut e = Keys::new(tt, &p);
        let t = e.num_pos("taps", true, errs);
        let taps = e.required("taps", t, errs);
        let c = e.num_pos("cutoff", true, errs);
        let cutoff_hz = e.required("cutoff", c, errs);
        // run faster than the output and read every `decimation`-th sample (a half-band
        // decimator: 2, the cut-off at the output's Nyquist)
        let decimation = e.num_pos("decimation", true, errs).unwrap_or(1.0);
        e.finish(errs);
        let lp = LowPass::Fir {
            taps: whole(&p, "taps", taps, errs),
            cutoff_hz,
            decimation: whole(&p, "decimation", decimation, errs),
        };
        found.push((p, lp));
    }
    if let Some((p, tt)) = k.table("butterworth_filter", errs) {
        let mut e = Keys::new(tt, &p);
        let o = e.num_pos("order", true, errs);
        let order = e.required("order", o, errs);
        let c = e.num_pos("cutoff", true, errs);
        let cutoff_hz = e.required("cutoff", c, errs);
        // run faster than the output and read every `decimation`-th sample
        let decimation = e.num_pos("decimation", true, errs).unwrap_or(1.0);
        e.finish(errs);
        let lp = LowPass::Butterworth {
            order: whole(&p, "order", order, errs),
            cutoff_hz,
            decimation: whole(&p, "decimation", decimation, errs),
        };
        found.push((p, lp));
    }
    let behind = output_filter.map(|f| LowPass::FirstOrder {
        time_constant_s: f.time_constant_s,
    });
    let mut out: Option<LowPass> = None;
    for (p, lp) in found.into_iter() {
        // a moving average first (its table is read first), with one low-pass behind it
        let average = |lp: Option<LowPass>| matches!(lp, Some(LowPass::MovingAverage { .. }));
        let fits = match out {
            None => behind.is_none() || average(Some(lp)),
            Some(_) => {
                behind.is_none()
                    && average(out)
                    && matches!(
                        lp,
                        LowPass::SecondOrder { .. } | LowPass::Butterworth { .. }
                    )
            }
        };
        if !fits {
            errs.bad(
                p,
                "one filter per channel (output_filter, moving_average, second_order_filter, \
                 zero_phase_filter, fir_filter and butterworth_filter exclude each other), or a \
                 moving_average with one output_filter, second_order_filter or \
                 butterworth_filter behind it",
            );
            continue;
        }
        // Parameters already reported missing or not positive are not judged again.
        let judged = match lp {
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                ..
            } => natural_frequency_hz.is_finite() && damping.is_finite(),
            LowPass::ZeroPhase { time_constant_s } => time_constant_s.is_finite(),
            LowPass::Fir { cutoff_hz, .. } | LowPass::Butterworth { cutoff_hz, .. } => {
                cutoff_hz.is_finite()
            }
            _ => true,
        };
        if judged {
            if let Some(problem) = lp.check(tau0_s) {
                errs.bad(p, problem);
                continue;
            }
        }
        out = Some(LowPass::compose(out, lp));
    }
    // an output filter behind the moving average joins it
    match (out, behind) {
        (Some(lp @ LowPass::MovingAverage { .. }), Some(fo)) => {
            *output_filter = None;
            Some(LowPass::compose(Some(lp), fo))
        }
        _ => out,
    }
}
