//! The JSON-lines records of docs/records.md, as serde structs. Field names and units here are the
//! contract: scripts read them. Extra fields may be added; none may be renamed.

use serde::{Deserialize, Serialize};

use crate::allan::{Curve, Stat};

/// A non-finite number (an undefined edf or interval) is written as JSON `null`.
fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// `curve`: one statistic of one channel. Arrays are parallel, one entry per tau.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CurveRecord {
    #[serde(rename = "type")]
    pub kind: String,
    pub channel: String,
    pub unit: String,
    pub stat: Stat,
    /// Seconds of data consumed.
    pub t_data: f64,
    /// True once the input has ended.
    pub r#final: bool,
    /// Averaging times in s.
    pub tau: Vec<f64>,
    /// Deviations in u/s.
    pub sigma: Vec<f64>,
    /// 95% interval of sigma, u/s.
    pub lo: Vec<Option<f64>>,
    pub hi: Vec<Option<f64>>,
    /// Equivalent degrees of freedom.
    pub edf: Vec<Option<f64>>,
    /// Number of differences averaged.
    pub count: Vec<u64>,
    /// Cluster sizes (tau / tau0).
    pub m: Vec<u64>,
    /// Power-law noise exponent of S_y used for the edf at each tau.
    pub alpha: Vec<i32>,
    /// Run index (0-based) when several inputs are analyzed.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub run: Option<usize>,
}

impl CurveRecord {
    pub fn new(channel: &str, unit: &str, curve: &Curve, final_: bool, run: Option<usize>) -> Self {
        let p = &curve.points;
        CurveRecord {
            kind: "curve".into(),
            channel: channel.into(),
            unit: unit.into(),
            stat: curve.stat,
            t_data: curve.t_data_s,
            r#final: final_,
            tau: p.iter().map(|q| q.tau_s).collect(),
            sigma: p.iter().map(|q| q.sigma()).collect(),
            lo: p.iter().map(|q| finite(q.sigma_lo)).collect(),
            hi: p.iter().map(|q| finite(q.sigma_hi)).collect(),
            edf: p.iter().map(|q| finite(q.edf)).collect(),
            count: p.iter().map(|q| q.count).collect(),
            m: p.iter().map(|q| q.m).collect(),
            alpha: p.iter().map(|q| q.alpha).collect(),
            run,
        }
    }
}

/// `fit`: the five-term model of one channel.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct FitRecord {
    #[serde(rename = "type")]
    pub kind: String,
    pub channel: String,
    pub unit: String,
    pub r#final: bool,
    pub t_data: f64,
    /// `{Q, N, B, K, R}`, each `{value, lo, hi, determined}` (docs/theory.md section 2 units).
    pub coef: serde_json::Value,
    /// Goodness of fit, near 1 when the model explains the curve.
    pub gof: Option<f64>,
    /// The fit method (`model`, `paper`, `slopes`, `loglog`).
    pub method: String,
    /// The fitted linear coefficients `(Q^2, N^2, B^2, K^2, R^2)` of docs/theory.md section 2,
    /// determined or not: the model curve `AVAR(tau) = sum c_i basis_i(tau)` (for plots and
    /// the diagnosis).
    #[serde(default)]
    pub model_c: Vec<f64>,
    /// The same coefficients in datasheet units, where the unit is known.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub datasheet: Option<serde_json::Value>,
    /// IEEE 952 read-outs of the AVAR curve beside the fit (model::readout): `arw`,
    /// `bias_instability`, `rrw`.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub readouts: Option<Box<crate::model::readout::ReadoutsRecord>>,
    /// Q divided by LSB/sqrt(12), where the LSB is known (the seed paper's comparison).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub q_over_lsb: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub run: Option<usize>,
}

/// `health`: what the decoder saw (docs/records.md).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
pub struct HealthRecord {
    #[serde(rename = "type")]
    pub kind: String,
    pub frames: u64,
    pub crc_errors: u64,
    pub resyncs: u64,
    pub missing: u64,
    pub duplicates: u64,
    pub bytes_skipped: u64,
    #[serde(flatten)]
    pub extra: serde_json::Map<String, serde_json::Value>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub run: Option<usize>,
}

/// `summary`: one at the end of each run.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SummaryRecord {
    #[serde(rename = "type")]
    pub kind: String,
    pub input: String,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub run: Option<usize>,
    pub channels: Vec<String>,
    /// Sampling step, s.
    pub tau0: f64,
    /// Seconds of data consumed, gaps included.
    pub t_data: f64,
    /// Samples accepted per channel.
    pub samples: Vec<u64>,
    /// Phase segments per channel (1 + the number of gaps).
    pub segments: Vec<u64>,
    /// Input rows or frames that could not be read and were skipped as gaps.
    pub bad_rows: u64,
    /// Text values that were infinite or beyond `input::MAX_ABS_VALUE`, read as gaps (frames
    /// count theirs in `health`'s `invalid_values`).
    #[serde(skip_serializing_if = "is_zero", default)]
    pub invalid_values: u64,
    pub overlap: String,
    /// Wall-clock seconds spent.
    pub elapsed_s: f64,
    /// Datasheet limits judged, when a stand config gives them.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub limits: Vec<crate::model::limits::LimitResult>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub pass: Option<bool>,
    /// True when the input was read to its end (docs/records.md); false for a replay stopped early
    /// (SIGINT) and for a live source, which has no end (`stopped_by` says what ended it).
    #[serde(default)]
    pub read_to_end: bool,
    /// Text input with a time column: what it found (docs/records.md, `time_column`).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub time_column: Option<TimeColumnRecord>,
    /// What stopped the run before its input ended: `SIGINT`, `SIGTERM` or `--duration`.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub stopped_by: Option<String>,
    /// The `--capture` file's write error, when the capture stopped early (the analysis went on).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub capture_error: Option<String>,
}

/// The `summary`'s account of a text input's time column (src/input/time_column.rs): its name,
/// whether it was used to find gaps (`false`: its first step was not tau0 in s, ms, us or ns,
/// and it was only skipped), its unit, the jumps taken as gaps and the samples they stood for
/// (rows absent from the file, read as gaps), and the steps that went backwards or repeated, were
/// not a whole number of tau0, or were too large to fill (each row then read as the next sample).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TimeColumnRecord {
    pub name: String,
    pub used: bool,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub unit: Option<String>,
    pub gaps: u64,
    pub missing_samples: u64,
    pub backwards: u64,
    pub irregular: u64,
    pub discontinuities: u64,
}

/// `aggregate`: run-to-run statistics of one coefficient of one channel (the seed paper's
/// table 2).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct AggregateRecord {
    #[serde(rename = "type")]
    pub kind: String,
    pub channel: String,
    pub unit: String,
    /// `Q`, `N`, `B`, `K` or `R`.
    pub coef: String,
    /// Runs in which the coefficient was determined.
    pub n: usize,
    pub mean: Option<f64>,
    /// Sample standard deviation (n - 1).
    pub sd: Option<f64>,
    /// Student 95% interval of the mean.
    pub ci_t: Option<[f64; 2]>,
    /// The seed paper's `mean +- 1.96 sd / sqrt(n)`.
    pub ci_z: Option<[f64; 2]>,
}

/// `outage`: a unit of a run of several (`[[unit]]`) that went quiet, came back, or whose
/// source failed, while the other units went on (docs/records.md, "Several units").
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct OutageRecord {
    #[serde(rename = "type")]
    pub kind: String,
    /// `quiet` (no byte for `run.quiet_after` wall-seconds), `resumed` (bytes again) or
    /// `failed` (the source stopped with an error; the unit's final records follow at the end).
    pub event: String,
    /// When, in seconds since the Unix epoch.
    pub at_unix_s: f64,
    /// Seconds of the unit's data analysed by then.
    pub t_data: f64,
    /// Wall-seconds since the unit's last byte (for `resumed`: the whole silence).
    pub silent_s: f64,
    /// The source's error, for `failed`.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub error: Option<String>,
}

/// Any record, written as its own JSON object.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum Record {
    Curve(CurveRecord),
    Fit(FitRecord),
    Health(HealthRecord),
    Aggregate(AggregateRecord),
    Summary(SummaryRecord),
    Outage(OutageRecord),
    /// `diagnosis`: the sim-to-real gap of one channel (`crate::gap::record`).
    Diagnosis(Box<crate::gap::DiagnosisRecord>),
    /// Records of other stages, already as JSON.
    Other(serde_json::Value),
}
