//! docs/records.md's `diagnosis` record: `type`, `channel`, `gap_before`, `gap_after`, `verdict`,
//! `regions`, `effects`, optional `holdout`, plus extra fields (`final`, `t_data`, `tau_span`,
//! `base_coef`, `final_coef`, `segments`, `jumps`, `residual_shape`, `model_tau`, `model_base`,
//! `model_effects`, `outliers`, `quantization`, `quantization_limited`, `alternatives`, and
//! `run` when several inputs are analyzed).

use super::diagnose::{Diagnosis, Verdict};
use super::holdout::HoldoutGap;
use serde::{Deserialize, Serialize};

/// One region of the record.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RegionRecord {
    pub tau_lo: f64,
    pub tau_hi: f64,
    pub sign: i32,
    pub worst_ratio: f64,
}

/// One effect of the record (`params` with docs/records.md's names: u/s, s, Hz).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectRecord {
    pub kind: String,
    pub params: serde_json::Value,
    pub gap_after: f64,
    /// 95% intervals of the parameters, by their `params` names (`{name: [lo, hi]}`;
    /// docs/gap.md, "Parameter intervals"); absent when none was computed (warm-ups, jumps).
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub intervals: std::collections::BTreeMap<String, [f64; 2]>,
}

/// The gap on a held-out run (docs/records.md's `gap_before`, `gap_after`; extra fields `carried`
/// and `effects`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HoldoutRecord {
    pub gap_before: f64,
    /// With the effects that carried: never above `gap_before`.
    pub gap_after: f64,
    /// Whether any effect of the fitting run lowered the held-out gap; `false` says plainly
    /// that the diagnosis did not carry to this run.
    #[serde(default)]
    pub carried: bool,
    /// Each effect of the fitting run on the held-out run, in order (bias jumps left out).
    #[serde(default)]
    pub effects: Vec<HeldEffectRecord>,
}

/// One effect on the held-out run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldEffectRecord {
    pub kind: String,
    /// The held-out gap with it added to the effects that carried before it.
    pub gap_after: f64,
    /// Whether it lowered the held-out gap (kept for the effects after it).
    pub carried: bool,
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
    /// Outliers found and replaced before the curve was computed (docs/gap.md, "Outliers").
    #[serde(default)]
    pub outliers: OutliersRecord,
    /// What the values' step does to the curve (docs/gap.md, "Rate-sample quantization"):
    /// absent when the values are not whole multiples of one step.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub quantization: Option<serde_json::Value>,
    /// Other explanations that fit about as well as the one chosen (docs/gap.md,
    /// "Alternatives"): `[{effects: [{kind, params}], gap, delta_chi2, coef}]`, empty when the
    /// choice is clear.
    #[serde(default)]
    pub alternatives: Vec<serde_json::Value>,
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
/// error is white again.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuantizationRecord {
    pub lsb: f64,
    pub ratio: f64,
    pub tau_white: f64,
}

/// The `outliers` object: how many, how often (per second of data), their rms and largest size
/// (u/s).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct OutliersRecord {
    pub count: u64,
    pub rate: f64,
    pub rms_size: f64,
    pub max_size: f64,
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
                    kind: e.params.kind().name().into(),
                    params: e.params.to_json(),
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
                    })
                    .collect(),
            }),
            is_final,
            t_data: d.t_data_s,
            tau_span: [d.tau_span_s.0, d.tau_span_s.1],
            base_coef: d.base_coef,
            final_coef: d.final_coef,
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
            outliers: OutliersRecord {
                count: d.outliers.count,
                rate: if d.t_data_s > 0.0 {
                    d.outliers.count as f64 / d.t_data_s
                } else {
                    0.0
                },
                rms_size: d.outliers.rms_size(),
                max_size: d.outliers.max_size,
            },
            quantization: d.quantization.map(|q| q.to_json()),
            alternatives: d.alternatives.iter().map(|a| a.to_json()).collect(),
            run: None,
            unit: None,
            quantization_limited: d.quantization_limited.map(|q| QuantizationRecord {
                lsb: q.lsb,
                ratio: q.ratio,
                tau_white: q.tau_white_s,
            }),
            ensemble: None,
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
