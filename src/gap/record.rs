//! docs/records.md's `diagnosis` record: `type`, `channel`, `gap_before`, `gap_after`, `verdict`,
//! `regions`, `effects`, optional `holdout`, plus extra fields (`final`, `t_data`, `tau_span`,
//! `base_coef`, `final_coef`, `segments`, `jumps`, `residual_shape`, `model_tau`, `model_base`,
//! `model_effects`, `outliers`, `quantization`, `quantization_limited`, `alternatives`, and
//! `run` when several inputs are analyzed).

use std::collections::BTreeMap;

use super::alternatives::Alternative;
use super::diagnose::{Diagnosis, Verdict};
use super::effects::{nullable_f64, EffectParams};
use super::holdout::HoldoutGap;
use super::limit_cycle::LimitCycle;
use super::quantization::QuantizationFinding;
use crate::model::term_values::{CoefValue, Terms};
use serde::{Deserialize, Serialize};

/// One region of the record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionRecord {
    pub tau_lo: f64,
    pub tau_hi: f64,
    pub sign: i32,
    pub worst_ratio: f64,
}

/// One effect of the record: `kind` and `params` (docs/records.md's names and units: u/s, s,
/// Hz), the gap with it added, and its parameters' intervals.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectRecord {
    /// `kind` and `params`, written first.
    #[serde(flatten)]
    pub effect: RecordedEffect,
    pub gap_after: f64,
    /// 95% intervals of the parameters, by their `params` names (`{name: [lo, hi]}`;
    /// docs/gap.md, "Parameter intervals"); absent when none was computed (warm-ups, jumps).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub intervals: BTreeMap<String, [f64; 2]>,
    /// What the effect is when it is not an effect of the unit (absent otherwise): a named
    /// sinusoid that is the counter's limit cycle (docs/gap.md, "The counter's limit cycle").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cause: Option<EffectCause>,
}

/// The record's `cause` of an effect that is not the unit's: `{kind, expected_frequency,
/// harmonic, mean_rate, lsb}`. `kind` is `quantization_limit_cycle`: the line at the
/// `harmonic`-th multiple of `|mean_rate| / lsb` (aliased, Hz: `expected_frequency`) that a
/// counter with carry makes under a nearly constant rate (`mean_rate` in u/s, `lsb` in u).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectCause {
    pub kind: String,
    pub expected_frequency: f64,
    pub harmonic: u32,
    pub mean_rate: f64,
    pub lsb: f64,
}

impl EffectCause {
    /// The cause of a limit cycle.
    pub fn limit_cycle(c: &LimitCycle) -> Self {
        EffectCause {
            kind: "quantization_limit_cycle".into(),
            expected_frequency: c.expected_hz,
            harmonic: c.harmonic,
            mean_rate: c.mean_rate,
            lsb: c.lsb,
        }
    }
}

/// An effect as a record holds it: one of the kinds this version diagnoses, or a kind a newer
/// version wrote, kept with its numbers under their record names so a reader can still show it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum RecordedEffect {
    Known(EffectParams),
    Unknown(UnknownEffect),
}

/// An effect of a kind this version does not know: its `kind` and its `params` (numbers, `null`
/// where not finite) in the record's order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UnknownEffect {
    pub kind: String,
    pub params: BTreeMap<String, Option<f64>>,
}

impl RecordedEffect {
    /// The record's `kind` string.
    pub fn kind_name(&self) -> &str {
        match self {
            RecordedEffect::Known(p) => p.kind().name(),
            RecordedEffect::Unknown(u) => &u.kind,
        }
    }
}

/// An entry of the record's `alternatives` (docs/gap.md, "Alternatives";
/// [`super::alternatives::Alternative`]): `{coef, delta_chi2, effects: [{kind, params}], gap}`,
/// the fields in alphabetical order, the order earlier versions wrote them in.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AlternativeRecord {
    /// Its five terms `[Q, N, B, K, R]` (docs/theory.md section 2 units).
    pub coef: [f64; 5],
    /// Its `r' S^-1 r` less the chosen model's.
    #[serde(deserialize_with = "nullable_f64")]
    pub delta_chi2: f64,
    pub effects: Vec<RecordedEffect>,
    #[serde(deserialize_with = "nullable_f64")]
    pub gap: f64,
}

impl AlternativeRecord {
    pub fn new(a: &Alternative) -> Self {
        AlternativeRecord {
            coef: a.coef,
            delta_chi2: a.delta_chi2,
            effects: a
                .effects
                .iter()
                .map(|p| RecordedEffect::Known(*p))
                .collect(),
            gap: a.gap,
        }
    }
}

/// The gap on a held-out run (docs/records.md's `gap_before`, `gap_after`; extra fields `carried`
/// and `effects`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HoldoutRecord {
    pub gap_before: f64,
    /// With the effects that carried: never above `gap_before`.
    pub gap_after: f64,
    /// Whether any effect of the fitting run carried (`gap::holdout::carries`: lowered the
    /// held-out `r' S^-1 r` by a margin that means something); `false` says plainly
    /// that the diagnosis did not carry to this run.
    #[serde(default)]
    pub carried: bool,
    /// Each effect of the fitting run on the held-out run, in order (bias jumps left out).
    #[serde(default)]
    pub effects: Vec<HeldEffectRecord>,
    /// The kinds of the fitting run's effects the held-out run could not judge
    /// (`gap::holdout::HoldoutGap::not_judged`); absent when none (and before session 53).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub not_judged: Vec<String>,
}

/// One effect on the held-out run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldEffectRecord {
    pub kind: String,
    /// The held-out gap with it added to the effects that carried before it.
    pub gap_after: f64,
    /// Whether it carried: it lowered the held-out `r' S^-1 r` by a margin that means
    /// something (`gap::holdout::carries`), and was kept for the effects after it.
    pub carried: bool,
    /// The drop of `r' S^-1 r` it brought on the held-out run (negative: it raised it); absent
    /// in records written before session 10.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delta_chi2: Option<f64>,
}

/// One segment homogeneity test (extra field `segments`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentRecord {
    pub tau: f64,
    pub stat: f64,
    pub p_value: f64,
    pub worst_segment: usize,
    pub worst_ratio: f64,
}

/// The `diagnosis` JSON line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename = "diagnosis")]
pub struct DiagnosisRecord {
    pub channel: String,
    pub gap_before: f64,
    pub gap_after: f64,
    pub verdict: Verdict,
    pub regions: Vec<RegionRecord>,
    pub effects: Vec<EffectRecord>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub holdout: Option<HoldoutRecord>,
    #[serde(rename = "final", default)]
    pub is_final: bool,
    /// Seconds of data diagnosed.
    #[serde(default)]
    pub t_data: f64,
    /// Tau range of the curve used (s).
    #[serde(default)]
    pub tau_span: [f64; 2],
    /// Five-term fit alone and with the effects, `[Q, N, B, K, R]` (docs/theory.md section 2 units).
    #[serde(default)]
    pub base_coef: [f64; 5],
    #[serde(default)]
    pub final_coef: [f64; 5],
    /// `final_coef` with 95% intervals, as the `fit` record's `coef`: `{Q, N, B, K, R}`, each
    /// `{value, lo, hi, determined}`, `value` null where not determined (since session 40).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub final_terms: Option<Terms<CoefValue>>,
    #[serde(default)]
    pub segments: Vec<SegmentRecord>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub residual_shape: Option<String>,
    /// The taus of the curve diagnosed (s), and at each the deviation (u/s) of the five-term
    /// model alone (`model_base`) and with the effects in (`model_effects`): the two lines a
    /// plot draws over the measured curve.
    #[serde(default)]
    pub model_tau: Vec<f64>,
    #[serde(default)]
    pub model_base: Vec<f64>,
    #[serde(default)]
    pub model_effects: Vec<f64>,
    /// The bias jumps named (docs/gap.md, "Jumps kept in time (session 18)"): each step's time
    /// (s from the record's first sample, at a block boundary: the step lies within `block_s`
    /// of it), size (u/s, the rate after less the rate before) and z score when the search
    /// added it; absent when no jump was named.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub jumps: Option<JumpsRecord>,
    /// Outliers found and replaced before the curve was computed (docs/gap.md, "Outliers").
    #[serde(default)]
    pub outliers: OutliersRecord,
    /// Stretches where the channel did not move (one value repeated far beyond its noise),
    /// taken out as gaps before the curve was computed (docs/gap.md, "Stuck stretches"):
    /// absent when there is none.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub stuck: Option<super::stuck::StuckSpan>,
    /// The block tests' first block when its mean is far off the rest of the run, by a
    /// start-up transient or one block's excursion of slower noise, too short to name as a
    /// warm-up (docs/gap.md, "A first block far off (session 45)"): `{start_s, seconds,
    /// offset, p_value}`, absent otherwise.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub first_block: Option<super::first_block::FirstBlock>,
    /// What the values' step does to the curve (docs/gap.md, "Rate-sample quantization"):
    /// absent when the values are not whole multiples of one step.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub quantization: Option<QuantizationFinding>,
    /// Other explanations that fit about as well as the one chosen (docs/gap.md,
    /// "Alternatives"): `[{effects: [{kind, params}], gap, delta_chi2, coef}]`, empty when the
    /// choice is clear.
    #[serde(default)]
    pub alternatives: Vec<AlternativeRecord>,
    /// When the input has a temperature: the coefficient the block means allow (u/s per degC,
    /// with its 95% interval and `z`) and why a temperature is or is not named (`outcome`:
    /// `named`, `not_shown`, `straight`, `not_kept`, `constant`, `too_short`), with the
    /// temperature's change (degC) and its bend from a straight line (docs/gap.md, "The
    /// temperature's check"); absent without a temperature.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub temperature_check: Option<super::temperature_check::TemperatureCheck>,
    /// Run index (0-based) when several inputs are analyzed, as in the other records.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub run: Option<usize>,
    /// The channel's unit `u` (as in the curve and fit records), so the parameters in u/s can be
    /// shown in datasheet units by a reader that has only this record (`diagnose`'s output).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub unit: Option<String>,
    /// Present when the unit's quantization is not white phase noise at the shortest taus
    /// (its LSB is coarse against the per-sample noise; docs/gap.md, "Quantization-limited
    /// units"): the curve was diagnosed from `tau_white` on.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub quantization_limited: Option<QuantizationRecord>,
    /// With `diagnose --ensemble N` only.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub ensemble: Option<EnsembleRecord>,
    /// Present when the base model carries the counter's sawtooth (a unit counting with carry
    /// at a steady rate; docs/gap.md, "The counter's sawtooth in the base model (session 23)").
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub counter_sawtooth: Option<SawtoothRecord>,
    /// Present when the curve was judged beyond the unit's filter's own stretch (docs/gap.md,
    /// "The filter's own stretch of the curve (session 48)").
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub filter_shape: Option<FilterShapeRecord>,
}

/// The extra field `filter_shape`: the curve was diagnosed from `from_tau` (s) on, five of its
/// filter's memories, because on the whole curve the nearest filter kind's misfit left it
/// `unexplained` or brought effects within that stretch. `filter` is the unit's filter the
/// whole curve named (`{kind, params, gap_after}` as effects, a cascade's two parts), which
/// the unit's model keeps; `gap_whole` and `verdict_whole` are the whole curve's final gap and
/// verdict; `set_aside` the whole curve's effects within the stretch, which the curve beyond
/// it did not need.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FilterShapeRecord {
    pub from_tau: f64,
    pub filter: Vec<EffectRecord>,
    pub gap_whole: f64,
    pub verdict_whole: Verdict,
    pub set_aside: Vec<EffectRecord>,
}

impl FilterShapeRecord {
    fn new(f: &super::filter_shape::FilterShape) -> Self {
        let effect = |e: &super::diagnose::AddedEffect| EffectRecord {
            effect: RecordedEffect::Known(e.params),
            gap_after: e.gap_after,
            intervals: BTreeMap::new(),
            cause: None,
        };
        FilterShapeRecord {
            from_tau: f.from_tau_s,
            filter: f.named.iter().map(effect).collect(),
            gap_whole: f.gap_whole,
            verdict_whole: f.verdict_whole,
            set_aside: f.set_aside.iter().map(effect).collect(),
        }
    }
}

/// The extra field `counter_sawtooth`: the counter's LSB (u), the line's frequency (Hz, before
/// aliasing), the dither before the counter (u, standard deviation), the white rate `N`
/// (u/sqrt(s)) and the rate's wander (u/s) that widen it ([`super::sawtooth::Sawtooth`]); when
/// the unit counts behind its own low-pass (session 25), that filter as the sawtooth's model
/// holds it (`behind_filter`, `{kind, params}` as an effect): the filtered rate's walk widens
/// the harmonics. The sawtooth so widened stays a fixed part of every model of the curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SawtoothRecord {
    pub lsb: f64,
    pub frequency: f64,
    pub dither: f64,
    pub width_n: f64,
    pub wander: f64,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub behind_filter: Option<RecordedEffect>,
}

/// The extra field `ensemble` (`diagnose --ensemble N`; docs/gap.md, "The ensemble band"): at
/// the record's `model_tau`, the measured ADEV and the 2.5-97.5% band of `runs` simulated runs
/// of the fitted unit, base (five terms) and twin (with the effects), and the share of those
/// taus where the measured curve lies outside each band.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnsembleRecord {
    pub runs: usize,
    pub measured: Vec<f64>,
    pub base_lo: Vec<f64>,
    pub base_hi: Vec<f64>,
    pub twin_lo: Vec<f64>,
    pub twin_hi: Vec<f64>,
    pub outside_base: f64,
    pub outside_twin: f64,
}

/// The extra field `quantization_limited`: the increments' LSB (u), the per-sample rms change
/// of the phase over it (`ratio`, below 0.5), and the shortest tau (s) where the quantization
/// error is white again (the curve is diagnosed from there on, or whole when the base model
/// carries the counter's sawtooth); for rate samples rounded after the unit's filter in the
/// dead band (session 13, [`super::discrepancy`]), the filtered rate's rms over the step and
/// the tau up to which the rounding model's error is carried in full.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuantizationRecord {
    pub lsb: f64,
    pub ratio: f64,
    pub tau_white: f64,
}

/// The extra field `jumps`: the search's block length (s), which is the resolution of each
/// step's time, and the steps in time order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JumpsRecord {
    pub block_s: f64,
    pub steps: Vec<JumpStepRecord>,
}

/// One bias jump: its time (s from the record's first sample), size (u/s) and z score.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JumpStepRecord {
    pub time_s: f64,
    pub size: f64,
    pub z: f64,
}

impl JumpsRecord {
    /// The steps of `f` in time order, or `None` when it holds none.
    fn new(f: &super::steps::JumpFinding) -> Option<Self> {
        let mut steps: Vec<JumpStepRecord> = (0..f.sizes.len())
            .map(|i| JumpStepRecord {
                time_s: f.times_s[i],
                size: f.sizes[i],
                z: f.z_scores.get(i).copied().unwrap_or(f64::NAN),
            })
            .collect();
        steps.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        (!steps.is_empty()).then_some(Self {
            block_s: f.block_s,
            steps,
        })
    }
}

/// The `outliers` object: how many, how often (per second of data), their rms and largest size
/// (u/s), and the tail's shoulder that tells glitches from a heavy-tailed noise.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct OutliersRecord {
    pub count: u64,
    pub rate: f64,
    pub rms_size: f64,
    pub max_size: f64,
    /// Samples in the tail's shoulder, between 4 and 6 robust deviations
    /// ([`super::outliers::SHOULDER_Z`]), kept.
    #[serde(default)]
    pub shoulder: u64,
    /// The shoulder a Gaussian white noise gives over as many samples.
    #[serde(default)]
    pub shoulder_normal: f64,
    /// The samples beyond are the noise's own heavy tail, not glitches
    /// ([`super::outliers::OutlierCount::heavy_tail`]): no effect, the verdict not moved.
    #[serde(default)]
    pub heavy_tail: bool,
}

impl DiagnosisRecord {
    /// The record of a diagnosis; `holdout` from [`super::holdout::holdout_gap`].
    pub fn new(channel: &str, d: &Diagnosis, holdout: Option<&HoldoutGap>, is_final: bool) -> Self {
        Self {
            channel: channel.into(),
            gap_before: d.gap_before,
            gap_after: d.gap_after,
            verdict: d.verdict,
            regions: d
                .regions
                .iter()
                .map(|r| RegionRecord {
                    tau_lo: r.tau_lo_s,
                    tau_hi: r.tau_hi_s,
                    sign: r.sign,
                    worst_ratio: r.worst_ratio,
                })
                .collect(),
            effects: d
                .effects
                .iter()
                .enumerate()
                .map(|(i, e)| EffectRecord {
                    effect: RecordedEffect::Known(e.params),
                    gap_after: e.gap_after,
                    intervals: d
                        .effect_intervals
                        .get(i)
                        .map(|v| {
                            v.iter()
                                .filter(|(_, iv)| iv.iter().all(|x| x.is_finite()))
                                .map(|(k, iv)| (k.to_string(), *iv))
                                .collect()
                        })
                        .unwrap_or_default(),
                    cause: d
                        .limit_cycles
                        .iter()
                        .find(|c| c.effect == i)
                        .map(EffectCause::limit_cycle),
                })
                .collect(),
            holdout: holdout.map(|h| HoldoutRecord {
                gap_before: h.gap_before,
                gap_after: h.gap_after,
                carried: h.carried(),
                effects: h
                    .effects
                    .iter()
                    .map(|e| HeldEffectRecord {
                        kind: e.kind.name().into(),
                        gap_after: e.gap_after,
                        carried: e.carried,
                        delta_chi2: e.delta_chi2.is_finite().then_some(e.delta_chi2),
                    })
                    .collect(),
                not_judged: h.not_judged.iter().map(|k| k.name().into()).collect(),
            }),
            is_final,
            t_data: d.t_data_s,
            tau_span: [d.tau_span_s.0, d.tau_span_s.1],
            base_coef: d.base_coef,
            final_coef: d.final_coef,
            final_terms: d.final_terms.iter().all(Option::is_some).then(|| {
                Terms::from_fn(|i| {
                    let t = d.final_terms[i].unwrap_or_default();
                    CoefValue {
                        value: t.determined.then_some(t.value),
                        lo: Some(t.lo),
                        hi: Some(t.hi),
                        determined: t.determined,
                    }
                })
            }),
            segments: d
                .segment_tests
                .iter()
                .map(|s| SegmentRecord {
                    tau: s.tau_s,
                    stat: s.stat,
                    p_value: s.p_value,
                    worst_segment: s.worst_segment,
                    worst_ratio: s.worst_ratio,
                })
                .collect(),
            residual_shape: d.residual_shape.clone(),
            model_tau: d.model_tau_s.clone(),
            model_base: d
                .model_base_avar
                .iter()
                .map(|v| v.max(0.0).sqrt())
                .collect(),
            model_effects: d
                .model_final_avar
                .iter()
                .map(|v| v.max(0.0).sqrt())
                .collect(),
            jumps: d.jumps.as_ref().and_then(JumpsRecord::new),
            outliers: OutliersRecord {
                count: d.outliers.count,
                rate: if d.t_data_s > 0.0 {
                    d.outliers.count as f64 / d.t_data_s
                } else {
                    0.0
                },
                rms_size: d.outliers.rms_size(),
                max_size: d.outliers.max_size,
                shoulder: d.outliers.shoulder,
                shoulder_normal: d.outliers.shoulder_normal(),
                heavy_tail: d.outliers.heavy_tail(),
            },
            stuck: d.stuck,
            first_block: d.first_block,
            quantization: d.quantization,
            alternatives: d.alternatives.iter().map(AlternativeRecord::new).collect(),
            temperature_check: d.temperature_check,
            run: None,
            unit: None,
            quantization_limited: d.quantization_limited.map(|q| QuantizationRecord {
                lsb: q.lsb,
                ratio: q.ratio,
                tau_white: q.tau_white_s,
            }),
            ensemble: None,
            counter_sawtooth: d.sawtooth.map(|s| SawtoothRecord {
                lsb: s.lsb,
                frequency: s.frequency_hz,
                dither: s.dither,
                width_n: s.n_arw,
                wander: s.rate_wander,
                behind_filter: s
                    .filter
                    .map(|lp| RecordedEffect::Known(EffectParams::from_lowpass(lp))),
            }),
            filter_shape: d.filter_shape.as_ref().map(FilterShapeRecord::new),
        }
    }

    /// The JSON line (no trailing newline).
    pub fn to_json_line(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| {
            format!(
                "{{\"type\":\"diagnosis\",\"channel\":\"{}\",\"error\":\"{e}\"}}",
                self.channel
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gap::effects::EffectKind;
    use crate::gap::quantization::QuantKind;

    fn every_kind() -> Vec<EffectParams> {
        vec![
            EffectParams::GaussMarkov {
                sigma: 0.3,
                tau_c_s: 30.0,
            },
            EffectParams::Sinusoid {
                amplitude: 0.25,
                frequency_hz: 0.8,
            },
            EffectParams::OutputFilter {
                time_constant_s: 0.01,
            },
            EffectParams::Warmup {
                amplitude: -1.5,
                time_constant_s: 60.0,
            },
            EffectParams::BiasJumps {
                count: 3,
                rms_size: 0.125,
            },
            EffectParams::Temperature {
                coefficient: 0.02,
                lo: f64::NAN,
                hi: 0.03,
                quadratic: None,
                lag: None,
            },
            EffectParams::MovingAverage {
                taps: 8,
                stages: 2,
                decimation: 1,
            },
            EffectParams::SecondOrderFilter {
                natural_frequency_hz: 20.0,
                damping: 0.7,
                bilinear: false,
                zero: None,
            },
            EffectParams::ZeroPhaseFilter {
                time_constant_s: 0.02,
            },
            EffectParams::FirFilter {
                cutoff_hz: 131.0,
                decimation: 1,
                taps: 47,
            },
            EffectParams::ButterworthFilter {
                cutoff_hz: 21.5,
                decimation: 1,
                order: 4,
            },
            EffectParams::BandNoise {
                frequency_hz: 20.5,
                sigma: 0.25,
                width_hz: 2.0,
            },
        ]
    }

    /// The bytes the untyped records wrote (a sorted JSON map per `params`, `null` for NaN),
    /// written out by hand: the typed effects must write exactly these.
    #[test]
    fn effects_write_the_bytes_of_the_untyped_records() {
        let want = [
            r#"{"kind":"gauss_markov","params":{"sigma":0.3,"tau_c":30.0},"gap_after":1.5}"#,
            r#"{"kind":"sinusoid","params":{"amplitude":0.25,"frequency":0.8},"gap_after":1.5}"#,
            r#"{"kind":"output_filter","params":{"time_constant":0.01},"gap_after":1.5}"#,
            r#"{"kind":"warmup","params":{"amplitude":-1.5,"time_constant":60.0},"gap_after":1.5}"#,
            r#"{"kind":"bias_jumps","params":{"count":3,"rms_size":0.125},"gap_after":1.5}"#,
            r#"{"kind":"temperature","params":{"coefficient":0.02,"hi":0.03,"lo":null},"gap_after":1.5}"#,
            r#"{"kind":"moving_average","params":{"stages":2,"taps":8},"gap_after":1.5}"#,
            r#"{"kind":"second_order_filter","params":{"damping":0.7,"natural_frequency":20.0},"gap_after":1.5}"#,
            r#"{"kind":"zero_phase_filter","params":{"time_constant":0.02},"gap_after":1.5}"#,
            r#"{"kind":"fir_filter","params":{"cutoff":131.0,"taps":47},"gap_after":1.5}"#,
            r#"{"kind":"butterworth_filter","params":{"cutoff":21.5,"order":4},"gap_after":1.5}"#,
            r#"{"kind":"band_noise","params":{"frequency":20.5,"sigma":0.25,"width":2.0},"gap_after":1.5}"#,
        ];
        let kinds = every_kind();
        assert_eq!(kinds.len(), EffectKind::ALL.len());
        for (p, want) in kinds.iter().zip(want) {
            let mut rec = EffectRecord {
                effect: RecordedEffect::Known(*p),
                gap_after: 1.5,
                intervals: BTreeMap::new(),
                cause: None,
            };
            let line = serde_json::to_string(&rec).unwrap();
            assert_eq!(line, want);
            // Read back: the same kind and numbers (NaN from `null`).
            let back: EffectRecord = serde_json::from_str(&line).unwrap();
            assert_eq!(serde_json::to_string(&back).unwrap(), want);
            assert!(matches!(back.effect, RecordedEffect::Known(q) if q.kind() == p.kind()));
            // `record_params` names the same parameters in the same order.
            let v: serde_json::Value = serde_json::from_str(&line).unwrap();
            let keys: Vec<&String> = v["params"].as_object().unwrap().keys().collect();
            let named: Vec<&str> = p.record_params().iter().map(|(k, _)| *k).collect();
            assert_eq!(keys, named, "{want}");
            // Intervals follow `params`.
            rec.intervals.insert(named[0].into(), [0.5, 2.0]);
            let line = serde_json::to_string(&rec).unwrap();
            assert!(line.ends_with(&format!(
                r#""gap_after":1.5,"intervals":{{"{}":[0.5,2.0]}}}}"#,
                named[0]
            )));
        }
    }

    /// The second order's sampled form writes its zero after the other two parameters, and a
    /// moving average run faster than the output its decimation before its stages, and a FIR
    /// run faster than the output its decimation between cut-off and taps (the record's keys
    /// sorted); `record_params` names them in that order; read back, each is the same.
    #[test]
    fn the_sampled_forms_write_their_extra_parameter() {
        for (p, want, names) in [
            (
                EffectParams::SecondOrderFilter {
                    natural_frequency_hz: 20.0,
                    damping: 0.7,
                    bilinear: false,
                    zero: Some(0.3),
                },
                r#"{"kind":"second_order_filter","params":{"damping":0.7,"natural_frequency":20.0,"zero":0.3},"gap_after":1.5}"#,
                &["damping", "natural_frequency", "zero"][..],
            ),
            (
                EffectParams::MovingAverage {
                    taps: 8,
                    stages: 3,
                    decimation: 8,
                },
                r#"{"kind":"moving_average","params":{"decimation":8,"stages":3,"taps":8},"gap_after":1.5}"#,
                &["decimation", "stages", "taps"][..],
            ),
            (
                EffectParams::FirFilter {
                    cutoff_hz: 250.0,
                    decimation: 2,
                    taps: 31,
                },
                r#"{"kind":"fir_filter","params":{"cutoff":250.0,"decimation":2,"taps":31},"gap_after":1.5}"#,
                &["cutoff", "decimation", "taps"][..],
            ),
        ] {
            let rec = EffectRecord {
                effect: RecordedEffect::Known(p),
                gap_after: 1.5,
                intervals: BTreeMap::new(),
                cause: None,
            };
            let line = serde_json::to_string(&rec).unwrap();
            assert_eq!(line, want);
            let named: Vec<&str> = p.record_params().iter().map(|(k, _)| *k).collect();
            assert_eq!(named, names);
            let back: EffectRecord = serde_json::from_str(&line).unwrap();
            assert!(matches!(back.effect, RecordedEffect::Known(q) if q == p));
        }
    }

    /// A kind a newer version wrote is kept with its numbers, and written back as it was.
    #[test]
    fn an_unknown_kind_is_kept() {
        let line = r#"{"kind":"vibration","params":{"amplitude":0.5,"band":null},"gap_after":2.0}"#;
        let e: EffectRecord = serde_json::from_str(line).unwrap();
        match &e.effect {
            RecordedEffect::Unknown(u) => {
                assert_eq!(u.kind, "vibration");
                assert_eq!(u.params.get("amplitude"), Some(&Some(0.5)));
                assert_eq!(u.params.get("band"), Some(&None));
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(e.effect.kind_name(), "vibration");
        assert_eq!(serde_json::to_string(&e).unwrap(), line);
    }

    #[test]
    fn quantization_and_alternatives_write_sorted_keys() {
        let q = QuantizationFinding {
            kind: QuantKind::Rate,
            lsb: 0.5,
            rate_lsb: 50.0,
            q_q: 0.25,
            n_q: 1.5,
            delta_chi2_angle: 12.0,
            delta_chi2_rate: 0.5,
            share_of_n2: f64::INFINITY,
            n_unit: 2.0,
        };
        let line = serde_json::to_string(&q).unwrap();
        assert_eq!(
            line,
            r#"{"delta_chi2_angle":12.0,"delta_chi2_rate":0.5,"kind":"rate","lsb":0.5,"n_q":1.5,"n_unit":2.0,"q_q":0.25,"rate_lsb":50.0,"share_of_n2":null}"#
        );
        let back: QuantizationFinding = serde_json::from_str(&line).unwrap();
        assert!(back.share_of_n2.is_nan() && back.kind == QuantKind::Rate);
        let a = AlternativeRecord::new(&Alternative {
            effects: vec![EffectParams::GaussMarkov {
                sigma: 0.3,
                tau_c_s: 30.0,
            }],
            gap: 1.25,
            delta_chi2: 0.5,
            coef: [0.0, 0.25, 0.5, 0.0, 1.0],
        });
        let line = serde_json::to_string(&a).unwrap();
        assert_eq!(
            line,
            r#"{"coef":[0.0,0.25,0.5,0.0,1.0],"delta_chi2":0.5,"effects":[{"kind":"gauss_markov","params":{"sigma":0.3,"tau_c":30.0}}],"gap":1.25}"#
        );
        assert_eq!(serde_json::from_str::<AlternativeRecord>(&line).unwrap(), a);
    }
}
